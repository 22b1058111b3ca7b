//! The crank-drive case: a TOML file (`[machine] kind = "crank-drive"`) or the built-in paper
//! drive, every value checked before any work (errors name the file, the line and the key).

// `!(x > 0.0)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::f64::consts::TAU;
use std::path::Path;

use serde::Deserialize;

use super::model::{CrankDrive, MAX_STEADY_STEPS, Mechanism, Motor, MotorLaw, PaperRow, Reducer};
use crate::app::machines::case_file::{Checks, Source};
use crate::{Error, Result};

/// The built-in crank-drive file (the paper's two-cart drive and Table 1 setups).
pub const CRANK_DEFAULT_TOML: &str = include_str!("../../../../scenes/machines/crank_two_carts.toml");
/// Its name in messages.
pub const CRANK_DEFAULT_NAME: &str = "scenes/machines/crank_two_carts.toml (built in)";

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
struct RawCrank {
    machine: RawHeader,
    mechanism: RawMechanism,
    drive: RawDrive,
    motor: RawMotor,
    #[serde(default)]
    run: RawRun,
    #[serde(default)]
    startup: RawStartup,
    #[serde(default)]
    setup: Vec<RawSetup>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMechanism {
    crank_radius: f64,
    rod_length: f64,
    rod_mass_per_length: f64,
    cart_mass: f64,
    cart_resistance: f64,
    gravity: Option<f64>,
    carts: Option<i64>,
    phase_shift_deg: Option<f64>,
    phases_deg: Option<Vec<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDrive {
    ratio: f64,
    efficiency: f64,
    inertia: f64,
    design_speed: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMotor {
    law: Option<String>,
    synchronous_speed: f64,
    critical_speed: f64,
    critical_torque: f64,
    nominal_speed: Option<f64>,
    nominal_torque: Option<f64>,
    starting_torque: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawRun {
    start_speed: Option<f64>,
    start_angle_deg: Option<f64>,
    step_deg: Option<f64>,
    max_revolutions: Option<i64>,
    steady_tol: Option<f64>,
    rtol: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawStartup {
    ramp_time: Option<f64>,
    duration: Option<f64>,
    dt: Option<f64>,
    start_angle_deg: Option<f64>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawScale {
    Factor(f64),
    Rule(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSetup {
    name: String,
    carts: Option<i64>,
    phase_shift_deg: Option<f64>,
    phases_deg: Option<Vec<f64>>,
    motor_scale: Option<RawScale>,
    paper_extremes: Option<[f64; 4]>,
    paper_metrics: Option<[f64; 3]>,
}

/// How a setup's motor is sized.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MotorScale {
    /// The motor torque scaled by the ratio of mean resisting moments (setup / main drive).
    Power,
    /// A given factor on the motor torque.
    Factor(f64),
}

/// One setup of the comparison table.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Setup {
    /// Name.
    pub name: String,
    /// Crank phases, rad.
    pub phases: Vec<f64>,
    /// Motor sizing.
    pub motor_scale: MotorScale,
    /// The paper's values for it, if given (extremes and printed metrics).
    pub paper: Option<PaperRow>,
}

/// Settings of the steady-state runs.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RunSettings {
    /// Start speed, rad/s.
    pub start_speed: f64,
    /// Start angle, rad.
    pub start_angle: f64,
    /// Baranov step, rad.
    pub step: f64,
    /// Most revolutions.
    pub max_revolutions: usize,
    /// Steady tolerance.
    pub steady_tol: f64,
    /// Relative tolerance of the adaptive integrator.
    pub rtol: f64,
}

/// Settings of the runs from rest.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct StartupSettings {
    /// Frequency-converter ramp, s (None: no ramp case).
    pub ramp_time: Option<f64>,
    /// Simulated time, s.
    pub duration: f64,
    /// Output spacing, s.
    pub dt: f64,
    /// Angle at rest, rad.
    pub start_angle: f64,
}

/// A crank-drive input file.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CrankCase {
    /// File (or built-in name).
    pub file: String,
    /// Name of the machine.
    pub name: String,
    /// The drive.
    pub drive: CrankDrive,
    /// Design crank speed, rad/s.
    pub design_speed: f64,
    /// Steady-state runs.
    pub run: RunSettings,
    /// Runs from rest.
    pub startup: StartupSettings,
    /// Comparison setups.
    pub setups: Vec<Setup>,
}

fn phases(
    src: &Source,
    table: &str,
    index: Option<usize>,
    carts: Option<i64>,
    shift: Option<f64>,
    list: Option<&Vec<f64>>,
) -> Result<Vec<f64>> {
    let c = Checks { src, table, index };
    match (list, carts) {
        (Some(_), Some(_)) => Err(src.err(
            table,
            index,
            "phases_deg",
            "give either phases_deg or carts (+ phase_shift_deg), not both",
        )),
        (Some(l), None) => {
            if shift.is_some() {
                return Err(src.err(table, index, "phase_shift_deg", "not used with phases_deg"));
            }
            if l.is_empty() || l.len() > 64 {
                return Err(src.err(
                    table,
                    index,
                    "phases_deg",
                    format!("needs 1–64 phases, got {}", l.len()),
                ));
            }
            for v in l {
                c.test("phases_deg", *v, v.abs() <= 360.0, "within ±360°")?;
            }
            Ok(l.iter().map(|d| d.to_radians()).collect())
        }
        (None, Some(n)) => {
            if !(1..=64).contains(&n) {
                return Err(src.err(table, index, "carts", format!("must be 1–64, got {n}")));
            }
            let s = match shift {
                Some(s) => c.test("phase_shift_deg", s, s.abs() <= 360.0, "within ±360°")?,
                None if n == 1 => 0.0,
                None => return Err(src.err(table, index, "phase_shift_deg", "missing (needed with carts > 1)")),
            };
            Ok(Mechanism::uniform_phases(n as usize, s.to_radians()))
        }
        (None, None) => Err(src.err(table, index, "carts", "missing (give carts or phases_deg)")),
    }
}

impl CrankCase {
    /// The built-in case: the paper's two-cart drive with the four setups of Table 1.
    pub fn builtin() -> Result<CrankCase> {
        CrankCase::parse(CRANK_DEFAULT_NAME, CRANK_DEFAULT_TOML)
    }

    /// Reads a crank-drive file.
    pub fn from_toml(path: &Path) -> Result<CrankCase> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        CrankCase::parse(&path.display().to_string(), &text)
    }

    /// Parses crank-drive TOML; `file` names it in messages.
    pub fn parse(file: &str, text: &str) -> Result<CrankCase> {
        let src = Source::new(file, text);
        let raw: RawCrank = src.parse("crank-drive")?;
        let mechanism = mechanism(&src, &raw.mechanism)?;
        let (reducer, design_speed) = reducer(&src, &raw.drive)?;
        let motor = motor(&src, &raw.motor)?;
        let drive = CrankDrive {
            mechanism,
            motor,
            reducer,
            torque_scale: 1.0,
        };
        drive.validate().map_err(|e| src.whole(e))?;
        // The crank's synchronous speed: no steady state lies above it (the motor brakes there).
        let sync = drive.motor.synchronous_speed / drive.reducer.ratio;
        let run = run_settings(&src, &raw.run, design_speed, sync)?;
        let startup = startup_settings(&src, &raw.startup, sync)?;
        let setups = raw
            .setup
            .iter()
            .enumerate()
            .map(|(k, st)| setup(&src, k, st))
            .collect::<Result<Vec<_>>>()?;
        if setups.len() > 32 {
            return Err(src.err("setup", Some(32), "name", "at most 32 setups"));
        }
        // "power" scales the motor by the ratio of mean resisting moments: none without resistance.
        if let Some(k) = setups.iter().position(|s| s.motor_scale == MotorScale::Power)
            && drive.mechanism.mean_resisting_moment() <= 0.0
        {
            return Err(src.err(
                "setup",
                Some(k),
                "motor_scale",
                "\"power\" (the default) scales the motor by the ratio of mean resisting moments, and \
                 [mechanism] has none (cart_resistance = 0): give the scale as a number",
            ));
        }
        Ok(CrankCase {
            file: file.to_string(),
            name: raw.machine.name.clone().unwrap_or_else(|| "crank drive".into()),
            drive,
            design_speed,
            run,
            startup,
            setups,
        })
    }

    /// The drive of a setup: the main drive's data with the setup's cranks and motor scale.
    pub fn setup_drive(&self, s: &Setup) -> CrankDrive {
        let mut d = self.drive.clone();
        d.mechanism.phases = s.phases.clone();
        d.torque_scale = match s.motor_scale {
            MotorScale::Factor(f) => f,
            MotorScale::Power => {
                d.mechanism.mean_resisting_moment() / self.drive.mechanism.mean_resisting_moment().max(1e-300)
            }
        };
        d
    }
}

/// `[mechanism]`.
fn mechanism(src: &Source, m: &RawMechanism) -> Result<Mechanism> {
    let cm = Checks::table(src, "mechanism");
    let crank_radius = cm.test(
        "crank_radius",
        m.crank_radius,
        m.crank_radius > 0.0 && m.crank_radius <= 100.0,
        "> 0 and at most 100 m (check the units)",
    )?;
    let rod_length = cm.test(
        "rod_length",
        m.rod_length,
        m.rod_length > crank_radius,
        "longer than crank_radius",
    )?;
    Ok(Mechanism {
        crank_radius,
        rod_length,
        rod_mass_per_length: cm.nonneg("rod_mass_per_length", m.rod_mass_per_length)?,
        cart_mass: cm.nonneg("cart_mass", m.cart_mass)?,
        cart_resistance: cm.nonneg("cart_resistance", m.cart_resistance)?,
        gravity: cm.nonneg("gravity", m.gravity.unwrap_or(9.81))?,
        phases: phases(
            src,
            "mechanism",
            None,
            m.carts,
            m.phase_shift_deg,
            m.phases_deg.as_ref(),
        )?,
    })
}

/// `[drive]`: the reducer and the design speed.
fn reducer(src: &Source, d: &RawDrive) -> Result<(Reducer, f64)> {
    let cd = Checks::table(src, "drive");
    let reducer = Reducer {
        ratio: cd.pos("ratio", d.ratio)?,
        efficiency: cd.test(
            "efficiency",
            d.efficiency,
            d.efficiency > 0.0 && d.efficiency <= 1.0,
            "in (0, 1]",
        )?,
        inertia: cd.nonneg("inertia", d.inertia)?,
    };
    Ok((reducer, cd.pos("design_speed", d.design_speed)?))
}

/// `[motor]`.
fn motor(src: &Source, mo: &RawMotor) -> Result<Motor> {
    let cmo = Checks::table(src, "motor");
    let law = match mo.law.as_deref() {
        None | Some("kloss") => MotorLaw::Kloss,
        Some("kloss-corrected") => MotorLaw::KlossStartCorrected,
        Some(o) => return Err(cmo.err("law", format!("'{o}': use \"kloss\" or \"kloss-corrected\""))),
    };
    let w0 = cmo.pos("synchronous_speed", mo.synchronous_speed)?;
    let motor = Motor {
        synchronous_speed: w0,
        critical_speed: cmo.test(
            "critical_speed",
            mo.critical_speed,
            mo.critical_speed < w0,
            "below synchronous_speed",
        )?,
        critical_torque: cmo.pos("critical_torque", mo.critical_torque)?,
        // A catalogue's nominal point lies on the stable branch, between ω_c and ω0.
        nominal_speed: mo
            .nominal_speed
            .map(|v| {
                cmo.test(
                    "nominal_speed",
                    v,
                    v > mo.critical_speed && v < w0,
                    "between critical_speed and synchronous_speed",
                )
            })
            .transpose()?,
        nominal_torque: mo.nominal_torque.map(|v| cmo.pos("nominal_torque", v)).transpose()?,
        starting_torque: mo
            .starting_torque
            .map(|v| {
                cmo.test(
                    "starting_torque",
                    v,
                    v > 0.0 && v <= mo.critical_torque,
                    "> 0 and at most critical_torque",
                )
            })
            .transpose()?,
        law,
    };
    if law == MotorLaw::KlossStartCorrected && motor.starting_torque.is_none() {
        return Err(cmo.err("starting_torque", "missing (needed by law = \"kloss-corrected\")"));
    }
    Ok(motor)
}

/// `[run]`: the steady-state runs, their work bounded ([`MAX_STEADY_STEPS`]).
fn run_settings(src: &Source, r: &RawRun, design_speed: f64, sync: f64) -> Result<RunSettings> {
    let cr = Checks::table(src, "run");
    let step_deg = cr.test(
        "step_deg",
        r.step_deg.unwrap_or(0.5),
        r.step_deg
            .is_none_or(|s| s > 0.0 && s <= 10.0 && ((360.0 / s).round() * s - 360.0).abs() < 1e-9),
        "in (0, 10] and divide 360",
    )?;
    let max_rev = r.max_revolutions.unwrap_or(60);
    if !(2..=10_000).contains(&max_rev) {
        return Err(cr.err("max_revolutions", format!("must be 2–10000, got {max_rev}")));
    }
    // Each revolution takes 360/step_deg steps (and keeps as many samples): bound the work.
    let steps = (360.0 / step_deg).round() * max_rev as f64;
    if steps > MAX_STEADY_STEPS as f64 {
        return Err(cr.err(
            "step_deg",
            format!(
                "{step_deg}° with max_revolutions = {max_rev} asks for up to {steps:.3e} steps \
                 (at most {:.0e}): take a larger step_deg or fewer max_revolutions",
                MAX_STEADY_STEPS as f64
            ),
        ));
    }
    Ok(RunSettings {
        // From far above the synchronous speed a drive coasts for many revolutions, each so
        // like the last that the run would pass for steady.
        start_speed: cr.test(
            "start_speed",
            r.start_speed.unwrap_or(design_speed),
            r.start_speed.is_none_or(|v| v > 0.0 && v <= 2.0 * sync),
            &format!("> 0 and at most twice the crank's synchronous speed ω0/i = {sync:.4} rad/s"),
        )?,
        start_angle: cr
            .finite("start_angle_deg", r.start_angle_deg.unwrap_or(0.0))?
            .to_radians(),
        step: step_deg.to_radians(),
        max_revolutions: max_rev as usize,
        steady_tol: cr.test(
            "steady_tol",
            r.steady_tol.unwrap_or(1e-7),
            r.steady_tol.is_none_or(|v| v > 0.0 && v < 0.1),
            "in (0, 0.1)",
        )?,
        rtol: cr.test(
            "rtol",
            r.rtol.unwrap_or(1e-10),
            r.rtol.is_none_or(|v| (1e-14..=1e-3).contains(&v)),
            "in [1e-14, 1e-3]",
        )?,
    })
}

/// `[startup]`: the runs from rest.
fn startup_settings(src: &Source, s: &RawStartup, sync: f64) -> Result<StartupSettings> {
    let cs = Checks::table(src, "startup");
    let duration = cs.test(
        "duration",
        s.duration.unwrap_or(12.0),
        s.duration.is_none_or(|v| v > 0.0 && v <= 3600.0),
        "in (0, 3600] s",
    )?;
    // The metrics of a revolution come from the samples: at least 36 a revolution (10°) at the
    // synchronous speed, and ten in the run.
    let dt = cs.recording_step(
        s.dt,
        2e-3,
        (TAU / sync / 36.0).min(duration / 10.0),
        "36 samples a revolution at the synchronous speed, 10 in the run",
        duration,
    )?;
    Ok(StartupSettings {
        ramp_time: s.ramp_time.map(|v| cs.pos("ramp_time", v)).transpose()?,
        duration,
        dt,
        start_angle: cs
            .finite("start_angle_deg", s.start_angle_deg.unwrap_or(0.0))?
            .to_radians(),
    })
}

/// The `k`-th `[[setup]]`.
fn setup(src: &Source, k: usize, st: &RawSetup) -> Result<Setup> {
    let c = Checks::item(src, "setup", k);
    let ph = phases(
        src,
        "setup",
        Some(k),
        st.carts,
        st.phase_shift_deg,
        st.phases_deg.as_ref(),
    )?;
    let motor_scale = match &st.motor_scale {
        None => MotorScale::Power,
        Some(RawScale::Rule(s)) if s == "power" => MotorScale::Power,
        Some(RawScale::Rule(s)) => return Err(c.err("motor_scale", format!("'{s}': use \"power\" or a number"))),
        Some(RawScale::Factor(f)) => MotorScale::Factor(c.pos("motor_scale", *f)?),
    };
    let paper = match (st.paper_extremes, st.paper_metrics) {
        (None, None) => None,
        (Some(e), Some(m)) => {
            for v in e {
                c.pos("paper_extremes", v)?;
            }
            for v in m {
                c.nonneg("paper_metrics", v)?;
            }
            let (carts, shift_deg) = (ph.len(), ph.get(1).map(|p| p.to_degrees()).unwrap_or(0.0));
            Some(PaperRow {
                carts,
                shift_deg,
                omega_min: e[0],
                omega_max: e[1],
                omega_mean: e[2],
                eps_max: e[3],
                delta: m[0],
                mu: m[1],
                k_p: m[2],
            })
        }
        (Some(_), None) => return Err(c.err("paper_metrics", "missing (with paper_extremes)")),
        (None, Some(_)) => return Err(c.err("paper_extremes", "missing (with paper_metrics)")),
    };
    Ok(Setup {
        name: st.name.clone(),
        phases: ph,
        motor_scale,
        paper,
    })
}
