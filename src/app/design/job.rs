//! The whole `design` job, shared by `vibrofem design` and Python's `vf.design()`: the chain, the
//! envelope, the start-up study and, when a check fails, the search; every report file written
//! into the output folder. The caller prints (the command line) or returns (Python) the result.

use super::results::DesignReport;
use super::search::search_lazy;
use super::{Design, SearchOutcome, envelope, report, run_design, search_text, search_with, startup};
use crate::app::report::{Report, render};
use crate::{Error, Result};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// What a design job wrote.
pub struct Job {
    /// The design's report (its `data` is `report.json` and `design --json`).
    pub report: Report,
    /// The search, when it ran: its outcome, its text (`search.txt`) and folder.
    pub search: Option<(SearchOutcome, String, PathBuf)>,
    /// The passing variant's report, when the search found one.
    pub variant: Option<Report>,
}

/// The studies of the design's own run: start-up (soft and switched, with their wall time) and
/// the envelope.
struct Studies {
    soft: startup::Startup,
    switched: startup::Startup,
    startup_s: f64,
    env: Option<envelope::EnvelopeResult>,
}

fn studies(d: &Design, r: &DesignReport, progress: &dyn Fn(&str)) -> Result<Studies> {
    // Issue 29 item 3: start-up and run-down on the 3D machine's modes, the two-mass estimate
    // beside it (its wall time joins the run's timings).
    progress("start-up and run-down (3D machine and two-mass estimate)");
    let clock = std::time::Instant::now();
    let soft = startup::run(d, r, startup::RAMP_S)?;
    let switched = startup::run(d, r, 0.0)?;
    let startup_s = clock.elapsed().as_secs_f64();
    let env = if d.envelope.enabled {
        Some(envelope::run(d, r, progress)?)
    } else {
        None
    };
    Ok(Studies {
        soft,
        switched,
        startup_s,
        env,
    })
}

/// Run `first` on this thread and `second` on a thread of its own at the same time; `second` may
/// ask for `share` of `first`'s result through the function it is given, which waits until
/// `first` has ended and gives `None` when `first` failed or panicked. Both results are returned
/// (a panic of either is carried on after both have ended). `second` runs on a plain thread, not
/// a worker of the pool: its wait never holds a worker the pool's jobs (`first`'s among them)
/// need.
pub fn beside<A, B, P>(
    first: impl FnOnce() -> Result<A>,
    share: impl FnOnce(&A) -> P,
    second: impl FnOnce(&dyn Fn() -> Option<P>) -> Result<B> + Send,
) -> (Result<A>, Result<B>)
where
    B: Send,
    P: Clone + Send + Sync,
{
    /// Sets the cell to `None` if it is still empty when dropped (on a panic of `first`).
    struct Release<'a, P>(&'a OnceLock<Option<P>>);
    impl<P> Drop for Release<'_, P> {
        fn drop(&mut self) {
            let _ = self.0.set(None);
        }
    }
    let cell: OnceLock<Option<P>> = OnceLock::new();
    let get = || loop {
        if let Some(p) = cell.get() {
            return p.clone();
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    };
    std::thread::scope(|s| {
        let other = s.spawn(|| second(&get));
        let a = {
            let _release = Release(&cell);
            let a = first();
            let _ = cell.set(a.as_ref().ok().map(share));
            a
        };
        let b = match other.join() {
            Ok(b) => b,
            Err(e) => std::panic::resume_unwind(e),
        };
        (a, b)
    })
}

/// Run the job on `d`, writing the reports into `out` (which exists).
///
/// When the design already fails a check at its nominal point the search is certain to run:
/// it then runs on its own thread beside the start-up study and the envelope (both use the
/// worker threads), and asks for the envelope's corner patterns only if a variant passes at its
/// nominal point (it waits for them then). Otherwise it runs after the envelope, when the
/// envelope fails. Either way the results are those of the sequential order: every part is a
/// function of its inputs (the FE memo returns what a computation gives).
pub fn run(d: &Design, out: &Path, progress: &(dyn Fn(&str) + Sync)) -> Result<Job> {
    let mut r = run_design(d, Some(out), progress)?;
    let vdir = out.join("passing-variant");
    // The variants run whole write their plots here; it becomes `vdir` only when one passes.
    let staging = out.join("passing-variant.partial");
    let nominal_fails = r.checks.iter().any(|c| !c.ok);
    let (st, early_search) = if d.search.enabled && nominal_fails {
        crate::io::create_dir(&staging)?;
        let (st, o) = beside(
            || studies(d, &r, progress),
            |st: &Studies| st.env.as_ref().map(envelope::patterns_of),
            |patterns| search_lazy(d, Some(&staging), &|| patterns().flatten(), progress),
        );
        (st, Some(o))
    } else {
        (studies(d, &r, progress), None)
    };
    if st.is_err() {
        let _ = remove_output(&staging);
    }
    let st = st?;
    r.timings_s.push(("start-up and run-down".into(), st.startup_s));
    let mut rep = report::report(&r);
    if let Some(e) = &st.env {
        insert_envelope(&mut rep, e, out)?;
    }
    let at = rep
        .sections
        .iter()
        .position(|s| s.id == "quantities")
        .unwrap_or(rep.sections.len());
    rep.sections.insert(at, startup::section(&st.soft, &st.switched));
    rep.data["startup"] = serde_json::json!({ "ramped": json_value(&st.soft)?, "switched": json_value(&st.switched)? });
    let margin = d.search.required_margin;
    let fails = nominal_fails
        || st
            .env
            .as_ref()
            .is_some_and(|e| d.search.over_envelope && !e.passes(margin));
    let mut search = None;
    let mut variant = None;
    if d.search.enabled && fails {
        // Issue 13 item 3: a failing design is followed by the lightest passing variant (issue
        // 29 item 7: over the envelope, with the required margin).
        let o = match early_search {
            Some(o) => o,
            None => {
                crate::io::create_dir(&staging)?;
                let patterns = st.env.as_ref().map(envelope::patterns_of);
                search_with(d, Some(&staging), patterns.as_deref(), progress)
            }
        };
        let o = settle_variant_dir(o, &staging, &vdir)?;
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
    } else {
        // No search this run: an earlier run's search and passing variant do not belong beside
        // this report.
        remove_output(&vdir)?;
        remove_output(&out.join("search.txt"))?;
    }
    render::write_all(&rep, out)?;
    Ok(Job {
        report: rep,
        search,
        variant,
    })
}

/// Settle the search's staging folder: renamed `vdir` (replacing an earlier run's) when a
/// variant passed, removed otherwise or when the search failed. The plots of the failing
/// variants run whole under the name `passing-variant`, or an earlier run's passing variant
/// beside this run's report, would mislead.
fn settle_variant_dir(o: Result<SearchOutcome>, staging: &Path, vdir: &Path) -> Result<SearchOutcome> {
    remove_output(vdir)?;
    match &o {
        Ok(o) if o.best.is_some() => std::fs::rename(staging, vdir).map_err(|e| Error::io(vdir, e))?,
        _ => remove_output(staging)?,
    }
    o
}

/// Remove the file or folder `path` (and what it holds); one that is not there is fine.
fn remove_output(path: &Path) -> Result<()> {
    let removed = if path.is_dir() {
        std::fs::remove_dir_all(path)
    } else {
        std::fs::remove_file(path)
    };
    match removed {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(Error::io(path, e)),
        _ => Ok(()),
    }
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
