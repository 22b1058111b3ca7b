//! The single-stroke electromagnetic drive (docs/spec/paper.md §8, eq. (8)–(15)).
//!
//! Each magnet is fed from the mains at ω (rad/s) and only attracts, so the total pull of the
//! magnets is the rectified sine
//!
//! ```text
//! P(t) = P_em·|sin ωt| = (2/π)·P_em − Σ_{k≥1} 4·P_em/(π(4k² − 1))·cos(2kωt)             (8)
//!      = (2/π)·P_em − (4/(3π))·P_em·cos Ωt − (4/(15π))·P_em·cos 2Ωt − …,   Ω = 2ω
//! ```
//!
//! with P_em the total peak pull (N) of all magnets together. The constant part (2/π)·P_em (eq. (9))
//! deflects the leaf springs statically; the Ω harmonic of amplitude F = (4/(3π))·P_em (eq. (11))
//! drives the resonant system. Higher harmonics (2Ω, 3Ω, …) fall well above the tuned resonance and
//! contribute little.
//!
//! The force acts as in the paper's Mathcad listing (§19): −P(t) on the active mass m1 (armature)
//! and +P(t) on the reactive mass m2 (core).

use std::f64::consts::PI;

use nalgebra::Complex;

use super::two_mass::TwoMass;
use crate::{Error, Result};

/// Coefficient a_k of cos(2kωt) in the expansion of |sin ωt| (eq. (8)), dimensionless:
/// a_0 = 2/π, a_k = −4/(π(4k² − 1)) for k ≥ 1 (a_1 = −4/(3π), a_2 = −4/(15π)).
pub fn fourier_coefficient(k: u32) -> f64 {
    if k == 0 {
        2.0 / PI
    } else {
        let k = k as f64;
        -4.0 / (PI * (4.0 * k * k - 1.0))
    }
}

/// The rectified magnet force P(t) = P_em·|sin ωt|.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RectifiedDrive {
    /// Total peak pull of all magnets P_em, N (≥ 0).
    pub p_em: f64,
    /// Mains angular frequency ω, rad/s (> 0); the force repeats at Ω = 2ω.
    pub omega_mains: f64,
}

impl RectifiedDrive {
    /// A validated drive: P_em (N, finite, ≥ 0), ω (rad/s, finite, > 0).
    pub fn new(p_em: f64, omega_mains: f64) -> Result<Self> {
        if !(p_em.is_finite() && p_em >= 0.0) {
            return Err(Error::param(
                "p_em",
                format!("electromagnet peak pull P_em must be finite and ≥ 0 N, got {p_em}"),
            ));
        }
        if !(omega_mains.is_finite() && omega_mains > 0.0) {
            return Err(Error::param(
                "omega_mains",
                format!("mains angular frequency ω must be finite and > 0 rad/s, got {omega_mains}"),
            ));
        }
        Ok(RectifiedDrive { p_em, omega_mains })
    }

    /// `n` magnets of peak pull `p_each` (N) each, on mains ω (rad/s): P_em = n·p_each.
    pub fn from_magnets(n: usize, p_each: f64, omega_mains: f64) -> Result<Self> {
        if n == 0 {
            return Err(Error::param("n_magnets", "number of electromagnets must be ≥ 1"));
        }
        if !(p_each.is_finite() && p_each >= 0.0) {
            return Err(Error::param(
                "p_each",
                format!("peak pull per electromagnet must be finite and ≥ 0 N, got {p_each}"),
            ));
        }
        Self::new(n as f64 * p_each, omega_mains)
    }

    /// The paper's drive: 8 magnets × 370 N on 50 Hz mains (ω = 2π·50 rad/s).
    pub fn paper() -> Self {
        RectifiedDrive {
            p_em: 8.0 * 370.0,
            omega_mains: 2.0 * PI * 50.0,
        }
    }

    /// Force frequency Ω = 2ω, rad/s.
    pub fn omega_force(&self) -> f64 {
        2.0 * self.omega_mains
    }

    /// Instantaneous pull P(t) = P_em·|sin ωt|, N (t in s).
    pub fn force(&self, t: f64) -> f64 {
        self.p_em * (self.omega_mains * t).sin().abs()
    }

    /// Constant part P_const = (2/π)·P_em, N (eq. (9)). Paper: 1884 N.
    pub fn constant(&self) -> f64 {
        fourier_coefficient(0) * self.p_em
    }

    /// Amplitude of the Ω = 2ω harmonic, F = (4/(3π))·P_em, N (eq. (11)). Paper: 1256 N.
    pub fn harmonic_amplitude(&self) -> f64 {
        -fourier_coefficient(1) * self.p_em
    }

    /// Coefficient of cos(kΩt) = cos(2kωt) in P(t), N (k = 0: the constant part).
    pub fn cos_coefficient(&self, k: u32) -> f64 {
        fourier_coefficient(k) * self.p_em
    }

    /// The truncated series Σ_{k=0..n} a_k·P_em·cos(kΩt), N.
    pub fn partial_sum(&self, t: f64, n: u32) -> f64 {
        let w = self.omega_force();
        (0..=n)
            .map(|k| self.cos_coefficient(k) * (k as f64 * w * t).cos())
            .sum()
    }

    /// Times in (0, t_end) where P(t) has a kink (the zeros of sin ωt: t = jπ/ω), s.
    pub fn kinks(&self, t_end: f64) -> Vec<f64> {
        let dt = PI / self.omega_mains;
        (1..).map(|j| j as f64 * dt).take_while(|&t| t < t_end).collect()
    }
}

/// Eq. (13): the total peak pull P_em (N) that gives the target steady amplitude |X1| = `x1_target`
/// (m) of the active mass at the force frequency Ω (rad/s), using the model's own receptance
/// |X1|/F at Ω: P_em = (3π/4)·X1/(|X1|/F). Divide by the number of magnets for the per-magnet pull.
pub fn required_peak_force(model: &TwoMass, omega: f64, x1_target: f64) -> Result<f64> {
    if !(x1_target.is_finite() && x1_target > 0.0) {
        return Err(Error::param(
            "x1_target",
            format!("target amplitude X1 must be finite and > 0 m, got {x1_target}"),
        ));
    }
    let s = model.steady_state(omega, 1.0)?;
    if s.amp1().is_nan() || s.amp1() <= 0.0 {
        return Err(Error::param(
            "omega",
            format!(
                "the active mass does not move at Ω = {omega} rad/s (anti-resonance): no pull reaches X1 = {x1_target} m"
            ),
        ));
    }
    Ok(3.0 * PI / 4.0 * x1_target / s.amp1())
}

/// Eq. (15): P_em = (3π/4)·X1·m1·Ω²/γ1, N, from the target amplitude X1 (m), the active mass m1
/// (kg), Ω (rad/s) and a given dynamic factor γ1 (> 0). Paper: 0.2 mm, 206.7 kg, 100 Hz, γ1 = 13
/// → 2958 N (369.7 N per magnet of 8).
pub fn peak_force_from_gamma(x1: f64, m1: f64, omega: f64, gamma1: f64) -> Result<f64> {
    for (name, v) in [("X1", x1), ("m1", m1), ("Ω", omega), ("γ1", gamma1)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::param(name, format!("{name} must be finite and > 0, got {v}")));
        }
    }
    Ok(3.0 * PI / 4.0 * x1 * m1 * omega * omega / gamma1)
}

/// Static deflection of the leaf springs under the constant pull P_const (N): P_const/c12, m
/// (c12 in N/m). The model's relative coordinate settles at x1 − x2 = −P_const/c12 (the masses are
/// pulled together); see [`TwoMass::static_response`]. Paper: 1884/3.808e7 = 0.0495 mm.
pub fn static_offset(c12: f64, p_const: f64) -> Result<f64> {
    if !(c12.is_finite() && c12 > 0.0) {
        return Err(Error::param(
            "c12",
            format!("c12 must be finite and > 0 N/m, got {c12}"),
        ));
    }
    if !p_const.is_finite() {
        return Err(Error::param(
            "p_const",
            format!("constant pull must be finite, got {p_const} N"),
        ));
    }
    Ok(p_const / c12)
}

/// Periodic steady state under the full rectified force, by harmonic balance (superposition of
/// the static response to the constant part and the steady responses to the harmonics kΩ,
/// k = 1..n): `x_j(t) = x_j,static + Σ_k Re(H_j(kΩ)·a_k·P_em·e^{ikΩt})`.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicResponse {
    /// Force frequency Ω, rad/s.
    pub omega: f64,
    /// Static displacements (x1, x2) under the constant part, m.
    pub static_x: (f64, f64),
    /// Complex amplitudes (X1_k, X2_k) of the cos(kΩt) responses, m, for k = 1..n.
    pub harmonics: Vec<(Complex<f64>, Complex<f64>)>,
}

/// Amplitudes and mean values of a periodic motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodicSummary {
    /// Half peak-to-peak of x1, m.
    pub amplitude1: f64,
    /// Half peak-to-peak of x2, m.
    pub amplitude2: f64,
    /// Mean of x1 over a period, m.
    pub mean1: f64,
    /// Mean of x2 over a period, m.
    pub mean2: f64,
}

impl PeriodicResponse {
    /// Harmonic balance with `n_harmonics` ≥ 1 harmonics of the rectified force.
    ///
    /// Errors: invalid model, and (undamped model) a harmonic at a natural frequency.
    pub fn new(model: &TwoMass, drive: &RectifiedDrive, n_harmonics: u32) -> Result<Self> {
        if n_harmonics == 0 {
            return Err(Error::param(
                "n_harmonics",
                "harmonic balance needs at least 1 harmonic",
            ));
        }
        let omega = drive.omega_force();
        let static_x = model.static_response(drive.constant())?;
        let harmonics = (1..=n_harmonics)
            .map(|k| {
                let s = model.steady_state(k as f64 * omega, drive.cos_coefficient(k))?;
                Ok((s.x1, s.x2))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(PeriodicResponse {
            omega,
            static_x,
            harmonics,
        })
    }

    /// Displacements (x1, x2) at time t (s), m.
    pub fn eval(&self, t: f64) -> (f64, f64) {
        let (mut x1, mut x2) = self.static_x;
        for (k, (a, b)) in self.harmonics.iter().enumerate() {
            let e = Complex::from_polar(1.0, (k + 1) as f64 * self.omega * t);
            x1 += (a * e).re;
            x2 += (b * e).re;
        }
        (x1, x2)
    }

    /// Half peak-to-peak amplitudes and means over one period: 2000 samples, each extremum refined
    /// by golden-section search (relative accuracy ~1e-12 of the amplitude).
    pub fn summary(&self) -> PeriodicSummary {
        let period = std::f64::consts::TAU / self.omega;
        let n = 2000;
        let dt = period / n as f64;
        let mut out = [(0.0, 0.0); 2];
        for (j, o) in out.iter_mut().enumerate() {
            let f = |t: f64| {
                let (a, b) = self.eval(t);
                if j == 0 { a } else { b }
            };
            let v: Vec<f64> = (0..n).map(|i| f(i as f64 * dt)).collect();
            let (imax, _) = v
                .iter()
                .enumerate()
                .fold((0, f64::MIN), |acc, (i, &x)| if x > acc.1 { (i, x) } else { acc });
            let (imin, _) = v
                .iter()
                .enumerate()
                .fold((0, f64::MAX), |acc, (i, &x)| if x < acc.1 { (i, x) } else { acc });
            let hi = golden(&f, (imax as f64 - 1.0) * dt, (imax as f64 + 1.0) * dt, true);
            let lo = golden(&f, (imin as f64 - 1.0) * dt, (imin as f64 + 1.0) * dt, false);
            // The mean of a trigonometric polynomial is its constant term.
            let mean = if j == 0 { self.static_x.0 } else { self.static_x.1 };
            *o = (0.5 * (f(hi) - f(lo)), mean);
        }
        PeriodicSummary {
            amplitude1: out[0].0,
            amplitude2: out[1].0,
            mean1: out[0].1,
            mean2: out[1].1,
        }
    }
}

/// Golden-section search for the arg max (or arg min) of `f` on [a, b].
fn golden(f: &dyn Fn(f64) -> f64, mut a: f64, mut b: f64, max: bool) -> f64 {
    let s = if max { 1.0 } else { -1.0 };
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = b - g * (b - a);
    let mut x2 = a + g * (b - a);
    let mut f1 = s * f(x1);
    let mut f2 = s * f(x2);
    for _ in 0..100 {
        if f1 < f2 {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = s * f(x2);
        } else {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = s * f(x1);
        }
    }
    0.5 * (a + b)
}

/// How the magnets' pull varies over a mains period (`drive.force_law` of a design file).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ForceLaw {
    /// The paper's rectified sine P·|sin ωt| (eq. (8)): mean (2/π)·P, every even harmonic of ω.
    Paper,
    /// A coil fed from the mains: the pull goes with the flux squared, and with a sinusoidal
    /// flux P·sin²ωt = P/2 − (P/2)·cos 2ωt: mean P/2, one harmonic at 2ω of amplitude P/2 and
    /// nothing above (the default for new designs).
    #[default]
    Flux,
}

impl ForceLaw {
    /// `"paper"` or `"flux"`.
    pub fn parse(s: &str) -> Option<ForceLaw> {
        match s {
            "paper" => Some(ForceLaw::Paper),
            "flux" => Some(ForceLaw::Flux),
            _ => None,
        }
    }

    /// The name used in design files and reports.
    pub fn name(self) -> &'static str {
        match self {
            ForceLaw::Paper => "paper",
            ForceLaw::Flux => "flux",
        }
    }
}

/// The magnets' pull under either force law: P(t) = P·|sin ωt| (paper) or P·sin²ωt (flux),
/// P the total peak pull of all magnets, ω the mains angular frequency; the force repeats at
/// Ω = 2ω under both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagnetDrive {
    /// The force law.
    pub law: ForceLaw,
    /// Total peak pull of all magnets P, N (≥ 0).
    pub p_em: f64,
    /// Mains angular frequency ω, rad/s (> 0).
    pub omega_mains: f64,
}

impl MagnetDrive {
    /// `n` magnets of peak pull `p_each` (N) on mains ω (rad/s), validated as
    /// [`RectifiedDrive::from_magnets`].
    pub fn from_magnets(law: ForceLaw, n: usize, p_each: f64, omega_mains: f64) -> Result<Self> {
        let r = RectifiedDrive::from_magnets(n, p_each, omega_mains)?;
        Ok(MagnetDrive {
            law,
            p_em: r.p_em,
            omega_mains,
        })
    }

    /// Force frequency Ω = 2ω, rad/s.
    pub fn omega_force(&self) -> f64 {
        2.0 * self.omega_mains
    }

    /// Instantaneous pull P(t), N.
    pub fn force(&self, t: f64) -> f64 {
        let s = (self.omega_mains * t).sin();
        match self.law {
            ForceLaw::Paper => self.p_em * s.abs(),
            ForceLaw::Flux => self.p_em * s * s,
        }
    }

    /// Coefficient of cos(kΩt) in P(t), N (k = 0: the mean pull). Paper: eq. (8); flux:
    /// P/2 at k = 0, −P/2 at k = 1, zero above.
    pub fn cos_coefficient(&self, k: u32) -> f64 {
        match self.law {
            ForceLaw::Paper => fourier_coefficient(k) * self.p_em,
            ForceLaw::Flux => match k {
                0 => 0.5 * self.p_em,
                1 => -0.5 * self.p_em,
                _ => 0.0,
            },
        }
    }

    /// Mean pull, N: (2/π)·P (paper, eq. (9)) or P/2 (flux).
    pub fn mean(&self) -> f64 {
        self.cos_coefficient(0)
    }

    /// Amplitude of the Ω = 2ω harmonic that drives the machine, N: (4/(3π))·P (paper,
    /// eq. (11)) or P/2 (flux).
    pub fn harmonic_amplitude(&self) -> f64 {
        -self.cos_coefficient(1)
    }

    /// The paper law's drive as the transient integrator takes it.
    pub fn rectified(&self) -> Result<RectifiedDrive> {
        RectifiedDrive::new(self.p_em, self.omega_mains)
    }
}

/// The magnets' stiffness at the working gap δ (m), all magnets together (N/m, negative): the
/// gradient of the mean pull P̄ (N). An electromagnet's pull at a constant current linkage NI
/// is F = μ0·A·(NI)²/(4δ²)·(per pole pair) — Roters, *Electromagnetic Devices* (Wiley 1941),
/// ch. 7; the same form in Harris' *Shock and Vibration Handbook* (6th ed., ch. 13,
/// electrodynamic and electromagnetic exciters) — so dF/dδ = −2F/δ: the pull grows as the gap
/// closes, a negative spring −2P̄/δ between armature and core. (At a constant flux, i.e. a coil
/// fed at constant voltage with negligible resistance, the pull does not depend on the gap and
/// the stiffness vanishes; the constant-current value is the conservative one and is used.)
pub fn magnet_stiffness(mean_pull: f64, gap: f64) -> Result<f64> {
    if !(gap.is_finite() && gap > 0.0) {
        return Err(Error::param(
            "gap",
            format!("magnet gap must be finite and > 0 m, got {gap}"),
        ));
    }
    if !(mean_pull.is_finite() && mean_pull >= 0.0) {
        return Err(Error::param(
            "mean_pull",
            format!("mean magnet pull must be finite and ≥ 0 N, got {mean_pull}"),
        ));
    }
    Ok(-2.0 * mean_pull / gap)
}

/// The largest relative displacement |x1 − x2| (m) of the start-up from rest under `drive`
/// over `t_end` (s), and the steady relative amplitude at its end (half peak-to-peak over the
/// last period, m): classical fourth-order Runge–Kutta with 400 steps per force period (the
/// system is linear and its fastest mode is the resonant one near Ω, so the step resolves it
/// with an error far below the 1e-3 this peak is read to).
pub fn startup_peak_relative(model: &TwoMass, drive: &MagnetDrive, t_end: f64) -> Result<(f64, f64)> {
    model.validate()?;
    if !(t_end.is_finite() && t_end > 0.0) {
        return Err(Error::param(
            "t_end",
            format!("start-up length must be > 0 s, got {t_end}"),
        ));
    }
    let (m, c, k) = model.matrices();
    let period = std::f64::consts::TAU / drive.omega_force();
    let n_per = 400usize;
    let dt = period / n_per as f64;
    let steps = (t_end / dt).ceil() as usize;
    let rhs = |t: f64, y: &[f64; 4]| -> [f64; 4] {
        let p = drive.force(t);
        let f = [-p, p];
        let mut a = [0.0; 2];
        for i in 0..2 {
            let s: f64 = (0..2).map(|j| c[(i, j)] * y[2 + j] + k[(i, j)] * y[j]).sum();
            a[i] = (f[i] - s) / m[(i, i)];
        }
        [y[2], y[3], a[0], a[1]]
    };
    let mut y = [0.0f64; 4];
    let (mut peak, mut lo, mut hi) = (0.0f64, f64::INFINITY, f64::NEG_INFINITY);
    for s in 0..steps {
        let t = s as f64 * dt;
        let k1 = rhs(t, &y);
        let y2: [f64; 4] = std::array::from_fn(|i| y[i] + 0.5 * dt * k1[i]);
        let k2 = rhs(t + 0.5 * dt, &y2);
        let y3: [f64; 4] = std::array::from_fn(|i| y[i] + 0.5 * dt * k2[i]);
        let k3 = rhs(t + 0.5 * dt, &y3);
        let y4: [f64; 4] = std::array::from_fn(|i| y[i] + dt * k3[i]);
        let k4 = rhs(t + dt, &y4);
        y = std::array::from_fn(|i| y[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        let rel = y[0] - y[1];
        peak = peak.max(rel.abs());
        if s + n_per >= steps {
            lo = lo.min(rel);
            hi = hi.max(rel);
        }
    }
    Ok((peak, 0.5 * (hi - lo)))
}
