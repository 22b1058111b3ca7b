//! The other machines of the family (docs/spec/machines.md): the crank drive of a roller-forming
//! machine, the ball autobalancer of a grinder and the reduction of autobalancer test-stand data.
//!
//! Every machine has the same shape, one folder each:
//!
//! - `case.rs`: the case, read from a file (or built in), every value validated before any work,
//!   errors naming the file, the line and the key;
//! - `model.rs` (where there is a model of its own): the physics, usable alone;
//! - `run.rs`: the analysis of a case, giving the run's serialisable result (the `--json` schema);
//! - `report.rs`: that result as a [`Report`] (sections, tables, quantities, figures), rendered
//!   to the terminal, `report.md`, `report.html` and `report.json` by [`crate::app::report::render`];
//! - `plots.rs`: its SVG figures;
//! - `mod.rs`: its [`Machine`] entry (command name, help, the run).
//!
//! [`registry::MACHINES`] lists them; the command line builds one subcommand per entry
//! ([`MachineCommand`]) and runs it through [`run_command`].
//!
//! Exit codes: 0 success; 1 bad input (file, line and key named); 2 when the machine's main
//! result failed (a crank drive whose steady run stalls: the report is still written and says
//! where and why); 4 a result could not be written; 141 standard output closed.

pub mod autobalancer;
pub mod balancer_data;
pub mod case_file;
pub mod command;
pub mod crank;
pub mod plot;
pub mod registry;

use crate::app::output::{check_outputs, emit};
use std::path::Path;

use serde::Serialize;

use crate::app::report::{Report, render};
use crate::{Error, Result};

pub use command::MachineCommand;
pub use registry::{MACHINES, machine};

/// One machine of the registry: what the command line (and other front ends) need to run it.
#[derive(Clone, Copy)]
pub struct Machine {
    /// Command name (`crank-drive`).
    pub command: &'static str,
    /// What it does (the command's help).
    pub about: &'static str,
    /// Help of the command's FILE argument: the file format and the built-in case.
    pub file_help: &'static str,
    /// Default output folder of the command.
    pub default_out: &'static str,
    /// Reads and validates the case (`None`: the built-in case), runs the analysis and, with an
    /// output folder, writes the plots there; returns the report (whose `data` is the `--json`
    /// document, listing the files of [`report_files`] as written).
    pub run: fn(file: Option<&Path>, out: Option<&Path>) -> Result<Outcome>,
}

/// What a machine run gives.
pub struct Outcome {
    /// The report.
    pub report: Report,
    /// Ids of the sections printed on the terminal (the others are in the report files).
    pub summary: &'static [&'static str],
    /// The machine's main result failed (exit code 2 after the report is written): why.
    pub failure: Option<String>,
}

/// The report files [`publish`] writes into `out`, as listed in a report's `outputs`.
pub fn report_files(out: &Path) -> Vec<String> {
    ["report.md", "report.json", "report.html"]
        .iter()
        .map(|f| out.join(f).display().to_string())
        .collect()
}

/// A report whose JSON payload is `data` serialised.
pub(crate) fn report_of<T: Serialize>(title: impl Into<String>, data: &T) -> Result<Report> {
    let v = serde_json::to_value(data).map_err(|e| Error::output("report JSON", e))?;
    Ok(Report::new(title, v))
}

/// The command-line arguments every machine takes.
#[derive(Debug, Clone)]
pub struct CommandArgs<'a> {
    /// The case file (`None`: the built-in case).
    pub file: Option<&'a Path>,
    /// Output folder.
    pub out: &'a Path,
    /// Print the JSON report instead of the summary.
    pub json: bool,
}

/// Runs machine `command` as the command line does: refuses an output folder that cannot be
/// written or is the case file before any work, runs, writes `report.md`, `report.html` and `report.json` into the folder and prints
/// the summary (or the JSON) through the checked writer. Returns the exit code.
pub fn run_command(command: &str, a: &CommandArgs) -> Result<i32> {
    let m = machine(command).ok_or_else(|| Error::option(command, format!("no machine '{command}'")))?;
    let inputs: Vec<(&str, &Path)> = a.file.iter().map(|f| ("case file", *f)).collect();
    check_outputs(&[], Some(("--out", a.out)), &inputs)?;
    crate::io::create_dir(a.out)?;
    // A failure in the run (a simulation's) names the case file, as reading errors do.
    let o = (m.run)(a.file, Some(a.out)).map_err(|e| match a.file.map(|f| f.display().to_string()) {
        Some(f) if !e.to_string().contains(&f) => e.with_prefix(&f),
        _ => e,
    })?;
    render::write_all(&o.report, a.out)?;
    if a.json {
        emit(&(render::json(&o.report)? + "\n"))?;
    } else {
        emit(&summary_text(&o))?;
        emit(&format!(
            "\nreport: {} (plots beside it)\n",
            a.out.join("report.md").display()
        ))?;
    }
    if let Some(why) = o.failure {
        eprintln!("error: {why}");
        return Ok(2);
    }
    Ok(0)
}

/// The summary sections of an outcome as terminal text.
pub fn summary_text(o: &Outcome) -> String {
    let mut r = Report::new(o.report.title.clone(), serde_json::Value::Null);
    r.sections = o
        .report
        .sections
        .iter()
        .filter(|s| o.summary.contains(&s.id.as_str()))
        .cloned()
        .collect();
    render::text(&r)
}

/// A file name of `outputs` for a figure.
pub(crate) fn file_name(path: &str) -> String {
    Path::new(path)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The figures among a run's `outputs` (the SVG files), for the report's plots section.
pub(crate) fn figures(outputs: &[String], caption: impl Fn(&str) -> String) -> Vec<crate::app::report::Block> {
    outputs
        .iter()
        .map(|o| file_name(o))
        .filter(|n| n.ends_with(".svg"))
        .map(|n| {
            crate::app::report::Block::Figure(crate::app::report::Figure {
                id: n.trim_end_matches(".svg").into(),
                caption: caption(&n),
                file: n,
            })
        })
        .collect()
}
