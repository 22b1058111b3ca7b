//! `vibrofem design`: the vibratory-table design chain and, when it fails, the search.

use super::{check_outputs, emit};
use crate::app::design;
use crate::app::report::render;
use crate::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct DesignArgs {
    /// Design file (TOML); default: the paper's 100 Hz table, built in.
    file: Option<PathBuf>,
    /// Folder for the report (report.md, report.json, SVG plots, mode shapes).
    #[arg(short, long, default_value = "vibrofem-design")]
    out: PathBuf,
    /// Print the JSON report on stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// Run a design whose models exceed 300 000 DOFs (refused otherwise, with the estimate).
    #[arg(long)]
    yes: bool,
}

pub fn design_cmd(a: &DesignArgs) -> Result<i32> {
    let d = match &a.file {
        Some(f) => design::Design::from_toml(f)?,
        None => design::Design::paper(),
    };
    if !a.yes {
        // A design file's sizes are all valid alone, yet a 5 mm element size or a 10 m plate
        // makes minutes of work: say so before starting.
        let dofs = design::estimate_dofs(&d)?;
        if dofs > design::LARGE_DESIGN_DOFS {
            return Err(Error::option(
                "--yes",
                format!(
                    "the design's FE models have about {dofs} DOFs (more than {}): minutes to hours of work; \
                     rerun with --yes to start it, or coarsen the mesh sizes",
                    design::LARGE_DESIGN_DOFS
                ),
            ));
        }
    }
    check_outputs(
        &[],
        Some(("--out", &a.out)),
        &a.file.iter().map(|f| ("design file", f.as_path())).collect::<Vec<_>>(),
    )?;
    let t0 = std::time::Instant::now();
    crate::io::create_dir(&a.out)?;
    let job = with_progress(t0, |p| design::job::run(&d, &a.out, p))?;
    if a.json {
        outln!("{}", render::json(&job.report)?);
    } else {
        out!("{}", render::text(&job.report));
        outln!(
            "\nreport: {}/report.md (plots and mode shapes beside it)",
            a.out.display()
        );
        if let Some((_, text, vdir)) = &job.search {
            outln!("\n{text}");
            if let Some(vreport) = &job.variant {
                out!("{}", render::text(vreport));
                outln!("\nreport of the passing variant: {}/report.md", vdir.display());
            }
        }
    }
    if !a.json {
        outln!("total time {:.1} s", t0.elapsed().as_secs_f64());
    }
    Ok(0)
}

/// Run `work`, telling the user each step it starts: a spinner on a terminal, else timed lines
/// on stderr (seconds since `t0`).
fn with_progress<T>(t0: std::time::Instant, work: impl FnOnce(&(dyn Fn(&str) + Sync)) -> Result<T>) -> Result<T> {
    use std::io::IsTerminal;
    let bar = std::io::stderr().is_terminal().then(|| {
        let b = indicatif::ProgressBar::new_spinner();
        b.enable_steady_tick(std::time::Duration::from_millis(120));
        b
    });
    let progress = |step: &str| match &bar {
        Some(b) => b.set_message(step.to_string()),
        None => eprintln!("[{:6.1} s] {step}", t0.elapsed().as_secs_f64()),
    };
    let r = work(&progress);
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    r
}
