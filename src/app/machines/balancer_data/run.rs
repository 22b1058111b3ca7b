//! The test-stand data reduction of a CSV text; the result is the `--json` document
//! ([`BalancerDataReport`]).

use std::path::Path;

use serde::Serialize;

use super::case::parse_csv;
use super::model::{Reduction, reduce};
use super::plots;
use crate::app::machines::report_files;
use crate::{Error, Result};

/// The balancer-data report (`report.json`).
#[derive(Debug, Clone, Serialize)]
pub struct BalancerDataReport {
    /// Input file.
    pub file: String,
    /// The reductions.
    pub reduction: Reduction,
    /// Files written.
    pub outputs: Vec<String>,
}

/// Parses and reduces balancer-data CSV text; with `out`, writes the scatter plot there and
/// lists it, with the report files, in `outputs`.
pub fn balancer_data_analysis(file: &str, text: &str, out: Option<&Path>) -> Result<BalancerDataReport> {
    let d = parse_csv(file, text)?;
    let red = reduce(file, &d)?;
    check_finite(file, &red)?;
    let mut outputs = Vec::new();
    if let Some(dir) = out {
        if let Some(sc) = &red.scatter {
            let p = dir.join("scatter.svg");
            plots::scatter_plot(&p, sc)?;
            outputs.push(p.display().to_string());
        }
        outputs.extend(report_files(dir));
    }
    Ok(BalancerDataReport {
        file: file.to_string(),
        reduction: red,
        outputs,
    })
}

/// Every number of a reduction is finite: values of the file whose products overflow (a
/// 1e300 kg ball) are refused, naming the file and the quantity, instead of reported as `inf` or
/// `null` with success.
fn check_finite(file: &str, red: &Reduction) -> Result<()> {
    let mut named: Vec<(&str, f64)> = Vec::new();
    for c in &red.correction {
        named.extend([
            ("correction imbalance S", c.imbalance),
            ("correction cut mass", c.cut_mass),
        ]);
    }
    if let Some(sc) = &red.scatter {
        for r in &sc.rows {
            named.extend([("S_x", r.sx), ("S_y", r.sy), ("S", r.s), ("ΔS", r.ds), ("η_i", r.eta)]);
        }
        named.extend([
            ("S_xc", sc.sx_mean),
            ("S_yc", sc.sy_mean),
            ("S_c", sc.s_mean),
            ("mean ΔS", sc.ds_mean),
        ]);
        named.extend([("η", sc.eta), ("η_min", sc.eta_min), ("η_max", sc.eta_max)]);
    }
    if let Some(se) = &red.sensitivity {
        named.push(("sensitivity η", se.eta));
    }
    for e in &red.efficiency {
        named.push(("efficiency", e.efficiency));
    }
    match named.iter().find(|(_, v)| !v.is_finite()) {
        None => Ok(()),
        Some((what, v)) => Err(Error::Input {
            file: file.to_string(),
            line: None,
            key: None,
            msg: format!(
                "the data give a non-finite {what} ({v}): a value overflows double precision \
                 (check the units of the ball mass and the radii)"
            ),
        }),
    }
}
