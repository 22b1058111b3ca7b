//! The test-stand reduction ([`BalancerDataReport`]) as a [`Report`]: correction cut, imbalance
//! scatter, sensitivity, efficiency, plot.

use super::run::BalancerDataReport;
use crate::Result;
use crate::app::machines::{figures, report_of};
use crate::app::report::{Block, Cell, Column, QuantityRow, Report, Table, fmt_sig};

/// Sections printed on the terminal.
pub const SUMMARY: &[&str] = &["correction", "scatter_means", "sensitivity", "efficiency"];

fn num(value: f64, digits: usize) -> Cell {
    Cell::Num { value, digits }
}

fn pct(value: f64) -> Cell {
    Cell::Pct { value, decimals: 1 }
}

fn q(id: &str, name: &str, unit: &str, value: f64) -> QuantityRow {
    QuantityRow::new(id, name, unit, value)
}

/// The report of a test-stand reduction; its data is `r` serialised.
pub fn report(r: &BalancerDataReport) -> Result<Report> {
    let red = &r.reduction;
    let mut rep = report_of("Autobalancer test-stand data", r)?;
    let mut input = format!("Input: `{}`.", r.file);
    if let Some((m, rad)) = red.ball {
        input += &format!(
            " Balls: {} g on a {} mm race.",
            fmt_sig(m * 1e3, 4),
            fmt_sig(rad * 1e3, 4)
        );
    }
    rep.section("input", "").push(Block::Text(input));
    if !red.correction.is_empty() {
        let rows = red
            .correction
            .iter()
            .map(|c| {
                vec![
                    Cell::text(&c.label),
                    num(c.spread_deg, 4),
                    num(c.imbalance * 1e6, 4),
                    num(c.cut_mass * 1e3, 4),
                ]
            })
            .collect();
        rep.section("correction", "Correction cut of the housing")
            .push(Block::Text(format!(
                "S = 2 m R |cos(α0/2)|, cut mass S/L at L = {} mm.",
                red.cut_radius.map(|l| fmt_sig(l * 1e3, 4)).unwrap_or_default()
            )))
            .push(Block::Table(Table {
                id: "correction".into(),
                caption: None,
                columns: vec![
                    Column::new("test", None),
                    Column::new("α0", Some("deg")),
                    Column::new("S", Some("g·mm")),
                    Column::new("cut mass", Some("g")),
                ],
                rows,
            }));
    }
    scatter(&mut rep, r);
    if let Some(se) = &red.sensitivity {
        rep.section("sensitivity", "Sensitivity").push(Block::Quantities(vec![
            q("m_min", "smallest test mass balanced m_min", "g", se.m_min * 1e3),
            q("m_max", "largest test mass balanced m_max", "g", se.m_max * 1e3),
            q("eta", "sensitivity η = m_min/m_max", "%", se.eta * 100.0),
        ]));
    }
    if !red.efficiency.is_empty() {
        let rows = red
            .efficiency
            .iter()
            .map(|e| {
                vec![
                    Cell::text(&e.label),
                    Cell::text(format!("{}", e.a_max)),
                    Cell::text(format!("{}", e.a)),
                    pct(e.efficiency),
                ]
            })
            .collect();
        rep.section("efficiency", "Efficiency").push(Block::Table(Table {
            id: "efficiency".into(),
            caption: None,
            columns: vec![
                Column::new("case", None),
                Column::new("a_max", Some("m/s²")),
                Column::new("a", Some("m/s²")),
                Column::new("e = (a_max − a)/a_max", None),
            ],
            rows,
        }));
    }
    let figs = figures(&r.outputs, |_| {
        "Residual imbalance per mounting, its mean and mean scatter".into()
    });
    if !figs.is_empty() {
        rep.section("plots", "Plots").blocks = figs;
    }
    Ok(rep)
}

fn scatter(rep: &mut Report, r: &BalancerDataReport) {
    let Some(sc) = &r.reduction.scatter else {
        return;
    };
    let rows = sc
        .rows
        .iter()
        .map(|row| {
            vec![
                Cell::text(&row.label),
                num(row.sx * 1e6, 4),
                num(row.sy * 1e6, 4),
                num(row.s * 1e6, 4),
                num(row.ds * 1e6, 4),
                pct(row.eta),
            ]
        })
        .collect();
    rep.section("scatter", "Imbalance scatter over re-mountings")
        .push(Block::Table(Table {
            id: "scatter".into(),
            caption: None,
            columns: vec![
                Column::new("mounting", None),
                Column::new("S_x", Some("g·mm")),
                Column::new("S_y", Some("g·mm")),
                Column::new("S", Some("g·mm")),
                Column::new("ΔS", Some("g·mm")),
                Column::new("η_i", None),
            ],
            rows,
        }));
    rep.section(
        "scatter_means",
        &format!("Imbalance scatter: means over {} mountings", sc.rows.len()),
    )
    .push(Block::Quantities(vec![
        q("sx_mean", "S_xc", "g·mm", sc.sx_mean * 1e6),
        q("sy_mean", "S_yc", "g·mm", sc.sy_mean * 1e6),
        q("s_mean", "S_c", "g·mm", sc.s_mean * 1e6),
        q("ds_mean", "mean ΔS", "g·mm", sc.ds_mean * 1e6),
        q("eta", "η = mean ΔS / S_c", "%", sc.eta * 100.0),
        q("eta_min", "smallest η_i", "%", sc.eta_min * 100.0),
        q("eta_max", "largest η_i", "%", sc.eta_max * 100.0),
    ]));
}
