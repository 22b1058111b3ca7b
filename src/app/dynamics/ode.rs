//! Adaptive explicit Runge–Kutta integrator: Dormand–Prince 5(4) ("DOPRI5", the method of
//! MATLAB's `ode45` and scipy's `RK45`) with embedded error control, a PI step-size controller and
//! the 4th-order continuous extension (dense output) of Hairer, Nørsett & Wanner, *Solving Ordinary
//! Differential Equations I*, §II.4–II.6 (the coefficients of their `dopri5.f`).
//!
//! # Error control
//! After each step the embedded 4th-order solution gives a local error estimate `err_i`. The step is
//! accepted when the scaled RMS norm
//!
//! ```text
//! ‖err‖ = sqrt( (1/n) Σ_i ( err_i / (atol + rtol·max(|y_i|, |y_new_i|)) )² ) ≤ 1
//! ```
//!
//! (scipy uses the same norm). `rtol` is dimensionless; `atol` is in the units of the state (for the
//! two-mass model: metres for positions and m/s for velocities). The *local* error per step is held
//! below the tolerance; the *global* error after many steps is typically 1–100 × `rtol` relative to
//! the solution's scale, depending on how errors propagate (undamped oscillators accumulate them
//! linearly in time).
//!
//! # Breakpoints
//! A right-hand side with a kink or jump (the rectified force `|sin ωt|` has a kink at each zero)
//! makes a single-step method lose order on the step that straddles it. [`integrate`] takes a list
//! of breakpoints: no step crosses one; integration restarts there with a fresh derivative.
//!
//! # Output
//! The solution is reported at caller-chosen output times, interpolated with the dense output
//! (4th-order accurate, same order as the error estimate), so the output grid does not constrain
//! the step size.

use crate::{Error, Result};

/// Options of the Dormand–Prince integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dopri5Options {
    /// Relative tolerance (dimensionless), > 0. Default 1e-10.
    pub rtol: f64,
    /// Absolute tolerance (units of the state), > 0. Default 1e-15.
    pub atol: f64,
    /// Largest step allowed (units of t, s for the transient); `f64::INFINITY` for none.
    pub h_max: f64,
    /// Initial step; `None` chooses one automatically (Hairer's `hinit` heuristic).
    pub h_init: Option<f64>,
    /// Maximum number of steps (accepted + rejected) before giving up with an error.
    pub max_steps: usize,
}

impl Default for Dopri5Options {
    fn default() -> Self {
        Dopri5Options {
            rtol: 1e-10,
            atol: 1e-15,
            h_max: f64::INFINITY,
            h_init: None,
            max_steps: 10_000_000,
        }
    }
}

/// Counters of an integration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OdeStats {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps (error estimate above tolerance).
    pub rejected: usize,
    /// Right-hand-side evaluations.
    pub rhs_evals: usize,
}

/// Solution sampled at the requested output times.
#[derive(Debug, Clone, PartialEq)]
pub struct OdeSolution {
    /// Output times (as requested).
    pub t: Vec<f64>,
    /// State at each output time: `y[k][i]` is component `i` at `t[k]`.
    pub y: Vec<Vec<f64>>,
    /// Step counters.
    pub stats: OdeStats,
}

// Dormand–Prince 5(4) Butcher tableau.
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
// Error coefficients: 5th-order weights minus the embedded 4th-order weights.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Dense-output coefficients (Hairer's dopri5.f, "contd5").
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

// Step-size controller constants (Hairer's defaults): safety factor, bounds of the ratio
// h_new/h, and the PI ("Lund stabilisation") exponent.
const SAFE: f64 = 0.9;
const FAC_MIN: f64 = 0.2;
const FAC_MAX: f64 = 10.0;
const BETA: f64 = 0.04;

fn check_options(o: &Dopri5Options) -> Result<()> {
    let bad = |name: &str, msg: String| Err(Error::param(name, format!("ode: {msg}")));
    if !(o.rtol.is_finite() && o.rtol > 0.0) {
        return bad("rtol", format!("rtol must be finite and > 0, got {}", o.rtol));
    }
    if !(o.atol.is_finite() && o.atol > 0.0) {
        return bad("atol", format!("atol must be finite and > 0, got {}", o.atol));
    }
    if o.rtol < 1e-14 {
        return bad(
            "rtol",
            format!(
                "rtol = {:e} is below what double precision can deliver (use ≥ 1e-14)",
                o.rtol
            ),
        );
    }
    if o.h_max.is_nan() || o.h_max <= 0.0 {
        return bad("h_max", format!("h_max must be > 0, got {}", o.h_max));
    }
    if let Some(h) = o.h_init
        && !(h.is_finite() && h > 0.0)
    {
        return bad("h_init", format!("h_init must be finite and > 0, got {h}"));
    }
    if o.max_steps == 0 {
        return bad("max_steps", "max_steps must be > 0".into());
    }
    Ok(())
}

/// The start, the initial state and the output times: finite, output times ascending from t0.
fn check_inputs(t0: f64, y0: &[f64], t_out: &[f64]) -> Result<()> {
    let bad = |name: &str, msg: String| Err(Error::param(name, format!("ode: {msg}")));
    if y0.is_empty() {
        return bad("y0", "empty state vector".into());
    }
    if !t0.is_finite() {
        return bad("t0", format!("t0 must be finite, got {t0}"));
    }
    if y0.iter().any(|v| !v.is_finite()) {
        return bad("y0", "initial state has a non-finite component".into());
    }
    if t_out.is_empty() {
        return bad("t_out", "no output times".into());
    }
    for w in t_out.windows(2) {
        if w[0].is_nan() || w[1].is_nan() || w[1] < w[0] {
            return bad("t_out", "output times must be ascending".into());
        }
    }
    if t_out[0].is_nan() || t_out[0] < t0 || !t_out[t_out.len() - 1].is_finite() {
        return bad(
            "t_out",
            format!(
                "output times must be finite and ≥ t0 = {t0} (first {}, last {})",
                t_out[0],
                t_out[t_out.len() - 1]
            ),
        );
    }
    Ok(())
}

fn err_norm(err: &[f64], y0: &[f64], y1: &[f64], o: &Dopri5Options) -> f64 {
    let n = err.len() as f64;
    let s: f64 = err
        .iter()
        .zip(y0.iter().zip(y1))
        .map(|(e, (a, b))| {
            let sc = o.atol + o.rtol * a.abs().max(b.abs());
            (e / sc) * (e / sc)
        })
        .sum();
    (s / n).sqrt()
}

/// The work arrays of one Dormand–Prince step: the seven stages, the new state, the error
/// estimate and the dense-output coefficients of the last accepted step.
struct Stages {
    k: Vec<Vec<f64>>,
    ytmp: Vec<f64>,
    ynew: Vec<f64>,
    err: Vec<f64>,
    rcont: Vec<Vec<f64>>,
}

impl Stages {
    fn new(n: usize) -> Self {
        Stages {
            k: vec![vec![0.0; n]; 7],
            ytmp: vec![0.0; n],
            ynew: vec![0.0; n],
            err: vec![0.0; n],
            rcont: vec![vec![0.0; n]; 5],
        }
    }

    /// One step of size `h` from (t, y) (`k[0]` = y'(t)): the stages, `ynew` at `t_new` (its
    /// derivative in `k[6]`) and the local error estimate in `err`.
    fn step<F>(&mut self, rhs: &mut F, t: f64, y: &[f64], h: f64, t_new: f64)
    where
        F: FnMut(f64, &[f64], &mut [f64]),
    {
        let n = y.len();
        let Stages { k, ytmp, ynew, err, .. } = self;
        for i in 0..n {
            ytmp[i] = y[i] + h * A21 * k[0][i];
        }
        rhs(t + C2 * h, ytmp, &mut k[1]);
        for i in 0..n {
            ytmp[i] = y[i] + h * (A31 * k[0][i] + A32 * k[1][i]);
        }
        rhs(t + C3 * h, ytmp, &mut k[2]);
        for i in 0..n {
            ytmp[i] = y[i] + h * (A41 * k[0][i] + A42 * k[1][i] + A43 * k[2][i]);
        }
        rhs(t + C4 * h, ytmp, &mut k[3]);
        for i in 0..n {
            ytmp[i] = y[i] + h * (A51 * k[0][i] + A52 * k[1][i] + A53 * k[2][i] + A54 * k[3][i]);
        }
        rhs(t + C5 * h, ytmp, &mut k[4]);
        for i in 0..n {
            ytmp[i] = y[i] + h * (A61 * k[0][i] + A62 * k[1][i] + A63 * k[2][i] + A64 * k[3][i] + A65 * k[4][i]);
        }
        rhs(t + h, ytmp, &mut k[5]);
        for i in 0..n {
            ynew[i] = y[i] + h * (A71 * k[0][i] + A73 * k[2][i] + A74 * k[3][i] + A75 * k[4][i] + A76 * k[5][i]);
        }
        rhs(t_new, ynew, &mut k[6]);
        for i in 0..n {
            err[i] = h * (E1 * k[0][i] + E3 * k[2][i] + E4 * k[3][i] + E5 * k[4][i] + E6 * k[5][i] + E7 * k[6][i]);
        }
    }

    /// The dense-output coefficients of the accepted step of size `h` from `y` to `ynew`.
    fn dense(&mut self, y: &[f64], h: f64) {
        let Stages { k, ynew, rcont, .. } = self;
        for i in 0..y.len() {
            let ydiff = ynew[i] - y[i];
            let bspl = h * k[0][i] - ydiff;
            rcont[0][i] = y[i];
            rcont[1][i] = ydiff;
            rcont[2][i] = bspl;
            rcont[3][i] = ydiff - h * k[6][i] - bspl;
            rcont[4][i] = h * (D1 * k[0][i] + D3 * k[2][i] + D4 * k[3][i] + D5 * k[4][i] + D6 * k[5][i] + D7 * k[6][i]);
        }
    }

    /// The state at fraction `th` ∈ [0, 1] of the last accepted step.
    fn at(&self, th: f64) -> Vec<f64> {
        let r = &self.rcont;
        let th1 = 1.0 - th;
        (0..r[0].len())
            .map(|i| r[0][i] + th * (r[1][i] + th1 * (r[2][i] + th * (r[3][i] + th1 * r[4][i]))))
            .collect()
    }
}

/// The segment ends: the breakpoints strictly inside (t0, t_end), sorted, then t_end.
fn segment_ends(breakpoints: &[f64], t0: f64, t_end: f64) -> Vec<f64> {
    let mut cuts: Vec<f64> = breakpoints
        .iter()
        .copied()
        .filter(|b| b.is_finite() && *b > t0 && *b < t_end)
        .collect();
    cuts.sort_by(f64::total_cmp);
    // A breakpoint within a few ulps of another, of t0 or of t_end (a period's multiple that
    // rounds to just below the end) would leave a segment shorter than any step can be: it is
    // merged with its neighbour (the right-hand side cannot change over so short a time).
    let tiny = 64.0 * f64::EPSILON * t0.abs().max(t_end.abs()).max(f64::MIN_POSITIVE);
    let mut segs = Vec::with_capacity(cuts.len() + 1);
    let mut last = t0;
    for b in cuts {
        if b - last > tiny && t_end - b > tiny {
            segs.push(b);
            last = b;
        }
    }
    segs.push(t_end);
    segs
}

/// The integration state carried across segments.
struct Run<'a> {
    t: f64,
    y: Vec<f64>,
    h_prev: Option<f64>,
    stats: OdeStats,
    t_out: &'a [f64],
    out_y: Vec<Vec<f64>>,
    next_out: usize,
    s: Stages,
}

/// Integrates `y' = f(t, y)` from `t0` with `y(t0) = y0` to the last output time, and returns the
/// solution at the output times `t_out` (ascending, all ≥ `t0`).
///
/// `rhs(t, y, dy)` writes the derivative into `dy`. `breakpoints` are times where the right-hand
/// side is not smooth; no step crosses one (those outside `(t0, t_end)` are ignored; any order).
///
/// Errors: invalid options or times ([`Error::param`] naming the option), a non-finite
/// derivative, the step size underflowing, or `max_steps` exceeded (an error at the parameter
/// `max_steps`).
pub fn integrate<F>(
    mut rhs: F,
    t0: f64,
    y0: &[f64],
    t_out: &[f64],
    breakpoints: &[f64],
    opts: &Dopri5Options,
) -> Result<OdeSolution>
where
    F: FnMut(f64, &[f64], &mut [f64]),
{
    check_options(opts)?;
    check_inputs(t0, y0, t_out)?;
    let t_end = t_out[t_out.len() - 1];
    let mut run = Run {
        t: t0,
        y: y0.to_vec(),
        h_prev: None,
        stats: OdeStats::default(),
        t_out,
        out_y: Vec::with_capacity(t_out.len()),
        next_out: 0,
        s: Stages::new(y0.len()),
    };
    while run.next_out < t_out.len() && t_out[run.next_out] == t0 {
        run.out_y.push(y0.to_vec());
        run.next_out += 1;
    }
    for seg_end in segment_ends(breakpoints, t0, t_end) {
        if seg_end > run.t {
            run.segment(&mut rhs, seg_end, opts)?;
        }
    }
    // Output times equal to t_end that were not yet produced (only possible by rounding).
    while run.next_out < t_out.len() {
        run.out_y.push(run.y.clone());
        run.next_out += 1;
    }
    Ok(OdeSolution {
        t: t_out.to_vec(),
        y: run.out_y,
        stats: run.stats,
    })
}

impl Run<'_> {
    /// Integrates from the current time to `seg_end` (no step crosses it), writing the output
    /// times it passes.
    fn segment<F>(&mut self, rhs: &mut F, seg_end: f64, opts: &Dopri5Options) -> Result<()>
    where
        F: FnMut(f64, &[f64], &mut [f64]),
    {
        // Fresh derivative at the segment start (the RHS may jump at a breakpoint).
        rhs(self.t, &self.y, &mut self.s.k[0]);
        self.stats.rhs_evals += 1;
        check_finite(&self.s.k[0], self.t)?;
        let span = seg_end - self.t;
        let mut h = match (opts.h_init, self.h_prev) {
            (Some(h0), None) => h0,
            (_, Some(hp)) => hp,
            (None, None) => {
                let h = initial_step(rhs, self.t, &self.y, &self.s.k[0], opts, &mut self.stats);
                h.min(span)
            }
        };
        h = h.min(opts.h_max).min(span);
        let mut facold: f64 = 1e-4;
        let mut last_rejected = false;
        loop {
            let t = self.t;
            if self.stats.accepted + self.stats.rejected >= opts.max_steps {
                return Err(Error::param(
                    "max_steps",
                    format!(
                        "ode: more than max_steps = {} steps before t = {seg_end} (stopped at t = {t}); \
                         loosen rtol/atol or raise max_steps",
                        opts.max_steps
                    ),
                ));
            }
            let last = t + h >= seg_end || (seg_end - (t + h)) <= 1e-12 * seg_end.abs().max(1.0);
            let h_step = if last { seg_end - t } else { h };
            if h_step <= 16.0 * f64::EPSILON * t.abs().max(1e-300) {
                return Err(Error::InvalidInput(format!(
                    "ode: step size underflow at t = {t} (h = {h_step:e}); the problem may be stiff or singular"
                )));
            }
            let t_new = if last { seg_end } else { t + h_step };
            self.s.step(rhs, t, &self.y, h_step, t_new);
            self.stats.rhs_evals += 6;
            let en = err_norm(&self.s.err, &self.y, &self.s.ynew, opts);
            if !en.is_finite() {
                // A non-finite stage: shrink hard and retry (the underflow check above ends this).
                self.stats.rejected += 1;
                h = h_step * FAC_MIN;
                last_rejected = true;
                continue;
            }
            let fac11 = en.powf(0.2 - 0.75 * BETA);
            if en > 1.0 {
                self.stats.rejected += 1;
                h = h_step / (fac11 / SAFE).min(1.0 / FAC_MIN);
                last_rejected = true;
                continue;
            }
            self.stats.accepted += 1;
            self.s.dense(&self.y, h_step);
            self.write_outputs(t, t_new, h_step);
            // PI controller: h_new = h·SAFE/(err^(0.2−0.75β)·err_prev^(−β)), ratio bounded.
            let mut fac = fac11 / facold.powf(BETA);
            facold = en.max(1e-4);
            fac = (fac / SAFE).clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
            let mut h_next = h_step / fac;
            if last_rejected {
                h_next = h_next.min(h_step);
            }
            last_rejected = false;
            self.y.copy_from_slice(&self.s.ynew);
            self.s.k.swap(0, 6); // FSAL: the last stage is the next step's first.
            check_finite(&self.s.k[0], t_new)?;
            self.t = t_new;
            h = h_next.min(opts.h_max);
            if last {
                return Ok(());
            }
            self.h_prev = Some(h);
            h = h.min(seg_end - self.t);
        }
    }

    /// The output times in (t, t_new] from the dense output of the accepted step.
    fn write_outputs(&mut self, t: f64, t_new: f64, h_step: f64) {
        while self.next_out < self.t_out.len() && self.t_out[self.next_out] <= t_new {
            let th = ((self.t_out[self.next_out] - t) / h_step).clamp(0.0, 1.0);
            self.out_y.push(self.s.at(th));
            self.next_out += 1;
        }
    }
}

fn check_finite(dy: &[f64], t: f64) -> Result<()> {
    if dy.iter().any(|v| !v.is_finite()) {
        return Err(Error::InvalidInput(format!(
            "ode: the right-hand side is not finite at t = {t}"
        )));
    }
    Ok(())
}

/// Hairer's `hinit`: a first step such that an explicit Euler step would make an error of
/// about the tolerance.
fn initial_step<F>(rhs: &mut F, t: f64, y: &[f64], f0: &[f64], o: &Dopri5Options, stats: &mut OdeStats) -> f64
where
    F: FnMut(f64, &[f64], &mut [f64]),
{
    let n = y.len();
    let sc: Vec<f64> = y.iter().map(|v| o.atol + o.rtol * v.abs()).collect();
    let norm = |v: &[f64]| (v.iter().zip(&sc).map(|(a, s)| (a / s) * (a / s)).sum::<f64>() / n as f64).sqrt();
    let d0 = norm(y);
    let d1 = norm(f0);
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 };
    h0 = h0.min(o.h_max);
    let y1: Vec<f64> = y.iter().zip(f0).map(|(a, b)| a + h0 * b).collect();
    let mut f1 = vec![0.0; n];
    rhs(t + h0, &y1, &mut f1);
    stats.rhs_evals += 1;
    let diff: Vec<f64> = f1.iter().zip(f0).map(|(a, b)| a - b).collect();
    let d2 = norm(&diff) / h0;
    let dm = d1.max(d2);
    let h1 = if !dm.is_finite() || dm <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / dm).powf(0.2)
    };
    (100.0 * h0).min(h1).min(o.h_max)
}
