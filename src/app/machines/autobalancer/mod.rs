//! The ball autobalancer of a grinder on a rocker (docs/spec/machines.md §B): the linear
//! criterion, the nonlinear model at the operating speed, a speed sweep and a run-up.
//!
//! [`case`] → [`run`] → [`report`]; [`model`] is the physics, [`plots`] the figures.

pub mod case;
pub mod model;
pub mod plots;
pub mod report;
pub mod run;

use std::path::Path;

pub use case::{
    AUTOBALANCER_DEFAULT_NAME, AUTOBALANCER_DEFAULT_TOML, AutobalancerCase, MAX_REVOLUTIONS, RunupSettings,
    SweepSettings,
};
pub use run::{
    AutobalancerFigures, AutobalancerReport, CUTTING_FRACTIONS, OperatingRun, RunupSummary, autobalancer_analysis,
};

use super::{Machine, Outcome};
use crate::Result;

/// The registry entry.
pub const MACHINE: Machine = Machine {
    command: "autobalancer",
    about: "Ball autobalancer of a grinder on a rocker: criterion, speed sweep, run-up; built-in grinder when no file is given.",
    file_help: r#"Autobalancer file (TOML, `[machine] kind = "autobalancer"`); default: a plausible 125 mm grinder, built in (scenes/machines/grinder_autobalancer.toml)"#,
    default_out: "vibrofem-autobalancer",
    run: run_case,
};

/// Reads the case (or the built-in one), runs it and reports.
fn run_case(file: Option<&Path>, out: Option<&Path>) -> Result<Outcome> {
    let c = match file {
        Some(f) => AutobalancerCase::from_toml(f)?,
        None => AutobalancerCase::builtin()?,
    };
    let r = autobalancer_analysis(&c, out)?;
    Ok(Outcome {
        report: report::report(&r)?,
        summary: report::SUMMARY,
        failure: None,
    })
}
