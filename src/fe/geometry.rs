//! Geometry of mapped cells, shared by every formulation and by the loads: small vector
//! algebra, the Jacobian of volume cells, the metric of surface cells in 3D and of line cells.
//!
//! Every function here is written once with a fixed order of operations, and the element
//! kernels call these instead of private copies, so a change of arithmetic in one place shows
//! everywhere (and nowhere else).
//!
//! | cell | map | what is returned |
//! |---|---|---|
//! | volume (3D) | `x(ξ)`, `J_ij = ∂x_i/∂ξ_j` | [`volume_jacobian`]: `det J`, `J⁻¹`; [`physical_gradient`]: `J⁻ᵀ ∂N/∂ξ` |
//! | surface in 3D | `x(ξ, η)` | [`surface_metric`]: area vector `x_ξ × x_η`, area element `|x_ξ × x_η|` |
//! | flat surface in its plane | `p(ξ, η)` in 2D | [`plane_jacobian`]: `det J`, `J⁻¹` |
//! | line | `x(ξ)` | [`line_metric`]: tangent `x_ξ`, length element `|x_ξ|` |

/// `a · b`.
#[inline(always)]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a × b`.
#[inline(always)]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a − b`.
#[inline(always)]
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `s a`.
#[inline(always)]
pub fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Euclidean norm `|a|`.
#[inline(always)]
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// `a / |a|`, or `Err(0.0)` for a zero or non-finite vector (the error value is the
/// "determinant" the element kernels report for a degenerate element).
#[inline(always)]
pub fn normalize(a: [f64; 3]) -> Result<[f64; 3], f64> {
    let l = norm(a);
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(l > 0.0 && l.is_finite()) {
        return Err(0.0);
    }
    Ok([a[0] / l, a[1] / l, a[2] / l])
}

/// Jacobian determinant and inverse of a volume cell at one point, from node coordinates `x`
/// and reference gradients `dn` (`∂N_a/∂ξ` at the point): `J_ij = Σ_a x_a,i ∂N_a/∂ξ_j`.
/// `Err(det)` unless `det > 0` (NaN included): an inverted or degenerate cell.
///
/// ```
/// use vibrofem::fe::geometry::volume_jacobian;
/// // Tet4 with the edges 2, 3, 4 along the axes: J = diag(2, 3, 4).
/// let x = [[0.0; 3], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 4.0]];
/// let dn = [[-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
/// let (det, inv) = volume_jacobian(&x, &dn).unwrap();
/// assert_eq!(det, 24.0);
/// assert_eq!(inv[1][1], 1.0 / 3.0);
/// ```
#[inline(always)]
pub fn volume_jacobian(x: &[[f64; 3]], dn: &[[f64; 3]]) -> Result<(f64, [[f64; 3]; 3]), f64> {
    let mut j = [[0.0; 3]; 3];
    for (xa, ga) in x.iter().zip(dn) {
        for r in 0..3 {
            for c in 0..3 {
                j[r][c] += xa[r] * ga[c];
            }
        }
    }
    let c00 = j[1][1] * j[2][2] - j[1][2] * j[2][1];
    let c01 = j[1][2] * j[2][0] - j[1][0] * j[2][2];
    let c02 = j[1][0] * j[2][1] - j[1][1] * j[2][0];
    let det = j[0][0] * c00 + j[0][1] * c01 + j[0][2] * c02;
    // Written so that a NaN determinant is rejected as well.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(det > 0.0) {
        return Err(det);
    }
    let d = 1.0 / det;
    let inv = [
        [
            c00 * d,
            (j[0][2] * j[2][1] - j[0][1] * j[2][2]) * d,
            (j[0][1] * j[1][2] - j[0][2] * j[1][1]) * d,
        ],
        [
            c01 * d,
            (j[0][0] * j[2][2] - j[0][2] * j[2][0]) * d,
            (j[0][2] * j[1][0] - j[0][0] * j[1][2]) * d,
        ],
        [
            c02 * d,
            (j[0][1] * j[2][0] - j[0][0] * j[2][1]) * d,
            (j[0][0] * j[1][1] - j[0][1] * j[1][0]) * d,
        ],
    ];
    Ok((det, inv))
}

/// Physical gradient `∇N = J⁻ᵀ ∂N/∂ξ`, i.e. `∂N/∂x_i = Σ_j (J⁻¹)_ji ∂N/∂ξ_j`, with `inv` from
/// [`volume_jacobian`].
#[inline(always)]
pub fn physical_gradient(inv: &[[f64; 3]; 3], g: [f64; 3]) -> [f64; 3] {
    [
        inv[0][0] * g[0] + inv[1][0] * g[1] + inv[2][0] * g[2],
        inv[0][1] * g[0] + inv[1][1] * g[1] + inv[2][1] * g[2],
        inv[0][2] * g[0] + inv[1][2] * g[1] + inv[2][2] * g[2],
    ]
}

/// Metric of a surface cell in 3D at one point: the area vector `x_ξ × x_η` (normal to the
/// surface, by the right-hand rule on the node order) and the area element `|x_ξ × x_η|`
/// (`dA = |x_ξ × x_η| dξ dη`), from node coordinates `x` and reference gradients `dn`.
///
/// ```
/// use vibrofem::fe::geometry::surface_metric;
/// // Tri3 with legs 2 (x) and 3 (y): dA = 6 dξ dη, normal +z.
/// let x = [[0.0; 3], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]];
/// let dn = [[-1.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// assert_eq!(surface_metric(&x, &dn), ([0.0, 0.0, 6.0], 6.0));
/// ```
#[inline(always)]
pub fn surface_metric(x: &[[f64; 3]], dn: &[[f64; 3]]) -> ([f64; 3], f64) {
    let mut t1 = [0.0; 3];
    let mut t2 = [0.0; 3];
    for (xa, ga) in x.iter().zip(dn) {
        for d in 0..3 {
            t1[d] += ga[0] * xa[d];
            t2[d] += ga[1] * xa[d];
        }
    }
    let nv = cross(t1, t2);
    (nv, norm(nv))
}

/// Jacobian determinant and inverse of a flat surface cell in its own plane, from in-plane
/// node coordinates `p` and 2D reference gradients `dn` (first `nn` entries used):
/// `J = [[x_ξ, y_ξ], [x_η, y_η]]`. `Err(det)` unless `det > 0`.
#[inline(always)]
pub fn plane_jacobian(p: &[[f64; 2]], dn: &[[f64; 2]], nn: usize) -> Result<(f64, [[f64; 2]; 2]), f64> {
    let mut j = [[0.0; 2]; 2];
    for a in 0..nn {
        for r in 0..2 {
            for c in 0..2 {
                j[r][c] += dn[a][r] * p[a][c];
            }
        }
    }
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(det > 0.0) {
        return Err(det);
    }
    let inv = [[j[1][1] / det, -j[0][1] / det], [-j[1][0] / det, j[0][0] / det]];
    Ok((det, inv))
}

/// Metric of a line cell at one point: the tangent `x_ξ = Σ_a ∂N_a/∂ξ x_a` (pointing from
/// node 0 towards node 1) and the length element `|x_ξ|` (`ds = |x_ξ| dξ`), from node
/// coordinates `x` and the `ξ`-derivatives `dn` of the shape functions.
///
/// ```
/// use vibrofem::fe::geometry::line_metric;
/// let x = [[0.0; 3], [2.0, 0.0, 0.0]];
/// assert_eq!(line_metric(&x, &[-0.5, 0.5]), ([1.0, 0.0, 0.0], 1.0));
/// ```
#[inline(always)]
pub fn line_metric(x: &[[f64; 3]], dn: &[f64]) -> ([f64; 3], f64) {
    let mut t = [0.0; 3];
    for (xa, &ga) in x.iter().zip(dn) {
        for i in 0..3 {
            t[i] += ga * xa[i];
        }
    }
    (t, norm(t))
}
