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
//! 4. **Two-mass model, the paper's chain**: m1 = FE table mass + other active parts + load
//!    share, m2 given; c12 = n_leaves · k_leaf · k_clamp; c13 = n_isolators · k_coil, under the
//!    paper's force law P|sin ωt| and without the magnets' stiffness: what the paper's published
//!    numbers are compared with (built-in design only), and the transient start-up.
//! 5. **3D machine, the model of record** ([`super::machine`]): with `tune = "leaf"` the leaf
//!    thickness is iterated again (secant on h³ against the working mode's frequency², from the
//!    two-mass thickness corrected for the magnets' stiffness) until the 3D working mode gives
//!    the target detuning; then its modes, the forced response over the work surface, the
//!    relative motion across each leaf and each magnet's gap, the floor forces per isolator.
//! 6. **Two-mass estimate** at the model of record's leaves under the design's force law, with
//!    the magnets' stiffness −2P̄/δ: the designer's estimate beside the 3D machine, a
//!    difference above 5 % noted with its cause (table flexibility or layout asymmetry, by the
//!    rigid-table machine).
//! 7. **Stresses and gap**: the leaf at the largest 3D relative amplitude (linear scaling of
//!    the FE stress field of step 3), the coil by Wahl's formula under the static load; the gap
//!    closed by the static sag, the relative amplitude across the magnets and the start-up
//!    overshoot (design law).
//! 8. **Checks** ([`super::checks`]) and the quantity table ([`super::reference`]); plots.
//!
//! Everything is built in code (no mesh files): a design runs from [`Design::paper`] or a TOML
//! file with the same fields.

use super::checks;
use super::file::Design;
use super::machine::{MachineResult, analyse};
use super::parts::{coil_fe, leaf_fe, table_fe};
use super::plots;
use super::reference;
use super::results::{ChainValues, DesignReport, LumpedValues};
use crate::app::dynamics::electromagnet::{ForceLaw, MagnetDrive, required_peak_force, startup_peak_relative};
use crate::app::dynamics::isolation::{transmissibility, wahl_factor};
use crate::app::dynamics::transient::{TransientOptions, simulate_startup};
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
    progress("two-mass model (paper's chain)");
    let (paper, paper_model, tr) = clock.time("two-mass model and transient", || {
        let drive = paper_drive(d)?;
        let (lv, model) = lumped(d, &masses, leaf.h, leaf.k, leaf.stress_per_m, &drive, 0.0)?;
        progress("transient start-up (Dormand–Prince)");
        let tr = simulate_startup(
            &model,
            &drive.rectified()?,
            &TransientOptions {
                t_end: d.drive.transient_s,
                ..Default::default()
            },
        )?;
        Ok((lv, model, tr))
    })?;
    progress("3D machine: modes and forced response");
    let mach = clock.time("3D machine", || tune_machine(d, &masses, &leaf, progress))?;
    let drive = d.magnet_drive()?;
    let k_mag = d.magnet_stiffness()?;
    let (two, two_model) = lumped(d, &masses, mach.h, mach.k, mach.stress_per_m, &drive, k_mag)?;
    let startup = startup_peak_relative(&two_model, &drive, d.drive.transient_s)?;
    let difference = clock.time("two-mass against 3D", || model_difference(d, &two, &mach))?;
    let v = values(
        d,
        Parts {
            m_table,
            f_table,
            k_coil,
        },
        &masses,
        &leaf,
        paper,
        two,
        &tr,
        mach,
        startup,
        difference,
    )?;
    if let Some(dir) = out_dir {
        progress("report and plots");
        plots::write_all(
            dir,
            d,
            &paper_model,
            &paper_drive(d)?.rectified()?,
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
        leaf_thickness_m: v.h,
        machine_modes: v.machine.modes.clone(),
        force_law: v.force_law.clone(),
        mains_hz: v.mains_hz,
        floor_force: super::results::FloorForces {
            machine: v.machine.floor.clone(),
            two_mass: v
                .two_mass
                .floor
                .iter()
                .map(|&(k, f, total)| super::machine::FloorForce {
                    harmonic: k,
                    frequency_hz: f,
                    per_isolator: vec![total / d.coil.count as f64; d.coil.count],
                    total,
                })
                .collect(),
        },
        inputs: reference::inputs(d, &v),
        timings_s: clock.0,
        notes: notes(d, &v),
        machine_modal: v.machine.modal.clone(),
    })
}

/// The paper's two-mass amplitude X1 (m) of `d`: work side `m1` (kg), leaves `c12` (N/m) all
/// together, isolators `k_coil` (N/m) each, the rectified magnet drive at the excitation (the
/// screen of the design search and the envelope's tuning chart).
pub(super) fn two_mass_x1(d: &Design, m1: f64, c12: f64, k_coil: f64) -> Result<f64> {
    use crate::app::dynamics::electromagnet::RectifiedDrive;
    let omega = TAU * d.excitation_hz;
    let tm = TwoMass::new(
        m1,
        d.masses.reactive,
        c12,
        d.coil.count as f64 * k_coil,
        d.damping.mu1,
        d.damping.mu12,
        d.damping.mu13,
    )?;
    let f = RectifiedDrive::from_magnets(d.drive.magnets, d.drive.pull, omega / 2.0)?.harmonic_amplitude();
    Ok(tm.steady_state(omega, f)?.amp1())
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
    })
}

/// The paper's drive: its force law on the design's mains.
fn paper_drive(d: &Design) -> Result<MagnetDrive> {
    MagnetDrive::from_magnets(ForceLaw::Paper, d.drive.magnets, d.drive.pull, TAU * d.mains_hz())
}

/// The two-mass model at leaves of thickness `h` (FE stiffness `k_leaf`, stress per metre
/// `stress_per_m`) under `drive`, with the magnets' stiffness `k_mag` (N/m, ≤ 0) added to the
/// leaves': steady state, natural frequencies, dynamic factors, eq. (6) and the dissipated
/// power, the pull for the target amplitude, the floor force per harmonic.
fn lumped(
    d: &Design,
    m: &Masses,
    h: f64,
    k_leaf: f64,
    stress_per_m: f64,
    drive: &MagnetDrive,
    k_mag: f64,
) -> Result<(LumpedValues, TwoMass)> {
    let omega = TAU * d.excitation_hz;
    let c12 = d.leaf.count as f64 * k_leaf * d.leaf.clamping;
    let model = TwoMass::new(
        m.m1,
        m.m2,
        c12 + k_mag,
        m.c13,
        d.damping.mu1,
        d.damping.mu12,
        d.damping.mu13,
    )
    .map_err(|e| {
        super::file::bad(
            "drive.gap",
            format!("the magnets' stiffness {k_mag:.4e} N/m outweighs the leaves' {c12:.4e} N/m: {e}"),
        )
    })?;
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
    // The pull for the target: the law's harmonic is a fixed share of the peak pull.
    let share = drive.harmonic_amplitude() / drive.p_em.max(1e-300);
    let p_req =
        required_peak_force(&model, omega, d.target_amplitude)? * (4.0 / (3.0 * PI)) / share / d.drive.magnets as f64;
    let mut floor = vec![];
    for k in 1..=3u32 {
        let fk = drive.cos_coefficient(k).abs();
        if fk > 0.0 {
            let wk = k as f64 * omega;
            floor.push((k, k as f64 * d.excitation_hz, model.floor_force(wk, fk)?.norm()));
        }
    }
    let lv = LumpedValues {
        law: drive.law.name().into(),
        h,
        k_leaf,
        c12,
        k_magnet: k_mag,
        z: omega / model.omega0(),
        w1: w[0],
        w2: w[1],
        force,
        constant_pull: drive.mean(),
        offset: drive.mean() / (c12 + k_mag),
        x1,
        x2: ss.amp2(),
        rel: ss.relative_amp(),
        gamma1,
        gamma2,
        power,
        dissipated: model.dissipated_power(omega, force)?,
        p_req,
        sigma_leaf: stress_per_m * ss.relative_amp(),
        floor,
    };
    Ok((lv, model))
}

/// The 3D machine at the model of record's leaves, and those leaves.
struct Machine {
    h: f64,
    k: f64,
    stress_per_m: f64,
    iters: Vec<(f64, f64)>,
    result: MachineResult,
}

/// The detuning of a 3D machine: the excitation over its working mode (NaN without one).
fn machine_z(d: &Design, r: &MachineResult) -> f64 {
    r.working
        .map_or(f64::NAN, |i| d.excitation_hz / r.modes[i].frequency_hz)
}

/// With `tune = "leaf"`, the leaf thickness whose 3D working mode gives the target detuning: a
/// secant on h³ against the working frequency squared (both nearly linear in the leaves'
/// stiffness), from the two-mass thickness corrected for the magnets' stiffness, to 1e-6 on z;
/// otherwise the given thickness.
fn tune_machine(d: &Design, m: &Masses, leaf: &Leaf, progress: &dyn Fn(&str)) -> Result<Machine> {
    let (k_leaf, stress_per_m) = if d.tune == "leaf" {
        (leaf.k, leaf.stress_per_m)
    } else {
        (leaf.k_given, leaf.stress_per_m)
    };
    let mut h = leaf.h;
    if d.tune != "leaf" {
        let result = analyse(d, h)?;
        let z = machine_z(d, &result);
        return Ok(Machine {
            h,
            k: k_leaf,
            stress_per_m,
            iters: vec![(h, z)],
            result,
        });
    }
    let omega = TAU * d.excitation_hz;
    let k_mag = d.magnet_stiffness()?;
    let c12_target = m.m_red * (omega / d.target_detuning).powi(2);
    let per_leaf = d.leaf.count as f64 * d.leaf.clamping;
    let k_with = ((c12_target - k_mag) / per_leaf).max(1e-12);
    h *= (k_with / leaf.k).cbrt();
    let f_target = d.excitation_hz / d.target_detuning;
    let mut iters = vec![];
    let mut prev: Option<(f64, f64)> = None;
    let mut result = analyse(d, h)?;
    for _ in 0..8 {
        let z = machine_z(d, &result);
        iters.push((h, z));
        progress(&format!("3D machine: tuning, h = {:.3} mm, z = {z:.5}", h * 1e3));
        if !z.is_finite() || (z - d.target_detuning).abs() < 1e-6 * d.target_detuning {
            break;
        }
        let fw2 = (d.excitation_hz / z).powi(2);
        let next = match prev {
            Some((a, fa)) if (fw2 - fa).abs() > 0.0 => {
                let b = h.powi(3);
                b + (f_target * f_target - fw2) * (b - a) / (fw2 - fa)
            }
            _ => h.powi(3) * (f_target * f_target) / fw2,
        };
        prev = Some((h.powi(3), fw2));
        h = next.max(1e-12).cbrt();
        result = analyse(d, h)?;
    }
    let (k, stress_per_m) = leaf_fe(d, h)?;
    Ok(Machine {
        h,
        k,
        stress_per_m,
        iters,
        result,
    })
}

/// Where the two-mass estimate and the 3D machine differ by more than 5 % (work-surface
/// amplitude, reactive amplitude, relative amplitude across the leaves), and why: the machine
/// with a rigid table at the same leaves tells table flexibility (it then agrees with the
/// two-mass model) from layout asymmetry (it does not).
fn model_difference(d: &Design, two: &LumpedValues, mach: &Machine) -> Result<Option<String>> {
    let r = &mach.result;
    let rel3 = r.leaf_relative.iter().copied().fold(0.0, f64::max);
    let diffs: Vec<(&str, f64, f64)> = vec![
        ("work-surface amplitude", r.mean, two.x1),
        ("reactive amplitude", r.reactive_amplitude, two.x2),
        ("relative amplitude across the leaves", rel3, two.rel),
    ];
    let big: Vec<String> = diffs
        .iter()
        .filter(|(_, a, b)| (a - b).abs() > 0.05 * b.abs())
        .map(|(n, a, b)| {
            format!(
                "{n} {:.4} mm against {:.4} mm ({} %)",
                a * 1e3,
                b * 1e3,
                signed_pct(a / b - 1.0)
            )
        })
        .collect();
    if big.is_empty() {
        return Ok(None);
    }
    let cause = if d.machine.table_model == "rigid" {
        "the table is rigid here, so the cause is the layout (leaves, magnets and isolators not symmetric about the centre of mass, or rotations coupling into the vertical motion)".to_string()
    } else {
        let mut rd = d.clone();
        rd.machine.table_model = "rigid".into();
        let rr = analyse(&rd, mach.h)?;
        let dev = (rr.mean / two.x1 - 1.0).abs();
        if dev <= 0.05 {
            format!(
                "table flexibility: the same machine with a rigid table gives {:.4} mm ({} % from the two-mass model)",
                rr.mean * 1e3,
                signed_pct(rr.mean / two.x1 - 1.0)
            )
        } else {
            format!(
                "layout asymmetry as well as the table: with a rigid table the machine still gives {:.4} mm ({} %)",
                rr.mean * 1e3,
                signed_pct(rr.mean / two.x1 - 1.0)
            )
        }
    };
    Ok(Some(format!(
        "the two-mass estimate and the 3D machine (the model of record) differ by more than 5 %: {}; cause: {cause}",
        big.join(", ")
    )))
}

/// The FE parts' numbers.
struct Parts {
    m_table: f64,
    f_table: Vec<f64>,
    k_coil: f64,
}

/// The chain's numbers in one place, with the stresses and the gap: the leaf at the largest
/// relative amplitude across a leaf of the 3D machine, the coil (Wahl) under the static load;
/// the gap closed by the static sag (weight of the active parts and the whole load, and the
/// mean pull, on the leaves and magnets), the 3D relative amplitude across the magnets, the
/// start-up overshoot (two-mass, design law, scaled to the 3D amplitude) and the margin.
#[allow(clippy::too_many_arguments)]
fn values(
    d: &Design,
    parts: Parts,
    m: &Masses,
    leaf: &Leaf,
    paper: LumpedValues,
    two: LumpedValues,
    tr: &crate::app::dynamics::transient::Transient,
    mach: Machine,
    startup: (f64, f64),
    difference: Option<String>,
) -> Result<ChainValues> {
    let omega = TAU * d.excitation_hz;
    let m_total = m.m1 + m.m2 + d.masses.load;
    let q_static = m_total * 9.81 / d.coil.count as f64;
    let kw = wahl_factor(d.coil.mean_diameter / d.coil.wire)?;
    let tau = 8.0 * kw * q_static * d.coil.mean_diameter / (PI * d.coil.wire.powi(3));
    let m2_for_target = (d.tune == "mass").then(|| {
        reactive_mass_for_detuning(m.m1, two.c12 + two.k_magnet, omega, d.target_detuning)
            .map_err(|e: Error| e.to_string())
    });
    let r = &mach.result;
    let rel = r.leaf_relative.iter().copied().fold(0.0, f64::max);
    let gap_amp = r.magnet_relative.iter().copied().fold(0.0, f64::max);
    let k12 = two.c12 + two.k_magnet;
    let weight = (m.m1 - d.masses.load_share * d.masses.load + d.masses.load) * 9.81;
    let gap_sag = (weight + two.constant_pull) / k12;
    // The start-up overshoot of |x1 − x2| beyond its steady peak (offset + amplitude), from the
    // two-mass start-up under the design's law, in proportion to the 3D amplitude.
    let (peak, steady) = startup;
    let over2 = (peak - (two.offset + steady)).max(0.0);
    let gap_startup = if two.rel > 0.0 {
        over2 * gap_amp / two.rel
    } else {
        over2
    };
    let gap_closing = gap_sag + gap_amp + gap_startup + d.drive.gap_margin;
    let f_iso = (m.c13 / m_total).sqrt() / TAU;
    let trans = transmissibility(d.excitation_hz / f_iso, 0.0)?;
    Ok(ChainValues {
        omega,
        m_table: parts.m_table,
        f_table: parts.f_table,
        k_coil: parts.k_coil,
        m1: m.m1,
        m2: m.m2,
        m_red: m.m_red,
        c13: m.c13,
        h_given: leaf.h_given,
        k_leaf_given: leaf.k_given,
        h: mach.h,
        k_leaf: mach.k,
        stress_per_m: mach.stress_per_m,
        iters: leaf.iters.clone(),
        c12: two.c12,
        z: two.z,
        w1: two.w1,
        w2: two.w2,
        force: two.force,
        constant_pull: two.constant_pull,
        offset: two.offset,
        x1: r.mean,
        x2: r.reactive_amplitude,
        rel,
        x1_two_mass: two.x1,
        x2_two_mass: two.x2,
        rel_two_mass: two.rel,
        sigma_leaf_two_mass: two.sigma_leaf,
        gamma1: two.gamma1,
        gamma2: two.gamma2,
        power: two.power,
        p_req: two.p_req,
        transient: tr.summary(10)?,
        f_iso,
        trans,
        sigma_leaf: mach.stress_per_m * rel,
        tau,
        m2_for_target,
        builtin: d.is_builtin(),
        force_law: d.drive.force_law.clone(),
        mains_hz: d.mains_hz(),
        k_magnet: two.k_magnet,
        z_machine: machine_z(d, r),
        h_two_mass: leaf.h,
        iters_machine: mach.iters.clone(),
        gap_sag,
        gap_amplitude: gap_amp,
        gap_startup,
        gap_closing,
        model_difference: difference,
        two_mass: two,
        paper,
        machine: mach.result,
    })
}

/// The report's notes: the force laws, what tuning changed, the two models' difference, a
/// missing working mode, the machine's size.
fn notes(d: &Design, v: &ChainValues) -> Vec<String> {
    let mut notes = vec![];
    if v.builtin {
        notes.push(format!(
            "the built-in paper design is compared with the published numbers under the paper's force law P·|sin ωt| \
             on its two-mass chain (leaves tuned on the two-mass model, no magnet stiffness); its verdict is taken \
             under the design's force law '{}' on the 3D machine",
            v.force_law
        ));
    }
    if let Some(Err(e)) = &v.m2_for_target {
        notes.push(format!("no reactive mass reaches z = {}: {e}", d.target_detuning));
    }
    if d.tune == "leaf" {
        notes.push(format!(
            "with the clamping coefficient {} the given {:.1} mm leaves give z = {:.3} (two-mass); the two-mass \
             tuning gives {:.2} mm (eq. (16) with i = {}, k = {}: {:.2} mm); tuned on the 3D machine's working mode \
             with the magnets' stiffness {:.3e} N/m: {:.3} mm (z = {:.5})",
            d.leaf.clamping,
            v.h_given * 1e3,
            v.iters[0].1,
            v.h_two_mass * 1e3,
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
                * 1e3,
            v.k_magnet,
            v.h * 1e3,
            v.z_machine
        ));
    }
    if let Some(s) = &v.model_difference {
        notes.push(s.clone());
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

/// A relative difference in per cent with its sign and one decimal; one that rounds to zero is
/// "+0.0" (never "-0.0", a rounding's sign).
fn signed_pct(rel: f64) -> String {
    let r = (1000.0 * rel).round() / 10.0;
    format!("{:+.1}", if r == 0.0 { 0.0 } else { r })
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_difference_that_rounds_to_zero_has_no_minus_sign() {
        assert_eq!(super::signed_pct(-1e-5), "+0.0");
        assert_eq!(super::signed_pct(0.409), "+40.9");
        assert_eq!(super::signed_pct(-0.0012), "-0.1");
    }
}
