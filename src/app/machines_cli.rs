//! The lumped-dynamics commands for the other machines of the family (docs/spec/machines.md):
//! `vibrofem crank-drive`, `vibrofem autobalancer` and `vibrofem balancer-data`.
//!
//! Each writes `report.md`, `report.json` and SVG plots into its output folder and prints a short
//! summary (or, with `--json`, the JSON report) on stdout. Exit codes: 0 success; 1 bad input
//! (file, line and key named); 2 when the main steady-state run of a crank drive stalls (the report
//! is still written and says where and why). A stall of a run from rest is a result, not a
//! failure: it is reported with exit code 0.
//!
//! The analyses ([`crank_analysis`], [`autobalancer_analysis`], [`balancer_data_analysis`]) are
//! public so that tests and other programs can run them without the command line.

use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::app::dynamics::autobalancer::{
    self, BALANCED_RESIDUAL, Cutting, CuttingRow, Grinder, SimOptions, SpeedProfile, SteadyEnd, SweepRow,
};
use crate::app::dynamics::balancer_data::{self, Reduction};
use crate::app::dynamics::crank::{
    self, CrankDrive, Metrics, MotorLaw, PaperRow, RunUpOptions, Stall, Startup, SteadyOptions, SteadyRun,
};
use crate::app::dynamics::machine_files::{AutobalancerCase, CrankCase, Setup};
use crate::app::dynamics::machine_plot::{Mark, Panel, Series, write_panels_svg};
use crate::app::dynamics::ode::Dopri5Options;
use crate::{Error, Result};

/// `n` significant digits, plain for moderate magnitudes, scientific otherwise.
fn sig(x: f64, n: usize) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".into();
    }
    let e = x.abs().log10().floor() as i32;
    if !(-3..6).contains(&e) {
        return format!("{:.*e}", n.saturating_sub(1), x);
    }
    let dec = (n as i32 - 1 - e).max(0) as usize;
    format!("{x:.dec$}")
}

fn pct(x: f64) -> String {
    format!("{:.1} %", 100.0 * x)
}

fn write_file(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}

fn to_json<T: Serialize>(v: &T) -> Result<String> {
    serde_json::to_string_pretty(v).map_err(|e| Error::output("report.json", e))
}

fn make_dir(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))
}

// =============================================================================================
// Crank drive

/// `vibrofem crank-drive [FILE.toml]`.
#[derive(Debug, Clone, clap::Args)]
pub struct CrankDriveArgs {
    /// Crank-drive file (TOML, `[machine] kind = "crank-drive"`); default: the paper's two-cart
    /// drive with the four setups of its Table 1, built in (scenes/machines/crank_two_carts.toml).
    pub file: Option<PathBuf>,
    /// Folder for report.md, report.json and the SVG plots.
    #[arg(short, long, default_value = "vibrofem-crank-drive")]
    pub out: PathBuf,
    /// Print the JSON report on stdout instead of the summary.
    #[arg(long)]
    pub json: bool,
}

/// Summary of a φ-domain steady-state run (the samples are in the plots, not in the JSON).
#[derive(Debug, Clone, Serialize)]
pub struct SteadySummary {
    /// Method.
    pub method: String,
    /// Revolutions integrated.
    pub revolutions: usize,
    /// Two successive revolutions agreed within the tolerance.
    pub converged: bool,
    /// Metrics of the last revolution.
    pub metrics: Option<Metrics>,
    /// (ω_min + ω_max)/2, rad/s.
    pub omega_midrange: Option<f64>,
    /// Angle mean of ω, rad/s.
    pub omega_angle_mean: Option<f64>,
    /// Stall, if any.
    pub stall: Option<Stall>,
    /// RHS evaluations (adaptive) or steps (Baranov).
    pub evaluations: usize,
}

impl From<&SteadyRun> for SteadySummary {
    fn from(r: &SteadyRun) -> Self {
        SteadySummary {
            method: r.method.clone(),
            revolutions: r.revolutions,
            converged: r.converged,
            metrics: r.metrics,
            omega_midrange: r.omega_midrange,
            omega_angle_mean: r.omega_angle_mean,
            stall: r.stall.clone(),
            evaluations: r.evaluations,
        }
    }
}

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
    /// The paper's Baranov step.
    pub baranov: SteadySummary,
    /// The adaptive integrator of the energy form.
    pub energy_form: SteadySummary,
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

/// Runs the crank-drive analysis of a case; with `out`, writes the SVG plots there (the caller
/// writes the report files). Errors: invalid data, integrator failure, I/O.
pub fn crank_analysis(c: &CrankCase, out: Option<&Path>) -> Result<CrankReport> {
    let d = &c.drive;
    let o = steady_options(c);
    let bar = crank::baranov(d, &o)?;
    let ef = crank::energy_form(d, &o)?;
    let m = &d.motor;
    let r = &d.reducer;
    let motor = MotorFigures {
        nominal_speed: m.nominal_speed,
        torque_at_nominal: m.nominal_speed.map(|w| m.torque(w)),
        catalogue_nominal_torque: m.nominal_torque,
        kloss_at_standstill: m.kloss_at(0.0, m.synchronous_speed),
        catalogue_starting_torque: m.starting_torque,
        torque_at_standstill: m.torque(0.0),
        driving_moment_at_rest: d.driving_moment(0.0),
        driving_moment_at_critical: d.driving_moment(m.critical_speed / r.ratio),
    };
    let mut notes = Vec::new();
    for run in [&bar, &ef] {
        if run.stall.is_none() && !run.converged {
            notes.push(format!(
                "{}: not steady after {} revolutions (tolerance {:e}); the last revolution is reported",
                run.method, run.revolutions, o.steady_tol
            ));
        }
    }
    // Setups.
    let mut setups = Vec::new();
    let mut setup_runs: Vec<(String, Option<SteadyRun>)> = Vec::new();
    for s in &c.setups {
        let sd = c.setup_drive(s);
        let run = crank::energy_form(&sd, &o)?;
        setups.push(setup_row(s, &sd, &run, c.design_speed)?);
        setup_runs.push((s.name.clone(), Some(run)));
    }
    // Runs from rest.
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
            format!("frequency ramp 0 → ω0 in {} s, {}", sig(rt, 3), law_name(m.law)),
            d.clone(),
            Startup::FrequencyRamp { ramp_time: rt },
        ));
    }
    let mut startup = Vec::new();
    let mut startup_runs = Vec::new();
    for (name, dd, st) in cases {
        let ru = crank::run_up(
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
        startup.push(StartupRow {
            case: name.clone(),
            law: dd.motor.law,
            startup: st,
            stall: ru.stall.clone(),
            time_to_95: ru.time_to_95,
            revolutions_to_95: ru.revolutions_to_95,
            metrics: ru.metrics,
            revolutions: ru.revolutions,
        });
        startup_runs.push((name, ru));
    }
    let (ilo, ihi) = d.reduced_inertia_range(1440);
    let mut outputs = Vec::new();
    if let Some(dir) = out {
        let p = dir.join("crank_drive.svg");
        crank_plot(&p, c, &bar, &ef)?;
        outputs.push(p.display().to_string());
        if !setup_runs.is_empty() {
            let p = dir.join("setups.svg");
            setups_plot(&p, c, &setup_runs)?;
            outputs.push(p.display().to_string());
        }
        let p = dir.join("startup.svg");
        startup_plot(&p, &startup_runs)?;
        outputs.push(p.display().to_string());
    }
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
        motor,
        baranov: (&bar).into(),
        energy_form: (&ef).into(),
        setups,
        startup,
        outputs,
        notes,
    })
}

fn law_name(l: MotorLaw) -> &'static str {
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

fn crank_plot(path: &Path, c: &CrankCase, bar: &SteadyRun, ef: &SteadyRun) -> Result<()> {
    let d = &c.drive;
    let n = 720;
    let grid: Vec<f64> = (0..=n).map(|k| TAU * k as f64 / n as f64).collect();
    let phi0 = c.run.start_angle;
    let deg = |p: f64| p.to_degrees();
    let i_curve: Vec<(f64, f64)> = grid.iter().map(|p| (deg(*p), d.reduced_inertia(phi0 + p).0)).collect();
    let mr: Vec<(f64, f64)> = grid
        .iter()
        .map(|p| (deg(*p), d.mechanism.resisting_moment(phi0 + p)))
        .collect();
    let mut panels = vec![
        Panel {
            title: format!("{}: reduced inertia I(φ)", c.name),
            x_label: "crank angle φ (from the start angle), deg".into(),
            y_label: "I, kg·m²".into(),
            series: vec![Series::new("I(φ)", i_curve, 0, Mark::Line)],
            x_range: Some((0.0, 360.0)),
            ..Panel::default()
        },
        Panel {
            title: "Resisting moment M_r(φ) and driving moment M_d(ω(φ)) on the steady revolution".into(),
            x_label: "crank angle φ, deg".into(),
            y_label: "moment, N·m".into(),
            series: vec![Series::new("M_r(φ)", mr, 1, Mark::Line)],
            x_range: Some((0.0, 360.0)),
            ..Panel::default()
        },
    ];
    let mut w_series = Vec::new();
    let mut e_series = Vec::new();
    for (run, color, mark) in [(ef, 0usize, Mark::Line), (bar, 1usize, Mark::Dashed)] {
        if run.metrics.is_none() {
            continue;
        }
        let s = &run.last;
        let short = if run.method == "baranov" {
            format!("Baranov, Δφ = {}°", sig(c.run.step.to_degrees(), 3))
        } else {
            "adaptive, energy form".to_string()
        };
        w_series.push(Series::new(
            format!("ω(φ), {short}"),
            s.phi.iter().zip(&s.omega).map(|(p, w)| (deg(*p), *w)).collect(),
            color,
            mark,
        ));
        e_series.push(Series::new(
            format!("ε(φ), {short}"),
            s.phi.iter().zip(&s.eps).map(|(p, e)| (deg(*p), *e)).collect(),
            color,
            mark,
        ));
    }
    if let Some(s) = ef.metrics.map(|_| &ef.last) {
        panels[1].series.push(Series::new(
            "M_d(ω(φ)), adaptive",
            s.phi
                .iter()
                .zip(&s.omega)
                .map(|(p, w)| (deg(*p), d.driving_moment(*w)))
                .collect(),
            0,
            Mark::Line,
        ));
    }
    panels.push(Panel {
        title: "Crank speed ω(φ) on the steady revolution".into(),
        x_label: "crank angle φ, deg".into(),
        y_label: "ω, rad/s".into(),
        series: w_series,
        x_range: Some((0.0, 360.0)),
        ..Panel::default()
    });
    panels.push(Panel {
        title: "Angular acceleration ε(φ) = dω/dt".into(),
        x_label: "crank angle φ, deg".into(),
        y_label: "ε, rad/s²".into(),
        series: e_series,
        x_range: Some((0.0, 360.0)),
        ..Panel::default()
    });
    write_panels_svg(path, &panels, 1000, 360)
}

fn setups_plot(path: &Path, c: &CrankCase, runs: &[(String, Option<SteadyRun>)]) -> Result<()> {
    let mut w = Vec::new();
    let mut mr = Vec::new();
    let mut inertia = Vec::new();
    for (k, ((name, run), s)) in runs.iter().zip(&c.setups).enumerate() {
        let sd = c.setup_drive(s);
        let grid: Vec<f64> = (0..=720).map(|j| TAU * j as f64 / 720.0).collect();
        mr.push(Series::new(
            name.clone(),
            grid.iter()
                .map(|p| (p.to_degrees(), sd.mechanism.resisting_moment(c.run.start_angle + p)))
                .collect(),
            k,
            Mark::Line,
        ));
        inertia.push(Series::new(
            name.clone(),
            grid.iter()
                .map(|p| (p.to_degrees(), sd.reduced_inertia(c.run.start_angle + p).0))
                .collect(),
            k,
            Mark::Line,
        ));
        if let Some(r) = run
            && r.metrics.is_some()
        {
            w.push(Series::new(
                name.clone(),
                r.last
                    .phi
                    .iter()
                    .zip(&r.last.omega)
                    .map(|(p, x)| (p.to_degrees(), *x))
                    .collect(),
                k,
                Mark::Line,
            ));
        }
    }
    let panels = vec![
        Panel {
            title: "Setups: crank speed ω(φ) on the steady revolution (adaptive integrator)".into(),
            x_label: "crank angle φ, deg".into(),
            y_label: "ω, rad/s".into(),
            series: w,
            x_range: Some((0.0, 360.0)),
            ..Panel::default()
        },
        Panel {
            title: "Setups: resisting moment M_r(φ)".into(),
            x_label: "crank angle φ, deg".into(),
            y_label: "M_r, N·m".into(),
            series: mr,
            x_range: Some((0.0, 360.0)),
            ..Panel::default()
        },
        Panel {
            title: "Setups: reduced inertia I(φ)".into(),
            x_label: "crank angle φ, deg".into(),
            y_label: "I, kg·m²".into(),
            series: inertia,
            x_range: Some((0.0, 360.0)),
            ..Panel::default()
        },
    ];
    write_panels_svg(path, &panels, 1000, 360)
}

fn startup_plot(path: &Path, runs: &[(String, crank::RunUp)]) -> Result<()> {
    let mut series = Vec::new();
    let mut revs = Vec::new();
    for (k, (name, r)) in runs.iter().enumerate() {
        let label = match &r.stall {
            Some(s) => format!("{name}: stalls at t = {} s", sig(s.t, 3)),
            None => name.clone(),
        };
        let stride = (r.samples.t.len() / 4000).max(1);
        series.push(Series::new(
            label.clone(),
            r.samples
                .t
                .iter()
                .zip(&r.samples.omega)
                .step_by(stride)
                .map(|(t, w)| (*t, *w))
                .collect(),
            k,
            Mark::Line,
        ));
        revs.push(Series::new(
            label,
            r.samples
                .t
                .iter()
                .zip(&r.samples.phi)
                .step_by(stride)
                .map(|(t, p)| (*t, (p - r.samples.phi[0]) / TAU))
                .collect(),
            k,
            Mark::Line,
        ));
    }
    let t_end = runs
        .iter()
        .filter_map(|(_, r)| r.samples.t.last().copied())
        .fold(0.0f64, f64::max)
        .max(1e-3);
    let panels = vec![
        Panel {
            title: "Start-up from rest: crank speed".into(),
            x_label: "time, s".into(),
            y_label: "ω, rad/s".into(),
            series,
            x_range: Some((0.0, t_end)),
            ..Panel::default()
        },
        Panel {
            title: "Start-up from rest: revolutions turned".into(),
            x_label: "time, s".into(),
            y_label: "revolutions".into(),
            series: revs,
            x_range: Some((0.0, t_end)),
            ..Panel::default()
        },
    ];
    write_panels_svg(path, &panels, 1000, 380)
}

fn metrics_cells(m: &Option<Metrics>) -> String {
    match m {
        Some(m) => format!(
            "{} | {} | {} | {} | {} | {} | {}",
            sig(m.omega_min, 4),
            sig(m.omega_max, 4),
            sig(m.omega_mean, 5),
            sig(m.eps_max, 4),
            sig(m.delta, 3),
            sig(m.mu, 3),
            sig(m.k_p, 3)
        ),
        None => "stalls | | | | | |".into(),
    }
}

/// The comparison of the setups with the paper's Table 1 as a Markdown table.
pub fn crank_table_markdown(r: &CrankReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| setup | M_mean, N·m | P, kW | motor × | source | ω_min | ω_max | ω_mean | \\|ε\\|max | δ | μ | k_p |\n\
         |---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|"
    );
    for row in &r.setups {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | vibrofem | {} |",
            row.name,
            sig(row.mean_moment, 5),
            sig(row.design_power / 1e3, 4),
            sig(row.torque_scale, 3),
            metrics_cells(&row.metrics)
        );
        if let (Some(p), Some(q)) = (&row.paper, &row.paper_recomputed) {
            let _ = writeln!(
                s,
                "| | | | | paper | {} | {} | {} | {} | {} | {} | {} |",
                p.omega_min, p.omega_max, p.omega_mean, p.eps_max, p.delta, p.mu, p.k_p
            );
            let _ = writeln!(
                s,
                "| | | | | paper's extremes → metrics | | | | | {} | {} | {} |",
                sig(q.delta, 4),
                sig(q.mu, 4),
                sig(q.k_p, 4)
            );
        }
    }
    s
}

/// The crank-drive report as Markdown.
pub fn crank_markdown(r: &CrankReport) -> String {
    let mut s = String::new();
    let d = &r.drive;
    let _ = writeln!(s, "# Crank drive: {}\n", r.name);
    let _ = writeln!(
        s,
        "Input: `{}`. Units SI; speeds of the crank shaft in rad/s.\n",
        r.file
    );
    let _ = writeln!(s, "## Drive\n");
    let _ = writeln!(
        s,
        "- {} cart(s), crank phases {} deg; r = {} m, l = {} m (λ = {}), q = {} kg/m, m = {} kg, F = {} N per cart",
        d.mechanism.phases.len(),
        d.mechanism
            .phases
            .iter()
            .map(|p| sig(p.to_degrees(), 4))
            .collect::<Vec<_>>()
            .join(", "),
        d.mechanism.crank_radius,
        d.mechanism.rod_length,
        sig(d.mechanism.lambda(), 3),
        d.mechanism.rod_mass_per_length,
        d.mechanism.cart_mass,
        d.mechanism.cart_resistance
    );
    let _ = writeln!(
        s,
        "- reducer i = {}, η = {}, drive inertia I_p = {} kg·m² on the motor shaft (I_p i² = {} kg·m²)",
        d.reducer.ratio,
        d.reducer.efficiency,
        d.reducer.inertia,
        sig(d.reducer.inertia * d.reducer.ratio * d.reducer.ratio, 4)
    );
    let _ = writeln!(
        s,
        "- reduced inertia {}–{} kg·m²; resisting moment {}–{} N·m",
        sig(r.inertia_range[0], 4),
        sig(r.inertia_range[1], 4),
        sig(r.resisting_range[0], 4),
        sig(r.resisting_range[1], 4)
    );
    let _ = writeln!(
        s,
        "- mean resisting moment {} N·m (closed form n·2Fr/π = {} N·m); design power M_mean·ω/η at {} rad/s: {} kW\n",
        sig(r.mean_resisting_moment, 6),
        sig(r.mean_resisting_moment_closed_form, 6),
        r.design_speed,
        sig(r.design_power / 1e3, 4)
    );
    let m = &r.motor;
    let _ = writeln!(s, "## Motor ({})\n", law_name(d.motor.law));
    if let (Some(w), Some(t)) = (m.nominal_speed, m.torque_at_nominal) {
        let _ = writeln!(
            s,
            "- at the nominal speed {w} rad/s: {} N·m (catalogue {})",
            sig(t, 4),
            m.catalogue_nominal_torque
                .map(|v| format!("{v} N·m"))
                .unwrap_or("–".into())
        );
    }
    let _ = writeln!(
        s,
        "- at standstill: Kloss {} N·m (catalogue starting torque {}); the law used gives {} N·m, i.e. {} N·m at the crank",
        sig(m.kloss_at_standstill, 3),
        m.catalogue_starting_torque
            .map(|v| format!("{v} N·m"))
            .unwrap_or("–".into()),
        sig(m.torque_at_standstill, 4),
        sig(m.driving_moment_at_rest, 4)
    );
    let _ = writeln!(
        s,
        "- at the critical speed: {} N·m at the crank\n",
        sig(m.driving_moment_at_critical, 4)
    );
    let _ = writeln!(s, "## Steady state from {} rad/s\n", sig(r.start_speed, 4));
    let _ = writeln!(
        s,
        "| integrator | revolutions | steady | ω_min | ω_max | ω_mean (2π/T) | \\|ε\\|max | δ | μ | k_p | midrange | angle mean |\n\
         |---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for run in [&r.baranov, &r.energy_form] {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} |",
            run.method,
            run.revolutions,
            if run.converged { "yes" } else { "no" },
            metrics_cells(&run.metrics),
            run.omega_midrange.map(|v| sig(v, 5)).unwrap_or_default(),
            run.omega_angle_mean.map(|v| sig(v, 5)).unwrap_or_default()
        );
    }
    for run in [&r.baranov, &r.energy_form] {
        if let Some(st) = &run.stall {
            let _ = writeln!(s, "\n**{}: {}**", run.method, st.message);
        }
    }
    let _ = writeln!(
        s,
        "\nBaranov's step is first order in Δφ; the adaptive integrator holds a local error of rtol per step. \
         ω_mean is the time mean 2π/T of the revolution.\n"
    );
    if !r.setups.is_empty() {
        let _ = writeln!(
            s,
            "## Setups against the paper's Table 1\n\nAdaptive integrator, steady revolution from {} rad/s. \
             \"motor ×\" is the factor on the motor torque (\"power\": the ratio of mean resisting moments). \
             The paper's rows show its printed values and the metrics recomputed from its extremes.\n",
            sig(r.start_speed, 4)
        );
        s.push_str(&crank_table_markdown(r));
        for row in &r.setups {
            if let Some(m) = &row.stall {
                let _ = writeln!(s, "\n- {}: {m}", row.name);
            }
        }
        s.push('\n');
    }
    let _ = writeln!(
        s,
        "## Start-up from rest\n\nTime domain, (φ, ω) by Dormand–Prince; the cart resistance holds the drive at rest \
         while the motor cannot move it.\n"
    );
    let _ = writeln!(
        s,
        "| case | outcome | time to 95 % of ω_mean, s | revolutions by then | steady ω_mean | δ | μ |\n|---|---|---:|---:|---:|---:|---:|"
    );
    for st in &r.startup {
        let outcome = match &st.stall {
            Some(x) => format!("stalls at t = {} s", sig(x.t, 3)),
            None => format!("runs up ({} revolutions in all)", sig(st.revolutions, 3)),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} |",
            st.case,
            outcome,
            st.time_to_95.map(|v| sig(v, 3)).unwrap_or("–".into()),
            st.revolutions_to_95.map(|v| sig(v, 3)).unwrap_or("–".into()),
            st.metrics.map(|m| sig(m.omega_mean, 5)).unwrap_or("–".into()),
            st.metrics.map(|m| sig(m.delta, 3)).unwrap_or("–".into()),
            st.metrics.map(|m| sig(m.mu, 3)).unwrap_or("–".into()),
        );
    }
    for st in &r.startup {
        if let Some(x) = &st.stall {
            let _ = writeln!(s, "\n- {}: {}", st.case, x.message);
        }
    }
    if !r.notes.is_empty() {
        let _ = writeln!(s, "\n## Notes\n");
        for n in &r.notes {
            let _ = writeln!(s, "- {n}");
        }
    }
    let _ = writeln!(s, "\n## Plots\n");
    for o in &r.outputs {
        let name = Path::new(o)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.ends_with(".svg") {
            let _ = writeln!(s, "![{name}]({name})");
        }
    }
    s
}

/// Write `report.json` and `report.md` into `out`, and print the JSON (`--json`) or the text.
fn publish<T: Serialize>(out: &Path, r: &T, markdown: &str, text: &str, json_out: bool) -> Result<()> {
    let json = to_json(r)?;
    write_file(&out.join("report.json"), &json)?;
    write_file(&out.join("report.md"), markdown)?;
    if json_out {
        println!("{json}");
    } else {
        print!("{text}");
    }
    Ok(())
}

/// Runs `vibrofem crank-drive`.
pub fn run_crank_drive(a: &CrankDriveArgs) -> Result<i32> {
    let c = match &a.file {
        Some(f) => CrankCase::from_toml(f)?,
        None => CrankCase::builtin()?,
    };
    make_dir(&a.out)?;
    let mut r = crank_analysis(&c, Some(&a.out))?;
    r.outputs.push(a.out.join("report.md").display().to_string());
    r.outputs.push(a.out.join("report.json").display().to_string());
    publish(&a.out, &r, &crank_markdown(&r), &crank_text(&r), a.json)?;
    if let Some(st) = &r.energy_form.stall {
        eprintln!("error: {}", st.message);
        return Ok(2);
    }
    Ok(0)
}

fn crank_text(r: &CrankReport) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "crank drive   {}", r.name);
    let _ = writeln!(
        s,
        "mean resisting moment   {} N·m   design power {} kW",
        sig(r.mean_resisting_moment, 5),
        sig(r.design_power / 1e3, 4)
    );
    let _ = writeln!(
        s,
        "reduced inertia         {}–{} kg·m²",
        sig(r.inertia_range[0], 4),
        sig(r.inertia_range[1], 4)
    );
    for run in [&r.baranov, &r.energy_form] {
        match (&run.metrics, &run.stall) {
            (Some(m), _) => {
                let _ = writeln!(
                    s,
                    "{:<36} ω {}–{} rad/s, mean {}, |ε|max {} rad/s²: δ = {}, μ = {}, k_p = {}",
                    run.method,
                    sig(m.omega_min, 4),
                    sig(m.omega_max, 4),
                    sig(m.omega_mean, 5),
                    sig(m.eps_max, 4),
                    sig(m.delta, 3),
                    sig(m.mu, 3),
                    sig(m.k_p, 3)
                );
            }
            (None, Some(st)) => {
                let _ = writeln!(s, "{:<36} {}", run.method, st.message);
            }
            (None, None) => {}
        }
    }
    if !r.setups.is_empty() {
        let _ = writeln!(
            s,
            "\nsetup                                   ω_mean     δ       μ      k_p   (paper δ, μ, k_p)"
        );
        for row in &r.setups {
            let p = row
                .paper
                .map(|p| format!("({}, {}, {})", p.delta, p.mu, p.k_p))
                .unwrap_or_default();
            match &row.metrics {
                Some(m) => {
                    let _ = writeln!(
                        s,
                        "{:<38} {:>7} {:>7} {:>7} {:>7}   {p}",
                        row.name,
                        sig(m.omega_mean, 5),
                        sig(m.delta, 3),
                        sig(m.mu, 3),
                        sig(m.k_p, 3)
                    );
                }
                None => {
                    let _ = writeln!(s, "{:<38} stalls   {p}", row.name);
                }
            }
        }
    }
    let _ = writeln!(s, "\nstart-up from rest:");
    for st in &r.startup {
        match &st.stall {
            Some(x) => {
                let _ = writeln!(s, "  {}: {}", st.case, x.message);
            }
            None => {
                let _ = writeln!(
                    s,
                    "  {}: 95 % of the mean speed after {} s ({} revolutions)",
                    st.case,
                    st.time_to_95.map(|v| sig(v, 3)).unwrap_or("–".into()),
                    st.revolutions_to_95.map(|v| sig(v, 3)).unwrap_or("–".into())
                );
            }
        }
    }
    for n in &r.notes {
        let _ = writeln!(s, "note: {n}");
    }
    if let Some(md) = r.outputs.iter().find(|o| o.ends_with("report.md")) {
        let _ = writeln!(s, "\nreport: {md} (plots beside it)");
    }
    s
}

// =============================================================================================
// Autobalancer

/// `vibrofem autobalancer [FILE.toml]`.
#[derive(Debug, Clone, clap::Args)]
pub struct AutobalancerArgs {
    /// Autobalancer file (TOML, `[machine] kind = "autobalancer"`); default: a plausible 125 mm
    /// grinder, built in (scenes/machines/grinder_autobalancer.toml).
    pub file: Option<PathBuf>,
    /// Folder for report.md, report.json and the SVG plots.
    #[arg(short, long, default_value = "vibrofem-autobalancer")]
    pub out: PathBuf,
    /// Print the JSON report on stdout instead of the summary.
    #[arg(long)]
    pub json: bool,
}

/// Closed-form figures of the grinder.
#[derive(Debug, Clone, Serialize)]
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
    /// Linear criterion at idle: ω > ω_0.
    pub balances_idle: bool,
    /// Linear criterion while cutting: ω > ω_0 (cutting).
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

/// One operating run with and without the balls.
#[derive(Debug, Clone, Serialize)]
pub struct OperatingRun {
    /// "idle" or "cutting".
    pub case: String,
    /// Speed, rad/s.
    pub speed: f64,
    /// With the balls.
    pub with_balls: SteadyEnd,
    /// Without the balls.
    pub without_balls: SteadyEnd,
    /// Balanced (residual below the threshold).
    pub balanced: bool,
}

/// Run-up figures.
#[derive(Debug, Clone, Serialize)]
pub struct RunupSummary {
    /// Ramp time, s.
    pub ramp_time: f64,
    /// Simulated time, s.
    pub duration: f64,
    /// Largest per-revolution vibration amplitude with the balls, m, and its time, s.
    pub peak_with_balls: (f64, f64),
    /// The same without the balls.
    pub peak_without_balls: (f64, f64),
    /// Disc speed at the peak with the balls, rad/s.
    pub speed_at_peak: f64,
    /// Largest residual imbalance (balls bunched with the imbalance: up to 1 + capacity).
    pub max_residual: f64,
    /// Time from which the residual stays below the balanced threshold, s.
    pub balanced_from: Option<f64>,
    /// Steady values at the end, with the balls.
    pub end: SteadyEnd,
}

/// The autobalancer report (`report.json`).
#[derive(Debug, Clone, Serialize)]
pub struct AutobalancerReport {
    /// Input file.
    pub file: String,
    /// Machine name.
    pub name: String,
    /// The grinder.
    pub grinder: Grinder,
    /// Cutting.
    pub cutting: Option<Cutting>,
    /// Closed-form figures.
    pub figures: AutobalancerFigures,
    /// Operating runs (idle, cutting).
    pub operating: Vec<OperatingRun>,
    /// Cutting at the operating speed with c_r as fractions of the bound (if cutting is given).
    pub cutting_scan: Vec<CuttingRow>,
    /// Simulated time per sweep speed, s.
    pub sweep_duration: f64,
    /// Speed sweep at idle.
    pub sweep: Vec<SweepRow>,
    /// Highest unbalanced and lowest balanced speed of the sweep, rad/s.
    pub threshold: Option<(f64, f64)>,
    /// The same as ω/ω_0.
    pub threshold_ratio: Option<(f64, f64)>,
    /// Run-up.
    pub runup: RunupSummary,
    /// Files written.
    pub outputs: Vec<String>,
}

fn figures(g: &Grinder, cut: Option<&Cutting>) -> AutobalancerFigures {
    let w0 = g.omega0(None);
    let n = autobalancer::n_factor(g.speed, w0, g.h_tilde());
    AutobalancerFigures {
        inertia: g.inertia(),
        omega0: w0,
        omega0_rpm: w0 * 60.0 / TAU,
        omega0_cutting: cut.map(|c| g.omega0(Some(c))),
        h_tilde: g.h_tilde(),
        epsilon: g.epsilon(),
        speed: g.speed,
        speed_rpm: g.speed * 60.0 / TAU,
        ratio: g.speed / w0,
        n_factor: n,
        mean_projection: g.arm * autobalancer::mean_projection(g.speed, w0, g.h_tilde(), g.epsilon()),
        balances_idle: g.speed > w0,
        balances_cutting: cut.map(|c| g.speed > g.omega0(Some(c))),
        cr_bound: cut.map(|c| g.cr_bound(g.speed, c)),
        cr_bound_paper: cut.map(|c| g.cr_bound_paper(g.speed, c.friction)),
        capacity_ratio: g.capacity() / (g.imbalance_mass * g.imbalance_radius),
        balanced_angles_deg: g.balanced_angles().map(|a| [a[0].to_degrees(), a[1].to_degrees()]),
    }
}

fn operating(g: &Grinder, cut: Option<Cutting>, duration: f64) -> Result<OperatingRun> {
    let mut o = SimOptions::constant(g.speed, duration);
    o.cutting = cut;
    let with = autobalancer::simulate(g, &o)?;
    o.with_balls = false;
    let without = autobalancer::simulate(g, &o)?;
    Ok(OperatingRun {
        case: if cut.is_some() { "cutting" } else { "idle" }.into(),
        speed: g.speed,
        balanced: with.end.residual < BALANCED_RESIDUAL,
        with_balls: with.end,
        without_balls: without.end,
    })
}

/// Per-revolution vibration amplitude (half peak-to-peak of the disc centre over each disc
/// revolution): (time at the middle of the revolution, amplitude).
fn envelope(sim: &autobalancer::Simulation, profile: &SpeedProfile) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut rev_start = 0usize;
    let mut rev = (profile.at(sim.t[0]).0 / TAU).floor();
    for i in 1..sim.t.len() {
        let r = (profile.at(sim.t[i]).0 / TAU).floor();
        if r > rev {
            let seg = &sim.x[rev_start..=i];
            let (lo, hi) = seg
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
            out.push((0.5 * (sim.t[rev_start] + sim.t[i]), 0.5 * (hi - lo)));
            rev_start = i;
            rev = r;
        }
    }
    out
}

fn residual_history(g: &Grinder, sim: &autobalancer::Simulation) -> Vec<f64> {
    let m0r0 = g.imbalance_mass * g.imbalance_radius;
    (0..sim.t.len())
        .map(|k| {
            let (mut sx, mut sy) = (m0r0, 0.0);
            for (b, a) in g.balls.iter().zip(&sim.ball_angles) {
                sx += b.mass * b.radius * a[k].cos();
                sy += b.mass * b.radius * a[k].sin();
            }
            sx.hypot(sy) / m0r0
        })
        .collect()
}

/// Fractions of the surface-stiffness bound scanned with the nonlinear model while cutting.
pub const CUTTING_FRACTIONS: [f64; 9] = [0.25, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 1.05, 1.2];

/// Runs the autobalancer analysis of a case; with `out`, writes the SVG plots there.
pub fn autobalancer_analysis(c: &AutobalancerCase, out: Option<&Path>) -> Result<AutobalancerReport> {
    let g = &c.grinder;
    let fig = figures(g, c.cutting.as_ref());
    let mut ops = vec![operating(g, None, c.sweep.duration)?];
    if let Some(cut) = c.cutting {
        ops.push(operating(g, Some(cut), c.sweep.duration)?);
    }
    let cutting_scan = match &c.cutting {
        Some(cut) if fig.cr_bound.is_some_and(|b| b.is_finite() && b > 0.0) => {
            autobalancer::cutting_scan(g, cut, &CUTTING_FRACTIONS, c.sweep.duration)?
        }
        _ => Vec::new(),
    };
    let speeds = c.sweep.speeds(fig.omega0);
    let rows = autobalancer::sweep(g, &speeds, c.sweep.duration, None)?;
    let thr = autobalancer::threshold(&rows);
    // Run-up with and without the balls.
    let profile = SpeedProfile::Ramp {
        speed: g.speed,
        ramp_time: c.runup.ramp_time,
    };
    let mut o = SimOptions::constant(g.speed, c.runup.duration);
    o.profile = profile;
    o.record_dt = Some(c.runup.dt);
    let with = autobalancer::simulate(g, &o)?;
    o.with_balls = false;
    let without = autobalancer::simulate(g, &o)?;
    let env_w = envelope(&with, &profile);
    let env_n = envelope(&without, &profile);
    let peak = |e: &[(f64, f64)]| {
        e.iter()
            .fold((0.0f64, 0.0f64), |a, p| if p.1 > a.0 { (p.1, p.0) } else { a })
    };
    let pw = peak(&env_w);
    let res = residual_history(g, &with);
    let max_res = res.iter().copied().fold(0.0f64, f64::max);
    let balanced_from = match res.iter().rposition(|r| *r >= BALANCED_RESIDUAL) {
        Some(i) if i + 1 < res.len() => Some(with.t[i + 1]),
        Some(_) => None,
        None => Some(0.0),
    };
    let runup = RunupSummary {
        ramp_time: c.runup.ramp_time,
        duration: c.runup.duration,
        peak_with_balls: pw,
        peak_without_balls: peak(&env_n),
        speed_at_peak: profile.at(pw.1).1,
        max_residual: max_res,
        balanced_from,
        end: with.end.clone(),
    };
    let mut outputs = Vec::new();
    if let Some(dir) = out {
        let p = dir.join("sweep.svg");
        sweep_plot(&p, c, &fig, &rows)?;
        outputs.push(p.display().to_string());
        let p = dir.join("runup.svg");
        runup_plot(&p, c, &with, &env_w, &env_n, &res)?;
        outputs.push(p.display().to_string());
    }
    Ok(AutobalancerReport {
        file: c.file.clone(),
        name: c.name.clone(),
        grinder: g.clone(),
        cutting: c.cutting,
        threshold_ratio: thr.map(|(a, b)| (a / fig.omega0, b / fig.omega0)),
        figures: fig,
        operating: ops,
        cutting_scan,
        sweep_duration: c.sweep.duration,
        sweep: rows,
        threshold: thr,
        runup,
        outputs,
    })
}

fn sweep_plot(path: &Path, c: &AutobalancerCase, fig: &AutobalancerFigures, rows: &[SweepRow]) -> Result<()> {
    let floor = 1e-3; // µm: amplitudes below are drawn at the floor (balanced to rounding)
    let um = |v: f64| (v * 1e6).max(floor);
    let with: Vec<(f64, f64)> = rows.iter().map(|r| (r.ratio, um(r.amplitude_with_balls))).collect();
    let without: Vec<(f64, f64)> = rows.iter().map(|r| (r.ratio, um(r.amplitude_without_balls))).collect();
    let bal: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.balanced)
        .map(|r| (r.ratio, um(r.amplitude_with_balls)))
        .collect();
    let mut vlines = vec![(1.0, "ω = ω_0 (linear criterion)".to_string(), 5)];
    let op = fig.ratio;
    if op >= c.sweep.from_ratio && op <= c.sweep.to_ratio {
        vlines.push((op, "operating speed".to_string(), 4));
    }
    let n_balls = rows.first().map(|r| r.ball_angles_deg.len()).unwrap_or(0);
    let mut angle_series: Vec<Series> = (0..n_balls)
        .map(|i| {
            Series::new(
                format!("ball {}", i + 1),
                rows.iter().map(|r| (r.ratio, r.ball_angles_deg[i])).collect(),
                i % 5,
                Mark::Dots,
            )
        })
        .collect();
    if let Some(a) = fig.balanced_angles_deg {
        for (k, v) in a.iter().enumerate() {
            angle_series.push(Series {
                label: (k == 0).then(|| "balanced position ±(180° − arccos(m_0R_0/2mR))".to_string()),
                points: vec![(c.sweep.from_ratio, *v), (c.sweep.to_ratio, *v)],
                color: 6,
                mark: Mark::Dashed,
            });
        }
    }
    let panels = vec![
        Panel {
            title: format!(
                "Housing vibration with and without balls (ω_0 = {} rpm; operating {} rpm = {} ω_0)",
                sig(fig.omega0_rpm, 4),
                sig(fig.speed_rpm, 5),
                sig(fig.ratio, 3)
            ),
            x_label: "disc speed ω/ω_0".into(),
            y_label: "amplitude, µm (log)".into(),
            series: vec![
                Series::new("without balls", without, 1, Mark::Line),
                Series::new("with balls (below 0.001 µm drawn at 0.001)", with, 0, Mark::Line),
                Series::new(
                    format!("balanced (residual < {} % of the imbalance)", BALANCED_RESIDUAL * 100.0),
                    bal,
                    2,
                    Mark::Circles,
                ),
            ],
            log_y: true,
            x_range: Some((c.sweep.from_ratio, c.sweep.to_ratio)),
            vlines: vlines.clone(),
            ..Panel::default()
        },
        Panel {
            title: format!(
                "Ball angles relative to the imbalance after {} s at each speed",
                sig(c.sweep.duration, 3)
            ),
            x_label: "disc speed ω/ω_0".into(),
            y_label: "angle, deg".into(),
            series: angle_series,
            x_range: Some((c.sweep.from_ratio, c.sweep.to_ratio)),
            y_range: Some((-200.0, 200.0)),
            vlines: vec![(1.0, String::new(), 5)],
            ..Panel::default()
        },
    ];
    write_panels_svg(path, &panels, 1000, 420)
}

fn runup_plot(
    path: &Path,
    c: &AutobalancerCase,
    with: &autobalancer::Simulation,
    env_w: &[(f64, f64)],
    env_n: &[(f64, f64)],
    res: &[f64],
) -> Result<()> {
    let stride = (with.t.len() / 6000).max(1);
    let rpm: Vec<(f64, f64)> = with
        .t
        .iter()
        .zip(&with.speed)
        .step_by(stride)
        .map(|(t, w)| (*t, w * 60.0 / TAU))
        .collect();
    let mut angle_series = Vec::new();
    for (i, a) in with.ball_angles.iter().enumerate() {
        // Wrapped to (−180°, 180°]; lines break at the wrap.
        let mut pts = Vec::new();
        let mut prev: Option<f64> = None;
        for (t, v) in with.t.iter().zip(a).step_by(stride) {
            let d = autobalancer::wrap_deg(v.to_degrees());
            if let Some(p) = prev
                && (d - p).abs() > 180.0
            {
                pts.push((*t, f64::NAN));
            }
            pts.push((*t, d));
            prev = Some(d);
        }
        angle_series.push(Series::new(format!("ball {}", i + 1), pts, i % 5, Mark::Line));
    }
    let resid: Vec<(f64, f64)> = with.t.iter().zip(res).step_by(stride).map(|(t, r)| (*t, *r)).collect();
    let t_end = c.runup.duration;
    let panels = vec![
        Panel {
            title: format!(
                "Run-up from rest to {} rpm in {} s: disc speed",
                sig(c.grinder.speed * 60.0 / TAU, 5),
                sig(c.runup.ramp_time, 3)
            ),
            x_label: "time, s".into(),
            y_label: "speed, rpm".into(),
            series: vec![Series::new("disc speed", rpm, 5, Mark::Line)],
            x_range: Some((0.0, t_end)),
            ..Panel::default()
        },
        Panel {
            title: "Housing vibration at the disc centre, per disc revolution (half peak-to-peak)".into(),
            x_label: "time, s".into(),
            y_label: "amplitude, µm (log)".into(),
            series: vec![
                Series::new(
                    "without balls",
                    env_n.iter().map(|p| (p.0, (p.1 * 1e6).max(1e-3))).collect(),
                    1,
                    Mark::Line,
                ),
                Series::new(
                    "with balls",
                    env_w.iter().map(|p| (p.0, (p.1 * 1e6).max(1e-3))).collect(),
                    0,
                    Mark::Line,
                ),
            ],
            log_y: true,
            x_range: Some((0.0, t_end)),
            ..Panel::default()
        },
        Panel {
            title: "Ball angles relative to the imbalance".into(),
            x_label: "time, s".into(),
            y_label: "angle, deg".into(),
            series: angle_series,
            x_range: Some((0.0, t_end)),
            y_range: Some((-200.0, 200.0)),
            ..Panel::default()
        },
        Panel {
            title: "Residual imbalance |m_0R_0 + Σ m_iR_i e^{iα_i}| / m_0R_0 (1 without balls; bunched balls add)"
                .into(),
            x_label: "time, s".into(),
            y_label: "residual".into(),
            series: vec![Series::new("residual", resid, 3, Mark::Line)],
            x_range: Some((0.0, t_end)),
            ..Panel::default()
        },
    ];
    write_panels_svg(path, &panels, 1000, 320)
}

/// Amplitude in µm; below 1e-12 m (rounding of the integration) as "< 1e-6 µm".
fn um(v: f64) -> String {
    if v.abs() < 1e-12 {
        "< 1e-6 µm".into()
    } else {
        format!("{} µm", sig(v * 1e6, 3))
    }
}

/// The autobalancer report as Markdown.
pub fn autobalancer_markdown(r: &AutobalancerReport) -> String {
    let mut s = String::new();
    let g = &r.grinder;
    let f = &r.figures;
    let _ = writeln!(s, "# Autobalancer: {}\n", r.name);
    let _ = writeln!(s, "Input: `{}`. Units SI; angles relative to the imbalance.\n", r.file);
    let _ = writeln!(s, "## Grinder\n");
    let _ = writeln!(
        s,
        "- rocker: arm l = {} m, J_0 = {} kg·m², hinge c = {} N/m, h = {} N·s/m",
        g.arm,
        g.rocker_inertia,
        sig(g.stiffness, 4),
        sig(g.damping, 4)
    );
    let _ = writeln!(
        s,
        "- disc: m_d = {} kg, J_d = {} kg·m², R = {} m; imbalance {} g at {} mm ({} g·mm) at {}°; speed {} rpm",
        g.disc_mass,
        g.disc_inertia,
        g.disc_radius,
        sig(g.imbalance_mass * 1e3, 3),
        sig(g.imbalance_radius * 1e3, 3),
        sig(g.imbalance_mass * g.imbalance_radius * 1e6, 3),
        sig(g.imbalance_angle.to_degrees(), 3),
        sig(f.speed_rpm, 5)
    );
    for (i, b) in g.balls.iter().enumerate() {
        let _ = writeln!(
            s,
            "- ball {}: {} g on a {} mm race, drag {} N·s/m, starts at {}°",
            i + 1,
            sig(b.mass * 1e3, 3),
            sig(b.radius * 1e3, 3),
            b.drag,
            sig(b.initial_angle.to_degrees(), 3)
        );
    }
    if let Some(c) = &r.cutting {
        let _ = writeln!(
            s,
            "- cutting: c_r = {} N/m, f_r = {}, θ = {}°, moment {} N·m",
            sig(c.surface_stiffness, 3),
            c.friction,
            sig(c.contact_angle.to_degrees(), 3),
            c.moment
        );
    }
    let _ = writeln!(s, "\n## Linear criterion (closed form)\n");
    let _ = writeln!(
        s,
        "- J = {} kg·m², ω_0 = √(c l²/J) = {} rad/s ({} rpm), h̃ = {} 1/s, ε = l m_0 R_0/J = {}",
        sig(f.inertia, 4),
        sig(f.omega0, 4),
        sig(f.omega0_rpm, 4),
        sig(f.h_tilde, 4),
        sig(f.epsilon, 3)
    );
    let _ = writeln!(
        s,
        "- operating ω/ω_0 = {}: N = {}, mean projection of the disc centre on the imbalance l ε N/2 = {} → {}",
        sig(f.ratio, 3),
        sig(f.n_factor, 4),
        um(f.mean_projection),
        if f.balances_idle {
            "balances (ω > ω_0)"
        } else {
            "does not balance (ω ≤ ω_0)"
        }
    );
    if let (Some(w0c), Some(b), Some(cr), Some(crp)) =
        (f.omega0_cutting, f.balances_cutting, f.cr_bound, f.cr_bound_paper)
    {
        let _ = writeln!(
            s,
            "- cutting: ω_0' = {} rad/s → {}; surface stiffness bound c_r < {} N/m at the given θ, {} N/m by the seed's closed form (worst θ, cos θ = −f_r/2)",
            sig(w0c, 4),
            if b { "balances" } else { "does not balance" },
            sig(cr, 4),
            sig(crp, 4)
        );
    }
    if let Some(a) = f.balanced_angles_deg {
        let _ = writeln!(
            s,
            "- ball capacity Σ m R = {} × m_0 R_0; balanced balls at {}° and {}°",
            sig(f.capacity_ratio, 3),
            sig(a[0], 4),
            sig(a[1], 4)
        );
    }
    let _ = writeln!(s, "\n## Nonlinear model at the operating speed\n");
    let _ = writeln!(
        s,
        "| case | amplitude with balls | without balls | ball angles, deg | residual | balanced |\n|---|---:|---:|---|---:|---|"
    );
    for o in &r.operating {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} |",
            o.case,
            um(o.with_balls.amplitude),
            um(o.without_balls.amplitude),
            o.with_balls
                .ball_angles_deg
                .iter()
                .map(|a| sig(*a, 4))
                .collect::<Vec<_>>()
                .join(", "),
            sig(o.with_balls.residual, 2),
            if o.balanced { "yes" } else { "no" }
        );
    }
    if !r.cutting_scan.is_empty() {
        let _ = writeln!(
            s,
            "\n## Cutting: surface stiffness against its bound\n\nNonlinear model at the operating speed, c_r as a fraction \
             of the bound (at the file's contact angle); ω_0' is the rocker frequency while cutting.\n\n\
             | c_r / bound | c_r, N/m | ω/ω_0' | amplitude with balls | residual | drift, deg/s | balanced |\n\
             |---:|---:|---:|---:|---:|---:|---|"
        );
        for row in &r.cutting_scan {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} |",
                sig(row.fraction_of_bound, 3),
                sig(row.surface_stiffness, 4),
                sig(row.ratio, 4),
                um(row.amplitude_with_balls),
                sig(row.residual, 2),
                sig(row.drift_deg_s, 2),
                if row.balanced { "yes" } else { "no" }
            );
        }
    }
    let _ = writeln!(
        s,
        "\n## Speed sweep at idle\n\nEach speed: {} s from the balls' initial angles, steady values over the last 10 revolutions. \
         Balanced = residual imbalance below {} % of the disc's.\n",
        sig(r.sweep_duration, 3),
        BALANCED_RESIDUAL * 100.0
    );
    let _ = writeln!(
        s,
        "| ω/ω_0 | rpm | with balls | without balls | ball angles, deg | residual | drift, deg/s | balanced | linear criterion |\n\
         |---:|---:|---:|---:|---|---:|---:|---|---|"
    );
    for row in &r.sweep {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            sig(row.ratio, 3),
            sig(row.speed_rpm, 4),
            um(row.amplitude_with_balls),
            um(row.amplitude_without_balls),
            row.ball_angles_deg
                .iter()
                .map(|a| sig(*a, 3))
                .collect::<Vec<_>>()
                .join(", "),
            sig(row.residual, 2),
            sig(row.drift_deg_s, 2),
            if row.balanced { "yes" } else { "no" },
            if row.predicted { "balances" } else { "no" }
        );
    }
    match r.threshold_ratio {
        Some((a, b)) => {
            let _ = writeln!(
                s,
                "\nThreshold: unbalanced at ω/ω_0 = {}, balanced from {} on (linear criterion: 1).",
                sig(a, 3),
                sig(b, 3)
            );
        }
        None => {
            let _ = writeln!(
                s,
                "\nNo threshold inside the sweep (all rows balanced, or the fastest not)."
            );
        }
    }
    let u = &r.runup;
    let _ = writeln!(s, "\n## Run-up from rest\n");
    let _ = writeln!(
        s,
        "The disc accelerates linearly to the operating speed in {} s; the balls start at rest on the disc.\n",
        sig(u.ramp_time, 3)
    );
    let _ = writeln!(
        s,
        "- largest vibration with balls {} at t = {} s ({} rpm); without balls {} at t = {} s",
        um(u.peak_with_balls.0),
        sig(u.peak_with_balls.1, 3),
        sig(u.speed_at_peak * 60.0 / TAU, 4),
        um(u.peak_without_balls.0),
        sig(u.peak_without_balls.1, 3)
    );
    let _ = writeln!(
        s,
        "- largest residual imbalance {} × m_0 R_0 (balls bunched with the imbalance while passing ω_0)",
        sig(u.max_residual, 3)
    );
    let _ = writeln!(
        s,
        "- balanced from t = {} on; at the end: amplitude {}, balls at {}°\n",
        u.balanced_from
            .map(|t| format!("{} s", sig(t, 3)))
            .unwrap_or("– (not within the run)".into()),
        um(u.end.amplitude),
        u.end
            .ball_angles_deg
            .iter()
            .map(|a| sig(*a, 4))
            .collect::<Vec<_>>()
            .join("°, ")
    );
    let _ = writeln!(s, "## Plots\n");
    for o in &r.outputs {
        let name = Path::new(o)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.ends_with(".svg") {
            let _ = writeln!(s, "![{name}]({name})");
        }
    }
    s
}

fn autobalancer_text(r: &AutobalancerReport) -> String {
    let mut s = String::new();
    let f = &r.figures;
    let _ = writeln!(s, "autobalancer   {}", r.name);
    let _ = writeln!(
        s,
        "ω_0 = {} rad/s ({} rpm), operating {} rpm = {} ω_0: {}",
        sig(f.omega0, 4),
        sig(f.omega0_rpm, 4),
        sig(f.speed_rpm, 5),
        sig(f.ratio, 3),
        if f.balances_idle {
            "ω > ω_0, balances"
        } else {
            "ω ≤ ω_0, does not balance"
        }
    );
    if let (Some(cr), Some(crp), Some(w0c)) = (f.cr_bound, f.cr_bound_paper, f.omega0_cutting) {
        let _ = writeln!(
            s,
            "cutting: ω_0' = {} rad/s; c_r bound {} N/m (closed form, worst θ: {} N/m)",
            sig(w0c, 4),
            sig(cr, 4),
            sig(crp, 4)
        );
    }
    for o in &r.operating {
        let _ = writeln!(
            s,
            "{:<8} amplitude with balls {}, without {}; balls at {}°; {}",
            o.case,
            um(o.with_balls.amplitude),
            um(o.without_balls.amplitude),
            o.with_balls
                .ball_angles_deg
                .iter()
                .map(|a| sig(*a, 4))
                .collect::<Vec<_>>()
                .join("°, "),
            if o.balanced { "balanced" } else { "not balanced" }
        );
    }
    if let Some((a, b)) = r.threshold_ratio {
        let _ = writeln!(
            s,
            "sweep: unbalanced up to ω/ω_0 = {}, balanced from {} (criterion: 1)",
            sig(a, 3),
            sig(b, 3)
        );
    }
    let u = &r.runup;
    let _ = writeln!(
        s,
        "run-up: peak {} with balls (without {}), balanced from t = {}",
        um(u.peak_with_balls.0),
        um(u.peak_without_balls.0),
        u.balanced_from
            .map(|t| format!("{} s", sig(t, 3)))
            .unwrap_or("–".into())
    );
    if let Some(md) = r.outputs.iter().find(|o| o.ends_with("report.md")) {
        let _ = writeln!(s, "\nreport: {md} (plots beside it)");
    }
    s
}

/// Runs `vibrofem autobalancer`.
pub fn run_autobalancer(a: &AutobalancerArgs) -> Result<i32> {
    let c = match &a.file {
        Some(f) => AutobalancerCase::from_toml(f)?,
        None => AutobalancerCase::builtin()?,
    };
    make_dir(&a.out)?;
    let mut r = autobalancer_analysis(&c, Some(&a.out))?;
    r.outputs.push(a.out.join("report.md").display().to_string());
    r.outputs.push(a.out.join("report.json").display().to_string());
    publish(&a.out, &r, &autobalancer_markdown(&r), &autobalancer_text(&r), a.json)?;
    Ok(0)
}

// =============================================================================================
// Test-stand data

/// The built-in example data (scenes/machines/balancer_test_stand.csv).
pub const BALANCER_DATA_DEFAULT_CSV: &str = include_str!("../../scenes/machines/balancer_test_stand.csv");

/// `vibrofem balancer-data [FILE.csv]`.
#[derive(Debug, Clone, clap::Args)]
pub struct BalancerDataArgs {
    /// Test-stand CSV (header `record,label,x,y`, first record `version,balancer-data,1`);
    /// default: the built-in example (scenes/machines/balancer_test_stand.csv).
    pub file: Option<PathBuf>,
    /// Folder for report.md, report.json and the scatter plot.
    #[arg(short, long, default_value = "vibrofem-balancer-data")]
    pub out: PathBuf,
    /// Print the JSON report on stdout instead of the summary.
    #[arg(long)]
    pub json: bool,
}

/// The balancer-data report (`report.json`).
#[derive(Debug, Clone, Serialize)]
pub struct BalancerDataReport {
    /// Input file.
    pub file: String,
    /// The reductions.
    pub reduction: Reduction,
    /// Files written.
    pub outputs: Vec<String>,
}

/// Parses and reduces balancer-data CSV text; with `out`, writes the scatter plot there.
pub fn balancer_data_analysis(file: &str, text: &str, out: Option<&Path>) -> Result<BalancerDataReport> {
    let d = balancer_data::parse_csv(file, text)?;
    let red = balancer_data::reduce(file, &d)?;
    let mut outputs = Vec::new();
    if let (Some(dir), Some(sc)) = (out, &red.scatter) {
        let p = dir.join("scatter.svg");
        let g_mm = |v: f64| v * 1e6; // kg·m → g·mm
        let pts: Vec<(f64, f64)> = sc.rows.iter().map(|r| (g_mm(r.sx), g_mm(r.sy))).collect();
        let circle: Vec<(f64, f64)> = (0..=180)
            .map(|k| {
                let a = TAU * k as f64 / 180.0;
                (
                    g_mm(sc.sx_mean + sc.ds_mean * a.cos()),
                    g_mm(sc.sy_mean + sc.ds_mean * a.sin()),
                )
            })
            .collect();
        let panels = vec![Panel {
            title: format!(
                "Residual imbalance over {} re-mountings: η = mean ΔS / S_c = {}",
                sc.rows.len(),
                pct(sc.eta)
            ),
            x_label: "S_x, g·mm".into(),
            y_label: "S_y, g·mm".into(),
            series: vec![
                Series::new("S_i per mounting", pts, 0, Mark::Dots),
                Series::new(
                    "mean (S_xc, S_yc)",
                    vec![(g_mm(sc.sx_mean), g_mm(sc.sy_mean))],
                    1,
                    Mark::Circles,
                ),
                Series::new("mean ΔS around the mean", circle, 6, Mark::Dashed),
            ],
            ..Panel::default()
        }];
        write_panels_svg(&p, &panels, 900, 700)?;
        outputs.push(p.display().to_string());
    }
    Ok(BalancerDataReport {
        file: file.to_string(),
        reduction: red,
        outputs,
    })
}

/// The balancer-data report as Markdown.
pub fn balancer_data_markdown(r: &BalancerDataReport) -> String {
    let mut s = String::new();
    let red = &r.reduction;
    let _ = writeln!(s, "# Autobalancer test-stand data\n\nInput: `{}`.\n", r.file);
    if let Some((m, rad)) = red.ball {
        let _ = writeln!(s, "Balls: {} g on a {} mm race.\n", sig(m * 1e3, 4), sig(rad * 1e3, 4));
    }
    if !red.correction.is_empty() {
        let _ = writeln!(
            s,
            "## Correction cut of the housing\n\nS = 2 m R |cos(α0/2)|, cut mass S/L at L = {} mm.\n\n\
             | test | α0, deg | S, g·mm | cut mass, g |\n|---|---:|---:|---:|",
            red.cut_radius.map(|l| sig(l * 1e3, 4)).unwrap_or_default()
        );
        for c in &red.correction {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} |",
                c.label,
                sig(c.spread_deg, 4),
                sig(c.imbalance * 1e6, 4),
                sig(c.cut_mass * 1e3, 4)
            );
        }
        s.push('\n');
    }
    if let Some(sc) = &red.scatter {
        let _ = writeln!(
            s,
            "## Imbalance scatter over re-mountings\n\n| mounting | S_x, g·mm | S_y, g·mm | S, g·mm | ΔS, g·mm | η_i |\n|---|---:|---:|---:|---:|---:|"
        );
        for row in &sc.rows {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} |",
                row.label,
                sig(row.sx * 1e6, 4),
                sig(row.sy * 1e6, 4),
                sig(row.s * 1e6, 4),
                sig(row.ds * 1e6, 4),
                pct(row.eta)
            );
        }
        let _ = writeln!(
            s,
            "\nMeans: S_xc = {} g·mm, S_yc = {} g·mm, S_c = {} g·mm, mean ΔS = {} g·mm. \
             **η = {}** (η_i from {} to {}).\n",
            sig(sc.sx_mean * 1e6, 4),
            sig(sc.sy_mean * 1e6, 4),
            sig(sc.s_mean * 1e6, 4),
            sig(sc.ds_mean * 1e6, 4),
            pct(sc.eta),
            pct(sc.eta_min),
            pct(sc.eta_max)
        );
    }
    if let Some(se) = &red.sensitivity {
        let _ = writeln!(
            s,
            "## Sensitivity\n\nη = m_min/m_max = {} g / {} g = **{}**\n",
            sig(se.m_min * 1e3, 4),
            sig(se.m_max * 1e3, 4),
            pct(se.eta)
        );
    }
    if !red.efficiency.is_empty() {
        let _ = writeln!(
            s,
            "## Efficiency\n\n| case | a_max, m/s² | a, m/s² | e = (a_max − a)/a_max |\n|---|---:|---:|---:|"
        );
        for e in &red.efficiency {
            let _ = writeln!(s, "| {} | {} | {} | **{}** |", e.label, e.a_max, e.a, pct(e.efficiency));
        }
        s.push('\n');
    }
    for o in &r.outputs {
        let name = Path::new(o)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.ends_with(".svg") {
            let _ = writeln!(s, "![{name}]({name})");
        }
    }
    s
}

fn balancer_data_text(r: &BalancerDataReport) -> String {
    let mut s = String::new();
    let red = &r.reduction;
    let _ = writeln!(s, "balancer test-stand data   {}", r.file);
    for c in &red.correction {
        let _ = writeln!(
            s,
            "correction cut '{}': α0 = {}°, S = {} g·mm, cut {} g",
            c.label,
            sig(c.spread_deg, 4),
            sig(c.imbalance * 1e6, 4),
            sig(c.cut_mass * 1e3, 4)
        );
    }
    if let Some(sc) = &red.scatter {
        let _ = writeln!(
            s,
            "imbalance scatter over {} mountings: S_c = {} g·mm, η = {} ({}–{})",
            sc.rows.len(),
            sig(sc.s_mean * 1e6, 4),
            pct(sc.eta),
            pct(sc.eta_min),
            pct(sc.eta_max)
        );
    }
    if let Some(se) = &red.sensitivity {
        let _ = writeln!(s, "sensitivity m_min/m_max = {}", pct(se.eta));
    }
    for e in &red.efficiency {
        let _ = writeln!(
            s,
            "efficiency '{}': ({} − {})/{} = {}",
            e.label,
            e.a_max,
            e.a,
            e.a_max,
            pct(e.efficiency)
        );
    }
    if let Some(md) = r.outputs.iter().find(|o| o.ends_with("report.md")) {
        let _ = writeln!(s, "\nreport: {md}");
    }
    s
}

/// Runs `vibrofem balancer-data`.
pub fn run_balancer_data(a: &BalancerDataArgs) -> Result<i32> {
    let (name, text) = match &a.file {
        Some(f) => (
            f.display().to_string(),
            std::fs::read_to_string(f).map_err(|e| Error::io(f, e))?,
        ),
        None => (
            "scenes/machines/balancer_test_stand.csv (built in)".to_string(),
            BALANCER_DATA_DEFAULT_CSV.to_string(),
        ),
    };
    make_dir(&a.out)?;
    let mut r = balancer_data_analysis(&name, &text, Some(&a.out))?;
    r.outputs.push(a.out.join("report.md").display().to_string());
    r.outputs.push(a.out.join("report.json").display().to_string());
    publish(&a.out, &r, &balancer_data_markdown(&r), &balancer_data_text(&r), a.json)?;
    Ok(0)
}
