//! Geometric (initial-stress) stiffness `K_σ` of the element families, from a stress state
//! at their integration points.
//!
//! A body carrying a stress `σ⁰` stores, to second order in an added displacement `u`, the
//! work `½ ∫ σ⁰_ij u_k,i u_k,j dV` of the preload on the quadratic part of the Green strain.
//! Its matrix is the geometric stiffness; `K + K_σ` is the tangent stiffness about the
//! preloaded state (tension stiffens, compression softens; `det(K + λ K_σ) = 0` is linear
//! buckling). The kernels write dense, row-major element matrices with the layout of the
//! element's stiffness (node-major DOFs).
//!
//! - **Solids** (every kind of [`crate::element::solid`]): `K_σ,ab = ∫ ∇N_aᵀ σ ∇N_b dV · I₃`,
//!   i.e. `∫ Gᵀ S G dV` with `G` the 9 × 3n displacement-gradient matrix and `S` the 9 × 9
//!   block diagonal of the 3 × 3 Cauchy stress, integrated with the cell's stiffness rule
//!   ([`solid_rule`]) at whose points the stress is given. A hex8 with incompatible modes gets
//!   the geometric stiffness of its nodal (compatible) field: the condensed modes carry no
//!   geometric term.
//! - **Beams**, `Line2`: every stress resultant of the static state — axial force `N`, shear
//!   forces `Q_y`, `Q_z`, torque `T`, bending moments `M_y`, `M_z` ([`beam_resultants`]: from
//!   the element's end forces `K_e u_e` in local axes, `N`, `Q`, `T` constant and the moments
//!   linear). `N` acts on the transverse displacements, `N ∫ v'δv' + w'δw' dx`, with the slopes
//!   of the element's own interdependent interpolation (Friedman and Kosmatka 1993; for `Φ = 0`
//!   the classical consistent matrix `N/(30L) [36, 3L, −36, 3L; 3L, 4L², −3L, −L²; …]`,
//!   Przemieniecki 1968, §15), on the twist through the Wagner term `N (I_p/A) ∫ θ_x'δθ_x' dx`
//!   (`I_p = I_y + I_z` about the centroid; linear twist, or cubic Hermite with warping), and
//!   on the axial strain, `N ∫ u'δu' dx`. The moments, shears and torque enter through the
//!   second-order energy of a section rotating rigidly with `R = I + Θ + ½Θ²` (the rotation
//!   vector: **semitangential** moments), for a doubly symmetric section about its centroid:
//!   `M_y[½(θxθz)' + u'θy' − v'θx'] − M_z[½(θxθy)' − u'θz' + w'θx'] + Q_y[½θxθy − u'θz + w'θx]
//!   + Q_z[½θxθz + u'θy − v'θx] + ½T(θy'θz − θyθz')`, integrated with 4 Gauss points (exact) over
//!   the element's deflections and rotations. With Hermite interpolation this is the 12 × 12
//!   matrix of Yang and McGuire (J. Struct. Eng. 112(4), 1986; Yang and Kuo 1994) plus the
//!   axial–rotation couplings (`u'θ` terms) that make the rigid-body rule exact in every row: a
//!   rigid rotation `θ` gives `K_σ u = (θ × F, ½ θ × M)` at each node. Not included: the
//!   Wagner coefficients of monosymmetric sections (shear-centre offsets act in `K_e` only),
//!   `½N(I_z θz'² + I_y θy'²)/A`, and loads along the element.
//! - **Beams**, `Line3`: the axial force only, `N` at the 2 Gauss points of its stiffness on
//!   the component of `u'` across the tangent and on the twist (Wagner); its moments, shears
//!   and torque carry no geometric stiffness (docs/buckling.md says to mesh such structures
//!   with `Line2`).
//! - **Shells** (MITC3/MITC4): the membrane forces `N_αβ` (per unit length, in the element
//!   frame) act on the in-plane gradients of all three translations of the mid-surface,
//!   `∫ N_αβ u_k,α δu_k,β dA` — the transverse component is the plate's buckling term, the
//!   in-plane ones the membrane's. Mid-surface translations follow the nodes through the
//!   offset and warping links of the stiffness (`u_mid = u + d n × θ`). Not included: the
//!   rotations' term `t²/12 N_αβ θ,α θ,β` and the transverse shear forces.

// Index loops over nodes, components and points read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

use std::sync::OnceLock;

use crate::element::beam::{self, NodeTransform, congruence};
use crate::element::shell;
use crate::element::solid::{self, Integration};
use crate::error::Result;
use crate::fe::geometry::{dot, norm, physical_gradient, plane_jacobian, sub, volume_jacobian};
use crate::fe::quadrature::{self, GAUSS2, GAUSS4, QUAD_2X2, Rule, TRIANGLE_3};
use crate::fe::shape::{self, MAX_NODES};
use crate::material::Material;
use crate::mesh::CellKind;
use crate::section::{BeamSection, ShellSection};

static SOLID_RULES: [[OnceLock<Rule>; 2]; 7] = [const { [const { OnceLock::new() }, const { OnceLock::new() }] }; 7];

/// The rule a solid cell's `K_σ` is integrated with: its stiffness rule
/// ([`solid::stiffness_degree`], or [`solid::curved_stiffness_degree`] for a curved cell).
/// The stress is wanted at these points. `None` for a kind that is not a solid.
pub fn solid_rule(kind: CellKind, integration: Integration) -> Option<&'static Rule> {
    let i = solid::solid_index(kind)?;
    let (slot, degree) = match integration {
        Integration::Straight => (0, solid::stiffness_degree(kind)),
        Integration::Curved => (1, solid::curved_stiffness_degree(kind)),
    };
    Some(SOLID_RULES[i][slot].get_or_init(|| quadrature::for_cell(kind, degree)))
}

/// The symmetric 3 × 3 tensor of a Voigt vector `[σxx, σyy, σzz, σyz, σxz, σxy]`.
pub fn tensor(s: &[f64; 6]) -> [[f64; 3]; 3] {
    [[s[0], s[5], s[4]], [s[5], s[1], s[3]], [s[4], s[3], s[2]]]
}

/// Geometric stiffness of a solid cell: `K_σ,(3a+i)(3b+j) = δ_ij ∫ ∇N_a · σ ∇N_b dV`.
///
/// - `x`: node coordinates; `integration`: the rule set ([`solid::integration`] of the cell);
/// - `sigma`: the Cauchy stress (Voigt order of [`crate::material`], Pa) at each point of
///   [`solid_rule`]`(kind, integration)`, in its order;
/// - `kg`: output, `3n × 3n` row-major, fully written.
///
/// `Err(det)` for a non-positive Jacobian determinant (`NaN` for a kind that is not a solid).
///
/// ```
/// use vibrofem::{element::{geometric, solid::Integration}, mesh::CellKind};
/// // Unit tet under σxx = 1: K_σ = V ∂N_a/∂x ∂N_b/∂x per component.
/// let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
/// let mut kg = [0.0; 144];
/// geometric::solid(CellKind::Tet4, &x, Integration::Straight, &[[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]], &mut kg).unwrap();
/// assert!((kg[0] - 1.0 / 6.0).abs() < 1e-15 && (kg[3] + 1.0 / 6.0).abs() < 1e-15 && kg[1] == 0.0);
/// ```
pub fn solid(
    kind: CellKind,
    x: &[[f64; 3]],
    integration: Integration,
    sigma: &[[f64; 6]],
    kg: &mut [f64],
) -> std::result::Result<(), f64> {
    let rule = solid_rule(kind, integration).ok_or(f64::NAN)?;
    let n = kind.n_nodes();
    assert_eq!(x.len(), n, "geometric::solid: {kind} needs {n} node coordinates");
    assert_eq!(sigma.len(), rule.len(), "geometric::solid: one stress per rule point");
    assert_eq!(kg.len(), 9 * n * n, "geometric::solid: kg must be 3n × 3n");
    kg.fill(0.0);
    let nd = 3 * n;
    let mut dn = [[0.0; 3]; MAX_NODES];
    let mut g = [[0.0; 3]; MAX_NODES];
    let mut sg = [[0.0; 3]; MAX_NODES];
    for (q, (&p, &w)) in rule.points.iter().zip(&rule.weights).enumerate() {
        shape::gradients(kind, p, &mut dn[..n]);
        let (det, inv) = volume_jacobian(x, &dn[..n])?;
        let c = w * det;
        let s = tensor(&sigma[q]);
        for a in 0..n {
            g[a] = physical_gradient(&inv, dn[a]);
            for i in 0..3 {
                sg[a][i] = c * (s[i][0] * g[a][0] + s[i][1] * g[a][1] + s[i][2] * g[a][2]);
            }
        }
        for a in 0..n {
            for b in a..n {
                let v = dot(g[a], sg[b]);
                for i in 0..3 {
                    kg[(3 * a + i) * nd + 3 * b + i] += v;
                }
            }
        }
    }
    for a in 0..n {
        for b in a + 1..n {
            for i in 0..3 {
                kg[(3 * b + i) * nd + 3 * a + i] = kg[(3 * a + i) * nd + 3 * b + i];
            }
        }
    }
    Ok(())
}

/// The `(ξ, η, weight)` points at which a shell's membrane forces are sampled and its `K_σ`
/// integrated: 2 × 2 Gauss on `Quad4`, the 3-point rule on `Tri3` (the element's own rules).
pub fn shell_points(kind: CellKind) -> &'static [(f64, f64, f64)] {
    if kind == CellKind::Quad4 {
        &QUAD_2X2
    } else {
        &TRIANGLE_3
    }
}

/// Membrane forces `[N_11, N_22, N_12]` (N/m, in the element frame
/// [`shell::local_frame`]) at the points of [`shell_points`] for element displacements `ue`
/// (global, `6n`): the thickness times the mid-surface stress of [`shell::stress_at`].
/// Unused entries (triangles) are 0. `Err(det)` as for [`shell::stiffness`].
pub fn shell_membrane_forces(
    kind: CellKind,
    x: &[[f64; 3]],
    sec: &ShellSection,
    mat: &Material,
    ue: &[f64],
) -> std::result::Result<[[f64; 3]; 4], f64> {
    let r = shell::local_frame(kind, x)?;
    let mut out = [[0.0; 3]; 4];
    for (q, &(xi, eta, _)) in shell_points(kind).iter().enumerate() {
        let s = tensor(&shell::stress_at(kind, x, sec, mat, ue, [xi, eta, 0.0])?.middle);
        let along = |a: [f64; 3], b: [f64; 3]| {
            let mut v = 0.0;
            for i in 0..3 {
                for j in 0..3 {
                    v += a[i] * s[i][j] * b[j];
                }
            }
            sec.thickness * v
        };
        out[q] = [along(r[0], r[0]), along(r[1], r[1]), along(r[0], r[1])];
    }
    Ok(out)
}

/// Geometric stiffness of a shell element (`Tri3`, `Quad4`) from its membrane forces
/// `nf[q] = [N_11, N_22, N_12]` at the points of [`shell_points`] (element frame):
/// `∫ N_αβ u_k,α δu_k,β dA` over the three translations of the mid-surface, joined to the
/// nodes by the links of the stiffness (offset and warping heights). `kg`: `6n × 6n`
/// row-major, fully written. `Err(det)` as for [`shell::stiffness`].
pub fn shell(
    kind: CellKind,
    x: &[[f64; 3]],
    sec: &ShellSection,
    nf: &[[f64; 3]],
    kg: &mut [f64],
) -> std::result::Result<(), f64> {
    let r = shell::local_frame(kind, x)?;
    let nn = kind.n_nodes();
    let nd = 6 * nn;
    assert_eq!(kg.len(), nd * nd, "geometric::shell: kg must be 6n × 6n");
    let mut c = [0.0; 3];
    for xa in x {
        for i in 0..3 {
            c[i] += xa[i] / nn as f64;
        }
    }
    let mut p = [[0.0; 2]; 4];
    let mut d = [0.0; 4];
    for a in 0..nn {
        let v = sub(x[a], c);
        p[a] = [dot(v, r[0]), dot(v, r[1])];
        d[a] = sec.offset + if nn == 4 { dot(v, r[2]) } else { 0.0 };
    }
    // Scalar matrix k_ab = ∫ N_αβ ∂N_a/∂x_α ∂N_b/∂x_β dA.
    let mut k = [[0.0; 4]; 4];
    for (q, &(xi, eta, w)) in shell_points(kind).iter().enumerate() {
        let mut nv = [0.0; 4];
        let mut g3 = [[0.0; 3]; 4];
        shape::values_and_gradients(kind, [xi, eta, 0.0], &mut nv[..nn], &mut g3[..nn]);
        let dn: [[f64; 2]; 4] = g3.map(|g| [g[0], g[1]]);
        let (det, inv) = plane_jacobian(&p, &dn, nn)?;
        let mut g = [[0.0; 2]; 4];
        for a in 0..nn {
            g[a] = [
                inv[0][0] * dn[a][0] + inv[0][1] * dn[a][1],
                inv[1][0] * dn[a][0] + inv[1][1] * dn[a][1],
            ];
        }
        let [n11, n22, n12] = nf[q];
        let cw = w * det;
        for a in 0..nn {
            let t = [n11 * g[a][0] + n12 * g[a][1], n12 * g[a][0] + n22 * g[a][1]];
            for b in 0..nn {
                k[a][b] += cw * (t[0] * g[b][0] + t[1] * g[b][1]);
            }
        }
    }
    // Mid-surface translation of node a: u + d_a n × θ = T_a [u; θ], T_a = [I | d_a [n]×].
    let n = r[2];
    let nx = [[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]];
    let t_of = |a: usize| -> [[f64; 6]; 3] {
        let mut t = [[0.0; 6]; 3];
        for i in 0..3 {
            t[i][i] = 1.0;
            for j in 0..3 {
                t[i][3 + j] = d[a] * nx[i][j];
            }
        }
        t
    };
    kg.fill(0.0);
    for a in 0..nn {
        let ta = t_of(a);
        for b in 0..nn {
            let tb = t_of(b);
            for pp in 0..6 {
                for qq in 0..6 {
                    let v: f64 = (0..3).map(|i| ta[i][pp] * tb[i][qq]).sum();
                    kg[(6 * a + pp) * nd + 6 * b + qq] = k[a][b] * v;
                }
            }
        }
    }
    Ok(())
}

/// Axial forces `N` (N, tension positive) of a beam element at the points of its geometric
/// stiffness for element displacements `ue` (global, [`beam::dofs_per_node`] per node):
/// `Line2` the constant `EA (u_1 − u_0)·e_x / L` (twice), `Line3` `EA t·u'` at its 2 Gauss
/// points.
pub fn beam_axial_forces(
    kind: CellKind,
    x: &[[f64; 3]],
    sec: &BeamSection,
    mat: &Material,
    ue: &[f64],
) -> Result<[f64; 2]> {
    let nd = beam::dofs_per_node(sec);
    let ea = mat.young * sec.area;
    match kind {
        CellKind::Line2 => {
            let axis = sub(x[1], x[0]);
            let l = norm(axis);
            let du: f64 = (0..3).map(|i| (ue[nd + i] - ue[i]) * axis[i] / l).sum();
            let f = ea * du / l;
            Ok([f, f])
        }
        CellKind::Line3 => {
            let mut out = [0.0; 2];
            for (q, &(xi, _)) in GAUSS2.iter().enumerate() {
                let (tan, jac, dn) = line3_metric(x, xi);
                let mut du = [0.0; 3];
                for a in 0..3 {
                    for i in 0..3 {
                        du[i] += dn[a] / jac * ue[nd * a + i];
                    }
                }
                out[q] = ea * dot(tan, du) / jac;
            }
            Ok(out)
        }
        CellKind::Point1
        | CellKind::Tri3
        | CellKind::Tri6
        | CellKind::Quad4
        | CellKind::Quad8
        | CellKind::Quad9
        | CellKind::Tet4
        | CellKind::Tet10
        | CellKind::Hex8
        | CellKind::Hex20
        | CellKind::Hex27
        | CellKind::Wedge6
        | CellKind::Wedge15 => Err(beam::not_a_beam(kind)),
    }
}

/// Tangent `x_ξ`, its length and the `ξ`-derivatives of the `Line3` shape functions at `ξ`.
fn line3_metric(x: &[[f64; 3]], xi: f64) -> ([f64; 3], f64, [f64; 3]) {
    let mut nv = [0.0; 3];
    let mut g = [[0.0; 3]; 3];
    shape::values_and_gradients(CellKind::Line3, [xi, 0.0, 0.0], &mut nv, &mut g);
    let dn = [g[0][0], g[1][0], g[2][0]];
    let mut tan = [0.0; 3];
    for a in 0..3 {
        for i in 0..3 {
            tan[i] += dn[a] * x[a][i];
        }
    }
    (tan, norm(tan), dn)
}

/// Slopes `dN/dx` of the interdependent deflection functions of the exact two-node
/// Timoshenko element (Friedman and Kosmatka 1993) at `ξ = x/L`, for `(d_1, θ_1, d_2, θ_2)`.
fn kosmatka_slopes(xi: f64, l: f64, phi: f64) -> [f64; 4] {
    let c = 1.0 / (1.0 + phi);
    let x2 = xi * xi;
    [
        c * (6.0 * x2 - 6.0 * xi - phi) / l,
        c * (3.0 * x2 - (4.0 + phi) * xi + 1.0 + 0.5 * phi),
        c * (-6.0 * x2 + 6.0 * xi + phi) / l,
        c * (3.0 * x2 - (2.0 - phi) * xi - 0.5 * phi),
    ]
}

/// Stress resultants `[N, Q_y, Q_z, T, M_y, M_z]` of a beam element in its local axes for
/// element displacements `ue` (global, [`beam::dofs_per_node`] per node): the force and moment
/// that the part beyond a section exerts on the part before it (`N` tension positive,
/// `M_y = ∫σ z dA`, `M_z = −∫σ y dA`, `T` about the node line).
///
/// - `Line2`: at its two ends (`x = 0`, `x = L`), from the element's end forces
///   `f = K_e u_e` rotated to local axes: `−f` at node 0, `+f` at node 1. Between them `N`,
///   `Q` and `T` are constant and the moments linear (no load along the element).
/// - `Line3`: the axial force at its 2 Gauss points ([`beam_axial_forces`]); the other
///   resultants are returned as 0, since its geometric stiffness carries `N` only.
///
/// Errors as for [`beam::stiffness`].
pub fn beam_resultants(
    kind: CellKind,
    x: &[[f64; 3]],
    orientation: [f64; 3],
    sec: &BeamSection,
    mat: &Material,
    ue: &[f64],
) -> Result<[[f64; 6]; 2]> {
    match kind {
        CellKind::Line2 => beam_end_resultants(kind, x, orientation, sec, mat, ue),
        _ => {
            let n = beam_axial_forces(kind, x, sec, mat, ue)?;
            Ok([[n[0], 0.0, 0.0, 0.0, 0.0, 0.0], [n[1], 0.0, 0.0, 0.0, 0.0, 0.0]])
        }
    }
}

/// The resultants `[N, Q_y, Q_z, T, M_y, M_z]` at the two ends of a `Line2` or `Line3` beam
/// element, local axes, from its end forces `f = K_e u_e`: `−f` at the first node and `+f` at
/// the second (the convention of [`beam_resultants`], whose `Line2` resultants these are). A
/// `Line3`'s axes at each end follow its tangent there (gmsh's order: the ends, then the
/// midside node, whose force is the load applied there), the chord where the tangent vanishes
/// (a midside node at a quarter point, valid at the integration points). With loads at the
/// nodes only, the end forces are the section's resultants at the ends (the element's
/// equilibrium; exact where the structure is statically determinate).
///
/// Errors as for [`beam::stiffness`].
pub fn beam_end_resultants(
    kind: CellKind,
    x: &[[f64; 3]],
    orientation: [f64; 3],
    sec: &BeamSection,
    mat: &Material,
    ue: &[f64],
) -> Result<[[f64; 6]; 2]> {
    let nd = beam::dofs_per_node(sec);
    let n = x.len() * nd;
    let mut ke = [0.0; 21 * 21];
    beam::stiffness(kind, x, orientation, sec, mat, &mut ke[..n * n])?;
    let chord = sub(x[1], x[0]);
    let tangents = if kind == CellKind::Line3 {
        let comb = |c: [f64; 3]| std::array::from_fn(|i| c[0] * x[0][i] + c[1] * x[1][i] + c[2] * x[2][i]);
        // dx/dξ at ξ = −1 and +1 of the quadratic line (nodes at ξ = −1, +1, 0).
        let norm = |v: [f64; 3]| dot(v, v).sqrt();
        [comb([-1.5, -0.5, 2.0]), comb([0.5, 1.5, -2.0])].map(|t| if norm(t) > 1e-6 * norm(chord) { t } else { chord })
    } else {
        [chord, chord]
    };
    let mut out = [[0.0; 6]; 2];
    for (a, sign) in [(0, -1.0), (1, 1.0)] {
        let r = beam::local_axes(tangents[a], orientation)?;
        let mut f = [0.0; 6];
        for (i, fi) in f.iter_mut().enumerate() {
            *fi = (0..n).map(|j| ke[(a * nd + i) * n + j] * ue[j]).sum();
        }
        for i in 0..3 {
            out[a][i] = sign * dot(r[i], [f[0], f[1], f[2]]);
            out[a][3 + i] = sign * dot(r[i], [f[3], f[4], f[5]]);
        }
    }
    Ok(out)
}

/// Rotation functions `ψ` of the exact two-node Timoshenko element (Friedman and Kosmatka
/// 1993) and their `x`-derivatives at `ξ = x/L`, for `(d_1, θ_1, d_2, θ_2)`.
fn kosmatka_rotations(xi: f64, l: f64, phi: f64) -> ([f64; 4], [f64; 4]) {
    let c = 1.0 / (1.0 + phi);
    let x2 = xi * xi;
    let psi = [
        c * 6.0 * (x2 - xi) / l,
        c * (3.0 * x2 - (4.0 + phi) * xi + 1.0 + phi),
        -c * 6.0 * (x2 - xi) / l,
        c * (3.0 * x2 - (2.0 - phi) * xi),
    ];
    let dpsi = [
        c * 6.0 * (2.0 * xi - 1.0) / (l * l),
        c * (6.0 * xi - 4.0 - phi) / l,
        -c * 6.0 * (2.0 * xi - 1.0) / (l * l),
        c * (6.0 * xi - 2.0 + phi) / l,
    ];
    (psi, dpsi)
}

/// Adds to the local `Line2` matrix `kl` (`2nd × 2nd`, node-major local DOFs) the terms of the
/// axial strain, the bending moments, the shear forces and the torque of the resultants `res`
/// at both ends (see the module docs): `∫ Bᵀ H B dx` over the generalized displacements
/// `g = (u′, v′, w′, θx, θy, θz, θx′, θy′, θz′)`, 4-point Gauss (exact: the integrand is a
/// polynomial of degree ≤ 5).
fn line2_moment_terms(l: f64, phi: [f64; 2], nd: usize, res: &[[f64; 6]; 2], kl: &mut [f64]) {
    let n = 2 * nd;
    for &(xg, wg) in &GAUSS4 {
        let xi = 0.5 * (1.0 + xg);
        let r: [f64; 6] = std::array::from_fn(|k| (1.0 - xi) * res[0][k] + xi * res[1][k]);
        let [nx, qy, qz, t, my, mz] = r;
        // B: 9 generalized displacements × 2nd local DOFs.
        let mut b = [[0.0; 14]; 9];
        b[0][0] = -1.0 / l;
        b[0][nd] = 1.0 / l;
        // x–y plane: (v, θz), slope v′ ≈ θz; x–z plane: (w, −θy).
        for (dof, rot, sr, ph, row_d, row_r, row_dr) in [(1, 5, 1.0, phi[0], 1, 5, 8), (2, 4, -1.0, phi[1], 2, 4, 7)] {
            let s = kosmatka_slopes(xi, l, ph);
            let (psi, dpsi) = kosmatka_rotations(xi, l, ph);
            let idx = [dof, rot, nd + dof, nd + rot];
            let sgn = [1.0, sr, 1.0, sr];
            for i in 0..4 {
                b[row_d][idx[i]] += sgn[i] * s[i];
                b[row_r][idx[i]] += sr * sgn[i] * psi[i];
                b[row_dr][idx[i]] += sr * sgn[i] * dpsi[i];
            }
        }
        if nd == 6 {
            b[3][3] = 1.0 - xi;
            b[3][nd + 3] = xi;
            b[6][3] = -1.0 / l;
            b[6][nd + 3] = 1.0 / l;
        } else {
            let (h, dh) = hermite(xi, l);
            for (i, &c) in [3, 6, nd + 3, nd + 6].iter().enumerate() {
                b[3][c] = h[i];
                b[6][c] = dh[i];
            }
        }
        // H of the density ½ gᵀ H g: each product c·g_a·g_b puts c at (a, b) and (b, a).
        let mut hm = [[0.0; 9]; 9];
        hm[0][0] = nx;
        for (a, bb, c) in [
            (6, 5, 0.5 * my),
            (3, 8, 0.5 * my),
            (0, 7, my),
            (1, 6, -my),
            (6, 4, -0.5 * mz),
            (3, 7, -0.5 * mz),
            (0, 8, mz),
            (2, 6, -mz),
            (3, 4, 0.5 * qy),
            (0, 5, -qy),
            (2, 3, qy),
            (3, 5, 0.5 * qz),
            (0, 4, qz),
            (1, 3, -qz),
            (7, 5, 0.5 * t),
            (4, 8, -0.5 * t),
        ] {
            hm[a][bb] += c;
            hm[bb][a] += c;
        }
        let w = 0.5 * wg * l;
        let mut hb = [[0.0; 14]; 9];
        for a in 0..9 {
            for j in 0..n {
                hb[a][j] = (0..9).map(|k| hm[a][k] * b[k][j]).sum();
            }
        }
        for i in 0..n {
            for j in 0..n {
                let v: f64 = (0..9).map(|k| b[k][i] * hb[k][j]).sum();
                kl[i * n + j] += w * v;
            }
        }
    }
}

/// Cubic Hermite functions' values and `x`-derivatives on `[0, L]` at `ξ = x/L`, for
/// `(θ(0), θ′(0), θ(L), θ′(L))` (the warping element's twist).
fn hermite(t: f64, l: f64) -> ([f64; 4], [f64; 4]) {
    let t2 = t * t;
    let t3 = t2 * t;
    (
        [
            1.0 - 3.0 * t2 + 2.0 * t3,
            l * (t - 2.0 * t2 + t3),
            3.0 * t2 - 2.0 * t3,
            l * (t3 - t2),
        ],
        [
            (6.0 * t2 - 6.0 * t) / l,
            1.0 - 4.0 * t + 3.0 * t2,
            (6.0 * t - 6.0 * t2) / l,
            3.0 * t2 - 2.0 * t,
        ],
    )
}

/// Local geometric stiffness of a `Line2` beam, `(2nd)²` row-major in `kl`.
fn line2_local(l: f64, sec: &BeamSection, mat: &Material, nd: usize, res: &[[f64; 6]; 2], kl: &mut [f64]) {
    let n = 2 * nd;
    let f = 0.5 * (res[0][0] + res[1][0]);
    let wagner = sec.polar() / sec.area;
    let (e, g) = (mat.young, mat.shear_modulus());
    let phi_y = 12.0 * e * sec.iz / (sec.ky * g * sec.area * l * l);
    let phi_z = 12.0 * e * sec.iy / (sec.kz * g * sec.area * l * l);
    for (d, rr, sr, phi) in [(1, 5, 1.0, phi_y), (2, 4, -1.0, phi_z)] {
        let idx = [d, rr, nd + d, nd + rr];
        let sgn = [1.0, sr, 1.0, sr];
        for &(xi, w) in &GAUSS4 {
            let s = kosmatka_slopes(0.5 * (1.0 + xi), l, phi);
            let c = 0.5 * w * l * f;
            for i in 0..4 {
                for j in 0..4 {
                    kl[idx[i] * n + idx[j]] += c * sgn[i] * sgn[j] * s[i] * s[j];
                }
            }
        }
    }
    if nd == 6 {
        let kt = f * wagner / l;
        for (i, j, v) in [(3, 3, kt), (nd + 3, nd + 3, kt), (3, nd + 3, -kt), (nd + 3, 3, -kt)] {
            kl[i * n + j] += v;
        }
    } else {
        // The twist's cubic Hermite interpolation in (θx, w) of the warping element.
        let idx = [3, 6, nd + 3, nd + 6];
        for &(xi, w) in &GAUSS4 {
            let (_, dh) = hermite(0.5 * (1.0 + xi), l);
            let c = 0.5 * w * l * f * wagner;
            for i in 0..4 {
                for j in 0..4 {
                    kl[idx[i] * n + idx[j]] += c * dh[i] * dh[j];
                }
            }
        }
    }
    line2_moment_terms(l, [phi_y, phi_z], nd, res, kl);
}

/// Geometric stiffness of a beam element from its stress resultants `res` at the points of
/// [`beam_resultants`] (see the module docs for the terms). `kg`: `(n·d)²` row-major in
/// global axes, `d` = [`beam::dofs_per_node`]; fully written. Errors as for
/// [`beam::stiffness`].
pub fn beam(
    kind: CellKind,
    x: &[[f64; 3]],
    orientation: [f64; 3],
    sec: &BeamSection,
    mat: &Material,
    res: &[[f64; 6]; 2],
    kg: &mut [f64],
) -> Result<()> {
    let nd = beam::dofs_per_node(sec);
    let wagner = sec.polar() / sec.area;
    kg.fill(0.0);
    match kind {
        CellKind::Line2 => {
            let axis = sub(x[1], x[0]);
            let r = beam::local_axes(axis, orientation)?;
            let mut kl = [0.0; 14 * 14];
            line2_local(norm(axis), sec, mat, nd, res, &mut kl);
            let mut gt: NodeTransform = [[0.0; 7]; 7];
            for i in 0..3 {
                for j in 0..3 {
                    gt[i][j] = r[i][j];
                    gt[3 + i][3 + j] = r[i][j];
                }
            }
            if nd == 7 {
                gt[6][6] = 1.0;
            }
            congruence(&kl, 2, nd, &[gt, gt], kg);
            Ok(())
        }
        CellKind::Line3 => {
            if nd != 6 {
                return Err(beam::warping_line3());
            }
            for (q, &(xi, w)) in GAUSS2.iter().enumerate() {
                let (tan, jac, dn) = line3_metric(x, xi);
                let t = beam::local_axes(tan, orientation)?[0];
                let c = w * jac * res[q][0];
                for a in 0..3 {
                    for b in 0..3 {
                        let v = c * (dn[a] / jac) * (dn[b] / jac);
                        for i in 0..3 {
                            for j in 0..3 {
                                let across = if i == j { 1.0 } else { 0.0 } - t[i] * t[j];
                                kg[(6 * a + i) * 18 + 6 * b + j] += v * across;
                                kg[(6 * a + 3 + i) * 18 + 6 * b + 3 + j] += v * wagner * t[i] * t[j];
                            }
                        }
                    }
                }
            }
            Ok(())
        }
        CellKind::Point1
        | CellKind::Tri3
        | CellKind::Tri6
        | CellKind::Quad4
        | CellKind::Quad8
        | CellKind::Quad9
        | CellKind::Tet4
        | CellKind::Tet10
        | CellKind::Hex8
        | CellKind::Hex20
        | CellKind::Hex27
        | CellKind::Wedge6
        | CellKind::Wedge15 => Err(beam::not_a_beam(kind)),
    }
}
