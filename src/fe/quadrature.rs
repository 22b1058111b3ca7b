//! Quadrature rules on the reference cells of [`crate::fe::shape`].
//!
//! A [`Rule`] approximates `∫_ref f(ξ) dξ ≈ Σ_q w_q f(ξ_q)` on the reference cell of a kind, so
//! the weights sum to the reference measure: 2 (line), 1/2 (triangle), 4 (quadrilateral), 1/6
//! (tetrahedron), 8 (hexahedron), 1 (wedge = unit triangle × [-1, 1]).
//!
//! | cell | family | degree → rule |
//! |---|---|---|
//! | line | Gauss–Legendre | `n = degree / 2 + 1` points (exact to `2n − 1`) |
//! | quad, hex | tensor Gauss–Legendre | `n` per direction, as the line |
//! | triangle | symmetric rules | 1: centroid; 2: 3 pts; 3–4: 6 pts (Cowper/Dunavant); 5: 7 pts (Radon); 6: 12 pts (Dunavant); > 6: collapsed Gauss |
//! | tetrahedron | symmetric rules | 1: centroid; 2: 4 pts; 3–5: 14 pts (degree 5, Walkington); 6: 24 pts (Keast); > 6: collapsed Gauss |
//! | wedge | triangle × Gauss | triangle rule of `degree` × `degree / 2 + 1` Gauss points in `w` |
//!
//! The degree is the total degree on simplices and the degree per direction on tensor cells
//! (the wedge is exact for `p(u, v) q(w)` with `deg p ≤ degree` and `deg q ≤ degree`).
//! Every rule has positive weights and its points inside the cell. The tabulated parameters
//! were re-solved from the moment equations in 60-digit arithmetic and are given to 20 digits;
//! the tests check exactness on all monomials of the rule's degree.
//!
//! The "collapsed Gauss" rules (Duffy/Stroud conical product with Gauss–Legendre factors) are
//! exact for any degree; they are the fallback above the tabulated degrees.

use crate::mesh::CellKind;

/// A quadrature rule on a reference cell: points `ξ_q` (unused coordinates are 0) and weights
/// `w_q`, in matching order.
#[derive(Clone, Debug, PartialEq)]
pub struct Rule {
    /// Reference coordinates of the points.
    pub points: Vec<[f64; 3]>,
    /// Weights, summing to the measure of the reference cell.
    pub weights: Vec<f64>,
}

impl Rule {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// True for a rule without points.
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// `Σ_q w_q f(ξ_q)`.
    pub fn integrate(&self, f: impl Fn([f64; 3]) -> f64) -> f64 {
        self.points.iter().zip(&self.weights).map(|(&p, &w)| w * f(p)).sum()
    }

    fn with_capacity(n: usize) -> Rule {
        Rule {
            points: Vec::with_capacity(n),
            weights: Vec::with_capacity(n),
        }
    }

    fn push(&mut self, p: [f64; 3], w: f64) {
        self.points.push(p);
        self.weights.push(w);
    }
}

/// Gauss–Legendre nodes (ascending) and weights on [-1, 1] with `n ≥ 1` points, exact for
/// polynomials of degree `2n − 1`.
///
/// The nodes are the roots of the Legendre polynomial `P_n`, found by Newton's method from
/// Tricomi's initial guesses and then symmetrised, so they are accurate to about one ulp.
///
/// ```
/// let (x, w) = vibrofem::fe::quadrature::gauss_legendre(2);
/// assert!((x[1] - 1.0 / 3f64.sqrt()).abs() < 1e-15 && (w[0] - 1.0).abs() < 1e-15);
/// ```
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 1, "a Gauss rule needs at least one point");
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    // Roots come in ± pairs: compute the non-negative half, largest first.
    for i in 0..n.div_ceil(2) {
        let mut t = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (p, d) = legendre(n, t);
            let dt = p / d;
            t -= dt;
            if dt.abs() <= 1e-16 {
                break;
            }
        }
        // The derivative at the converged root gives the weight.
        let (_, dp) = legendre(n, t);
        let wi = 2.0 / ((1.0 - t * t) * dp * dp);
        if 2 * i + 1 == n {
            t = 0.0;
        }
        x[n - 1 - i] = t;
        x[i] = -t;
        w[n - 1 - i] = wi;
        w[i] = wi;
    }
    (x, w)
}

/// `(P_n(t), P_n'(t))` by the three-term recurrence.
fn legendre(n: usize, t: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, t);
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * t * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    let d = n as f64 * (t * p1 - p0) / (t * t - 1.0);
    (p1, d)
}

/// Number of Gauss points per direction that integrates degree `degree` exactly.
pub const fn gauss_points_for_degree(degree: usize) -> usize {
    degree / 2 + 1
}

/// `n`-point Gauss–Legendre rule on the line [-1, 1] (points along ξ).
pub fn line(n: usize) -> Rule {
    let (x, w) = gauss_legendre(n);
    let mut r = Rule::with_capacity(n);
    for (xi, wi) in x.into_iter().zip(w) {
        r.push([xi, 0.0, 0.0], wi);
    }
    r
}

/// `n × n` tensor Gauss rule on [-1, 1]², ξ running fastest.
pub fn quad(n: usize) -> Rule {
    let (x, w) = gauss_legendre(n);
    let mut r = Rule::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            r.push([x[i], x[j], 0.0], w[i] * w[j]);
        }
    }
    r
}

/// `n × n × n` tensor Gauss rule on [-1, 1]³, ξ running fastest, then η, then ζ.
pub fn hex(n: usize) -> Rule {
    let (x, w) = gauss_legendre(n);
    let mut r = Rule::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                r.push([x[i], x[j], x[k]], w[i] * w[j] * w[k]);
            }
        }
    }
    r
}

/// All distinct permutations of a barycentric tuple, as reference coordinates (the barycentric
/// coordinates `L_1..L_d`; `L_0 = 1 − Σ`), each with weight `w`.
fn push_orbit<const M: usize>(r: &mut Rule, bary: [f64; M], w: f64) {
    let mut seen: Vec<[f64; M]> = Vec::new();
    let mut idx: [usize; M] = std::array::from_fn(|i| i);
    // Heap's algorithm, iterative.
    let mut c = [0usize; M];
    let mut emit = |idx: &[usize; M], seen: &mut Vec<[f64; M]>| {
        let p: [f64; M] = std::array::from_fn(|i| bary[idx[i]]);
        if !seen.contains(&p) {
            seen.push(p);
            let mut xi = [0.0; 3];
            xi[..M - 1].copy_from_slice(&p[1..]);
            r.push(xi, w);
        }
    };
    emit(&idx, &mut seen);
    let mut i = 1;
    while i < M {
        if c[i] < i {
            if i % 2 == 0 {
                idx.swap(0, i);
            } else {
                idx.swap(c[i], i);
            }
            emit(&idx, &mut seen);
            c[i] += 1;
            i = 1;
        } else {
            c[i] = 0;
            i += 1;
        }
    }
}

/// Symmetric rule on the unit triangle `{u, v ≥ 0, u + v ≤ 1}` exact for total degree
/// `degree` (weights sum to 1/2).
///
/// Orbits are written in barycentric coordinates: `S21(a)` is the 3 permutations of
/// `(a, a, 1 − 2a)`, `S111(a, b)` the 6 permutations of `(a, b, 1 − a − b)`.
// The parameters carry 20 digits on purpose: the compiler rounds them correctly to f64.
#[allow(clippy::excessive_precision)]
#[rustfmt::skip]
pub fn triangle(degree: usize) -> Rule {
    let mut r = Rule::with_capacity(12);
    let third = 1.0 / 3.0;
    match degree {
        0 | 1 => r.push([third, third, 0.0], 0.5),
        2 => push_orbit(&mut r, [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0], 1.0 / 6.0),
        3 | 4 => {
            // Cowper / Dunavant 6 points, degree 4.
            for (a, w) in [
                (0.445_948_490_915_964_886_32, 0.111_690_794_839_005_732_85),
                (0.091_576_213_509_770_743_46, 0.054_975_871_827_660_933_819),
            ] {
                push_orbit(&mut r, [a, a, 1.0 - 2.0 * a], w);
            }
        }
        5 => {
            // Radon 7 points, degree 5: a = (6 ∓ √15)/21, w = (155 ∓ √15)/2400.
            r.push([third, third, 0.0], 9.0 / 80.0);
            for (a, w) in [
                (0.101_286_507_323_456_338_80, 0.062_969_590_272_413_576_298),
                (0.470_142_064_105_115_089_77, 0.066_197_076_394_253_090_369),
            ] {
                push_orbit(&mut r, [a, a, 1.0 - 2.0 * a], w);
            }
        }
        6 => {
            // Dunavant 12 points, degree 6.
            for (a, w) in [
                (0.063_089_014_491_502_228_34, 0.025_422_453_185_103_408_46),
                (0.249_286_745_170_910_421_29, 0.058_393_137_863_189_683_013),
            ] {
                push_orbit(&mut r, [a, a, 1.0 - 2.0 * a], w);
            }
            let (a, b) = (0.053_145_049_844_816_947_353, 0.310_352_451_033_784_405_42);
            push_orbit(&mut r, [a, b, 1.0 - a - b], 0.041_425_537_809_186_787_597);
        }
        _ => return collapsed_triangle(degree),
    }
    r
}

/// Symmetric rule on the unit tetrahedron `{u, v, w ≥ 0, u + v + w ≤ 1}` exact for total
/// degree `degree` (weights sum to 1/6).
///
/// Orbits in barycentric coordinates: `S31(a)` = permutations of `(a, a, a, 1 − 3a)`,
/// `S22(a)` of `(a, a, ½ − a, ½ − a)`, `S211(a, b)` of `(a, a, b, 1 − 2a − b)`.
#[allow(clippy::excessive_precision)]
#[rustfmt::skip]
pub fn tetrahedron(degree: usize) -> Rule {
    let mut r = Rule::with_capacity(24);
    match degree {
        0 | 1 => r.push([0.25, 0.25, 0.25], 1.0 / 6.0),
        2 => {
            // a = (5 − √5)/20.
            let a = 0.138_196_601_125_010_515_18;
            push_orbit(&mut r, [a, a, a, 1.0 - 3.0 * a], 1.0 / 24.0);
        }
        3..=5 => {
            // 14 points, degree 5, positive weights (Walkington; also in Keast's list).
            for (a, w) in [
                (0.310_885_919_263_300_609_8, 0.018_781_320_953_002_641_8),
                (0.092_735_250_310_891_226_402, 0.012_248_840_519_393_658_257),
            ] {
                push_orbit(&mut r, [a, a, a, 1.0 - 3.0 * a], w);
            }
            let a = 0.045_503_704_125_649_649_492;
            push_orbit(&mut r, [a, a, 0.5 - a, 0.5 - a], 0.007_091_003_462_846_911_073);
        }
        6 => {
            // Keast 24 points, degree 6, positive weights.
            for (a, w) in [
                (0.214_602_871_259_152_029_29, 0.006_653_791_709_694_582_016_6),
                (0.040_673_958_534_611_353_116, 0.001_679_535_175_886_773_824_7),
                (0.322_337_890_142_275_510_34, 0.009_226_196_923_942_453_682_5),
            ] {
                push_orbit(&mut r, [a, a, a, 1.0 - 3.0 * a], w);
            }
            let (a, b) = (0.063_661_001_875_017_525_299, 0.269_672_331_458_315_808_03);
            push_orbit(&mut r, [a, a, b, 1.0 - 2.0 * a - b], 9.0 / 1120.0);
        }
        _ => return collapsed_tetrahedron(degree),
    }
    r
}

/// Collapsed (Duffy) Gauss rule on the unit triangle, exact for total degree `degree`:
/// `u = s`, `v = t (1 − s)`, `dA = (1 − s) ds dt` on `[0, 1]²`.
fn collapsed_triangle(degree: usize) -> Rule {
    let n = gauss_points_for_degree(degree + 1);
    let (x, w) = gauss_legendre(n);
    let mut r = Rule::with_capacity(n * n);
    for j in 0..n {
        let t = 0.5 * (x[j] + 1.0);
        for i in 0..n {
            let s = 0.5 * (x[i] + 1.0);
            r.push([s, t * (1.0 - s), 0.0], 0.25 * w[i] * w[j] * (1.0 - s));
        }
    }
    r
}

/// Collapsed (Duffy) Gauss rule on the unit tetrahedron, exact for total degree `degree`:
/// `u = s`, `v = t (1 − s)`, `w = r (1 − s)(1 − t)`, `dV = (1 − s)² (1 − t) ds dt dr`.
fn collapsed_tetrahedron(degree: usize) -> Rule {
    let n = gauss_points_for_degree(degree + 2);
    let (x, w) = gauss_legendre(n);
    let mut rule = Rule::with_capacity(n * n * n);
    for k in 0..n {
        let r = 0.5 * (x[k] + 1.0);
        for j in 0..n {
            let t = 0.5 * (x[j] + 1.0);
            for i in 0..n {
                let s = 0.5 * (x[i] + 1.0);
                let jac = (1.0 - s) * (1.0 - s) * (1.0 - t);
                rule.push(
                    [s, t * (1.0 - s), r * (1.0 - s) * (1.0 - t)],
                    0.125 * w[i] * w[j] * w[k] * jac,
                );
            }
        }
    }
    rule
}

/// Wedge rule: the triangle rule of degree `tri_degree` in `(u, v)` times an `n_line`-point
/// Gauss rule in `w ∈ [-1, 1]` (triangle points running fastest).
pub fn wedge(tri_degree: usize, n_line: usize) -> Rule {
    let t = triangle(tri_degree);
    let (x, w) = gauss_legendre(n_line);
    let mut r = Rule::with_capacity(t.len() * n_line);
    for (&z, &wz) in x.iter().zip(&w) {
        for (p, &wt) in t.points.iter().zip(&t.weights) {
            r.push([p[0], p[1], z], wt * wz);
        }
    }
    r
}

/// Fixed small rules as constants `(ξ, w)` / `(ξ, η, w)`, for the kernels that integrate
/// without building a [`Rule`] (shells and beams). Their literal values and point order define
/// those kernels' results to the last bit; the tests check them against [`gauss_legendre`],
/// [`quad`] and [`triangle`].
///
/// 2-point Gauss–Legendre on [-1, 1].
pub const GAUSS2: [(f64, f64); 2] = [(-0.577_350_269_189_625_8, 1.0), (0.577_350_269_189_625_8, 1.0)];
/// 3-point Gauss–Legendre on [-1, 1].
pub const GAUSS3: [(f64, f64); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];
/// 4-point Gauss–Legendre on [-1, 1].
pub const GAUSS4: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];
/// 2 × 2 Gauss on [-1, 1]², ξ running fastest (the points and order of [`quad`]`(2)`).
pub const QUAD_2X2: [(f64, f64, f64); 4] = [
    (-GAUSS2[1].0, -GAUSS2[1].0, 1.0),
    (GAUSS2[1].0, -GAUSS2[1].0, 1.0),
    (-GAUSS2[1].0, GAUSS2[1].0, 1.0),
    (GAUSS2[1].0, GAUSS2[1].0, 1.0),
];
/// The 3-point degree-2 rule on the unit triangle (weights summing to 1/2): the points of
/// [`triangle`]`(2)`, ordered from the one near vertex 0.
pub const TRIANGLE_3: [(f64, f64, f64); 3] = [
    (1.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0),
    (2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0),
    (1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0),
];

/// The rule of a cell kind exact for degree `degree`: total degree on triangles and
/// tetrahedra, degree per direction on lines, quadrilaterals and hexahedra, and both (triangle
/// total degree, `w` degree) on wedges. A point cell gets the single point with weight 1.
///
/// ```
/// use vibrofem::{fe::quadrature::for_cell, mesh::CellKind};
/// assert_eq!(for_cell(CellKind::Hex20, 4).len(), 27);
/// assert_eq!(for_cell(CellKind::Tet10, 2).len(), 4);
/// let r = for_cell(CellKind::Tet4, 4);
/// let v: f64 = r.integrate(|x| x[0] * x[0] * x[1] * x[2]); // 2!·1!·1!/7! = 1/2520
/// assert!((v - 1.0 / 2520.0).abs() < 1e-17);
/// ```
pub fn for_cell(kind: CellKind, degree: usize) -> Rule {
    let n = gauss_points_for_degree(degree);
    match kind {
        CellKind::Point1 => Rule {
            points: vec![[0.0; 3]],
            weights: vec![1.0],
        },
        CellKind::Line2 | CellKind::Line3 => line(n),
        CellKind::Tri3 | CellKind::Tri6 => triangle(degree),
        CellKind::Quad4 | CellKind::Quad8 | CellKind::Quad9 => quad(n),
        CellKind::Tet4 | CellKind::Tet10 => tetrahedron(degree),
        CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => hex(n),
        CellKind::Wedge6 | CellKind::Wedge15 => wedge(degree, n),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_matches_closed_forms() {
        let (x, w) = gauss_legendre(3);
        let a = (0.6f64).sqrt();
        assert_eq!(x[1], 0.0);
        assert!((x[2] - a).abs() < 1e-16 && (x[0] + a).abs() < 1e-16);
        assert!((w[1] - 8.0 / 9.0).abs() < 1e-15 && (w[0] - 5.0 / 9.0).abs() < 1e-15);
        for n in 1..=12 {
            let (_, w) = gauss_legendre(n);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-14, "n = {n}");
        }
    }

    #[test]
    fn constant_rules_match_the_computed_ones() {
        for (n, c) in [(2, &GAUSS2[..]), (3, &GAUSS3[..]), (4, &GAUSS4[..])] {
            let (x, w) = gauss_legendre(n);
            for i in 0..n {
                assert!(
                    (x[i] - c[i].0).abs() < 1e-15 && (w[i] - c[i].1).abs() < 1e-15,
                    "n = {n}"
                );
            }
        }
        let q = quad(2);
        for (i, &(u, v, w)) in QUAD_2X2.iter().enumerate() {
            let p = q.points[i];
            assert!((p[0] - u).abs() < 1e-15 && (p[1] - v).abs() < 1e-15 && (q.weights[i] - w).abs() < 1e-15);
        }
        let t = triangle(2);
        for &(u, v, w) in &TRIANGLE_3 {
            let found = t
                .points
                .iter()
                .zip(&t.weights)
                .any(|(p, &wt)| (p[0] - u).abs() < 1e-15 && (p[1] - v).abs() < 1e-15 && (wt - w).abs() < 1e-15);
            assert!(found, "({u}, {v}) is not a point of triangle(2)");
        }
    }

    #[test]
    fn orbit_sizes() {
        assert_eq!(triangle(2).len(), 3);
        assert_eq!(triangle(4).len(), 6);
        assert_eq!(triangle(5).len(), 7);
        assert_eq!(triangle(6).len(), 12);
        assert_eq!(tetrahedron(2).len(), 4);
        assert_eq!(tetrahedron(4).len(), 14);
        assert_eq!(tetrahedron(6).len(), 24);
        assert_eq!(wedge(4, 3).len(), 18);
    }
}
