//! Load cases and tolerance bands: every check of the design over its envelope.
//!
//! The design file's `[envelope]` ([`EnvelopeDesign`]) declares load cases (sets of design keys,
//! e.g. an empty table, a share of the load moving with the table, an eccentric load) and
//! tolerance bands (a parameter given by one or more design keys, moved by an absolute or a
//! relative amount each way). Both act on the design's serialized form: a key path such as
//! `leaf.material.0` is set in the design's JSON value, which is read back as a [`Design`] and
//! validated, so a band works for any field of the file, present or future.
//!
//! The envelope is taken about the machine *as built*: the design with its leaves at the tuned
//! thickness and `tune = "none"` (a tolerance must not be tuned away). The plan, with its count
//! stated in the report:
//! 1. the nominal run (the as-built design);
//! 2. one forward finite difference per parameter, at `fd_step` × its band: the sensitivity of
//!    every check's value and margin;
//! 3. per load case, the corners of the tolerance box that the margins' gradients point to:
//!    for each check the corner against its margin's gradient (its worst corner) and the opposite
//!    one (the vertex method; corners several checks share are run once);
//! 4. per load case and mirror pair of corners between which the 3D machine's working mode
//!    crosses the excitation, the point on that segment where it does (linear in the detuning
//!    of the two ends): the amplitude's peak lies inside the box there, not at a corner.
//!
//! Every run is a whole [`run_design`] of its own [`Design`] (kept with the run): a corner
//! equals a single run of that design. The FE parts that do not change between runs (the work
//! table's modal run, the leaf's statics per thickness, the coil) come from the memo of
//! [`super::cache`].

use super::chain::run_design;
use super::file::{Design, bad};
use super::reduced::{Plan, within};
use super::results::{Check, DesignReport};
use crate::Result;
use crate::app::report::{Block, Cell, Column, Figure, Section, Table};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;
use std::sync::Arc;

/// `[envelope]` of a design file.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvelopeDesign {
    /// Run the envelope (with `vibrofem design`).
    pub enabled: bool,
    /// Load cases, each a set of design keys.
    pub load_cases: Vec<LoadCase>,
    /// Tolerance bands.
    pub tolerances: Vec<Tolerance>,
    /// Finite-difference step of the sensitivities, as a fraction of each band's `plus`.
    pub fd_step: f64,
    /// Run the 3D machine of the envelope's points (all but the nominal one) in a reduced
    /// (Ritz) basis per geometry and load case ([`super::reduced`]); `false`: every run full.
    pub reduced: bool,
    /// Bar on a reduced run's backward errors (every mode it uses); over it, the run is full.
    pub reduced_tol: f64,
}

/// A load case: design keys set to values (`set = { "masses.load" = 0.0 }`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadCase {
    /// Stable id (and name) of the case.
    pub name: String,
    /// Key path (dots; array items by index, `leaf.material.0`) → value.
    #[serde(default)]
    pub set: BTreeMap<String, Value>,
}

/// A tolerance band on a parameter.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tolerance {
    /// Stable id.
    pub id: String,
    /// What it is.
    pub name: String,
    /// The design keys it moves (together); `a|b` takes the first of `a`, `b` the design has.
    pub keys: Vec<String>,
    /// Band below the nominal value (absolute, or a fraction with `relative`).
    pub minus: f64,
    /// Band above.
    pub plus: f64,
    /// The band is a fraction of each key's value.
    #[serde(default)]
    pub relative: bool,
}

impl Default for EnvelopeDesign {
    /// Four load cases (empty table, nominal, 30 % of the load moving with the table, that load
    /// off centre by a quarter of the table's length and width) and five bands (leaf clamping
    /// ±0.03, leaf thickness ±0.1 mm, the leaves' E ±1.5 %, mains ±0.4 %, damping ±30 %):
    /// docs/design-envelope.md gives their sources.
    fn default() -> Self {
        let case = |name: &str, set: &[(&str, Value)]| LoadCase {
            name: name.into(),
            set: set.iter().map(|(k, v)| (k.to_string(), v.clone())).collect(),
        };
        let tol = |id: &str, name: &str, keys: &[&str], band: f64, relative: bool| Tolerance {
            id: id.into(),
            name: name.into(),
            keys: keys.iter().map(|k| k.to_string()).collect(),
            minus: band,
            plus: band,
            relative,
        };
        let share = ("masses.load_share", Value::from(0.3));
        EnvelopeDesign {
            enabled: true,
            load_cases: vec![
                case("empty", &[("masses.load", 0.0.into()), ("damping.mu1", 0.0.into())]),
                case("nominal", &[]),
                case("share", std::slice::from_ref(&share)),
                case(
                    "eccentric",
                    &[share.clone(), ("masses.load_offset", serde_json::json!([0.3, 0.15]))],
                ),
            ],
            tolerances: vec![
                tol("clamping", "leaf clamping coefficient", &["leaf.clamping"], 0.03, false),
                tol("thickness", "leaf thickness [m]", &["leaf.thickness"], 1e-4, false),
                tol("young", "leaf steel E (temperature)", &["leaf.material.0"], 0.015, true),
                tol(
                    "mains",
                    "mains frequency",
                    &["drive.mains_hz|excitation_hz"],
                    0.004,
                    true,
                ),
                tol(
                    "damping",
                    "damping μ1, μ12, μ13",
                    &["damping.mu1", "damping.mu12", "damping.mu13"],
                    0.3,
                    true,
                ),
            ],
            fd_step: 0.1,
            reduced: true,
            reduced_tol: super::reduced::DEFAULT_TOL,
        }
    }
}

/// The slot of `path` (dots; array items by index) in `v`.
fn slot<'a>(v: &'a mut Value, path: &str) -> Option<&'a mut Value> {
    let mut cur = v;
    for seg in path.split('.') {
        cur = match cur {
            Value::Object(m) => m.get_mut(seg)?,
            Value::Array(a) => a.get_mut(seg.parse::<usize>().ok()?)?,
            _ => return None,
        };
    }
    Some(cur)
}

/// The first alternative of `key` (`a|b`) that `v` has as a number.
fn resolve(v: &Value, key: &str) -> Option<String> {
    let mut v = v.clone();
    key.split('|')
        .find(|k| slot(&mut v, k).is_some_and(|s| s.is_f64() || s.is_i64() || s.is_u64()))
        .map(str::to_string)
}

/// A design's JSON value (the file's keys).
fn to_value(d: &Design) -> Result<Value> {
    serde_json::to_value(d).map_err(|e| bad("envelope", format!("the design does not serialize: {e}")))
}

/// Read a JSON value back as a design (the envelope and the search off) and validate it;
/// errors name `at`.
fn from_value(v: Value, at: &str) -> Result<Design> {
    let mut d: Design =
        serde_json::from_value(v).map_err(|e| bad(at, format!("gives a design that does not read: {e}")))?;
    d.envelope.enabled = false;
    d.search.enabled = false;
    d.validate()
        .map_err(|e| bad(at, format!("gives an invalid design: {e}")))?;
    Ok(d)
}

impl EnvelopeDesign {
    /// Check the section against the design `d` (keys present, bands in range, each load case
    /// and each band's ends a valid design), and `masses.load_offset`; errors name the key.
    pub fn validate(&self, d: &Design) -> Result<()> {
        let o = d.masses.load_offset;
        if !o.iter().all(|x| x.is_finite()) || o[0].abs() > 0.5 * d.table.length || o[1].abs() > 0.5 * d.table.top_width
        {
            return Err(bad(
                "masses.load_offset",
                format!("must lie on the work surface (|x| ≤ length/2, |y| ≤ top_width/2), got {o:?}"),
            ));
        }
        if !self.enabled {
            return Ok(());
        }
        if !(self.fd_step.is_finite() && self.fd_step > 0.0 && self.fd_step <= 1.0) {
            return Err(bad(
                "envelope.fd_step",
                format!("must be above 0 and at most 1, got {}", self.fd_step),
            ));
        }
        if !(self.reduced_tol.is_finite() && self.reduced_tol > 0.0 && self.reduced_tol < 1.0) {
            return Err(bad(
                "envelope.reduced_tol",
                format!("must be above 0 and below 1, got {}", self.reduced_tol),
            ));
        }
        let mut base = to_value(d)?;
        if let Some(e) = slot(&mut base, "envelope.enabled") {
            *e = Value::Bool(false);
        }
        for (i, c) in self.load_cases.iter().enumerate() {
            let at = format!("envelope.load_cases[{i}]");
            if c.name.trim().is_empty() || self.load_cases[..i].iter().any(|o| o.name == c.name) {
                return Err(bad(&at, format!("needs a name of its own, got '{}'", c.name)));
            }
            let mut v = base.clone();
            for (k, x) in &c.set {
                *slot(&mut v, k).ok_or_else(|| bad(&at, format!("sets '{k}', which is not a key of the design")))? =
                    x.clone();
            }
            from_value(v, &at)?;
        }
        let mut seen = vec![];
        for (i, t) in self.tolerances.iter().enumerate() {
            let at = format!("envelope.tolerances[{i}]");
            if t.id.trim().is_empty() || seen.contains(&t.id) {
                return Err(bad(&at, format!("needs an id of its own, got '{}'", t.id)));
            }
            seen.push(t.id.clone());
            let ok = |x: f64| x.is_finite() && x >= 0.0 && (!t.relative || x < 1.0);
            if !(ok(t.minus) && ok(t.plus)) || t.keys.is_empty() {
                return Err(bad(
                    &at,
                    format!(
                        "'{}': keys must not be empty and minus, plus must be ≥ 0{} (got {}, {})",
                        t.id,
                        if t.relative { " and below 1" } else { "" },
                        t.minus,
                        t.plus
                    ),
                ));
            }
            for k in &t.keys {
                resolve(&base, k).ok_or_else(|| bad(&at, format!("'{k}' is not a number key of the design")))?;
            }
            for s in [-1.0, 1.0] {
                let mut tv = vec![0.0; self.tolerances.len()];
                tv[i] = s;
                from_value(self.perturb(&base, &tv)?, &format!("{at} ('{}' at {s:+})", t.id))?;
            }
        }
        Ok(())
    }

    /// `base` with every band moved to `t` (−1: the band's lower end, +1: its upper end).
    fn perturb(&self, base: &Value, t: &[f64]) -> Result<Value> {
        let mut v = base.clone();
        for (tol, &ti) in self.tolerances.iter().zip(t) {
            if ti == 0.0 {
                continue;
            }
            let band = if ti > 0.0 { tol.plus } else { tol.minus };
            for k in &tol.keys {
                let k = resolve(&v, k).ok_or_else(|| bad("envelope.tolerances", format!("no key '{k}'")))?;
                let s = slot(&mut v, &k).ok_or_else(|| bad("envelope.tolerances", format!("no key '{k}'")))?;
                let x = s.as_f64().unwrap_or(0.0);
                let y = if tol.relative {
                    x * (1.0 + ti * band)
                } else {
                    x + ti * band
                };
                *s = Value::from(y);
                // A given mains frequency fixes the excitation at twice it (the file's
                // validation): the band moves both, or a valid design would read as invalid.
                if k == "drive.mains_hz" && x != 0.0 {
                    if let Some(e) = slot(&mut v, "excitation_hz") {
                        *e = Value::from(e.as_f64().unwrap_or(0.0) * (y / x));
                    }
                }
            }
        }
        Ok(v)
    }

    /// The design of load case `case` (None: as built) with the bands at `t`.
    pub fn design_at(&self, as_built: &Design, case: Option<usize>, t: &[f64]) -> Result<Design> {
        let mut v = to_value(as_built)?;
        let at = match case {
            Some(i) => {
                for (k, x) in &self.load_cases[i].set {
                    if let Some(s) = slot(&mut v, k) {
                        *s = x.clone();
                    }
                }
                format!("envelope.load_cases[{i}] with the bands at {t:?}")
            }
            None => format!("envelope: the bands at {t:?}"),
        };
        from_value(self.perturb(&v, t)?, &at)
    }

    /// The nominal value of each band's first key in `d`.
    fn nominal_values(&self, d: &Design) -> Result<Vec<f64>> {
        let mut v = to_value(d)?;
        self.tolerances
            .iter()
            .map(|t| {
                let k = resolve(&v, &t.keys[0]).unwrap_or_default();
                Ok(slot(&mut v, &k).and_then(|s| s.as_f64()).unwrap_or(f64::NAN))
            })
            .collect()
    }
}

/// The design as built: the leaves at the thickness the run `r` of `d` used, `tune = "none"`.
pub fn as_built(d: &Design, r: &DesignReport) -> Design {
    let mut b = d.clone();
    // The model of record's thickness (tuned on the 3D machine), not the two-mass tuning's.
    if r.leaf_thickness_m.is_finite() && r.leaf_thickness_m > 0.0 {
        b.leaf.thickness = r.leaf_thickness_m;
    }
    b.tune = "none".into();
    b.envelope.enabled = false;
    b.search.enabled = false;
    b
}

/// One run of the envelope.
#[derive(Clone, Debug, Serialize)]
pub struct EnvelopeRun {
    /// What it is (`nominal`, `d clamping`, `empty corner 3`, …).
    pub label: String,
    /// Its load case (`nominal` for the as-built design).
    pub case: String,
    /// Where each band is (−1 … +1, by the tolerances' ids).
    pub at: BTreeMap<String, f64>,
    /// Every check's value, by id.
    pub values: BTreeMap<String, f64>,
    /// The design of this run (a single run of it gives the same checks).
    #[serde(skip)]
    pub design: Design,
    /// Its checks.
    #[serde(skip)]
    pub checks: Vec<Check>,
    /// The 3D machine's working mode against the excitation, f_w/f_e − 1 (NaN: none).
    pub working_detuning: f64,
}

/// One check over the envelope.
#[derive(Clone, Debug, Serialize)]
pub struct CheckEnvelope {
    /// Stable id.
    #[serde(skip)]
    pub id: String,
    /// What is checked (with its unit).
    pub name: String,
    /// Smallest value over the runs.
    pub min: f64,
    /// Value at the nominal point.
    pub nominal: f64,
    /// Largest value over the runs.
    pub max: f64,
    /// Limit at the nominal point.
    pub limit: f64,
    /// The value must stay at or below the limit.
    pub upper: bool,
    /// Smallest margin over the runs (a fraction of the limit).
    pub worst_margin: f64,
    /// The run with the smallest margin.
    pub worst_run: String,
    /// Passed in every run.
    pub ok: bool,
}

/// One parameter's band and sensitivities.
#[derive(Clone, Debug, Serialize)]
pub struct Sensitivity {
    /// The band's id.
    #[serde(skip)]
    pub id: String,
    /// What it is.
    pub name: String,
    /// The keys it moves.
    pub keys: Vec<String>,
    /// Nominal value of its first key.
    pub nominal: f64,
    /// Band below and above (absolute, or fractions when `relative`).
    pub minus: f64,
    /// Above.
    pub plus: f64,
    /// Fractions of the keys' values.
    pub relative: bool,
    /// Finite-difference step (in the band's units).
    pub step: f64,
    /// ∂value/∂p per check id (per unit of the key, or per unit of relative change).
    pub d_value: BTreeMap<String, f64>,
}

/// The envelope of a design.
#[derive(Clone, Debug, Serialize)]
pub struct EnvelopeResult {
    /// How the points were chosen, in words.
    pub method: String,
    /// Load cases, by name.
    pub load_cases: Vec<String>,
    /// Every check over the runs (in JSON: by check id).
    #[serde(serialize_with = "by_id_checks")]
    pub checks: Vec<CheckEnvelope>,
    /// The parameters with their bands and sensitivities (in JSON: by id).
    #[serde(serialize_with = "by_id_params")]
    pub sensitivities: Vec<Sensitivity>,
    /// Every run.
    pub runs: Vec<EnvelopeRun>,
    /// The tolerances' ids in the design file's order.
    #[serde(skip)]
    pub tolerance_order: Vec<String>,
    /// Wall time of the envelope, s.
    pub seconds: f64,
    /// Requests for FE parts during the envelope served by a part already computed (or being
    /// computed by another thread at the time).
    pub memo_hits: usize,
    /// Distinct FE parts computed during the envelope.
    pub memo_misses: usize,
    /// 3D machine runs of the points (the nominal one aside) made in the reduced basis.
    pub reduced_runs: usize,
    /// Those made on the full model (reduction off, a rigid table's aside: no basis, or over
    /// the bar).
    pub full_runs: usize,
    /// Of the full runs, those whose reduced run was over the bar.
    pub reduced_fallbacks: usize,
    /// Largest backward error of the modes of an accepted reduced run.
    pub reduced_max_backward_error: f64,
    /// The bar (`envelope.reduced_tol`).
    pub reduced_tol: f64,
}

fn by_id_checks<S: serde::Serializer>(c: &[CheckEnvelope], ser: S) -> std::result::Result<S::Ok, S::Error> {
    crate::app::report::by_id(c, |x| x.id.as_str(), ser)
}

fn by_id_params<S: serde::Serializer>(c: &[Sensitivity], ser: S) -> std::result::Result<S::Ok, S::Error> {
    crate::app::report::by_id(c, |x| x.id.as_str(), ser)
}

impl EnvelopeResult {
    /// Every check holds over the envelope with at least `margin` (a fraction of its limit).
    pub fn passes(&self, margin: f64) -> bool {
        self.checks.iter().all(|c| c.ok && c.worst_margin >= margin)
    }

    /// The checks that miss `margin` somewhere: (id, worst margin, where).
    pub fn short(&self, margin: f64) -> Vec<(String, f64, String)> {
        self.checks
            .iter()
            .filter(|c| !(c.ok && c.worst_margin >= margin))
            .map(|c| (c.id.clone(), c.worst_margin, c.worst_run.clone()))
            .collect()
    }
}

/// The 3D machine's working mode against the excitation of `d`: f_w/f_e − 1 (NaN: none).
fn working_detuning(d: &Design, r: &DesignReport) -> f64 {
    let fe = d.excitation_hz;
    r.machine_modes
        .iter()
        .filter(|m| m.name.starts_with("working"))
        .map(|m| m.frequency_hz / fe - 1.0)
        .min_by(|a, b| a.abs().total_cmp(&b.abs()))
        .unwrap_or(f64::NAN)
}

/// Run `d` as one point of the envelope.
fn run_point(e: &EnvelopeDesign, d: Design, label: String, case: &str, t: &[f64]) -> Result<EnvelopeRun> {
    let r = run_design(&d, None, &|_| {})?;
    Ok(EnvelopeRun {
        at: e.tolerances.iter().zip(t).map(|(x, &v)| (x.id.clone(), v)).collect(),
        values: r.checks.iter().map(|c| (c.id.clone(), c.value)).collect(),
        working_detuning: working_detuning(&d, &r),
        checks: r.checks,
        design: d,
        label,
        case: case.into(),
    })
}

/// [`run_point`] over independent `points` (design, label, band position) of load case `case`,
/// on the worker threads (the FE memo is shared; each run is whole), in the given order.
/// The reduced plan of the calling thread ([`super::reduced::current`]) goes with each run.
fn run_points(e: &EnvelopeDesign, points: Vec<(Design, String, Vec<f64>)>, case: &str) -> Result<Vec<EnvelopeRun>> {
    use rayon::prelude::*;
    let plan = super::reduced::current();
    points
        .into_par_iter()
        .map(|(d, label, t)| super::reduced::within(plan.as_ref(), || run_point(e, d, label, case, &t)))
        .collect()
}

/// The reduced plan of an envelope about `built`: a basis per machine base of the load cases
/// (and of the as-built design), built in parallel, unless `envelope.reduced` is off.
fn reduced_plan(e: &EnvelopeDesign, built: &Design, progress: &dyn Fn(&str)) -> Result<Arc<Plan>> {
    use rayon::prelude::*;
    let plan = Arc::new(Plan::new(e.reduced, e.reduced_tol));
    if !e.reduced {
        return Ok(plan);
    }
    let nt = e.tolerances.len();
    let mut designs = vec![e.design_at(built, None, &vec![0.0; nt])?];
    for ci in 0..e.load_cases.len() {
        designs.push(e.design_at(built, Some(ci), &vec![0.0; nt])?);
    }
    let mut keys = vec![];
    designs.retain(|d| {
        let k = super::machine::base_memo_key(d);
        let new = !keys.contains(&k);
        keys.push(k);
        new
    });
    progress(&format!(
        "envelope: reduced bases of the 3D machine ({} geometries and loads, in parallel)",
        designs.len()
    ));
    designs
        .par_iter()
        .try_for_each(|d| super::machine::prepare_basis(d, &plan))?;
    Ok(plan)
}

/// The corner sign patterns of the checks' margins: per check with a gradient, the corner
/// against it and the opposite one (each pattern once, the worst corners first).
pub fn corner_patterns(grad: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = vec![];
    let sign = |g: f64| if g > 0.0 { 1.0 } else { -1.0 };
    for g in grad {
        if g.iter().all(|x| !x.is_finite() || *x == 0.0) {
            continue;
        }
        let worst: Vec<f64> = g
            .iter()
            .map(|&x| if x.is_finite() && x != 0.0 { -sign(x) } else { 1.0 })
            .collect();
        let best: Vec<f64> = worst.iter().map(|x| -x).collect();
        for p in [worst, best] {
            if !out.contains(&p) {
                out.push(p);
            }
        }
    }
    out
}

/// Margins by check id.
fn margins(c: &[Check]) -> BTreeMap<String, f64> {
    c.iter().map(|c| (c.id.clone(), c.margin)).collect()
}

/// The envelope of design `d` whose own run gave `r`: the plan of the module's documentation.
pub fn run(d: &Design, r: &DesignReport, progress: &dyn Fn(&str)) -> Result<EnvelopeResult> {
    run_plan(d, r, None, progress)
}

/// The corner sign patterns an envelope ran (to reuse on a variant of its design).
pub fn patterns_of(e: &EnvelopeResult) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = vec![];
    for r in e
        .runs
        .iter()
        .filter(|r| r.label.starts_with(&format!("{} corner ", r.case)))
    {
        let p: Vec<f64> = e
            .tolerance_order
            .iter()
            .map(|id| r.at.get(id).copied().unwrap_or(0.0))
            .collect();
        if !out.contains(&p) {
            out.push(p);
        }
    }
    out
}

/// The envelope with the corner patterns `given` (no sensitivities then), or as [`run`].
pub fn run_plan(
    d: &Design,
    r: &DesignReport,
    given: Option<&[Vec<f64>]>,
    progress: &dyn Fn(&str),
) -> Result<EnvelopeResult> {
    let t0 = std::time::Instant::now();
    let (h0, m0) = super::cache::stats();
    let e = &d.envelope;
    let built = as_built(d, r);
    let nt = e.tolerances.len();
    progress("envelope: nominal point (as built)");
    let nominal = run_point(
        e,
        e.design_at(&built, None, &vec![0.0; nt])?,
        "nominal".into(),
        "nominal",
        &vec![0.0; nt],
    )?;
    let plan = reduced_plan(e, &built, progress)?;
    let (sens, fd_runs) = match given {
        Some(_) => (vec![], vec![]),
        None => within(Some(&plan), || sensitivities(e, &built, &nominal, progress))?,
    };
    let grad: Vec<Vec<f64>> = nominal
        .checks
        .iter()
        .map(|c| sens.iter().map(|s| s.1.get(&c.id).copied().unwrap_or(0.0)).collect())
        .collect();
    let patterns = given.map_or_else(|| corner_patterns(&grad), |p| p.to_vec());
    let mut runs = vec![nominal];
    runs.extend(fd_runs);
    for ci in 0..e.load_cases.len() {
        runs.extend(within(Some(&plan), || corners(e, &built, ci, &patterns, progress))?);
    }
    let nominal_values = e.nominal_values(&built)?;
    let sensitivities = e
        .tolerances
        .iter()
        .zip(&sens)
        .zip(nominal_values)
        .map(|((t, s), nominal)| Sensitivity {
            id: t.id.clone(),
            name: t.name.clone(),
            keys: t.keys.clone(),
            nominal,
            minus: t.minus,
            plus: t.plus,
            relative: t.relative,
            step: e.fd_step * t.plus,
            d_value: s.0.clone(),
        })
        .collect();
    let (h1, m1) = super::cache::stats();
    let counts = plan.stats();
    Ok(EnvelopeResult {
        method: format!(
            "vertex method: the nominal point, {} forward differences at {} of each band, then per load case \
             the corners the checks' margin gradients point to ({} sign patterns, each check's worst corner and \
             its opposite{}) and, where the 3D working mode crosses the excitation between opposite corners, the \
             crossing point; {} runs of the whole chain",
            sens.len(),
            e.fd_step,
            patterns.len(),
            if given.is_some() {
                ", taken from the given design's envelope"
            } else {
                ""
            },
            runs.len()
        ),
        tolerance_order: e.tolerances.iter().map(|t| t.id.clone()).collect(),
        load_cases: e.load_cases.iter().map(|c| c.name.clone()).collect(),
        checks: aggregate(&runs),
        sensitivities,
        runs,
        seconds: t0.elapsed().as_secs_f64(),
        memo_hits: h1 - h0,
        memo_misses: m1 - m0,
        reduced_runs: counts.reduced_runs,
        full_runs: counts.full_runs,
        reduced_fallbacks: counts.fallbacks,
        reduced_max_backward_error: counts.max_backward_error,
        reduced_tol: e.reduced_tol,
    })
}

/// A change of a check's margin (a fraction of its limit) below which a forward difference
/// counts as none.
const MARGIN_NOISE: f64 = 1e-7;

/// The forward difference (v − v0)/step of a check's value, 0 when the change is within
/// [`MARGIN_NOISE`] of the value itself: rounding, not a direction. A reduced run resolves a
/// value only to its backward errors (up to `reduced_tol`, 1e-7 by default), so a quotient of
/// ~1e-8 printed beside real ones (the mode clearance against the damping, which it does not
/// depend on) would be noise read as a sensitivity. No nominal value: NaN.
fn value_quotient(v: f64, v0: Option<f64>, step: f64) -> f64 {
    let Some(v0) = v0 else { return f64::NAN };
    forward_difference(v - v0, MARGIN_NOISE * v.abs().max(v0.abs()), step)
}

/// d/step, or 0 when the change d is within `noise` (no direction).
fn forward_difference(d: f64, noise: f64, step: f64) -> f64 {
    if d.abs() <= noise { 0.0 } else { d / step }
}

/// One forward difference per band at the nominal point: (∂value/∂p, ∂margin/∂p) per check id,
/// and the runs.
#[allow(clippy::type_complexity)]
fn sensitivities(
    e: &EnvelopeDesign,
    built: &Design,
    nominal: &EnvelopeRun,
    progress: &dyn Fn(&str),
) -> Result<(Vec<(BTreeMap<String, f64>, BTreeMap<String, f64>)>, Vec<EnvelopeRun>)> {
    let nt = e.tolerances.len();
    let m0 = margins(&nominal.checks);
    progress("envelope: sensitivities (one run per band, in parallel)");
    let points: Vec<(Design, String, Vec<f64>)> = e
        .tolerances
        .iter()
        .enumerate()
        .map(|(i, tol)| {
            let mut t = vec![0.0; nt];
            t[i] = e.fd_step;
            Ok((e.design_at(built, None, &t)?, format!("d {}", tol.id), t))
        })
        .collect::<Result<_>>()?;
    let runs = run_points(e, points, "nominal")?;
    let mut out = vec![];
    for (tol, run) in e.tolerances.iter().zip(&runs) {
        let step = e.fd_step * tol.plus;
        let dv = run
            .values
            .iter()
            .map(|(k, v)| (k.clone(), value_quotient(*v, nominal.values.get(k).copied(), step)))
            .collect();
        let dm = margins(&run.checks)
            .into_iter()
            .map(|(k, m)| {
                let dm = m - m0.get(&k).copied().unwrap_or(f64::NAN);
                // A margin change below MARGIN_NOISE is no direction: a reduced run carries
                // rounding of that order (backward errors up to `reduced_tol`), where the full run
                // of an insensitive check gives exactly 0.
                let g = forward_difference(dm, MARGIN_NOISE, step);
                (k, if g.is_finite() { g } else { 0.0 })
            })
            .collect();
        out.push((dv, dm));
    }
    Ok((out, runs))
}

/// The corners of load case `ci` for `patterns`, and the working mode's crossing points between
/// opposite corners.
fn corners(
    e: &EnvelopeDesign,
    built: &Design,
    ci: usize,
    patterns: &[Vec<f64>],
    progress: &dyn Fn(&str),
) -> Result<Vec<EnvelopeRun>> {
    let name = &e.load_cases[ci].name;
    let mut runs: Vec<EnvelopeRun> = vec![];
    if patterns.is_empty() {
        let t = vec![0.0; e.tolerances.len()];
        progress(&format!("envelope: {name}"));
        runs.push(run_point(e, e.design_at(built, Some(ci), &t)?, name.clone(), name, &t)?);
        return Ok(runs);
    }
    progress(&format!("envelope: {name}, {} corners (in parallel)", patterns.len()));
    let points: Vec<(Design, String, Vec<f64>)> = patterns
        .iter()
        .enumerate()
        .map(|(k, p)| {
            Ok((
                e.design_at(built, Some(ci), p)?,
                format!("{name} corner {}", k + 1),
                p.clone(),
            ))
        })
        .collect::<Result<_>>()?;
    runs.extend(run_points(e, points, name)?);
    let mut crossings = vec![];
    for (a, ra) in runs.iter().enumerate() {
        for rb in runs.iter().skip(a + 1) {
            let mirror = ra.at.values().zip(rb.at.values()).all(|(x, y)| *x == -*y);
            let (da, db) = (ra.working_detuning, rb.working_detuning);
            if mirror && da.is_finite() && db.is_finite() && da * db < 0.0 {
                let s = da / (da - db);
                let t: Vec<f64> = ra
                    .at
                    .values()
                    .zip(rb.at.values())
                    .map(|(x, y)| x + s * (y - x))
                    .collect();
                // `at` is keyed by id (sorted): back to the tolerances' order.
                let t: Vec<f64> = e
                    .tolerances
                    .iter()
                    .map(|tol| {
                        let i = ra.at.keys().position(|k| k == &tol.id).unwrap_or(0);
                        t[i]
                    })
                    .collect();
                crossings.push((format!("{name} resonance between {} and {}", ra.label, rb.label), t));
            }
        }
    }
    if !crossings.is_empty() {
        progress(&format!(
            "envelope: {name}, {} resonance crossings (in parallel)",
            crossings.len()
        ));
    }
    let points: Vec<(Design, String, Vec<f64>)> = crossings
        .into_iter()
        .map(|(label, t)| Ok((e.design_at(built, Some(ci), &t)?, label, t)))
        .collect::<Result<_>>()?;
    runs.extend(run_points(e, points, name)?);
    Ok(runs)
}

/// Every check over the runs (the first run is the nominal one).
fn aggregate(runs: &[EnvelopeRun]) -> Vec<CheckEnvelope> {
    let Some(nominal) = runs.first() else { return vec![] };
    nominal
        .checks
        .iter()
        .map(|c0| {
            let mut out = CheckEnvelope {
                id: c0.id.clone(),
                name: c0.name.clone(),
                min: c0.value,
                nominal: c0.value,
                max: c0.value,
                limit: c0.limit,
                upper: c0.upper,
                worst_margin: c0.margin,
                worst_run: nominal.label.clone(),
                ok: c0.ok,
            };
            for r in runs {
                for c in r.checks.iter().filter(|c| c.id == c0.id) {
                    out.min = out.min.min(c.value);
                    out.max = out.max.max(c.value);
                    out.ok &= c.ok;
                    if worse(c.margin, out.worst_margin) {
                        out.worst_margin = c.margin;
                        out.worst_run = r.label.clone();
                    }
                }
            }
            out
        })
        .collect()
}

/// Whether margin `a` is worse than `b` (or not a number): lower by more than 1e-9 of their
/// size. Margins that agree to rounding are one tie, and the first run keeps it, so that the
/// "worst at" of two runs that are the same in exact arithmetic (two corners whose bands do not
/// touch the check) does not follow the last digits of the eigen solutions (verified to ~1e-12).
fn worse(a: f64, b: f64) -> bool {
    a.is_nan() || a < b - 1e-9 * a.abs().max(b.abs())
}

/// How the envelope's 3D machine runs were made, in words.
fn reduced_words(e: &EnvelopeResult) -> String {
    if e.reduced_runs == 0 && e.full_runs == 0 {
        return "3D machine runs: all of a rigid table (12 DOFs, no reduced basis)".into();
    }
    if e.reduced_runs == 0 && e.reduced_fallbacks == 0 {
        return format!("3D machine runs: {} on the full model", e.full_runs);
    }
    format!(
        "3D machine runs: {} in the reduced basis (largest backward error of their modes {:.1e}, bar {:.0e}), {} on \
         the full model ({} over the bar)",
        e.reduced_runs, e.reduced_max_backward_error, e.reduced_tol, e.full_runs, e.reduced_fallbacks
    )
}

/// The envelope and the sensitivities as report sections (the chart `tuning_chart.svg` beside
/// the report when written).
pub fn sections(e: &EnvelopeResult) -> Vec<Section> {
    let mut env = Section {
        id: "envelope".into(),
        title: "Checks over the load cases and tolerance bands".into(),
        blocks: vec![],
    };
    env.blocks.push(Block::Text(format!(
        "load cases: {}; {}; {:.1} s (FE parts: {} computed, {} further requests of the same parts); {}",
        e.load_cases.join(", "),
        e.method,
        e.seconds,
        e.memo_misses,
        e.memo_hits,
        reduced_words(e)
    )));
    env.blocks.push(Block::Table(Table {
        id: "envelope".into(),
        caption: None,
        columns: vec![
            Column::new("check", None),
            Column::new("min", None),
            Column::new("nominal", None),
            Column::new("max", None),
            Column::new("limit", None),
            Column::new("worst margin", None),
            Column::new("worst at", None),
            Column::new("verdict", None),
        ],
        rows: e
            .checks
            .iter()
            .map(|c| {
                vec![
                    Cell::text(c.name.clone()),
                    Cell::num(c.min),
                    Cell::num(c.nominal),
                    Cell::num(c.max),
                    Cell::num(c.limit),
                    worst_margin_cell(c),
                    Cell::text(c.worst_run.clone()),
                    Cell::text(if c.ok { "ok" } else { "FAILS" }),
                ]
            })
            .collect(),
    }));
    env.blocks.push(Block::Figure(Figure {
        id: "tuning_chart".into(),
        file: "tuning_chart.svg".into(),
        caption: "Tuning chart: work-table amplitude against the load moving with the table and against the leaf \
                  thickness (two-mass estimate; points: the envelope's 3D runs)"
            .into(),
    }));
    vec![env, sensitivity_section(e)]
}

/// A check's worst margin as the nominal table prints its margin: `+12.3 %` of the limit, and for
/// a check in percent (`… [%]`) the difference in percentage points (the fraction times the
/// limit), so that one check reads alike in both tables.
fn worst_margin_cell(c: &CheckEnvelope) -> Cell {
    let points = super::report::name_and_unit(&c.name).1 == "%";
    let m = if points {
        c.worst_margin * c.limit.abs()
    } else {
        c.worst_margin
    };
    Cell::text(crate::app::report::render::margin_text(m, points))
}

/// The bands and the sensitivity of every check to each.
fn sensitivity_section(e: &EnvelopeResult) -> Section {
    let mut s = Section {
        id: "sensitivity".into(),
        title: "Sensitivities (forward differences at the nominal point)".into(),
        blocks: vec![],
    };
    s.blocks.push(Block::Table(Table {
        id: "bands".into(),
        caption: Some("tolerance bands (relative bands as fractions of the value)".into()),
        columns: vec![
            Column::new("parameter", None),
            Column::new("nominal", None),
            Column::new("−", None),
            Column::new("+", None),
            Column::new("step", None),
        ],
        rows: e
            .sensitivities
            .iter()
            .map(|p| {
                let rel = |x: f64| {
                    if p.relative {
                        Cell::Pct { value: x, decimals: 2 }
                    } else {
                        Cell::num(x)
                    }
                };
                vec![
                    Cell::text(format!("{} ({})", p.name, p.id)),
                    Cell::num(p.nominal),
                    rel(p.minus),
                    rel(p.plus),
                    rel(p.step),
                ]
            })
            .collect(),
    }));
    let mut columns = vec![Column::new("check", None)];
    columns.extend(
        e.sensitivities
            .iter()
            .map(|p| Column::new(&format!("∂/∂{}", p.id), None)),
    );
    columns.extend(
        e.sensitivities
            .iter()
            .map(|p| Column::new(&format!("Δ over +{}", p.id), None)),
    );
    s.blocks.push(Block::Table(Table {
        id: "sensitivity".into(),
        caption: Some(
            "∂value/∂p (per unit of the key; per unit of relative change for relative bands) and the linear change \
             over the + band"
                .into(),
        ),
        columns,
        rows: e
            .checks
            .iter()
            .map(|c| {
                let d = |p: &Sensitivity| p.d_value.get(&c.id).copied().unwrap_or(f64::NAN);
                let mut row = vec![Cell::text(c.name.clone())];
                row.extend(e.sensitivities.iter().map(|p| Cell::num(d(p))));
                row.extend(e.sensitivities.iter().map(|p| Cell::num(d(p) * p.plus)));
                row
            })
            .collect(),
    }));
    s
}

/// The two-mass amplitude X1 (m) of `d` with `load` kg moving with the table and leaves `h` m
/// thick, the leaf stiffness scaled as h³ from the FE value `k0` at `h0`.
fn two_mass_x1(d: &Design, m_table: f64, k_coil: f64, (k0, h0): (f64, f64), load: f64, h: f64) -> f64 {
    let c12 = d.leaf.count as f64 * d.leaf.clamping * k0 * (h / h0).powi(3);
    super::chain::two_mass_x1(d, m_table + d.masses.active_extra + load, c12, k_coil).unwrap_or(f64::NAN)
}

/// The tuning chart (`tuning_chart.svg`): the two-mass work-table amplitude against the load
/// moving with the table (0 to the whole load) and against the leaf thickness (±5 %), at the
/// as-built point, with the envelope's runs as points (their `table_amplitude`).
pub fn write_tuning_chart(path: &std::path::Path, e: &EnvelopeResult) -> Result<()> {
    use super::parts::{coil_fe, leaf_fe, table_fe};
    use plotters::prelude::*;
    let Some(first) = e.runs.first() else { return Ok(()) };
    let d = &first.design;
    let (m_table, ..) = table_fe(d)?;
    let k_coil = coil_fe(d)?;
    let h0 = d.leaf.thickness;
    let (k0, _) = leaf_fe(d, h0)?;
    let load0 = d.masses.load_share * d.masses.load;
    let n = 80;
    let loads: Vec<(f64, f64)> = (0..=n)
        .map(|i| {
            let m = d.masses.load.max(1.0) * i as f64 / n as f64;
            (m, 1e3 * two_mass_x1(d, m_table, k_coil, (k0, h0), m, h0))
        })
        .collect();
    let hs: Vec<(f64, f64)> = (0..=n)
        .map(|i| {
            let h = h0 * (0.95 + 0.1 * i as f64 / n as f64);
            (h * 1e3, 1e3 * two_mass_x1(d, m_table, k_coil, (k0, h0), load0, h))
        })
        .collect();
    let amp = |r: &EnvelopeRun| r.values.get("table_amplitude").copied().unwrap_or(f64::NAN);
    let pts_load: Vec<(f64, f64)> = e
        .runs
        .iter()
        .map(|r| (r.design.masses.load_share * r.design.masses.load, amp(r)))
        .collect();
    let pts_h: Vec<(f64, f64)> = e.runs.iter().map(|r| (r.design.leaf.thickness * 1e3, amp(r))).collect();
    let err = |x: &dyn std::fmt::Display| crate::Error::output(path.display(), format!("plotting failed: {x}"));
    let root = SVGBackend::new(path, (1100, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| err(&x))?;
    let (left, right) = root.split_horizontally(550);
    let panels = [
        (left, loads, pts_load, "load moving with the table [kg]"),
        (right, hs, pts_h, "leaf thickness [mm]"),
    ];
    for (area, curve, pts, xdesc) in panels {
        let all = || {
            curve
                .iter()
                .chain(pts.iter())
                .filter(|p| p.0.is_finite() && p.1.is_finite())
        };
        let (x0, x1) = all().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| (a.0.min(p.0), a.1.max(p.0)));
        let y1 = all().fold(0.0f64, |a, p| a.max(p.1)) * 1.1;
        if !(x0 < x1 && y1 > 0.0) {
            continue;
        }
        let mut ch = ChartBuilder::on(&area)
            .caption(format!("amplitude against the {xdesc}"), ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, 0.0..y1)
            .map_err(|x| err(&x))?;
        ch.configure_mesh()
            .x_desc(xdesc)
            .y_desc("work-table amplitude [mm]")
            .draw()
            .map_err(|x| err(&x))?;
        ch.draw_series(LineSeries::new(
            curve.into_iter().filter(|p| p.1.is_finite()),
            BLUE.stroke_width(2),
        ))
        .map_err(|x| err(&x))?
        .label("two-mass model (as built)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
        ch.draw_series(
            pts.into_iter()
                .filter(|p| p.0.is_finite() && p.1.is_finite())
                .map(|p| Circle::new(p, 4, RED.filled())),
        )
        .map_err(|x| err(&x))?
        .label("envelope runs (table_amplitude)")
        .legend(|(x, y)| Circle::new((x + 10, y), 4, RED.filled()));
        ch.configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|x| err(&x))?;
    }
    root.present().map_err(|x| err(&x))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(label: &str, margin: f64) -> EnvelopeRun {
        EnvelopeRun {
            label: label.into(),
            case: "nominal".into(),
            at: BTreeMap::new(),
            values: BTreeMap::new(),
            design: Design::default(),
            checks: vec![Check {
                id: "overrun".into(),
                name: "coil overrun".into(),
                value: margin,
                limit: 1.0,
                margin,
                ok: true,
                upper: false,
            }],
            working_detuning: f64::NAN,
        }
    }

    /// A value's change at the rounding level of the value is no sensitivity; 1e-6 of it is.
    #[test]
    fn a_value_changed_by_rounding_has_no_sensitivity() {
        let v0 = 16.68;
        assert_eq!(value_quotient(v0 * (1.0 + 1e-11), Some(v0), 0.03), 0.0);
        assert_eq!(value_quotient(0.0, Some(0.0), 0.03), 0.0);
        let g = value_quotient(v0 * (1.0 + 1e-6), Some(v0), 0.03);
        assert!((g - v0 * 1e-6 / 0.03).abs() <= 1e-9 * g, "{g}");
        assert!(value_quotient(v0, None, 0.03).is_nan());
    }

    /// Two corners whose margins differ by rounding are one tie: the first keeps "worst at";
    /// a margin lower by a real amount (1e-6) takes it.
    #[test]
    fn worst_run_ignores_rounding_ties() {
        let m = 6.274;
        let tie = [
            run("nominal", 7.0),
            run("eccentric corner 2", m),
            run("share corner 2", m * (1.0 - 1e-14)),
            run("empty corner 1", 9.0),
        ];
        let e = aggregate(&tie);
        assert_eq!((e[0].worst_run.as_str(), e[0].worst_margin), ("eccentric corner 2", m));
        let lower = [
            run("nominal", 7.0),
            run("eccentric corner 2", m),
            run("share corner 2", m * (1.0 - 1e-6)),
        ];
        assert_eq!(aggregate(&lower)[0].worst_run, "share corner 2");
        let nan = [run("nominal", 7.0), run("eccentric corner 2", f64::NAN)];
        assert_eq!(aggregate(&nan)[0].worst_run, "eccentric corner 2");
    }
}
