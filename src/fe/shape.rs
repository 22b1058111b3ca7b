//! Shape functions of every [`CellKind`], in gmsh's node ordering.
//!
//! Each kind has a reference cell, its nodes ([`reference_nodes`]), the shape functions
//! `N_i(ξ)` ([`values`]) and their reference gradients `∂N_i/∂ξ` ([`gradients`]). Coordinates
//! `ξ = (ξ, η, ζ)` (also written `(u, v, w)`) always have three components; those beyond the
//! cell's dimension are ignored on input and get zero derivatives on output.
//!
//! | cells | reference cell |
//! |---|---|
//! | lines | `ξ ∈ [-1, 1]` |
//! | triangles, tetrahedra | unit simplex `u, v (, w) ≥ 0`, `u + v (+ w) ≤ 1` |
//! | quadrilaterals, hexahedra | `[-1, 1]²`, `[-1, 1]³` |
//! | wedges | unit triangle in `(u, v)` × `w ∈ [-1, 1]` |
//!
//! The families: Lagrange on simplices (`Tri6`, `Tet10`: `L(2L − 1)` at vertices and `4 L_a L_b`
//! on edges, with barycentric `L`), tensor-product Lagrange on `Quad4/9`, `Hex8/27` (built from
//! the 1D linear and quadratic Lagrange functions of each node's coordinates), serendipity on
//! `Quad8`, `Hex20` and `Wedge15`, and triangle × line on `Wedge6`.
//!
//! # Node ordering (gmsh)
//!
//! Lines: vertices first, then the midpoint.
//! ```text
//! Line2:  0----------1 --> u        Line3:  0-----2----1
//! ```
//!
//! Triangles (edges 3: 0-1, 4: 1-2, 5: 2-0) and quadrilaterals (edges 4: 0-1, 5: 1-2,
//! 6: 2-3, 7: 3-0; centre 8):
//! ```text
//! Tri3:               Tri6:                 Quad4:            Quad8:            Quad9:
//! v
//! ^                                          v
//! |                                          ^
//! 2                   2                      |
//! |`\                 |`\               3----+----2       3-----6-----2     3-----6-----2
//! |  `\               |  `\             |    |    |       |           |     |           |
//! |    `\             5    `4           |    +----|-> u   7           5     7     8     5
//! |      `\           |      `\         |         |       |           |     |           |
//! 0--------1 --> u    0---3----1        0---------1       0-----4-----1     0-----4-----1
//! ```
//!
//! Tetrahedra (edges 4: 0-1, 5: 1-2, 6: 2-0, 7: 0-3, 8: 2-3, 9: 1-3):
//! ```text
//! Tet4:                                Tet10:
//!                    v
//!                  .
//!                ,/
//!               /
//!            2                                     2
//!          ,/|`\                                 ,/|`\
//!        ,/  |  `\                             ,/  |  `\
//!      ,/    '.   `\                         ,6    '.   `5
//!    ,/       |     `\                     ,/       8     `\
//!  ,/         |       `\                 ,/         |       `\
//! 0-----------'.--------1 --> u         0--------4--'.--------1
//!  `\.         |      ,/                 `\.         |      ,/
//!     `\.      |    ,/                      `\.      |    ,9
//!        `\.   '. ,/                           `7.   '. ,/
//!           `\. |/                                `\. |/
//!              `3                                    `3
//!                 `\.
//!                    ` w
//! ```
//!
//! Hexahedra. Vertices 0–3 at `ζ = −1`, 4–7 at `ζ = +1`, each square counter-clockwise from
//! `(−1, −1)`. Edges 8: 0-1, 9: 0-3, 10: 0-4, 11: 1-2, 12: 1-5, 13: 2-3, 14: 2-6, 15: 3-7,
//! 16: 4-5, 17: 4-7, 18: 5-6, 19: 6-7. Faces 20: 0-3-2-1 (`ζ = −1`), 21: 0-1-5-4 (`η = −1`),
//! 22: 0-4-7-3 (`ξ = −1`), 23: 1-2-6-5 (`ξ = +1`), 24: 2-3-7-6 (`η = +1`), 25: 4-5-6-7
//! (`ζ = +1`); centre 26.
//! ```text
//! Hex8:                   Hex20:                 Hex27:
//!        v
//! 3----------2            3----13----2           3----13----2
//! |\     ^   |\           |\         |\          |\         |\
//! | \    |   | \          | 15       | 14        |15    24  | 14
//! |  \   |   |  \         9  \       11 \        9  \ 20    11 \
//! |   7------+---6        |   7----19+---6       |   7----19+---6
//! |   |  +-- |-- | -> u   |   |      |   |       |22 |  26  | 23|
//! 0---+---\--1   |        0---+-8----1   |       0---+-8----1   |
//!  \  |    \  \  |         \  17      \  18       \ 17    25 \  18
//!   \ |     \  \ |         10 |        12|        10 |  21    12|
//!    \|      w  \|           \|         \|          \|         \|
//!     4----------5            4----16----5           4----16----5
//! ```
//!
//! Wedges (prisms). Vertices 0, 1, 2 at `w = −1` (at `(u, v)` = (0, 0), (1, 0), (0, 1)) and
//! 3, 4, 5 above them at `w = +1`. Edges 6: 0-1, 7: 0-2, 8: 0-3, 9: 1-2, 10: 1-4, 11: 2-5,
//! 12: 3-4, 13: 3-5, 14: 4-5.
//! ```text
//! Wedge6:                        Wedge15:
//!            w
//!            ^
//!            |
//!            3                              3
//!          ,/|`\                          ,/|`\
//!        ,/  |  `\                      12  |  13
//!      ,/    |    `\                  ,/    |    `\
//!     4------+------5                4------14-----5
//!     |      |      |                |      8      |
//!     |    ,/|`\    |                |    ,/|`\    |
//!     |  ,/  |  `\  |                |  ,/  |  `\  |
//!     |,/    |    `\|                |,/    |    `\|
//!    ,|      |      |\               10     |      11
//!  ,/ |      0      | `\             |      0      |
//! u   |    ,/ `\    |    v           |    ,/ `\    |
//!     |  ,/     `\  |                |  ,6     `7  |
//!     |,/         `\|                |,/         `\|
//!     1-------------2                1------9------2
//! ```

use crate::mesh::CellKind;

/// The largest number of nodes of any kind (`Hex27`), for stack buffers.
pub const MAX_NODES: usize = 27;

#[rustfmt::skip]
static POINT1: [[f64; 3]; 1] = [[0.0, 0.0, 0.0]];

#[rustfmt::skip]
static LINE3: [[f64; 3]; 3] = [
    [-1.0, 0.0, 0.0], [1.0, 0.0, 0.0],
    [ 0.0, 0.0, 0.0],
];

#[rustfmt::skip]
static TRI6: [[f64; 3]; 6] = [
    [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
    [0.5, 0.0, 0.0], [0.5, 0.5, 0.0], [0.0, 0.5, 0.0],
];

#[rustfmt::skip]
static QUAD9: [[f64; 3]; 9] = [
    [-1.0, -1.0, 0.0], [ 1.0, -1.0, 0.0], [ 1.0,  1.0, 0.0], [-1.0,  1.0, 0.0],
    [ 0.0, -1.0, 0.0], [ 1.0,  0.0, 0.0], [ 0.0,  1.0, 0.0], [-1.0,  0.0, 0.0],
    [ 0.0,  0.0, 0.0],
];

#[rustfmt::skip]
static TET10: [[f64; 3]; 10] = [
    [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0],
    [0.5, 0.0, 0.0], [0.5, 0.5, 0.0], [0.0, 0.5, 0.0],   // 0-1, 1-2, 2-0
    [0.0, 0.0, 0.5], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5],   // 0-3, 2-3, 1-3
];

#[rustfmt::skip]
static HEX27: [[f64; 3]; 27] = [
    // vertices
    [-1.0, -1.0, -1.0], [ 1.0, -1.0, -1.0], [ 1.0,  1.0, -1.0], [-1.0,  1.0, -1.0],
    [-1.0, -1.0,  1.0], [ 1.0, -1.0,  1.0], [ 1.0,  1.0,  1.0], [-1.0,  1.0,  1.0],
    // edges 0-1, 0-3, 0-4, 1-2, 1-5, 2-3, 2-6, 3-7, 4-5, 4-7, 5-6, 6-7
    [ 0.0, -1.0, -1.0], [-1.0,  0.0, -1.0], [-1.0, -1.0,  0.0], [ 1.0,  0.0, -1.0],
    [ 1.0, -1.0,  0.0], [ 0.0,  1.0, -1.0], [ 1.0,  1.0,  0.0], [-1.0,  1.0,  0.0],
    [ 0.0, -1.0,  1.0], [-1.0,  0.0,  1.0], [ 1.0,  0.0,  1.0], [ 0.0,  1.0,  1.0],
    // faces ζ−, η−, ξ−, ξ+, η+, ζ+
    [ 0.0,  0.0, -1.0], [ 0.0, -1.0,  0.0], [-1.0,  0.0,  0.0], [ 1.0,  0.0,  0.0],
    [ 0.0,  1.0,  0.0], [ 0.0,  0.0,  1.0],
    // centre
    [ 0.0,  0.0,  0.0],
];

#[rustfmt::skip]
static WEDGE15: [[f64; 3]; 15] = [
    [0.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 1.0, -1.0],
    [0.0, 0.0,  1.0], [1.0, 0.0,  1.0], [0.0, 1.0,  1.0],
    // edges 0-1, 0-2, 0-3, 1-2, 1-4, 2-5, 3-4, 3-5, 4-5
    [0.5, 0.0, -1.0], [0.0, 0.5, -1.0], [0.0, 0.0,  0.0], [0.5, 0.5, -1.0],
    [1.0, 0.0,  0.0], [0.0, 1.0,  0.0], [0.5, 0.0,  1.0], [0.0, 0.5,  1.0],
    [0.5, 0.5,  1.0],
];

/// Edges of the quadratic triangle (nodes 3, 4, 5).
const TRI6_EDGES: [[usize; 2]; 3] = [[0, 1], [1, 2], [2, 0]];
/// Edges of the quadratic tetrahedron (nodes 4..9).
const TET10_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [2, 3], [1, 3]];
/// Edges of the serendipity wedge (nodes 6..14).
const WEDGE15_EDGES: [[usize; 2]; 9] = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 4], [2, 5], [3, 4], [3, 5], [4, 5]];

/// Reference coordinates of the nodes of `kind`, in gmsh order (unused coordinates are 0).
///
/// Lower-order kinds share the leading rows of their quadratic relatives (`Hex8` is the first
/// 8 rows of `Hex27`, and so on).
pub fn reference_nodes(kind: CellKind) -> &'static [[f64; 3]] {
    match kind {
        CellKind::Point1 => &POINT1,
        CellKind::Line2 => &LINE3[..2],
        CellKind::Line3 => &LINE3,
        CellKind::Tri3 => &TRI6[..3],
        CellKind::Tri6 => &TRI6,
        CellKind::Quad4 => &QUAD9[..4],
        CellKind::Quad8 => &QUAD9[..8],
        CellKind::Quad9 => &QUAD9,
        CellKind::Tet4 => &TET10[..4],
        CellKind::Tet10 => &TET10,
        CellKind::Hex8 => &HEX27[..8],
        CellKind::Hex20 => &HEX27[..20],
        CellKind::Hex27 => &HEX27,
        CellKind::Wedge6 => &WEDGE15[..6],
        CellKind::Wedge15 => &WEDGE15,
    }
}

/// Shape function values `n[i] = N_i(ξ)` of `kind` at `xi`.
///
/// `n.len()` must equal `kind.n_nodes()` (a wrong length is a programmer error and panics).
///
/// ```
/// use vibrofem::{fe::shape, mesh::CellKind};
/// let mut n = [0.0; 4];
/// shape::values(CellKind::Tet4, [0.2, 0.3, 0.1], &mut n);
/// assert_eq!(n, [0.4, 0.2, 0.3, 0.1]);
/// ```
pub fn values(kind: CellKind, xi: [f64; 3], n: &mut [f64]) {
    assert_eq!(n.len(), kind.n_nodes(), "shape::values: buffer length for {kind}");
    eval(kind, xi, |i, v, _| n[i] = v);
}

/// The linear interpolation of `kind`'s higher-order nodes from its corners: for each node
/// beyond the corners of `kind.linear()`, in order, the corners whose linear shape functions
/// are not zero at its reference position, with those values (½ and ½ at a mid-edge node, ¼ at
/// each corner of a hex27 face, ⅛ at its centre). Empty for a linear kind. Exact for linear
/// fields on straight cells: the space of the mesh's linear elements inside its own.
pub fn corner_weights(kind: CellKind) -> Vec<Vec<(usize, f64)>> {
    let lin = kind.linear();
    let corners = lin.n_nodes();
    let refs = reference_nodes(kind);
    let mut buf = vec![0.0; corners];
    (corners..kind.n_nodes())
        .map(|j| {
            values(lin, refs[j], &mut buf);
            (0..corners)
                .filter(|&i| buf[i].abs() > 1e-12)
                .map(|i| (i, buf[i]))
                .collect()
        })
        .collect()
}

/// Reference gradients `dn[i] = ∂N_i/∂ξ (ξ)` of `kind` at `xi`.
///
/// `dn.len()` must equal `kind.n_nodes()`. Components beyond the cell dimension are 0.
pub fn gradients(kind: CellKind, xi: [f64; 3], dn: &mut [[f64; 3]]) {
    assert_eq!(dn.len(), kind.n_nodes(), "shape::gradients: buffer length for {kind}");
    eval(kind, xi, |i, _, g| dn[i] = g);
}

/// Values and gradients together (one pass): `n[i] = N_i(ξ)`, `dn[i] = ∂N_i/∂ξ`.
pub fn values_and_gradients(kind: CellKind, xi: [f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
    assert_eq!(n.len(), kind.n_nodes(), "shape: buffer length for {kind}");
    assert_eq!(dn.len(), kind.n_nodes(), "shape: buffer length for {kind}");
    eval(kind, xi, |i, v, g| {
        n[i] = v;
        dn[i] = g;
    });
}

/// Evaluates every shape function of `kind` at `xi` and hands `(node, N, ∂N/∂ξ)` to `out`.
///
/// Written once for values and gradients so the two can never disagree; the unused half is
/// optimised away after inlining.
#[inline(always)]
fn eval(kind: CellKind, xi: [f64; 3], mut out: impl FnMut(usize, f64, [f64; 3])) {
    match kind {
        CellKind::Point1 => out(0, 1.0, [0.0; 3]),
        CellKind::Line2 | CellKind::Quad4 | CellKind::Hex8 => tensor(kind, xi, lagrange1, out),
        CellKind::Line3 | CellKind::Quad9 | CellKind::Hex27 => tensor(kind, xi, lagrange2, out),
        CellKind::Quad8 | CellKind::Hex20 => serendipity(kind, xi, out),
        CellKind::Tri3 | CellKind::Tet4 => {
            let (l, dl) = barycentric(kind.dim(), xi);
            for i in 0..=kind.dim() {
                out(i, l[i], dl[i]);
            }
        }
        CellKind::Tri6 => simplex_p2(2, &TRI6_EDGES, xi, out),
        CellKind::Tet10 => simplex_p2(3, &TET10_EDGES, xi, out),
        CellKind::Wedge6 => wedge6(xi, out),
        CellKind::Wedge15 => wedge15(xi, out),
    }
}

/// 1D linear Lagrange function of the node at `c ∈ {−1, 1}`: value and derivative at `x`.
#[inline(always)]
fn lagrange1(c: f64, x: f64) -> (f64, f64) {
    (0.5 * (1.0 + c * x), 0.5 * c)
}

/// 1D quadratic Lagrange function of the node at `c ∈ {−1, 0, 1}` (nodes −1, 0, 1).
#[inline(always)]
fn lagrange2(c: f64, x: f64) -> (f64, f64) {
    if c == 0.0 {
        (1.0 - x * x, -2.0 * x)
    } else {
        // c = ±1: x (x + c) / 2
        (0.5 * x * (x + c), x + 0.5 * c)
    }
}

/// Tensor-product Lagrange functions: `N_i(ξ) = Π_d f(c_id, ξ_d)` over the cell's dimensions.
#[inline(always)]
fn tensor(kind: CellKind, xi: [f64; 3], f: impl Fn(f64, f64) -> (f64, f64), mut out: impl FnMut(usize, f64, [f64; 3])) {
    let dim = kind.dim();
    for (i, c) in reference_nodes(kind).iter().enumerate() {
        let mut v = [1.0; 3];
        let mut d = [0.0; 3];
        for k in 0..dim {
            (v[k], d[k]) = f(c[k], xi[k]);
        }
        out(
            i,
            v[0] * v[1] * v[2],
            [d[0] * v[1] * v[2], v[0] * d[1] * v[2], v[0] * v[1] * d[2]],
        );
    }
}

/// Serendipity quadrilateral (`D = 2`) and hexahedron (`D = 3`).
///
/// Vertex: `N = 2^−D Π_d (1 + c_d ξ_d) (Σ_d c_d ξ_d − (D − 1))`.
/// Edge midpoint with `c_k = 0`: `N = 2^−(D−1) (1 − ξ_k²) Π_{d≠k} (1 + c_d ξ_d)`.
#[inline(always)]
fn serendipity(kind: CellKind, xi: [f64; 3], mut out: impl FnMut(usize, f64, [f64; 3])) {
    let dim = kind.dim();
    let scale = if dim == 2 { 0.25 } else { 0.125 };
    for (i, c) in reference_nodes(kind).iter().enumerate() {
        // Factors f_d and derivatives; directions beyond `dim` contribute 1.
        let mut f = [1.0; 3];
        let mut df = [0.0; 3];
        let mid = (0..dim).find(|&k| c[k] == 0.0);
        for k in 0..dim {
            if Some(k) == mid {
                (f[k], df[k]) = (1.0 - xi[k] * xi[k], -2.0 * xi[k]);
            } else {
                (f[k], df[k]) = (1.0 + c[k] * xi[k], c[k]);
            }
        }
        let p = f[0] * f[1] * f[2];
        let dp = [df[0] * f[1] * f[2], f[0] * df[1] * f[2], f[0] * f[1] * df[2]];
        if mid.is_some() {
            let s = 2.0 * scale;
            out(i, s * p, [s * dp[0], s * dp[1], s * dp[2]]);
        } else {
            let mut sum = -(dim as f64 - 1.0);
            for k in 0..dim {
                sum += c[k] * xi[k];
            }
            let mut g = [0.0; 3];
            for k in 0..dim {
                g[k] = scale * (dp[k] * sum + p * c[k]);
            }
            out(i, scale * p * sum, g);
        }
    }
}

/// Barycentric coordinates `L_0 = 1 − Σ ξ_d`, `L_d = ξ_d` of a simplex of dimension `dim` and
/// their (constant) gradients.
#[inline(always)]
fn barycentric(dim: usize, xi: [f64; 3]) -> ([f64; 4], [[f64; 3]; 4]) {
    let mut l = [0.0; 4];
    let mut dl = [[0.0; 3]; 4];
    l[0] = 1.0;
    for d in 0..dim {
        l[d + 1] = xi[d];
        l[0] -= xi[d];
        dl[d + 1][d] = 1.0;
        dl[0][d] = -1.0;
    }
    (l, dl)
}

/// Quadratic Lagrange simplex: `L(2L − 1)` at the vertices, `4 L_a L_b` on the edges.
#[inline(always)]
fn simplex_p2(dim: usize, edges: &[[usize; 2]], xi: [f64; 3], mut out: impl FnMut(usize, f64, [f64; 3])) {
    let (l, dl) = barycentric(dim, xi);
    for i in 0..=dim {
        let s = 4.0 * l[i] - 1.0;
        out(i, l[i] * (2.0 * l[i] - 1.0), dl[i].map(|g| s * g));
    }
    for (e, &[a, b]) in edges.iter().enumerate() {
        let g = std::array::from_fn(|k| 4.0 * (l[b] * dl[a][k] + l[a] * dl[b][k]));
        out(dim + 1 + e, 4.0 * l[a] * l[b], g);
    }
}

/// Linear wedge: `N = L_a(u, v) (1 + c w) / 2` for the node over triangle vertex `a` at `w = c`.
#[inline(always)]
fn wedge6(xi: [f64; 3], mut out: impl FnMut(usize, f64, [f64; 3])) {
    let (l, dl) = barycentric(2, xi);
    let w = xi[2];
    for i in 0..6 {
        let (a, c) = (i % 3, if i < 3 { -1.0 } else { 1.0 });
        let h = 0.5 * (1.0 + c * w);
        out(i, l[a] * h, [dl[a][0] * h, dl[a][1] * h, 0.5 * c * l[a]]);
    }
}

/// Serendipity wedge, with `A = 1 + c w` for a node at `w = c`:
/// vertex `N = ½ L_a A (2 L_a + c w − 2)`, triangle-edge midpoint `N = 2 L_a L_b A`,
/// vertical-edge midpoint `N = L_a (1 − w²)`.
#[inline(always)]
fn wedge15(xi: [f64; 3], mut out: impl FnMut(usize, f64, [f64; 3])) {
    let (l, dl) = barycentric(2, xi);
    let w = xi[2];
    let side = |node: usize| if node < 3 { -1.0 } else { 1.0 };
    for i in 0..6 {
        let (a, c) = (i % 3, side(i));
        let big_a = 1.0 + c * w;
        let big_b = 2.0 * l[a] + c * w - 2.0;
        let du = 0.5 * big_a * (big_b + 2.0 * l[a]);
        out(
            i,
            0.5 * l[a] * big_a * big_b,
            [du * dl[a][0], du * dl[a][1], 0.5 * l[a] * c * (big_a + big_b)],
        );
    }
    for (e, &[p, q]) in WEDGE15_EDGES.iter().enumerate() {
        let (a, b) = (p % 3, q % 3);
        if a == b {
            let h = 1.0 - w * w;
            out(6 + e, l[a] * h, [dl[a][0] * h, dl[a][1] * h, -2.0 * w * l[a]]);
        } else {
            let c = side(p);
            let big_a = 1.0 + c * w;
            let g = |k: usize| 2.0 * big_a * (dl[a][k] * l[b] + l[a] * dl[b][k]);
            out(6 + e, 2.0 * l[a] * l[b] * big_a, [g(0), g(1), 2.0 * l[a] * l[b] * c]);
        }
    }
}
