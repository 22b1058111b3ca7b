//! Synthesis formulas of the paper: resonance tuning (eq. (5)), the leaf-spring thickness
//! (eq. (16)) and its stress, damping from a loss factor (§18) and the drive power (eq. (6)).

use crate::{Error, Result};

/// Standard gravity used to express accelerations as overloads, m/s² (the paper's 9.81).
pub const G_ACCEL: f64 = 9.81;

fn pos(name: &str, v: f64, unit: &str) -> Result<()> {
    if !(v.is_finite() && v > 0.0) {
        return Err(Error::param(
            name,
            format!("{name} must be finite and > 0 {unit}, got {v}"),
        ));
    }
    Ok(())
}

/// Reduced mass m_red = m1·m2/(m1 + m2), kg, from m1, m2 in kg (both > 0).
pub fn reduced_mass(m1: f64, m2: f64) -> Result<f64> {
    pos("m1 (active mass)", m1, "kg")?;
    pos("m2 (reactive mass)", m2, "kg")?;
    Ok(m1 * m2 / (m1 + m2))
}

/// Eq. (5): the leaf-spring stiffness c12 = m_red·(Ω/z)², N/m, that tunes the pair to
/// ω0 = Ω/z. Masses in kg, Ω in rad/s (> 0), tuning z > 0 (z < 1: the machine runs below resonance).
///
/// Paper: m1 = 206.7, m2 = 161.8 kg, Ω = 2π·100, z = 0.97 → 3.808e7 N/m.
pub fn c12_from_detuning(m1: f64, m2: f64, omega: f64, z: f64) -> Result<f64> {
    let mr = reduced_mass(m1, m2)?;
    pos("forcing frequency Ω", omega, "rad/s")?;
    if !(z.is_finite() && z > 0.0) {
        return Err(Error::param(
            "z",
            format!("resonance tuning z = Ω/ω0 must be finite and > 0, got {z}"),
        ));
    }
    Ok(mr * (omega / z).powi(2))
}

/// Inverse of eq. (5): the tuning z = Ω/sqrt(c12/m_red) (dimensionless) for a given c12 (N/m, > 0).
pub fn detuning_from_c12(m1: f64, m2: f64, omega: f64, c12: f64) -> Result<f64> {
    let mr = reduced_mass(m1, m2)?;
    pos("forcing frequency Ω", omega, "rad/s")?;
    pos("c12 (leaf-spring stiffness)", c12, "N/m")?;
    Ok(omega / (c12 / mr).sqrt())
}

/// Design iteration on the tuning plates: the reactive mass m2 (kg) that tunes a given c12 (N/m)
/// to z at Ω (rad/s) for the active mass m1 (kg), from eq. (5): m_red = c12·z²/Ω², then
/// m2 = m1·m_red/(m1 − m_red). Paper: m1 = 206.7 kg, c12 = 3.808e7 N/m, z = 0.97 → 161.8 kg.
///
/// Errors: non-positive inputs, and m_red ≥ m1 (no finite m2 reaches that tuning: the pair's
/// reduced mass is always below m1).
pub fn reactive_mass_for_detuning(m1: f64, c12: f64, omega: f64, z: f64) -> Result<f64> {
    pos("m1 (active mass)", m1, "kg")?;
    pos("c12 (leaf-spring stiffness)", c12, "N/m")?;
    pos("forcing frequency Ω", omega, "rad/s")?;
    if !(z.is_finite() && z > 0.0) {
        return Err(Error::param(
            "z",
            format!("resonance tuning z = Ω/ω0 must be finite and > 0, got {z}"),
        ));
    }
    let mr = c12 * z * z / (omega * omega);
    if mr >= m1 {
        return Err(Error::param(
            "z",
            format!(
                "tuning z = {z} with c12 = {c12} N/m needs a reduced mass {mr:.4} kg ≥ m1 = {m1} kg: \
             no reactive mass m2 can reach it (stiffen the leaves or raise z)"
            ),
        ));
    }
    Ok(m1 * mr / (m1 - mr))
}

/// Viscous coefficient from a frequency-independent loss factor (the paper's "internal-friction
/// coefficient" ψ, §18): μ = c·ψ/Ω, N·s/m, from c in N/m, ψ ≥ 0 (dimensionless), Ω in rad/s (> 0).
/// The equivalent viscous damper dissipates the same energy per cycle at Ω as the hysteretic
/// spring c(1 + iψ).
///
/// Paper: c12 = 3.808e7 N/m, ψ = 0.03, Ω = 628.3 rad/s → 1818 N·s/m (the paper prints 1830).
pub fn damping_from_loss_factor(c: f64, psi: f64, omega: f64) -> Result<f64> {
    pos("stiffness c", c, "N/m")?;
    pos("forcing frequency Ω", omega, "rad/s")?;
    if !(psi.is_finite() && psi >= 0.0) {
        return Err(Error::param(
            "psi",
            format!("loss factor ψ must be finite and ≥ 0, got {psi}"),
        ));
    }
    Ok(c * psi / omega)
}

fn check_leaf(n_leaves: usize, e: f64, b: f64, l: f64, k_clamp: f64) -> Result<()> {
    if n_leaves == 0 {
        return Err(Error::param(
            "n_leaves",
            "number of leaves (elastic pairs) i must be ≥ 1",
        ));
    }
    pos("Young's modulus E", e, "Pa")?;
    pos("leaf width b", b, "m")?;
    pos("leaf free length l", l, "m")?;
    if !(k_clamp.is_finite() && k_clamp > 0.0 && k_clamp <= 1.0) {
        return Err(Error::param(
            "k_clamp",
            format!("clamping coefficient k must be in (0, 1], got {k_clamp}"),
        ));
    }
    Ok(())
}

/// Eq. (16): thickness h = l·∛(c12/(E·b·i·k)), m, of `n_leaves` (i) fixed–guided leaves in
/// parallel that give the total stiffness c12 (N/m), for Young's modulus E (Pa), width b (m), free
/// length l (m) and clamping coefficient k (0 < k ≤ 1; the paper takes 0.75).
///
/// Paper: c12 = 3.808e7, l = 0.169, b = 0.146, E = 2.1e11, i = 8: 10.00 mm with k = 0.75, 9.08 mm
/// with k = 1 (the paper states 9 mm; see docs/spec/paper.md §12).
pub fn leaf_thickness_for_stiffness(c12: f64, n_leaves: usize, e: f64, b: f64, l: f64, k_clamp: f64) -> Result<f64> {
    pos("c12 (leaf-spring stiffness)", c12, "N/m")?;
    check_leaf(n_leaves, e, b, l, k_clamp)?;
    Ok(l * (c12 / (e * b * n_leaves as f64 * k_clamp)).cbrt())
}

/// Inverse of eq. (16): the total stiffness c12 = E·b·i·k·(h/l)³, N/m, of `n_leaves` leaves of
/// thickness h (m); other arguments as in [`leaf_thickness_for_stiffness`].
pub fn stiffness_for_leaf_thickness(h: f64, n_leaves: usize, e: f64, b: f64, l: f64, k_clamp: f64) -> Result<f64> {
    pos("leaf thickness h", h, "m")?;
    check_leaf(n_leaves, e, b, l, k_clamp)?;
    Ok(e * b * n_leaves as f64 * k_clamp * (h / l).powi(3))
}

/// Maximum bending stress of a fixed–guided leaf under an end deflection Δ without rotation,
/// σ = 3·E·h·Δ/l², Pa (E in Pa; h, Δ, l in m). Paper §14: h 9 mm, Δ 0.46 mm, l 169 mm → 91.3 MPa.
pub fn leaf_bending_stress(e: f64, h: f64, l: f64, delta: f64) -> Result<f64> {
    pos("Young's modulus E", e, "Pa")?;
    pos("leaf thickness h", h, "m")?;
    pos("leaf free length l", l, "m")?;
    if !delta.is_finite() {
        return Err(Error::param(
            "delta",
            format!("deflection Δ must be finite, got {delta} m"),
        ));
    }
    Ok(3.0 * e * h * delta.abs() / (l * l))
}

/// Overload K = X·Ω²/g (in g) of a harmonic motion of amplitude X (m) at Ω (rad/s).
pub fn overload_g(x: f64, omega: f64) -> f64 {
    x * omega * omega / G_ACCEL
}

/// Eq. (6): drive power, W,
/// `N = Ω³/(2η)·(Σ_j X_j²·m_j/γ_j + X1²·m_pr)`.
///
/// `terms` holds (X_j in m, m_j in kg, γ_j dimensionless > 0) for each oscillating mass; `x1` (m)
/// is the amplitude of the work organ and `m_pr` (kg, ≥ 0) the load mass attached to it; Ω in
/// rad/s; η the drive efficiency, 0 < η ≤ 1 (illegible in the paper: 0.7 gives 1.81 kW, 0.57
/// gives 2.2 kW for the §18 inputs).
pub fn drive_power(omega: f64, eta: f64, terms: &[(f64, f64, f64)], x1: f64, m_pr: f64) -> Result<f64> {
    pos("forcing frequency Ω", omega, "rad/s")?;
    if !(eta.is_finite() && eta > 0.0 && eta <= 1.0) {
        return Err(Error::param(
            "eta",
            format!("drive efficiency η must be in (0, 1], got {eta}"),
        ));
    }
    if !(m_pr.is_finite() && m_pr >= 0.0) {
        return Err(Error::param(
            "m_pr",
            format!("attached load mass m_pr must be ≥ 0 kg, got {m_pr}"),
        ));
    }
    if !x1.is_finite() {
        return Err(Error::param("x1", format!("amplitude X1 must be finite, got {x1} m")));
    }
    let mut s = x1 * x1 * m_pr;
    for (j, &(x, m, g)) in terms.iter().enumerate() {
        if !x.is_finite() {
            return Err(Error::param(
                "terms",
                format!("amplitude X{} must be finite, got {x} m", j + 1),
            ));
        }
        pos(&format!("mass m{}", j + 1), m, "kg")?;
        pos(&format!("dynamic factor γ{}", j + 1), g, "")?;
        s += x * x * m / g;
    }
    Ok(omega.powi(3) / (2.0 * eta) * s)
}
