//! The fatigue checks of the design: the leaves (mean stress from the static sag under the
//! active part's weight and the magnets' constant pull, alternating stress from the relative
//! amplitude), the coil isolators (Wahl-corrected mean and alternating shear against Zimmerli's
//! data), the coils' binding margin, their buckling margin (Haringx, EN 13906-1 §9.2) and their
//! surge frequency against the force harmonics.
//!
//! Every check reads the chain's values by name ([`ChainValues`]: `rel`, `x2`, `offset`,
//! `c12`, `tau`, `k_coil`, …), so it follows whichever model the chain makes the model of
//! record. The library functions are in [`crate::post::fatigue`] and [`crate::post::spring`];
//! docs/fatigue.md gives the method and sources.

use super::file::Design;
use super::parts::leaf_fe_stresses;
use super::results::{ChainValues, Check};
use crate::Result;
use crate::post::fatigue::{
    Endurance, FatigueMaterial, MeanStress, PartCondition, equivalent_diameter_rect, finite_life_strength, safety,
};
use crate::post::spring::{
    Ends, SpringCriterion, ZIMMERLI_PEENED, ZIMMERLI_UNPEENED, binding, buckling_deflection, lengths, shear_stress,
    spring_safety, surge_clearance, surge_frequency, torsional_ultimate, wahl_factor, zimmerli_endurance,
};

/// Standard gravity (m/s²), as the chain uses it.
const G: f64 = 9.81;
/// Density of the coil wire (kg/m³), as the coil's FE part uses it.
const COIL_DENSITY: f64 = 7850.0;

/// The leaf's fatigue numbers at the chain's operating point.
#[derive(Clone, Debug)]
pub struct LeafFatigueValues {
    /// Principal stress per metre of guided displacement (Pa/m).
    pub principal_per_m: f64,
    /// Static deflection of the leaves: weight sag + magnet offset (m).
    pub static_deflection: f64,
    /// Mean and alternating stress (Pa).
    pub sigma_m: f64,
    /// Alternating stress (Pa).
    pub sigma_a: f64,
    /// The corrected endurance and the strength at the design's cycles (Pa).
    pub endurance: Endurance,
    /// Strength at the cycles.
    pub strength: f64,
    /// Safety factor.
    pub safety: f64,
}

/// The leaf's fatigue: σ_m = principal stress per metre × (weight sag + magnet offset), with the
/// weight of everything the leaves carry, (m1 + (1 − load_share)·load)·g over c12, taken tensile
/// (each leaf has a tensile and a compressive clamp fibre; the tensile one governs);
/// σ_a = principal stress per metre × the relative amplitude `rel`.
pub fn leaf_values(d: &Design, v: &ChainValues) -> Result<LeafFatigueValues> {
    let lf = &d.leaf.fatigue;
    let mat = FatigueMaterial::parse("leaf.fatigue.material", &lf.material)?;
    let st = leaf_fe_stresses(d, v.h)?;
    let carried = v.m1 + (1.0 - d.masses.load_share) * d.masses.load;
    let static_deflection = carried * G / v.c12 + v.offset.abs();
    let sigma_m = st.principal_per_m * static_deflection;
    let sigma_a = st.principal_per_m * v.rel;
    let cond = PartCondition {
        rz_um: lf.roughness,
        size_mm: Some(equivalent_diameter_rect(v.h, d.leaf.width) * 1e3),
        reliability: lf.reliability,
    };
    let endurance = Endurance::new(&mat, &cond)?;
    let strength = finite_life_strength(endurance.value, mat.slope, mat.knee_cycles, lf.cycles);
    let ms = MeanStress::parse("leaf.fatigue.mean_stress", &lf.mean_stress)?;
    let n = safety(ms, sigma_a, sigma_m, strength, mat.r_m, mat.mean_stress_sensitivity());
    Ok(LeafFatigueValues {
        principal_per_m: st.principal_per_m,
        static_deflection,
        sigma_m,
        sigma_a,
        endurance,
        strength,
        safety: n,
    })
}

/// The leaves' fatigue safety at the design's cycles against the required safety.
pub fn leaf_fatigue(d: &Design, v: &ChainValues) -> Check {
    let lf = &d.leaf.fatigue;
    let n = leaf_values(d, v).map_or(f64::NAN, |x| x.safety);
    Check::new(
        "leaf_fatigue",
        &format!(
            "leaf fatigue safety at {:.0e} cycles ({}, {}, signed principal stress) ≥ required",
            lf.cycles, lf.material, lf.mean_stress
        ),
        n,
        lf.safety,
        false,
    )
}

/// The coil's numbers at the chain's operating point.
#[derive(Clone, Debug)]
pub struct CoilFatigueValues {
    /// Wahl factor.
    pub wahl: f64,
    /// Mean shear (Pa): the chain's static Wahl stress `tau`.
    pub tau_m: f64,
    /// Alternating shear (Pa): Wahl stress of k_coil·x2.
    pub tau_a: f64,
    /// S_su = 0.67 R_m (Pa).
    pub ssu: f64,
    /// Fully reversed endurance through Zimmerli's point (Pa).
    pub sse: f64,
    /// Safety factor.
    pub safety: f64,
}

/// The coil's fatigue: τ_m the chain's static Wahl stress, τ_a = K_W·8(k_coil·x2)D/(πd³),
/// S_su = 0.67 R_m of the wire, the line through Zimmerli's point, safety on the load line.
pub fn coil_values(d: &Design, v: &ChainValues) -> Result<CoilFatigueValues> {
    let (c, cf) = (&d.coil, &d.coil.fatigue);
    let mat = FatigueMaterial::parse("coil.fatigue.material", &cf.material)?;
    let wahl = wahl_factor(crate::post::spring::spring_index(c.wire, c.mean_diameter)?);
    let tau_a = shear_stress(wahl, v.k_coil * v.x2, c.wire, c.mean_diameter);
    let ssu = torsional_ultimate(mat.r_m);
    let (ssa, ssm) = if cf.peened { ZIMMERLI_PEENED } else { ZIMMERLI_UNPEENED };
    let crit = if cf.criterion == "gerber" {
        SpringCriterion::Gerber
    } else {
        SpringCriterion::Goodman
    };
    let sse = zimmerli_endurance(crit, ssa, ssm, ssu);
    Ok(CoilFatigueValues {
        wahl,
        tau_m: v.tau,
        tau_a,
        ssu,
        sse,
        safety: spring_safety(crit, tau_a, v.tau, sse, ssu),
    })
}

/// The coil isolators' fatigue safety (Zimmerli) against the required safety.
pub fn coil_fatigue(d: &Design, v: &ChainValues) -> Check {
    let cf = &d.coil.fatigue;
    Check::new(
        "coil_fatigue",
        &format!(
            "coil fatigue safety ({}–Zimmerli, {}, Wahl mean and alternating shear) ≥ required",
            cf.criterion, cf.material
        ),
        coil_values(d, v).map_or(f64::NAN, |x| x.safety),
        cf.safety,
        false,
    )
}

/// Free and solid length of the coil from its pitch, active turns and end type.
pub fn coil_lengths(d: &Design) -> (f64, f64, f64) {
    let c = &d.coil;
    let ends = match c.fatigue.ends.as_str() {
        "plain" => Ends::Plain,
        "plain_ground" => Ends::PlainGround,
        "squared" => Ends::Squared,
        _ => Ends::SquaredGround,
    };
    lengths(ends, c.wire, c.pitch, c.turns)
}

/// The start-up peak of the reactive mass in the two-mass transient (m): the chain's model and
/// drive re-run from rest (milliseconds); NaN when the model cannot be built.
fn startup_peak_x2(d: &Design, v: &ChainValues) -> f64 {
    use crate::app::dynamics::electromagnet::RectifiedDrive;
    use crate::app::dynamics::transient::{TransientOptions, simulate_startup};
    use crate::app::dynamics::two_mass::TwoMass;
    let run = || -> Result<f64> {
        let model = TwoMass::new(v.m1, v.m2, v.c12, v.c13, d.damping.mu1, d.damping.mu12, d.damping.mu13)?;
        let drive = RectifiedDrive::from_magnets(d.drive.magnets, d.drive.pull, v.omega / 2.0)?;
        let tr = simulate_startup(
            &model,
            &drive,
            &TransientOptions {
                t_end: d.drive.transient_s,
                ..Default::default()
            },
        )?;
        Ok(tr.x2.iter().fold(0.0f64, |a, x| a.max(x.abs())))
    };
    run().unwrap_or(f64::NAN)
}

/// The binding numbers: travel, static deflection, dynamic amplitude, start-up peak (m).
pub fn coil_binding_values(d: &Design, v: &ChainValues) -> crate::post::spring::Binding {
    let (free, solid, _) = coil_lengths(d);
    let m_total = v.m1 + v.m2 + d.masses.load;
    let static_defl = m_total * G / v.c13;
    let startup = startup_peak_x2(d, v);
    // The start-up peak contains the steady amplitude: count the larger once, beyond the static.
    let excess = (startup - v.x2).max(0.0);
    binding(free, solid, static_defl, v.x2, excess)
}

/// Coil binding: fractional overrun to closure ξ = travel/(static + dynamic + start-up) − 1
/// against the design's least overrun (Shigley's ξ ≥ 0.15).
pub fn coil_binding(d: &Design, v: &ChainValues) -> Check {
    let b = coil_binding_values(d, v);
    Check::new(
        "coil_binding",
        &format!(
            "coil overrun to solid ξ = travel {:.1} mm / (static + dynamic + start-up {:.2} mm) − 1 ≥ limit",
            b.travel * 1e3,
            b.deflection * 1e3
        ),
        b.overrun,
        d.coil.fatigue.overrun,
        false,
    )
}

/// The coil's buckling numbers (m): the critical deflection and the working deflection.
#[derive(Clone, Debug)]
pub struct CoilBucklingValues {
    /// Critical deflection s_k (Haringx, EN 13906-1 §9.2) for the design's seating coefficient ν;
    /// for a coil stable at any deflection, its value at the stability limit, 0.5·L0/(1 − G/E)
    /// (the formula's limit there: continuous across it, ≈ 0.81 L0 for steel).
    pub critical: f64,
    /// The coil is stable at any deflection (L0 < πD/ν·√((1 − G/E)/(0.5 + G/E))).
    pub stable: bool,
    /// Static + dynamic + start-up deflection, as the binding check takes it.
    pub deflection: f64,
}

/// The coil's critical buckling deflection against the binding check's deflection; E = 2G(1 + 0.3)
/// as the coil's FE part takes it.
pub fn coil_buckling_values(d: &Design, v: &ChainValues) -> Result<CoilBucklingValues> {
    let c = &d.coil;
    let (free, _, _) = coil_lengths(d);
    let shear = c.shear_modulus;
    let young = 2.0 * shear * (1.0 + 0.3);
    let sk = buckling_deflection(free, c.mean_diameter, c.fatigue.seating, young, shear)?;
    Ok(CoilBucklingValues {
        critical: sk.unwrap_or(0.5 * free / (1.0 - shear / young)),
        stable: sk.is_none(),
        deflection: coil_binding_values(d, v).deflection,
    })
}

/// Coil buckling: fractional reserve s_k/(static + dynamic + start-up) − 1 against the binding
/// check's least overrun (`coil.fatigue.overrun`).
pub fn coil_buckling(d: &Design, v: &ChainValues) -> Check {
    let b = coil_buckling_values(d, v);
    let (value, what) = match &b {
        Ok(b) => (
            b.critical / b.deflection - 1.0,
            format!(
                "{} s_k {:.1} mm / (static + dynamic + start-up {:.2} mm)",
                if b.stable {
                    "stable at any deflection;"
                } else {
                    "critical deflection"
                },
                b.critical * 1e3,
                b.deflection * 1e3
            ),
        ),
        Err(_) => (
            f64::NAN,
            "critical deflection s_k / (static + dynamic + start-up)".to_string(),
        ),
    };
    Check::new(
        "coil_buckling",
        &format!(
            "coil buckling (Haringx, EN 13906-1, seating ν = {}): {what} − 1 ≥ limit",
            d.coil.fatigue.seating
        ),
        value,
        d.coil.fatigue.overrun,
        false,
    )
}

/// The coil's surge frequency (Hz) and, among the force harmonics k·f (k up to one beyond the
/// surge frequency), the nearest and its clearance.
pub fn coil_surge_values(d: &Design) -> (f64, usize, f64) {
    let c = &d.coil;
    let fs = surge_frequency(c.wire, c.mean_diameter, c.turns, c.shear_modulus, COIL_DENSITY);
    let harmonics = (fs / d.excitation_hz).ceil() as usize + 1;
    let (k, cl) = surge_clearance(fs, d.excitation_hz, harmonics.max(1)).unwrap_or((0, f64::NAN));
    (fs, k, cl)
}

/// The surge frequency at least the design's clearance from every harmonic of the force (the
/// rectified pull has every multiple of the excitation).
pub fn coil_surge(d: &Design, v: &ChainValues) -> Check {
    let _ = v;
    let (fs, k, cl) = coil_surge_values(d);
    Check::new(
        "coil_surge",
        &format!(
            "coil surge frequency {fs:.0} Hz clear of the force harmonics (nearest {k} × {} Hz) [%]",
            d.excitation_hz
        ),
        cl * 100.0,
        d.coil.fatigue.surge_clearance * 100.0,
        false,
    )
}
