//! Autobalancer test-stand data reduction (docs/spec/machines.md §C): correction cut, imbalance
//! scatter, sensitivity, efficiency from a CSV file.
//!
//! [`case`] (the CSV) → [`run`] → [`report`]; [`model`] holds the reductions, [`plots`] the
//! figure.

pub mod case;
pub mod model;
pub mod plots;
pub mod report;
pub mod run;

use std::path::Path;

pub use case::{Labelled, Mount, StandData, parse_csv, read_csv};
pub use model::{
    CutRow, EfficiencyRow, Reduction, Scatter, ScatterRow, Sensitivity, ball_imbalance, correction_cut, efficiency,
    reduce, sensitivity,
};
pub use run::{BalancerDataReport, balancer_data_analysis};

use super::{Machine, Outcome};
use crate::{Error, Result};

/// The built-in example data (scenes/machines/balancer_test_stand.csv).
pub const BALANCER_DATA_DEFAULT_CSV: &str = include_str!("../../../../scenes/machines/balancer_test_stand.csv");
/// Its name in messages.
pub const BALANCER_DATA_DEFAULT_NAME: &str = "scenes/machines/balancer_test_stand.csv (built in)";

/// The registry entry.
pub const MACHINE: Machine = Machine {
    command: "balancer-data",
    about: "Autobalancer test-stand data reduction (correction cut, imbalance scatter, sensitivity, efficiency) from a CSV file; built-in example when no file is given.",
    file_help: r#"Test-stand CSV (header `record,label,x,y`, first record `version,balancer-data,1`); default: the built-in example (scenes/machines/balancer_test_stand.csv)"#,
    default_out: "vibrofem-balancer-data",
    run: run_case,
};

/// Reads the CSV (or the built-in one), reduces it and reports.
fn run_case(file: Option<&Path>, out: Option<&Path>) -> Result<Outcome> {
    let (name, text) = match file {
        Some(f) => (
            f.display().to_string(),
            std::fs::read_to_string(f).map_err(|e| Error::io(f, e))?,
        ),
        None => (
            BALANCER_DATA_DEFAULT_NAME.to_string(),
            BALANCER_DATA_DEFAULT_CSV.to_string(),
        ),
    };
    let r = balancer_data_analysis(&name, &text, out)?;
    Ok(Outcome {
        report: report::report(&r)?,
        summary: report::SUMMARY,
        failure: None,
    })
}
