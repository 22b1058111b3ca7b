//! Start-up and run-down through the isolation modes: the design's machine driven from rest by
//! a supply whose frequency runs up from zero to the mains (a frequency converter's ramp; a zero
//! ramp is a switch straight onto the mains), holds, runs down to zero and goes off, integrated
//! by [`crate::app::dynamics::transient::simulate_linear`] (Dormand–Prince, no step across a
//! kink of the rectified pull).
//!
//! Reported: the peak isolator deflection, the peak floor force (the isolators' spring and
//! dashpot forces together), the peak relative motion across the leaves (what the magnet gap
//! sees), each against its steady value at full frequency, and the time the excitation spends in
//! each mode's half-power band, f_k (1 ± ζ_k), on the way up.
//!
//! The model is the two-mass machine of the chain's run (m1, m2, c12, c13 as reported, the design
//! file's damping): for the symmetric layout its two modes are the vertical isolation (bounce)
//! and working modes of the 3D machine. Roll, pitch and sway are not excited by a symmetric
//! vertical pull and are not in it.

use super::file::Design;
use super::results::DesignReport;
use crate::app::dynamics::ode::Dopri5Options;
use crate::app::dynamics::transient::{Ramp, simulate_linear};
use crate::app::report::{Block, Cell, Column, Section, Table};
use crate::{Error, Result};
use serde::Serialize;
use std::f64::consts::TAU;

/// Run-up and run-down time of the built-in study, s (a frequency converter's soft start).
pub const RAMP_S: f64 = 2.0;
/// Time at full frequency between them, s.
pub const HOLD_S: f64 = 1.0;
/// Samples per period of the full-frequency pull (peaks read within 1 − cos(π/40) = 0.3 %).
pub const SAMPLES_PER_PERIOD: f64 = 40.0;

/// What a start-up and run-down gives.
#[derive(Clone, Debug, Serialize)]
pub struct Startup {
    /// Run-up (= run-down) time, s.
    pub ramp_s: f64,
    /// Peak isolator deflection over the whole record, m, and its steady amplitude at full
    /// frequency (last period before the run-down).
    pub peak_isolator_deflection: f64,
    /// Steady.
    pub steady_isolator_deflection: f64,
    /// Peak floor force (all isolators, spring + dashpot), N, and its steady amplitude.
    pub peak_floor_force: f64,
    /// Steady.
    pub steady_floor_force: f64,
    /// Peak relative motion across the leaves |x1 − x2|, m, and its steady peak.
    pub peak_relative: f64,
    /// Steady.
    pub steady_relative: f64,
    /// Per mode: (frequency Hz, damping ratio, time in its half-power band on the way up, s).
    pub modes: Vec<(f64, f64, f64)>,
}

/// The number under quantity id `id` of the run `r`.
fn quantity(r: &DesignReport, id: &str) -> Result<f64> {
    r.quantities
        .iter()
        .find(|q| q.id == id)
        .map(|q| q.value)
        .ok_or_else(|| Error::Verification(format!("start-up: the run reports no '{id}'")))
}

/// Modal frequencies (Hz) and damping ratios of the 2-DOF M, C, K (undamped modes, diagonal of
/// the modal damping).
fn modes(m: [f64; 2], c: &[f64], k: &[f64]) -> Vec<(f64, f64)> {
    let s = [1.0 / m[0].sqrt(), 1.0 / m[1].sqrt()];
    let a = nalgebra::Matrix2::new(
        k[0] * s[0] * s[0],
        k[1] * s[0] * s[1],
        k[2] * s[1] * s[0],
        k[3] * s[1] * s[1],
    );
    let e = a.symmetric_eigen();
    let mut out: Vec<(f64, f64)> = (0..2)
        .map(|i| {
            let w = e.eigenvalues[i].max(0.0).sqrt();
            let v = e.eigenvectors.column(i);
            let phi = [v[0] * s[0], v[1] * s[1]];
            let cq = (0..2)
                .map(|r| (0..2).map(|q| phi[r] * c[r * 2 + q] * phi[q]).sum::<f64>())
                .sum::<f64>();
            (w / TAU, cq / (2.0 * w.max(1e-300)))
        })
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// Start-up and run-down of design `d` whose run gave `r`, with run-up/run-down `ramp_s`.
pub fn run(d: &Design, r: &DesignReport, ramp_s: f64) -> Result<Startup> {
    let (m1, m2) = (quantity(r, "m1")?, quantity(r, "m2")?);
    let (c12, c13) = (quantity(r, "c12")?, quantity(r, "c13")?);
    let dp = &d.damping;
    let m = [m1, 0.0, 0.0, m2];
    let c = [dp.mu1 + dp.mu12, -dp.mu12, -dp.mu12, dp.mu12 + dp.mu13];
    let k = [c12, -c12, -c12, c12 + c13];
    let omega = TAU * d.excitation_hz;
    let ramp = Ramp {
        omega_mains: omega / 2.0,
        up_s: ramp_s,
        hold_s: HOLD_S,
        down_s: ramp_s,
    };
    let p_em = d.drive.magnets as f64 * d.drive.pull;
    let dt = 1.0 / (d.excitation_hz * SAMPLES_PER_PERIOD);
    let t_end = ramp.off() + 1.0;
    let ode = Dopri5Options {
        rtol: 1e-8,
        atol: 1e-13,
        ..Default::default()
    };
    let tr = simulate_linear(&m, &c, &k, &[-1.0, 1.0], p_em, &ramp, t_end, dt, &ode)?;
    let iso = |i: usize| tr.x[i][1].abs();
    let floor = |i: usize| (c13 * tr.x[i][1] + dp.mu13 * tr.v[i][1]).abs();
    let rel = |i: usize| (tr.x[i][0] - tr.x[i][1]).abs();
    let all = 0..tr.t.len();
    let peak = |f: &dyn Fn(usize) -> f64| all.clone().map(f).fold(0.0, f64::max);
    // The steady values: the last force period before the run-down.
    let t1 = ramp_s + HOLD_S;
    let steady_idx: Vec<usize> = (0..tr.t.len())
        .filter(|&i| tr.t[i] > t1 - 1.0 / d.excitation_hz && tr.t[i] <= t1)
        .collect();
    let steady = |f: &dyn Fn(usize) -> f64| steady_idx.iter().map(|&i| f(i)).fold(0.0, f64::max);
    // On the way up the force frequency (twice the mains) rises at f_e / ramp (Hz/s): the time in
    // a band of width 2 ζ f_k is 2 ζ f_k · ramp / f_e.
    let modes = modes([m1, m2], &c, &k)
        .into_iter()
        .map(|(f, z)| (f, z, 2.0 * z * f * ramp_s / d.excitation_hz))
        .collect();
    Ok(Startup {
        ramp_s,
        peak_isolator_deflection: peak(&iso),
        steady_isolator_deflection: steady(&iso),
        peak_floor_force: peak(&floor),
        steady_floor_force: steady(&floor),
        peak_relative: peak(&rel),
        steady_relative: steady(&rel),
        modes,
    })
}

/// The start-up (ramped) and the switch-on as a report section.
pub fn section(soft: &Startup, switch_on: &Startup) -> Section {
    let row = |name: &str, unit: &str, a: f64, b: f64, s: f64| {
        vec![
            Cell::text(format!("{name} [{unit}]")),
            Cell::num(a),
            Cell::num(b),
            Cell::num(s),
        ]
    };
    let mut rows = vec![
        row(
            "isolator deflection",
            "mm",
            1e3 * soft.peak_isolator_deflection,
            1e3 * switch_on.peak_isolator_deflection,
            1e3 * soft.steady_isolator_deflection,
        ),
        row(
            "floor force, all isolators",
            "N",
            soft.peak_floor_force,
            switch_on.peak_floor_force,
            soft.steady_floor_force,
        ),
        row(
            "relative motion across the leaves",
            "mm",
            1e3 * soft.peak_relative,
            1e3 * switch_on.peak_relative,
            1e3 * soft.steady_relative,
        ),
    ];
    for (f, z, t) in &soft.modes {
        rows.push(vec![
            Cell::text(format!(
                "time in the half-power band of the {f:.2} Hz mode (ζ = {z:.3}) [s]"
            )),
            Cell::num(*t),
            Cell::Empty,
            Cell::Empty,
        ]);
    }
    Section {
        id: "startup".into(),
        title: "Start-up and run-down (two-mass machine)".into(),
        blocks: vec![
            Block::Text(
                "model: the two-mass machine of the chain (its two modes are the 3D machine's isolation bounce and \
                 working modes); the 3D machine's other isolation modes (sway, rocking, yaw) are not excited by the \
                 symmetric vertical pull and are not in it, nor the roll and pitch an eccentric load excites"
                    .into(),
            ),
            Block::Table(Table {
                id: "startup".into(),
                caption: Some(format!(
                    "peaks from rest: a {} s frequency ramp up, {HOLD_S} s at full frequency, {} s down, then off; \
                 and switched straight onto the mains and off; steady: the last period at full frequency",
                    soft.ramp_s, soft.ramp_s
                )),
                columns: vec![
                    Column::new("quantity", None),
                    Column::new("peak, ramped", None),
                    Column::new("peak, switched", None),
                    Column::new("steady", None),
                ],
                rows,
            }),
        ],
    }
}
