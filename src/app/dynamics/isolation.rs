//! Vibration isolation of the table (docs/spec/paper.md §16, eq. (17)–(19)): isolator stiffness from a target
//! isolation frequency, transmissibility to the floor, and the helical coil springs that make up
//! the isolators (turns, Wahl factor, shear stress).
//!
//! The force the two-mass model actually transmits through the isolators is
//! [`super::TwoMass::floor_force`].

use std::f64::consts::PI;

use crate::{Error, Result};

fn pos(name: &str, v: f64, unit: &str) -> Result<()> {
    if !(v.is_finite() && v > 0.0) {
        return Err(Error::param(
            name,
            format!("{name} must be finite and > 0 {unit}, got {v}"),
        ));
    }
    Ok(())
}

/// Eq. (17)/(18): total isolator stiffness c13 = M_tot·(2π·n13)², N/m, that puts the table of total
/// mass M_tot (kg: oscillating masses plus load) at the rigid-body isolation frequency n13 (Hz).
/// Paper: (368.5 + 120) kg at 5 Hz → 482 128 N/m = 8 × 60 266 N/m.
pub fn c13_for_isolation_frequency(total_mass: f64, n13_hz: f64) -> Result<f64> {
    pos("total mass on the isolators", total_mass, "kg")?;
    pos("isolation frequency n13", n13_hz, "Hz")?;
    Ok(total_mass * (2.0 * PI * n13_hz).powi(2))
}

/// Eq. (18): rigid-body isolation frequency n13 = sqrt(c13/M_tot)/(2π), Hz (c13 in N/m, mass in kg).
pub fn isolation_frequency_hz(c13: f64, total_mass: f64) -> Result<f64> {
    pos("isolator stiffness c13", c13, "N/m")?;
    pos("total mass on the isolators", total_mass, "kg")?;
    Ok((c13 / total_mass).sqrt() / (2.0 * PI))
}

/// Force transmissibility of a single-mass isolator at the frequency ratio r = f/n13 (≥ 0) with
/// damping ratio ζ (≥ 0): `T = sqrt(1 + (2ζr)²) / sqrt((1 − r²)² + (2ζr)²)`; undamped
/// `1/|1 − r²|` (paper: r = 20 → 1/399 ≈ "400 times").
///
/// Errors: r or ζ negative/non-finite, and r = 1 with ζ = 0 (undamped resonance: unbounded).
pub fn transmissibility(r: f64, zeta: f64) -> Result<f64> {
    if !(r.is_finite() && r >= 0.0) {
        return Err(Error::param(
            "r",
            format!("frequency ratio r must be finite and ≥ 0, got {r}"),
        ));
    }
    if !(zeta.is_finite() && zeta >= 0.0) {
        return Err(Error::param(
            "zeta",
            format!("damping ratio ζ must be finite and ≥ 0, got {zeta}"),
        ));
    }
    let a = 1.0 - r * r;
    let b = 2.0 * zeta * r;
    let den = (a * a + b * b).sqrt();
    if den == 0.0 {
        return Err(Error::param(
            "r",
            "transmissibility at r = 1 with no damping: the isolator is at resonance (unbounded)",
        ));
    }
    Ok((1.0 + b * b).sqrt() / den)
}

/// Spring index C = D/d (dimensionless) of a coil with mean diameter D and wire diameter d (m).
pub fn spring_index(mean_d: f64, wire_d: f64) -> Result<f64> {
    pos("mean coil diameter D", mean_d, "m")?;
    pos("wire diameter d", wire_d, "m")?;
    Ok(mean_d / wire_d)
}

/// Wahl stress-correction factor K = (4C − 1)/(4C − 4) + 0.615/C for spring index C > 1.
/// Paper: C = 32/6 = 5.333 → 1.288 (the paper rounds to 1.28).
pub fn wahl_factor(c: f64) -> Result<f64> {
    if !(c.is_finite() && c > 1.0) {
        return Err(Error::param(
            "c",
            format!("spring index C = D/d must be finite and > 1, got {c}"),
        ));
    }
    Ok((4.0 * c - 1.0) / (4.0 * c - 4.0) + 0.615 / c)
}

/// Eq. (19) solved for the turns: i = G·d⁴/(8·D³·k) (active turns, dimensionless) for the axial
/// stiffness k (N/m), shear modulus G (Pa), wire diameter d and mean diameter D (m).
/// Paper: k = 60 266 N/m, G = 7.7e10, d = 6 mm, D = 32 mm → 6.317.
pub fn coil_turns_for_stiffness(k: f64, g: f64, wire_d: f64, mean_d: f64) -> Result<f64> {
    pos("spring stiffness k", k, "N/m")?;
    pos("shear modulus G", g, "Pa")?;
    pos("wire diameter d", wire_d, "m")?;
    pos("mean coil diameter D", mean_d, "m")?;
    Ok(g * wire_d.powi(4) / (8.0 * mean_d.powi(3) * k))
}

/// Shear stress τ = 8·K·Q·D/(π·d³), Pa, in a coil spring under the axial load Q (N) with the stress
/// factor K (≥ 1, e.g. [`wahl_factor`]), mean diameter D and wire diameter d (m).
/// Paper: Q = 600 N, D = 32 mm, d = 6 mm, K = 1.28 → 289.7 MPa (291.6 MPa with K = 1.2884).
pub fn coil_shear_stress(q: f64, k_factor: f64, mean_d: f64, wire_d: f64) -> Result<f64> {
    if !q.is_finite() {
        return Err(Error::param("q", format!("axial load Q must be finite, got {q} N")));
    }
    if !(k_factor.is_finite() && k_factor >= 1.0) {
        return Err(Error::param(
            "k_factor",
            format!("stress factor K must be finite and ≥ 1, got {k_factor}"),
        ));
    }
    pos("mean coil diameter D", mean_d, "m")?;
    pos("wire diameter d", wire_d, "m")?;
    Ok(8.0 * k_factor * q.abs() * mean_d / (PI * wire_d.powi(3)))
}

/// A helical compression spring (isolator).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoilSpring {
    /// Wire diameter d, m.
    pub wire_d: f64,
    /// Mean coil diameter D, m.
    pub mean_d: f64,
    /// Active turns i_n (dimensionless, > 0; need not be an integer).
    pub turns: f64,
    /// Shear modulus G, Pa (spring steel 7.7e10).
    pub shear_modulus: f64,
}

impl CoilSpring {
    /// A validated spring (all quantities finite and > 0, D > d).
    pub fn new(wire_d: f64, mean_d: f64, turns: f64, shear_modulus: f64) -> Result<Self> {
        let s = CoilSpring {
            wire_d,
            mean_d,
            turns,
            shear_modulus,
        };
        s.validate()?;
        Ok(s)
    }

    /// The paper's isolator (docs/spec/scenes.md S5): d = 6 mm, D = 32 mm, 6 turns, G = 7.7e10 Pa.
    pub fn paper() -> Self {
        CoilSpring {
            wire_d: 0.006,
            mean_d: 0.032,
            turns: 6.0,
            shear_modulus: 7.7e10,
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        pos("wire diameter d", self.wire_d, "m")?;
        pos("mean coil diameter D", self.mean_d, "m")?;
        pos("active turns i_n", self.turns, "")?;
        pos("shear modulus G", self.shear_modulus, "Pa")?;
        if self.mean_d <= self.wire_d {
            return Err(Error::param(
                "mean_d",
                format!(
                    "coil spring: mean diameter D = {} m must exceed the wire diameter d = {} m",
                    self.mean_d, self.wire_d
                ),
            ));
        }
        Ok(())
    }

    /// Axial stiffness k = G·d⁴/(8·D³·i_n), N/m (eq. (19)). Paper spring with 6 turns: 63 446 N/m.
    pub fn stiffness(&self) -> Result<f64> {
        self.validate()?;
        Ok(self.shear_modulus * self.wire_d.powi(4) / (8.0 * self.mean_d.powi(3) * self.turns))
    }

    /// Wahl factor of this spring (dimensionless).
    pub fn wahl_factor(&self) -> Result<f64> {
        self.validate()?;
        wahl_factor(self.mean_d / self.wire_d)
    }

    /// Shear stress under the axial load Q (N) with the Wahl factor, Pa.
    pub fn shear_stress(&self, q: f64) -> Result<f64> {
        coil_shear_stress(q, self.wahl_factor()?, self.mean_d, self.wire_d)
    }
}
