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
    let r = with_progress(t0, |p| design::run_design(&d, Some(&a.out), p))?;
    let mut report = design::report::report(&r);
    let env = if d.envelope.enabled {
        let e = with_progress(t0, |p| design::envelope::run(&d, &r, p))?;
        design::envelope::write_tuning_chart(&a.out.join("tuning_chart.svg"), &e)?;
        let at = report
            .sections
            .iter()
            .position(|s| s.id == "checks")
            .map_or(0, |i| i + 1);
        for (k, s) in design::envelope::sections(&e).into_iter().enumerate() {
            report.sections.insert(at + k, s);
        }
        report.data["envelope"] = json_value(&e)?;
        Some(e)
    } else {
        None
    };
    let soft = design::startup::run(&d, &r, design::startup::RAMP_S)?;
    let switched = design::startup::run(&d, &r, 0.0)?;
    let at = report
        .sections
        .iter()
        .position(|s| s.id == "quantities")
        .unwrap_or(report.sections.len());
    report.sections.insert(at, design::startup::section(&soft, &switched));
    report.data["startup"] = serde_json::json!({ "ramped": json_value(&soft)?, "switched": json_value(&switched)? });
    let margin = d.search.required_margin;
    let fails = r.checks.iter().any(|c| !c.ok)
        || env
            .as_ref()
            .is_some_and(|e| d.search.over_envelope && !e.passes(margin));
    let mut search_out = None;
    if d.search.enabled && fails {
        // Issue 13 item 3: a failing design is followed by the lightest passing variant (issue
        // 29 item 7: over the envelope, with the required margin).
        let vdir = a.out.join("passing-variant");
        std::fs::create_dir_all(&vdir).map_err(|e| Error::io(&vdir, e))?;
        let patterns = env.as_ref().map(design::envelope::patterns_of);
        let o = with_progress(t0, |p| design::search_with(&d, Some(&vdir), patterns.as_deref(), p))?;
        let text = design::search_text(&d, &o);
        std::fs::write(a.out.join("search.txt"), &text).map_err(|e| Error::io(a.out.join("search.txt"), e))?;
        report.data["search"] = search_json(&o)?;
        search_out = Some((o, text, vdir));
    }
    render::write_all(&report, &a.out)?;
    if a.json {
        outln!("{}", render::json(&report)?);
    } else {
        out!("{}", render::text(&report));
        outln!(
            "\nreport: {}/report.md (plots and mode shapes beside it)",
            a.out.display()
        );
    }
    if let Some((o, text, vdir)) = &search_out {
        if !a.json {
            outln!("\n{text}");
        }
        if let Some((_, vr)) = &o.best {
            let mut vreport = design::report::report(vr);
            if let Some(e) = &o.envelope {
                design::envelope::write_tuning_chart(&vdir.join("tuning_chart.svg"), e)?;
                let at = vreport
                    .sections
                    .iter()
                    .position(|s| s.id == "checks")
                    .map_or(0, |i| i + 1);
                for (k, s) in design::envelope::sections(e).into_iter().enumerate() {
                    vreport.sections.insert(at + k, s);
                }
                vreport.data["envelope"] = json_value(e)?;
            }
            render::write_all(&vreport, vdir)?;
            if !a.json {
                out!("{}", render::text(&vreport));
                outln!("\nreport of the passing variant: {}/report.md", vdir.display());
            }
        }
    }
    if !a.json {
        outln!("total time {:.1} s", t0.elapsed().as_secs_f64());
    }
    Ok(0)
}

fn json_value<T: serde::Serialize>(x: &T) -> Result<serde_json::Value> {
    serde_json::to_value(x).map_err(|e| Error::output("design --json", e))
}

/// The search under `search` in `design --json`: each variant with its verdict, the passing
/// variant's full checks and envelope, the checks no variant met.
fn search_json(o: &design::SearchOutcome) -> Result<serde_json::Value> {
    let variants: Vec<serde_json::Value> = o
        .candidates
        .iter()
        .map(|c| {
            let verdict = match (&c.failed, c.f1_hz) {
                (Some(f), _) if f.is_empty() => "passes".to_string(),
                (Some(_), _) => "fails".to_string(),
                (None, Some(_)) => "first elastic mode below 3 × excitation, or not run".to_string(),
                (None, None) => "not run".to_string(),
            };
            let mut v = json_value(c)?;
            v["verdict"] = verdict.into();
            Ok(v)
        })
        .collect::<Result<_>>()?;
    let passing = match &o.best {
        Some((v, r)) => serde_json::json!({
            "name": v.name,
            "pull": v.drive.pull,
            "leaves": v.machine.leaves,
            "report": json_value(r)?,
            "envelope": json_value(&o.envelope)?,
        }),
        None => serde_json::Value::Null,
    };
    Ok(serde_json::json!({
        "variants": variants,
        "screened": o.screened,
        "passing": passing,
        "never_met": o.never_met,
    }))
}

/// Run `work`, telling the user each step it starts: a spinner on a terminal, else timed lines
/// on stderr (seconds since `t0`).
fn with_progress<T>(t0: std::time::Instant, work: impl FnOnce(&dyn Fn(&str)) -> Result<T>) -> Result<T> {
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
