//! The application's reports from Python: the design chain (`vibrofem design`) and the machines
//! of the registry (`vibrofem crank-drive`, `autobalancer`, `balancer-data`). Each runs as its
//! command does with `--out DIR --json`: the same checks of the output folder before any work,
//! the report files and plots written into the folder, and the `--json` document returned (as
//! text; the Python half parses it) instead of printed.

use crate::interruptible;
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use vibrofem::app::design;
use vibrofem::app::machines;
use vibrofem::app::output::check_outputs;
use vibrofem::app::report::render;
use vibrofem::{Error, Result};

/// The design chain on `path` (a design TOML; `None`: the paper's built-in table), as
/// `vibrofem design PATH --out OUT --json [--yes]`: refuses a design over the DOF limit without
/// `yes`, writes the report and plots into `out` and, when a check fails and the design asks for
/// a search, the lightest passing variant into `out/passing-variant` (and `out/search.txt`).
/// Returns (the `--json` document, the passing variant's JSON document if one was found).
#[pyfunction]
#[pyo3(signature = (path, out, yes = false))]
pub fn run_design(
    py: Python<'_>,
    path: Option<PathBuf>,
    out: PathBuf,
    yes: bool,
) -> PyResult<(String, Option<String>)> {
    interruptible(py, move || design_in(path.as_deref(), &out, yes))
}

fn design_in(path: Option<&Path>, out: &Path, yes: bool) -> Result<(String, Option<String>)> {
    let d = match path {
        Some(f) => design::Design::from_toml(f)?,
        None => design::Design::paper(),
    };
    if !yes {
        let dofs = design::estimate_dofs(&d)?;
        if dofs > design::LARGE_DESIGN_DOFS {
            return Err(Error::option(
                "yes",
                format!(
                    "the design's FE models have about {dofs} DOFs (more than {}): minutes to hours of work; \
                     call again with yes=True to start it, or coarsen the mesh sizes",
                    design::LARGE_DESIGN_DOFS
                ),
            ));
        }
    }
    let inputs: Vec<(&str, &Path)> = path.iter().map(|f| ("design file", *f)).collect();
    check_outputs(&[], Some(("out", out)), &inputs)?;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let quiet = |_: &str| {};
    let job = design::job::run(&d, out, &quiet)?;
    let json = render::json(&job.report)?;
    let variant = job.variant.as_ref().map(render::json).transpose()?;
    Ok((json, variant))
}

/// Machine `command` of the registry (`crank-drive`, `autobalancer`, `balancer-data`) on case
/// file `path` (`None`: its built-in case), as `vibrofem COMMAND PATH --out OUT --json`: the
/// report files and plots written into `out`. Returns (the `--json` document, why the machine's
/// main result failed, if it did: the command line's exit code 2, the report written all the
/// same).
#[pyfunction]
#[pyo3(signature = (command, path, out))]
pub fn run_machine(
    py: Python<'_>,
    command: String,
    path: Option<PathBuf>,
    out: PathBuf,
) -> PyResult<(String, Option<String>)> {
    interruptible(py, move || {
        let m = machines::machine(&command).ok_or_else(|| {
            let known: Vec<&str> = machines::MACHINES.iter().map(|m| m.command).collect();
            Error::option(
                "command",
                format!("no machine '{command}' (known: {})", known.join(", ")),
            )
        })?;
        let inputs: Vec<(&str, &Path)> = path.iter().map(|f| ("case file", f.as_path())).collect();
        check_outputs(&[], Some(("out", &out)), &inputs)?;
        std::fs::create_dir_all(&out).map_err(|e| Error::io(&out, e))?;
        let o = (m.run)(path.as_deref(), Some(&out))?;
        render::write_all(&o.report, &out)?;
        let json = render::json(&o.report)?;
        Ok((json, o.failure))
    })
}

/// The machines of the registry: (command, what it does).
#[pyfunction]
pub fn machine_list() -> Vec<(&'static str, &'static str)> {
    machines::MACHINES.iter().map(|m| (m.command, m.about)).collect()
}
