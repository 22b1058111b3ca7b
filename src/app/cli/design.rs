//! `vibrofem design`: the vibratory-table design chain and, when it fails, the search.

use super::{check_outputs, emit};
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
    use std::io::IsTerminal;
    let d = match &a.file {
        Some(f) => crate::app::design::Design::from_toml(f)?,
        None => crate::app::design::Design::paper(),
    };
    if !a.yes {
        // A design file's sizes are all valid alone, yet a 5 mm element size or a 10 m plate
        // makes minutes of work: say so before starting.
        let dofs = crate::app::design::estimate_dofs(&d)?;
        if dofs > crate::app::design::LARGE_DESIGN_DOFS {
            return Err(Error::InvalidInput(format!(
                "the design's FE models have about {dofs} DOFs (more than {}): minutes to hours of work; \
                 rerun with --yes to start it, or coarsen the mesh sizes",
                crate::app::design::LARGE_DESIGN_DOFS
            )));
        }
    }
    check_outputs(
        &[],
        Some(("--out", &a.out)),
        &a.file.iter().map(|f| ("design file", f.as_path())).collect::<Vec<_>>(),
    )?;
    let bar = if std::io::stderr().is_terminal() {
        let b = indicatif::ProgressBar::new_spinner();
        b.enable_steady_tick(std::time::Duration::from_millis(120));
        Some(b)
    } else {
        None
    };
    let t0 = std::time::Instant::now();
    let progress = |step: &str| match &bar {
        Some(b) => b.set_message(step.to_string()),
        None => eprintln!("[{:6.1} s] {step}", t0.elapsed().as_secs_f64()),
    };
    let r = crate::app::design::run_design(&d, Some(&a.out), &progress);
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let r = r?;
    let json = serde_json::to_string_pretty(&r).map_err(|e| Error::output("JSON", e))?;
    std::fs::write(a.out.join("report.json"), &json).map_err(|e| Error::io(a.out.join("report.json"), e))?;
    std::fs::write(a.out.join("report.md"), crate::app::design::report_markdown(&r))
        .map_err(|e| Error::io(a.out.join("report.md"), e))?;
    let html = a.out.join("report.html");
    std::fs::write(&html, crate::app::design::report_html(&r, &a.out)).map_err(|e| Error::io(&html, e))?;
    if a.json {
        outln!("{json}");
    } else {
        out!("{}", crate::app::design::verdict_text(&r));
        outln!(
            "
report: {}/report.md (plots and mode shapes beside it)",
            a.out.display()
        );
    }
    if d.search.enabled && r.checks.iter().any(|c| !c.ok) {
        // Issue 13 item 3: a failing design is followed by the lightest passing variant.
        let vdir = a.out.join("passing-variant");
        let bar = if std::io::stderr().is_terminal() {
            let b = indicatif::ProgressBar::new_spinner();
            b.enable_steady_tick(std::time::Duration::from_millis(120));
            Some(b)
        } else {
            None
        };
        let progress = |step: &str| match &bar {
            Some(b) => b.set_message(step.to_string()),
            None => eprintln!("[{:6.1} s] {step}", t0.elapsed().as_secs_f64()),
        };
        std::fs::create_dir_all(&vdir).map_err(|e| Error::io(&vdir, e))?;
        let o = crate::app::design_search::search(&d, Some(&vdir), &progress);
        if let Some(b) = &bar {
            b.finish_and_clear();
        }
        let o = o?;
        let text = crate::app::design_search::search_text(&d, &o);
        std::fs::write(a.out.join("search.txt"), &text).map_err(|e| Error::io(a.out.join("search.txt"), e))?;
        if !a.json {
            outln!("\n{text}");
        }
        if let Some((_, vr)) = &o.best {
            let vjson = serde_json::to_string_pretty(vr).map_err(|e| Error::output("JSON", e))?;
            std::fs::write(vdir.join("report.json"), &vjson).map_err(|e| Error::io(vdir.join("report.json"), e))?;
            std::fs::write(vdir.join("report.md"), crate::app::design::report_markdown(vr))
                .map_err(|e| Error::io(vdir.join("report.md"), e))?;
            let vhtml = vdir.join("report.html");
            std::fs::write(&vhtml, crate::app::design::report_html(vr, &vdir)).map_err(|e| Error::io(&vhtml, e))?;
            if !a.json {
                out!("{}", crate::app::design::verdict_text(vr));
                outln!("\nreport of the passing variant: {}/report.md", vdir.display());
            }
        }
    }
    Ok(0)
}
