//! Helical compression springs (round wire): stress correction factors, mean and alternating
//! shear, fatigue safety with Zimmerli's endurance data, solid length and binding margin, and
//! the surge frequency against the force harmonics.
//!
//! Sources: Budynas & Nisbett, Shigley's Mechanical Engineering Design, 9th ed. (2011), ch. 10
//! (Wahl and Bergsträsser factors §10-2, end types Table 10-1, Zimmerli data §10-9, surge §10-8);
//! A. M. Wahl, Mechanical Springs, 2nd ed. (1963).

use crate::{Error, Result};
use serde::Serialize;
use std::f64::consts::PI;

/// Zimmerli's endurance data for unpeened spring steel wire (d < 10 mm, infinite life):
/// S_sa = 241 MPa at S_sm = 379 MPa (35 and 55 kpsi; Shigley 9th ed., §10-9, Eq. (10-28)).
pub const ZIMMERLI_UNPEENED: (f64, f64) = (241e6, 379e6);
/// Zimmerli's data for peened wire: S_sa = 398 MPa at S_sm = 534 MPa (57.5 and 77.5 kpsi).
pub const ZIMMERLI_PEENED: (f64, f64) = (398e6, 534e6);

fn index(d: f64, big_d: f64) -> Result<f64> {
    let c = big_d / d;
    if !(c.is_finite() && c > 1.0 && d > 0.0) {
        return Err(Error::param(
            "spring index",
            format!("spring index C = D/d = {big_d}/{d} must be finite and > 1"),
        ));
    }
    Ok(c)
}

/// Wahl factor K_W = (4C − 1)/(4C − 4) + 0.615/C for the index C = D/d (Wahl 1963; Shigley
/// 9th ed., §10-2).
pub fn wahl_factor(c: f64) -> f64 {
    (4.0 * c - 1.0) / (4.0 * c - 4.0) + 0.615 / c
}

/// Bergsträsser factor K_B = (4C + 2)/(4C − 3) (Shigley 9th ed., Eq. (10-5)).
pub fn bergstrasser_factor(c: f64) -> f64 {
    (4.0 * c + 2.0) / (4.0 * c - 3.0)
}

/// Corrected shear stress τ = K·8FD/(πd³) (Pa) under the axial force `f` (N) with the factor `k`.
pub fn shear_stress(k: f64, f: f64, d: f64, big_d: f64) -> f64 {
    k * 8.0 * f * big_d / (PI * d.powi(3))
}

/// Axial rate k = d⁴G/(8D³N_a) (N/m).
pub fn rate(d: f64, big_d: f64, g: f64, active: f64) -> f64 {
    d.powi(4) * g / (8.0 * big_d.powi(3) * active)
}

/// Tensile strength of spring wire, S_ut = A/d^m (Shigley 9th ed., Eq. (10-14)); `a` and `d` in
/// consistent units (kpsi·in^m and in, or MPa·mm^m and mm).
pub fn wire_strength(a: f64, m: f64, d: f64) -> f64 {
    a / d.powf(m)
}

/// Torsional ultimate strength estimate S_su = 0.67 S_ut (Shigley 9th ed., Eq. (10-30)).
pub fn torsional_ultimate(s_ut: f64) -> f64 {
    0.67 * s_ut
}

/// How the endurance line through Zimmerli's point is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SpringCriterion {
    /// Goodman line through (S_sm, S_sa) and (S_su, 0).
    Goodman,
    /// Gerber parabola through the same points.
    Gerber,
}

/// The fully reversed torsional endurance S_se of the line through Zimmerli's point
/// (S_sm, S_sa) and (S_su, 0): Goodman S_sa/(1 − S_sm/S_su), Gerber S_sa/(1 − (S_sm/S_su)²)
/// (Shigley 9th ed., §10-9).
pub fn zimmerli_endurance(crit: SpringCriterion, ssa: f64, ssm: f64, ssu: f64) -> f64 {
    match crit {
        SpringCriterion::Goodman => ssa / (1.0 - ssm / ssu),
        SpringCriterion::Gerber => ssa / (1.0 - (ssm / ssu).powi(2)),
    }
}

/// Fatigue safety of a spring at alternating and mean shear `ta`, `tm` along the load line
/// r = τ_a/τ_m through the origin (Shigley 9th ed., §10-9, Table 6-7 with torsional strengths):
/// Goodman n = 1/(τ_a/S_se + τ_m/S_su), Gerber n = ½(S_su/τ_m)²(τ_a/S_se)[−1 + √(1 + (2τ_m S_se/(S_su τ_a))²)].
pub fn spring_safety(crit: SpringCriterion, ta: f64, tm: f64, sse: f64, ssu: f64) -> f64 {
    let ta = ta.abs();
    if tm <= 0.0 {
        return if ta > 0.0 { sse / ta } else { f64::INFINITY };
    }
    if ta == 0.0 {
        return ssu / tm;
    }
    match crit {
        SpringCriterion::Goodman => 1.0 / (ta / sse + tm / ssu),
        SpringCriterion::Gerber => {
            let q = 2.0 * tm * sse / (ssu * ta);
            0.5 * (ssu / tm).powi(2) * (ta / sse) * (-1.0 + (1.0 + q * q).sqrt())
        }
    }
}

/// End type of a compression spring (Shigley 9th ed., Table 10-1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Ends {
    /// Plain: N_t = N_a, L_s = d(N_t + 1), L_0 = pN_a + d.
    Plain,
    /// Plain and ground: N_t = N_a + 1, L_s = dN_t, L_0 = p(N_a + 1).
    PlainGround,
    /// Squared (closed): N_t = N_a + 2, L_s = d(N_t + 1), L_0 = pN_a + 3d.
    Squared,
    /// Squared and ground: N_t = N_a + 2, L_s = dN_t, L_0 = pN_a + 2d.
    SquaredGround,
}

/// Free length, solid length and total turns of a spring with `active` turns, pitch `p`, wire
/// `d` and the given ends (Shigley 9th ed., Table 10-1).
pub fn lengths(ends: Ends, d: f64, p: f64, active: f64) -> (f64, f64, f64) {
    match ends {
        Ends::Plain => (p * active + d, d * (active + 1.0), active),
        Ends::PlainGround => (p * (active + 1.0), d * (active + 1.0), active + 1.0),
        Ends::Squared => (p * active + 3.0 * d, d * (active + 3.0), active + 2.0),
        Ends::SquaredGround => (p * active + 2.0 * d, d * (active + 2.0), active + 2.0),
    }
}

/// Binding (coil clash) check: the travel to solid L_0 − L_s against the largest deflection in
/// service, static + dynamic amplitude + start-up excess.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Binding {
    /// Travel from free to solid length (m).
    pub travel: f64,
    /// Largest deflection in service (m).
    pub deflection: f64,
    /// Margin (travel − deflection)/travel: the fraction of the travel left.
    pub margin: f64,
    /// Fractional overrun to closure ξ = travel/deflection − 1 (Shigley's ξ ≥ 0.15, Eq. (10-20)).
    pub overrun: f64,
}

/// [`Binding`] for free and solid lengths and the deflections (m).
pub fn binding(free: f64, solid: f64, static_defl: f64, dynamic: f64, startup: f64) -> Binding {
    let travel = free - solid;
    let deflection = static_defl.abs() + dynamic.abs() + startup.abs();
    Binding {
        travel,
        deflection,
        margin: (travel - deflection) / travel,
        overrun: travel / deflection - 1.0,
    }
}

/// Surge (first axial standing-wave) frequency of a spring between two fixed plates,
/// f_s = d/(2π N_a D²)·√(G/(2ρ)) (Hz) (Shigley 9th ed., Eq. (10-25) with W = π²d²DN_aρg/4;
/// equal to ½√(k/m_spring) of the active coils).
pub fn surge_frequency(d: f64, big_d: f64, active: f64, g: f64, rho: f64) -> f64 {
    d / (2.0 * PI * active * big_d * big_d) * (g / (2.0 * rho)).sqrt()
}

/// The harmonic k·f of the force nearest the surge frequency `fs` among k = 1..=`harmonics`,
/// and the clearance |fs − k f|/(k f).
pub fn surge_clearance(fs: f64, f: f64, harmonics: usize) -> Result<(usize, f64)> {
    if !(f.is_finite() && f > 0.0 && fs.is_finite() && fs > 0.0) || harmonics == 0 {
        return Err(Error::param(
            "surge",
            format!("surge clearance: frequencies {fs} and {f} must be positive, harmonics ≥ 1"),
        ));
    }
    Ok((1..=harmonics)
        .map(|k| (k, (fs - k as f64 * f).abs() / (k as f64 * f)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((1, f64::INFINITY)))
}

/// Index C = D/d after checking it (C > 1).
pub fn spring_index(d: f64, big_d: f64) -> Result<f64> {
    index(d, big_d)
}

/// Critical deflection of a helical compression spring against lateral buckling (Haringx's
/// theory, the criterion of EN 13906-1:2013 §9.2; the same closed form as Shigley 9th ed.,
/// ch. 10 "Stability", y_cr = L0·C1·[1 − √(1 − C2/λ²)], C1 = E/(2(E − G)),
/// C2 = 2π²(E − G)/(2G + E), λ = νL0/D):
///
/// s_k = L0 · 0.5/(1 − G/E) · [1 − √(1 − (1 − G/E)/(0.5 + G/E) · (πD/(νL0))²)]
///
/// with the free length `free` L0, the mean coil diameter `big_d` D, the seating coefficient
/// `seating` ν (EN 13906-1 Fig. 6: 0.5 both ends clamped parallel, 0.7 one clamped one pinned,
/// 1 both pinned or guided, 2 one clamped one free) and the moduli E, G. `Ok(None)`: the
/// spring is stable at any deflection (the root is imaginary: L0 < πD/ν·√((1 − G/E)/(0.5 + G/E)),
/// about 2.62 D/ν for steel).
pub fn buckling_deflection(free: f64, big_d: f64, seating: f64, young: f64, shear: f64) -> Result<Option<f64>> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    if !(ok(free) && ok(big_d) && ok(seating) && ok(young) && ok(shear)) || shear >= young {
        return Err(Error::param(
            "spring",
            format!(
                "coil buckling: free length {free}, mean diameter {big_d}, seating coefficient {seating}, E {young}, \
                 G {shear} must be positive with G < E"
            ),
        ));
    }
    let r = shear / young;
    let x = (1.0 - r) / (0.5 + r) * (PI * big_d / (seating * free)).powi(2);
    if x >= 1.0 {
        return Ok(None);
    }
    Ok(Some(free * 0.5 / (1.0 - r) * (1.0 - (1.0 - x).sqrt())))
}
