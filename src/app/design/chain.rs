//! The design chain, a recipe of named steps: FE parts feeding the two-mass model, the 3D
//! machine, then the checks and the quantity table.
//!
//! Steps (each timed and reported):
//! 1. **Work table** (shell sandwich, free–free modal): mass, first six elastic frequencies.
//! 2. **Coil isolator** (Timoshenko beams along the helix, one end clamped, the other guided
//!    axially): stiffness.
//! 3. **Leaf spring** (hex20 solid, clamped at one end, the other guided through a rigid
//!    coupling): stiffness from a 1000 N load; with `tune = "leaf"` the leaf thickness is
//!    iterated (secant on FE solves) until the detuning z reaches its target.
//! 4. **Two-mass model**: m1 = FE table mass + other active parts + load share, m2 given;
//!    c12 = n_leaves · k_leaf · k_clamp; c13 = n_isolators · k_coil. Natural frequencies,
//!    steady state at the excitation, dynamic factors, drive force and power, isolation; the
//!    transient start-up.
//! 5. **3D machine** ([`super::machine`]): modes and the forced response over the work surface.
//! 6. **Stresses**: the leaf at the working relative amplitude |X1 − X2| (linear scaling of the
//!    FE stress field of step 3), the coil by Wahl's formula under the static load.
//! 7. **Checks** ([`super::checks`]) and the quantity table ([`super::reference`]); plots.
//!
//! Everything is built in code (no mesh files): a design runs from [`Design::paper`] or a TOML
//! file with the same fields.

use super::checks;
use super::file::Design;
use super::machine::{MachineResult, analyse};
use super::parts::{coil_fe, leaf_fe, table_fe};
use super::plots;
use super::reference;
use super::results::{ChainValues, DesignReport};
use crate::app::dynamics::electromagnet::{RectifiedDrive, required_peak_force};
use crate::app::dynamics::isolation::{transmissibility, wahl_factor};
use crate::app::dynamics::transient::{Transient, TransientOptions, simulate_startup};
use crate::app::dynamics::tuning::{drive_power, leaf_thickness_for_stiffness, reactive_mass_for_detuning};
use crate::app::dynamics::two_mass::TwoMass;
use crate::{Error, Result};
use std::f64::consts::{PI, TAU};
use std::time::Instant;

/// Wall time per step.
#[derive(Default)]
struct Clock(Vec<(String, f64)>);

impl Clock {
    /// Run `step`, recording its wall time under `name`.
    fn time<T>(&mut self, name: &str, step: impl FnOnce() -> Result<T>) -> Result<T> {
        let t = Instant::now();
        let r = step()?;
        self.0.push((name.to_string(), t.elapsed().as_secs_f64()));
        Ok(r)
    }
}

/// The masses and the isolators' stiffness of the two-mass model.
struct Masses {
    m1: f64,
    m2: f64,
    m_red: f64,
    c13: f64,
}

/// The leaf as tuned (or as given).
struct Leaf {
    h_given: f64,
    k_given: f64,
    h: f64,
    k: f64,
    stress_per_m: f64,
    iters: Vec<(f64, f64)>,
    c12: f64,
}

/// The two-mass model at the excitation.
struct Lumped {
    model: TwoMass,
    drive: RectifiedDrive,
    force: f64,
    w: [f64; 2],
    z: f64,
    x1: f64,
    x2: f64,
    rel: f64,
    gamma: [f64; 2],
    power: f64,
    p_req: f64,
    f_iso: f64,
    trans: f64,
}

/// Run the whole chain; `progress` is told the name of each step as it starts. Plots and mode
/// shapes go to `out_dir` if given (the report itself is written by the caller, from
/// [`super::report::report`]).
pub fn run_design(d: &Design, out_dir: Option<&std::path::Path>, progress: &dyn Fn(&str)) -> Result<DesignReport> {
    d.validate()?;
    let mut clock = Clock::default();
    progress("work table: shell modal analysis");
    let (m_table, f_table, table_run, table_mesh) = clock.time("work table modal", || table_fe(d))?;
    progress("coil isolator: beam helix statics");
    let k_coil = clock.time("coil spring statics", || coil_fe(d))?;
    let masses = masses(d, m_table, k_coil);
    progress("leaf spring: solid statics");
    let leaf = clock.time("leaf spring statics", || tune_leaf(d, masses.m_red, progress))?;
    progress("two-mass model");
    let (lumped, tr) = clock.time("two-mass model and transient", || {
        let lumped = two_mass(d, &masses, &leaf)?;
        progress("transient start-up (Dormand–Prince)");
        let tr = startup(d, &lumped)?;
        Ok((lumped, tr))
    })?;
    progress("3D machine: modes and forced response");
    let machine = clock.time("3D machine", || analyse(d, leaf.h))?;
    let v = values(d, m_table, f_table, k_coil, &masses, &leaf, &lumped, &tr, machine)?;
    if let Some(dir) = out_dir {
        progress("report and plots");
        plots::write_all(
            dir,
            d,
            &lumped.model,
            &lumped.drive,
            &tr,
            &table_run,
            &table_mesh,
            &v.machine,
        )?;
    }
    Ok(DesignReport {
        name: d.name.clone(),
        checks: checks::all(d, &v),
        quantities: reference::quantities(d, &v),
        table_frequencies_hz: v.f_table.clone(),
        leaf_iterations: v.iters.clone(),
        machine_modes: v.machine.modes.clone(),
        timings_s: clock.0,
        notes: notes(d, &v),
    })
}

/// m1 = FE table + other active parts + the load share; m2; the reduced mass; c13.
fn masses(d: &Design, m_table: f64, k_coil: f64) -> Masses {
    let m1 = m_table + d.masses.active_extra + d.masses.load_share * d.masses.load;
    let m2 = d.masses.reactive;
    Masses {
        m1,
        m2,
        m_red: m1 * m2 / (m1 + m2),
        c13: d.coil.count as f64 * k_coil,
    }
}

/// The leaf's FE stiffness at the given thickness and, with `tune = "leaf"`, the thickness that
/// reaches the target detuning: a secant on h³ (k grows like h³) over FE solves, to 1e-6 on k.
fn tune_leaf(d: &Design, m_red: f64, progress: &dyn Fn(&str)) -> Result<Leaf> {
    let omega = TAU * d.excitation_hz;
    let mut h = d.leaf.thickness;
    let (mut k_leaf, mut stress_per_m) = leaf_fe(d, h)?;
    let c12_of = |k: f64| d.leaf.count as f64 * k * d.leaf.clamping;
    let z_of = |c12: f64| omega / (c12 / m_red).sqrt();
    let mut iters = vec![(h, z_of(c12_of(k_leaf)))];
    let (k_given, h_given) = (k_leaf, h);
    if d.tune == "leaf" {
        // Secant on the thickness for c12 = m_red (Ω/z)²; k grows like h³, so iterate on h³.
        let c12_target = m_red * (omega / d.target_detuning).powi(2);
        let k_target = c12_target / (d.leaf.count as f64 * d.leaf.clamping);
        let mut h_prev = h;
        let mut k_prev = k_leaf;
        h *= (k_target / k_leaf).cbrt();
        for _ in 0..8 {
            progress(&format!("leaf spring: tuning, h = {:.3} mm", h * 1e3));
            (k_leaf, stress_per_m) = leaf_fe(d, h)?;
            iters.push((h, z_of(c12_of(k_leaf))));
            if (k_leaf - k_target).abs() < 1e-6 * k_target {
                break;
            }
            let (a, b) = (h_prev.powi(3), h.powi(3));
            let next = b + (k_target - k_leaf) * (b - a) / (k_leaf - k_prev);
            h_prev = h;
            k_prev = k_leaf;
            h = next.max(1e-12).cbrt();
        }
    }
    Ok(Leaf {
        h_given,
        k_given,
        h,
        k: k_leaf,
        stress_per_m,
        iters,
        c12: c12_of(k_leaf),
    })
}

/// The two-mass model at the excitation: steady state, natural frequencies, dynamic factors,
/// the drive power of eq. (6), the pull for the target amplitude, isolation.
fn two_mass(d: &Design, m: &Masses, leaf: &Leaf) -> Result<Lumped> {
    let omega = TAU * d.excitation_hz;
    let model = TwoMass::new(
        m.m1,
        m.m2,
        leaf.c12,
        m.c13,
        d.damping.mu1,
        d.damping.mu12,
        d.damping.mu13,
    )?;
    let drive = RectifiedDrive::from_magnets(d.drive.magnets, d.drive.pull, omega / 2.0)?;
    let force = drive.harmonic_amplitude();
    let ss = model.steady_state(omega, force)?;
    let w = model.natural_frequencies_hz()?;
    let x1 = ss.amp1();
    let gamma1 = x1 * m.m1 * omega * omega / force;
    let gamma2 = ss.amp2() * m.m2 * omega * omega / force;
    // Eq. (6) as the paper applies it: at the sizing overload (11 g), X2 in the model's ratio
    // to X1, the model's dynamic factors, and the load share taken with a margin.
    let x1p = d.drive.power_overload_g * 9.81 / (omega * omega);
    let x2p = x1p * ss.amp2() / x1;
    let power = drive_power(
        omega,
        d.drive.efficiency,
        &[(x1p, m.m1, gamma1), (x2p, m.m2, gamma2)],
        x1p,
        d.drive.power_load_share,
    )?;
    let p_req = required_peak_force(&model, omega, d.target_amplitude)? / d.drive.magnets as f64;
    let m_total = m.m1 + m.m2 + d.masses.load;
    let f_iso = (m.c13 / m_total).sqrt() / TAU;
    let trans = transmissibility(d.excitation_hz / f_iso, 0.0)?;
    Ok(Lumped {
        z: omega / model.omega0(),
        model,
        drive,
        force,
        w,
        x1,
        x2: ss.amp2(),
        rel: ss.relative_amp(),
        gamma: [gamma1, gamma2],
        power,
        p_req,
        f_iso,
        trans,
    })
}

/// The start-up from rest under the rectified pull (Dormand–Prince).
fn startup(d: &Design, l: &Lumped) -> Result<Transient> {
    simulate_startup(
        &l.model,
        &l.drive,
        &TransientOptions {
            t_end: d.drive.transient_s,
            ..Default::default()
        },
    )
}

/// The chain's numbers in one place, with the stresses: the leaf at the working relative
/// amplitude, the coil (Wahl) under the static load.
#[allow(clippy::too_many_arguments)]
fn values(
    d: &Design,
    m_table: f64,
    f_table: Vec<f64>,
    k_coil: f64,
    m: &Masses,
    leaf: &Leaf,
    l: &Lumped,
    tr: &Transient,
    machine: MachineResult,
) -> Result<ChainValues> {
    let omega = TAU * d.excitation_hz;
    let m_total = m.m1 + m.m2 + d.masses.load;
    let q_static = m_total * 9.81 / d.coil.count as f64;
    let kw = wahl_factor(d.coil.mean_diameter / d.coil.wire)?;
    let tau = 8.0 * kw * q_static * d.coil.mean_diameter / (PI * d.coil.wire.powi(3));
    let m2_for_target = (d.tune == "mass").then(|| {
        reactive_mass_for_detuning(m.m1, leaf.c12, omega, d.target_detuning).map_err(|e: Error| e.to_string())
    });
    Ok(ChainValues {
        omega,
        m_table,
        f_table,
        k_coil,
        m1: m.m1,
        m2: m.m2,
        m_red: m.m_red,
        c13: m.c13,
        h_given: leaf.h_given,
        k_leaf_given: leaf.k_given,
        h: leaf.h,
        k_leaf: leaf.k,
        stress_per_m: leaf.stress_per_m,
        iters: leaf.iters.clone(),
        c12: leaf.c12,
        z: l.z,
        w1: l.w[0],
        w2: l.w[1],
        force: l.force,
        constant_pull: l.drive.constant(),
        offset: l.drive.constant() / leaf.c12,
        x1: l.x1,
        x2: l.x2,
        rel: l.rel,
        gamma1: l.gamma[0],
        gamma2: l.gamma[1],
        power: l.power,
        p_req: l.p_req,
        transient: tr.summary(10)?,
        f_iso: l.f_iso,
        trans: l.trans,
        sigma_leaf: leaf.stress_per_m * l.rel,
        tau,
        m2_for_target,
        machine,
    })
}

/// The report's notes: what tuning changed, a missing working mode, the machine's size.
fn notes(d: &Design, v: &ChainValues) -> Vec<String> {
    let mut notes = vec![];
    if let Some(Err(e)) = &v.m2_for_target {
        notes.push(format!("no reactive mass reaches z = {}: {e}", d.target_detuning));
    }
    if d.tune == "leaf" && (v.h - v.h_given).abs() > 1e-9 {
        notes.push(format!(
            "with the clamping coefficient {} the given {:.1} mm leaves give z = {:.3}; the FE-tuned thickness for z = {} is {:.2} mm (eq. (16) with i = {}, k = {}: {:.2} mm)",
            d.leaf.clamping,
            v.h_given * 1e3,
            v.iters[0].1,
            d.target_detuning,
            v.h * 1e3,
            d.leaf.count,
            d.leaf.clamping,
            leaf_thickness_for_stiffness(
                v.m_red * (v.omega / d.target_detuning).powi(2),
                d.leaf.count,
                d.leaf.material[0],
                d.leaf.width,
                d.leaf.length,
                d.leaf.clamping
            )
            .unwrap_or(f64::NAN)
                * 1e3
        ));
    }
    let mach = &v.machine;
    if mach.working.is_none() {
        notes.push(format!(
            "the 3D machine has no working mode (leaves strained, masses in vertical antiphase) below {} Hz",
            d.machine.mode_range * d.excitation_hz
        ));
    }
    notes.push(format!(
        "3D machine: {} DOFs; forced response from {} modes up to {:.0} Hz with the two-mass dashpots placed on the leaves, isolators and work surface",
        mach.dofs, mach.response_modes.0, mach.response_modes.1
    ));
    notes
}
