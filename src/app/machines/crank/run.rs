//! The crank-drive analysis of a case: the steady state by the paper's Baranov step and by the
//! adaptive integrator, the comparison setups, the runs from rest; the result is the
//! `--json` document ([`CrankReport`]).

use std::f64::consts::TAU;
use std::path::Path;

use serde::Serialize;

use super::case::{CrankCase, Setup};
use super::model::{
    self, CrankDrive, Metrics, MotorLaw, PaperRow, RunUp, RunUpOptions, Stall, Startup, SteadyOptions, SteadyRun,
};
use super::plots;
use crate::Result;
use crate::app::dynamics::ode::Dopri5Options;
use crate::app::machines::report_files;
use crate::app::report::fmt_sig;

/// Motor figures.
#[derive(Debug, Clone, Serialize)]
pub struct MotorFigures {
    /// Catalogue nominal speed, rad/s.
    pub nominal_speed: Option<f64>,
    /// The law's torque there, N·m.
    pub torque_at_nominal: Option<f64>,
    /// Catalogue nominal torque, N·m.
    pub catalogue_nominal_torque: Option<f64>,
    /// Plain Kloss torque at standstill, N·m.
    pub kloss_at_standstill: f64,
    /// Catalogue starting torque, N·m.
    pub catalogue_starting_torque: Option<f64>,
    /// The law's torque at standstill, N·m.
    pub torque_at_standstill: f64,
    /// Driving moment at the crank at standstill, N·m.
    pub driving_moment_at_rest: f64,
    /// Driving moment at the crank at the critical speed, N·m.
    pub driving_moment_at_critical: f64,
}

/// One row of the comparison table.
#[derive(Debug, Clone, Serialize)]
pub struct SetupRow {
    /// Name.
    pub name: String,
    /// Number of carts.
    pub carts: usize,
    /// Crank phases, degrees.
    pub phases_deg: Vec<f64>,
    /// Factor on the motor torque.
    pub torque_scale: f64,
    /// Mean resisting moment, N·m.
    pub mean_moment: f64,
    /// Design power, W.
    pub design_power: f64,
    /// Reduced inertia range, kg·m².
    pub inertia_range: [f64; 2],
    /// Steady metrics (adaptive integrator), None if stalled.
    pub metrics: Option<Metrics>,
    /// Midrange speed, rad/s.
    pub omega_midrange: Option<f64>,
    /// Stall message.
    pub stall: Option<String>,
    /// The paper's row.
    pub paper: Option<PaperRow>,
    /// The metrics recomputed from the paper's extremes.
    pub paper_recomputed: Option<Metrics>,
}

/// One run from rest.
#[derive(Debug, Clone, Serialize)]
pub struct StartupRow {
    /// Description.
    pub case: String,
    /// Motor law.
    pub law: MotorLaw,
    /// Treatment.
    pub startup: Startup,
    /// Stall, if any.
    pub stall: Option<Stall>,
    /// Time to 95 % of the final mean speed, s.
    pub time_to_95: Option<f64>,
    /// Revolutions by then.
    pub revolutions_to_95: Option<f64>,
    /// Metrics of the last revolution.
    pub metrics: Option<Metrics>,
    /// Revolutions turned.
    pub revolutions: f64,
}

/// The crank-drive report (`report.json`).
#[derive(Debug, Clone, Serialize)]
pub struct CrankReport {
    /// Input file.
    pub file: String,
    /// Machine name.
    pub name: String,
    /// The drive.
    pub drive: CrankDrive,
    /// Design crank speed, rad/s.
    pub design_speed: f64,
    /// Start speed of the steady-state runs, rad/s.
    pub start_speed: f64,
    /// Mean resisting moment by quadrature, N·m.
    pub mean_resisting_moment: f64,
    /// Its closed form n·2Fr/π, N·m.
    pub mean_resisting_moment_closed_form: f64,
    /// Design power M_mean ω/η, W.
    pub design_power: f64,
    /// Reduced inertia range, kg·m².
    pub inertia_range: [f64; 2],
    /// Resisting moment range, N·m.
    pub resisting_range: [f64; 2],
    /// Motor figures.
    pub motor: MotorFigures,
    /// The paper's Baranov step (its samples are in the plots, not in the JSON).
    pub baranov: SteadyRun,
    /// The adaptive integrator of the energy form.
    pub energy_form: SteadyRun,
    /// Comparison setups.
    pub setups: Vec<SetupRow>,
    /// Runs from rest.
    pub startup: Vec<StartupRow>,
    /// Files written.
    pub outputs: Vec<String>,
    /// Notes.
    pub notes: Vec<String>,
}

fn steady_options(c: &CrankCase) -> SteadyOptions {
    SteadyOptions {
        omega_start: c.run.start_speed,
        phi_start: c.run.start_angle,
        step: c.run.step,
        min_revolutions: 3,
        max_revolutions: c.run.max_revolutions,
        steady_tol: c.run.steady_tol,
        ode: Dopri5Options {
            rtol: c.run.rtol,
            atol: c.run.rtol,
            ..Dopri5Options::default()
        },
    }
}

fn resisting_range(d: &CrankDrive) -> [f64; 2] {
    let (lo, hi) = (0..1440)
        .map(|k| d.mechanism.resisting_moment(TAU * k as f64 / 1440.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    [lo, hi]
}

/// Runs the crank-drive analysis of a case; with `out`, writes the SVG plots there and lists
/// them, with the report files, in `outputs`. Errors: invalid data, integrator failure, I/O.
pub fn crank_analysis(c: &CrankCase, out: Option<&Path>) -> Result<CrankReport> {
    let d = &c.drive;
    let o = steady_options(c);
    let bar = model::baranov(d, &o)?;
    let ef = model::energy_form(d, &o)?;
    let mut notes = Vec::new();
    for run in [&bar, &ef] {
        if run.stall.is_none() && !run.converged {
            notes.push(format!(
                "{}: not steady after {} revolutions (tolerance {:e}); the last revolution is reported",
                run.method, run.revolutions, o.steady_tol
            ));
        }
    }
    let mut setups = Vec::new();
    let mut setup_runs = Vec::new();
    for s in &c.setups {
        let sd = c.setup_drive(s);
        let run = model::energy_form(&sd, &o)?;
        setups.push(setup_row(s, &sd, &run, c.design_speed)?);
        setup_runs.push((s.name.clone(), Some(run)));
    }
    let startup_runs = runs_from_rest(c)?;
    let startup = startup_runs
        .iter()
        .map(|(name, ru)| StartupRow {
            case: name.clone(),
            law: ru.law,
            startup: ru.startup,
            stall: ru.stall.clone(),
            time_to_95: ru.time_to_95,
            revolutions_to_95: ru.revolutions_to_95,
            metrics: ru.metrics,
            revolutions: ru.revolutions,
        })
        .collect();
    let mut outputs = Vec::new();
    if let Some(dir) = out {
        let p = dir.join("crank_drive.svg");
        plots::crank_plot(&p, c, &bar, &ef)?;
        outputs.push(p.display().to_string());
        if !setup_runs.is_empty() {
            let p = dir.join("setups.svg");
            plots::setups_plot(&p, c, &setup_runs)?;
            outputs.push(p.display().to_string());
        }
        let p = dir.join("startup.svg");
        plots::startup_plot(&p, &startup_runs)?;
        outputs.push(p.display().to_string());
        outputs.extend(report_files(dir));
    }
    let (ilo, ihi) = d.reduced_inertia_range(1440);
    Ok(CrankReport {
        file: c.file.clone(),
        name: c.name.clone(),
        drive: d.clone(),
        design_speed: c.design_speed,
        start_speed: c.run.start_speed,
        mean_resisting_moment: d.mechanism.mean_resisting_moment(),
        mean_resisting_moment_closed_form: d.mechanism.mean_resisting_moment_closed_form(),
        design_power: d.design_power(c.design_speed),
        inertia_range: [ilo, ihi],
        resisting_range: resisting_range(d),
        motor: motor_figures(d),
        baranov: bar,
        energy_form: ef,
        setups,
        startup,
        outputs,
        notes,
    })
}

/// The motor's figures at its nominal speed, at standstill and at the critical speed.
fn motor_figures(d: &CrankDrive) -> MotorFigures {
    let m = &d.motor;
    MotorFigures {
        nominal_speed: m.nominal_speed,
        torque_at_nominal: m.nominal_speed.map(|w| m.torque(w)),
        catalogue_nominal_torque: m.nominal_torque,
        kloss_at_standstill: m.kloss_at(0.0, m.synchronous_speed),
        catalogue_starting_torque: m.starting_torque,
        torque_at_standstill: m.torque(0.0),
        driving_moment_at_rest: d.driving_moment(0.0),
        driving_moment_at_critical: d.driving_moment(m.critical_speed / d.reducer.ratio),
    }
}

/// The runs from rest: direct on line with the file's law, with the starting-torque correction
/// when the catalogue gives a starting torque, and with a frequency ramp when the file gives one.
fn runs_from_rest(c: &CrankCase) -> Result<Vec<(String, RunUp)>> {
    let d = &c.drive;
    let m = &d.motor;
    let mut cases: Vec<(String, CrankDrive, Startup)> = vec![(
        format!("direct on line, {}", law_name(m.law)),
        d.clone(),
        Startup::Direct,
    )];
    if m.law == MotorLaw::Kloss && m.starting_torque.is_some() {
        let mut dc = d.clone();
        dc.motor.law = MotorLaw::KlossStartCorrected;
        cases.push((
            format!("direct on line, {}", law_name(MotorLaw::KlossStartCorrected)),
            dc,
            Startup::Direct,
        ));
    }
    if let Some(rt) = c.startup.ramp_time {
        cases.push((
            format!("frequency ramp 0 → ω0 in {} s, {}", fmt_sig(rt, 3), law_name(m.law)),
            d.clone(),
            Startup::FrequencyRamp { ramp_time: rt },
        ));
    }
    cases
        .into_iter()
        .map(|(name, dd, st)| {
            let ru = model::run_up(
                &dd,
                &RunUpOptions {
                    phi_start: c.startup.start_angle,
                    startup: st,
                    duration: c.startup.duration,
                    dt_out: c.startup.dt,
                    ode: Dopri5Options {
                        rtol: 1e-9,
                        atol: 1e-9,
                        ..Dopri5Options::default()
                    },
                },
            )?;
            Ok((name, ru))
        })
        .collect()
}

pub(crate) fn law_name(l: MotorLaw) -> &'static str {
    match l {
        MotorLaw::Kloss => "Kloss",
        MotorLaw::KlossStartCorrected => "Kloss with the starting torque",
    }
}

fn setup_row(s: &Setup, sd: &CrankDrive, run: &SteadyRun, design_speed: f64) -> Result<SetupRow> {
    let (ilo, ihi) = sd.reduced_inertia_range(1440);
    Ok(SetupRow {
        name: s.name.clone(),
        carts: s.phases.len(),
        phases_deg: s.phases.iter().map(|p| p.to_degrees()).collect(),
        torque_scale: sd.torque_scale,
        mean_moment: sd.mechanism.mean_resisting_moment(),
        design_power: sd.design_power(design_speed),
        inertia_range: [ilo, ihi],
        metrics: run.metrics,
        omega_midrange: run.omega_midrange,
        stall: run.stall.as_ref().map(|x| x.message.clone()),
        paper: s.paper,
        paper_recomputed: match &s.paper {
            Some(p) => Some(Metrics::from_extremes(
                p.omega_min,
                p.omega_max,
                p.omega_mean,
                p.eps_max,
            )?),
            None => None,
        },
    })
}
