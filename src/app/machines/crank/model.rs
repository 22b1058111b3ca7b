//! Crank–slider drives of a roller-forming machine: motion non-uniformity (docs/spec/machines.md §A).
//!
//! One degree of freedom, the crank angle φ with speed ω, and the equation of motion
//!
//! ```text
//! I(φ)·ω·dω/dφ + ½·ω²·dI/dφ = M_d(ω) − M_r(φ)      ⇔      d(I ω²)/dφ = 2 (M_d − M_r)        (1)
//! ```
//!
//! - [`Mechanism`]: the kinematics of any number of crank–slider mechanisms on one shaft with phase
//!   shifts φ_k = φ + Δφ_k, their reduced inertia I(φ) and its exact derivative, and the reduced
//!   resisting moment M_r(φ) = Σ_k [F |dx_k/dφ| + G dyS_k/dφ] (the cart resistance opposes the
//!   cart's velocity; G = q l g is the rod weight).
//! - [`Motor`]: an induction motor by the Kloss formula, optionally with the unstable branch
//!   corrected to the catalogue starting torque ([`MotorLaw::KlossStartCorrected`]).
//! - [`CrankDrive`]: mechanism + motor through a reducer (ratio i, efficiency η, drive inertia I_p
//!   on the motor shaft, reduced as I_p i²): M_d(ω) = M(i ω)·i·η.
//! - Integrators: [`baranov`], the paper's first-order finite-difference step in φ, and
//!   [`energy_form`], the Dormand–Prince integrator of [`crate::app::dynamics::ode`] on d(Iω²)/dφ (with t as a
//!   second state); both run revolution by revolution until the revolution-to-revolution change of
//!   the metrics is below a tolerance. [`run_up`] starts from rest in the time domain (the
//!   φ-forms are singular at ω = 0) with a start-up treatment ([`Startup`]), and reports a stall.
//! - [`Metrics`]: δ = (ω_max − ω_min)/ω_mean, μ = |ε|_max/ω_mean², k_p = δ² + μ.
//!
//! `ω_mean` of a simulated revolution is its time average 2π/T (T the duration of the
//! revolution). The paper's Table 1 quotes ω_mean equal to (ω_min + ω_max)/2 for one and two carts;
//! the midrange is reported beside it.
//!
//! Units: SI (m, kg, N, N·m, kg·m², rad, rad/s, rad/s², s, W). Bad input gives an error at the
//! parameter ([`crate::Error::param`]) naming it; nothing panics.

// `!(x > 0.0)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::f64::consts::{PI, TAU};

use serde::Serialize;

use crate::app::dynamics::ode::{Dopri5Options, integrate};
use crate::{Error, Result};

fn check(name: &str, v: f64, ok: bool, want: &str) -> Result<()> {
    if v.is_finite() && ok {
        Ok(())
    } else {
        Err(Error::param(
            name,
            format!("crank drive: {name} must be {want}, got {}", crate::io::fmt_plain(v)),
        ))
    }
}

/// Derivatives with respect to φ of one crank–slider mechanism at its own crank angle φ_k.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CrankKinematics {
    /// dx/dφ: cart (slider) velocity per unit crank speed, m/rad.
    pub dx: f64,
    /// d²x/dφ², m/rad².
    pub ddx: f64,
    /// dxS/dφ: rod centre, along the slide, m/rad.
    pub dxs: f64,
    /// d²xS/dφ², m/rad².
    pub ddxs: f64,
    /// dyS/dφ: rod centre, across the slide, m/rad.
    pub dys: f64,
    /// d²yS/dφ², m/rad².
    pub ddys: f64,
    /// dβ/dφ: rod angle, rad/rad.
    pub dbeta: f64,
    /// d²β/dφ², 1/rad.
    pub ddbeta: f64,
}

/// A set of identical crank–slider mechanisms (carts) on one crank shaft.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Mechanism {
    /// Crank radius r, m.
    pub crank_radius: f64,
    /// Connecting-rod length l, m (> r).
    pub rod_length: f64,
    /// Rod mass per length q, kg/m.
    pub rod_mass_per_length: f64,
    /// Cart mass m (per cart), kg.
    pub cart_mass: f64,
    /// Cart resistance F (per cart), N: opposes the cart's velocity.
    pub cart_resistance: f64,
    /// Gravity g, m/s².
    pub gravity: f64,
    /// Crank phase of each cart relative to the shaft angle φ, rad (one entry per cart).
    pub phases: Vec<f64>,
}

impl Mechanism {
    /// Phases of `carts` cranks shifted successively by `shift` rad: 0, shift, 2·shift, ….
    pub fn uniform_phases(carts: usize, shift: f64) -> Vec<f64> {
        (0..carts).map(|k| k as f64 * shift).collect()
    }

    /// The paper's cart and rod data with `carts` cranks shifted by `shift` rad.
    pub fn paper(carts: usize, shift: f64) -> Mechanism {
        Mechanism {
            crank_radius: 0.2,
            rod_length: 0.8,
            rod_mass_per_length: 80.0,
            cart_mass: 1000.0,
            cart_resistance: 3562.0,
            gravity: 9.81,
            phases: Self::uniform_phases(carts, shift),
        }
    }

    /// Checks the data: positive lengths with r < l, non-negative masses and forces, 1–64 carts.
    pub fn validate(&self) -> Result<()> {
        check("crank_radius", self.crank_radius, self.crank_radius > 0.0, "> 0 m")?;
        check(
            "rod_length",
            self.rod_length,
            self.rod_length > self.crank_radius,
            "longer than the crank radius",
        )?;
        check(
            "rod_mass_per_length",
            self.rod_mass_per_length,
            self.rod_mass_per_length >= 0.0,
            "≥ 0 kg/m",
        )?;
        check("cart_mass", self.cart_mass, self.cart_mass >= 0.0, "≥ 0 kg")?;
        check(
            "cart_resistance",
            self.cart_resistance,
            self.cart_resistance >= 0.0,
            "≥ 0 N",
        )?;
        check("gravity", self.gravity, self.gravity >= 0.0, "≥ 0 m/s²")?;
        if self.phases.is_empty() || self.phases.len() > 64 {
            return Err(Error::param(
                "phases",
                format!(
                    "crank drive: the number of carts must be 1–64, got {}",
                    self.phases.len()
                ),
            ));
        }
        for p in &self.phases {
            check("a crank phase", *p, true, "finite")?;
        }
        Ok(())
    }

    /// λ = r/l.
    pub fn lambda(&self) -> f64 {
        self.crank_radius / self.rod_length
    }

    /// Rod inertia about its centre, I_s = q l³/12, kg·m².
    pub fn rod_inertia(&self) -> f64 {
        self.rod_mass_per_length * self.rod_length.powi(3) / 12.0
    }

    /// Rod weight G = q l g, N.
    pub fn rod_weight(&self) -> f64 {
        self.rod_mass_per_length * self.rod_length * self.gravity
    }

    /// First and second φ-derivatives of the cart, rod-centre and rod-angle motion of a crank at
    /// angle `phi_k` (docs/spec/machines.md §A; the second derivatives use
    /// d/dφ [cos φ/√(1 − λ² sin² φ)] = −(1 − λ²) sin φ/(1 − λ² sin² φ)^{3/2}).
    pub fn crank_kinematics(&self, phi_k: f64) -> CrankKinematics {
        let r = self.crank_radius;
        let lam = self.lambda();
        let (s, c) = phi_k.sin_cos();
        let d = (1.0 - lam * lam * s * s).sqrt();
        let g = c / d;
        let gp = -s * (1.0 - lam * lam) / (d * d * d);
        CrankKinematics {
            dx: -r * s * (1.0 + lam * g),
            ddx: -r * c * (1.0 + lam * g) - r * s * lam * gp,
            dxs: -r * s * (1.0 + 0.5 * lam * g),
            ddxs: -r * c * (1.0 + 0.5 * lam * g) - r * s * 0.5 * lam * gp,
            dys: 0.5 * r * c,
            ddys: -0.5 * r * s,
            dbeta: lam * g,
            ddbeta: lam * gp,
        }
    }

    /// Inertia of the carts and rods reduced to the crank shaft and its derivative dI/dφ, at φ.
    pub fn inertia(&self, phi: f64) -> (f64, f64) {
        let ql = self.rod_mass_per_length * self.rod_length;
        let is = self.rod_inertia();
        let m = self.cart_mass;
        let (mut i, mut di) = (0.0, 0.0);
        for &p in &self.phases {
            let k = self.crank_kinematics(phi + p);
            i += m * k.dx * k.dx + ql * (k.dxs * k.dxs + k.dys * k.dys) + is * k.dbeta * k.dbeta;
            di += 2.0 * (m * k.dx * k.ddx + ql * (k.dxs * k.ddxs + k.dys * k.ddys) + is * k.dbeta * k.ddbeta);
        }
        (i, di)
    }

    /// Reduced resisting moment M_r(φ) = Σ_k [F |dx_k/dφ| + G dyS_k/dφ], N·m (valid for ω > 0).
    pub fn resisting_moment(&self, phi: f64) -> f64 {
        let g = self.rod_weight();
        self.phases
            .iter()
            .map(|&p| {
                let k = self.crank_kinematics(phi + p);
                self.cart_resistance * k.dx.abs() + g * k.dys
            })
            .sum()
    }

    /// Mean resisting moment (1/2π)∫M_r dφ by Gauss–Legendre quadrature on the smooth pieces
    /// between the kinks of |dx_k/dφ| (where sin φ_k = 0), accurate to rounding.
    pub fn mean_resisting_moment(&self) -> f64 {
        let mut cuts: Vec<f64> = vec![0.0, TAU];
        for &p in &self.phases {
            for j in -2..=2 {
                let x = j as f64 * PI - p;
                let x = x.rem_euclid(TAU);
                cuts.push(x);
            }
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-14);
        let (xg, wg) = crate::fe::quadrature::gauss_legendre(16);
        let (mut sum, mut sum_abs) = (0.0, 0.0);
        for w in cuts.windows(2) {
            let (a, b) = (w[0], w[1]);
            if b - a <= 0.0 {
                continue;
            }
            // Four sub-intervals per piece: the integrand is smooth but not a low-degree polynomial.
            let n = 4;
            for k in 0..n {
                let (lo, hi) = (
                    a + (b - a) * k as f64 / n as f64,
                    a + (b - a) * (k + 1) as f64 / n as f64,
                );
                let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
                for (x, wt) in xg.iter().zip(&wg) {
                    let m = self.resisting_moment(mid + half * x);
                    sum += wt * half * m;
                    sum_abs += wt * half * m.abs();
                }
            }
        }
        // Without cart resistance the rods' weights average to zero: what the sum leaves then
        // is rounding (−7e-15 N·m), not a moment.
        if sum.abs() <= 1e-12 * sum_abs { 0.0 } else { sum / TAU }
    }

    /// The closed form of the mean: each cart travels 4r per revolution against F, and the rod
    /// weights average to zero: n·2Fr/π, N·m.
    pub fn mean_resisting_moment_closed_form(&self) -> f64 {
        self.phases.len() as f64 * 2.0 * self.cart_resistance * self.crank_radius / PI
    }
}

/// How the motor torque is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MotorLaw {
    /// The Kloss formula M = 2 M_c s s_c/(s_c² + s²) in slip speeds s = ω0 − ω_m, s_c = ω0 − ω_c.
    Kloss,
    /// Kloss on the stable branch (s ≤ s_c); on the unstable branch (s > s_c) the Kloss curve is
    /// mapped affinely so that it still reaches M_c at s_c (with zero slope: the law is C¹) and
    /// gives the catalogue starting torque at standstill. The Kloss formula alone gives far too
    /// little torque at low speed (39.8 N·m against the catalogue 129.24 N·m for the paper's motor).
    KlossStartCorrected,
}

/// An induction motor.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Motor {
    /// Synchronous speed ω0, rad/s.
    pub synchronous_speed: f64,
    /// Critical (pull-out) speed ω_c, rad/s (< ω0).
    pub critical_speed: f64,
    /// Critical (pull-out) torque M_c, N·m.
    pub critical_torque: f64,
    /// Catalogue nominal speed, rad/s (reported, not used by the law).
    pub nominal_speed: Option<f64>,
    /// Catalogue nominal torque, N·m (reported, not used by the law).
    pub nominal_torque: Option<f64>,
    /// Catalogue starting torque, N·m (needed by [`MotorLaw::KlossStartCorrected`]).
    pub starting_torque: Option<f64>,
    /// Torque law.
    pub law: MotorLaw,
}

impl Motor {
    /// The paper's motor: ω0 = 104.72, ω_c = 94.95 rad/s, M_c = 215.4 N·m; nominal 102.1 rad/s and
    /// 107.7 N·m; starting torque 129.24 N·m.
    pub fn paper(law: MotorLaw) -> Motor {
        Motor {
            synchronous_speed: 104.72,
            critical_speed: 94.95,
            critical_torque: 215.4,
            nominal_speed: Some(102.1),
            nominal_torque: Some(107.7),
            starting_torque: Some(129.24),
            law,
        }
    }

    /// Checks ω0 > 0, ω_c < ω0, M_c > 0, positive catalogue values, and 0 < M_start ≤ M_c (the
    /// corrected law needs M_start).
    pub fn validate(&self) -> Result<()> {
        check(
            "motor synchronous_speed",
            self.synchronous_speed,
            self.synchronous_speed > 0.0,
            "> 0 rad/s",
        )?;
        check(
            "motor critical_speed",
            self.critical_speed,
            self.critical_speed < self.synchronous_speed,
            "below the synchronous speed",
        )?;
        check(
            "motor critical_torque",
            self.critical_torque,
            self.critical_torque > 0.0,
            "> 0 N·m",
        )?;
        for (n, v) in [
            ("motor nominal_speed", self.nominal_speed),
            ("motor nominal_torque", self.nominal_torque),
        ] {
            if let Some(v) = v {
                check(n, v, v > 0.0, "> 0")?;
            }
        }
        if let Some(ms) = self.starting_torque {
            check(
                "motor starting_torque",
                ms,
                ms > 0.0 && ms <= self.critical_torque,
                "> 0 and at most the critical torque",
            )?;
        }
        if self.law == MotorLaw::KlossStartCorrected && self.starting_torque.is_none() {
            return Err(Error::param(
                "motor starting_torque",
                "crank drive: motor law 'kloss-corrected' needs the motor's starting_torque",
            ));
        }
        Ok(())
    }

    /// The plain Kloss torque at motor speed `w_m` with synchronous speed `w0` (the critical slip
    /// speed ω0 − ω_c and M_c kept: a constant-V/f supply), N·m. Negative above ω0 (generating).
    pub fn kloss_at(&self, w_m: f64, w0: f64) -> f64 {
        let s = w0 - w_m;
        let sc = self.synchronous_speed - self.critical_speed;
        2.0 * self.critical_torque * s * sc / (sc * sc + s * s)
    }

    /// Motor torque at speed `w_m` with synchronous speed `w0`, by the motor's law, N·m.
    pub fn torque_at(&self, w_m: f64, w0: f64) -> f64 {
        let k = self.kloss_at(w_m, w0);
        match (self.law, self.starting_torque) {
            (MotorLaw::KlossStartCorrected, Some(ms)) => {
                let s = w0 - w_m;
                let sc = self.synchronous_speed - self.critical_speed;
                if s <= sc {
                    k
                } else {
                    // Affine map of the unstable Kloss branch: M_c at s_c, M_start at s = ω0.
                    let k0 = self.kloss_at(0.0, self.synchronous_speed);
                    let mc = self.critical_torque;
                    ms + (k - k0) * (mc - ms) / (mc - k0)
                }
            }
            _ => k,
        }
    }

    /// Motor torque at speed `w_m` on the mains (ω0 as given), N·m.
    pub fn torque(&self, w_m: f64) -> f64 {
        self.torque_at(w_m, self.synchronous_speed)
    }
}

/// The reducer between the motor and the crank shaft.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Reducer {
    /// Ratio i = ω_motor/ω_crank.
    pub ratio: f64,
    /// Efficiency η (0, 1].
    pub efficiency: f64,
    /// Inertia of the drive on the motor shaft I_p (rotor, coupling, reducer), kg·m².
    pub inertia: f64,
}

/// How a run from rest is started.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum Startup {
    /// Direct on line: the motor law at the mains frequency from t = 0.
    Direct,
    /// A frequency-converter ramp: the synchronous speed rises linearly from 0 to ω0 in
    /// `ramp_time` s with the critical slip speed and torque kept (constant V/f), so the motor
    /// works on the stable part of its curve throughout.
    FrequencyRamp {
        /// Ramp duration, s (> 0).
        ramp_time: f64,
    },
}

/// A crank drive: mechanism, motor and reducer.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CrankDrive {
    /// Carts, rods and cranks.
    pub mechanism: Mechanism,
    /// The motor.
    pub motor: Motor,
    /// The reducer.
    pub reducer: Reducer,
    /// Factor on the motor torque (1 for the motor as given; e.g. a motor sized for another power).
    pub torque_scale: f64,
}

impl CrankDrive {
    /// The paper's two-cart drive (Δφ = π/2) with the plain Kloss motor.
    pub fn paper_two_carts() -> CrankDrive {
        CrankDrive {
            mechanism: Mechanism::paper(2, PI / 2.0),
            motor: Motor::paper(MotorLaw::Kloss),
            reducer: Reducer {
                ratio: 9.8,
                efficiency: 0.9,
                inertia: 0.138 + 0.32 + 0.046,
            },
            torque_scale: 1.0,
        }
    }

    /// Checks all the data.
    pub fn validate(&self) -> Result<()> {
        self.mechanism.validate()?;
        self.motor.validate()?;
        check("reducer ratio", self.reducer.ratio, self.reducer.ratio > 0.0, "> 0")?;
        check(
            "reducer efficiency",
            self.reducer.efficiency,
            self.reducer.efficiency > 0.0 && self.reducer.efficiency <= 1.0,
            "in (0, 1]",
        )?;
        check(
            "drive inertia",
            self.reducer.inertia,
            self.reducer.inertia >= 0.0,
            "≥ 0 kg·m²",
        )?;
        check("torque scale", self.torque_scale, self.torque_scale > 0.0, "> 0")?;
        let i_min = self.reduced_inertia_range(360).0;
        if !(i_min > 0.0) {
            return Err(Error::param(
                "reducer inertia",
                "crank drive: the reduced inertia is zero somewhere (give the drive inertia or cart masses)",
            ));
        }
        Ok(())
    }

    /// Reduced inertia I(φ) = I_p i² + carts and rods, and dI/dφ, kg·m².
    pub fn reduced_inertia(&self, phi: f64) -> (f64, f64) {
        let (i, di) = self.mechanism.inertia(phi);
        (i + self.reducer.inertia * self.reducer.ratio * self.reducer.ratio, di)
    }

    /// Smallest and largest reduced inertia on `n` samples of a revolution, kg·m².
    pub fn reduced_inertia_range(&self, n: usize) -> (f64, f64) {
        let n = n.max(4);
        (0..n)
            .map(|k| self.reduced_inertia(TAU * k as f64 / n as f64).0)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)))
    }

    /// Driving moment at the crank M_d = M(i ω)·i·η·scale at crank speed `w` (mains supply), N·m.
    pub fn driving_moment(&self, w: f64) -> f64 {
        self.driving_moment_at(w, self.motor.synchronous_speed)
    }

    /// Driving moment at the crank with the motor's synchronous speed `w0`, N·m.
    pub fn driving_moment_at(&self, w: f64, w0: f64) -> f64 {
        let r = &self.reducer;
        self.motor.torque_at(r.ratio * w, w0) * r.ratio * r.efficiency * self.torque_scale
    }

    /// Design power P = M_mean·ω/η at crank speed `w`, W.
    pub fn design_power(&self, w: f64) -> f64 {
        self.mechanism.mean_resisting_moment() * w / self.reducer.efficiency
    }

    /// Angular acceleration ε = dω/dt = (M_d − M_r − ½ ω² dI/dφ)/I at (φ, ω) with the driving
    /// moment `md`, rad/s².
    pub fn acceleration(&self, phi: f64, w: f64, md: f64) -> f64 {
        let (i, di) = self.reduced_inertia(phi);
        (md - self.mechanism.resisting_moment(phi) - 0.5 * w * w * di) / i
    }
}

/// The figures of merit of a steady revolution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Metrics {
    /// Smallest crank speed, rad/s.
    pub omega_min: f64,
    /// Largest crank speed, rad/s.
    pub omega_max: f64,
    /// Mean crank speed, rad/s (time mean 2π/T for a simulated revolution).
    pub omega_mean: f64,
    /// Largest |ε|, rad/s².
    pub eps_max: f64,
    /// δ = (ω_max − ω_min)/ω_mean.
    pub delta: f64,
    /// μ = |ε|_max/ω_mean².
    pub mu: f64,
    /// k_p = δ² + μ.
    pub k_p: f64,
}

impl Metrics {
    /// The metrics from the extremes, as the paper's Table 1 computes them.
    pub fn from_extremes(omega_min: f64, omega_max: f64, omega_mean: f64, eps_max: f64) -> Result<Metrics> {
        if !(omega_mean.is_finite() && omega_mean > 0.0) {
            return Err(Error::param(
                "omega_mean",
                format!("metrics: the mean speed must be > 0, got {omega_mean}"),
            ));
        }
        if !(omega_min.is_finite() && omega_max.is_finite() && eps_max.is_finite() && omega_max >= omega_min) {
            return Err(Error::param(
                "omega_max",
                format!(
                    "metrics: need finite extremes with ω_max ≥ ω_min, got {omega_min}, {omega_max}, |ε| {eps_max}"
                ),
            ));
        }
        let delta = (omega_max - omega_min) / omega_mean;
        let mu = eps_max.abs() / (omega_mean * omega_mean);
        Ok(Metrics {
            omega_min,
            omega_max,
            omega_mean,
            eps_max: eps_max.abs(),
            delta,
            mu,
            k_p: delta * delta + mu,
        })
    }
}

/// One row of the paper's Table 1: (ω_min, ω_max, ω_mean, |ε|_max) and the printed (δ, μ, k_p).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PaperRow {
    /// Number of carts.
    pub carts: usize,
    /// Phase shift between successive cranks, degrees.
    pub shift_deg: f64,
    /// ω_min, rad/s.
    pub omega_min: f64,
    /// ω_max, rad/s.
    pub omega_max: f64,
    /// ω_mean, rad/s.
    pub omega_mean: f64,
    /// |ε|_max, rad/s².
    pub eps_max: f64,
    /// Printed δ.
    pub delta: f64,
    /// Printed μ.
    pub mu: f64,
    /// Printed k_p.
    pub k_p: f64,
}

/// The paper's Table 1 (docs/spec/machines.md §A): one cart; two at 90°; three at 120°; four at 90°.
pub const PAPER_TABLE1: [PaperRow; 4] = [
    PaperRow {
        carts: 1,
        shift_deg: 0.0,
        omega_min: 7.898,
        omega_max: 11.5612,
        omega_mean: 9.7296,
        eps_max: 48.67,
        delta: 0.3765,
        mu: 0.51412,
        k_p: 0.656,
    },
    PaperRow {
        carts: 2,
        shift_deg: 90.0,
        omega_min: 9.546,
        omega_max: 11.166,
        omega_mean: 10.356,
        eps_max: 15.583,
        delta: 0.156,
        mu: 0.1453,
        k_p: 0.1696,
    },
    PaperRow {
        carts: 3,
        shift_deg: 120.0,
        omega_min: 9.714,
        omega_max: 10.845,
        omega_mean: 10.263,
        eps_max: 17.778,
        delta: 0.11,
        mu: 0.169,
        k_p: 0.181,
    },
    PaperRow {
        carts: 4,
        shift_deg: 90.0,
        omega_min: 9.02,
        omega_max: 11.752,
        omega_mean: 10.288,
        eps_max: 29.55,
        delta: 0.265,
        mu: 0.2792,
        k_p: 0.3497,
    },
];

/// Samples of a revolution (or of a run-up).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Samples {
    /// Crank angle, rad (cumulative).
    pub phi: Vec<f64>,
    /// Time, s.
    pub t: Vec<f64>,
    /// Crank speed, rad/s.
    pub omega: Vec<f64>,
    /// Angular acceleration, rad/s².
    pub eps: Vec<f64>,
}

impl Samples {
    fn push(&mut self, phi: f64, t: f64, w: f64, e: f64) {
        self.phi.push(phi);
        self.t.push(t);
        self.omega.push(w);
        self.eps.push(e);
    }
    fn clear(&mut self) {
        self.phi.clear();
        self.t.clear();
        self.omega.clear();
        self.eps.clear();
    }
}

/// Where and why a drive stalled.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stall {
    /// Crank angle (cumulative), rad.
    pub phi: f64,
    /// Time, s.
    pub t: f64,
    /// Driving moment at the crank at standstill (with the supply at that time), N·m.
    pub driving_at_rest: f64,
    /// Resisting moment at the stall angle, N·m.
    pub resisting: f64,
    /// Explanation.
    pub message: String,
}

/// Options of the φ-domain integrations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadyOptions {
    /// Crank speed at φ = start angle, rad/s (> 0).
    pub omega_start: f64,
    /// Crank angle at the start, rad.
    pub phi_start: f64,
    /// Baranov step Δφ, rad; also the output spacing of the adaptive integrator.
    pub step: f64,
    /// At least this many revolutions.
    pub min_revolutions: usize,
    /// At most this many revolutions.
    pub max_revolutions: usize,
    /// Steady when ω_min, ω_max and ω_mean of two successive revolutions differ by less than this
    /// (relative).
    pub steady_tol: f64,
    /// Tolerances of the adaptive integrator.
    pub ode: Dopri5Options,
}

impl Default for SteadyOptions {
    fn default() -> Self {
        SteadyOptions {
            omega_start: 10.5,
            phi_start: 0.0,
            step: 0.5f64.to_radians(),
            min_revolutions: 3,
            max_revolutions: 60,
            steady_tol: 1e-7,
            ode: Dopri5Options {
                rtol: 1e-10,
                atol: 1e-10,
                ..Dopri5Options::default()
            },
        }
    }
}

/// Result of a φ-domain integration to the steady state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteadyRun {
    /// "baranov" or "energy-form (Dormand–Prince 5(4))".
    pub method: String,
    /// Revolutions integrated.
    pub revolutions: usize,
    /// The last two revolutions agreed within the tolerance.
    pub converged: bool,
    /// Metrics of the last revolution (None if the drive stalled).
    pub metrics: Option<Metrics>,
    /// (ω_min + ω_max)/2 of the last revolution, rad/s.
    pub omega_midrange: Option<f64>,
    /// Angle mean (1/2π)∫ω dφ of the last revolution, rad/s.
    pub omega_angle_mean: Option<f64>,
    /// ω_mean of each revolution, rad/s (the approach to the steady state; not serialised).
    #[serde(skip)]
    pub mean_per_revolution: Vec<f64>,
    /// The last revolution, φ from 0 to 2π relative to its start (in the plots; not serialised).
    #[serde(skip)]
    pub last: Samples,
    /// Set if the drive stalled.
    pub stall: Option<Stall>,
    /// Right-hand-side evaluations (adaptive) or steps (Baranov).
    pub evaluations: usize,
}

/// Most steps (of the Baranov step, or output samples of the adaptive integrator) a steady-state
/// run may take over all its revolutions: 360/step per revolution × the revolutions.
pub const MAX_STEADY_STEPS: usize = 10_000_000;

fn validate_steady(drive: &CrankDrive, o: &SteadyOptions) -> Result<usize> {
    drive.validate()?;
    check("start speed", o.omega_start, o.omega_start > 0.0, "> 0 rad/s")?;
    check("start angle", o.phi_start, true, "finite")?;
    check(
        "step",
        o.step,
        o.step > 0.0 && o.step <= 10f64.to_radians(),
        "in (0°, 10°]",
    )?;
    let per_rev = (TAU / o.step).round();
    if (per_rev * o.step - TAU).abs() > 1e-9 * TAU {
        return Err(Error::param(
            "step",
            format!(
                "crank drive: the step {}° must divide 360° into a whole number of steps",
                o.step.to_degrees()
            ),
        ));
    }
    if o.min_revolutions < 2 || o.max_revolutions < o.min_revolutions || o.max_revolutions > 10_000 {
        return Err(Error::param(
            "max_revolutions",
            format!(
                "crank drive: revolutions must satisfy 2 ≤ min ≤ max ≤ 10000, got {}..{}",
                o.min_revolutions, o.max_revolutions
            ),
        ));
    }
    // Each revolution takes per_rev steps and keeps as many samples.
    if per_rev * o.max_revolutions as f64 > MAX_STEADY_STEPS as f64 {
        return Err(Error::param(
            "step",
            format!(
                "crank drive: a step of {}° over up to {} revolutions asks for {:.3e} steps (at most {:.0e})",
                o.step.to_degrees(),
                o.max_revolutions,
                per_rev * o.max_revolutions as f64,
                MAX_STEADY_STEPS as f64
            ),
        ));
    }
    check(
        "steady tolerance",
        o.steady_tol,
        o.steady_tol > 0.0 && o.steady_tol < 0.1,
        "in (0, 0.1)",
    )?;
    Ok(per_rev as usize)
}

fn revolution_metrics(s: &Samples) -> Option<(Metrics, f64, f64)> {
    if s.t.len() < 2 {
        return None;
    }
    let dt = s.t[s.t.len() - 1] - s.t[0];
    if !(dt > 0.0) {
        return None;
    }
    let wmin = s.omega.iter().copied().fold(f64::INFINITY, f64::min);
    let wmax = s.omega.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let emax = s.eps.iter().fold(0.0f64, |a, e| a.max(e.abs()));
    let m = Metrics::from_extremes(wmin, wmax, TAU / dt, emax).ok()?;
    // Angle mean by the trapezoidal rule on the uniform φ grid.
    let n = s.omega.len() - 1;
    let am = s.omega.windows(2).map(|w| 0.5 * (w[0] + w[1])).sum::<f64>() / n as f64;
    Some((m, 0.5 * (wmin + wmax), am))
}

fn steady_change(a: &Metrics, b: &Metrics) -> f64 {
    let r = |x: f64, y: f64| (x - y).abs() / y.abs().max(1e-300);
    r(a.omega_min, b.omega_min)
        .max(r(a.omega_max, b.omega_max))
        .max(r(a.omega_mean, b.omega_mean))
}

fn stall_message(drive: &CrankDrive, phi: f64, t: f64, w0: f64, how: &str) -> Stall {
    let md0 = drive.driving_moment_at(0.0, w0);
    let mr = drive.mechanism.resisting_moment(phi);
    let (mr_lo, mr_hi) = (0..720)
        .map(|k| drive.mechanism.resisting_moment(TAU * k as f64 / 720.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    Stall {
        phi,
        t,
        driving_at_rest: md0,
        resisting: mr,
        message: format!(
            "the drive stalls {how} at φ = {:.1}° (revolution {}, t = {:.3} s): the motor gives {:.0} N·m at the \
             crank at standstill against {:.0} N·m of resistance there ({:.0}–{:.0} N·m over a revolution)",
            phi.rem_euclid(TAU).to_degrees(),
            (phi / TAU).floor() as i64 + 1,
            t,
            md0,
            mr,
            mr_lo,
            mr_hi
        ),
    }
}

/// Where a drive at speed `w` at (`phi`, `t`) (the last sample above the stall floor) comes to
/// rest, before the next sample at `phi_next`: with the kinetic energy K = I ω² falling linearly
/// in φ at dK/dφ = 2 (M_d − M_r) (its rate at the sample), rest comes after
/// Δφ = I ω² / (2 (M_r − M_d)) and Δt = ∫ dφ/ω = I ω / (M_r − M_d) (a uniform deceleration).
/// A rate that does not fall gives the next sample's angle and the time at the sample's speed.
fn stall_point(drive: &CrankDrive, (phi, t, w): (f64, f64, f64), phi_next: f64) -> (f64, f64) {
    let (i, _) = drive.reduced_inertia(phi);
    let excess = drive.mechanism.resisting_moment(phi) - drive.driving_moment(w);
    if excess > 0.0 && w > 0.0 {
        let dphi = (i * w * w / (2.0 * excess)).min(phi_next - phi);
        // The time of the uniform deceleration over the angle actually taken.
        let w_end = (w * w - 2.0 * excess / i * dphi).max(0.0).sqrt();
        (phi + dphi, t + i * (w - w_end) / excess)
    } else {
        (phi_next, t + (phi_next - phi) / w.max(f64::MIN_POSITIVE))
    }
}

/// Close a revolution of a φ-domain run: record its mean speed and say whether the run is
/// steady (two successive revolutions agree within the tolerance, after the minimum count).
fn revolution_closed(
    last: &Samples,
    prev: &mut Option<Metrics>,
    means: &mut Vec<f64>,
    revs: usize,
    o: &SteadyOptions,
) -> Result<bool> {
    let (m, _, _) = revolution_metrics(last)
        .ok_or_else(|| Error::InvalidInput("crank drive: a revolution took no time (speed not finite)".into()))?;
    means.push(m.omega_mean);
    let steady = matches!(prev, Some(p) if revs >= o.min_revolutions && steady_change(&m, p) < o.steady_tol);
    *prev = Some(m);
    Ok(steady)
}

/// The result of a φ-domain run that reached its end without stalling.
fn steady_run(
    method: &str,
    revolutions: usize,
    converged: bool,
    means: Vec<f64>,
    last: Samples,
    evaluations: usize,
) -> Result<SteadyRun> {
    let (m, mid, am) = revolution_metrics(&last)
        .ok_or_else(|| Error::InvalidInput("crank drive: no complete revolution was integrated".into()))?;
    Ok(SteadyRun {
        method: method.into(),
        revolutions,
        converged,
        metrics: Some(m),
        omega_midrange: Some(mid),
        omega_angle_mean: Some(am),
        mean_per_revolution: means,
        last,
        stall: None,
        evaluations,
    })
}

/// The paper's Baranov finite-difference step in φ, from `o.omega_start` at `o.phi_start`:
///
/// ```text
/// ω_{n+1} = (M_d(ω_n) − M_r(φ_n))/(I_n ω_n)·Δφ + (3 I_n − I_{n+1})/(2 I_n)·ω_n
/// t_{n+1} = t_n + 2Δφ/(ω_n + ω_{n+1}),   ε_n = (ω_{n+1} − ω_n)/(t_{n+1} − t_n)
/// ```
///
/// First order in Δφ; singular at ω = 0 (a speed falling to zero is reported as a stall).
pub fn baranov(drive: &CrankDrive, o: &SteadyOptions) -> Result<SteadyRun> {
    let per_rev = validate_steady(drive, o)?;
    let dphi = TAU / per_rev as f64;
    let mut w = o.omega_start;
    let mut t = 0.0;
    let mut phi = o.phi_start;
    let mut i_n = drive.reduced_inertia(phi).0;
    let mut means = Vec::new();
    let mut last = Samples::default();
    let mut prev: Option<Metrics> = None;
    let mut converged = false;
    let mut steps = 0usize;
    let mut revs = 0usize;
    for rev in 0..o.max_revolutions {
        last.clear();
        let (phi0, t0) = (phi, t);
        for k in 0..per_rev {
            let phi_next = o.phi_start + (rev * per_rev + k + 1) as f64 * dphi;
            let i_next = drive.reduced_inertia(phi_next).0;
            let md = drive.driving_moment(w);
            let mr = drive.mechanism.resisting_moment(phi);
            let w_next = (md - mr) / (i_n * w) * dphi + (3.0 * i_n - i_next) / (2.0 * i_n) * w;
            steps += 1;
            if !(w_next.is_finite() && w_next > 0.0) {
                let st = stall_message(drive, phi, t, drive.motor.synchronous_speed, "(Baranov step)");
                return Ok(SteadyRun {
                    method: "baranov".into(),
                    revolutions: rev + 1,
                    converged: false,
                    metrics: None,
                    omega_midrange: None,
                    omega_angle_mean: None,
                    mean_per_revolution: means,
                    last,
                    stall: Some(st),
                    evaluations: steps,
                });
            }
            let t_next = t + 2.0 * dphi / (w + w_next);
            let eps = (w_next - w) / (t_next - t);
            last.push(phi - phi0, t - t0, w, eps);
            w = w_next;
            t = t_next;
            phi = phi_next;
            i_n = i_next;
        }
        // Close the revolution with its end point (its ε is the next step's; use the last one).
        let e_last = *last.eps.last().unwrap_or(&0.0);
        last.push(phi - phi0, t - t0, w, e_last);
        revs = rev + 1;
        if revolution_closed(&last, &mut prev, &mut means, revs, o)? {
            converged = true;
            break;
        }
    }
    steady_run("baranov", revs, converged, means, last, steps)
}

/// The energy form of (1) integrated in φ by Dormand–Prince 5(4): state (K = I ω², t) with
///
/// ```text
/// dK/dφ = 2 (M_d(ω) − M_r(φ)),   dt/dφ = 1/ω,   ω = √(K/I(φ))
/// ```
///
/// revolution by revolution, sampled every `o.step` (dense output). ε = (M_d − M_r − ½ω² I')/I
/// at the samples. A speed falling below 0.1 % of the start speed is reported as a stall.
pub fn energy_form(drive: &CrankDrive, o: &SteadyOptions) -> Result<SteadyRun> {
    let per_rev = validate_steady(drive, o)?;
    let dphi = TAU / per_rev as f64;
    let w_floor = 1e-3 * o.omega_start;
    let rhs = |phi: f64, y: &[f64], dy: &mut [f64]| {
        let (i, _) = drive.reduced_inertia(phi);
        let w = (y[0].max(0.0) / i).sqrt().max(1e-2 * w_floor);
        dy[0] = 2.0 * (drive.driving_moment(w) - drive.mechanism.resisting_moment(phi));
        dy[1] = 1.0 / w;
    };
    let i0 = drive.reduced_inertia(o.phi_start).0;
    let mut y = vec![i0 * o.omega_start * o.omega_start, 0.0];
    let mut phi = o.phi_start;
    let mut means = Vec::new();
    let mut last = Samples::default();
    let mut prev: Option<Metrics> = None;
    let mut converged = false;
    let mut evals = 0usize;
    let mut revs = 0usize;
    // The last sample above the stall floor (φ, t, ω): the stall point is extrapolated from it.
    let mut above = (o.phi_start, 0.0, o.omega_start);
    for rev in 0..o.max_revolutions {
        let phi0 = phi;
        let outs: Vec<f64> = (0..=per_rev).map(|k| phi0 + k as f64 * dphi).collect();
        let sol = integrate(rhs, phi0, &y, &outs, &[], &o.ode)?;
        evals += sol.stats.rhs_evals;
        last.clear();
        let t0 = sol.y[0][1];
        for (p, yy) in outs.iter().zip(&sol.y) {
            let (i, _) = drive.reduced_inertia(*p);
            let w = (yy[0].max(0.0) / i).sqrt();
            if w < w_floor {
                // Past the stall the integrated time means nothing (ω is held at a floor there):
                // the stall point comes from the last sample above it.
                let (phi_s, t_s) = stall_point(drive, above, *p);
                let st = stall_message(drive, phi_s, t_s, drive.motor.synchronous_speed, "(energy form)");
                return Ok(SteadyRun {
                    method: "energy-form (Dormand–Prince 5(4))".into(),
                    revolutions: rev + 1,
                    converged: false,
                    metrics: None,
                    omega_midrange: None,
                    omega_angle_mean: None,
                    mean_per_revolution: means,
                    last,
                    stall: Some(st),
                    evaluations: evals,
                });
            }
            let e = drive.acceleration(*p, w, drive.driving_moment(w));
            last.push(p - phi0, yy[1] - t0, w, e);
            above = (*p, yy[1], w);
        }
        y = sol.y[sol.y.len() - 1].clone();
        phi = outs[outs.len() - 1];
        revs = rev + 1;
        if revolution_closed(&last, &mut prev, &mut means, revs, o)? {
            converged = true;
            break;
        }
    }
    steady_run("energy-form (Dormand–Prince 5(4))", revs, converged, means, last, evals)
}

/// Options of [`run_up`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunUpOptions {
    /// Crank angle at rest, rad.
    pub phi_start: f64,
    /// Start-up treatment.
    pub startup: Startup,
    /// Simulated time, s (> 0).
    pub duration: f64,
    /// Output spacing, s.
    pub dt_out: f64,
    /// Integrator tolerances.
    pub ode: Dopri5Options,
}

impl Default for RunUpOptions {
    fn default() -> Self {
        RunUpOptions {
            phi_start: 0.0,
            startup: Startup::Direct,
            duration: 12.0,
            dt_out: 2e-3,
            ode: Dopri5Options {
                rtol: 1e-9,
                atol: 1e-9,
                ..Dopri5Options::default()
            },
        }
    }
}

/// A run from rest.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunUp {
    /// Treatment used.
    pub startup: Startup,
    /// Motor law used.
    pub law: MotorLaw,
    /// Samples (φ, t, ω, ε) every `dt_out` until the end or the stall.
    pub samples: Samples,
    /// Set if the drive stalled (never started, or stopped again).
    pub stall: Option<Stall>,
    /// Metrics of the last whole revolution, if the drive turned at least two revolutions.
    pub metrics: Option<Metrics>,
    /// First time the speed reached 95 % of the final mean speed, s.
    pub time_to_95: Option<f64>,
    /// Revolutions turned by then.
    pub revolutions_to_95: Option<f64>,
    /// Revolutions turned in all.
    pub revolutions: f64,
}

/// Start-up from rest in the time domain: state (φ, ω),
///
/// ```text
/// dφ/dt = ω,   dω/dt = (M_d(ω, t) − M_r(φ) − ½ ω² I'(φ)) / I(φ)
/// ```
///
/// (equation (1) with t as the independent variable; not singular at ω = 0). The cart resistance
/// is Coulomb friction: at rest it holds the drive as long as the net moment does not push it
/// forward, so the speed stays at zero there. A drive at rest that the motor cannot move any more
/// (the supply has reached its final frequency) has stalled; the run stops with a [`Stall`].
pub fn run_up(drive: &CrankDrive, o: &RunUpOptions) -> Result<RunUp> {
    drive.validate()?;
    check(
        "run-up duration",
        o.duration,
        o.duration > 0.0 && o.duration <= 3600.0,
        "in (0, 3600] s",
    )?;
    check(
        "run-up output spacing",
        o.dt_out,
        o.dt_out > 0.0 && o.duration / o.dt_out <= 2e6,
        "> 0 and at most 2e6 samples",
    )?;
    check("start angle", o.phi_start, true, "finite")?;
    let w0_full = drive.motor.synchronous_speed;
    let ramp = match o.startup {
        Startup::Direct => 0.0,
        Startup::FrequencyRamp { ramp_time } => {
            check("ramp_time", ramp_time, ramp_time > 0.0, "> 0 s")?;
            ramp_time
        }
    };
    let sync = move |t: f64| {
        if ramp > 0.0 {
            w0_full * (t / ramp).min(1.0)
        } else {
            w0_full
        }
    };
    let net = |phi: f64, w: f64, t: f64| -> f64 {
        let (i, di) = drive.reduced_inertia(phi);
        (drive.driving_moment_at(w, sync(t)) - drive.mechanism.resisting_moment(phi) - 0.5 * w * w * di) / i
    };
    let rhs = |t: f64, y: &[f64], dy: &mut [f64]| {
        let w = y[1].max(0.0);
        let a = net(y[0], w, t);
        if y[1] <= 0.0 && a <= 0.0 {
            dy[0] = 0.0;
            dy[1] = 0.0;
        } else {
            dy[0] = w;
            dy[1] = a;
        }
    };
    let n_out = (o.duration / o.dt_out).ceil() as usize;
    let chunk = 250usize;
    let mut samples = Samples::default();
    let mut y = vec![o.phi_start, 0.0];
    let mut t = 0.0;
    let mut stall = None;
    let mut k0 = 0usize;
    // Breakpoint: the ramp's kink.
    let bps = if ramp > 0.0 { vec![ramp] } else { vec![] };
    let push = |s: &mut Samples, t: f64, y: &[f64]| {
        let w = y[1].max(0.0);
        let a = net(y[0], w, t);
        let e = if y[1] <= 0.0 && a <= 0.0 { 0.0 } else { a };
        s.push(y[0], t, w, e);
    };
    push(&mut samples, 0.0, &y);
    while k0 < n_out {
        let k1 = (k0 + chunk).min(n_out);
        let outs: Vec<f64> = (k0 + 1..=k1).map(|k| k as f64 * o.dt_out).collect();
        let sol = integrate(rhs, t, &y, &outs, &bps, &o.ode)?;
        for (tt, yy) in outs.iter().zip(&sol.y) {
            push(&mut samples, *tt, yy);
        }
        t = outs[outs.len() - 1];
        y = sol.y[sol.y.len() - 1].clone();
        k0 = k1;
        // Stuck at rest with the supply at its final frequency: a stall.
        if y[1] <= 1e-9 * w0_full && t >= ramp && net(y[0], 0.0, t) <= 0.0 {
            let how = if samples.phi.iter().any(|p| *p > o.phi_start + 1e-6) {
                "after starting"
            } else {
                "at start (it never moves)"
            };
            // The time it came to rest: the first sample of the final rest.
            let t_rest = match samples.omega.iter().rposition(|w| *w > 1e-9 * w0_full) {
                Some(idx) => samples.t[(idx + 1).min(samples.t.len() - 1)],
                None => 0.0,
            };
            let s = stall_message(drive, y[0], t_rest, sync(t), how);
            stall = Some(s);
            break;
        }
    }
    let revolutions = (samples.phi[samples.phi.len() - 1] - o.phi_start) / TAU;
    let mut metrics = None;
    let (mut t95, mut r95) = (None, None);
    if stall.is_none() && revolutions >= 2.0 {
        // Last whole revolution: from φ_end − 2π to φ_end.
        let n = samples.phi.len();
        let phi_end = samples.phi[n - 1];
        let start = samples.phi.iter().rposition(|p| *p <= phi_end - TAU).unwrap_or(0);
        let sub = Samples {
            phi: samples.phi[start..].to_vec(),
            t: samples.t[start..].to_vec(),
            omega: samples.omega[start..].to_vec(),
            eps: samples.eps[start..].to_vec(),
        };
        // Time of the revolution from the crossing times (linear interpolation in φ).
        let (p0, p1, ta, tb) = (sub.phi[0], sub.phi[1], sub.t[0], sub.t[1]);
        let t_cross = if p1 > p0 {
            ta + (phi_end - TAU - p0) / (p1 - p0) * (tb - ta)
        } else {
            ta
        };
        let dt = sub.t[sub.t.len() - 1] - t_cross;
        let wmin = sub.omega.iter().copied().fold(f64::INFINITY, f64::min);
        let wmax = sub.omega.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let emax = sub.eps.iter().fold(0.0f64, |a, e| a.max(e.abs()));
        if dt > 0.0 {
            let m = Metrics::from_extremes(wmin, wmax, TAU / dt, emax)?;
            if let Some(i) = samples.omega.iter().position(|w| *w >= 0.95 * m.omega_mean) {
                t95 = Some(samples.t[i]);
                r95 = Some((samples.phi[i] - o.phi_start) / TAU);
            }
            metrics = Some(m);
        }
    }
    Ok(RunUp {
        startup: o.startup,
        law: drive.motor.law,
        samples,
        stall,
        metrics,
        time_to_95: t95,
        revolutions_to_95: r95,
        revolutions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inertia_derivative_matches_finite_difference() {
        let d = CrankDrive::paper_two_carts();
        for k in 0..37 {
            let p = 0.17 * k as f64;
            let h = 1e-5;
            let fd = (d.reduced_inertia(p + h).0 - d.reduced_inertia(p - h).0) / (2.0 * h);
            let an = d.reduced_inertia(p).1;
            assert!((fd - an).abs() < 1e-6 * (1.0 + an.abs()), "φ = {p}: {an} vs {fd}");
        }
    }
}
