//! Crank–slider drives of a roller-forming machine (docs/spec/machines.md §A): reduced inertia,
//! Kloss motor, motion non-uniformity, runs from rest.
//!
//! [`case`] → [`run`] → [`report`]; [`model`] is the physics, [`plots`] the figures.

pub mod case;
pub mod model;
pub mod plots;
pub mod report;
pub mod run;

use std::path::Path;

pub use case::{CRANK_DEFAULT_NAME, CRANK_DEFAULT_TOML, CrankCase, MotorScale, RunSettings, Setup, StartupSettings};
pub use run::{CrankReport, MotorFigures, SetupRow, StartupRow, crank_analysis};

use super::{Machine, Outcome};
use crate::Result;

/// The registry entry.
pub const MACHINE: Machine = Machine {
    command: "crank-drive",
    about: "Crank–slider drives (roller-forming machine): reduced inertia, Kloss motor, motion non-uniformity; built-in paper drive when no file is given.",
    file_help: r#"Crank-drive file (TOML, `[machine] kind = "crank-drive"`); default: the paper's two-cart drive with the four setups of its Table 1, built in (scenes/machines/crank_two_carts.toml)"#,
    default_out: "vibrofem-crank-drive",
    run: run_case,
};

/// Reads the case (or the built-in one), runs it and reports; a main steady run that stalls is a
/// failure of the result (exit 2), reported after the report is written.
fn run_case(file: Option<&Path>, out: Option<&Path>) -> Result<Outcome> {
    let c = match file {
        Some(f) => CrankCase::from_toml(f)?,
        None => CrankCase::builtin()?,
    };
    let r = crank_analysis(&c, out)?;
    Ok(Outcome {
        report: report::report(&r)?,
        summary: report::SUMMARY,
        failure: r.energy_form.stall.as_ref().map(|st| st.message.clone()),
    })
}
