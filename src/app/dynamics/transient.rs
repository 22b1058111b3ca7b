//! Transient start-up of the two-mass model from rest under the real rectified magnet force, as in
//! the paper's Mathcad listing (§19, Fig. 22):
//!
//! ```text
//! x1'' = ( −P(t) − μ12·(x1' − x2') − c12·(x1 − x2) − μ1·x1' ) / m1
//! x2'' = ( +P(t) − μ12·(x2' − x1') − c12·(x2 − x1) − c13·x2 − μ13·x2' ) / m2
//! ```
//!
//! with P(t) = P_em·|sin ωt| (constant part included, not the pure harmonic of eq. (1)); in general
//! `M x'' + C x' + K x = (−P(t), +P(t))` with the matrices of [`TwoMass::matrices`] (so the
//! [`super::KTerms::AsPrinted`] variant is simulated with the isolators on m1).
//!
//! Integration: Dormand–Prince 5(4) with error control ([`super::ode`]), default rtol = 1e-10 and
//! atol = 1e-15 (m for positions, m/s for velocities: about 1e-11 of the 0.2 mm amplitude and
//! negligible next to rtol for the ~0.1 m/s velocities). Steps never cross a kink of |sin ωt|.
//! The solution is sampled `samples_per_period` times per force period T = 2π/Ω via the dense
//! output, so periods align with samples and averages over whole periods are exact for the
//! harmonics below the sampling rate.

use super::electromagnet::{ForceLaw, RectifiedDrive};
use super::ode::{Dopri5Options, OdeStats, integrate};
use super::two_mass::TwoMass;
use crate::{Error, Result};

/// Options of [`simulate_startup`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransientOptions {
    /// End time, s (> 0). Output runs to the first whole sample at or after it. Default 0.5 s.
    pub t_end: f64,
    /// Output samples per force period T = 2π/Ω (≥ 20). Default 400 (25 µs at 100 Hz).
    pub samples_per_period: usize,
    /// Integrator tolerances and limits (default rtol 1e-10, atol 1e-15).
    pub ode: Dopri5Options,
    /// Whether steps stop at the kinks of |sin ωt| (default true; more accurate per step).
    pub split_at_kinks: bool,
}

impl Default for TransientOptions {
    fn default() -> Self {
        TransientOptions {
            t_end: 0.5,
            samples_per_period: 400,
            ode: Dopri5Options::default(),
            split_at_kinks: true,
        }
    }
}

/// A simulated start-up, sampled uniformly.
#[derive(Debug, Clone, PartialEq)]
pub struct Transient {
    /// Sample times, s (t_i = i·T/samples_per_period).
    pub t: Vec<f64>,
    /// Displacement of the active mass x1, m.
    pub x1: Vec<f64>,
    /// Velocity of the active mass, m/s.
    pub v1: Vec<f64>,
    /// Displacement of the reactive mass x2, m.
    pub x2: Vec<f64>,
    /// Velocity of the reactive mass, m/s.
    pub v2: Vec<f64>,
    /// Force frequency Ω = 2ω, rad/s.
    pub omega: f64,
    /// Samples per force period.
    pub samples_per_period: usize,
    /// Integrator counters.
    pub stats: OdeStats,
}

/// Quantities read from the end of a transient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransientSummary {
    /// Number of whole force periods at the end used for the steady values.
    pub periods: usize,
    /// Steady amplitude of x1: half peak-to-peak over the last periods, m.
    pub amplitude1: f64,
    /// Steady amplitude of x2: half peak-to-peak over the last periods, m.
    pub amplitude2: f64,
    /// Static offset of x1: mean over the last periods, m.
    pub mean1: f64,
    /// Static offset of x2: mean over the last periods, m.
    pub mean2: f64,
    /// Mean of the relative coordinate x1 − x2 over the last periods, m (→ −P_const/c12).
    pub relative_mean: f64,
    /// Settling time of x1, s: the start of the first force period from which on every period's
    /// half peak-to-peak stays within 2 % of `amplitude1` (resolution: one period). `None` if the
    /// record never settles by this criterion.
    pub settling_time1: Option<f64>,
    /// Settling time of x2, s (same definition with `amplitude2`).
    pub settling_time2: Option<f64>,
}

/// Band used for the settling time: ±2 % of the steady amplitude.
pub const SETTLING_BAND: f64 = 0.02;

/// Integrates the start-up from rest (x = x' = 0 at t = 0) under P(t) = P_em·|sin ωt|.
///
/// Errors: invalid model, drive or options, and integrator failures.
pub fn simulate_startup(model: &TwoMass, drive: &RectifiedDrive, opts: &TransientOptions) -> Result<Transient> {
    model.validate()?;
    let drive = RectifiedDrive::new(drive.p_em, drive.omega_mains)?;
    if !(opts.t_end.is_finite() && opts.t_end > 0.0) {
        return Err(Error::param(
            "t_end",
            format!("transient: t_end must be finite and > 0 s, got {}", opts.t_end),
        ));
    }
    if opts.samples_per_period < 20 {
        return Err(Error::param(
            "samples_per_period",
            format!(
                "transient: samples_per_period must be ≥ 20, got {}",
                opts.samples_per_period
            ),
        ));
    }
    let omega = drive.omega_force();
    let dt = std::f64::consts::TAU / omega / opts.samples_per_period as f64;
    let n_out = (opts.t_end / dt - 1e-9).ceil() as usize;
    if n_out > 50_000_000 {
        return Err(Error::param(
            "t_end",
            format!("transient: {n_out} output samples requested; shorten t_end or lower samples_per_period"),
        ));
    }
    let t_out: Vec<f64> = (0..=n_out).map(|i| i as f64 * dt).collect();
    let t_last = t_out[n_out];
    let kinks = if opts.split_at_kinks {
        drive.kinks(t_last)
    } else {
        Vec::new()
    };

    let (m, c, k) = model.matrices();
    let (im1, im2) = (1.0 / m[(0, 0)], 1.0 / m[(1, 1)]);
    let rhs = |t: f64, y: &[f64], dy: &mut [f64]| {
        let p = drive.force(t);
        let (x1, v1, x2, v2) = (y[0], y[1], y[2], y[3]);
        dy[0] = v1;
        dy[1] = (-p - c[(0, 0)] * v1 - c[(0, 1)] * v2 - k[(0, 0)] * x1 - k[(0, 1)] * x2) * im1;
        dy[2] = v2;
        dy[3] = (p - c[(1, 0)] * v1 - c[(1, 1)] * v2 - k[(1, 0)] * x1 - k[(1, 1)] * x2) * im2;
    };
    let sol = integrate(rhs, 0.0, &[0.0; 4], &t_out, &kinks, &opts.ode)?;
    let col = |i: usize| sol.y.iter().map(|v| v[i]).collect::<Vec<f64>>();
    Ok(Transient {
        t: sol.t.clone(),
        x1: col(0),
        v1: col(1),
        x2: col(2),
        v2: col(3),
        omega,
        samples_per_period: opts.samples_per_period,
        stats: sol.stats,
    })
}

/// Extremum of a sampled signal, refined by a parabola through the extreme sample and its neighbours.
fn refined_extremum(v: &[f64], max: bool) -> f64 {
    let s = if max { 1.0 } else { -1.0 };
    let (i, _) = v.iter().enumerate().fold((0usize, f64::NEG_INFINITY), |acc, (i, &x)| {
        if s * x > acc.1 { (i, s * x) } else { acc }
    });
    if i == 0 || i + 1 == v.len() {
        return v[i];
    }
    let (a, b, c) = (v[i - 1], v[i], v[i + 1]);
    let den = a - 2.0 * b + c;
    if den == 0.0 {
        return b;
    }
    // Vertex of the parabola through (−1, a), (0, b), (1, c).
    let p = 0.5 * (a - c) / den;
    if p.abs() > 1.0 {
        return b;
    }
    b - 0.25 * (a - c) * p
}

/// Half peak-to-peak of a sampled signal with parabolic refinement of both extrema.
fn half_pp(v: &[f64]) -> f64 {
    0.5 * (refined_extremum(v, true) - refined_extremum(v, false))
}

impl Transient {
    /// Force period T = 2π/Ω, s.
    pub fn period(&self) -> f64 {
        std::f64::consts::TAU / self.omega
    }

    /// Number of whole force periods in the record.
    pub fn whole_periods(&self) -> usize {
        if self.samples_per_period == 0 {
            return 0;
        }
        let n = self.t.len().min(self.x1.len()).min(self.x2.len());
        n.saturating_sub(1) / self.samples_per_period
    }

    /// Half peak-to-peak of x1 (`which` = 0) or x2 (`which` = 1) in each whole force period:
    /// (start time of the period in s, amplitude in m).
    pub fn period_amplitudes(&self, which: usize) -> Vec<(f64, f64)> {
        let x = if which == 0 { &self.x1 } else { &self.x2 };
        let m = self.samples_per_period;
        (0..self.whole_periods())
            .map(|p| (self.t[p * m], half_pp(&x[p * m..=(p + 1) * m])))
            .collect()
    }

    /// Steady amplitudes, offsets and settling times from the last `n_last` whole periods (≥ 1).
    ///
    /// Amplitudes are half peak-to-peak over the whole window, with each extremum refined by a
    /// parabola (error ≈ (π/samples_per_period)⁴ relative for a sinusoid); means are sample means
    /// over whole periods (exact for harmonics below the sampling rate). Any residual slow motion
    /// (the ≈ 5.8 Hz rigid-body mode on the isolators, ~10 % damped) inflates the amplitude of the
    /// window: simulate long enough for it to die out when a sharp value is wanted.
    pub fn summary(&self, n_last: usize) -> Result<TransientSummary> {
        let np = self.whole_periods();
        if n_last == 0 || n_last > np {
            return Err(Error::param(
                "n_last",
                format!("transient summary: n_last must be in 1..={np} (whole periods simulated), got {n_last}"),
            ));
        }
        let m = self.samples_per_period;
        let end = np * m;
        let start = end - n_last * m;
        let w = |v: &Vec<f64>| -> (f64, f64) {
            let s = &v[start..=end];
            let mean = v[start..end].iter().sum::<f64>() / (end - start) as f64;
            (half_pp(s), mean)
        };
        let (a1, mean1) = w(&self.x1);
        let (a2, mean2) = w(&self.x2);
        let settle = |which: usize, a: f64| -> Option<f64> {
            let pa = self.period_amplitudes(which);
            let mut first_ok = None;
            for (t, ap) in pa.iter().rev() {
                if (ap - a).abs() <= SETTLING_BAND * a {
                    first_ok = Some(*t);
                } else {
                    break;
                }
            }
            first_ok
        };
        Ok(TransientSummary {
            periods: n_last,
            amplitude1: a1,
            amplitude2: a2,
            mean1,
            mean2,
            relative_mean: mean1 - mean2,
            settling_time1: settle(0, a1),
            settling_time2: settle(1, a2),
        })
    }
}

/// A ramped mains supply: the mains frequency rises linearly from 0 to `omega_mains` over
/// `up_s`, holds for `hold_s`, falls linearly to 0 over `down_s`, and the supply is then off
/// (`up_s = 0`: switched straight onto the mains; `down_s = 0`: switched off at full frequency).
/// The pull is P_em·|sin φ(t)| with φ the mains phase ∫ω dt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramp {
    /// Full mains angular frequency ω, rad/s.
    pub omega_mains: f64,
    /// Run-up time, s.
    pub up_s: f64,
    /// Time at full frequency, s.
    pub hold_s: f64,
    /// Run-down time, s.
    pub down_s: f64,
}

impl Ramp {
    /// When the supply goes off, s.
    pub fn off(&self) -> f64 {
        self.up_s + self.hold_s + self.down_s
    }

    /// Mains phase at `t` (None once the supply is off).
    pub fn phase(&self, t: f64) -> Option<f64> {
        let w = self.omega_mains;
        let t1 = self.up_s + self.hold_s;
        if t < 0.0 || t > self.off() {
            None
        } else if t < self.up_s {
            Some(0.5 * w * t * t / self.up_s)
        } else if t <= t1 {
            Some(0.5 * w * self.up_s + w * (t - self.up_s))
        } else {
            let tau = t - t1;
            Some(0.5 * w * self.up_s + w * self.hold_s + w * (tau - 0.5 * tau * tau / self.down_s))
        }
    }

    /// Instantaneous mains angular frequency at `t`, rad/s.
    pub fn omega_at(&self, t: f64) -> f64 {
        let t1 = self.up_s + self.hold_s;
        if t < 0.0 || t > self.off() {
            0.0
        } else if t < self.up_s {
            self.omega_mains * t / self.up_s
        } else if t <= t1 {
            self.omega_mains
        } else {
            self.omega_mains * (1.0 - (t - t1) / self.down_s)
        }
    }

    /// The zeros of sin φ (kinks of the pull) and the switching times, up to `t_end`.
    pub fn kinks(&self, t_end: f64) -> Vec<f64> {
        use std::f64::consts::PI;
        let mut out = vec![self.up_s, self.up_s + self.hold_s, self.off()];
        let phi_end = self.phase(self.off().min(t_end)).unwrap_or(0.0);
        let n_max = (phi_end / PI).floor() as usize;
        for n in 1..=n_max {
            let target = n as f64 * PI;
            // Bisection on the monotone phase (exact to rounding in 80 halvings).
            let (mut a, mut b) = (0.0, self.off().min(t_end));
            for _ in 0..80 {
                let m = 0.5 * (a + b);
                if self.phase(m).unwrap_or(f64::INFINITY) < target {
                    a = m;
                } else {
                    b = m;
                }
            }
            out.push(0.5 * (a + b));
        }
        // A zero of sin φ may fall on a switching time or on the end to rounding: breakpoints
        // closer than 1 ns to another, to 0 or to `t_end` would leave the integrator a step of
        // rounding size.
        out.retain(|&t| t > 1e-9 && t < t_end - 1e-9);
        out.sort_by(f64::total_cmp);
        out.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        out
    }
}

impl Ramp {
    /// The pull at `t` of a peak total `p_em` under `law`: P·|sin φ| (paper) or P·sin²φ (flux),
    /// zero before the start and once the supply is off.
    pub fn pull(&self, law: ForceLaw, p_em: f64, t: f64) -> f64 {
        self.phase(t).map_or(0.0, |ph| {
            let s = ph.sin();
            match law {
                ForceLaw::Paper => p_em * s.abs(),
                ForceLaw::Flux => p_em * s * s,
            }
        })
    }

    /// The pull's rate of change dP/dt at `t` (the one-sided value at a kink of |sin φ|).
    pub fn pull_rate(&self, law: ForceLaw, p_em: f64, t: f64) -> f64 {
        self.phase(t).map_or(0.0, |ph| {
            let (s, c) = ph.sin_cos();
            let w = self.omega_at(t);
            match law {
                ForceLaw::Paper => p_em * s.signum() * c * w,
                ForceLaw::Flux => p_em * 2.0 * s * c * w,
            }
        })
    }

    /// Where the pull under `law` is not smooth, up to `t_end`: the switching times and, under
    /// the paper's law, the zeros of sin φ ([`Ramp::kinks`]); sin²φ is smooth in φ.
    pub fn breakpoints(&self, law: ForceLaw, t_end: f64) -> Vec<f64> {
        match law {
            ForceLaw::Paper => self.kinks(t_end),
            ForceLaw::Flux => {
                let mut out = vec![self.up_s, self.up_s + self.hold_s, self.off()];
                out.retain(|&t| t > 1e-9 && t < t_end - 1e-9);
                out.sort_by(f64::total_cmp);
                out.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
                out
            }
        }
    }
}

/// A linear system's transient: `x[k]` and `v[k]` are the displacements and velocities at `t[k]`.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearTransient {
    /// Sample times, s.
    pub t: Vec<f64>,
    /// Displacements per sample.
    pub x: Vec<Vec<f64>>,
    /// Velocities per sample.
    pub v: Vec<Vec<f64>>,
}

/// The response from rest of `M x'' + C x' + K x = b·P(t)` (n DOFs, row-major n×n matrices)
/// under the pull P(t) = `p_em`·|sin φ(t)| of the ramped supply `ramp`, sampled every `dt` s to
/// `t_end` (Dormand–Prince, no step across a kink of the pull or a switching time).
#[allow(clippy::too_many_arguments)]
pub fn simulate_linear(
    m: &[f64],
    c: &[f64],
    k: &[f64],
    b: &[f64],
    p_em: f64,
    ramp: &Ramp,
    t_end: f64,
    dt: f64,
    ode: &Dopri5Options,
) -> Result<LinearTransient> {
    simulate_linear_law(m, c, k, b, ForceLaw::Paper, p_em, ramp, t_end, dt, ode)
}

/// [`simulate_linear`] under either force law: P(t) = `p_em`·|sin φ(t)| (paper) or
/// `p_em`·sin²φ(t) (flux), with steps stopped at the switching times and, under the paper's
/// law, at the zeros of sin φ ([`Ramp::breakpoints`]). With M = I, C = C_r, K = Λ and b = Φᵀf
/// it integrates a structure's modal coordinates.
#[allow(clippy::too_many_arguments)]
pub fn simulate_linear_law(
    m: &[f64],
    c: &[f64],
    k: &[f64],
    b: &[f64],
    law: ForceLaw,
    p_em: f64,
    ramp: &Ramp,
    t_end: f64,
    dt: f64,
    ode: &Dopri5Options,
) -> Result<LinearTransient> {
    let n = b.len();
    if m.len() != n * n || c.len() != n * n || k.len() != n * n || n == 0 {
        return Err(Error::param("b", format!("linear transient: matrices must be {n}×{n}")));
    }
    if !(t_end.is_finite() && t_end > 0.0 && dt.is_finite() && dt > 0.0 && t_end / dt < 5e7) {
        return Err(Error::param(
            "t_end",
            format!("linear transient: t_end {t_end} s and dt {dt} s must be positive, with fewer than 5e7 samples"),
        ));
    }
    let minv = nalgebra::DMatrix::from_row_slice(n, n, m)
        .try_inverse()
        .ok_or_else(|| Error::param("m", "linear transient: the mass matrix is singular"))?;
    // M = I (modal coordinates): the accelerations are the forces, with no product by M⁻¹.
    let identity = (0..n * n).all(|i| m[i] == if i % (n + 1) == 0 { 1.0 } else { 0.0 });
    let rhs = |t: f64, y: &[f64], dy: &mut [f64]| {
        let p = ramp.pull(law, p_em, t);
        if identity {
            dy[..n].copy_from_slice(&y[n..]);
            for i in 0..n {
                let (ci, ki) = (&c[i * n..(i + 1) * n], &k[i * n..(i + 1) * n]);
                let mut f = b[i] * p;
                for j in 0..n {
                    f -= ci[j] * y[n + j] + ki[j] * y[j];
                }
                dy[n + i] = f;
            }
            return;
        }
        let f: Vec<f64> = (0..n)
            .map(|i| {
                b[i] * p
                    - (0..n)
                        .map(|j| c[i * n + j] * y[n + j] + k[i * n + j] * y[j])
                        .sum::<f64>()
            })
            .collect();
        for i in 0..n {
            dy[i] = y[n + i];
            dy[n + i] = (0..n).map(|j| minv[(i, j)] * f[j]).sum();
        }
    };
    let n_out = (t_end / dt - 1e-9).ceil() as usize;
    let t_out: Vec<f64> = (0..=n_out).map(|i| i as f64 * dt).collect();
    let sol = integrate(
        rhs,
        0.0,
        &vec![0.0; 2 * n],
        &t_out,
        &ramp.breakpoints(law, t_out[n_out]),
        ode,
    )?;
    Ok(LinearTransient {
        t: sol.t,
        x: sol.y.iter().map(|y| y[..n].to_vec()).collect(),
        v: sol.y.iter().map(|y| y[n..].to_vec()).collect(),
    })
}
