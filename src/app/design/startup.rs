//! Start-up and run-down through the isolation modes: the design's machine driven from rest by
//! a supply whose frequency runs up from zero to the mains (a frequency converter's ramp; a zero
//! ramp is a switch straight onto the mains), holds, runs down to zero and goes off, under the
//! design's force law (P·sin²φ for `flux`, P·|sin φ| for `paper`, φ the mains phase), integrated
//! by [`crate::app::dynamics::transient::simulate_linear_law`] (Dormand–Prince, no step across a
//! kink of the pull or a switching time).
//!
//! Reported: the peak isolator deflection (largest isolator), the peak floor force (the
//! isolators' spring and dashpot forces together, summed at each instant), the peak relative
//! motion across the leaves (largest leaf) and across the magnet gaps (largest magnet), each
//! against its steady value at full frequency, and the time the excitation spends in each
//! mode's half-power band, f_k (1 ± ζ_k), on the way up.
//!
//! Two models:
//! - **the 3D machine** (the model of record): the modes that carry its forced response (up to
//!   `machine.response_range` × the excitation), q'' + C_r q' + Λ q = Φᵀf·p(t) with the coupled
//!   modal damping C_r of the harmonic response and f one newton of pull per magnet, all in
//!   phase ([`MachineModal`]); the outputs add the static correction of the modes left out, as
//!   the harmonic response does. With a symmetric layout and load the pull excites the bounce
//!   and working modes (and the table's symmetric elastic modes); an eccentric load or an
//!   asymmetric layout couples roll and pitch in, which the two-mass model cannot show.
//! - **the two-mass estimate** beside it: m1, m2, the model of record's leaves with the magnets'
//!   stiffness (c12 + k_magnet), c13 and the design file's damping, under the same law — for
//!   the symmetric rigid machine its two modes are the 3D machine's bounce and working modes.

use super::file::Design;
use super::machine::{MachineModal, ModalOutput};
use super::results::DesignReport;
use crate::app::dynamics::electromagnet::ForceLaw;
use crate::app::dynamics::ode::Dopri5Options;
use crate::app::dynamics::transient::{LinearTransient, Ramp, simulate_linear_law};
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
/// A mode is counted as excited when its peak modal coordinate reaches this share of the
/// largest one (a mode the pull does not reach by symmetry stays at rounding, ~1e-12).
pub const EXCITED_SHARE: f64 = 1e-6;

/// What a start-up and run-down gives (the two-mass estimate; the 3D machine in `machine`).
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
    /// The 3D machine's start-up (the model of record), when the run has its modal model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine: Option<MachineStartup>,
}

/// The 3D machine's start-up: peaks over the record and steady values (the last period at full
/// frequency), each the largest over the isolators, leaves or magnets.
#[derive(Clone, Debug, Serialize)]
pub struct MachineStartup {
    /// Largest isolator's vertical deflection, m.
    pub peak_isolator_deflection: f64,
    /// Steady.
    pub steady_isolator_deflection: f64,
    /// The floor force, all isolators summed at each instant (spring + dashpot), N.
    pub peak_floor_force: f64,
    /// Steady.
    pub steady_floor_force: f64,
    /// Relative vertical motion across the leaves (table end against clamp), largest leaf, m.
    pub peak_relative: f64,
    /// Steady.
    pub steady_relative: f64,
    /// Relative vertical motion across the magnet gaps (armature against core), largest, m.
    pub peak_gap: f64,
    /// Steady.
    pub steady_gap: f64,
    /// Modes integrated.
    pub modes_used: usize,
    /// The modes, lowest first.
    pub modes: Vec<ModeStartup>,
}

/// One mode of the 3D machine in the start-up.
#[derive(Clone, Debug, Serialize)]
pub struct ModeStartup {
    /// Its name in the machine's mode table.
    pub name: String,
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// Damping ratio from the diagonal of C_r, C_r,kk/(2ω_k).
    pub damping_ratio: f64,
    /// Time the excitation spends in its half-power band on the way up, s (0 for a band above
    /// the excitation or without a ramp).
    pub band_time_s: f64,
    /// Peak |q_k| over the record, m·kg^½ (mass-normalised modal coordinate).
    pub peak_modal: f64,
    /// Whether the pull excites it: peak |q_k| ≥ [`EXCITED_SHARE`] × the largest.
    pub excited: bool,
}

/// The two-mass model the estimate runs: masses (kg), leaves with the magnets' stiffness and
/// isolators (N/m); the damping is the design file's.
#[derive(Clone, Copy, Debug)]
pub struct TwoMassParts {
    /// Active mass m1.
    pub m1: f64,
    /// Reactive mass m2.
    pub m2: f64,
    /// c12 + k_magnet.
    pub k12: f64,
    /// c13.
    pub c13: f64,
}

/// The number under quantity id `id` of the run `r`.
fn quantity(r: &DesignReport, id: &str) -> Result<f64> {
    r.quantities
        .iter()
        .find(|q| q.id == id)
        .map(|q| q.value)
        .ok_or_else(|| Error::Verification(format!("start-up: the run reports no '{id}'")))
}

impl TwoMassParts {
    /// The two-mass estimate of run `r`: m1, m2, the model of record's leaves with the magnets'
    /// stiffness, c13 (quantities `m1`, `m2`, `c12_machine`, `k_magnet`, `c13`).
    pub fn of(r: &DesignReport) -> Result<TwoMassParts> {
        Ok(TwoMassParts {
            m1: quantity(r, "m1")?,
            m2: quantity(r, "m2")?,
            k12: quantity(r, "c12_machine")? + quantity(r, "k_magnet")?,
            c13: quantity(r, "c13")?,
        })
    }
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

/// Time (s) the force frequency, rising linearly from 0 to `f_e` over `ramp_s`, spends in the
/// band f (1 ± ζ): the part of the band below `f_e` over the sweep rate f_e/ramp.
pub fn band_time(f: f64, zeta: f64, f_e: f64, ramp_s: f64) -> f64 {
    let (lo, hi) = ((f * (1.0 - zeta)).max(0.0), f * (1.0 + zeta));
    (hi.min(f_e) - lo.min(f_e)).max(0.0) * ramp_s / f_e
}

/// The supply, the sampling step, the record's end and the integrator's tolerances of a run
/// with run-up/run-down `ramp_s`.
fn setup(d: &Design, ramp_s: f64) -> (Ramp, f64, f64, Dopri5Options) {
    let ramp = Ramp {
        omega_mains: TAU * d.excitation_hz / 2.0,
        up_s: ramp_s,
        hold_s: HOLD_S,
        down_s: ramp_s,
    };
    let dt = 1.0 / (d.excitation_hz * SAMPLES_PER_PERIOD);
    let t_end = ramp.off() + 1.0;
    let ode = Dopri5Options {
        rtol: 1e-8,
        atol: 1e-13,
        ..Default::default()
    };
    (ramp, dt, t_end, ode)
}

/// Peak of |f| over the record and its peak over the last force period before the run-down.
fn peak_steady(tr: &LinearTransient, d: &Design, ramp_s: f64, f: &dyn Fn(usize) -> f64) -> (f64, f64) {
    let t1 = ramp_s + HOLD_S;
    let t0 = t1 - 1.0 / d.excitation_hz;
    let (mut peak, mut steady) = (0.0f64, 0.0f64);
    for (i, &t) in tr.t.iter().enumerate() {
        let v = f(i).abs();
        peak = peak.max(v);
        if t > t0 && t <= t1 {
            steady = steady.max(v);
        }
    }
    (peak, steady)
}

/// The two-mass start-up of design `d` with parts `p` and run-up/run-down `ramp_s`.
pub fn two_mass(d: &Design, p: &TwoMassParts, ramp_s: f64) -> Result<Startup> {
    let dp = &d.damping;
    let m = [p.m1, 0.0, 0.0, p.m2];
    let c = [dp.mu1 + dp.mu12, -dp.mu12, -dp.mu12, dp.mu12 + dp.mu13];
    let k = [p.k12, -p.k12, -p.k12, p.k12 + p.c13];
    let (ramp, dt, t_end, ode) = setup(d, ramp_s);
    let p_em = d.drive.magnets as f64 * d.drive.pull;
    let tr = simulate_linear_law(&m, &c, &k, &[-1.0, 1.0], d.force_law(), p_em, &ramp, t_end, dt, &ode)?;
    let (iso, iso_s) = peak_steady(&tr, d, ramp_s, &|i| tr.x[i][1]);
    let (floor, floor_s) = peak_steady(&tr, d, ramp_s, &|i| p.c13 * tr.x[i][1] + dp.mu13 * tr.v[i][1]);
    let (rel, rel_s) = peak_steady(&tr, d, ramp_s, &|i| tr.x[i][0] - tr.x[i][1]);
    let modes = modes([p.m1, p.m2], &c, &k)
        .into_iter()
        .map(|(f, z)| (f, z, band_time(f, z, d.excitation_hz, ramp_s)))
        .collect();
    Ok(Startup {
        ramp_s,
        peak_isolator_deflection: iso,
        steady_isolator_deflection: iso_s,
        peak_floor_force: floor,
        steady_floor_force: floor_s,
        peak_relative: rel,
        steady_relative: rel_s,
        modes,
        machine: None,
    })
}

/// The 3D machine's start-up of design `d` on its modal model `mm`, run-up/run-down `ramp_s`.
pub fn machine(d: &Design, mm: &MachineModal, ramp_s: f64) -> Result<MachineStartup> {
    let n = mm.lambda.len();
    if n == 0 || mm.force.len() != n || mm.damping.len() != n * n || mm.names.len() != n {
        return Err(Error::Verification(format!(
            "start-up: the machine's modal model is inconsistent ({n} modes, {} forces, {} damping terms)",
            mm.force.len(),
            mm.damping.len()
        )));
    }
    let mut m = vec![0.0; n * n];
    let mut k = vec![0.0; n * n];
    for i in 0..n {
        m[i * n + i] = 1.0;
        k[i * n + i] = mm.lambda[i];
    }
    let (ramp, dt, t_end, ode) = setup(d, ramp_s);
    let (law, p): (ForceLaw, f64) = (d.force_law(), d.drive.pull);
    let tr = simulate_linear_law(&m, &mm.damping, &k, &mm.force, law, p, &ramp, t_end, dt, &ode)?;
    let pull: Vec<f64> = tr.t.iter().map(|&t| ramp.pull(law, p, t)).collect();
    let rate: Vec<f64> = tr.t.iter().map(|&t| ramp.pull_rate(law, p, t)).collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let x = |o: &ModalOutput, i: usize| dot(&o.shape, &tr.x[i]) + o.residual * pull[i];
    let v = |o: &ModalOutput, i: usize| dot(&o.shape, &tr.v[i]) + o.residual * rate[i];
    let largest = |outs: &[ModalOutput], i: usize| outs.iter().map(|o| x(o, i).abs()).fold(0.0, f64::max);
    let (iso, iso_s) = peak_steady(&tr, d, ramp_s, &|i| largest(&mm.isolators, i));
    let floor_at = |i: usize| {
        mm.isolators
            .iter()
            .map(|o| mm.k_isolator * x(o, i) + mm.c_isolator * v(o, i))
            .sum::<f64>()
    };
    let (floor, floor_s) = peak_steady(&tr, d, ramp_s, &floor_at);
    let (rel, rel_s) = peak_steady(&tr, d, ramp_s, &|i| largest(&mm.leaves, i));
    let (gap, gap_s) = peak_steady(&tr, d, ramp_s, &|i| largest(&mm.magnets, i));
    let peaks: Vec<f64> = (0..n)
        .map(|j| tr.x.iter().map(|q| q[j].abs()).fold(0.0, f64::max))
        .collect();
    let top = peaks.iter().copied().fold(0.0, f64::max);
    let modes = (0..n)
        .map(|j| {
            let w = mm.lambda[j].max(0.0).sqrt();
            let (f, z) = (w / TAU, mm.damping[j * n + j] / (2.0 * w.max(1e-300)));
            ModeStartup {
                name: mm.names[j].clone(),
                frequency_hz: f,
                damping_ratio: z,
                band_time_s: band_time(f, z, d.excitation_hz, ramp_s),
                peak_modal: peaks[j],
                excited: peaks[j] >= EXCITED_SHARE * top,
            }
        })
        .collect();
    Ok(MachineStartup {
        peak_isolator_deflection: iso,
        steady_isolator_deflection: iso_s,
        peak_floor_force: floor,
        steady_floor_force: floor_s,
        peak_relative: rel,
        steady_relative: rel_s,
        peak_gap: gap,
        steady_gap: gap_s,
        modes_used: n,
        modes,
    })
}

/// Start-up and run-down of design `d` whose run gave `r`, with run-up/run-down `ramp_s`: the
/// two-mass estimate, with the 3D machine's start-up in `machine` when the run carries its modal
/// model.
pub fn run(d: &Design, r: &DesignReport, ramp_s: f64) -> Result<Startup> {
    let mut s = two_mass(d, &TwoMassParts::of(r)?, ramp_s)?;
    if !r.machine_modal.lambda.is_empty() {
        s.machine = Some(machine(d, &r.machine_modal, ramp_s)?);
    }
    Ok(s)
}

/// The start-up table's rows: per quantity, the 3D machine's ramped and switched peaks and
/// steady value, then the two-mass estimate's.
fn rows(soft: &Startup, switched: &Startup) -> Vec<Vec<Cell>> {
    let m = |s: &Startup, f: fn(&MachineStartup) -> f64| s.machine.as_ref().map_or(Cell::Empty, |x| Cell::num(f(x)));
    type Q = (
        &'static str,
        fn(&MachineStartup) -> f64,
        fn(&MachineStartup) -> f64,
        fn(&Startup) -> f64,
        fn(&Startup) -> f64,
    );
    let table: [Q; 4] = [
        (
            "isolator deflection, largest [mm]",
            |x| 1e3 * x.peak_isolator_deflection,
            |x| 1e3 * x.steady_isolator_deflection,
            |s| 1e3 * s.peak_isolator_deflection,
            |s| 1e3 * s.steady_isolator_deflection,
        ),
        (
            "floor force, all isolators [N]",
            |x| x.peak_floor_force,
            |x| x.steady_floor_force,
            |s| s.peak_floor_force,
            |s| s.steady_floor_force,
        ),
        (
            "relative motion across the leaves, largest [mm]",
            |x| 1e3 * x.peak_relative,
            |x| 1e3 * x.steady_relative,
            |s| 1e3 * s.peak_relative,
            |s| 1e3 * s.steady_relative,
        ),
        (
            "relative motion across the magnet gaps, largest [mm]",
            |x| 1e3 * x.peak_gap,
            |x| 1e3 * x.steady_gap,
            |s| 1e3 * s.peak_relative,
            |s| 1e3 * s.steady_relative,
        ),
    ];
    let mut out: Vec<Vec<Cell>> = table
        .iter()
        .map(|(name, peak, steady, peak2, steady2)| {
            vec![
                Cell::text(*name),
                m(soft, *peak),
                m(switched, *peak),
                m(soft, *steady),
                Cell::num(peak2(soft)),
                Cell::num(peak2(switched)),
                Cell::num(steady2(soft)),
            ]
        })
        .collect();
    let band = |name: String, t3: Option<f64>, t2: Option<f64>| {
        let mut row = vec![Cell::text(name), t3.map_or(Cell::Empty, Cell::num)];
        row.extend([
            Cell::Empty,
            Cell::Empty,
            t2.map_or(Cell::Empty, Cell::num),
            Cell::Empty,
            Cell::Empty,
        ]);
        row
    };
    // The excited modes up to 1.5 × the two-mass working mode (the isolation and working modes and
    // their neighbours; the table's higher elastic modes are passed by no harmonic that matters).
    let limit = 1.5 * soft.modes.iter().map(|m| m.0).fold(0.0, f64::max);
    if let Some(x) = &soft.machine {
        for md in x.modes.iter().filter(|md| md.excited && md.frequency_hz < limit) {
            out.push(band(
                format!(
                    "time in the half-power band, 3D {} {:.2} Hz (ζ = {:.3}) [s]",
                    md.name, md.frequency_hz, md.damping_ratio
                ),
                Some(md.band_time_s),
                None,
            ));
        }
    }
    for (f, z, t) in &soft.modes {
        out.push(band(
            format!("time in the half-power band, two-mass {f:.2} Hz mode (ζ = {z:.3}) [s]"),
            None,
            Some(*t),
        ));
    }
    out
}

/// The start-up (ramped) and the switch-on as a report section: the 3D machine (model of
/// record) with the two-mass estimate beside it.
pub fn section(soft: &Startup, switch_on: &Startup) -> Section {
    let mut text = String::from(
        "model of record: the 3D machine in the modes that carry its forced response, with the coupled modal \
         damping and the static correction of the modes left out, under the design's force law; beside it the \
         two-mass estimate (m1, m2, the model of record's leaves with the magnets' stiffness, c13). With a \
         symmetric layout and load the pull excites only the bounce and working modes (and the table's symmetric \
         elastic modes); an eccentric load or an asymmetric layout excites roll and pitch, which only the 3D \
         machine shows",
    );
    if let Some(x) = &soft.machine {
        let excited: Vec<String> = x
            .modes
            .iter()
            .filter(|m| m.excited)
            .map(|m| format!("{} ({:.2} Hz)", m.name, m.frequency_hz))
            .collect();
        text.push_str(&format!(
            ". 3D machine: {} modes integrated; excited: {}",
            x.modes_used,
            excited.join(", ")
        ));
    }
    Section {
        id: "startup".into(),
        title: "Start-up and run-down (3D machine; two-mass estimate beside it)".into(),
        blocks: vec![
            Block::Text(text),
            Block::Table(Table {
                id: "startup".into(),
                caption: Some(format!(
                    "peaks from rest: a {} s frequency ramp up, {HOLD_S} s at full frequency, {} s down, then off; \
                 and switched straight onto the mains and off; steady: the last period at full frequency",
                    soft.ramp_s, soft.ramp_s
                )),
                columns: vec![
                    Column::new("quantity", None),
                    Column::new("3D: peak, ramped", None),
                    Column::new("3D: peak, switched", None),
                    Column::new("3D: steady", None),
                    Column::new("two-mass: peak, ramped", None),
                    Column::new("two-mass: peak, switched", None),
                    Column::new("two-mass: steady", None),
                ],
                rows: rows(soft, switch_on),
            }),
        ],
    }
}
