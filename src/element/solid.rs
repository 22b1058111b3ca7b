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
        let rule = quadrature::for_cell(kind, degree);
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
fn solid_index(kind: CellKind) -> Option<usize> {
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

fn stiffness_table(kind: CellKind) -> Result<&'static Table, f64> {
    let i = solid_index(kind).ok_or(NOT_A_SOLID)?;
    Ok(STIFFNESS_TABLES[i].get_or_init(|| Table::new(kind, stiffness_degree(kind))))
}

fn mass_table(kind: CellKind) -> Result<&'static Table, f64> {
    let i = solid_index(kind).ok_or(NOT_A_SOLID)?;
    Ok(MASS_TABLES[i].get_or_init(|| Table::new(kind, mass_degree(kind))))
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
    // Monomorphised per (nodes, points) so the inner loops have constant trip counts and the
    // gradient buffers live on the stack at their exact size.
    match kind {
        CellKind::Tet4 => stiffness_impl::<4, 1>(kind, x, mat, ke),
        CellKind::Tet10 => stiffness_impl::<10, 4>(kind, x, mat, ke),
        CellKind::Hex8 => stiffness_impl::<8, 8>(kind, x, mat, ke),
        CellKind::Hex20 => stiffness_impl::<20, 27>(kind, x, mat, ke),
        CellKind::Hex27 => stiffness_impl::<27, 27>(kind, x, mat, ke),
        CellKind::Wedge6 => stiffness_impl::<6, 6>(kind, x, mat, ke),
        CellKind::Wedge15 => stiffness_impl::<15, 18>(kind, x, mat, ke),
        CellKind::Point1
        | CellKind::Line2
        | CellKind::Line3
        | CellKind::Tri3
        | CellKind::Tri6
        | CellKind::Quad4
        | CellKind::Quad8
        | CellKind::Quad9 => Err(NOT_A_SOLID),
    }
}

fn stiffness_impl<const N: usize, const Q: usize>(
    kind: CellKind,
    x: &[[f64; 3]],
    mat: &Material,
    ke: &mut [f64],
) -> Result<(), f64> {
    let t = stiffness_table(kind)?;
    debug_assert!(t.nn == N && t.nq == Q, "stiffness table size of {kind}");
    assert_eq!(x.len(), N, "solid::stiffness: {kind} needs {N} node coordinates");
    assert_eq!(ke.len(), 9 * N * N, "solid::stiffness: ke must be 3n × 3n");
    let (lam, mu) = mat.lame();

    // g[a][q] = ∇N_a at point q; h[a][q] = w_q det J_q ∇N_a.
    let mut g = [[[0.0; 3]; Q]; N];
    let mut h = [[[0.0; 3]; Q]; N];
    for q in 0..Q {
        let dn = &t.dn[q * N..(q + 1) * N];
        let (det, inv) = volume_jacobian(x, dn)?;
        let c = t.w[q] * det;
        for a in 0..N {
            let ga = physical_gradient(&inv, dn[a]);
            g[a][q] = ga;
            h[a][q] = [c * ga[0], c * ga[1], c * ga[2]];
        }
    }

    let nd = 3 * N;
    for a in 0..N {
        for b in a..N {
            // S_ab = Σ_q w det ∇N_a ∇N_bᵀ
            let mut s = [[0.0; 3]; 3];
            for q in 0..Q {
                let (ha, gb) = (h[a][q], g[b][q]);
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
    match kind {
        CellKind::Tet4 => mass_impl::<4, 4>(kind, x, density, lumping, me),
        CellKind::Tet10 => mass_impl::<10, 14>(kind, x, density, lumping, me),
        CellKind::Hex8 => mass_impl::<8, 8>(kind, x, density, lumping, me),
        CellKind::Hex20 => mass_impl::<20, 27>(kind, x, density, lumping, me),
        CellKind::Hex27 => mass_impl::<27, 27>(kind, x, density, lumping, me),
        CellKind::Wedge6 => mass_impl::<6, 6>(kind, x, density, lumping, me),
        CellKind::Wedge15 => mass_impl::<15, 18>(kind, x, density, lumping, me),
        CellKind::Point1
        | CellKind::Line2
        | CellKind::Line3
        | CellKind::Tri3
        | CellKind::Tri6
        | CellKind::Quad4
        | CellKind::Quad8
        | CellKind::Quad9 => Err(NOT_A_SOLID),
    }
}

fn mass_impl<const N: usize, const Q: usize>(
    kind: CellKind,
    x: &[[f64; 3]],
    density: f64,
    lumping: MassLumping,
    me: &mut [f64],
) -> Result<(), f64> {
    let t = mass_table(kind)?;
    debug_assert!(t.nn == N && t.nq == Q, "mass table size of {kind}");
    assert_eq!(x.len(), N, "solid::mass: {kind} needs {N} node coordinates");
    assert_eq!(me.len(), 9 * N * N, "solid::mass: me must be 3n × 3n");

    // c_q = ρ w_q det J_q
    let mut c = [0.0; Q];
    for q in 0..Q {
        let (det, _) = volume_jacobian(x, &t.dn[q * N..(q + 1) * N])?;
        c[q] = density * t.w[q] * det;
    }
    let nd = 3 * N;
    me.fill(0.0);
    match lumping {
        MassLumping::Consistent => {
            for a in 0..N {
                for b in a..N {
                    let mut m = 0.0;
                    for q in 0..Q {
                        m += c[q] * t.n[q * N + a] * t.n[q * N + b];
                    }
                    for i in 0..3 {
                        me[(3 * a + i) * nd + 3 * b + i] = m;
                        me[(3 * b + i) * nd + 3 * a + i] = m;
                    }
                }
            }
        }
        MassLumping::Lumped => {
            let mut diag = [0.0; N];
            let mut total = 0.0;
            for q in 0..Q {
                total += c[q];
                for a in 0..N {
                    let na = t.n[q * N + a];
                    diag[a] += c[q] * na * na;
                }
            }
            lumping::hrz(&mut diag, total);
            for a in 0..N {
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
    let t = mass_table(kind)?;
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
