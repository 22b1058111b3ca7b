//! The autobalancer case: a TOML file (`[machine] kind = "autobalancer"`) or the built-in
//! grinder, every value checked before any work (errors name the file, the line and the key).
//! The speeds and durations are bounded so that no simulation integrates more than
//! [`MAX_REVOLUTIONS`] disc revolutions.

// `!(x > 0.0)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::f64::consts::TAU;
use std::path::Path;

use serde::Deserialize;

use super::model::{Ball, Cutting, Grinder};
use crate::app::machines::case_file::{Checks, Source};
use crate::{Error, Result};

/// The built-in autobalancer file (a plausible 125 mm grinder).
pub const AUTOBALANCER_DEFAULT_TOML: &str = include_str!("../../../../scenes/machines/grinder_autobalancer.toml");
/// Its name in messages.
pub const AUTOBALANCER_DEFAULT_NAME: &str = "scenes/machines/grinder_autobalancer.toml (built in)";

/// Most disc revolutions one simulation of a case may integrate (the built-in grinder needs
/// about 900): speeds and durations beyond ask for hours of work.
pub const MAX_REVOLUTIONS: f64 = 20_000.0;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHeader {
    #[allow(dead_code)]
    version: i64,
    #[allow(dead_code)]
    kind: String,
    name: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAb {
    machine: RawHeader,
    rocker: RawRocker,
    disc: RawDisc,
    #[serde(default)]
    ball: Vec<RawBall>,
    cutting: Option<RawCutting>,
    #[serde(default)]
    sweep: RawSweep,
    #[serde(default)]
    runup: RawRunup,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRocker {
    arm: f64,
    inertia: f64,
    stiffness: Option<f64>,
    natural_frequency_hz: Option<f64>,
    damping: Option<f64>,
    damping_ratio: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDisc {
    mass: f64,
    inertia: f64,
    radius: f64,
    speed_rpm: f64,
    imbalance_mass: f64,
    imbalance_radius: f64,
    imbalance_angle_deg: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBall {
    mass: f64,
    radius: f64,
    drag: f64,
    initial_angle_deg: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCutting {
    surface_stiffness: f64,
    friction: f64,
    contact_angle_deg: f64,
    moment: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawSweep {
    from_ratio: Option<f64>,
    to_ratio: Option<f64>,
    points: Option<i64>,
    duration: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawRunup {
    ramp_time: Option<f64>,
    duration: Option<f64>,
    dt: Option<f64>,
}

/// Speed sweep settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SweepSettings {
    /// Lowest ω/ω_0.
    pub from_ratio: f64,
    /// Highest ω/ω_0.
    pub to_ratio: f64,
    /// Number of speeds.
    pub points: usize,
    /// Simulated time per speed, s.
    pub duration: f64,
}

impl SweepSettings {
    /// The speeds (rad/s) for a rocker frequency `w0`.
    pub fn speeds(&self, w0: f64) -> Vec<f64> {
        let n = self.points;
        (0..n)
            .map(|k| {
                let r = if n == 1 {
                    self.from_ratio
                } else {
                    self.from_ratio + (self.to_ratio - self.from_ratio) * k as f64 / (n - 1) as f64
                };
                r * w0
            })
            .collect()
    }
}

/// Run-up settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RunupSettings {
    /// Ramp from rest to the operating speed, s.
    pub ramp_time: f64,
    /// Simulated time, s.
    pub duration: f64,
    /// Recording step, s.
    pub dt: f64,
}

/// An autobalancer input file.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AutobalancerCase {
    /// File (or built-in name).
    pub file: String,
    /// Name of the machine.
    pub name: String,
    /// The grinder.
    pub grinder: Grinder,
    /// Cutting, if given.
    pub cutting: Option<Cutting>,
    /// Speed sweep.
    pub sweep: SweepSettings,
    /// Run-up.
    pub runup: RunupSettings,
}

impl AutobalancerCase {
    /// The built-in case: [`Grinder::plausible`] with [`Grinder::plausible_cutting`].
    pub fn builtin() -> Result<AutobalancerCase> {
        AutobalancerCase::parse(AUTOBALANCER_DEFAULT_NAME, AUTOBALANCER_DEFAULT_TOML)
    }

    /// Reads an autobalancer file.
    pub fn from_toml(path: &Path) -> Result<AutobalancerCase> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        AutobalancerCase::parse(&path.display().to_string(), &text)
    }

    /// Parses autobalancer TOML; `file` names it in messages.
    pub fn parse(file: &str, text: &str) -> Result<AutobalancerCase> {
        let src = Source::new(file, text);
        let raw: RawAb = src.parse("autobalancer")?;
        let g = grinder(&src, &raw)?;
        let cutting = raw.cutting.as_ref().map(|c| cutting(&src, &g, c)).transpose()?;
        let sweep = sweep_settings(&src, &raw.sweep, &g)?;
        let runup = runup_settings(&src, &raw.runup, &g)?;
        Ok(AutobalancerCase {
            file: file.to_string(),
            name: raw.machine.name.clone().unwrap_or_else(|| "autobalancer".into()),
            grinder: g,
            cutting,
            sweep,
            runup,
        })
    }
}

/// `[[ball]]` tables.
fn balls(src: &Source, raw: &[RawBall]) -> Result<Vec<Ball>> {
    if raw.len() > 16 {
        return Err(src.err("ball", Some(16), "mass", "at most 16 balls"));
    }
    raw.iter()
        .enumerate()
        .map(|(k, b)| {
            let c = Checks::item(src, "ball", k);
            Ok(Ball {
                mass: c.pos("mass", b.mass)?,
                radius: c.pos("radius", b.radius)?,
                drag: c.nonneg("drag", b.drag)?,
                initial_angle: c.finite("initial_angle_deg", b.initial_angle_deg)?.to_radians(),
            })
        })
        .collect()
}

/// `[rocker]`, `[disc]` and the balls: the grinder, with its masses within what double
/// precision carries through the model (the balls' share of the inertia, the imbalance sums).
fn grinder(src: &Source, raw: &RawAb) -> Result<Grinder> {
    let (r, dd) = (&raw.rocker, &raw.disc);
    let cr = Checks::table(src, "rocker");
    let cd = Checks::table(src, "disc");
    let balls = balls(src, &raw.ball)?;
    let mut g = Grinder {
        arm: cr.pos("arm", r.arm)?,
        stiffness: 1.0,
        damping: 0.0,
        rocker_inertia: cr.nonneg("inertia", r.inertia)?,
        disc_mass: cd.nonneg("mass", dd.mass)?,
        disc_inertia: cd.nonneg("inertia", dd.inertia)?,
        disc_radius: cd.pos("radius", dd.radius)?,
        imbalance_mass: cd.pos("imbalance_mass", dd.imbalance_mass)?,
        imbalance_radius: cd.pos("imbalance_radius", dd.imbalance_radius)?,
        imbalance_angle: cd
            .finite("imbalance_angle_deg", dd.imbalance_angle_deg.unwrap_or(0.0))?
            .to_radians(),
        speed: cd.pos("speed_rpm", dd.speed_rpm)? * TAU / 60.0,
        balls,
    };
    match (r.stiffness, r.natural_frequency_hz) {
        (Some(c), None) => g.stiffness = cr.pos("stiffness", c)?,
        (None, Some(f)) => g.set_hinge_stiffness(cr.pos("natural_frequency_hz", f)?),
        (Some(_), Some(_)) => {
            return Err(cr.err(
                "natural_frequency_hz",
                "give either stiffness or natural_frequency_hz, not both",
            ));
        }
        (None, None) => return Err(cr.err("stiffness", "missing (or give natural_frequency_hz)")),
    }
    match (r.damping, r.damping_ratio) {
        (Some(h), None) => g.damping = cr.nonneg("damping", h)?,
        (None, Some(z)) => g.set_hinge_damping_ratio(cr.nonneg("damping_ratio", z)?),
        (Some(_), Some(_)) => {
            return Err(cr.err("damping_ratio", "give either damping or damping_ratio, not both"));
        }
        (None, None) => return Err(cr.err("damping", "missing (or give damping_ratio)")),
    }
    // A frequency or a damping ratio sets the hinge's stiffness or damping: one beyond any
    // grinder is named by the key the file gave. Checked before the model's own validation,
    // which knows only the stiffness.
    let keys = [
        if r.natural_frequency_hz.is_some() {
            "natural_frequency_hz"
        } else {
            "stiffness"
        },
        if r.damping_ratio.is_some() {
            "damping_ratio"
        } else {
            "damping"
        },
    ];
    check_scales(src, &g, keys)?;
    g.validate().map_err(|e| src.whole(e))?;
    Ok(g)
}

/// Largest magnitude of a mass, length, inertia, stiffness or damping of the grinder (SI):
/// far beyond any grinder, and small enough that the model's products (the residual imbalance
/// squares m R) stay finite.
pub const MAX_MAGNITUDE: f64 = 1e12;

/// The model's figures must be finite and its masses must not drown each other: a ball or an
/// imbalance of 1e300 kg makes the inertia, ω_0 or the residual overflow or lose every digit.
/// The hinge's stiffness and damping are named by the keys that set them (`stiffness` or
/// `natural_frequency_hz`, `damping` or `damping_ratio`).
fn check_scales(src: &Source, g: &Grinder, [stiffness_key, damping_key]: [&str; 2]) -> Result<()> {
    let big = |table: &str, index: Option<usize>, key: &str, v: f64| -> Result<()> {
        if v.abs() <= MAX_MAGNITUDE {
            Ok(())
        } else {
            Err(src.err(
                table,
                index,
                key,
                format!(
                    "{} beyond any grinder (at most {MAX_MAGNITUDE:e} in SI units): check the units",
                    match key {
                        "natural_frequency_hz" => format!("gives a hinge stiffness of {v:e} N/m,"),
                        "damping_ratio" => format!("gives a hinge damping of {v:e} N·s/m,"),
                        _ => format!("{v:e} is"),
                    }
                ),
            ))
        }
    };
    for (key, v) in [
        ("mass", g.disc_mass),
        ("inertia", g.disc_inertia),
        ("radius", g.disc_radius),
        ("imbalance_mass", g.imbalance_mass),
        ("imbalance_radius", g.imbalance_radius),
    ] {
        big("disc", None, key, v)?;
    }
    for (k, b) in g.balls.iter().enumerate() {
        for (key, v) in [("mass", b.mass), ("radius", b.radius), ("drag", b.drag)] {
            big("ball", Some(k), key, v)?;
        }
    }
    // The hinge's stiffness and damping may come from a frequency and a damping ratio: checked
    // after the masses they follow from.
    for (key, v) in [
        ("arm", g.arm),
        ("inertia", g.rocker_inertia),
        (stiffness_key, g.stiffness),
        (damping_key, g.damping),
    ] {
        big("rocker", None, key, v)?;
    }
    let j = g.inertia();
    let m0r0 = g.imbalance_mass * g.imbalance_radius;
    let figures = [
        j,
        g.omega0(None),
        g.h_tilde(),
        g.epsilon(),
        g.capacity() / m0r0,
        g.stiffness * g.arm * g.arm,
    ];
    if figures.iter().any(|v| !(v.is_finite() && *v >= 0.0)) || !(g.omega0(None) > 0.0) {
        return Err(src.whole(format!(
            "the masses, lengths and stiffness give non-finite or zero figures (J = {j:e} kg·m², ω_0 = {:e} rad/s): \
             check their units",
            g.omega0(None)
        )));
    }
    for (k, b) in g.balls.iter().enumerate() {
        let ratio = b.mass * b.radius / m0r0;
        if !(1e-6..=1e6).contains(&ratio) {
            return Err(src.err(
                "ball",
                Some(k),
                "mass",
                format!(
                    "{} kg at {} m is {ratio:e} × the disc imbalance m_0 R_0: outside [1e-6, 1e6] (check the units)",
                    b.mass, b.radius
                ),
            ));
        }
    }
    Ok(())
}

/// Largest static rocker angle of the cutting moment, rad (5.7°; sin φ and φ then differ by
/// 0.17 %).
pub const MAX_STATIC_TURN: f64 = 0.1;

/// `[cutting]`.
fn cutting(src: &Source, g: &Grinder, c: &RawCutting) -> Result<Cutting> {
    let ch = Checks::table(src, "cutting");
    let cut = Cutting {
        surface_stiffness: ch.nonneg("surface_stiffness", c.surface_stiffness)?,
        friction: ch.nonneg("friction", c.friction)?,
        contact_angle: ch
            .test(
                "contact_angle_deg",
                c.contact_angle_deg,
                (0.0..=180.0).contains(&c.contact_angle_deg),
                "in [0, 180] degrees",
            )?
            .to_radians(),
        moment: ch.finite("moment", c.moment.unwrap_or(0.0))?,
    };
    if !(g.effective_stiffness(Some(&cut)) > 0.0) {
        return Err(ch.err(
            "surface_stiffness",
            "makes the hinge stiffness while cutting non-positive",
        ));
    }
    // The rocker's equations are those of small angles: the moment's static turn must be one.
    let turn = cut.moment / (g.effective_stiffness(Some(&cut)) * g.arm * g.arm);
    if turn.abs() > MAX_STATIC_TURN {
        return Err(ch.err(
            "moment",
            format!(
                "turns the rocker by {} rad statically against the hinge (c' l²): the model holds for small \
                 angles, at most {MAX_STATIC_TURN} rad (check the units)",
                crate::io::fmt_short(turn, 3)
            ),
        ));
    }
    Ok(cut)
}

/// Refuses a simulation of `duration` s at up to `speed` rad/s that turns the disc more than
/// [`MAX_REVOLUTIONS`] times, naming `key` of `table`.
fn check_revolutions(c: &Checks, key: &str, speed: f64, duration: f64, what: &str) -> Result<()> {
    let revs = speed * duration / TAU;
    if revs > MAX_REVOLUTIONS {
        return Err(c.err(
            key,
            format!(
                "{what} turns the disc {revs:.3e} times at {:.4e} rpm for {duration} s (at most {MAX_REVOLUTIONS:.0e}): \
                 lower the speed or the duration",
                speed * 60.0 / TAU
            ),
        ));
    }
    Ok(())
}

/// `[sweep]`.
fn sweep_settings(src: &Source, s: &RawSweep, g: &Grinder) -> Result<SweepSettings> {
    let cs = Checks::table(src, "sweep");
    let from = cs.pos("from_ratio", s.from_ratio.unwrap_or(0.45))?;
    let to = cs.test(
        "to_ratio",
        s.to_ratio.unwrap_or(3.05),
        s.to_ratio.unwrap_or(3.05) > from,
        "above from_ratio",
    )?;
    let points = s.points.unwrap_or(27);
    if !(2..=2000).contains(&points) {
        return Err(cs.err("points", format!("must be 2–2000, got {points}")));
    }
    let w0 = g.omega0(None);
    let duration = cs.test(
        "duration",
        s.duration.unwrap_or(5.0),
        s.duration.is_none_or(|v| v > 0.0 && v <= 1000.0),
        "in (0, 1000] s",
    )?;
    // The final 10 revolutions at the lowest speed must fit in the duration.
    let need = 10.0 * TAU / (from * w0);
    if duration <= 2.0 * need {
        return Err(cs.err(
            "duration",
            format!("too short: the lowest speed needs more than {:.3} s", 2.0 * need),
        ));
    }
    // The operating runs (idle, cutting) last the sweep's duration at the operating speed.
    let cd = Checks::table(src, "disc");
    check_revolutions(&cd, "speed_rpm", g.speed, duration, "the run at the operating speed")?;
    check_revolutions(&cs, "to_ratio", to * w0, duration, "the fastest speed of the sweep")?;
    Ok(SweepSettings {
        from_ratio: from,
        to_ratio: to,
        points: points as usize,
        duration,
    })
}

/// `[runup]`.
fn runup_settings(src: &Source, u: &RawRunup, g: &Grinder) -> Result<RunupSettings> {
    let cu = Checks::table(src, "runup");
    let ramp_time = cu.pos("ramp_time", u.ramp_time.unwrap_or(1.0))?;
    let rdur = cu.pos("duration", u.duration.unwrap_or(4.0))?;
    if rdur <= ramp_time + 20.0 * TAU / g.speed || rdur > 1000.0 {
        return Err(cu.err(
            "duration",
            "must exceed ramp_time by at least 20 revolutions, and be at most 1000 s",
        ));
    }
    check_revolutions(&Checks::table(src, "disc"), "speed_rpm", g.speed, rdur, "the run-up")?;
    // The vibration's amplitude is read from the samples: at least 20 a revolution at the
    // operating speed (a sinusoid's peak then within 1.3 %).
    let dt = cu.recording_step(
        u.dt,
        2e-4,
        TAU / g.speed / 20.0,
        "20 samples a revolution at the operating speed",
        rdur,
    )?;
    Ok(RunupSettings {
        ramp_time,
        duration: rdur,
        dt,
    })
}
