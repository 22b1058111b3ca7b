//! The autobalancer analysis of a case: closed-form criterion, the nonlinear model at the
//! operating speed (idle and cutting), a cutting scan, a speed sweep and a run-up; the result is
//! the `--json` document ([`AutobalancerReport`]).

use std::f64::consts::TAU;
use std::path::Path;

use serde::Serialize;

use super::case::AutobalancerCase;
pub use super::model::AutobalancerFigures;
use super::model::{
    self, BALANCED_RESIDUAL, Cutting, CuttingRow, Grinder, SimOptions, Simulation, SpeedProfile, SteadyEnd, SweepRow,
};
use super::plots;
use crate::Result;
use crate::app::machines::report_files;

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
    let n = model::n_factor(g.speed, w0, g.h_tilde());
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
        mean_projection: g.arm * model::mean_projection(g.speed, w0, g.h_tilde(), g.epsilon()),
        balls_can_cancel: g.balls_can_cancel(),
        balances_idle: g.speed > w0 && g.balls_can_cancel(),
        balances_cutting: cut.map(|c| g.speed > g.omega0(Some(c)) && g.balls_can_cancel()),
        cr_bound: cut.map(|c| g.cr_bound(g.speed, c)),
        cr_bound_paper: cut.map(|c| g.cr_bound_paper(g.speed, c.friction)),
        capacity_ratio: g.capacity() / (g.imbalance_mass * g.imbalance_radius),
        balanced_angles_deg: g.balanced_angles().map(|a| [a[0].to_degrees(), a[1].to_degrees()]),
    }
}

fn operating(g: &Grinder, cut: Option<Cutting>, duration: f64) -> Result<OperatingRun> {
    let mut o = SimOptions::constant(g.speed, duration);
    o.cutting = cut;
    let with = model::simulate(g, &o)?;
    o.with_balls = false;
    let without = model::simulate(g, &o)?;
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
fn envelope(sim: &Simulation, profile: &SpeedProfile) -> Vec<(f64, f64)> {
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

fn residual_history(g: &Grinder, sim: &Simulation) -> Vec<f64> {
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
            model::cutting_scan(g, cut, &CUTTING_FRACTIONS, c.sweep.duration)?
        }
        _ => Vec::new(),
    };
    let speeds = c.sweep.speeds(fig.omega0);
    let rows = model::sweep(g, &speeds, c.sweep.duration, None)?;
    let thr = model::threshold(&rows);
    // Run-up with and without the balls.
    let profile = SpeedProfile::Ramp {
        speed: g.speed,
        ramp_time: c.runup.ramp_time,
    };
    let mut o = SimOptions::constant(g.speed, c.runup.duration);
    o.profile = profile;
    o.record_dt = Some(c.runup.dt);
    let with = model::simulate(g, &o)?;
    o.with_balls = false;
    let without = model::simulate(g, &o)?;
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
        plots::sweep_plot(&p, c, &fig, &rows)?;
        outputs.push(p.display().to_string());
        let p = dir.join("runup.svg");
        plots::runup_plot(&p, c, &with, &env_w, &env_n, &res)?;
        outputs.push(p.display().to_string());
        outputs.extend(report_files(dir));
    }
    check_finite(c, &ops, &cutting_scan, &rows, &runup)?;
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

/// Every simulated figure is finite: a case whose values overflow the model is refused, naming
/// the file and the figure, instead of reported as `inf`/`null` with success.
fn check_finite(
    c: &AutobalancerCase,
    ops: &[OperatingRun],
    scan: &[CuttingRow],
    rows: &[SweepRow],
    u: &RunupSummary,
) -> Result<()> {
    let end = |e: &SteadyEnd| {
        let mut v = vec![e.amplitude, e.mean_displacement, e.drift_deg_s, e.residual];
        v.extend(&e.ball_angles_deg);
        v
    };
    let mut named: Vec<(&str, Vec<f64>)> = Vec::new();
    for o in ops {
        named.push(("the operating run with the balls", end(&o.with_balls)));
        named.push(("the operating run without the balls", end(&o.without_balls)));
    }
    for r in scan {
        named.push((
            "the cutting scan",
            vec![r.amplitude_with_balls, r.residual, r.drift_deg_s],
        ));
    }
    for r in rows {
        let mut v = vec![
            r.amplitude_with_balls,
            r.amplitude_without_balls,
            r.residual,
            r.drift_deg_s,
        ];
        v.extend(&r.ball_angles_deg);
        named.push(("the speed sweep", v));
    }
    let mut v = end(&u.end);
    v.extend([
        u.peak_with_balls.0,
        u.peak_without_balls.0,
        u.max_residual,
        u.speed_at_peak,
    ]);
    named.push(("the run-up", v));
    match named.iter().find(|(_, v)| v.iter().any(|x| !x.is_finite())) {
        None => Ok(()),
        Some((what, _)) => Err(crate::Error::Input {
            file: c.file.clone(),
            line: None,
            key: None,
            msg: format!(
                "{what} gives non-finite results: the grinder's values overflow double precision (check their units)"
            ),
        }),
    }
}
