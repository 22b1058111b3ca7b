//! The whole `design` job, shared by `vibrofem design` and Python's `vf.design()`: the chain, the
//! envelope, the start-up study and, when a check fails, the search; every report file written
//! into the output folder. The caller prints (the command line) or returns (Python) the result.

use super::{Design, SearchOutcome, envelope, report, run_design, search_text, search_with, startup};
use crate::app::report::{Report, render};
use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// What a design job wrote.
pub struct Job {
    /// The design's report (its `data` is `report.json` and `design --json`).
    pub report: Report,
    /// The search, when it ran: its outcome, its text (`search.txt`) and folder.
    pub search: Option<(SearchOutcome, String, PathBuf)>,
    /// The passing variant's report, when the search found one.
    pub variant: Option<Report>,
}

/// Run the job on `d`, writing the reports into `out` (which exists).
pub fn run(d: &Design, out: &Path, progress: &dyn Fn(&str)) -> Result<Job> {
    let mut r = run_design(d, Some(out), progress)?;
    // Issue 29 item 3: start-up and run-down on the 3D machine's modes, the two-mass estimate
    // beside it (its wall time joins the run's timings).
    progress("start-up and run-down (3D machine and two-mass estimate)");
    let clock = std::time::Instant::now();
    let soft = startup::run(d, &r, startup::RAMP_S)?;
    let switched = startup::run(d, &r, 0.0)?;
    r.timings_s
        .push(("start-up and run-down".into(), clock.elapsed().as_secs_f64()));
    let mut rep = report::report(&r);
    let env = if d.envelope.enabled {
        let e = envelope::run(d, &r, progress)?;
        insert_envelope(&mut rep, &e, out)?;
        Some(e)
    } else {
        None
    };
    let at = rep
        .sections
        .iter()
        .position(|s| s.id == "quantities")
        .unwrap_or(rep.sections.len());
    rep.sections.insert(at, startup::section(&soft, &switched));
    rep.data["startup"] = serde_json::json!({ "ramped": json_value(&soft)?, "switched": json_value(&switched)? });
    let margin = d.search.required_margin;
    let fails = r.checks.iter().any(|c| !c.ok)
        || env
            .as_ref()
            .is_some_and(|e| d.search.over_envelope && !e.passes(margin));
    let mut search = None;
    let mut variant = None;
    if d.search.enabled && fails {
        // Issue 13 item 3: a failing design is followed by the lightest passing variant (issue
        // 29 item 7: over the envelope, with the required margin).
        let vdir = out.join("passing-variant");
        std::fs::create_dir_all(&vdir).map_err(|e| Error::io(&vdir, e))?;
        let patterns = env.as_ref().map(envelope::patterns_of);
        let o = search_with(d, Some(&vdir), patterns.as_deref(), progress)?;
        let text = search_text(d, &o);
        std::fs::write(out.join("search.txt"), &text).map_err(|e| Error::io(out.join("search.txt"), e))?;
        rep.data["search"] = search_json(&o)?;
        if let Some((_, vr)) = &o.best {
            let mut vreport = report::report(vr);
            if let Some(e) = &o.envelope {
                insert_envelope(&mut vreport, e, &vdir)?;
            }
            render::write_all(&vreport, &vdir)?;
            variant = Some(vreport);
        }
        search = Some((o, text, vdir));
    }
    render::write_all(&rep, out)?;
    Ok(Job {
        report: rep,
        search,
        variant,
    })
}

/// The envelope's sections after the checks, its data under `envelope`, its tuning chart.
fn insert_envelope(rep: &mut Report, e: &envelope::EnvelopeResult, dir: &Path) -> Result<()> {
    envelope::write_tuning_chart(&dir.join("tuning_chart.svg"), e)?;
    let at = rep.sections.iter().position(|s| s.id == "checks").map_or(0, |i| i + 1);
    for (k, s) in envelope::sections(e).into_iter().enumerate() {
        rep.sections.insert(at + k, s);
    }
    rep.data["envelope"] = json_value(e)?;
    Ok(())
}

fn json_value<T: serde::Serialize>(x: &T) -> Result<serde_json::Value> {
    serde_json::to_value(x).map_err(|e| Error::output("design --json", e))
}

/// The search under `search` in `design --json`: each variant with its verdict, the passing
/// variant's full checks and envelope, the checks no variant met.
fn search_json(o: &SearchOutcome) -> Result<serde_json::Value> {
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
