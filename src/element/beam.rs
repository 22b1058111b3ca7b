//! 3D Timoshenko beam elements: stiffness and mass of `Line2` and `Line3`, with an optional
//! warping degree of freedom (Vlasov torsion) on `Line2`.
//!
//! # Local axes and degrees of freedom
//!
//! Local `x` runs along the element (node 0 → node 1), local `y` is the element's orientation
//! vector made orthogonal to `x`, and `z = x × y`. An orientation vector (nearly) parallel to
//! the axis is an error: the sine of the angle between them must be at least `1e-6`. Section
//! properties refer to these axes ([`BeamSection`]).
//!
//! Each node carries `ux, uy, uz, rx, ry, rz` in **global** axes (component order of
//! [`crate::dof`]) and, for a warping section, a seventh component `w`, the warping amplitude
//! `w = dθx/dx` (the rate of twist about the local axis; it is a scalar, independent of the
//! direction in which the element is numbered). [`dofs_per_node`] gives 6 or 7.
//!
//! # Output layout
//!
//! Matrices are dense, row-major, `(n·d) × (n·d)` for `n` nodes and `d` = [`dofs_per_node`],
//! node-major: entry `(d a + i, d b + j)` couples component `i` of node `a` with component
//! `j` of node `b`.
//!
//! # `Line2`: exact two-node Timoshenko element
//!
//! Axial `EA/L` and, without warping, torsion `GJ/L`. Bending in each principal plane uses the
//! closed-form stiffness of the Timoshenko beam (Przemieniecki 1968, *Theory of Matrix
//! Structural Analysis* §5.6), with `Φ_y = 12 E Iz/(ky G A L²)` for the `x–y` plane
//! (`v`, `θz`) and `Φ_z = 12 E Iy/(kz G A L²)` for `x–z` (`w`, `θy`):
//!
//! ```text
//!              E I      | 12     6L          −12    6L        |
//! K_plane = ---------- | 6L     (4+Φ)L²     −6L    (2−Φ)L²   |    (v, θz) or (w, −θy)
//!           (1+Φ) L³   | −12    −6L          12    −6L        |
//!                       | 6L     (2−Φ)L²     −6L    (4+Φ)L²   |
//! ```
//!
//! It is the exact stiffness of the shear-deformable beam: a cantilever of one element gives
//! `PL³/(3EI) + PL/(kGA)` to rounding, so there is no shear locking in any aspect ratio.
//!
//! **Warping** (7 DOF per node): the torsion part becomes Vlasov's `½∫(GJ θ'² + E Cw θ''²) dx`
//! with the twist interpolated by cubic Hermite functions of `(θx, w)` at both nodes. The
//! element converges to the hyperbolic closed form with mesh refinement (4th order in the tip
//! rotation; see the tests). Warping is available on `Line2` only.
//!
//! **Shear centre.** Shear and twist act at the shear centre, offset `e = (ey, ez)` from the
//! centroid (the node line). The element is formulated with the shear-centre transverse
//! displacements `v_s = v − ez θx`, `w_s = w + ey θx` and transformed back to the centroid
//! degrees of freedom, `K = Sᵀ K_s S`; a force through the centroid then twists a channel and
//! one through the shear centre does not. Rigid motions are preserved by the transformation.
//!
//! **Mass** (consistent): axial `ρAL/6 [2 1; 1 2]`; torsion `ρ Ip L/6 [2 1; 1 2]` with the
//! polar moment about the centroid `Ip = Iy + Iz` (with warping: `∫ρ Ip θ² + ρ Cw θ'² dx` with
//! the Hermite functions); bending `∫ρA N N + ρI ψ ψ dx` with the interdependent
//! interpolation of the exact element (Friedman and Kosmatka 1993, Comput. Struct. 47,
//! 473–481): transverse and rotation fields that reproduce the stiffness above, so
//! translation *and* rotary inertia (`ρI` terms) are consistent. The mass is expressed in the
//! centroid variables (no shear-centre coupling: the kinetic energy of a section is
//! `½ρA|v̇_c|² + ½ρ Ip θ̇²`).
//!
//! # `Line3`: three-node isoparametric element, reduced integration
//!
//! Displacements `u` and rotations `θ` (global vectors) interpolate quadratically along a
//! possibly curved axis (nodes 0 and 1 at the ends, 2 in the middle, gmsh order). With the
//! unit tangent `t` and section axes `(t, e2, e3)` at each point, the generalized strains are
//! `Γ = u' + t × θ` (axial `t·Γ`, shear `e2·Γ`, `e3·Γ`) and `K = θ'` (twist `t·K`, bending
//! `e2·K`, `e3·K`); rigid motions give `Γ = K = 0` exactly, also on curved elements. All
//! stiffness terms use 2-point Gauss integration (reduced: no shear or membrane locking, and
//! still exactly 6 zero-energy modes), the mass 3 points. Shear-centre offsets enter as
//! `γ_y − ez κ_x`, `γ_z + ey κ_x`.
//!
//! # Lumped mass (HRZ)
//!
//! [`MassLumping::Lumped`] keeps the diagonal of the consistent matrix (in local axes), scaled
//! per field so that the translations get `ρAL` per direction, the twist `ρ Ip L`; the
//! rotation and warping entries of a field scale with it (Hinton, Rock and Zienkiewicz 1976).
//! The translational part is diagonal in global axes (isotropic); the rotational part is a
//! 3 × 3 block per node (diagonal in local axes), so the lumped matrix is node-block-diagonal.

// Index loops over nodes and components read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

use crate::element::lumping::MassLumping;
use crate::error::{Error, Result};
use crate::fe::geometry::{cross, line_metric, norm, scale, sub};
use crate::fe::quadrature::{GAUSS2, GAUSS3, GAUSS4};
use crate::fe::shape;
use crate::material::Material;
use crate::mesh::CellKind;
use crate::section::BeamSection;

/// Largest number of element DOFs (`Line3` × 7 would be 21; `Line3` × 6 = 18, `Line2` × 7 = 14).
const MAXD: usize = 21;

/// Components per node for `section`: 7 when it requests the warping DOF, else 6.
pub fn dofs_per_node(section: &BeamSection) -> usize {
    if section.warping { 7 } else { 6 }
}

/// True for the cell kinds this module handles (`Line2`, `Line3`).
pub fn supports(kind: CellKind) -> bool {
    matches!(kind, CellKind::Line2 | CellKind::Line3)
}

/// Local axes of a beam at a point with tangent `tangent` (any length) and orientation
/// vector `orientation` (the local `y` hint): rows `[e_x, e_y, e_z]`, orthonormal and
/// right-handed, `e_x ∥ tangent`, `e_y` in the plane of `tangent` and `orientation`.
///
/// Errors ([`Error::param`]): a zero or non-finite tangent (zero-length element), a
/// zero or non-finite orientation vector, or one within `1e-6` rad of the axis.
///
/// ```
/// use vibrofem::element::beam;
/// let r = beam::local_axes([2.0, 0.0, 0.0], [0.0, 0.0, 1.0]).unwrap();
/// assert_eq!(r, [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]);
/// assert!(beam::local_axes([0.0, 0.0, 1.0], [0.0, 0.0, -3.0]).is_err());
/// ```
pub fn local_axes(tangent: [f64; 3], orientation: [f64; 3]) -> Result<[[f64; 3]; 3]> {
    let lt = norm(tangent);
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(lt > 0.0 && lt.is_finite()) {
        return Err(Error::param(
            "tangent",
            format!("beam element of zero or undefined length (axis {tangent:?})"),
        ));
    }
    let lo = norm(orientation);
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(lo > 0.0 && lo.is_finite()) {
        return Err(Error::param(
            "orientation",
            format!("beam orientation vector {orientation:?} is zero or not finite"),
        ));
    }
    let ex = scale(tangent, 1.0 / lt);
    let ez = cross(ex, scale(orientation, 1.0 / lo));
    let s = norm(ez);
    if s < 1e-6 {
        return Err(Error::param(
            "orientation",
            format!(
                "beam orientation vector ({:.6}, {:.6}, {:.6}) is parallel to the element axis \
             ({:.6}, {:.6}, {:.6}): it must give the local y direction, across the beam",
                orientation[0], orientation[1], orientation[2], ex[0], ex[1], ex[2]
            ),
        ));
    }
    let ez = scale(ez, 1.0 / s);
    let ey = cross(ez, ex);
    Ok([ex, ey, ez])
}

/// Length of a beam element: the chord for `Line2` (the closed-form element is written in
/// it), the arc length (3-point Gauss, exact for straight elements) for `Line3`.
///
/// # Panics
/// For a kind that is not a beam (`Line2`, `Line3`): a length has no meaning there and the
/// function returns a plain number. The match is exhaustive, so a new kind must be placed.
pub fn length(kind: CellKind, x: &[[f64; 3]]) -> f64 {
    match kind {
        CellKind::Line2 => {
            assert_eq!(x.len(), 2, "beam::length: line2 needs 2 nodes");
            norm(sub(x[1], x[0]))
        }
        CellKind::Line3 => {
            assert_eq!(x.len(), 3, "beam::length: line3 needs 3 nodes");
            GAUSS3.iter().map(|&(xi, w)| w * norm(line3_tangent(x, xi))).sum()
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
        | CellKind::Wedge15 => panic!("beam::length: {kind} is not a beam cell kind"),
    }
}

/// Per-node transformation from global to local degrees of freedom: `local_i = Σ_j g[i][j]
/// global_j` (`g` is `d × d`, the rest of the 7 × 7 array unused).
pub(crate) type NodeTransform = [[f64; 7]; 7];

/// Congruence `out_ab = G_aᵀ A_ab G_b` of a node-major local matrix `a` (`nn` nodes, `nd`
/// components each, row-major `(nn·nd)²`) with the per-node transforms `g`, written to `out`
/// (same layout). This is how local element matrices become global ones.
pub(crate) fn congruence(a: &[f64], nn: usize, nd: usize, g: &[NodeTransform], out: &mut [f64]) {
    let n = nn * nd;
    debug_assert!(a.len() >= n * n && out.len() == n * n && g.len() >= nn);
    for na in 0..nn {
        for nb in 0..nn {
            // t = A_ab G_b
            let mut t = [[0.0; 7]; 7];
            for i in 0..nd {
                let row = &a[(na * nd + i) * n + nb * nd..(na * nd + i) * n + nb * nd + nd];
                for j in 0..nd {
                    let mut s = 0.0;
                    for k in 0..nd {
                        s += row[k] * g[nb][k][j];
                    }
                    t[i][j] = s;
                }
            }
            for p in 0..nd {
                for q in 0..nd {
                    let mut s = 0.0;
                    for i in 0..nd {
                        s += g[na][i][p] * t[i][q];
                    }
                    out[(na * nd + p) * n + nb * nd + q] = s;
                }
            }
        }
    }
}

/// Node transform `blockdiag(R, R, 1)` (rotation of translations and rotations; the warping
/// amplitude is a scalar), optionally followed by the shear-centre map `v_s = v − ez θx`,
/// `w_s = w + ey θx`.
fn node_transform(r: &[[f64; 3]; 3], nd: usize, shear_centre: Option<[f64; 2]>) -> NodeTransform {
    let mut g = [[0.0; 7]; 7];
    for i in 0..3 {
        for j in 0..3 {
            g[i][j] = r[i][j];
            g[3 + i][3 + j] = r[i][j];
        }
    }
    if nd == 7 {
        g[6][6] = 1.0;
    }
    if let Some([ey, ez]) = shear_centre {
        // Row of θx (local) is R[0] applied to the global rotations.
        for j in 0..3 {
            g[1][3 + j] -= ez * r[0][j];
            g[2][3 + j] += ey * r[0][j];
        }
    }
    g
}

/// Element stiffness matrix of a beam in global axes.
///
/// - `kind`: `Line2` or `Line3` (an [`Error::param`] otherwise).
/// - `x`: node coordinates in gmsh order; `orientation`: local `y` hint (see the module
///   docs); `sec`: a validated section; `mat`: the material.
/// - `ke`: output, `(n·d)²` row-major with `d` = [`dofs_per_node`]`(sec)`; fully written.
/// - Errors: zero length, orientation parallel to the axis, warping requested on `Line3`.
///
/// ```
/// use vibrofem::{element::beam, material::Material, mesh::CellKind, section::BeamSection};
/// // One element, cantilever along x: tip stiffness 1/(L³/(3EI) + L/(kGA)) in z.
/// let (l, sec, mat) = (2.0, BeamSection::rectangle(0.1, 0.2), Material::steel());
/// let mut ke = [0.0; 144];
/// beam::stiffness(CellKind::Line2, &[[0.0; 3], [l, 0.0, 0.0]], [0.0, 1.0, 0.0], &sec, &mat, &mut ke).unwrap();
/// // Condense the free end (w2, θy2): k = K_ww − K_wθ² / K_θθ.
/// let (kww, kwt, ktt) = (ke[8 * 12 + 8], ke[8 * 12 + 10], ke[10 * 12 + 10]);
/// let flex = l.powi(3) / (3.0 * mat.young * sec.iy) + l / (sec.kz * mat.shear_modulus() * sec.area);
/// assert!(((kww - kwt * kwt / ktt) * flex - 1.0).abs() < 1e-12);
/// ```
pub fn stiffness(
    kind: CellKind,
    x: &[[f64; 3]],
    orientation: [f64; 3],
    sec: &BeamSection,
    mat: &Material,
    ke: &mut [f64],
) -> Result<()> {
    let nd = dofs_per_node(sec);
    match kind {
        CellKind::Line2 => {
            assert_eq!(x.len(), 2, "beam::stiffness: line2 needs 2 nodes");
            assert_eq!(ke.len(), 4 * nd * nd, "beam::stiffness: ke must be 2d × 2d");
            let axis = sub(x[1], x[0]);
            let r = local_axes(axis, orientation)?;
            let mut kl = [0.0; MAXD * MAXD];
            line2_local_stiffness(norm(axis), sec, mat, nd, &mut kl);
            let g = node_transform(&r, nd, Some(sec.shear_centre));
            congruence(&kl, 2, nd, &[g, g], ke);
            Ok(())
        }
        CellKind::Line3 => {
            assert_eq!(x.len(), 3, "beam::stiffness: line3 needs 3 nodes");
            if sec.warping {
                return Err(warping_line3());
            }
            assert_eq!(ke.len(), 18 * 18, "beam::stiffness: ke must be 18 × 18 for line3");
            line3_stiffness(x, orientation, sec, mat, ke)
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
        | CellKind::Wedge15 => Err(not_a_beam(kind)),
    }
}

/// The error for a cell kind that is not a beam (every beam kernel).
pub(crate) fn not_a_beam(kind: CellKind) -> Error {
    Error::param("kind", format!("{kind} is not a beam cell kind (line2 or line3)"))
}

/// The error for the warping DOF on a 3-node beam (every beam kernel).
pub(crate) fn warping_line3() -> Error {
    Error::param(
        "BeamSection::warping",
        "the warping degree of freedom is available on 2-node beams (line2) only; \
         mesh this beam group with first-order lines or turn warping off"
            .to_string(),
    )
}

/// Adds the bending stiffness of one principal plane: deflection component `d`, rotation
/// component `r` with sign `sr` such that `d' ≈ sr·θ_r`.
#[allow(clippy::too_many_arguments)]
fn add_bending(k: &mut [f64], n: usize, nd: usize, d: usize, r: usize, sr: f64, ei: f64, phi: f64, l: f64) {
    let c = ei / ((1.0 + phi) * l.powi(3));
    #[rustfmt::skip]
    let m = [
        [12.0,      6.0 * l,                 -12.0,    6.0 * l],
        [6.0 * l,   (4.0 + phi) * l * l,     -6.0 * l, (2.0 - phi) * l * l],
        [-12.0,     -6.0 * l,                12.0,     -6.0 * l],
        [6.0 * l,   (2.0 - phi) * l * l,     -6.0 * l, (4.0 + phi) * l * l],
    ];
    let idx = [d, r, nd + d, nd + r];
    let sgn = [1.0, sr, 1.0, sr];
    for i in 0..4 {
        for j in 0..4 {
            k[idx[i] * n + idx[j]] += c * sgn[i] * sgn[j] * m[i][j];
        }
    }
}

/// Cubic Hermite functions on `[0, L]` at `ξ = x/L`: values, first and second derivatives in
/// `x`, for the DOFs `(θ(0), θ'(0), θ(L), θ'(L))`.
fn hermite(xi: f64, l: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let (x2, x3) = (xi * xi, xi * xi * xi);
    let h = [
        1.0 - 3.0 * x2 + 2.0 * x3,
        l * (xi - 2.0 * x2 + x3),
        3.0 * x2 - 2.0 * x3,
        l * (x3 - x2),
    ];
    let dh = [
        (6.0 * x2 - 6.0 * xi) / l,
        1.0 - 4.0 * xi + 3.0 * x2,
        (6.0 * xi - 6.0 * x2) / l,
        3.0 * x2 - 2.0 * xi,
    ];
    let ddh = [
        (12.0 * xi - 6.0) / (l * l),
        (6.0 * xi - 4.0) / l,
        (6.0 - 12.0 * xi) / (l * l),
        (6.0 * xi - 2.0) / l,
    ];
    (h, dh, ddh)
}

/// Local `Line2` stiffness in shear-centre variables, `(2nd)²` row-major in `k` (stride `2nd`).
fn line2_local_stiffness(l: f64, sec: &BeamSection, mat: &Material, nd: usize, k: &mut [f64]) {
    let n = 2 * nd;
    k[..n * n].fill(0.0);
    let (e, g) = (mat.young, mat.shear_modulus());
    let mut add = |i: usize, j: usize, v: f64| k[i * n + j] += v;
    // Axial.
    let ka = e * sec.area / l;
    add(0, 0, ka);
    add(nd, nd, ka);
    add(0, nd, -ka);
    add(nd, 0, -ka);
    // Torsion.
    if nd == 6 {
        let kt = g * sec.j / l;
        add(3, 3, kt);
        add(nd + 3, nd + 3, kt);
        add(3, nd + 3, -kt);
        add(nd + 3, 3, -kt);
    } else {
        let idx = [3, 6, nd + 3, nd + 6];
        for &(xi, w) in &GAUSS4 {
            let (_, dh, ddh) = hermite(0.5 * (1.0 + xi), l);
            let c = 0.5 * w * l;
            for i in 0..4 {
                for j in 0..4 {
                    add(
                        idx[i],
                        idx[j],
                        c * (g * sec.j * dh[i] * dh[j] + e * sec.cw * ddh[i] * ddh[j]),
                    );
                }
            }
        }
    }
    // Bending: x–y plane (v, θz), x–z plane (w, −θy).
    let phi_y = 12.0 * e * sec.iz / (sec.ky * g * sec.area * l * l);
    let phi_z = 12.0 * e * sec.iy / (sec.kz * g * sec.area * l * l);
    add_bending(k, n, nd, 1, 5, 1.0, e * sec.iz, phi_y, l);
    add_bending(k, n, nd, 2, 4, -1.0, e * sec.iy, phi_z, l);
}

/// Interdependent interpolation of the exact Timoshenko element (Friedman–Kosmatka) at
/// `ξ = x/L`: deflection functions `N` and rotation functions `ψ` for `(d1, θ1, d2, θ2)`.
fn kosmatka(xi: f64, l: f64, phi: f64) -> ([f64; 4], [f64; 4]) {
    let c = 1.0 / (1.0 + phi);
    let (x2, x3) = (xi * xi, xi * xi * xi);
    let n = [
        c * (2.0 * x3 - 3.0 * x2 - phi * xi + 1.0 + phi),
        c * l * (x3 - (2.0 + 0.5 * phi) * x2 + (1.0 + 0.5 * phi) * xi),
        c * (-2.0 * x3 + 3.0 * x2 + phi * xi),
        c * l * (x3 - (1.0 - 0.5 * phi) * x2 - 0.5 * phi * xi),
    ];
    let psi = [
        c * 6.0 * (x2 - xi) / l,
        c * (3.0 * x2 - (4.0 + phi) * xi + 1.0 + phi),
        -c * 6.0 * (x2 - xi) / l,
        c * (3.0 * x2 - (2.0 - phi) * xi),
    ];
    (n, psi)
}

/// Local consistent `Line2` mass (centroid variables), `(2nd)²` row-major in `m`.
fn line2_local_mass(l: f64, sec: &BeamSection, mat: &Material, nd: usize, m: &mut [f64]) {
    let n = 2 * nd;
    m[..n * n].fill(0.0);
    let rho = mat.density;
    let (e, g) = (mat.young, mat.shear_modulus());
    let mut add = |i: usize, j: usize, v: f64| m[i * n + j] += v;
    let link = |add: &mut dyn FnMut(usize, usize, f64), c: usize, total: f64| {
        add(c, c, total / 3.0);
        add(nd + c, nd + c, total / 3.0);
        add(c, nd + c, total / 6.0);
        add(nd + c, c, total / 6.0);
    };
    link(&mut add, 0, rho * sec.area * l);
    let ip = sec.polar();
    if nd == 6 {
        link(&mut add, 3, rho * ip * l);
    } else {
        let idx = [3, 6, nd + 3, nd + 6];
        for &(xi, w) in &GAUSS4 {
            let (h, dh, _) = hermite(0.5 * (1.0 + xi), l);
            let c = 0.5 * w * l * rho;
            for i in 0..4 {
                for j in 0..4 {
                    add(idx[i], idx[j], c * (ip * h[i] * h[j] + sec.cw * dh[i] * dh[j]));
                }
            }
        }
    }
    let phi_y = 12.0 * e * sec.iz / (sec.ky * g * sec.area * l * l);
    let phi_z = 12.0 * e * sec.iy / (sec.kz * g * sec.area * l * l);
    for (d, r, sr, inertia, phi) in [(1, 5, 1.0, sec.iz, phi_y), (2, 4, -1.0, sec.iy, phi_z)] {
        let idx = [d, r, nd + d, nd + r];
        let sgn = [1.0, sr, 1.0, sr];
        for &(xi, w) in &GAUSS4 {
            let (nn, psi) = kosmatka(0.5 * (1.0 + xi), l, phi);
            let c = 0.5 * w * l * rho;
            for i in 0..4 {
                for j in 0..4 {
                    add(
                        idx[i],
                        idx[j],
                        c * sgn[i] * sgn[j] * (sec.area * nn[i] * nn[j] + inertia * psi[i] * psi[j]),
                    );
                }
            }
        }
    }
}

/// HRZ lumping of a local `Line2` mass in place: per field, the diagonal scaled so that the
/// field's "translational" members sum to `total`; off-diagonal entries cleared.
fn line2_hrz(m: &mut [f64], nd: usize, sec: &BeamSection, rho: f64, l: f64) {
    let n = 2 * nd;
    let mut diag = [0.0; MAXD];
    for i in 0..n {
        diag[i] = m[i * n + i];
    }
    let mass = rho * sec.area * l;
    let torsion: &[usize] = if nd == 6 { &[3] } else { &[3, 6] };
    let fields: [(usize, &[usize], f64); 4] = [
        (0, &[0], mass),
        (1, &[1, 5], mass),
        (2, &[2, 4], mass),
        (3, torsion, rho * sec.polar() * l),
    ];
    let mut out = [0.0; MAXD];
    for (lead, members, total) in fields {
        let s = total / (diag[lead] + diag[nd + lead]);
        for &c in members {
            out[c] = s * diag[c];
            out[nd + c] = s * diag[nd + c];
        }
    }
    m[..n * n].fill(0.0);
    for i in 0..n {
        m[i * n + i] = out[i];
    }
}

/// Element mass matrix of a beam in global axes, consistent (with rotary inertia) or HRZ
/// lumped; layout and errors as for [`stiffness`]. The density is `mat.density`; `E/G`
/// shapes the interdependent interpolation of `Line2` (through `Φ`).
///
/// ```
/// use vibrofem::{element::{beam, MassLumping}, material::Material, mesh::CellKind, section::BeamSection};
/// let (sec, mat) = (BeamSection::circle(0.05), Material::steel());
/// let x = [[0.0, 0.0, 0.0], [0.3, 0.4, 0.0]];
/// let mut me = [0.0; 144];
/// beam::mass(CellKind::Line2, &x, [0.0, 0.0, 1.0], &sec, &mat, MassLumping::Consistent, &mut me).unwrap();
/// // A rigid translation along y carries the whole mass ρAL.
/// let m: f64 = [1, 7].iter().flat_map(|&i| [1, 7].map(|j| me[i * 12 + j])).sum();
/// assert!((m / (7850.0 * sec.area * 0.5) - 1.0).abs() < 1e-13);
/// ```
pub fn mass(
    kind: CellKind,
    x: &[[f64; 3]],
    orientation: [f64; 3],
    sec: &BeamSection,
    mat: &Material,
    lumping: MassLumping,
    me: &mut [f64],
) -> Result<()> {
    let nd = dofs_per_node(sec);
    match kind {
        CellKind::Line2 => {
            assert_eq!(x.len(), 2, "beam::mass: line2 needs 2 nodes");
            assert_eq!(me.len(), 4 * nd * nd, "beam::mass: me must be 2d × 2d");
            let axis = sub(x[1], x[0]);
            let r = local_axes(axis, orientation)?;
            let l = norm(axis);
            let mut ml = [0.0; MAXD * MAXD];
            line2_local_mass(l, sec, mat, nd, &mut ml);
            if lumping == MassLumping::Lumped {
                line2_hrz(&mut ml, nd, sec, mat.density, l);
            }
            let g = node_transform(&r, nd, None);
            congruence(&ml, 2, nd, &[g, g], me);
            Ok(())
        }
        CellKind::Line3 => {
            assert_eq!(x.len(), 3, "beam::mass: line3 needs 3 nodes");
            if sec.warping {
                return Err(warping_line3());
            }
            assert_eq!(me.len(), 18 * 18, "beam::mass: me must be 18 × 18 for line3");
            line3_mass(x, orientation, sec, mat.density, lumping, me)
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
        | CellKind::Wedge15 => Err(not_a_beam(kind)),
    }
}

/// Quadratic Lagrange functions on [-1, 1] (nodes −1, +1, 0) and their ξ-derivatives, from
/// [`crate::fe::shape`].
fn line3_shape(xi: f64) -> ([f64; 3], [f64; 3]) {
    let mut n = [0.0; 3];
    let mut g = [[0.0; 3]; 3];
    shape::values_and_gradients(CellKind::Line3, [xi, 0.0, 0.0], &mut n, &mut g);
    (n, [g[0][0], g[1][0], g[2][0]])
}

/// Tangent `x_ξ` of a `Line3` element at `ξ` ([`line_metric`]).
fn line3_tangent(x: &[[f64; 3]], xi: f64) -> [f64; 3] {
    let (_, dn) = line3_shape(xi);
    line_metric(x, &dn).0
}

fn line3_stiffness(
    x: &[[f64; 3]],
    orientation: [f64; 3],
    sec: &BeamSection,
    mat: &Material,
    ke: &mut [f64],
) -> Result<()> {
    let (e, g) = (mat.young, mat.shear_modulus());
    let d = [
        e * sec.area,
        sec.ky * g * sec.area,
        sec.kz * g * sec.area,
        g * sec.j,
        e * sec.iy,
        e * sec.iz,
    ];
    let [ey, ez] = sec.shear_centre;
    ke.fill(0.0);
    for &(xi, w) in &GAUSS2 {
        let tan = line3_tangent(x, xi);
        let r = local_axes(tan, orientation)?;
        let jac = norm(tan);
        let (nn, dn) = line3_shape(xi);
        let [t, e2, e3] = r;
        // B: 6 generalized strains × 18 DOFs.
        let mut b = [[0.0; 18]; 6];
        for a in 0..3 {
            let dna = dn[a] / jac;
            for i in 0..3 {
                let (u, th) = (6 * a + i, 6 * a + 3 + i);
                b[0][u] = dna * t[i];
                b[1][u] = dna * e2[i];
                b[1][th] = -nn[a] * e3[i];
                b[2][u] = dna * e3[i];
                b[2][th] = nn[a] * e2[i];
                b[3][th] = dna * t[i];
                b[4][th] = dna * e2[i];
                b[5][th] = dna * e3[i];
            }
        }
        for c in 0..18 {
            b[1][c] -= ez * b[3][c];
            b[2][c] += ey * b[3][c];
        }
        let wj = w * jac;
        for p in 0..18 {
            for q in p..18 {
                let mut s = 0.0;
                for k in 0..6 {
                    s += b[k][p] * d[k] * b[k][q];
                }
                ke[p * 18 + q] += wj * s;
            }
        }
    }
    for p in 0..18 {
        for q in 0..p {
            ke[p * 18 + q] = ke[q * 18 + p];
        }
    }
    Ok(())
}

fn line3_mass(
    x: &[[f64; 3]],
    orientation: [f64; 3],
    sec: &BeamSection,
    rho: f64,
    lumping: MassLumping,
    me: &mut [f64],
) -> Result<()> {
    // Scalar translational mass m_ab and rotational inertia blocks I_ab (3 × 3).
    let mut mt = [[0.0; 3]; 3];
    let mut mr = [[[[0.0; 3]; 3]; 3]; 3];
    let mut total = 0.0;
    for &(xi, w) in &GAUSS3 {
        let tan = line3_tangent(x, xi);
        let r = local_axes(tan, orientation)?;
        let wj = w * norm(tan);
        total += wj * rho * sec.area;
        let (nn, _) = line3_shape(xi);
        // Inertia tensor per length in global axes: Σ_k ρ I_k e_k e_kᵀ.
        let ik = [rho * sec.polar(), rho * sec.iy, rho * sec.iz];
        let mut it = [[0.0; 3]; 3];
        for k in 0..3 {
            for i in 0..3 {
                for j in 0..3 {
                    it[i][j] += ik[k] * r[k][i] * r[k][j];
                }
            }
        }
        for a in 0..3 {
            for b in 0..3 {
                let c = wj * nn[a] * nn[b];
                mt[a][b] += c * rho * sec.area;
                for i in 0..3 {
                    for j in 0..3 {
                        mr[a][b][i][j] += c * it[i][j];
                    }
                }
            }
        }
    }
    me.fill(0.0);
    if lumping == MassLumping::Lumped {
        let s = total / (mt[0][0] + mt[1][1] + mt[2][2]);
        for a in 0..3 {
            for i in 0..3 {
                me[(6 * a + i) * 18 + 6 * a + i] = s * mt[a][a];
                for j in 0..3 {
                    me[(6 * a + 3 + i) * 18 + 6 * a + 3 + j] = s * mr[a][a][i][j];
                }
            }
        }
        return Ok(());
    }
    for a in 0..3 {
        for b in 0..3 {
            for i in 0..3 {
                me[(6 * a + i) * 18 + 6 * b + i] = mt[a][b];
                for j in 0..3 {
                    me[(6 * a + 3 + i) * 18 + 6 * b + 3 + j] = mr[a][b][i][j];
                }
            }
        }
    }
    Ok(())
}
