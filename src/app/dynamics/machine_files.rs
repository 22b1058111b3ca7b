//! TOML input files of the crank drive and the autobalancer (`vibrofem crank-drive FILE`,
//! `vibrofem autobalancer FILE`).
//!
//! Both formats are strict: a `[machine]` table with `version = 1` and `kind = "crank-drive"` or
//! `"autobalancer"` is required, unknown keys are errors, and every error names the file, the line
//! and the key. The built-in defaults are the files in `scenes/machines/` (compiled in), whose
//! machines are also [`CrankDrive::paper_two_carts`] and [`Grinder::plausible`].

// `!(x > 0.0)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::f64::consts::TAU;
use std::path::Path;

use serde::Deserialize;
use serde::de::DeserializeOwned;

use super::autobalancer::{Ball, Cutting, Grinder};
use super::crank::{CrankDrive, Mechanism, Motor, MotorLaw, PaperRow, Reducer};
use crate::{Error, Result};

/// The built-in crank-drive file (the paper's two-cart drive and Table 1 setups).
pub const CRANK_DEFAULT_TOML: &str = include_str!("../../../scenes/machines/crank_two_carts.toml");
/// Its name in messages.
pub const CRANK_DEFAULT_NAME: &str = "scenes/machines/crank_two_carts.toml (built in)";
/// The built-in autobalancer file (a plausible 125 mm grinder).
pub const AUTOBALANCER_DEFAULT_TOML: &str = include_str!("../../../scenes/machines/grinder_autobalancer.toml");
/// Its name in messages.
pub const AUTOBALANCER_DEFAULT_NAME: &str = "scenes/machines/grinder_autobalancer.toml (built in)";

/// A TOML text with its file name, for messages that name the file, line and key.
struct Source<'a> {
    file: &'a str,
    text: &'a str,
}

impl Source<'_> {
    fn line_of(&self, offset: usize) -> usize {
        self.text[..offset.min(self.text.len())].matches('\n').count() + 1
    }

    /// Line of `key` in the `index`-th `[table]` / `[[table]]` (0-based), or of the table header
    /// when the key is absent, or None.
    fn key_line(&self, table: &str, index: usize, key: &str) -> Option<usize> {
        let mut current: Option<(String, usize)> = None;
        let mut counts: Vec<(String, usize)> = Vec::new();
        let mut header = None;
        for (i, raw) in self.text.lines().enumerate() {
            let l = raw.split('#').next().unwrap_or("").trim();
            if let Some(name) = l.strip_prefix("[[").and_then(|r| r.strip_suffix("]]")) {
                let name = name.trim().to_string();
                let c = match counts.iter_mut().find(|(n, _)| *n == name) {
                    Some((_, c)) => {
                        *c += 1;
                        *c
                    }
                    None => {
                        counts.push((name.clone(), 0));
                        0
                    }
                };
                current = Some((name, c));
            } else if let Some(name) = l.strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
                current = Some((name.trim().to_string(), 0));
            } else if let Some((k, _)) = l.split_once('=')
                && k.trim().trim_matches('"') == key
                && current.as_ref().is_some_and(|(n, c)| n == table && *c == index)
            {
                return Some(i + 1);
            }
            if header.is_none() && current.as_ref().is_some_and(|(n, c)| n == table && *c == index) {
                header = Some(i + 1);
            }
        }
        header
    }

    fn err(&self, table: &str, index: Option<usize>, key: &str, msg: impl std::fmt::Display) -> Error {
        let line = self.key_line(table, index.unwrap_or(0), key);
        let place = match index {
            Some(i) => format!("[[{table}]] #{} '{key}'", i + 1),
            None => format!("'{table}.{key}'"),
        };
        match line {
            Some(l) => Error::InvalidInput(format!("{}, line {l}: {place}: {msg}", self.file)),
            None => Error::InvalidInput(format!("{}: {place}: {msg}", self.file)),
        }
    }

    /// Checks `[machine] version = 1, kind = KIND`, then parses strictly.
    fn parse<T: DeserializeOwned>(&self, kind: &str) -> Result<T> {
        let loose: toml::Table = toml::from_str(self.text).map_err(|e| self.toml_error(&e))?;
        let header = loose.get("machine").and_then(|m| m.as_table()).ok_or_else(|| {
            Error::InvalidInput(format!(
                "{}: missing [machine] table (with version = 1 and kind = \"{kind}\")",
                self.file
            ))
        })?;
        match header.get("version") {
            Some(toml::Value::Integer(1)) => {}
            Some(v) => {
                return Err(self.err(
                    "machine",
                    None,
                    "version",
                    format!("unsupported version {v} (this vibrofem reads version 1)"),
                ));
            }
            None => return Err(self.err("machine", None, "version", "missing (version = 1)")),
        }
        match header.get("kind") {
            Some(toml::Value::String(k)) if k == kind => {}
            Some(v) => {
                return Err(self.err(
                    "machine",
                    None,
                    "kind",
                    format!("this command reads kind = \"{kind}\", the file says {v}"),
                ));
            }
            None => return Err(self.err("machine", None, "kind", format!("missing (kind = \"{kind}\")"))),
        }
        toml::from_str(self.text).map_err(|e| self.toml_error(&e))
    }

    fn toml_error(&self, e: &toml::de::Error) -> Error {
        let msg = e.message().trim().to_string();
        match e.span() {
            Some(s) => {
                let line = self.line_of(s.start);
                // Name the key when the error points into a `key = value` line.
                let text_line = self.text.lines().nth(line - 1).unwrap_or("");
                let key = text_line
                    .split('#')
                    .next()
                    .and_then(|l| l.split_once('='))
                    .map(|(k, _)| k.trim().to_string())
                    .filter(|k| !k.is_empty() && !k.starts_with('['));
                match key {
                    Some(k) if !msg.contains(&format!("`{k}`")) => {
                        Error::InvalidInput(format!("{}, line {line}: key '{k}': {msg}", self.file))
                    }
                    _ => Error::InvalidInput(format!("{}, line {line}: {msg}", self.file)),
                }
            }
            None => Error::InvalidInput(format!("{}: {msg}", self.file)),
        }
    }
}

/// A number check that names the table, key and line.
struct Checks<'a, 'b> {
    src: &'b Source<'a>,
    table: &'b str,
    index: Option<usize>,
}

impl Checks<'_, '_> {
    fn test(&self, key: &str, v: f64, ok: bool, want: &str) -> Result<f64> {
        if v.is_finite() && ok {
            Ok(v)
        } else {
            Err(self
                .src
                .err(self.table, self.index, key, format!("must be {want}, got {v}")))
        }
    }
    fn pos(&self, key: &str, v: f64) -> Result<f64> {
        self.test(key, v, v > 0.0, "> 0")
    }
    fn nonneg(&self, key: &str, v: f64) -> Result<f64> {
        self.test(key, v, v >= 0.0, "≥ 0")
    }
    fn finite(&self, key: &str, v: f64) -> Result<f64> {
        self.test(key, v, true, "finite")
    }
}

// ---------------------------------------------------------------------------------------------
// Crank drive

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
                c.finite("phases_deg", *v)?;
            }
            Ok(l.iter().map(|d| d.to_radians()).collect())
        }
        (None, Some(n)) => {
            if !(1..=64).contains(&n) {
                return Err(src.err(table, index, "carts", format!("must be 1–64, got {n}")));
            }
            let s = match shift {
                Some(s) => c.finite("phase_shift_deg", s)?,
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
        let src = Source { file, text };
        let raw: RawCrank = src.parse("crank-drive")?;
        let m = &raw.mechanism;
        let cm = Checks {
            src: &src,
            table: "mechanism",
            index: None,
        };
        let crank_radius = cm.pos("crank_radius", m.crank_radius)?;
        let rod_length = cm.test(
            "rod_length",
            m.rod_length,
            m.rod_length > crank_radius,
            "longer than crank_radius",
        )?;
        let mechanism = Mechanism {
            crank_radius,
            rod_length,
            rod_mass_per_length: cm.nonneg("rod_mass_per_length", m.rod_mass_per_length)?,
            cart_mass: cm.nonneg("cart_mass", m.cart_mass)?,
            cart_resistance: cm.nonneg("cart_resistance", m.cart_resistance)?,
            gravity: cm.nonneg("gravity", m.gravity.unwrap_or(9.81))?,
            phases: phases(
                &src,
                "mechanism",
                None,
                m.carts,
                m.phase_shift_deg,
                m.phases_deg.as_ref(),
            )?,
        };
        let d = &raw.drive;
        let cd = Checks {
            src: &src,
            table: "drive",
            index: None,
        };
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
        let design_speed = cd.pos("design_speed", d.design_speed)?;
        let mo = &raw.motor;
        let cmo = Checks {
            src: &src,
            table: "motor",
            index: None,
        };
        let law = match mo.law.as_deref() {
            None | Some("kloss") => MotorLaw::Kloss,
            Some("kloss-corrected") => MotorLaw::KlossStartCorrected,
            Some(o) => {
                return Err(src.err(
                    "motor",
                    None,
                    "law",
                    format!("'{o}': use \"kloss\" or \"kloss-corrected\""),
                ));
            }
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
            nominal_speed: mo.nominal_speed.map(|v| cmo.pos("nominal_speed", v)).transpose()?,
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
            return Err(src.err(
                "motor",
                None,
                "starting_torque",
                "missing (needed by law = \"kloss-corrected\")",
            ));
        }
        let drive = CrankDrive {
            mechanism,
            motor,
            reducer,
            torque_scale: 1.0,
        };
        drive
            .validate()
            .map_err(|e| Error::InvalidInput(format!("{file}: {e}")))?;

        let r = &raw.run;
        let cr = Checks {
            src: &src,
            table: "run",
            index: None,
        };
        let step_deg = cr.test(
            "step_deg",
            r.step_deg.unwrap_or(0.5),
            r.step_deg
                .is_none_or(|s| s > 0.0 && s <= 10.0 && ((360.0 / s).round() * s - 360.0).abs() < 1e-9),
            "in (0, 10] and divide 360",
        )?;
        let max_rev = r.max_revolutions.unwrap_or(60);
        if !(2..=10_000).contains(&max_rev) {
            return Err(src.err(
                "run",
                None,
                "max_revolutions",
                format!("must be 2–10000, got {max_rev}"),
            ));
        }
        let run = RunSettings {
            start_speed: cr.pos("start_speed", r.start_speed.unwrap_or(design_speed))?,
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
        };
        let s = &raw.startup;
        let cs = Checks {
            src: &src,
            table: "startup",
            index: None,
        };
        let duration = cs.test(
            "duration",
            s.duration.unwrap_or(12.0),
            s.duration.is_none_or(|v| v > 0.0 && v <= 3600.0),
            "in (0, 3600] s",
        )?;
        let dt = cs.pos("dt", s.dt.unwrap_or(2e-3))?;
        if duration / dt > 2e6 {
            return Err(src.err("startup", None, "dt", format!("too small: {} samples", duration / dt)));
        }
        let startup = StartupSettings {
            ramp_time: s.ramp_time.map(|v| cs.pos("ramp_time", v)).transpose()?,
            duration,
            dt,
            start_angle: cs
                .finite("start_angle_deg", s.start_angle_deg.unwrap_or(0.0))?
                .to_radians(),
        };
        let mut setups = Vec::new();
        for (k, st) in raw.setup.iter().enumerate() {
            let c = Checks {
                src: &src,
                table: "setup",
                index: Some(k),
            };
            let ph = phases(
                &src,
                "setup",
                Some(k),
                st.carts,
                st.phase_shift_deg,
                st.phases_deg.as_ref(),
            )?;
            let motor_scale = match &st.motor_scale {
                None => MotorScale::Power,
                Some(RawScale::Rule(s)) if s == "power" => MotorScale::Power,
                Some(RawScale::Rule(s)) => {
                    return Err(src.err(
                        "setup",
                        Some(k),
                        "motor_scale",
                        format!("'{s}': use \"power\" or a number"),
                    ));
                }
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
                (Some(_), None) => {
                    return Err(src.err("setup", Some(k), "paper_metrics", "missing (with paper_extremes)"));
                }
                (None, Some(_)) => {
                    return Err(src.err("setup", Some(k), "paper_extremes", "missing (with paper_metrics)"));
                }
            };
            setups.push(Setup {
                name: st.name.clone(),
                phases: ph,
                motor_scale,
                paper,
            });
        }
        if setups.len() > 32 {
            return Err(src.err("setup", Some(32), "name", "at most 32 setups"));
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

// ---------------------------------------------------------------------------------------------
// Autobalancer

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
        let src = Source { file, text };
        let raw: RawAb = src.parse("autobalancer")?;
        let r = &raw.rocker;
        let cr = Checks {
            src: &src,
            table: "rocker",
            index: None,
        };
        let dd = &raw.disc;
        let cd = Checks {
            src: &src,
            table: "disc",
            index: None,
        };
        if raw.ball.len() > 16 {
            return Err(src.err("ball", Some(16), "mass", "at most 16 balls"));
        }
        let mut balls = Vec::new();
        for (k, b) in raw.ball.iter().enumerate() {
            let c = Checks {
                src: &src,
                table: "ball",
                index: Some(k),
            };
            balls.push(Ball {
                mass: c.pos("mass", b.mass)?,
                radius: c.pos("radius", b.radius)?,
                drag: c.nonneg("drag", b.drag)?,
                initial_angle: c.finite("initial_angle_deg", b.initial_angle_deg)?.to_radians(),
            });
        }
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
                return Err(src.err(
                    "rocker",
                    None,
                    "natural_frequency_hz",
                    "give either stiffness or natural_frequency_hz, not both",
                ));
            }
            (None, None) => {
                return Err(src.err("rocker", None, "stiffness", "missing (or give natural_frequency_hz)"));
            }
        }
        match (r.damping, r.damping_ratio) {
            (Some(h), None) => g.damping = cr.nonneg("damping", h)?,
            (None, Some(z)) => g.set_hinge_damping_ratio(cr.nonneg("damping_ratio", z)?),
            (Some(_), Some(_)) => {
                return Err(src.err(
                    "rocker",
                    None,
                    "damping_ratio",
                    "give either damping or damping_ratio, not both",
                ));
            }
            (None, None) => return Err(src.err("rocker", None, "damping", "missing (or give damping_ratio)")),
        }
        g.validate().map_err(|e| Error::InvalidInput(format!("{file}: {e}")))?;
        let cutting = match &raw.cutting {
            None => None,
            Some(c) => {
                let ch = Checks {
                    src: &src,
                    table: "cutting",
                    index: None,
                };
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
                    return Err(src.err(
                        "cutting",
                        None,
                        "surface_stiffness",
                        "makes the hinge stiffness while cutting non-positive",
                    ));
                }
                Some(cut)
            }
        };
        let s = &raw.sweep;
        let cs = Checks {
            src: &src,
            table: "sweep",
            index: None,
        };
        let from = cs.pos("from_ratio", s.from_ratio.unwrap_or(0.45))?;
        let to = cs.test(
            "to_ratio",
            s.to_ratio.unwrap_or(3.05),
            s.to_ratio.unwrap_or(3.05) > from,
            "above from_ratio",
        )?;
        let points = s.points.unwrap_or(27);
        if !(2..=2000).contains(&points) {
            return Err(src.err("sweep", None, "points", format!("must be 2–2000, got {points}")));
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
            return Err(src.err(
                "sweep",
                None,
                "duration",
                format!("too short: the lowest speed needs more than {:.3} s", 2.0 * need),
            ));
        }
        let sweep = SweepSettings {
            from_ratio: from,
            to_ratio: to,
            points: points as usize,
            duration,
        };
        let u = &raw.runup;
        let cu = Checks {
            src: &src,
            table: "runup",
            index: None,
        };
        let ramp_time = cu.pos("ramp_time", u.ramp_time.unwrap_or(1.0))?;
        let rdur = cu.pos("duration", u.duration.unwrap_or(4.0))?;
        if rdur <= ramp_time + 20.0 * TAU / g.speed || rdur > 1000.0 {
            return Err(src.err(
                "runup",
                None,
                "duration",
                "must exceed ramp_time by at least 20 revolutions, and be at most 1000 s",
            ));
        }
        let dt = cu.pos("dt", u.dt.unwrap_or(2e-4))?;
        if rdur / dt > 2e6 {
            return Err(src.err("runup", None, "dt", format!("too small: {} samples", rdur / dt)));
        }
        Ok(AutobalancerCase {
            file: file.to_string(),
            name: raw.machine.name.clone().unwrap_or_else(|| "autobalancer".into()),
            grinder: g,
            cutting,
            sweep,
            runup: RunupSettings {
                ramp_time,
                duration: rdur,
                dt,
            },
        })
    }
}
