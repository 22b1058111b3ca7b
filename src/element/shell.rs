//! Reissner–Mindlin flat (faceted) shell elements: MITC4 on `Quad4`, MITC3 on `Tri3`.
//!
//! # Degrees of freedom and output layout
//!
//! Six components per node, `ux, uy, uz, rx, ry, rz`, in **global** axes (the order of
//! [`crate::dof`]). Matrices are dense, row-major, `6n × 6n`, node-major: entry
//! `(6a + i, 6b + j)` couples component `i` of node `a` with component `j` of node `b`.
//! On `Err` the output buffer holds unspecified values.
//!
//! # Element frame
//!
//! Each element is computed in a local frame `(e1, e2, n)`, `n` the element normal by the
//! right-hand rule on the node order ("top" is `+n`), and transformed to global axes.
//! - `Tri3`: `e1` along edge 0→1, `n = (x1 − x0) × (x2 − x0)/|…|`.
//! - `Quad4`: the **mean plane** through the centroid with `n ∥ d1 × d2` (the diagonals
//!   `d1 = x2 − x0`, `d2 = x3 − x1`), `e1` along the projected `ξ` direction. A warped
//!   (non-planar) quad has nodes at heights `h_a = (x_a − c)·n = ±h` above that plane; the
//!   element is computed on the projected flat quad and joined to the real nodes by rigid
//!   links of length `h_a` along `n` (`u_flat = u + θ × (−h_a n)`), the warping correction of
//!   Taylor (1987) and MacNeal (1978). Rigid links keep rigid-body motions exact; the accuracy
//!   degrades gracefully with warp (see the twisted-beam test, 90° of twist over 12 elements).
//!
//! # Membrane, drilling and plate parts (local frame)
//!
//! - **Membrane.** `Quad4`: bilinear displacements enriched with the four incompatible
//!   modes `(1 − ξ², 1 − η²)` of Wilson and Taylor (QM6; Taylor, Beresford and Wilson 1976),
//!   whose strains use the centre Jacobian scaled by `det J₀/det J` so that the element passes
//!   the patch test; the modes are condensed out per element. This makes in-plane bending of
//!   rectangles exact (webs of I-beams and channels bend in their plane). `Tri3`: constant
//!   strain.
//! - **Drilling rotation.** The rotation `θz` about `n` is tied to the in-plane rotation
//!   of the membrane `ω = ½(∂v/∂x − ∂u/∂y)` by the penalty of Hughes and Brezzi (1989),
//!   `½ ∫ α G t (θz − ω)² dA` with `α` = [`ShellSection::drilling`] (default `0.1`),
//!   integrated at the 2 × 2 (quad) or 3 (triangle) points so that every `θz` is restrained
//!   (no spurious zero-energy mode) while a rigid rotation costs nothing: a free element has
//!   exactly 6 zero eigenvalues. Within one quad the four nodal `θz` can match `ω` at the
//!   four points exactly, so the penalty does not stiffen a quad's membrane by itself; it only
//!   ties neighbours together (an in-plane cantilever moves by 2e-4 between `α = 1e-3` and
//!   `10`).
//!
//!   **Choice of `α`.** The term is variationally consistent for the membrane, but on a
//!   *twisted or curved* faceted surface the nodal rotation's normal component also enters
//!   the neighbours' bending, and a weak tie lets it act as an extra, nearly free field: the
//!   converged answer then depends on `α`, with a relative weight of about
//!   `(E/G)(t φ')²/(12 α)` for a twist rate `φ'`. Measured on the twisted-beam benchmark
//!   (90° over `L`/`t` = 37.5, quads): `α = 1e-3` is 26–32 % too flexible on 12 × 2 *and*
//!   48 × 8 meshes, `1e-2` is 3 % off, `0.1`–`10` within 0.4 %. Triangles prefer small `α`:
//!   the penalty over-constrains the constant-strain membrane (twisted beam 12 × 2: −15 % at
//!   `0.1`, −27 % at `10`; Scordelis–Lo 16 × 16: −4 % at `0.1`, −10 % at `10`). `α = 0.1`
//!   serves both; flat plates are insensitive to it.
//! - **Plate.** Mindlin bending with `D = E t³/(12(1 − ν²))` and transverse shear
//!   `κ G t`, `κ = 5/6`. The shear strains are the MITC assumed fields, which remove
//!   shear locking in the thin limit:
//!   - MITC4 (Dvorkin and Bathe 1984): covariant `γ_ξ` tied at the edge midpoints `(0, ±1)`
//!     and interpolated linearly in `η`, `γ_η` tied at `(±1, 0)` and linear in `ξ`.
//!   - MITC3 (Lee and Bathe 2004): the covariant field `γ_r = γ_r⁽¹⁾ + c s`,
//!     `γ_s = γ_s⁽²⁾ − c r`, `c = γ_s⁽²⁾ − γ_r⁽¹⁾ − γ_s⁽³⁾ + γ_r⁽³⁾` with tying points
//!     (1) `(½, 0)`, (2) `(0, ½)`, (3) `(½, ½)`: the tangential shear is constant along
//!     each edge.
//!
//!   Rotations `θx, θy` are the local components of the rotation vector: a fibre at height
//!   `z` moves by `z (θy, −θx)` in the plane.
//!
//! Integration: 2 × 2 Gauss on quads (membrane, bending, shear, drilling); the 3-point
//! degree-2 rule on triangles (exact for the quadratic shear and drilling integrands; the
//! constant membrane and bending terms are exact with any rule).
//!
//! # Offset
//!
//! Nodes lie on the reference surface, at [`ShellSection::offset`] from the mid-surface along
//! `n`. The element is computed at the mid-surface and joined to the nodes by rigid links
//! (exact for Reissner–Mindlin kinematics), which couples membrane and bending: a plate
//! meshed on its bottom face uses `offset = −t/2`. The mass is transformed with the same
//! links, which gives the first and second moments of the offset mass.
//!
//! # Mass
//!
//! Consistent: `∫ ρ t N_a N_b dA` for the three translations and the rotary inertia
//! `∫ ρ t³/12 N_a N_b dA` for **all three** rotations. The drilling entry has no physical
//! counterpart in Mindlin theory; giving it the bending rotary inertia keeps `M` positive
//! definite and rotation-invariant (a node's rotational inertia is isotropic), and since `θz`
//! is tied to the membrane rotation it adds no spurious low mode. HRZ lumping
//! ([`MassLumping::Lumped`]) keeps `ρ t ∫ N_a² dA` scaled to `ρ t A`, and `t²/12` of that for
//! each rotation; it is diagonal in global axes when the offset is zero, and has the 6 × 6
//! node blocks of the offset's moments otherwise. The mass is computed on the projected
//! (flat) element and attached at the nodes with the offset only (the warping links of the
//! stiffness are not applied: they would make the lumped matrix non-diagonal for a mass shift
//! of order `h_a`).
//!
//! # Stress
//!
//! [`stress_at`] gives the stress at a point at the bottom (`z = −t/2`), middle and top
//! (`z = +t/2`) of the shell, in global axes and the Voigt order of [`crate::material`].
//! In-plane stresses are plane stress from `ε₀ + z κ`; the transverse shear follows the
//! parabola `τ(z) = 1.5 (Q/t)(1 − 4z²/t²)` of the shear force `Q = κ G t γ` (zero at the
//! faces, 1.5 × the mean at the middle); `σ_nn = 0`.

// Index loops over nodes, components and points read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

use crate::element::beam::{NodeTransform, congruence};
use crate::element::lumping::MassLumping;
use crate::fe::geometry::{cross, dot, normalize as unit, plane_jacobian, sub};
use crate::fe::quadrature::{QUAD_2X2, TRIANGLE_3};
use crate::fe::shape as reference;
use crate::material::Material;
use crate::mesh::CellKind;
pub use crate::section::ShellSection;

/// Components per node of every shell element (`ux, uy, uz, rx, ry, rz`).
pub const DOFS_PER_NODE: usize = 6;

/// Transverse shear correction factor of the Mindlin plate.
pub const SHEAR_FACTOR: f64 = 5.0 / 6.0;

/// Largest element DOF count (Quad4 × 6).
const MAXD: usize = 24;

/// True for the cell kinds this module handles (`Tri3`, `Quad4`).
pub fn supports(kind: CellKind) -> bool {
    matches!(kind, CellKind::Tri3 | CellKind::Quad4)
}

/// The flat element: frame, in-plane node coordinates and heights above the mean plane.
struct Flat {
    kind: CellKind,
    nn: usize,
    /// Rows `e1, e2, n`: `local = r · global`.
    r: [[f64; 3]; 3],
    /// In-plane coordinates of the (projected) nodes relative to the centroid.
    p: [[f64; 2]; 4],
    /// Heights of the nodes above the mean plane (0 for triangles and flat quads).
    h: [f64; 4],
}

/// The error value of every kernel here for a kind that is not a shell: NaN, "no Jacobian"
/// (a set never holds such a kind: the model checks kinds when it binds the mesh).
const NOT_A_SHELL: f64 = f64::NAN;

fn flat(kind: CellKind, x: &[[f64; 3]]) -> Result<Flat, f64> {
    let nn = kind.n_nodes();
    if !supports(kind) {
        return Err(NOT_A_SHELL);
    }
    assert_eq!(x.len(), nn, "shell: {kind} needs {nn} node coordinates");
    let mut c = [0.0; 3];
    for xa in x {
        for i in 0..3 {
            c[i] += xa[i] / nn as f64;
        }
    }
    let (n, e1) = match kind {
        CellKind::Tri3 => {
            let n = unit(cross(sub(x[1], x[0]), sub(x[2], x[0])))?;
            (n, unit(sub(x[1], x[0]))?)
        }
        CellKind::Quad4 => {
            let n = unit(cross(sub(x[2], x[0]), sub(x[3], x[1])))?;
            let mut g = [0.0; 3];
            for i in 0..3 {
                g[i] = 0.25 * (-x[0][i] + x[1][i] + x[2][i] - x[3][i]);
            }
            let gn = dot(g, n);
            (n, unit([g[0] - gn * n[0], g[1] - gn * n[1], g[2] - gn * n[2]])?)
        }
        CellKind::Point1
        | CellKind::Line2
        | CellKind::Line3
        | CellKind::Tri6
        | CellKind::Quad8
        | CellKind::Quad9
        | CellKind::Tet4
        | CellKind::Tet10
        | CellKind::Hex8
        | CellKind::Hex20
        | CellKind::Hex27
        | CellKind::Wedge6
        | CellKind::Wedge15 => return Err(NOT_A_SHELL),
    };
    let e2 = cross(n, e1);
    let mut f = Flat {
        kind,
        nn,
        r: [e1, e2, n],
        p: [[0.0; 2]; 4],
        h: [0.0; 4],
    };
    for a in 0..nn {
        let d = sub(x[a], c);
        f.p[a] = [dot(d, e1), dot(d, e2)];
        if nn == 4 {
            f.h[a] = dot(d, n);
        }
    }
    Ok(f)
}

/// The element frame: rows `[e1, e2, n]` (orthonormal, right-handed, `n` the element normal
/// by the right-hand rule on the node order; for a warped quad the normal of the mean plane).
/// Stresses and resultants in local axes refer to it. `Err(0.0)` for a degenerate element.
///
/// ```
/// use vibrofem::{element::shell, mesh::CellKind};
/// let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
/// let r = shell::local_frame(CellKind::Quad4, &x).unwrap();
/// assert_eq!(r[2], [0.0, 0.0, 1.0]);
/// ```
pub fn local_frame(kind: CellKind, x: &[[f64; 3]]) -> Result<[[f64; 3]; 3], f64> {
    Ok(flat(kind, x)?.r)
}

/// Shape functions of the flat element at `(ξ, η)` and their 2D reference gradients, from
/// [`crate::fe::shape`] (bilinear on `Quad4`, `(1 − r − s, r, s)` on `Tri3`; unused entries 0).
fn shape(kind: CellKind, xi: f64, eta: f64) -> ([f64; 4], [[f64; 2]; 4]) {
    let nn = kind.n_nodes();
    let mut n = [0.0; 4];
    let mut g = [[0.0; 3]; 4];
    reference::values_and_gradients(kind, [xi, eta, 0.0], &mut n[..nn], &mut g[..nn]);
    let mut dn = [[0.0; 2]; 4];
    for a in 0..nn {
        dn[a] = [g[a][0], g[a][1]];
    }
    (n, dn)
}

/// Determinant and inverse of the 2D Jacobian of the flat element.
fn jac2(p: &[[f64; 2]; 4], dn: &[[f64; 2]; 4], nn: usize) -> Result<(f64, [[f64; 2]; 2]), f64> {
    plane_jacobian(p, dn, nn)
}

/// `inv · [a; b]`: physical gradient from reference gradient, or Cartesian shear from
/// covariant components.
fn apply(inv: &[[f64; 2]; 2], a: f64, b: f64) -> [f64; 2] {
    [inv[0][0] * a + inv[0][1] * b, inv[1][0] * a + inv[1][1] * b]
}

/// Integration points `(ξ, η, weight)` of the element's 2D rule: 2 × 2 Gauss (quad) or the
/// 3-point degree-2 rule (triangle, weights summing to 1/2), from [`crate::fe::quadrature`].
/// The triangle uses the constant [`TRIANGLE_3`], not `quadrature::triangle(2)`: that rule
/// lists the same points in another order, and the order of the sums is part of the result.
fn rule(nn: usize) -> &'static [(f64, f64, f64)] {
    if nn == 4 { &QUAD_2X2 } else { &TRIANGLE_3 }
}

/// Plane-stress matrix times `c`: `c [[1, ν, 0], [ν, 1, 0], [0, 0, (1 − ν)/2]]`.
fn plane(c: f64, nu: f64) -> [[f64; 3]; 3] {
    [[c, c * nu, 0.0], [c * nu, c, 0.0], [0.0, 0.0, c * 0.5 * (1.0 - nu)]]
}

/// Local index of membrane DOF `k` (`u, v, θz`) and plate DOF `k` (`w, θx, θy`) of node `a`.
const MEM: [usize; 3] = [0, 1, 5];
const PLT: [usize; 3] = [2, 3, 4];

/// Membrane + drilling matrices over `(u, v, θz)` per node (12 or 9 DOFs) and the four
/// incompatible modes `(u·P1, u·P2, v·P1, v·P2)` of the quad.
struct Membrane {
    kmm: [[f64; 12]; 12],
    kma: [[f64; 4]; 12],
    kaa: [[f64; 4]; 4],
}

/// Membrane strain row (3 × 12) and drilling row (θz − ω) of the compatible field, plus the
/// incompatible-mode rows (3 × 4, 4) at a point with physical gradients `g` and values `n`.
fn membrane_rows(nn: usize, n: &[f64; 4], g: &[[f64; 2]; 4]) -> ([[f64; 12]; 3], [f64; 12]) {
    let mut b = [[0.0; 12]; 3];
    let mut d = [0.0; 12];
    for a in 0..nn {
        let (gx, gy) = (g[a][0], g[a][1]);
        b[0][3 * a] = gx;
        b[1][3 * a + 1] = gy;
        b[2][3 * a] = gy;
        b[2][3 * a + 1] = gx;
        // θz − ½(v_x − u_y)
        d[3 * a] = 0.5 * gy;
        d[3 * a + 1] = -0.5 * gx;
        d[3 * a + 2] = n[a];
    }
    (b, d)
}

fn membrane(f: &Flat, sec: &ShellSection, mat: &Material) -> Result<Membrane, f64> {
    let nn = f.nn;
    let t = sec.thickness;
    let dm = plane(mat.young * t / (1.0 - mat.poisson * mat.poisson), mat.poisson);
    let gam = sec.drilling * mat.shear_modulus() * t;
    let mut m = Membrane {
        kmm: [[0.0; 12]; 12],
        kma: [[0.0; 4]; 12],
        kaa: [[0.0; 4]; 4],
    };
    let (det0, inv0) = if nn == 4 {
        let (_, dn0) = shape(CellKind::Quad4, 0.0, 0.0);
        let (d0, i0) = jac2(&f.p, &dn0, 4)?;
        (d0, i0)
    } else {
        (0.0, [[0.0; 2]; 2])
    };
    for &(xi, eta, w) in rule(nn) {
        let (n, dn) = shape(f.kind, xi, eta);
        let (det, inv) = jac2(&f.p, &dn, nn)?;
        let mut g = [[0.0; 2]; 4];
        for a in 0..nn {
            g[a] = apply(&inv, dn[a][0], dn[a][1]);
        }
        let (b, d) = membrane_rows(nn, &n, &g);
        let c = w * det;
        let nm = 3 * nn;
        // Compatible part: Bᵀ Dm B (constant strain of triangles: the 3 points sum to A).
        for p in 0..nm {
            for q in 0..nm {
                let mut s = 0.0;
                for i in 0..3 {
                    for j in 0..3 {
                        s += b[i][p] * dm[i][j] * b[j][q];
                    }
                }
                m.kmm[p][q] += c * (s + gam * d[p] * d[q]);
            }
        }
        if nn == 4 {
            // Incompatible modes with the centre Jacobian, scaled by det J₀ / det J.
            let sc = det0 / det;
            let g1 = apply(&inv0, -2.0 * xi, 0.0);
            let g2 = apply(&inv0, 0.0, -2.0 * eta);
            let (g1, g2) = ([sc * g1[0], sc * g1[1]], [sc * g2[0], sc * g2[1]]);
            let mut ba = [[0.0; 4]; 3];
            let mut da = [0.0; 4];
            for (k, gk) in [g1, g2].iter().enumerate() {
                // u-mode k and v-mode k.
                ba[0][k] = gk[0];
                ba[2][k] = gk[1];
                ba[1][2 + k] = gk[1];
                ba[2][2 + k] = gk[0];
                da[k] = 0.5 * gk[1];
                da[2 + k] = -0.5 * gk[0];
            }
            for p in 0..nm {
                for q in 0..4 {
                    let mut s = 0.0;
                    for i in 0..3 {
                        for j in 0..3 {
                            s += b[i][p] * dm[i][j] * ba[j][q];
                        }
                    }
                    m.kma[p][q] += c * (s + gam * d[p] * da[q]);
                }
            }
            for p in 0..4 {
                for q in 0..4 {
                    let mut s = 0.0;
                    for i in 0..3 {
                        for j in 0..3 {
                            s += ba[i][p] * dm[i][j] * ba[j][q];
                        }
                    }
                    m.kaa[p][q] += c * (s + gam * da[p] * da[q]);
                }
            }
        }
    }
    Ok(m)
}

/// Inverse of a symmetric positive definite 4 × 4 matrix (Gauss–Jordan; SPD needs no pivoting).
fn inverse4(a: &[[f64; 4]; 4]) -> [[f64; 4]; 4] {
    let mut m = *a;
    let mut inv = [[0.0; 4]; 4];
    for i in 0..4 {
        inv[i][i] = 1.0;
    }
    for c in 0..4 {
        let p = 1.0 / m[c][c];
        for j in 0..4 {
            m[c][j] *= p;
            inv[c][j] *= p;
        }
        for r in 0..4 {
            if r != c {
                let f = m[r][c];
                for j in 0..4 {
                    m[r][j] -= f * m[c][j];
                    inv[r][j] -= f * inv[c][j];
                }
            }
        }
    }
    inv
}

/// Covariant transverse shear row (over `(w, θx, θy)` per node) at `(ξ, η)` in reference
/// direction `dir`: `e = ∂w/∂ξ_dir + β·∂x/∂ξ_dir`, `β = (θy, −θx)`.
fn covariant_shear(f: &Flat, xi: f64, eta: f64, dir: usize) -> [f64; 12] {
    let (n, dn) = shape(f.kind, xi, eta);
    let mut xd = [0.0; 2];
    for a in 0..f.nn {
        xd[0] += dn[a][dir] * f.p[a][0];
        xd[1] += dn[a][dir] * f.p[a][1];
    }
    let mut row = [0.0; 12];
    for a in 0..f.nn {
        row[3 * a] = dn[a][dir];
        row[3 * a + 1] = -n[a] * xd[1];
        row[3 * a + 2] = n[a] * xd[0];
    }
    row
}

/// The tying rows of the element's assumed shear field.
struct Tying {
    /// Quad: `e_ξ` at `(0, 1)`, `(0, −1)`, `e_η` at `(1, 0)`, `(−1, 0)`. Triangle: `e_r⁽¹⁾`,
    /// `e_s⁽²⁾`, `c`, unused.
    rows: [[f64; 12]; 4],
}

fn tying(f: &Flat) -> Tying {
    if f.nn == 4 {
        Tying {
            rows: [
                covariant_shear(f, 0.0, 1.0, 0),
                covariant_shear(f, 0.0, -1.0, 0),
                covariant_shear(f, 1.0, 0.0, 1),
                covariant_shear(f, -1.0, 0.0, 1),
            ],
        }
    } else {
        let er1 = covariant_shear(f, 0.5, 0.0, 0);
        let es2 = covariant_shear(f, 0.0, 0.5, 1);
        let er3 = covariant_shear(f, 0.5, 0.5, 0);
        let es3 = covariant_shear(f, 0.5, 0.5, 1);
        let mut c = [0.0; 12];
        for k in 0..12 {
            c[k] = es2[k] - er1[k] - es3[k] + er3[k];
        }
        Tying {
            rows: [er1, es2, c, [0.0; 12]],
        }
    }
}

/// Cartesian assumed shear rows `[γ_xz, γ_yz]` at `(ξ, η)` with Jacobian inverse `inv`.
fn assumed_shear(f: &Flat, ty: &Tying, xi: f64, eta: f64, inv: &[[f64; 2]; 2]) -> [[f64; 12]; 2] {
    let r = &ty.rows;
    let mut out = [[0.0; 12]; 2];
    for k in 0..3 * f.nn {
        let (e1, e2) = if f.nn == 4 {
            (
                0.5 * (1.0 + eta) * r[0][k] + 0.5 * (1.0 - eta) * r[1][k],
                0.5 * (1.0 + xi) * r[2][k] + 0.5 * (1.0 - xi) * r[3][k],
            )
        } else {
            (r[0][k] + r[2][k] * eta, r[1][k] - r[2][k] * xi)
        };
        let g = apply(inv, e1, e2);
        out[0][k] = g[0];
        out[1][k] = g[1];
    }
    out
}

/// Curvature rows `κ = (∂θy/∂x, −∂θx/∂y, ∂θy/∂y − ∂θx/∂x)` over `(w, θx, θy)` per node.
fn curvature_rows(nn: usize, g: &[[f64; 2]; 4]) -> [[f64; 12]; 3] {
    let mut b = [[0.0; 12]; 3];
    for a in 0..nn {
        b[0][3 * a + 2] = g[a][0];
        b[1][3 * a + 1] = -g[a][1];
        b[2][3 * a + 2] = g[a][1];
        b[2][3 * a + 1] = -g[a][0];
    }
    b
}

/// Local stiffness of the flat mid-surface element, `(6n)²` in `k` with stride `6n`.
fn local_stiffness(f: &Flat, sec: &ShellSection, mat: &Material, k: &mut [f64]) -> Result<(), f64> {
    let nn = f.nn;
    let nd = 6 * nn;
    k[..nd * nd].fill(0.0);
    // Membrane with drilling, incompatible modes condensed.
    let m = membrane(f, sec, mat)?;
    let nm = 3 * nn;
    let mut kc = m.kmm;
    if nn == 4 {
        let ia = inverse4(&m.kaa);
        for p in 0..nm {
            for q in 0..nm {
                let mut s = 0.0;
                for i in 0..4 {
                    for j in 0..4 {
                        s += m.kma[p][i] * ia[i][j] * m.kma[q][j];
                    }
                }
                kc[p][q] -= s;
            }
        }
    }
    for a in 0..nn {
        for i in 0..3 {
            for b in 0..nn {
                for j in 0..3 {
                    k[(6 * a + MEM[i]) * nd + 6 * b + MEM[j]] = kc[3 * a + i][3 * b + j];
                }
            }
        }
    }
    // Plate: bending + MITC shear.
    let t = sec.thickness;
    let nu = mat.poisson;
    let db = plane(mat.young * t.powi(3) / (12.0 * (1.0 - nu * nu)), nu);
    let ds = SHEAR_FACTOR * mat.shear_modulus() * t;
    let ty = tying(f);
    let mut kp = [[0.0; 12]; 12];
    for &(xi, eta, w) in rule(nn) {
        let (_, dn) = shape(f.kind, xi, eta);
        let (det, inv) = jac2(&f.p, &dn, nn)?;
        let mut g = [[0.0; 2]; 4];
        for a in 0..nn {
            g[a] = apply(&inv, dn[a][0], dn[a][1]);
        }
        let bb = curvature_rows(nn, &g);
        let bs = assumed_shear(f, &ty, xi, eta, &inv);
        let c = w * det;
        for p in 0..nm {
            for q in 0..nm {
                let mut s = 0.0;
                for i in 0..3 {
                    for j in 0..3 {
                        s += bb[i][p] * db[i][j] * bb[j][q];
                    }
                }
                s += ds * (bs[0][p] * bs[0][q] + bs[1][p] * bs[1][q]);
                kp[p][q] += c * s;
            }
        }
    }
    for a in 0..nn {
        for i in 0..3 {
            for b in 0..nn {
                for j in 0..3 {
                    k[(6 * a + PLT[i]) * nd + 6 * b + PLT[j]] = kp[3 * a + i][3 * b + j];
                }
            }
        }
    }
    Ok(())
}

/// Per-node transform global → flat local: rotation `blockdiag(R, R)` followed by the rigid
/// link of length `d` along `n`: `u_l = u − d θy`, `v_l = v + d θx`.
fn node_transform(r: &[[f64; 3]; 3], d: f64) -> NodeTransform {
    let mut g = [[0.0; 7]; 7];
    for i in 0..3 {
        for j in 0..3 {
            g[i][j] = r[i][j];
            g[3 + i][3 + j] = r[i][j];
        }
    }
    for j in 0..3 {
        g[0][3 + j] -= d * r[1][j];
        g[1][3 + j] += d * r[0][j];
    }
    g
}

/// Node transforms with links `h_a + offset` (stiffness, stress) or `offset` (mass).
fn transforms(f: &Flat, sec: &ShellSection, warp: bool) -> [NodeTransform; 4] {
    let mut g = [[[0.0; 7]; 7]; 4];
    for a in 0..f.nn {
        let d = sec.offset + if warp { f.h[a] } else { 0.0 };
        g[a] = node_transform(&f.r, d);
    }
    g
}

/// Element stiffness of a shell in global axes (MITC4 on `Quad4`, MITC3 on `Tri3`, with
/// drilling penalty, warping links and offset as in the module docs).
///
/// - `kind`: `Tri3` or `Quad4` (panics otherwise: the caller checks [`supports`]).
/// - `x`: node coordinates in gmsh order; `sec`: a validated section; `mat`: the material.
/// - `ke`: output, `6n × 6n` row-major, node-major; fully written.
/// - `Err(det)`: degenerate (zero-area, collinear) or self-intersecting element, with the
///   offending Jacobian determinant of the flat element (0 for a zero normal).
///
/// ```
/// use vibrofem::{element::shell, material::Material, mesh::CellKind, section::ShellSection};
/// // Unit square, uniform stretch u = ε x: the nodal forces on the edge x = 1 add up to
/// // σ t = E ε t (ν = 0).
/// let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
/// let mat = Material { young: 1.0, poisson: 0.0, density: 1.0 };
/// let mut ke = [0.0; 576];
/// shell::stiffness(CellKind::Quad4, &x, &ShellSection::new(0.1), &mat, &mut ke).unwrap();
/// let u: Vec<f64> = (0..24).map(|i| if i % 6 == 0 { x[i / 6][0] } else { 0.0 }).collect();
/// let fx1: f64 = (0..24).map(|j| ke[6 * 24 + j] * u[j] + ke[12 * 24 + j] * u[j]).sum();
/// assert!((fx1 - 0.1).abs() < 1e-14);
/// ```
pub fn stiffness(
    kind: CellKind,
    x: &[[f64; 3]],
    sec: &ShellSection,
    mat: &Material,
    ke: &mut [f64],
) -> Result<(), f64> {
    let f = flat(kind, x)?;
    let nd = 6 * f.nn;
    assert_eq!(ke.len(), nd * nd, "shell::stiffness: ke must be 6n × 6n");
    let mut kl = [0.0; MAXD * MAXD];
    local_stiffness(&f, sec, mat, &mut kl)?;
    congruence(&kl, f.nn, 6, &transforms(&f, sec, true), ke);
    Ok(())
}

/// Area of the (projected, mean-plane) element: `Σ_q w_q det J_q`, the area the mass refers
/// to. `Err(det)` as for [`stiffness`].
pub fn area(kind: CellKind, x: &[[f64; 3]]) -> Result<f64, f64> {
    let f = flat(kind, x)?;
    let mut a = 0.0;
    for &(xi, eta, w) in rule(f.nn) {
        let (_, dn) = shape(f.kind, xi, eta);
        a += w * jac2(&f.p, &dn, f.nn)?.0;
    }
    Ok(a)
}

/// Element mass of a shell in global axes, consistent (translations `ρt`, rotations
/// `ρt³/12`, offset coupling) or HRZ lumped; see the module docs. Layout as for
/// [`stiffness`]; `density` is `ρ` (kg/m³). `Err(det)` as for [`stiffness`].
///
/// ```
/// use vibrofem::{element::{shell, MassLumping}, mesh::CellKind, section::ShellSection};
/// let x = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// let mut me = [0.0; 324];
/// shell::mass(CellKind::Tri3, &x, &ShellSection::new(0.01), 8000.0, MassLumping::Lumped, &mut me).unwrap();
/// // Each node gets a third of ρ t A = 80 kg per direction.
/// assert!((me[0] - 80.0 / 3.0).abs() < 1e-12 && me[1] == 0.0);
/// ```
pub fn mass(
    kind: CellKind,
    x: &[[f64; 3]],
    sec: &ShellSection,
    density: f64,
    lumping: MassLumping,
    me: &mut [f64],
) -> Result<(), f64> {
    let f = flat(kind, x)?;
    let nn = f.nn;
    let nd = 6 * nn;
    assert_eq!(me.len(), nd * nd, "shell::mass: me must be 6n × 6n");
    let t = sec.thickness;
    let rt = density * t;
    let mut m = [[0.0; 4]; 4];
    let mut total = 0.0;
    for &(xi, eta, w) in rule(nn) {
        let (n, dn) = shape(f.kind, xi, eta);
        let c = w * jac2(&f.p, &dn, nn)?.0 * rt;
        total += c;
        for a in 0..nn {
            for b in 0..nn {
                m[a][b] += c * n[a] * n[b];
            }
        }
    }
    if lumping == MassLumping::Lumped {
        let s = total / (0..nn).map(|a| m[a][a]).sum::<f64>();
        for a in 0..nn {
            for b in 0..nn {
                m[a][b] = if a == b { s * m[a][a] } else { 0.0 };
            }
        }
    }
    let rot = t * t / 12.0;
    let mut ml = [0.0; MAXD * MAXD];
    for a in 0..nn {
        for b in 0..nn {
            for i in 0..6 {
                ml[(6 * a + i) * nd + 6 * b + i] = if i < 3 { m[a][b] } else { rot * m[a][b] };
            }
        }
    }
    if sec.offset == 0.0 {
        // The blocks are isotropic: invariant under the rotation to global axes.
        me.copy_from_slice(&ml[..nd * nd]);
    } else {
        congruence(&ml, nn, 6, &transforms(&f, sec, false), me);
    }
    Ok(())
}

/// Stresses through the thickness at one point of a shell element, in global axes and the
/// Voigt order `[σ_xx, σ_yy, σ_zz, σ_yz, σ_xz, σ_xy]` of [`crate::material`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShellStress {
    /// At `z = −t/2` (the face opposite to the normal `n`).
    pub bottom: [f64; 6],
    /// At the mid-surface (membrane stress, peak transverse shear).
    pub middle: [f64; 6],
    /// At `z = +t/2` (the face on the side of `n`).
    pub top: [f64; 6],
}

/// Stresses at reference point `xi` (`(ξ, η)` in [-1, 1]² for quads, `(r, s)` on the unit
/// triangle) for element displacements `ue` (global, node-major, `6n`), at the bottom,
/// middle and top of the shell (see the module docs for the through-thickness model).
/// `Err(det)` as for [`stiffness`].
///
/// ```
/// use vibrofem::{element::shell, material::Material, mesh::CellKind, section::ShellSection};
/// // Rotation θy = κ x at the nodes and w = −κ x²/2 bend the square: σ_xx = ± E κ t/2.
/// let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
/// let mat = Material { young: 1e9, poisson: 0.0, density: 1.0 };
/// let k = 1e-3;
/// let mut ue = [0.0; 24];
/// for a in 0..4 {
///     ue[6 * a + 2] = -0.5 * k * x[a][0] * x[a][0];
///     ue[6 * a + 4] = k * x[a][0];
/// }
/// let s = shell::stress_at(CellKind::Quad4, &x, &ShellSection::new(0.01), &mat, &ue, [0.0; 3]).unwrap();
/// assert!((s.top[0] - 1e9 * k * 0.005).abs() < 1e-6 && (s.bottom[0] + s.top[0]).abs() < 1e-6);
/// ```
pub fn stress_at(
    kind: CellKind,
    x: &[[f64; 3]],
    sec: &ShellSection,
    mat: &Material,
    ue: &[f64],
    xi: [f64; 3],
) -> Result<ShellStress, f64> {
    let f = flat(kind, x)?;
    let nn = f.nn;
    assert_eq!(ue.len(), 6 * nn, "shell::stress_at: ue must have 6n entries");
    // Local flat DOFs.
    let g = transforms(&f, sec, true);
    let mut ul = [0.0; MAXD];
    for a in 0..nn {
        for i in 0..6 {
            ul[6 * a + i] = (0..6).map(|j| g[a][i][j] * ue[6 * a + j]).sum();
        }
    }
    let mut um = [0.0; 12];
    let mut up = [0.0; 12];
    for a in 0..nn {
        for k in 0..3 {
            um[3 * a + k] = ul[6 * a + MEM[k]];
            up[3 * a + k] = ul[6 * a + PLT[k]];
        }
    }
    let (r, s) = (xi[0], xi[1]);
    let (n, dn) = shape(f.kind, r, s);
    let (det, inv) = jac2(&f.p, &dn, nn)?;
    let mut gr = [[0.0; 2]; 4];
    for a in 0..nn {
        gr[a] = apply(&inv, dn[a][0], dn[a][1]);
    }
    let (bm, _) = membrane_rows(nn, &n, &gr);
    let mut eps = [0.0; 3];
    for i in 0..3 {
        eps[i] = (0..3 * nn).map(|p| bm[i][p] * um[p]).sum();
    }
    if nn == 4 {
        // Recover the condensed incompatible modes: α = −Kαα⁻¹ Kαm u_m.
        let m = membrane(&f, sec, mat)?;
        let ia = inverse4(&m.kaa);
        let mut rhs = [0.0; 4];
        for q in 0..4 {
            rhs[q] = (0..12).map(|p| m.kma[p][q] * um[p]).sum();
        }
        let mut alpha = [0.0; 4];
        for i in 0..4 {
            alpha[i] = -(0..4).map(|j| ia[i][j] * rhs[j]).sum::<f64>();
        }
        let (_, dn0) = shape(CellKind::Quad4, 0.0, 0.0);
        let (det0, inv0) = jac2(&f.p, &dn0, 4)?;
        let sc = det0 / det;
        let g1 = apply(&inv0, -2.0 * r, 0.0);
        let g2 = apply(&inv0, 0.0, -2.0 * s);
        for (k, gk) in [g1, g2].iter().enumerate() {
            let (gx, gy) = (sc * gk[0], sc * gk[1]);
            eps[0] += gx * alpha[k];
            eps[2] += gy * alpha[k] + gx * alpha[2 + k];
            eps[1] += gy * alpha[2 + k];
        }
    }
    let bb = curvature_rows(nn, &gr);
    let bs = assumed_shear(&f, &tying(&f), r, s, &inv);
    let mut kap = [0.0; 3];
    for i in 0..3 {
        kap[i] = (0..3 * nn).map(|p| bb[i][p] * up[p]).sum();
    }
    let gam: [f64; 2] = [0, 1].map(|i| (0..3 * nn).map(|p| bs[i][p] * up[p]).sum());
    let t = sec.thickness;
    let dp = plane(mat.young / (1.0 - mat.poisson * mat.poisson), mat.poisson);
    let gmod = mat.shear_modulus();
    let at = |z: f64| -> [f64; 6] {
        let e = [eps[0] + z * kap[0], eps[1] + z * kap[1], eps[2] + z * kap[2]];
        let sig: [f64; 3] = [0, 1, 2].map(|i| (0..3).map(|j| dp[i][j] * e[j]).sum());
        let prof = 1.5 * SHEAR_FACTOR * gmod * (1.0 - 4.0 * z * z / (t * t));
        let (txz, tyz) = (prof * gam[0], prof * gam[1]);
        // Local tensor → global: σ_g = Rᵀ σ_l R.
        let sl = [[sig[0], sig[2], txz], [sig[2], sig[1], tyz], [txz, tyz, 0.0]];
        let rr = &f.r;
        let mut sg = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let mut v = 0.0;
                for k in 0..3 {
                    for l in 0..3 {
                        v += rr[k][i] * sl[k][l] * rr[l][j];
                    }
                }
                sg[i][j] = v;
            }
        }
        [sg[0][0], sg[1][1], sg[2][2], sg[1][2], sg[0][2], sg[0][1]]
    };
    Ok(ShellStress {
        bottom: at(-0.5 * t),
        middle: at(0.0),
        top: at(0.5 * t),
    })
}
