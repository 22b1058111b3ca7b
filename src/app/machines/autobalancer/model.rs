//! Ball autobalancer of a hand grinder held by a rocker (docs/spec/machines.md §B).
//!
//! The grinder housing hangs on a rocker pivoting about O through a visco-elastic hinge (stiffness
//! c, damping h, both reduced to the arm l = |OK| from the pivot to the disc centre K). The disc
//! (mass m_d, inertia J_d) spins at ω relative to the housing and carries an imbalance m_0 at
//! radius R_0, angle α_0 on the disc. n balls (mass m_i, race radius R_i) roll in a race on the
//! disc with viscous drag h_i against it. Coordinates: rocker angle φ and ball angles ψ_i relative
//! to the housing (ψ_0 = θ(t) + α_0 for the imbalance, θ the disc angle). The equations (from the
//! Lagrangian; at constant ω they are the seed's):
//!
//! ```text
//! balls:   m_i [R_i (ψ̈_i + φ̈) + l φ̈ cos ψ_i + l φ̇² sin ψ_i] + h_i R_i (ψ̇_i − ω) = 0
//! housing: (J + 2l Σ_{0..n} m_i R_i cos ψ_i) φ̈ + J_d ω̇ + Σ_{0..n} m_i (R_i² + l R_i cos ψ_i) ψ̈_i
//!          − l Σ_{0..n} m_i R_i ψ̇_i² sin ψ_i − 2l φ̇ Σ_{0..n} m_i R_i ψ̇_i sin ψ_i + h l² φ̇ + c' l² φ = M
//! J = J_0 + J_d + m_d l² + Σ_{0..n} m_i (l² + R_i²)
//! ```
//!
//! (ψ̈_0 = ω̇ and the reaction J_d ω̇ of the spinning disc only matter during a run-up.) While
//! cutting, c' = c + c_r [sin θ + f_r (R/l − cos θ)] sin θ and M is the constant moment of the
//! cutting force about O; at idle c' = c, M = 0. The accelerations follow from the (1 + n)×(1 + n)
//! symmetric positive definite mass matrix by eliminating the balls. The state is (φ, φ̇, α_i, α̇_i)
//! with α_i = ψ_i − θ(t) the ball angles on the disc; integration by [`super::ode`].
//!
//! Linear criterion: with ω_0² = c' l²/J and h̃ = h l²/(2J), ε = l m_0 R_0/J, the first-order mean
//! projection of the disc centre's displacement on the imbalance is ε N l/2 with
//! N = ω²(ω_0² − ω²)/[(ω_0² − ω²)² + 4h̃²ω²] ([`mean_projection`], checked by
//! [`mean_projection_numeric`] on the linear periodic equation): negative, i.e. the housing swings
//! away from the imbalance and drives the balls opposite it, exactly when **ω > ω_0**. While cutting
//! this bounds the surface stiffness ([`Grinder::cr_bound`], [`Grinder::cr_bound_paper`]).
//!
//! Units: SI (m, kg, N/m, N·s/m, kg·m², rad, rad/s, s). Angles in reports are degrees.

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
            format!("autobalancer: {name} must be {want}, got {}", crate::io::fmt_plain(v)),
        ))
    }
}

/// Wraps an angle in degrees to (−180, 180].
pub fn wrap_deg(a: f64) -> f64 {
    let mut x = a.rem_euclid(360.0);
    if x > 180.0 {
        x -= 360.0;
    }
    x
}

/// One ball of the autobalancer.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ball {
    /// Mass m_i, kg.
    pub mass: f64,
    /// Race radius R_i, m.
    pub radius: f64,
    /// Viscous drag h_i against the race, N·s/m (force per relative speed).
    pub drag: f64,
    /// Initial angle on the disc (from the disc mark, like the imbalance angle), rad.
    pub initial_angle: f64,
}

/// Cutting with the disc periphery.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Cutting {
    /// Surface stiffness c_r, N/m.
    pub surface_stiffness: f64,
    /// Abrasive friction coefficient f_r.
    pub friction: f64,
    /// Contact angle θ, rad.
    pub contact_angle: f64,
    /// Constant moment of the cutting force about O, N·m.
    pub moment: f64,
}

/// The grinder on its rocker with the autobalancer.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Grinder {
    /// Arm l = |OK| from the pivot to the disc centre, m.
    pub arm: f64,
    /// Hinge stiffness c reduced to the arm, N/m.
    pub stiffness: f64,
    /// Hinge damping h reduced to the arm, N·s/m.
    pub damping: f64,
    /// Inertia J_0 of the rocker and housing about O, kg·m².
    pub rocker_inertia: f64,
    /// Disc mass m_d, kg.
    pub disc_mass: f64,
    /// Disc inertia J_d about its axis, kg·m².
    pub disc_inertia: f64,
    /// Disc radius R, m.
    pub disc_radius: f64,
    /// Imbalance mass m_0, kg.
    pub imbalance_mass: f64,
    /// Imbalance radius R_0, m.
    pub imbalance_radius: f64,
    /// Imbalance angle α_0 on the disc, rad.
    pub imbalance_angle: f64,
    /// Operating disc speed ω, rad/s.
    pub speed: f64,
    /// The balls.
    pub balls: Vec<Ball>,
}

impl Grinder {
    /// A plausible 125 mm angle grinder on a rocker, 10 000 rpm (the seed gives no numbers):
    ///
    /// - disc: 125 × 6 mm grinding disc, m_d = 0.18 kg, J_d = ½ m_d (R² + r_bore²) = 3.6245e-4 kg·m²
    ///   with a 22 mm bore;
    /// - imbalance: 1 g at 50 mm (50 g·mm, a coarse disc), at angle 0;
    /// - balls: two 8 mm steel balls (2.1 g each) in a race of radius 30 mm, drag 0.1 N·s/m
    ///   (oil-damped race: ball settling within about 0.1–1 s), starting at 60° and 150° on the disc;
    /// - rocker: arm 0.15 m, J_0 = 0.02 kg·m² (housing of about 2 kg about the pivot);
    /// - hinge: stiffness for a rocker natural frequency of 60 Hz with the balls
    ///   (c ≈ 1.55e5 N/m), damping ratio 0.1 (h ≈ 82 N·s/m).
    ///
    /// The operating speed is 2.78 ω_0. The same data are in `scenes/machines/grinder_autobalancer.toml`.
    pub fn plausible() -> Grinder {
        let ball_mass = 0.0021;
        let mut g = Grinder {
            arm: 0.15,
            stiffness: 0.0,
            damping: 0.0,
            rocker_inertia: 0.02,
            disc_mass: 0.18,
            disc_inertia: 3.6245e-4,
            disc_radius: 0.0625,
            imbalance_mass: 1e-3,
            imbalance_radius: 0.05,
            imbalance_angle: 0.0,
            speed: 10_000.0 * TAU / 60.0,
            balls: vec![
                Ball {
                    mass: ball_mass,
                    radius: 0.03,
                    drag: 0.1,
                    initial_angle: 60f64.to_radians(),
                },
                Ball {
                    mass: ball_mass,
                    radius: 0.03,
                    drag: 0.1,
                    initial_angle: 150f64.to_radians(),
                },
            ],
        };
        g.set_hinge_stiffness(60.0);
        g.set_hinge_damping_ratio(0.1);
        g
    }

    /// Sets the hinge stiffness c so that ω_0 = √(c l²/J) (with the balls) is `f_hz` Hz.
    pub fn set_hinge_stiffness(&mut self, f_hz: f64) {
        let w0 = TAU * f_hz;
        self.stiffness = self.inertia() * w0 * w0 / (self.arm * self.arm);
    }

    /// Sets the hinge damping h so that h̃/ω_0 = h l²/(2 J ω_0) is `zeta` (uses the current c).
    pub fn set_hinge_damping_ratio(&mut self, zeta: f64) {
        self.damping = 2.0 * self.inertia() * zeta * self.omega0(None) / (self.arm * self.arm);
    }

    /// A plausible cutting case for [`Grinder::plausible`]: c_r = 3e5 N/m, f_r = 0.4, θ = 90°, and
    /// a 30 N pressing force at the 0.15 m arm (M = 4.5 N·m).
    pub fn plausible_cutting() -> Cutting {
        Cutting {
            surface_stiffness: 3e5,
            friction: 0.4,
            contact_angle: 90f64.to_radians(),
            moment: 4.5,
        }
    }

    /// Checks the data.
    pub fn validate(&self) -> Result<()> {
        check("arm", self.arm, self.arm > 0.0, "> 0 m")?;
        check("stiffness", self.stiffness, self.stiffness > 0.0, "> 0 N/m")?;
        check("damping", self.damping, self.damping >= 0.0, "≥ 0 N·s/m")?;
        check(
            "rocker_inertia",
            self.rocker_inertia,
            self.rocker_inertia >= 0.0,
            "≥ 0 kg·m²",
        )?;
        check("disc_mass", self.disc_mass, self.disc_mass >= 0.0, "≥ 0 kg")?;
        check("disc_inertia", self.disc_inertia, self.disc_inertia >= 0.0, "≥ 0 kg·m²")?;
        check("disc_radius", self.disc_radius, self.disc_radius > 0.0, "> 0 m")?;
        check(
            "imbalance_mass",
            self.imbalance_mass,
            self.imbalance_mass > 0.0,
            "> 0 kg",
        )?;
        check(
            "imbalance_radius",
            self.imbalance_radius,
            self.imbalance_radius > 0.0,
            "> 0 m",
        )?;
        check("imbalance_angle", self.imbalance_angle, true, "finite")?;
        check("speed", self.speed, self.speed > 0.0, "> 0 rad/s")?;
        if self.balls.len() > 16 {
            return Err(Error::param(
                "balls",
                format!("autobalancer: at most 16 balls, got {}", self.balls.len()),
            ));
        }
        for (k, b) in self.balls.iter().enumerate() {
            let n = |s: &str| format!("ball {} {s}", k + 1);
            check(&n("mass"), b.mass, b.mass > 0.0, "> 0 kg")?;
            check(&n("radius"), b.radius, b.radius > 0.0, "> 0 m")?;
            check(&n("drag"), b.drag, b.drag >= 0.0, "≥ 0 N·s/m")?;
            check(&n("initial angle"), b.initial_angle, true, "finite")?;
        }
        if !(self.inertia() > 0.0) {
            return Err(Error::param(
                "rocker_inertia",
                "autobalancer: the rocker inertia J is zero",
            ));
        }
        Ok(())
    }

    /// J = J_0 + J_d + m_d l² + Σ_{0..n} m_i (l² + R_i²) with the balls, kg·m².
    pub fn inertia(&self) -> f64 {
        self.inertia_without_balls()
            + self
                .balls
                .iter()
                .map(|b| b.mass * (self.arm * self.arm + b.radius * b.radius))
                .sum::<f64>()
    }

    /// J without the balls, kg·m².
    pub fn inertia_without_balls(&self) -> f64 {
        let l2 = self.arm * self.arm;
        self.rocker_inertia
            + self.disc_inertia
            + self.disc_mass * l2
            + self.imbalance_mass * (l2 + self.imbalance_radius * self.imbalance_radius)
    }

    /// Added hinge stiffness factor of cutting g(θ) = [sin θ + f_r (R/l − cos θ)] sin θ.
    pub fn cutting_factor(&self, c: &Cutting) -> f64 {
        let (s, co) = c.contact_angle.sin_cos();
        // sin 180° is 1.2e-16 in floating point, not 0: a bound of 1e22 N/m where there is none.
        let s = if s.abs() < 1e-12 { 0.0 } else { s };
        (s + c.friction * (self.disc_radius / self.arm - co)) * s
    }

    /// Hinge stiffness c' = c + c_r g(θ) while cutting (c at idle), N/m.
    pub fn effective_stiffness(&self, cutting: Option<&Cutting>) -> f64 {
        match cutting {
            Some(c) => self.stiffness + c.surface_stiffness * self.cutting_factor(c),
            None => self.stiffness,
        }
    }

    /// ω_0 = √(c' l²/J) with the balls, rad/s.
    pub fn omega0(&self, cutting: Option<&Cutting>) -> f64 {
        (self.effective_stiffness(cutting) * self.arm * self.arm / self.inertia()).sqrt()
    }

    /// h̃ = h l²/(2J), 1/s.
    pub fn h_tilde(&self) -> f64 {
        self.damping * self.arm * self.arm / (2.0 * self.inertia())
    }

    /// ε = l m_0 R_0 / J of the disc's imbalance.
    pub fn epsilon(&self) -> f64 {
        self.arm * self.imbalance_mass * self.imbalance_radius / self.inertia()
    }

    /// Largest surface stiffness for which the grinder still balances at speed `w` while cutting
    /// at the contact angle of `c`: J ω² > c' l² ⇔ c_r < (J ω² − c l²)/(l² g(θ)), N/m. Negative
    /// when the grinder does not balance even at idle; infinite when g(θ) ≤ 0.
    pub fn cr_bound(&self, w: f64, c: &Cutting) -> f64 {
        let g = self.cutting_factor(c);
        let num = self.inertia() * w * w - self.stiffness * self.arm * self.arm;
        if g <= 0.0 {
            return if num > 0.0 { f64::INFINITY } else { f64::NEG_INFINITY };
        }
        num / (self.arm * self.arm * g)
    }

    /// The seed's closed form c_r < (J ω² − c l²)/(l [l + R f_r + l f_r²/4 − R f_r³/8]), N/m: the
    /// general bound at the worst contact angle cos θ* = −f_r/2 (the maximum of g(θ) without its
    /// R/l term) expanded to third order in f_r.
    pub fn cr_bound_paper(&self, w: f64, friction: f64) -> f64 {
        let (l, r, f) = (self.arm, self.disc_radius, friction);
        (self.inertia() * w * w - self.stiffness * l * l) / (l * (l + r * f + l * f * f / 4.0 - r * f * f * f / 8.0))
    }

    /// Angles of two equal balls (relative to the imbalance, rad) that cancel it:
    /// ±(π − arccos(m_0 R_0/(2 m R))); None if the balls are not two equal ones or too light.
    pub fn balanced_angles(&self) -> Option<[f64; 2]> {
        if self.balls.len() != 2 {
            return None;
        }
        let (a, b) = (&self.balls[0], &self.balls[1]);
        let s = a.mass * a.radius;
        if ((b.mass * b.radius) - s).abs() > 1e-12 * s {
            return None;
        }
        let c = self.imbalance_mass * self.imbalance_radius / (2.0 * s);
        if c > 1.0 {
            return None;
        }
        let x = PI - c.acos();
        Some([x, -x])
    }

    /// Largest imbalance the balls can cancel, Σ m_i R_i, kg·m.
    pub fn capacity(&self) -> f64 {
        // + 0.0: an empty sum is −0.0, which would print as "-0".
        self.balls.iter().map(|b| b.mass * b.radius).sum::<f64>() + 0.0
    }

    /// Whether some placement of the balls cancels the imbalance: their vectors m_i R_i and
    /// m_0 R_0 close a polygon, i.e. m_0 R_0 lies between the largest m_i R_i less the others and
    /// their sum (two balls: |m_1 R_1 − m_2 R_2| ≤ m_0 R_0 ≤ m_1 R_1 + m_2 R_2). No balls cancel
    /// nothing.
    pub fn balls_can_cancel(&self) -> bool {
        let s = self.capacity();
        let largest = self.balls.iter().map(|b| b.mass * b.radius).fold(0.0, f64::max);
        let m0r0 = self.imbalance_mass * self.imbalance_radius;
        let slack = 1e-12 * s;
        !self.balls.is_empty() && m0r0 <= s + slack && 2.0 * largest - s <= m0r0 + slack
    }
}

/// How the disc speed varies.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum SpeedProfile {
    /// Constant speed, rad/s.
    Constant {
        /// Speed, rad/s.
        speed: f64,
    },
    /// From rest to `speed` linearly in `ramp_time` s, then constant.
    Ramp {
        /// Final speed, rad/s.
        speed: f64,
        /// Ramp duration, s.
        ramp_time: f64,
    },
}

impl SpeedProfile {
    /// (θ, ω, ω̇) at time t.
    pub fn at(&self, t: f64) -> (f64, f64, f64) {
        match *self {
            SpeedProfile::Constant { speed } => (speed * t, speed, 0.0),
            SpeedProfile::Ramp { speed, ramp_time } => {
                if t <= ramp_time {
                    let a = speed / ramp_time;
                    (0.5 * a * t * t, a * t, a)
                } else {
                    (speed * (t - 0.5 * ramp_time), speed, 0.0)
                }
            }
        }
    }
    /// The final speed.
    pub fn final_speed(&self) -> f64 {
        match *self {
            SpeedProfile::Constant { speed } | SpeedProfile::Ramp { speed, .. } => speed,
        }
    }
}

/// Options of [`simulate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimOptions {
    /// Disc speed.
    pub profile: SpeedProfile,
    /// Simulated time, s.
    pub duration: f64,
    /// Include the balls (false: the same grinder without its balls).
    pub with_balls: bool,
    /// Cutting (None: idle).
    pub cutting: Option<Cutting>,
    /// Record the whole history every `record_dt` s (None: only the final window).
    pub record_dt: Option<f64>,
    /// Revolutions at the end over which the steady values are taken.
    pub window_revolutions: usize,
    /// Integrator tolerances (atol in rad and rad/s).
    pub ode: Dopri5Options,
}

impl SimOptions {
    /// Constant speed `w` for `duration` s, idle, with the balls; 10 revolutions window.
    pub fn constant(w: f64, duration: f64) -> SimOptions {
        SimOptions {
            profile: SpeedProfile::Constant { speed: w },
            duration,
            with_balls: true,
            cutting: None,
            record_dt: None,
            window_revolutions: 10,
            ode: Dopri5Options {
                rtol: 1e-8,
                atol: 1e-12,
                ..Dopri5Options::default()
            },
        }
    }
}

/// Steady values at the end of a simulation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteadyEnd {
    /// Vibration amplitude of the disc centre l·(φ_max − φ_min)/2 over the final window, m.
    pub amplitude: f64,
    /// Mean displacement of the disc centre l·φ over the final window, m.
    pub mean_displacement: f64,
    /// Ball angles relative to the imbalance at the end, degrees in (−180, 180].
    pub ball_angles_deg: Vec<f64>,
    /// Largest |mean drift| of a ball relative to the disc over the final window, deg/s.
    pub drift_deg_s: f64,
    /// |Σ_{0..n} m_i R_i e^{iα_i}| / (m_0 R_0) at the end: 0 when balanced, 1 without balls.
    pub residual: f64,
}

/// A simulated history.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Simulation {
    /// Sample times, s (the recorded history, or the final window).
    pub t: Vec<f64>,
    /// Disc centre displacement l·φ, m.
    pub x: Vec<f64>,
    /// Ball angles relative to the imbalance, rad (unwrapped), one vector per ball.
    pub ball_angles: Vec<Vec<f64>>,
    /// Disc speed, rad/s.
    pub speed: Vec<f64>,
    /// Steady values over the final window.
    pub end: SteadyEnd,
    /// Right-hand-side evaluations.
    pub rhs_evals: usize,
}

/// Checks the options of [`simulate`]; returns the length of the final window, s.
fn check_options(g: &Grinder, o: &SimOptions) -> Result<f64> {
    g.validate()?;
    check(
        "duration",
        o.duration,
        o.duration > 0.0 && o.duration <= 1000.0,
        "in (0, 1000] s",
    )?;
    match o.profile {
        SpeedProfile::Constant { speed } => check("speed", speed, speed > 0.0, "> 0 rad/s")?,
        SpeedProfile::Ramp { speed, ramp_time } => {
            check("speed", speed, speed > 0.0, "> 0 rad/s")?;
            check(
                "ramp_time",
                ramp_time,
                ramp_time > 0.0 && ramp_time < o.duration,
                "> 0 and shorter than the duration",
            )?;
        }
    }
    if let Some(c) = &o.cutting {
        check(
            "cutting surface_stiffness",
            c.surface_stiffness,
            c.surface_stiffness >= 0.0,
            "≥ 0 N/m",
        )?;
        check("cutting friction", c.friction, c.friction >= 0.0, "≥ 0")?;
        check("cutting contact_angle", c.contact_angle, true, "finite")?;
        check("cutting moment", c.moment, true, "finite")?;
        if !(g.effective_stiffness(Some(c)) > 0.0) {
            return Err(Error::param(
                "cutting",
                "autobalancer: the hinge stiffness while cutting c' is not positive",
            ));
        }
    }
    if o.window_revolutions == 0 || o.window_revolutions > 10_000 {
        return Err(Error::param(
            "window_revolutions",
            format!(
                "autobalancer: window_revolutions must be 1–10000, got {}",
                o.window_revolutions
            ),
        ));
    }
    let window = o.window_revolutions as f64 * TAU / o.profile.final_speed();
    if window >= o.duration {
        return Err(Error::param(
            "duration",
            format!(
                "autobalancer: the duration {} s is shorter than the final {} revolutions ({window:.3} s)",
                o.duration, o.window_revolutions
            ),
        ));
    }
    if let Some(dt) = o.record_dt {
        check(
            "record_dt",
            dt,
            dt > 0.0 && o.duration / dt <= 2e6,
            "> 0 and at most 2e6 samples",
        )?;
    }
    Ok(window)
}

/// The output times: the recorded history (every `record_dt` before the final window) and the
/// final window (64 samples per revolution), with the index where the window starts.
fn output_times(o: &SimOptions, window: f64) -> (Vec<f64>, usize) {
    let t_win = o.duration - window;
    let n_win = 64 * o.window_revolutions;
    let mut outs: Vec<f64> = match o.record_dt {
        Some(dt) => {
            let m = (o.duration / dt).floor() as usize;
            (0..=m).map(|i| i as f64 * dt).filter(|t| *t < t_win).collect()
        }
        None => Vec::new(),
    };
    let first_win = outs.len();
    outs.extend((0..=n_win).map(|i| t_win + window * i as f64 / n_win as f64));
    (outs, first_win)
}

/// Simulates the nonlinear model (seed's equations; see the module documentation).
///
/// Starts with the rocker at rest (φ = φ̇ = 0) and the balls at their initial angles, moving with
/// the disc (α̇ = 0). Errors: invalid data or options, integrator failure.
pub fn simulate(g: &Grinder, o: &SimOptions) -> Result<Simulation> {
    let window = check_options(g, o)?;
    let balls: Vec<Ball> = if o.with_balls { g.balls.clone() } else { Vec::new() };
    let n = balls.len();
    let l = g.arm;
    let j = g.inertia_without_balls()
        + balls
            .iter()
            .map(|b| b.mass * (l * l + b.radius * b.radius))
            .sum::<f64>();
    let k = g.effective_stiffness(o.cutting.as_ref()) * l * l;
    let mu = g.damping * l * l;
    let m_ext = o.cutting.map(|c| c.moment).unwrap_or(0.0);
    let (m0r0, a0) = (g.imbalance_mass * g.imbalance_radius, g.imbalance_angle);
    let m0r0sq = m0r0 * g.imbalance_radius;
    let profile = o.profile;
    let jd = g.disc_inertia;
    let rhs = |t: f64, y: &[f64], dy: &mut [f64]| {
        let (phi, dphi) = (y[0], y[1]);
        let (th, om, omd) = profile.at(t);
        let p0 = th + a0;
        let (s0, c0) = p0.sin_cos();
        let mut a00 = j + 2.0 * l * m0r0 * c0;
        let mut f0 = l * m0r0 * om * om * s0 + 2.0 * l * dphi * m0r0 * om * s0 - mu * dphi - k * phi + m_ext;
        let mut coef_omd = jd + m0r0sq + l * m0r0 * c0;
        let (mut corr, mut den) = (0.0, 0.0);
        for (i, b) in balls.iter().enumerate() {
            let psi = th + y[2 + i];
            let dpsi = om + y[2 + n + i];
            let (s, c) = psi.sin_cos();
            let mr = b.mass * b.radius;
            a00 += 2.0 * l * mr * c;
            f0 += l * mr * dpsi * dpsi * s + 2.0 * l * dphi * mr * dpsi * s;
            let bi = mr * b.radius;
            let a = bi + l * mr * c;
            let f = -bi * omd - l * mr * dphi * dphi * s - b.drag * b.radius * b.radius * y[2 + n + i];
            coef_omd += a;
            corr += a * f / bi;
            den += a * a / bi;
        }
        let ddphi = (f0 - coef_omd * omd - corr) / (a00 - den);
        dy[0] = dphi;
        dy[1] = ddphi;
        for (i, b) in balls.iter().enumerate() {
            let psi = th + y[2 + i];
            let c = psi.cos();
            let mr = b.mass * b.radius;
            let bi = mr * b.radius;
            let a = bi + l * mr * c;
            let f = -bi * omd - l * mr * dphi * dphi * psi.sin() - b.drag * b.radius * b.radius * y[2 + n + i];
            dy[2 + i] = y[2 + n + i];
            dy[2 + n + i] = (f - a * ddphi) / bi;
        }
    };
    let mut y0 = vec![0.0; 2 + 2 * n];
    for (i, b) in balls.iter().enumerate() {
        y0[2 + i] = b.initial_angle;
    }
    let (outs, first_win) = output_times(o, window);
    let bps: Vec<f64> = match o.profile {
        SpeedProfile::Ramp { ramp_time, .. } => vec![ramp_time],
        _ => vec![],
    };
    let sol = integrate(rhs, 0.0, &y0, &outs, &bps, &o.ode).map_err(|e| simulation_error(e, o))?;
    let rec = if o.record_dt.is_some() { 0 } else { first_win };
    let t: Vec<f64> = outs[rec..].to_vec();
    let x: Vec<f64> = sol.y[rec..].iter().map(|y| l * y[0]).collect();
    let ball_angles: Vec<Vec<f64>> = (0..n)
        .map(|i| sol.y[rec..].iter().map(|y| y[2 + i] - a0).collect())
        .collect();
    let speed: Vec<f64> = t.iter().map(|tt| o.profile.at(*tt).1).collect();
    Ok(Simulation {
        t,
        x,
        ball_angles,
        speed,
        end: steady_end(g, &balls, &sol.y[first_win..], window),
        rhs_evals: sol.stats.rhs_evals,
    })
}

/// An integrator failure in the terms of the simulation: a step limit is the work the speeds
/// and durations ask for (or a stiff model), not a setting to change.
fn simulation_error(e: Error, o: &SimOptions) -> Error {
    match e {
        Error::Invalid {
            at: crate::error::At::Param { name },
            ..
        } if name == "max_steps" => Error::InvalidInput(format!(
            "autobalancer simulation: more than {} integrator steps over {} s at up to {:.4e} rpm: the speed \
             and duration ask for too many revolutions, or the model is stiff (a light ball against a large \
             drag or hinge stiffness)",
            o.ode.max_steps,
            o.duration,
            o.profile.final_speed() * 60.0 / TAU
        )),
        Error::InvalidInput(m) => Error::InvalidInput(format!("autobalancer simulation: {m}")),
        Error::Invalid { at, msg } => Error::Invalid {
            at,
            msg: format!("autobalancer simulation: {msg}"),
        },
        other => other,
    }
}

/// Steady values over the final window (`win`: the states there, `window` s long).
fn steady_end(g: &Grinder, balls: &[Ball], win: &[Vec<f64>], window: f64) -> SteadyEnd {
    let (l, a0) = (g.arm, g.imbalance_angle);
    let m0r0 = g.imbalance_mass * g.imbalance_radius;
    let (lo, hi) = win.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
        (a.min(y[0]), b.max(y[0]))
    });
    let mean = win.iter().map(|y| y[0]).sum::<f64>() / win.len() as f64;
    let last = &win[win.len() - 1];
    let first = &win[0];
    let (mut sx, mut sy) = (m0r0 * a0.cos(), m0r0 * a0.sin());
    let mut drift = 0.0f64;
    let mut angles = Vec::with_capacity(balls.len());
    for (i, b) in balls.iter().enumerate() {
        let a = last[2 + i];
        sx += b.mass * b.radius * a.cos();
        sy += b.mass * b.radius * a.sin();
        drift = drift.max(((last[2 + i] - first[2 + i]) / window).abs().to_degrees());
        angles.push(wrap_deg((a - a0).to_degrees()));
    }
    SteadyEnd {
        amplitude: 0.5 * l * (hi - lo),
        mean_displacement: l * mean,
        ball_angles_deg: angles,
        drift_deg_s: drift,
        residual: (sx * sx + sy * sy).sqrt() / m0r0,
    }
}

/// One speed of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SweepRow {
    /// Disc speed, rad/s.
    pub speed: f64,
    /// Disc speed, rpm.
    pub speed_rpm: f64,
    /// ω/ω_0.
    pub ratio: f64,
    /// Housing (disc centre) vibration amplitude with the balls, m.
    pub amplitude_with_balls: f64,
    /// The same without the balls, m.
    pub amplitude_without_balls: f64,
    /// Ball angles relative to the imbalance at the end, degrees.
    pub ball_angles_deg: Vec<f64>,
    /// Residual imbalance / disc imbalance at the end.
    pub residual: f64,
    /// Largest ball drift relative to the disc at the end, deg/s.
    pub drift_deg_s: f64,
    /// Balanced: residual below [`BALANCED_RESIDUAL`].
    pub balanced: bool,
    /// The linear criterion's sign: N < 0 (ω > ω_0) predicts balancing.
    pub predicted: bool,
}

/// A speed counts as balanced when the residual imbalance at the end of the simulation is below
/// this fraction of the disc's imbalance.
pub const BALANCED_RESIDUAL: f64 = 0.05;

/// Runs the model with and without balls at each speed (constant, `duration` s each, from the
/// balls' initial angles) and reports the steady values. Speeds in rad/s. Runs in parallel.
pub fn sweep(g: &Grinder, speeds: &[f64], duration: f64, cutting: Option<Cutting>) -> Result<Vec<SweepRow>> {
    use rayon::prelude::*;
    g.validate()?;
    if speeds.is_empty() || speeds.len() > 2000 {
        return Err(Error::param(
            "speeds",
            format!("autobalancer sweep: 1–2000 speeds, got {}", speeds.len()),
        ));
    }
    let w0 = g.omega0(cutting.as_ref());
    speeds
        .par_iter()
        .map(|&w| {
            let mut o = SimOptions::constant(w, duration);
            o.cutting = cutting;
            let with = simulate(g, &o)?;
            o.with_balls = false;
            let without = simulate(g, &o)?;
            Ok(SweepRow {
                speed: w,
                speed_rpm: w * 60.0 / TAU,
                ratio: w / w0,
                amplitude_with_balls: with.end.amplitude,
                amplitude_without_balls: without.end.amplitude,
                ball_angles_deg: with.end.ball_angles_deg.clone(),
                residual: with.end.residual,
                drift_deg_s: with.end.drift_deg_s,
                balanced: with.end.residual < BALANCED_RESIDUAL,
                predicted: w > w0 && g.balls_can_cancel(),
            })
        })
        .collect()
}

/// The balancing threshold seen in a sweep (rows in ascending speed): the highest unbalanced speed
/// below the lowest speed from which every faster row is balanced, and that lowest speed (rad/s).
/// None when no row, or every row, is balanced.
pub fn threshold(rows: &[SweepRow]) -> Option<(f64, f64)> {
    let k = rows.iter().rposition(|r| !r.balanced)?;
    let above = rows.get(k + 1)?;
    Some((rows[k].speed, above.speed))
}

/// One surface stiffness of a cutting scan.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CuttingRow {
    /// c_r as a fraction of the bound [`Grinder::cr_bound`] at the operating speed.
    pub fraction_of_bound: f64,
    /// c_r, N/m.
    pub surface_stiffness: f64,
    /// ω/ω_0' (ω_0' while cutting).
    pub ratio: f64,
    /// Vibration amplitude with the balls, m.
    pub amplitude_with_balls: f64,
    /// Residual imbalance / disc imbalance at the end.
    pub residual: f64,
    /// Largest ball drift relative to the disc at the end, deg/s.
    pub drift_deg_s: f64,
    /// Balanced: residual below [`BALANCED_RESIDUAL`].
    pub balanced: bool,
}

/// The nonlinear model at the operating speed while cutting with c_r = `fractions` × the bound
/// (the other cutting data from `cut`), `duration` s each, from the balls' initial angles.
pub fn cutting_scan(g: &Grinder, cut: &Cutting, fractions: &[f64], duration: f64) -> Result<Vec<CuttingRow>> {
    use rayon::prelude::*;
    g.validate()?;
    let bound = g.cr_bound(g.speed, cut);
    if !(bound.is_finite() && bound > 0.0) {
        return Err(Error::param(
            "cut",
            format!("autobalancer: no positive surface-stiffness bound at the operating speed (bound {bound})"),
        ));
    }
    fractions
        .par_iter()
        .map(|&f| {
            check("a fraction of the bound", f, f >= 0.0, "≥ 0")?;
            let c = Cutting {
                surface_stiffness: f * bound,
                ..*cut
            };
            let mut o = SimOptions::constant(g.speed, duration);
            o.cutting = Some(c);
            let s = simulate(g, &o)?;
            Ok(CuttingRow {
                fraction_of_bound: f,
                surface_stiffness: c.surface_stiffness,
                ratio: g.speed / g.omega0(Some(&c)),
                amplitude_with_balls: s.end.amplitude,
                residual: s.end.residual,
                drift_deg_s: s.end.drift_deg_s,
                balanced: s.end.residual < BALANCED_RESIDUAL,
            })
        })
        .collect()
}

/// N = ω²(ω_0² − ω²)/[(ω_0² − ω²)² + 4h̃²ω²].
pub fn n_factor(w: f64, w0: f64, h_tilde: f64) -> f64 {
    let d = w0 * w0 - w * w;
    w * w * d / (d * d + 4.0 * h_tilde * h_tilde * w * w)
}

/// First-order mean projection ⟨z sin ωt⟩ = ε N/2 of the linear periodic equation (multiply by l
/// for the disc centre's displacement).
pub fn mean_projection(w: f64, w0: f64, h_tilde: f64, eps: f64) -> f64 {
    eps * n_factor(w, w0, h_tilde) / 2.0
}

/// ⟨z sin ωt⟩ of the steady solution of
///
/// ```text
/// z̈ (1 + 2ε cos ωt) + 2ż (h̃ − εω sin ωt) + ω_0² z = ω² ε sin ωt
/// ```
///
/// by integration: from rest until the transient has decayed by e^{−30} (t = 30/h̃, rounded up
/// to whole periods), then the mean over `periods` periods from an extra state q̇ = z sin ωt.
pub fn mean_projection_numeric(w: f64, w0: f64, h_tilde: f64, eps: f64, periods: usize) -> Result<f64> {
    for (n, v) in [("ω", w), ("ω_0", w0), ("h̃", h_tilde)] {
        check(n, v, v > 0.0, "> 0")?;
    }
    check("ε", eps, eps.abs() < 0.25, "|ε| < 0.25")?;
    if periods == 0 || periods > 100_000 {
        return Err(Error::param("periods", "mean projection: periods must be 1–100000"));
    }
    let tp = TAU / w;
    let settle = (30.0 / h_tilde / tp).ceil() * tp;
    let t_end = settle + periods as f64 * tp;
    let rhs = |t: f64, y: &[f64], dy: &mut [f64]| {
        let (s, c) = (w * t).sin_cos();
        let (z, zd) = (y[0], y[1]);
        dy[0] = zd;
        dy[1] = (w * w * eps * s - w0 * w0 * z - 2.0 * zd * (h_tilde - eps * w * s)) / (1.0 + 2.0 * eps * c);
        dy[2] = z * s;
    };
    let opts = Dopri5Options {
        rtol: 1e-11,
        atol: 1e-14,
        ..Dopri5Options::default()
    };
    let sol = integrate(rhs, 0.0, &[0.0, 0.0, 0.0], &[settle, t_end], &[], &opts)?;
    Ok((sol.y[1][2] - sol.y[0][2]) / (t_end - settle))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap() {
        assert_eq!(wrap_deg(190.0), -170.0);
        assert_eq!(wrap_deg(-180.0), 180.0);
        assert_eq!(wrap_deg(45.0), 45.0);
    }
}

/// Closed-form figures of the grinder.
#[derive(Debug, Clone, serde::Serialize)]
pub struct AutobalancerFigures {
    /// J with the balls, kg·m².
    pub inertia: f64,
    /// ω_0 at idle, rad/s.
    pub omega0: f64,
    /// ω_0 at idle, rpm.
    pub omega0_rpm: f64,
    /// ω_0 while cutting, rad/s.
    pub omega0_cutting: Option<f64>,
    /// h̃, 1/s.
    pub h_tilde: f64,
    /// ε = l m_0 R_0/J.
    pub epsilon: f64,
    /// Operating speed, rad/s.
    pub speed: f64,
    /// Operating speed, rpm.
    pub speed_rpm: f64,
    /// ω/ω_0 at idle.
    pub ratio: f64,
    /// N at the operating speed.
    pub n_factor: f64,
    /// First-order mean projection of the disc centre on the imbalance l ε N/2 (balls fixed), m.
    pub mean_projection: f64,
    /// Whether the balls can cancel the imbalance at all ([`Grinder::balls_can_cancel`]).
    pub balls_can_cancel: bool,
    /// Linear criterion at idle: ω > ω_0, and balls that can cancel the imbalance.
    pub balances_idle: bool,
    /// Linear criterion while cutting: ω > ω_0 (cutting), and balls that can cancel it.
    pub balances_cutting: Option<bool>,
    /// c_r bound at the file's contact angle, N/m.
    pub cr_bound: Option<f64>,
    /// The seed's closed-form c_r bound (worst contact angle), N/m.
    pub cr_bound_paper: Option<f64>,
    /// Ball capacity Σ m_i R_i / (m_0 R_0).
    pub capacity_ratio: f64,
    /// Balanced ball angles relative to the imbalance (two equal balls), degrees.
    pub balanced_angles_deg: Option<[f64; 2]>,
}
