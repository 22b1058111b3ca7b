//! Isoparametric 3D solid elements: stiffness, mass, volume and stress at a point.
//!
//! Geometry and displacement share the shape functions of [`crate::fe::shape`]:
//! `x(ξ) = Σ_a N_a(ξ) x_a`, `u(ξ) = Σ_a N_a(ξ) u_a`. With the Jacobian
//! `J_ij = ∂x_i/∂ξ_j = Σ_a x_a,i ∂N_a/∂ξ_j`, physical gradients are `∇N_a = J⁻ᵀ ∂N_a/∂ξ` and
//! `dV = det J dξ`. Integrals use the quadrature rules of the table below; the shape values
//! and reference gradients at their points are computed once per kind (a `OnceLock` table), so
//! a kernel call does no heap allocation.
//!
//! # Output layout
//!
//! Matrices are dense, row-major, `3n × 3n` for a kind with `n` nodes, with node-major degrees
//! of freedom `[n0.ux, n0.uy, n0.uz, n1.ux, …]`, i.e. entry `(3a + i, 3b + j)` couples
//! direction `i` of node `a` with direction `j` of node `b`. On `Err` the output buffer holds
//! unspecified values.
//!
//! # Quadrature
//!
//! The rules are chosen so that the integrals are exact on affine tetrahedra and wedges with
//! straight vertical edges and on parallelepiped hexahedra, which is where other codes
//! (scikit-fem, CalculiX) are exact too, so results on the same mesh agree to rounding. The
//! degree is as in [`quadrature::for_cell`].
//!
//! | kind | stiffness rule | points | mass / volume rule | points | why |
//! |---|---|---|---|---|---|
//! | `Tet4` | degree 1 | 1 | degree 2 | 4 | `∇N` constant; `N_a N_b` degree 2 |
//! | `Tet10` | degree 2 | 4 | degree 4 (14-point, degree 5) | 14 | `∇N_a·∇N_b` degree 2; `N_a N_b` degree 4 |
//! | `Hex8` | 2 × 2 × 2 Gauss | 8 | 2 × 2 × 2 Gauss | 8 | degree ≤ 2 per direction |
//! | `Hex20` | 3 × 3 × 3 Gauss | 27 | 3 × 3 × 3 Gauss | 27 | degree ≤ 4 per direction |
//! | `Hex27` | 3 × 3 × 3 Gauss | 27 | 3 × 3 × 3 Gauss | 27 | degree ≤ 4 per direction |
//! | `Wedge6` | triangle degree 2 × 2 Gauss | 6 | the same | 6 | degree ≤ 2 in `(u, v)` and in `w` |
//! | `Wedge15` | triangle degree 4 × 3 Gauss | 18 | the same | 18 | degree ≤ 4 in `(u, v)` and in `w` |
//!
//! **Curved cells.** A quadratic cell whose mid-side nodes are off the straight positions
//! ([`integration`]) has a non-constant Jacobian, and the rules above are no longer exact (on a
//! coil's wire, h = 3 mm on a 20 mm radius, a tet10 stiffness is 0.4 % off). Such cells get
//! higher rules ([`curved_stiffness_degree`], [`curved_mass_degree`]): tet10 24 points
//! (degree 6) for stiffness and 125 (degree 7, exact) for mass; hexahedra 4 × 4 × 4 Gauss;
//! wedge15 triangle degree 6 × 4 Gauss. Straight cells keep the table above, bit for bit.
//! The model notes how many cells were curved and the rule used.
//!
//! Every rule is a full integration: a free element has exactly the 6 rigid-body modes as the
//! null space of its stiffness (no hourglass modes).
//!
//! # Stiffness in block form
//!
//! For an isotropic material, `Bᵀ D B` never needs forming. With
//! `S_ab = ∫ ∇N_a ∇N_bᵀ dV` (a 3 × 3 matrix per node pair), the `(a, b)` block is
//!
//! ```text
//! K_ab = λ S_ab + μ S_abᵀ + μ tr(S_ab) I
//!      = ∫ [λ ∇N_a ∇N_bᵀ + μ ∇N_b ∇N_aᵀ + μ (∇N_a·∇N_b) I] dV,
//! ```
//!
//! which costs 9 multiply-adds per node pair and point instead of a `6 × 3n` product.

// Index loops over nodes and points read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

use std::sync::OnceLock;

use crate::element::lumping::{self, MassLumping};
use crate::fe::geometry::{physical_gradient, volume_jacobian};
use crate::fe::quadrature;
use crate::fe::shape::{self, MAX_NODES};
use crate::material::Material;
use crate::mesh::CellKind;

/// Quadrature degree (in the sense of [`quadrature::for_cell`]) of the stiffness rule of
/// `kind`; see the table in the module docs. A kind that is not a solid has no solid rule:
/// it gets the degree `2 · order` that integrates `∇N_a·∇N_b` of an affine cell of its order
/// (used by nothing in vibrofem; given so that the function is total).
pub fn stiffness_degree(kind: CellKind) -> usize {
    match kind {
        CellKind::Tet4 => 1,
        CellKind::Tet10 | CellKind::Hex8 | CellKind::Wedge6 => 2,
        CellKind::Hex20 | CellKind::Hex27 | CellKind::Wedge15 => 4,
        CellKind::Point1
        | CellKind::Line2
        | CellKind::Line3
        | CellKind::Tri3
        | CellKind::Tri6
        | CellKind::Quad4
        | CellKind::Quad8
        | CellKind::Quad9 => 2 * kind.order(),
    }
}

/// Quadrature degree of the mass (and volume) rule of `kind`; see the table in the module
/// docs. A kind that is not a solid gets `2 · order`, the degree of `N_a N_b` on an affine
/// cell of its order.
pub fn mass_degree(kind: CellKind) -> usize {
    match kind {
        CellKind::Tet4 | CellKind::Hex8 | CellKind::Wedge6 => 2,
        CellKind::Tet10 | CellKind::Hex20 | CellKind::Hex27 | CellKind::Wedge15 => 4,
        CellKind::Point1
        | CellKind::Line2
        | CellKind::Line3
        | CellKind::Tri3
        | CellKind::Tri6
        | CellKind::Quad4
        | CellKind::Quad8
        | CellKind::Quad9 => 2 * kind.order(),
    }
}

/// Shape values and reference gradients of one kind at the points of one rule.
struct Table {
    nn: usize,
    nq: usize,
    /// Points `ξ_q`.
    points: Vec<[f64; 3]>,
    /// Weights `w_q`.
    w: Vec<f64>,
    /// `N_a(ξ_q)` at `q * nn + a`.
    n: Vec<f64>,
    /// `∂N_a/∂ξ (ξ_q)` at `q * nn + a`.
    dn: Vec<[f64; 3]>,
}

impl Table {
    fn new(kind: CellKind, degree: usize) -> Table {
        Table::from_rule(kind, quadrature::for_cell(kind, degree))
    }

    fn from_rule(kind: CellKind, rule: quadrature::Rule) -> Table {
        let (nn, nq) = (kind.n_nodes(), rule.len());
        let mut n = vec![0.0; nq * nn];
        let mut dn = vec![[0.0; 3]; nq * nn];
        for (q, &p) in rule.points.iter().enumerate() {
            let r = q * nn..(q + 1) * nn;
            shape::values_and_gradients(kind, p, &mut n[r.clone()], &mut dn[r]);
        }
        Table {
            nn,
            nq,
            points: rule.points,
            w: rule.weights,
            n,
            dn,
        }
    }
}

/// Index of a solid kind in the table caches; `None` for a kind that is not a solid.
pub(crate) fn solid_index(kind: CellKind) -> Option<usize> {
    match kind {
        CellKind::Tet4 => Some(0),
        CellKind::Tet10 => Some(1),
        CellKind::Hex8 => Some(2),
        CellKind::Hex20 => Some(3),
        CellKind::Hex27 => Some(4),
        CellKind::Wedge6 => Some(5),
        CellKind::Wedge15 => Some(6),
        CellKind::Point1
        | CellKind::Line2
        | CellKind::Line3
        | CellKind::Tri3
        | CellKind::Tri6
        | CellKind::Quad4
        | CellKind::Quad8
        | CellKind::Quad9 => None,
    }
}

/// The error value of every kernel here for a kind that is not a solid: NaN, "no Jacobian"
/// (a set never holds such a kind: the model checks kinds when it binds the mesh).
const NOT_A_SOLID: f64 = f64::NAN;

static STIFFNESS_TABLES: [OnceLock<Table>; 7] = [const { OnceLock::new() }; 7];
static MASS_TABLES: [OnceLock<Table>; 7] = [const { OnceLock::new() }; 7];
static CURVED_STIFFNESS_TABLES: [OnceLock<Table>; 7] = [const { OnceLock::new() }; 7];
static CURVED_MASS_TABLES: [OnceLock<Table>; 7] = [const { OnceLock::new() }; 7];

fn stiffness_table(kind: CellKind) -> Result<&'static Table, f64> {
    let i = solid_index(kind).ok_or(NOT_A_SOLID)?;
    Ok(STIFFNESS_TABLES[i].get_or_init(|| Table::new(kind, stiffness_degree(kind))))
}

fn mass_table(kind: CellKind) -> Result<&'static Table, f64> {
    let i = solid_index(kind).ok_or(NOT_A_SOLID)?;
    Ok(MASS_TABLES[i].get_or_init(|| Table::new(kind, mass_degree(kind))))
}

fn stiffness_table_for(kind: CellKind, integration: Integration) -> Result<&'static Table, f64> {
    match integration {
        Integration::Straight => stiffness_table(kind),
        Integration::Curved => {
            let i = solid_index(kind).ok_or(NOT_A_SOLID)?;
            let d = curved_stiffness_degree(kind);
            Ok(CURVED_STIFFNESS_TABLES[i].get_or_init(|| Table::new(kind, d)))
        }
    }
}

fn mass_table_for(kind: CellKind, integration: Integration) -> Result<&'static Table, f64> {
    match integration {
        Integration::Straight => mass_table(kind),
        Integration::Curved => {
            let i = solid_index(kind).ok_or(NOT_A_SOLID)?;
            let d = curved_mass_degree(kind);
            Ok(CURVED_MASS_TABLES[i].get_or_init(|| Table::new(kind, d)))
        }
    }
}

/// Which of a kind's two rule sets integrates a cell: the straight-sided one of the table in
/// the module docs, or the higher-order one for a curved quadratic cell (see [`integration`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integration {
    /// The rules of the module-docs table (exact on affine cells).
    Straight,
    /// The rules of [`curved_stiffness_degree`] and [`curved_mass_degree`].
    Curved,
}

/// Relative distance (to the cell's largest vertex-to-vertex distance) beyond which a mid-side
/// node counts as moved off its straight position. Below it the stiffness error of the
/// straight rule is of the order of the square of the offset, far under rounding of input
/// coordinates written with 8 or more significant digits.
pub const CURVED_TOLERANCE: f64 = 1e-6;

/// The linear kind whose vertices span a quadratic kind's straight geometry.
fn linear_kind(kind: CellKind) -> Option<CellKind> {
    match kind {
        CellKind::Tet10 => Some(CellKind::Tet4),
        CellKind::Hex20 | CellKind::Hex27 => Some(CellKind::Hex8),
        CellKind::Wedge15 => Some(CellKind::Wedge6),
        _ => None,
    }
}

/// Whether a cell of `kind` with nodes `x` is curved: a quadratic solid (`Tet10`, `Hex20`,
/// `Hex27`, `Wedge15`) one of whose mid-edge, mid-face or centre nodes lies farther than
/// [`CURVED_TOLERANCE`] × (largest vertex distance) from the point the vertices alone place
/// it at (the linear kind's map at the node's reference position: the edge midpoint of a
/// tetrahedron, the trilinear point of a hexahedron). A straight tet10 is affine, a straight
/// hex20/27 or wedge15 has the geometry of its hex8/wedge6; linear kinds are never curved.
///
/// ```
/// use vibrofem::{element::solid::{self, Integration}, fe::shape, mesh::CellKind};
/// let mut x: Vec<[f64; 3]> = shape::reference_nodes(CellKind::Tet10).to_vec();
/// assert_eq!(solid::integration(CellKind::Tet10, &x), Integration::Straight);
/// x[4][1] -= 0.05; // the mid-node of edge 0–1 pushed off the edge
/// assert_eq!(solid::integration(CellKind::Tet10, &x), Integration::Curved);
/// ```
pub fn integration(kind: CellKind, x: &[[f64; 3]]) -> Integration {
    let Some(lin) = linear_kind(kind) else {
        return Integration::Straight;
    };
    let nv = lin.n_nodes();
    if x.len() != kind.n_nodes() {
        return Integration::Straight;
    }
    let mut h2: f64 = 0.0;
    for a in 0..nv {
        for b in a + 1..nv {
            h2 = h2.max(dist2(x[a], x[b]));
        }
    }
    let tol2 = CURVED_TOLERANCE * CURVED_TOLERANCE * h2;
    let mut n = [0.0; 8];
    for (a, &xi) in shape::reference_nodes(kind).iter().enumerate().skip(nv) {
        shape::values(lin, xi, &mut n[..nv]);
        let mut p = [0.0; 3];
        for b in 0..nv {
            for i in 0..3 {
                p[i] += n[b] * x[b][i];
            }
        }
        // Also true for a NaN coordinate: such a cell fails its Jacobian check either way.
        if !(dist2(p, x[a]) <= tol2) {
            return Integration::Curved;
        }
    }
    Integration::Straight
}

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

/// Quadrature degree of the stiffness rule of a curved cell of `kind` (see [`integration`]).
///
/// A curved quadratic map makes `∇N_a·∇N_b det J` a rational function, which no rule
/// integrates exactly; these degrees bring the stiffness error (Frobenius, relative) of a cell
/// spanning 0.15–0.3 rad of an arc (mid-node offsets 2–4 % of the edge) to 3e-9 … 1e-6, from
/// 5e-5 … 7.5e-3 with the straight rules, measured against degree-20 rules in
/// `tests/unit/solid_elements.rs`: tet10 the 24-point degree-6 rule (from
/// 4 points), hexahedra 4 × 4 × 4 Gauss (from 3 × 3 × 3), wedge15 the triangle degree-6 rule
/// × 4 Gauss points (from degree 4 × 3). Other kinds keep [`stiffness_degree`].
pub fn curved_stiffness_degree(kind: CellKind) -> usize {
    match kind {
        CellKind::Tet10 | CellKind::Hex20 | CellKind::Hex27 | CellKind::Wedge15 => 6,
        _ => stiffness_degree(kind),
    }
}

/// Quadrature degree of the mass (and volume) rule of a curved cell of `kind`: `N_a N_b det J`
/// is a polynomial; tet10 degree 4 + 3 = 7 (exact, collapsed Gauss); hexahedra and wedge15
/// the same rules as [`curved_stiffness_degree`]. Other kinds keep [`mass_degree`].
pub fn curved_mass_degree(kind: CellKind) -> usize {
    match kind {
        CellKind::Tet10 => 7,
        CellKind::Hex20 | CellKind::Hex27 | CellKind::Wedge15 => 6,
        _ => mass_degree(kind),
    }
}

/// A short description of the stiffness rule a cell of `kind` gets under `integration`, for
/// the model's notes (e.g. `"24-point degree 6"`, `"4×4×4 Gauss"`).
pub fn stiffness_rule_name(kind: CellKind, integration: Integration) -> String {
    let t = match stiffness_table_for(kind, integration) {
        Ok(t) => t,
        Err(_) => return String::new(),
    };
    let d = match integration {
        Integration::Straight => stiffness_degree(kind),
        Integration::Curved => curved_stiffness_degree(kind),
    };
    match kind {
        CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => {
            let n = quadrature::gauss_points_for_degree(d);
            format!("{n}×{n}×{n} Gauss")
        }
        _ => format!("{}-point degree {d}", t.nq),
    }
}

/// The reference points of the stiffness rule of a solid `kind` (where
/// [`crate::post::stress::gauss_point_stress`] samples); empty for other kinds.
pub fn stiffness_points(kind: CellKind) -> &'static [[f64; 3]] {
    stiffness_table(kind).map_or(&[], |t| &t.points)
}

/// Element stiffness `K = ∫ Bᵀ D B dV` of an isotropic solid, computed in the block form of the
/// module docs.
///
/// - `kind`: a solid kind (`Err(NaN)` otherwise); `x`: its `n` node coordinates in gmsh order.
/// - `ke`: output, `3n × 3n` row-major, node-major dofs (see the module docs); fully written.
/// - `Err(det)` when the Jacobian determinant at a quadrature point is not positive (inverted
///   or degenerate element), with that determinant.
///
/// ```
/// use vibrofem::{element::solid, material::Material, mesh::CellKind};
/// // Unit tetrahedron, E = 1, ν = 0: K_00 (ux-ux of node 0) = V (λ+2μ) + V μ + V μ = 2V = 1/3.
/// let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
/// let mat = Material { young: 1.0, poisson: 0.0, density: 1.0 };
/// let mut ke = [0.0; 144];
/// solid::stiffness(CellKind::Tet4, &x, &mat, &mut ke).unwrap();
/// assert!((ke[0] - 1.0 / 3.0).abs() < 1e-15);
/// ```
pub fn stiffness(kind: CellKind, x: &[[f64; 3]], mat: &Material, ke: &mut [f64]) -> Result<(), f64> {
    stiffness_with(kind, x, mat, integration(kind, x), ke)
}

/// [`stiffness`] with the rule set chosen by the caller rather than by [`integration`] (to
/// compare the straight rule with the curved one on the same cell).
pub fn stiffness_with(
    kind: CellKind,
    x: &[[f64; 3]],
    mat: &Material,
    integration: Integration,
    ke: &mut [f64],
) -> Result<(), f64> {
    let t = stiffness_table_for(kind, integration)?;
    // Monomorphised per (nodes, points) so the inner loops have constant trip counts and the
    // gradient buffers live on the stack at their exact size.
    match (kind, t.nq) {
        (CellKind::Tet4, 1) => stiffness_impl::<4, 1>(t, x, mat, ke),
        (CellKind::Tet10, 4) => stiffness_impl::<10, 4>(t, x, mat, ke),
        (CellKind::Tet10, 24) => stiffness_impl::<10, 24>(t, x, mat, ke),
        (CellKind::Hex8, 8) => stiffness_impl::<8, 8>(t, x, mat, ke),
        (CellKind::Hex20, 27) => stiffness_impl::<20, 27>(t, x, mat, ke),
        (CellKind::Hex20, 64) => stiffness_impl::<20, 64>(t, x, mat, ke),
        (CellKind::Hex27, 27) => stiffness_impl::<27, 27>(t, x, mat, ke),
        (CellKind::Hex27, 64) => stiffness_impl::<27, 64>(t, x, mat, ke),
        (CellKind::Wedge6, 6) => stiffness_impl::<6, 6>(t, x, mat, ke),
        (CellKind::Wedge15, 18) => stiffness_impl::<15, 18>(t, x, mat, ke),
        (CellKind::Wedge15, 48) => stiffness_impl::<15, 48>(t, x, mat, ke),
        _ => stiffness_dyn(t, x, mat, ke),
    }
}

/// [`stiffness`] integrated with an arbitrary `rule` on the reference cell of `kind` (a
/// reference for convergence checks: a rule of much higher degree than either rule set).
pub fn stiffness_with_rule(
    kind: CellKind,
    x: &[[f64; 3]],
    mat: &Material,
    rule: &quadrature::Rule,
    ke: &mut [f64],
) -> Result<(), f64> {
    solid_index(kind).ok_or(NOT_A_SOLID)?;
    let t = Table::from_rule(kind, rule.clone());
    stiffness_dyn(&t, x, mat, ke)
}

fn stiffness_dyn(t: &Table, x: &[[f64; 3]], mat: &Material, ke: &mut [f64]) -> Result<(), f64> {
    let mut g = vec![[0.0; 3]; t.nn * t.nq];
    let mut h = vec![[0.0; 3]; t.nn * t.nq];
    stiffness_core(t, x, mat, ke, &mut g, &mut h)
}

fn stiffness_impl<const N: usize, const Q: usize>(
    t: &Table,
    x: &[[f64; 3]],
    mat: &Material,
    ke: &mut [f64],
) -> Result<(), f64> {
    debug_assert!(t.nn == N && t.nq == Q, "stiffness table size");
    // g[a][q] = ∇N_a at point q; h[a][q] = w_q det J_q ∇N_a.
    let mut g = [[[0.0; 3]; Q]; N];
    let mut h = [[[0.0; 3]; Q]; N];
    stiffness_core(t, x, mat, ke, g.as_flattened_mut(), h.as_flattened_mut())
}

/// The stiffness of the module docs with the rule of `t`; `g` and `h` (length `n·nq`, index
/// `a·nq + q`) are scratch for `∇N_a` and `w_q det J_q ∇N_a` at each point.
fn stiffness_core(
    t: &Table,
    x: &[[f64; 3]],
    mat: &Material,
    ke: &mut [f64],
    g: &mut [[f64; 3]],
    h: &mut [[f64; 3]],
) -> Result<(), f64> {
    let (n, nq) = (t.nn, t.nq);
    assert_eq!(x.len(), n, "solid::stiffness: {n} node coordinates needed");
    assert_eq!(ke.len(), 9 * n * n, "solid::stiffness: ke must be 3n × 3n");
    let (lam, mu) = mat.lame();

    for q in 0..nq {
        let dn = &t.dn[q * n..(q + 1) * n];
        let (det, inv) = volume_jacobian(x, dn)?;
        let c = t.w[q] * det;
        for a in 0..n {
            let ga = physical_gradient(&inv, dn[a]);
            g[a * nq + q] = ga;
            h[a * nq + q] = [c * ga[0], c * ga[1], c * ga[2]];
        }
    }

    let nd = 3 * n;
    for a in 0..n {
        for b in a..n {
            // S_ab = Σ_q w det ∇N_a ∇N_bᵀ
            let mut s = [[0.0; 3]; 3];
            for q in 0..nq {
                let (ha, gb) = (h[a * nq + q], g[b * nq + q]);
                for i in 0..3 {
                    for j in 0..3 {
                        s[i][j] += ha[i] * gb[j];
                    }
                }
            }
            let tr = mu * (s[0][0] + s[1][1] + s[2][2]);
            for i in 0..3 {
                for j in 0..3 {
                    let mut k = lam * s[i][j] + mu * s[j][i];
                    if i == j {
                        k += tr;
                    }
                    ke[(3 * a + i) * nd + 3 * b + j] = k;
                    ke[(3 * b + j) * nd + 3 * a + i] = k;
                }
            }
        }
    }
    Ok(())
}

/// Element mass matrix of a solid, consistent `M = ∫ ρ Nᵀ N dV` or HRZ-lumped.
///
/// `M` is block-diagonal by direction: entry `(3a + i, 3b + j) = δ_ij m_ab` with
/// `m_ab = ∫ ρ N_a N_b dV`. With [`MassLumping::Lumped`] only the diagonal is non-zero:
/// `m̃_aa = m_aa ρV / Σ_c m_cc` (see [`lumping`]), which keeps the element mass `ρV` per
/// direction. `me` is `3n × 3n` row-major and fully written. `Err(det)` as for [`stiffness`].
///
/// ```
/// use vibrofem::{element::{solid, MassLumping}, mesh::CellKind};
/// // Tet4 consistent mass: m_ab = ρV (1 + δ_ab) / 20.
/// let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
/// let mut me = [0.0; 144];
/// solid::mass(CellKind::Tet4, &x, 6.0, MassLumping::Consistent, &mut me).unwrap();
/// assert!((me[0] - 0.1).abs() < 1e-15 && (me[3] - 0.05).abs() < 1e-15 && me[1] == 0.0);
/// ```
pub fn mass(kind: CellKind, x: &[[f64; 3]], density: f64, lumping: MassLumping, me: &mut [f64]) -> Result<(), f64> {
    mass_with(kind, x, density, lumping, integration(kind, x), me)
}

/// [`mass`] with the rule set chosen by the caller rather than by [`integration`].
pub fn mass_with(
    kind: CellKind,
    x: &[[f64; 3]],
    density: f64,
    lumping: MassLumping,
    integration: Integration,
    me: &mut [f64],
) -> Result<(), f64> {
    let t = mass_table_for(kind, integration)?;
    match (kind, t.nq) {
        (CellKind::Tet4, 4) => mass_impl::<4, 4>(t, x, density, lumping, me),
        (CellKind::Tet10, 14) => mass_impl::<10, 14>(t, x, density, lumping, me),
        (CellKind::Hex8, 8) => mass_impl::<8, 8>(t, x, density, lumping, me),
        (CellKind::Hex20, 27) => mass_impl::<20, 27>(t, x, density, lumping, me),
        (CellKind::Hex27, 27) => mass_impl::<27, 27>(t, x, density, lumping, me),
        (CellKind::Wedge6, 6) => mass_impl::<6, 6>(t, x, density, lumping, me),
        (CellKind::Wedge15, 18) => mass_impl::<15, 18>(t, x, density, lumping, me),
        (CellKind::Tet10, 125) => mass_impl::<10, 125>(t, x, density, lumping, me),
        (CellKind::Hex20, 64) => mass_impl::<20, 64>(t, x, density, lumping, me),
        (CellKind::Hex27, 64) => mass_impl::<27, 64>(t, x, density, lumping, me),
        (CellKind::Wedge15, 48) => mass_impl::<15, 48>(t, x, density, lumping, me),
        _ => {
            let mut c = vec![0.0; t.nq];
            let mut diag = vec![0.0; t.nn];
            mass_core(t, x, density, lumping, me, &mut c, &mut diag)
        }
    }
}

fn mass_impl<const N: usize, const Q: usize>(
    t: &Table,
    x: &[[f64; 3]],
    density: f64,
    lumping: MassLumping,
    me: &mut [f64],
) -> Result<(), f64> {
    debug_assert!(t.nn == N && t.nq == Q, "mass table size");
    let mut c = [0.0; Q];
    let mut diag = [0.0; N];
    mass_core(t, x, density, lumping, me, &mut c, &mut diag)
}

/// The mass of [`mass`] with the rule of `t`; `c` (length `nq`) and `diag` (length `n`) are
/// scratch.
fn mass_core(
    t: &Table,
    x: &[[f64; 3]],
    density: f64,
    lumping: MassLumping,
    me: &mut [f64],
    c: &mut [f64],
    diag: &mut [f64],
) -> Result<(), f64> {
    let (n, nq) = (t.nn, t.nq);
    assert_eq!(x.len(), n, "solid::mass: {n} node coordinates needed");
    assert_eq!(me.len(), 9 * n * n, "solid::mass: me must be 3n × 3n");

    // c_q = ρ w_q det J_q
    for q in 0..nq {
        let (det, _) = volume_jacobian(x, &t.dn[q * n..(q + 1) * n])?;
        c[q] = density * t.w[q] * det;
    }
    let nd = 3 * n;
    me.fill(0.0);
    match lumping {
        MassLumping::Consistent => {
            for a in 0..n {
                for b in a..n {
                    let mut m = 0.0;
                    for q in 0..nq {
                        m += c[q] * t.n[q * n + a] * t.n[q * n + b];
                    }
                    for i in 0..3 {
                        me[(3 * a + i) * nd + 3 * b + i] = m;
                        me[(3 * b + i) * nd + 3 * a + i] = m;
                    }
                }
            }
        }
        MassLumping::Lumped => {
            diag.fill(0.0);
            let mut total = 0.0;
            for q in 0..nq {
                total += c[q];
                for a in 0..n {
                    let na = t.n[q * n + a];
                    diag[a] += c[q] * na * na;
                }
            }
            lumping::hrz(diag, total);
            for a in 0..n {
                for i in 0..3 {
                    let r = 3 * a + i;
                    me[r * nd + r] = diag[a];
                }
            }
        }
    }
    Ok(())
}

/// Volume `V = ∫ dV = Σ_q w_q det J_q` of a solid element, with the mass rule of its kind (so
/// the consistent mass sums to exactly `ρV` per direction). `Err(det)` as for [`stiffness`].
///
/// ```
/// use vibrofem::{element::solid, fe::shape, mesh::CellKind};
/// let unit: Vec<[f64; 3]> = shape::reference_nodes(CellKind::Hex20)
///     .iter().map(|p| p.map(|c| 0.5 * (c + 1.0))).collect();
/// assert!((solid::volume(CellKind::Hex20, &unit).unwrap() - 1.0).abs() < 1e-14);
/// ```
pub fn volume(kind: CellKind, x: &[[f64; 3]]) -> Result<f64, f64> {
    let t = mass_table_for(kind, integration(kind, x))?;
    let n = t.nn;
    assert_eq!(x.len(), n, "solid::volume: {kind} needs {n} node coordinates");
    let mut v = 0.0;
    for q in 0..t.nq {
        let (det, _) = volume_jacobian(x, &t.dn[q * n..(q + 1) * n])?;
        v += t.w[q] * det;
    }
    Ok(v)
}

/// Strain at reference point `xi` for element displacements `ue` (node-major, length `3n`), in
/// Voigt order `[ε_xx, ε_yy, ε_zz, γ_yz, γ_xz, γ_xy]` with engineering shear strains
/// (`γ_yz = ∂u_y/∂z + ∂u_z/∂y`). `Err(det)` if `det J(ξ) ≤ 0`.
pub fn strain_at(kind: CellKind, x: &[[f64; 3]], ue: &[f64], xi: [f64; 3]) -> Result<[f64; 6], f64> {
    if solid_index(kind).is_none() {
        return Err(NOT_A_SOLID);
    }
    let n = kind.n_nodes();
    assert_eq!(x.len(), n, "solid::strain_at: {kind} needs {n} node coordinates");
    assert_eq!(ue.len(), 3 * n, "solid::strain_at: ue must have 3n entries");
    let mut dn = [[0.0; 3]; MAX_NODES];
    shape::gradients(kind, xi, &mut dn[..n]);
    let (_, inv) = volume_jacobian(x, &dn[..n])?;
    // Displacement gradient H_ij = ∂u_i/∂x_j = Σ_a u_a,i ∂N_a/∂x_j.
    let mut h = [[0.0; 3]; 3];
    for a in 0..n {
        let g = physical_gradient(&inv, dn[a]);
        for i in 0..3 {
            let u = ue[3 * a + i];
            for j in 0..3 {
                h[i][j] += u * g[j];
            }
        }
    }
    Ok([
        h[0][0],
        h[1][1],
        h[2][2],
        h[1][2] + h[2][1],
        h[0][2] + h[2][0],
        h[0][1] + h[1][0],
    ])
}

/// Stress `σ = D ε` at reference point `xi` for element displacements `ue` (node-major,
/// length `3n`), in Voigt order `[σ_xx, σ_yy, σ_zz, σ_yz, σ_xz, σ_xy]` (see
/// [`crate::material`]). `Err(det)` if `det J(ξ) ≤ 0`.
///
/// ```
/// use vibrofem::{element::solid, material::Material, mesh::CellKind};
/// // Unit tet stretched by u_x = 1e-3 x: σ_xx = (λ + 2μ) 1e-3.
/// let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
/// let mut ue = [0.0; 12];
/// ue[3] = 1e-3;
/// let mat = Material { young: 1.0, poisson: 0.0, density: 1.0 };
/// let s = solid::stress_at(CellKind::Tet4, &x, &mat, &ue, [0.25; 3]).unwrap();
/// assert!((s[0] - 1e-3).abs() < 1e-18 && s[1] == 0.0);
/// ```
pub fn stress_at(kind: CellKind, x: &[[f64; 3]], mat: &Material, ue: &[f64], xi: [f64; 3]) -> Result<[f64; 6], f64> {
    Ok(mat.stress(&strain_at(kind, x, ue, xi)?))
}
