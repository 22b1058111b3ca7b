//! Hex8 with incompatible modes (Wilson, Taylor, Doherty, Ghaboussi 1973; Taylor, Beresford,
//! Wilson 1976: "QM6" in 3D), the formulation commercial codes call HEXA8/C3D8I.
//!
//! A plain trilinear hex8 cannot bend: its displacements are linear in each direction, so a
//! pure bending state comes with parasitic shear (shear locking), and one element through a
//! thickness is far too stiff. Nine internal displacement modes are added,
//!
//! ```text
//! u(ξ) = Σ_a N_a(ξ) u_a + Σ_k P_k(ξ) α_k,   P_1 = 1 − ξ², P_2 = 1 − η², P_3 = 1 − ζ²,
//! ```
//!
//! (three modes × three components), which represent the quadratic bending displacement. The
//! modes are incompatible between elements (not shared) and are condensed at element level:
//! with `K = [K_cc K_ci; K_ic K_ii]` integrated by 2 × 2 × 2 Gauss,
//!
//! ```text
//! K* = K_cc − K_ci K_ii⁻¹ K_ic,     α = −K_ii⁻¹ K_ic u.
//! ```
//!
//! **Taylor's correction.** On a distorted element the mode gradients are evaluated with the
//! Jacobian at the centre, `∇P_k = (det J₀ / det J(ξ)) J₀⁻ᵀ ∂P_k/∂ξ`, so that
//! `∫ ∇P_k dV = det J₀ J₀⁻ᵀ ∫ ∂P_k/∂ξ dξ = 0` exactly: a constant strain state gives no
//! load on the modes (`K_ic u = 0`, `α = 0`) and the element passes the patch test on any
//! shape. For the same reason rigid-body motions stay in the null space of `K*`.
//!
//! The mass matrix is the consistent (or lumped) hex8 one: the modes carry no mass of their
//! own. Stresses are recovered from the full strain `B_c u + B_i α` with the condensed modes
//! `α` recomputed from the element displacements: the bending strain lives mostly in the modes,
//! and dropping them would give the locked element's stresses.

use nalgebra::{SMatrix, SVector};

use crate::fe::geometry::{physical_gradient, volume_jacobian};
use crate::fe::quadrature;
use crate::fe::shape;
use crate::material::Material;
use crate::mesh::CellKind;

/// How hex8 cells are formulated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Hex8Formulation {
    /// Trilinear isoparametric, 2 × 2 × 2 Gauss (locks in bending).
    #[default]
    Standard,
    /// With the nine incompatible modes of this module, condensed.
    Incompatible,
}

impl Hex8Formulation {
    /// Parse `standard` or `incompatible`.
    pub fn parse(text: &str) -> crate::Result<Self> {
        match text.trim().to_ascii_lowercase().as_str() {
            "standard" | "plain" => Ok(Hex8Formulation::Standard),
            "incompatible" | "im" | "incompatible-modes" => Ok(Hex8Formulation::Incompatible),
            other => Err(crate::Error::option(
                "--hex8",
                format!("hex8 formulation '{other}': expected 'standard' or 'incompatible'"),
            )),
        }
    }

    /// The name [`Hex8Formulation::parse`] reads.
    pub fn name(self) -> &'static str {
        match self {
            Hex8Formulation::Standard => "standard",
            Hex8Formulation::Incompatible => "incompatible",
        }
    }
}

const NC: usize = 24;
const NI: usize = 9;
type Kii = SMatrix<f64, NI, NI>;
type Kic = SMatrix<f64, NI, NC>;

/// Strain-displacement columns of one vector DOF: component `i` of a scalar field with
/// gradient `g`, as the Voigt strain `[ε_xx, ε_yy, ε_zz, γ_yz, γ_xz, γ_xy]` it produces.
fn strain_column(g: [f64; 3], i: usize) -> [f64; 6] {
    let mut b = [0.0; 6];
    b[i] = g[i];
    match i {
        0 => {
            b[4] = g[2];
            b[5] = g[1];
        }
        1 => {
            b[3] = g[2];
            b[5] = g[0];
        }
        _ => {
            b[3] = g[1];
            b[4] = g[0];
        }
    }
    b
}

/// Reference gradients of the modes at `xi`.
fn mode_gradients(xi: [f64; 3]) -> [[f64; 3]; 3] {
    [
        [-2.0 * xi[0], 0.0, 0.0],
        [0.0, -2.0 * xi[1], 0.0],
        [0.0, 0.0, -2.0 * xi[2]],
    ]
}

/// Physical gradients at `xi` of the 8 nodal shape functions and (Taylor-corrected) of the 3
/// modes; the Jacobian determinant. `Err(det)` if `det J(ξ)` or `det J₀` is not positive.
#[allow(clippy::type_complexity)]
fn gradients(x: &[[f64; 3]], xi: [f64; 3]) -> Result<([[f64; 3]; 8], [[f64; 3]; 3], f64), f64> {
    let mut dn = [[0.0; 3]; 8];
    shape::gradients(CellKind::Hex8, xi, &mut dn);
    let (det, inv) = volume_jacobian(x, &dn)?;
    let mut dn0 = [[0.0; 3]; 8];
    shape::gradients(CellKind::Hex8, [0.0; 3], &mut dn0);
    let (det0, inv0) = volume_jacobian(x, &dn0)?;
    let g = dn.map(|d| physical_gradient(&inv, d));
    let r = det0 / det;
    let gi = mode_gradients(xi).map(|d| physical_gradient(&inv0, d).map(|c| r * c));
    Ok((g, gi, det))
}

fn dot6(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    a.iter().zip(b).map(|(p, q)| p * q).sum()
}

/// The blocks `K_cc` (into `kcc`, 24 × 24 row-major), `K_ic` and `K_ii`.
fn blocks(x: &[[f64; 3]], mat: &Material, kcc: &mut [f64]) -> Result<(Kic, Kii), f64> {
    let rule = quadrature::hex(2);
    kcc.fill(0.0);
    let mut kic = Kic::zeros();
    let mut kii = Kii::zeros();
    let mut bc = [[0.0; 6]; NC];
    let mut bi = [[0.0; 6]; NI];
    for (&p, &w) in rule.points.iter().zip(&rule.weights) {
        let (g, gi, det) = gradients(x, p)?;
        let c = w * det;
        for a in 0..8 {
            for i in 0..3 {
                bc[3 * a + i] = strain_column(g[a], i);
            }
        }
        for k in 0..3 {
            for i in 0..3 {
                bi[3 * k + i] = strain_column(gi[k], i);
            }
        }
        for r in 0..NC {
            let db = mat.stress(&bc[r]);
            for s in 0..NC {
                kcc[r * NC + s] += c * dot6(&db, &bc[s]);
            }
            for s in 0..NI {
                kic[(s, r)] += c * dot6(&db, &bi[s]);
            }
        }
        for r in 0..NI {
            let db = mat.stress(&bi[r]);
            for s in 0..NI {
                kii[(r, s)] += c * dot6(&db, &bi[s]);
            }
        }
    }
    Ok((kic, kii))
}

/// `K_ii⁻¹ K_ic` by Cholesky; `Err(NaN)` when `K_ii` is not positive definite (a degenerate
/// element, which the Jacobian check catches first in practice).
fn solve_modes(kic: &Kic, kii: Kii) -> Result<Kic, f64> {
    let ch = kii.cholesky().ok_or(f64::NAN)?;
    Ok(ch.solve(kic))
}

/// Condensed stiffness `K* = K_cc − K_ciK_ii⁻¹K_ic` of a hex8 with incompatible modes (see the
/// module docs); `ke` is 24 × 24 row-major with node-major DOFs. `Err(det)` for a non-positive
/// Jacobian determinant (at a Gauss point or the centre).
pub fn stiffness(x: &[[f64; 3]], mat: &Material, ke: &mut [f64]) -> Result<(), f64> {
    assert_eq!(x.len(), 8, "incompatible hex8 needs 8 node coordinates");
    assert_eq!(ke.len(), NC * NC, "incompatible hex8: ke must be 24 × 24");
    let (kic, kii) = blocks(x, mat, ke)?;
    let a = solve_modes(&kic, kii)?;
    // K* = K_cc − K_icᵀ (K_ii⁻¹ K_ic), symmetrised against rounding.
    let corr = kic.transpose() * a;
    for r in 0..NC {
        for s in r..NC {
            let c = 0.5 * (corr[(r, s)] + corr[(s, r)]);
            let v = 0.5 * (ke[r * NC + s] + ke[s * NC + r]) - c;
            ke[r * NC + s] = v;
            ke[s * NC + r] = v;
        }
    }
    Ok(())
}

/// Strain at `xi` (Voigt, engineering shears) of a hex8 with incompatible modes for element
/// displacements `ue` (24, node-major): `B_c u + B_i α` with the condensed `α = −K_ii⁻¹ K_ic u`.
pub fn strain_at(x: &[[f64; 3]], mat: &Material, ue: &[f64], xi: [f64; 3]) -> Result<[f64; 6], f64> {
    assert_eq!(x.len(), 8, "incompatible hex8 needs 8 node coordinates");
    assert_eq!(ue.len(), NC, "incompatible hex8: ue must have 24 entries");
    let mut kcc = [0.0; NC * NC];
    let (kic, kii) = blocks(x, mat, &mut kcc)?;
    let a = solve_modes(&kic, kii)?;
    let alpha: SVector<f64, NI> = -(a * SVector::<f64, NC>::from_column_slice(ue));
    let (g, gi, _) = gradients(x, xi)?;
    let mut eps = [0.0; 6];
    for a in 0..8 {
        for i in 0..3 {
            let b = strain_column(g[a], i);
            for r in 0..6 {
                eps[r] += b[r] * ue[3 * a + i];
            }
        }
    }
    for k in 0..3 {
        for i in 0..3 {
            let b = strain_column(gi[k], i);
            for r in 0..6 {
                eps[r] += b[r] * alpha[3 * k + i];
            }
        }
    }
    Ok(eps)
}

/// Stress `σ = D ε` at `xi` from [`strain_at`].
pub fn stress_at(x: &[[f64; 3]], mat: &Material, ue: &[f64], xi: [f64; 3]) -> Result<[f64; 6], f64> {
    Ok(mat.stress(&strain_at(x, mat, ue, xi)?))
}
