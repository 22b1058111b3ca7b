//! The search for a design that passes: when a check of the design chain fails, the table
//! parameters the design file allows (`[search]`: plate thicknesses and widths, web counts in
//! both directions, plate or channel spacers) are combined with the sweep machinery's
//! [`TableSpec`], and the lightest combination that passes every check is reported with its
//! full chain.
//!
//! Order of work, cheapest first: every candidate's steel mass (from its mesh); a screen on the
//! two-mass amplitude, which with the leaves tuned to the target detuning depends only on the
//! masses (c12 = m_red (Ω/z)², exact up to the chain's tuning tolerance); then, lightest first,
//! the table's free–free modal analysis (first elastic mode against the limit) and, for those
//! that pass it, the whole chain with the 3D machine. The first candidate whose chain passes
//! every check is the lightest passing one.
use super::chain::run_design;
use super::envelope::EnvelopeResult;
use super::file::{Design, MAX_SEARCH_VARIANTS, bad};
use super::parts::{coil_fe, table_fe, table_mass};
use super::results::DesignReport;
use crate::Result;
use crate::app::sweep::TableSpec;
use serde::Serialize;
use std::f64::consts::TAU;

/// One candidate and how far it got.
#[derive(Clone, Debug, Serialize)]
pub struct Candidate {
    /// Its table in words.
    pub label: String,
    /// Steel mass of the table (kg, from its mesh).
    pub mass_kg: f64,
    /// Two-mass amplitude with tuned leaves (m).
    pub x1: f64,
    /// First elastic frequency of the table (Hz), if analysed.
    pub f1_hz: Option<f64>,
    /// Failed checks of its whole chain, if run (empty: passed).
    pub failed: Option<Vec<String>>,
}

/// The search's outcome.
pub struct SearchOutcome {
    /// Candidates in the order of mass.
    pub candidates: Vec<Candidate>,
    /// How many passed the amplitude screen.
    pub screened: usize,
    /// The lightest passing variant, with its design and full report.
    pub best: Option<(Design, DesignReport)>,
    /// The passing variant's envelope (when judged over one).
    pub envelope: Option<EnvelopeResult>,
    /// The checks every whole-chain variant missed (no passing variant: the check no variant
    /// could meet).
    pub never_met: Vec<String>,
    /// The given table with plate and with channel spacers: (spacers, mass kg, f1 Hz).
    pub spacer_effect: Vec<(String, f64, f64)>,
}

/// The check ids every variant run whole failed (empty when none was run or one passed).
fn never_met(c: &[Candidate]) -> Vec<String> {
    let runs: Vec<&Vec<String>> = c.iter().filter_map(|c| c.failed.as_ref()).collect();
    if runs.is_empty() || runs.iter().any(|f| f.is_empty()) {
        return vec![];
    }
    let id = |f: &String| f.split(' ').next().unwrap_or("").to_string();
    let mut out: Vec<String> = runs[0].iter().map(id).collect();
    out.retain(|x| runs.iter().all(|f| f.iter().any(|g| &id(g) == x)));
    out
}

fn label(t: &TableSpec, spacers: &str) -> String {
    format!(
        "top {:.0} mm, bottom {:.0} × {:.0} mm, {} long webs over {:.0} mm + {} transverse, {}",
        t.top_thickness * 1e3,
        t.bottom_width * 1e3,
        t.bottom_thickness * 1e3,
        t.n_long_webs,
        t.long_web_span * 1e3,
        t.n_trans_webs,
        if spacers == "channel10" {
            "channel No. 10"
        } else {
            "plate webs"
        }
    )
}

/// The two-mass amplitude X1 of `d` with its table of mass `m_table` and the leaves tuned to
/// the target detuning (c12 = m_red (Ω/z)²), isolators `k_coil` each.
fn screen_x1(d: &Design, m_table: f64, k_coil: f64) -> Result<f64> {
    let omega = TAU * d.excitation_hz;
    let m1 = m_table + d.masses.active_extra + d.masses.load_share * d.masses.load;
    let m2 = d.masses.reactive;
    let m_red = m1 * m2 / (m1 + m2);
    let c12 = m_red * (omega / d.target_detuning).powi(2);
    super::chain::two_mass_x1(d, m1, c12, k_coil)
}

/// Every variant of `d`'s table that the `[search]` lists give (webs within 10 mm of the bottom
/// plate's edge and invalid tables skipped), at most 1000.
fn variants(d: &Design) -> Result<Vec<Design>> {
    let s = &d.search;
    let lw = &d.table.long_webs;
    let span = if lw.len() > 1 {
        lw.iter().copied().fold(f64::NEG_INFINITY, f64::max) - lw.iter().copied().fold(f64::INFINITY, f64::min)
    } else {
        0.3
    };
    let mut base = TableSpec {
        length: d.table.length,
        top_width: d.table.top_width,
        top_thickness: d.table.top_thickness,
        bottom_width: d.table.bottom_width,
        bottom_thickness: d.table.bottom_thickness,
        web_height: d.table.web_height,
        n_long_webs: lw.len(),
        long_web_span: span,
        long_web_thickness: d.table.long_web_thickness,
        n_trans_webs: d.table.trans_webs.len(),
        trans_web_span: s.trans_web_span,
        trans_web_thickness: d.table.trans_web_thickness,
        elem_size: d.table.elem_size,
    };
    base.trans_web_span = s.trans_web_span;
    // `validate` has bounded the combinations (counted before anything is expanded).
    let combinations = s.combinations();
    let mut designs = vec![];
    for &tt in &s.top_thickness {
        for &tb in &s.bottom_thickness {
            for &wb in &s.bottom_width {
                for &nl in &s.n_long_webs {
                    for (&nt, sp, &span) in s
                        .n_trans_webs
                        .iter()
                        .flat_map(|n| s.spacers.iter().map(move |sp| (n, sp)))
                        .flat_map(|(n, sp)| s.long_web_span.iter().map(move |w| (n, sp, w)))
                    {
                        {
                            if nl > 1 && 0.5 * span > 0.5 * wb - 0.01 {
                                continue;
                            }
                            let mut t = base.clone();
                            t.top_thickness = tt;
                            t.bottom_thickness = tb;
                            t.bottom_width = wb;
                            t.n_long_webs = nl;
                            t.n_trans_webs = nt;
                            t.long_web_span = span;
                            if tt < s.top_min {
                                continue;
                            }
                            let Ok(p) = t.params() else { continue };
                            let mut v = d.clone();
                            v.table = p;
                            v.spacers = sp.clone();
                            v.search.enabled = false;
                            v.name = label(&t, sp);
                            designs.extend(drive_and_leaves(&v));
                            if designs.len() > MAX_SEARCH_VARIANTS {
                                return Err(bad(
                                    "search",
                                    format!(
                                        "gives more than {MAX_SEARCH_VARIANTS} variants (of {combinations} combinations): \
                                         shorten its lists"
                                    ),
                                ));
                            }
                        }
                    }
                }
            }
        }
    }
    Ok(designs)
}

/// The variants of `v` with each pull of `search.pull` (the design's if empty) and each move
/// of the leaves of `search.leaf_shift`, the valid ones.
fn drive_and_leaves(v: &Design) -> Vec<Design> {
    let s = &v.search;
    let pulls = if s.pull.is_empty() {
        vec![v.drive.pull]
    } else {
        s.pull.clone()
    };
    let mut out = vec![];
    for &p in &pulls {
        for &dx in &s.leaf_shift {
            let mut w = v.clone();
            w.drive.pull = p;
            for l in &mut w.machine.leaves {
                let n = (l[2] * l[2] + l[3] * l[3]).sqrt();
                l[0] += dx * l[2] / n;
                l[1] += dx * l[3] / n;
            }
            if s.pull.len() > 1 || s.leaf_shift.len() > 1 {
                w.name = format!("{}; pull {p:.0} N, leaves moved {:.0} mm", v.name, dx * 1e3);
            }
            if w.validate().is_ok() {
                out.push(w);
            }
        }
    }
    out
}

/// Whether run `r` of variant `v` passes: every check with `search.required_margin`, over the
/// envelope when `search.over_envelope` and `[envelope]` are on (with the given design's corner
/// patterns); the checks that miss, and the envelope.
fn judge(
    d: &Design,
    v: &Design,
    r: &DesignReport,
    patterns: &dyn Fn() -> Option<Vec<Vec<f64>>>,
    progress: &dyn Fn(&str),
) -> Result<(Vec<String>, Option<EnvelopeResult>)> {
    let margin = d.search.required_margin;
    // The envelope contains the nominal point: a variant short of the margin there is short over
    // the envelope, so its envelope is not run (the checks it misses are the nominal ones).
    let short: Vec<String> = r
        .checks
        .iter()
        .filter(|c| !(c.ok && c.margin >= margin))
        .map(|c| {
            format!(
                "{} (nominal {} vs {})",
                c.id,
                crate::io::fmt_sig(c.value, 4),
                crate::io::fmt_sig(c.limit, 4)
            )
        })
        .collect();
    if short.is_empty() && d.search.over_envelope && d.envelope.enabled {
        let mut v = v.clone();
        v.envelope = d.envelope.clone();
        let env = super::envelope::run_plan(&v, r, patterns().as_deref(), progress)?;
        let short = env
            .short(margin)
            .into_iter()
            .map(|(id, m, at)| format!("{id} (worst margin {:.1} % at {at})", 100.0 * m))
            .collect();
        return Ok((short, Some(env)));
    }
    Ok((short, None))
}

/// Search the variants of `d`'s table for the lightest that passes every check.
/// The whole chains write their plots to `out` (the passing variant's last).
pub fn search(d: &Design, out: Option<&std::path::Path>, progress: &dyn Fn(&str)) -> Result<SearchOutcome> {
    search_with(d, out, None, progress)
}

/// [`search`] reusing the corner patterns of the given design's envelope (`patterns`) for the
/// variants' envelopes.
pub fn search_with(
    d: &Design,
    out: Option<&std::path::Path>,
    patterns: Option<&[Vec<f64>]>,
    progress: &dyn Fn(&str),
) -> Result<SearchOutcome> {
    search_lazy(d, out, &|| patterns.map(<[Vec<f64>]>::to_vec), progress)
}

/// [`search_with`], asking `patterns` for the corner patterns only when a variant passes at its
/// nominal point and is judged over the envelope (the design job runs the search beside the
/// given design's envelope; its patterns are ready when it ends).
pub fn search_lazy(
    d: &Design,
    out: Option<&std::path::Path>,
    patterns: &dyn Fn() -> Option<Vec<Vec<f64>>>,
    progress: &dyn Fn(&str),
) -> Result<SearchOutcome> {
    let s = &d.search;
    s.validate()?;
    let k_coil = coil_fe(d)?;
    let designs = variants(d)?;
    progress(&format!(
        "design search: {} variants, masses and amplitude screen",
        designs.len()
    ));
    let mut rows: Vec<(f64, f64, Design)> = vec![];
    for v in designs {
        let m = table_mass(&v)?;
        let x1 = screen_x1(&v, m, k_coil)?;
        rows.push((m, x1, v));
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut candidates: Vec<Candidate> = rows
        .iter()
        .map(|(m, x1, v)| Candidate {
            label: v.name.clone(),
            mass_kg: *m,
            x1: *x1,
            f1_hz: None,
            failed: None,
        })
        .collect();
    let screened = rows.iter().filter(|r| r.1 >= d.target_amplitude).count();
    let mut best = None;
    let mut envelope = None;
    let mut full_runs = 0;
    for (i, (_, x1, v)) in rows.iter().enumerate() {
        if *x1 < d.target_amplitude {
            continue;
        }
        progress(&format!("design search: table modal, {}", v.name));
        let (_, f, _, _) = table_fe(v)?;
        let f1 = f.first().copied().unwrap_or(0.0);
        candidates[i].f1_hz = Some(f1);
        if f1 < 3.0 * v.excitation_hz {
            continue;
        }
        if full_runs == s.max_full_runs {
            break;
        }
        full_runs += 1;
        progress(&format!("design search: whole chain, {}", v.name));
        let r = run_design(v, out, &|_| {})?;
        let (failed, env) = judge(d, v, &r, patterns, progress)?;
        candidates[i].failed = Some(failed.clone());
        if failed.is_empty() {
            best = Some((v.clone(), r));
            envelope = env;
            break;
        }
    }
    // What the paper's channels change on the given table.
    let mut spacer_effect = vec![];
    for sp in ["plates", "channel10"] {
        let mut v = d.clone();
        v.spacers = sp.into();
        progress(&format!("design search: given table with {sp} spacers"));
        let (m, f, _, _) = table_fe(&v)?;
        spacer_effect.push((sp.to_string(), m, f.first().copied().unwrap_or(f64::NAN)));
    }
    let never_met = never_met(&candidates);
    Ok(SearchOutcome {
        candidates,
        screened,
        best,
        envelope,
        never_met,
        spacer_effect,
    })
}

/// What stopped the variants run whole: the checks that stop every one of them, and how many
/// each check stopped.
fn stoppers(o: &SearchOutcome) -> String {
    let runs: Vec<&Vec<String>> = o.candidates.iter().filter_map(|c| c.failed.as_ref()).collect();
    if runs.is_empty() {
        return "; no variant reached the whole chain".into();
    }
    let id = |f: &String| f.split(' ').next().unwrap_or("").to_string();
    let mut counts: Vec<(String, usize)> = vec![];
    for f in runs.iter().flat_map(|r| r.iter()) {
        match counts.iter_mut().find(|c| c.0 == id(f)) {
            Some(c) => c.1 += 1,
            None => counts.push((id(f), 1)),
        }
    }
    counts.sort_by(|a, b| b.1.cmp(&a.1));
    let every = if o.never_met.is_empty() {
        "no single check stops every variant run".to_string()
    } else {
        format!("the check(s) that stop every variant run: {}", o.never_met.join(", "))
    };
    format!(
        "; {every}; checks failed (variants of {}): {} (a variant short at the nominal point is not run over the envelope)",
        runs.len(),
        counts
            .iter()
            .map(|(k, n)| format!("{k} {n}"))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// The search as text: what was tried, the spacers' effect and the outcome.
pub fn search_text(d: &Design, o: &SearchOutcome) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "design search: {} variants of the table; {} reach the target amplitude in the two-mass model with tuned leaves",
        o.candidates.len(),
        o.screened
    );
    let _ = writeln!(
        s,
        "\n  {:<70} {:>8} {:>9} {:>8}  verdict",
        "variant (lightest first)", "mass kg", "X1 mm", "f1 Hz"
    );
    for c in o.candidates.iter().filter(|c| c.f1_hz.is_some()) {
        let verdict = match (&c.failed, c.f1_hz) {
            (Some(f), _) if f.is_empty() => "PASSES every check".to_string(),
            (Some(f), _) => format!("fails {}", f.join(", ")),
            (None, Some(f1)) if f1 < 3.0 * d.excitation_hz => "first elastic mode below 3 × excitation".into(),
            _ => "not run".into(),
        };
        let _ = writeln!(
            s,
            "  {:<70} {:>8.1} {:>9.4} {:>8.1}  {}",
            c.label,
            c.mass_kg,
            c.x1 * 1e3,
            c.f1_hz.unwrap_or(f64::NAN),
            verdict
        );
    }
    let _ = writeln!(
        s,
        "  ({} variants miss the amplitude target in the two-mass model (they are heavier) and {} were not reached)",
        o.candidates.len() - o.screened,
        o.candidates
            .iter()
            .filter(|c| c.f1_hz.is_none() && c.x1 >= d.target_amplitude)
            .count()
    );
    if let [a, b] = o.spacer_effect.as_slice() {
        let _ = writeln!(
            s,
            "\nspacers on the given table: plate webs {:.1} kg, first elastic mode {:.1} Hz; channel No. 10 (GOST 8240) {:.1} kg ({:+.1} kg), {:.1} Hz ({:+.1} %)",
            a.1,
            a.2,
            b.1,
            b.1 - a.1,
            b.2,
            (b.2 / a.2 - 1.0) * 100.0
        );
    }
    match &o.best {
        Some((v, _)) => {
            let _ = writeln!(s, "\nlightest variant that passes every check: {}", v.name);
        }
        None => {
            let _ = writeln!(
                s,
                "\nno variant passes every check (within search.max_full_runs = {} whole chains){}",
                d.search.max_full_runs,
                stoppers(o)
            );
        }
    }
    s
}
