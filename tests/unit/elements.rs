//! Property sweeps over every cell kind: shape functions, quadrature, material, and the solid
//! element kernels (stiffness, mass, lumping, volume, stress); and the element sweep over every
//! formulation through [`ElementSet`] ([`element_sweep`]): one line per element there is all
//! a new formulation needs to be checked for symmetry, rigid-body modes and mass.
//!
//! Geometry is a reference cell under a fixed affine map, optionally with a seeded random
//! perturbation of every node ("distorted"), so no test depends on axis-aligned cells.
//! Tolerances are relative and a few orders of magnitude above rounding (f64, ≤ 81 dofs).

#![allow(clippy::needless_range_loop)]

use nalgebra::{DMatrix, SymmetricEigen};
use vibrofem::Error;
use vibrofem::element::{ElementSet, MassLumping, lumping, solid};
use vibrofem::fe::{quadrature, shape};
use vibrofem::material::Material;
use vibrofem::mesh::CellKind;
use vibrofem::model::{BeamSet, DiscreteSet, ShellSet, SolidSet};
use vibrofem::section::{BeamSection, ShellSection};

// ---------------------------------------------------------------------------------------------
// helpers

/// SplitMix64: small, seeded, good enough for test geometry.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn is_simplex(kind: CellKind) -> bool {
    matches!(kind, CellKind::Tri3 | CellKind::Tri6 | CellKind::Tet4 | CellKind::Tet10)
}

fn is_wedge(kind: CellKind) -> bool {
    matches!(kind, CellKind::Wedge6 | CellKind::Wedge15)
}

/// A random point strictly inside the reference cell of `kind` (unused coordinates 0).
fn random_xi(kind: CellKind, rng: &mut Rng) -> [f64; 3] {
    let dim = kind.dim();
    let mut xi = [0.0; 3];
    if is_simplex(kind) {
        loop {
            for c in xi.iter_mut().take(dim) {
                *c = rng.uniform(0.02, 0.98);
            }
            if xi.iter().sum::<f64>() < 0.98 {
                return xi;
            }
        }
    }
    if is_wedge(kind) {
        loop {
            xi[0] = rng.uniform(0.02, 0.98);
            xi[1] = rng.uniform(0.02, 0.98);
            if xi[0] + xi[1] < 0.98 {
                break;
            }
        }
        xi[2] = rng.uniform(-0.95, 0.95);
        return xi;
    }
    for c in xi.iter_mut().take(dim) {
        *c = rng.uniform(-0.95, 0.95);
    }
    xi
}

/// A well-conditioned affine map with positive determinant (≈ 1.0875).
const A: [[f64; 3]; 3] = [[1.2, 0.3, -0.1], [0.1, 0.9, 0.2], [-0.2, 0.15, 1.1]];
const T: [f64; 3] = [0.3, -0.7, 2.0];

fn det3(a: &[[f64; 3]; 3]) -> f64 {
    a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
}

fn affine_point(p: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| T[i] + (0..3).map(|j| A[i][j] * p[j]).sum::<f64>())
}

/// The reference nodes of `kind` under the affine map (A, T).
fn affine(kind: CellKind) -> Vec<[f64; 3]> {
    shape::reference_nodes(kind).iter().map(|&p| affine_point(p)).collect()
}

/// The reference nodes, each moved randomly by up to `amp` per coordinate (scaled to the cell
/// size: simplices and wedge triangles are half as large), then mapped by (A, T).
fn distorted(kind: CellKind, rng: &mut Rng, amp: f64) -> Vec<[f64; 3]> {
    let scale = if is_simplex(kind) { 0.5 } else { 1.0 };
    shape::reference_nodes(kind)
        .iter()
        .map(|&p| {
            let mut q = p;
            for c in q.iter_mut() {
                *c += scale * amp * rng.uniform(-1.0, 1.0);
            }
            affine_point(q)
        })
        .collect()
}

fn mat() -> Material {
    Material::steel()
}

fn stiffness(kind: CellKind, x: &[[f64; 3]]) -> Vec<f64> {
    let n = 3 * kind.n_nodes();
    let mut ke = vec![f64::NAN; n * n];
    solid::stiffness(kind, x, &mat(), &mut ke).unwrap();
    ke
}

fn mass(kind: CellKind, x: &[[f64; 3]], lump: MassLumping) -> Vec<f64> {
    let n = 3 * kind.n_nodes();
    let mut me = vec![f64::NAN; n * n];
    solid::mass(kind, x, mat().density, lump, &mut me).unwrap();
    me
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

fn matvec(k: &[f64], u: &[f64]) -> Vec<f64> {
    let n = u.len();
    (0..n).map(|r| (0..n).map(|c| k[r * n + c] * u[c]).sum()).collect()
}

/// Node-major displacement of the linear field `u(x) = u0 + G x` at the nodes.
fn linear_field(x: &[[f64; 3]], u0: [f64; 3], g: [[f64; 3]; 3]) -> Vec<f64> {
    let mut u = Vec::with_capacity(3 * x.len());
    for p in x {
        for i in 0..3 {
            u.push(u0[i] + (0..3).map(|j| g[i][j] * p[j]).sum::<f64>());
        }
    }
    u
}

/// Voigt strain (xx, yy, zz, yz, xz, xy; engineering shears) of a displacement gradient.
fn voigt_strain(g: [[f64; 3]; 3]) -> [f64; 6] {
    [
        g[0][0],
        g[1][1],
        g[2][2],
        g[1][2] + g[2][1],
        g[0][2] + g[2][0],
        g[0][1] + g[1][0],
    ]
}

fn random_gradient(rng: &mut Rng, s: f64) -> [[f64; 3]; 3] {
    std::array::from_fn(|_| std::array::from_fn(|_| s * rng.uniform(-1.0, 1.0)))
}

const SEED: u64 = 0x5EED_F00D;

// ---------------------------------------------------------------------------------------------
// shape functions

#[test]
fn shape_kronecker_delta_at_reference_nodes() {
    for kind in CellKind::ALL {
        let nodes = shape::reference_nodes(kind);
        let nn = kind.n_nodes();
        assert_eq!(nodes.len(), nn, "{kind}");
        let mut n = vec![0.0; nn];
        for (j, &p) in nodes.iter().enumerate() {
            shape::values(kind, p, &mut n);
            for (i, &v) in n.iter().enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-14, "{kind}: N_{i} at node {j} = {v}");
            }
        }
    }
}

#[test]
fn shape_reference_nodes_follow_gmsh_edges() {
    // Mid-edge nodes sit at the midpoint of the gmsh edge they belong to.
    let check = |kind: CellKind, first: usize, edges: &[[usize; 2]]| {
        let p = shape::reference_nodes(kind);
        for (e, &[a, b]) in edges.iter().enumerate() {
            for k in 0..3 {
                assert_eq!(p[first + e][k], 0.5 * (p[a][k] + p[b][k]), "{kind} node {}", first + e);
            }
        }
    };
    check(CellKind::Line3, 2, &[[0, 1]]);
    check(CellKind::Tri6, 3, &[[0, 1], [1, 2], [2, 0]]);
    check(CellKind::Quad9, 4, &[[0, 1], [1, 2], [2, 3], [3, 0], [0, 2]]);
    check(CellKind::Tet10, 4, &[[0, 1], [1, 2], [2, 0], [0, 3], [2, 3], [1, 3]]);
    #[rustfmt::skip]
    let hex_edges = [[0, 1], [0, 3], [0, 4], [1, 2], [1, 5], [2, 3], [2, 6], [3, 7], [4, 5], [4, 7], [5, 6], [6, 7]];
    check(CellKind::Hex20, 8, &hex_edges);
    // Hex27 faces 0-3-2-1, 0-1-5-4, 0-4-7-3, 1-2-6-5, 2-3-7-6, 4-5-6-7 (diagonals) and centre.
    check(
        CellKind::Hex27,
        20,
        &[[0, 2], [0, 5], [0, 7], [1, 6], [2, 7], [4, 6], [0, 6]],
    );
    #[rustfmt::skip]
    let wedge_edges = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 4], [2, 5], [3, 4], [3, 5], [4, 5]];
    check(CellKind::Wedge15, 6, &wedge_edges);
    // Vertex coordinates of the 3D cells.
    assert_eq!(shape::reference_nodes(CellKind::Hex8)[6], [1.0, 1.0, 1.0]);
    assert_eq!(shape::reference_nodes(CellKind::Hex8)[3], [-1.0, 1.0, -1.0]);
    assert_eq!(shape::reference_nodes(CellKind::Wedge6)[5], [0.0, 1.0, 1.0]);
    assert_eq!(shape::reference_nodes(CellKind::Tet4)[3], [0.0, 0.0, 1.0]);
}

#[test]
fn shape_partition_of_unity() {
    let mut rng = Rng(SEED);
    for kind in CellKind::ALL {
        let nn = kind.n_nodes();
        let (mut n, mut dn) = (vec![0.0; nn], vec![[0.0; 3]; nn]);
        for _ in 0..25 {
            let xi = random_xi(kind, &mut rng);
            shape::values_and_gradients(kind, xi, &mut n, &mut dn);
            let s: f64 = n.iter().sum();
            assert!((s - 1.0).abs() < 1e-14, "{kind} at {xi:?}: ΣN = {s}");
            for k in 0..3 {
                let g: f64 = dn.iter().map(|d| d[k]).sum();
                assert!(g.abs() < 1e-13, "{kind} at {xi:?}: Σ∂N/∂ξ{k} = {g}");
            }
        }
    }
}

#[test]
fn shape_gradients_match_central_differences() {
    let mut rng = Rng(SEED + 1);
    let h = 1e-6;
    for kind in CellKind::ALL {
        let nn = kind.n_nodes();
        let (mut np, mut nm, mut dn) = (vec![0.0; nn], vec![0.0; nn], vec![[0.0; 3]; nn]);
        for _ in 0..10 {
            let xi = random_xi(kind, &mut rng);
            shape::gradients(kind, xi, &mut dn);
            for k in 0..3 {
                let (mut xp, mut xm) = (xi, xi);
                xp[k] += h;
                xm[k] -= h;
                shape::values(kind, xp, &mut np);
                shape::values(kind, xm, &mut nm);
                for i in 0..nn {
                    let fd = (np[i] - nm[i]) / (2.0 * h);
                    assert!(
                        (fd - dn[i][k]).abs() < 1e-8,
                        "{kind} ∂N_{i}/∂ξ{k} at {xi:?}: analytic {} vs FD {fd}",
                        dn[i][k]
                    );
                }
            }
        }
    }
}

#[test]
fn shape_reproduces_linear_fields() {
    // Σ N_i x_i = A ξ + t and Σ x_i ⊗ ∂N_i/∂ξ = A (restricted to the cell's dimensions).
    let mut rng = Rng(SEED + 2);
    for kind in CellKind::ALL {
        let x = affine(kind);
        let nn = kind.n_nodes();
        let (mut n, mut dn) = (vec![0.0; nn], vec![[0.0; 3]; nn]);
        for _ in 0..10 {
            let xi = random_xi(kind, &mut rng);
            shape::values_and_gradients(kind, xi, &mut n, &mut dn);
            let want = affine_point(xi);
            for r in 0..3 {
                let got: f64 = (0..nn).map(|a| n[a] * x[a][r]).sum();
                assert!((got - want[r]).abs() < 1e-13, "{kind}: x_{r} {got} vs {}", want[r]);
                for c in 0..kind.dim() {
                    let j: f64 = (0..nn).map(|a| dn[a][c] * x[a][r]).sum();
                    assert!((j - A[r][c]).abs() < 1e-13, "{kind}: J_{r}{c} {j} vs {}", A[r][c]);
                }
            }
        }
    }
}

#[test]
fn shape_quadratic_kinds_reproduce_quadratic_fields() {
    // Every order-2 kind contains the complete quadratic polynomials of its reference cell.
    let f = |p: [f64; 3]| {
        0.3 + p[0] - 0.5 * p[1] + 0.25 * p[2] + 0.7 * p[0] * p[0] - 0.2 * p[1] * p[1]
            + 0.9 * p[2] * p[2]
            + 0.4 * p[0] * p[1]
            - 0.6 * p[1] * p[2]
            + 0.8 * p[0] * p[2]
    };
    let mut rng = Rng(SEED + 3);
    for kind in CellKind::ALL.into_iter().filter(|k| k.order() == 2) {
        let nodes = shape::reference_nodes(kind);
        let mut n = vec![0.0; kind.n_nodes()];
        for _ in 0..10 {
            let xi = random_xi(kind, &mut rng);
            shape::values(kind, xi, &mut n);
            let got: f64 = nodes.iter().zip(&n).map(|(&p, &v)| v * f(p)).sum();
            assert!((got - f(xi)).abs() < 1e-13, "{kind} at {xi:?}: {got} vs {}", f(xi));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// quadrature

fn factorial(n: u32) -> f64 {
    (1..=n).map(f64::from).product()
}

/// ∫ ξ^i over [-1, 1].
fn line_moment(i: u32) -> f64 {
    if i % 2 == 1 { 0.0 } else { 2.0 / (i as f64 + 1.0) }
}

fn check_rule(rule: &quadrature::Rule, exact: impl Fn([u32; 3]) -> Option<f64>, what: &str) {
    assert_eq!(rule.points.len(), rule.weights.len());
    assert!(rule.weights.iter().all(|&w| w > 0.0), "{what}: non-positive weight");
    for i in 0..=12u32 {
        for j in 0..=12u32 {
            for k in 0..=12u32 {
                let Some(want) = exact([i, j, k]) else {
                    continue;
                };
                let got = rule.integrate(|p| p[0].powi(i as i32) * p[1].powi(j as i32) * p[2].powi(k as i32));
                let scale = want.abs().max(1e-3 * rule.weights.iter().sum::<f64>());
                assert!(
                    (got - want).abs() <= 1e-13 * scale,
                    "{what}: ∫ξ^{i}η^{j}ζ^{k} = {got:e}, exact {want:e}"
                );
            }
        }
    }
}

#[test]
fn quadrature_gauss_and_tensor_rules_are_exact() {
    for n in 1..=6usize {
        let d = 2 * n as u32 - 1;
        let line = quadrature::line(n);
        check_rule(
            &line,
            |[i, j, k]| (i <= d && j == 0 && k == 0).then(|| line_moment(i)),
            &format!("gauss {n}"),
        );
        let quad = quadrature::quad(n);
        let ex = |[i, j, k]: [u32; 3]| (i <= d && j <= d && k == 0).then(|| line_moment(i) * line_moment(j));
        check_rule(&quad, ex, &format!("quad {n}"));
        let hex = quadrature::hex(n);
        let ex = |[i, j, k]: [u32; 3]| {
            (i <= d && j <= d && k <= d).then(|| line_moment(i) * line_moment(j) * line_moment(k))
        };
        check_rule(&hex, ex, &format!("hex {n}"));
    }
}

fn tri_moment(i: u32, j: u32) -> f64 {
    factorial(i) * factorial(j) / factorial(i + j + 2)
}

#[test]
fn quadrature_triangle_rules_are_exact() {
    for d in 0..=10u32 {
        let rule = quadrature::triangle(d as usize);
        let inside = rule
            .points
            .iter()
            .all(|p| p[0] > 0.0 && p[1] > 0.0 && p[0] + p[1] < 1.0 && p[2] == 0.0);
        assert!(inside, "triangle degree {d}: point outside");
        check_rule(
            &rule,
            |[i, j, k]| (i + j <= d && k == 0).then(|| tri_moment(i, j)),
            &format!("triangle degree {d}"),
        );
    }
}

#[test]
fn quadrature_tetrahedron_rules_are_exact() {
    for d in 0..=9u32 {
        let rule = quadrature::tetrahedron(d as usize);
        let inside = rule
            .points
            .iter()
            .all(|p| p.iter().all(|&c| c > 0.0) && p.iter().sum::<f64>() < 1.0);
        assert!(inside, "tetrahedron degree {d}: point outside");
        let ex = |[i, j, k]: [u32; 3]| {
            (i + j + k <= d).then(|| factorial(i) * factorial(j) * factorial(k) / factorial(i + j + k + 3))
        };
        check_rule(&rule, ex, &format!("tetrahedron degree {d}"));
    }
}

#[test]
fn quadrature_for_cell_is_exact_for_each_kind() {
    for kind in CellKind::ALL {
        for d in 0..=8u32 {
            let rule = quadrature::for_cell(kind, d as usize);
            let ex = |[i, j, k]: [u32; 3]| -> Option<f64> {
                match kind {
                    CellKind::Point1 => (i + j + k == 0).then_some(1.0),
                    CellKind::Line2 | CellKind::Line3 => (i <= d && j + k == 0).then(|| line_moment(i)),
                    CellKind::Tri3 | CellKind::Tri6 => (i + j <= d && k == 0).then(|| tri_moment(i, j)),
                    CellKind::Quad4 | CellKind::Quad8 | CellKind::Quad9 => {
                        (i <= d && j <= d && k == 0).then(|| line_moment(i) * line_moment(j))
                    }
                    CellKind::Tet4 | CellKind::Tet10 => {
                        (i + j + k <= d).then(|| factorial(i) * factorial(j) * factorial(k) / factorial(i + j + k + 3))
                    }
                    CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => {
                        (i <= d && j <= d && k <= d).then(|| line_moment(i) * line_moment(j) * line_moment(k))
                    }
                    CellKind::Wedge6 | CellKind::Wedge15 => {
                        (i + j <= d && k <= d).then(|| tri_moment(i, j) * line_moment(k))
                    }
                }
            };
            check_rule(&rule, ex, &format!("{kind} degree {d}"));
        }
    }
}

#[test]
fn kernel_rules_have_the_documented_sizes() {
    let sizes = |kind| {
        (
            quadrature::for_cell(kind, solid::stiffness_degree(kind)).len(),
            quadrature::for_cell(kind, solid::mass_degree(kind)).len(),
        )
    };
    assert_eq!(sizes(CellKind::Tet4), (1, 4));
    assert_eq!(sizes(CellKind::Tet10), (4, 14));
    assert_eq!(sizes(CellKind::Hex8), (8, 8));
    assert_eq!(sizes(CellKind::Hex20), (27, 27));
    assert_eq!(sizes(CellKind::Hex27), (27, 27));
    assert_eq!(sizes(CellKind::Wedge6), (6, 6));
    assert_eq!(sizes(CellKind::Wedge15), (18, 18));
}

// ---------------------------------------------------------------------------------------------
// material

#[test]
fn material_d_is_symmetric_positive_definite() {
    for nu in [-0.9, -0.3, 0.0, 0.3, 0.45, 0.499] {
        let m = Material {
            young: 7e10,
            poisson: nu,
            density: 2700.0,
        };
        m.validate("test").unwrap();
        let d = m.d_matrix();
        let dm = DMatrix::from_fn(6, 6, |i, j| d[i][j]);
        assert_eq!(dm, dm.transpose(), "ν = {nu}");
        let mut ev: Vec<f64> = SymmetricEigen::new(dm).eigenvalues.iter().copied().collect();
        ev.sort_by(f64::total_cmp);
        // Eigenvalues: μ (×3 shear), 2μ (×2 deviatoric), 3K (volumetric).
        let (g, k) = (m.shear_modulus(), m.bulk_modulus());
        let mut want = vec![g, g, g, 2.0 * g, 2.0 * g, 3.0 * k];
        want.sort_by(f64::total_cmp);
        for (e, w) in ev.iter().zip(&want) {
            assert!(*e > 0.0 && (e - w).abs() < 1e-10 * w, "ν = {nu}: eigenvalue {e} vs {w}");
        }
    }
}

#[test]
fn material_validation_and_parsing() {
    assert_eq!(
        Material::parse("steel").unwrap(),
        Material {
            young: 2.1e11,
            poisson: 0.3,
            density: 7850.0
        }
    );
    assert_eq!(Material::parse("2.1e11,0.3,7850").unwrap(), Material::steel());
    let (lam, mu) = Material::steel().lame();
    assert!((lam - 2.1e11 * 0.3 / (1.3 * 0.4)).abs() < 1e-3 && (mu - 2.1e11 / 2.6).abs() < 1e-3);
    for (bad, needle) in [
        (
            Material {
                young: 0.0,
                ..Material::steel()
            },
            "Young",
        ),
        (
            Material {
                young: f64::INFINITY,
                ..Material::steel()
            },
            "Young",
        ),
        (
            Material {
                poisson: 0.5,
                ..Material::steel()
            },
            "(-1, 0.5)",
        ),
        (
            Material {
                poisson: -1.0,
                ..Material::steel()
            },
            "(-1, 0.5)",
        ),
        (
            Material {
                poisson: f64::NAN,
                ..Material::steel()
            },
            "(-1, 0.5)",
        ),
        (
            Material {
                density: -1.0,
                ..Material::steel()
            },
            "density",
        ),
    ] {
        let err = bad.validate("body").unwrap_err();
        assert_eq!(err.exit_code(), 1);
        let Error::InvalidMaterial { ref name, ref msg } = err else {
            panic!("wrong variant {err:?}")
        };
        assert_eq!(name, "body");
        assert!(msg.contains(needle), "{msg}");
    }
    for bad in ["", "iron", "1,2", "1,0.3,x", "1,0.3,1,1", "1,0.7,1"] {
        assert!(
            matches!(Material::parse(bad), Err(Error::InvalidMaterial { .. })),
            "{bad}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// solid stiffness

#[test]
fn stiffness_is_symmetric() {
    let mut rng = Rng(SEED + 10);
    for kind in CellKind::SOLIDS {
        let x = distorted(kind, &mut rng, 0.1);
        let ke = stiffness(kind, &x);
        let n = 3 * kind.n_nodes();
        let scale = max_abs(&ke);
        assert!(ke.iter().all(|v| v.is_finite()), "{kind}: ke not fully written");
        for r in 0..n {
            for c in 0..r {
                let (a, b) = (ke[r * n + c], ke[c * n + r]);
                assert!((a - b).abs() <= 1e-14 * scale, "{kind}: K[{r},{c}] = {a} vs {b}");
            }
            assert!(ke[r * n + r] > 0.0, "{kind}: K[{r},{r}] not positive");
        }
    }
}

#[test]
fn stiffness_has_exactly_six_zero_eigenvalues() {
    let mut rng = Rng(SEED + 11);
    for kind in CellKind::SOLIDS {
        for amp in [0.0, 0.1] {
            let x = distorted(kind, &mut rng, amp);
            let ke = stiffness(kind, &x);
            let n = 3 * kind.n_nodes();
            let k = DMatrix::from_row_slice(n, n, &ke);
            let mut ev: Vec<f64> = SymmetricEigen::new(k).eigenvalues.iter().copied().collect();
            ev.sort_by(f64::total_cmp);
            let top = ev[n - 1];
            let zeros = ev.iter().filter(|e| e.abs() <= 1e-10 * top).count();
            assert_eq!(
                zeros,
                6,
                "{kind} (amp {amp}): eigenvalues / max = {:?}",
                ev.iter().map(|e| e / top).collect::<Vec<_>>()
            );
            assert!(
                ev[6] > 1e-6 * top,
                "{kind}: smallest elastic eigenvalue {:e} too small",
                ev[6] / top
            );
        }
    }
}

#[test]
fn stiffness_annihilates_rigid_body_motions() {
    let mut rng = Rng(SEED + 12);
    for kind in CellKind::SOLIDS {
        let x = distorted(kind, &mut rng, 0.1);
        let ke = stiffness(kind, &x);
        let scale = max_abs(&ke);
        let mut motions = Vec::new();
        for i in 0..3 {
            let mut t = [0.0; 3];
            t[i] = 1.0;
            motions.push(linear_field(&x, t, [[0.0; 3]; 3]));
        }
        // Infinitesimal rotations: skew-symmetric gradients.
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            let mut w = [[0.0; 3]; 3];
            w[i][j] = 1.0;
            w[j][i] = -1.0;
            motions.push(linear_field(&x, [0.0; 3], w));
        }
        for u in &motions {
            let f = matvec(&ke, u);
            let r = max_abs(&f) / (scale * max_abs(u));
            assert!(r < 1e-12, "{kind}: |K u_rigid| / |K||u| = {r:e}");
        }
    }
}

#[test]
fn constant_strain_patch_gives_d_epsilon_everywhere() {
    let mut rng = Rng(SEED + 13);
    let m = mat();
    let d = m.d_matrix();
    for kind in CellKind::SOLIDS {
        let x = distorted(kind, &mut rng, 0.1);
        // Any linear field (rigid part included) has constant strain ε(G) = sym(G).
        let g = random_gradient(&mut rng, 1e-3);
        let u = linear_field(&x, [1e-3, -2e-3, 5e-4], g);
        let eps = voigt_strain(g);
        let want: [f64; 6] = std::array::from_fn(|i| (0..6).map(|j| d[i][j] * eps[j]).sum());
        let smax = max_abs(&want);
        for _ in 0..8 {
            let xi = random_xi(kind, &mut rng);
            let e = solid::strain_at(kind, &x, &u, xi).unwrap();
            let s = solid::stress_at(kind, &x, &m, &u, xi).unwrap();
            for c in 0..6 {
                assert!(
                    (e[c] - eps[c]).abs() < 1e-12 * 1e-3,
                    "{kind}: ε_{c} {} vs {}",
                    e[c],
                    eps[c]
                );
                assert!(
                    (s[c] - want[c]).abs() < 1e-11 * smax,
                    "{kind}: σ_{c} {} vs {}",
                    s[c],
                    want[c]
                );
            }
        }
        // And the element is in equilibrium under it: uᵀ K u = ∫ εᵀ D ε dV on affine cells.
        let xa = affine(kind);
        let ua = linear_field(&xa, [0.0; 3], g);
        let ke = stiffness(kind, &xa);
        let energy: f64 = ua.iter().zip(matvec(&ke, &ua)).map(|(a, b)| a * b).sum();
        let v = solid::volume(kind, &xa).unwrap();
        let want_e = v * (0..6).map(|i| eps[i] * want[i]).sum::<f64>();
        assert!(
            (energy - want_e).abs() < 1e-11 * want_e,
            "{kind}: uᵀKu = {energy:e} vs V εᵀDε = {want_e:e}"
        );
    }
}

/// Reference stiffness: dense `B` (6 × 3n) and `D`, `K = Σ_q w det Bᵀ D B` with the given rule.
fn reference_stiffness(kind: CellKind, x: &[[f64; 3]], m: &Material, rule: &quadrature::Rule) -> Vec<f64> {
    let nn = kind.n_nodes();
    let nd = 3 * nn;
    let d = m.d_matrix();
    let dm = DMatrix::from_fn(6, 6, |i, j| d[i][j]);
    let mut k = DMatrix::<f64>::zeros(nd, nd);
    let mut dn = vec![[0.0; 3]; nn];
    for (p, &w) in rule.points.iter().zip(&rule.weights) {
        shape::gradients(kind, *p, &mut dn);
        let j = DMatrix::from_fn(3, 3, |r, c| (0..nn).map(|a| x[a][r] * dn[a][c]).sum::<f64>());
        let det = j.determinant();
        let jinv_t = j.try_inverse().unwrap().transpose();
        let mut b = DMatrix::<f64>::zeros(6, nd);
        for a in 0..nn {
            let g = &jinv_t * nalgebra::Vector3::new(dn[a][0], dn[a][1], dn[a][2]);
            let c = 3 * a;
            b[(0, c)] = g[0];
            b[(1, c + 1)] = g[1];
            b[(2, c + 2)] = g[2];
            b[(3, c + 1)] = g[2];
            b[(3, c + 2)] = g[1];
            b[(4, c)] = g[2];
            b[(4, c + 2)] = g[0];
            b[(5, c)] = g[1];
            b[(5, c + 1)] = g[0];
        }
        k += b.transpose() * &dm * b * (w * det);
    }
    k.transpose().iter().copied().collect() // row-major
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    let den: f64 = b.iter().map(|y| y * y).sum();
    (num / den).sqrt()
}

#[test]
fn stiffness_matches_dense_btdb() {
    let mut rng = Rng(SEED + 14);
    let m = Material {
        young: 7e10,
        poisson: 0.33,
        density: 2700.0,
    };
    for kind in CellKind::SOLIDS {
        // Distorted: same rule, so this checks the block formula against Bᵀ D B. Randomly moved
        // mid-side nodes make a quadratic cell curved, which takes the curved-cell rule.
        let x = distorted(kind, &mut rng, 0.1);
        let mut ke = vec![0.0; 9 * kind.n_nodes() * kind.n_nodes()];
        solid::stiffness(kind, &x, &m, &mut ke).unwrap();
        let degree = match solid::integration(kind, &x) {
            solid::Integration::Straight => solid::stiffness_degree(kind),
            solid::Integration::Curved => solid::curved_stiffness_degree(kind),
        };
        let rule = quadrature::for_cell(kind, degree);
        let r = rel_diff(&ke, &reference_stiffness(kind, &x, &m, &rule));
        assert!(r < 1e-13, "{kind} distorted: relative difference {r:e}");
        // Affine: a much higher rule gives the same matrix, so the kernel's rule is exact.
        let x = affine(kind);
        solid::stiffness(kind, &x, &m, &mut ke).unwrap();
        let r = rel_diff(&ke, &reference_stiffness(kind, &x, &m, &quadrature::for_cell(kind, 10)));
        assert!(r < 1e-13, "{kind} affine vs degree 10: relative difference {r:e}");
    }
}

// ---------------------------------------------------------------------------------------------
// solid mass and volume

#[test]
fn consistent_mass_sums_to_rho_v_per_direction() {
    let mut rng = Rng(SEED + 20);
    let rho = mat().density;
    for kind in CellKind::SOLIDS {
        let x = distorted(kind, &mut rng, 0.1);
        let me = mass(kind, &x, MassLumping::Consistent);
        let v = solid::volume(kind, &x).unwrap();
        let n = 3 * kind.n_nodes();
        let mut per_dir = [0.0; 3];
        for r in 0..n {
            for c in 0..n {
                let val = me[r * n + c];
                assert_eq!(val, me[c * n + r], "{kind}: M not symmetric");
                if r % 3 == c % 3 {
                    per_dir[r % 3] += val;
                } else {
                    assert_eq!(val, 0.0, "{kind}: M couples directions at [{r},{c}]");
                }
            }
        }
        for s in per_dir {
            assert!(
                (s - rho * v).abs() < 1e-12 * rho * v,
                "{kind}: ΣM = {s} vs ρV = {}",
                rho * v
            );
        }
        // Positive definite.
        assert!(
            DMatrix::from_row_slice(n, n, &me).cholesky().is_some(),
            "{kind}: M not SPD"
        );
    }
}

#[test]
fn consistent_mass_is_exact_on_affine_cells() {
    for kind in CellKind::SOLIDS {
        let x = affine(kind);
        let me = mass(kind, &x, MassLumping::Consistent);
        let nn = kind.n_nodes();
        let rho = mat().density;
        let rule = quadrature::for_cell(kind, 10);
        let mut n = vec![0.0; nn];
        let mut m_ref = vec![0.0; nn * nn];
        let det = det3(&A);
        for (p, &w) in rule.points.iter().zip(&rule.weights) {
            shape::values(kind, *p, &mut n);
            for a in 0..nn {
                for b in 0..nn {
                    m_ref[a * nn + b] += rho * w * det * n[a] * n[b];
                }
            }
        }
        let mut m_ref3 = vec![0.0; 9 * nn * nn];
        lumping::expand_blocks(&m_ref, nn, 3, &mut m_ref3);
        let r = rel_diff(&me, &m_ref3);
        assert!(r < 1e-13, "{kind}: relative difference to degree-10 mass {r:e}");
    }
}

#[test]
fn known_element_mass_matrices() {
    // Tet4: m_ab = ρV (1 + δ_ab) / 20. Tet10: corner diagonal 6/420 ρV, edge diagonal 32/420 ρV.
    let rho = 2.0;
    let tet = shape::reference_nodes(CellKind::Tet10);
    let v = 1.0 / 6.0;
    let mut me = vec![0.0; 144];
    solid::mass(CellKind::Tet4, &tet[..4], rho, MassLumping::Consistent, &mut me).unwrap();
    for a in 0..4 {
        for b in 0..4 {
            let want = rho * v * if a == b { 2.0 } else { 1.0 } / 20.0;
            assert!((me[3 * a * 12 + 3 * b] - want).abs() < 1e-15);
        }
    }
    let mut me = vec![0.0; 900];
    solid::mass(CellKind::Tet10, tet, rho, MassLumping::Consistent, &mut me).unwrap();
    assert!((me[0] - 6.0 / 420.0 * rho * v).abs() < 1e-15);
    assert!((me[12 * 30 + 12] - 32.0 / 420.0 * rho * v).abs() < 1e-15);
    assert!((me[3] - rho * v / 420.0).abs() < 1e-15); // corner-corner: +1/420 ρV
    // Hex8 unit cube: diagonal ρ (1/3)³ = ρ/27; lumped: ρ/8 each.
    let cube: Vec<[f64; 3]> = shape::reference_nodes(CellKind::Hex8)
        .iter()
        .map(|p| p.map(|c| 0.5 * (c + 1.0)))
        .collect();
    let mut me = vec![0.0; 576];
    solid::mass(CellKind::Hex8, &cube, rho, MassLumping::Consistent, &mut me).unwrap();
    assert!((me[0] - rho / 27.0).abs() < 1e-15);
    solid::mass(CellKind::Hex8, &cube, rho, MassLumping::Lumped, &mut me).unwrap();
    assert!((me[0] - rho / 8.0).abs() < 1e-15 && (me[23 * 24 + 23] - rho / 8.0).abs() < 1e-15);
}

#[test]
fn hrz_lumped_mass_is_positive_diagonal_with_the_same_total() {
    let mut rng = Rng(SEED + 21);
    let rho = mat().density;
    for kind in CellKind::SOLIDS {
        let x = distorted(kind, &mut rng, 0.1);
        let ml = mass(kind, &x, MassLumping::Lumped);
        let mc = mass(kind, &x, MassLumping::Consistent);
        let v = solid::volume(kind, &x).unwrap();
        let n = 3 * kind.n_nodes();
        let mut per_dir = [0.0; 3];
        for r in 0..n {
            for c in 0..n {
                if r != c {
                    assert_eq!(ml[r * n + c], 0.0, "{kind}: lumped M off-diagonal at [{r},{c}]");
                }
            }
            let d = ml[r * n + r];
            assert!(d > 0.0, "{kind}: lumped diagonal {r} = {d}");
            per_dir[r % 3] += d;
        }
        for s in per_dir {
            assert!(
                (s - rho * v).abs() < 1e-12 * rho * v,
                "{kind}: Σ lumped = {s} vs ρV = {}",
                rho * v
            );
        }
        // Proportional to the consistent diagonal, node by node and equal across directions.
        let ratio = ml[0] / mc[0];
        for r in 0..n {
            assert!(
                (ml[r * n + r] / mc[r * n + r] - ratio).abs() < 1e-12 * ratio,
                "{kind}: not HRZ at {r}"
            );
        }
    }
}

#[test]
fn volume_of_known_cells() {
    for kind in CellKind::SOLIDS {
        let x: Vec<[f64; 3]> = shape::reference_nodes(kind)
            .iter()
            .map(|p| {
                if is_simplex(kind) {
                    *p
                } else if is_wedge(kind) {
                    [p[0], p[1], 0.5 * (p[2] + 1.0)]
                } else {
                    p.map(|c| 0.5 * (c + 1.0))
                }
            })
            .collect();
        let want = match kind {
            CellKind::Tet4 | CellKind::Tet10 => 1.0 / 6.0,
            CellKind::Wedge6 | CellKind::Wedge15 => 0.5,
            _ => 1.0,
        };
        let v = solid::volume(kind, &x).unwrap();
        assert!((v - want).abs() < 1e-14, "{kind}: unit cell volume {v} vs {want}");
        // Under the affine map the volume scales by det A.
        let va = solid::volume(kind, &affine(kind)).unwrap();
        let vref = match kind {
            CellKind::Tet4 | CellKind::Tet10 => 1.0 / 6.0,
            CellKind::Wedge6 | CellKind::Wedge15 => 1.0,
            _ => 8.0,
        };
        assert!((va - det3(&A) * vref).abs() < 1e-14 * va, "{kind}: affine volume {va}");
    }
}

/// Volume enclosed by the bilinear faces of a hexahedron with corners `c` (gmsh order), by the
/// divergence theorem: `V = ⅓ ∮ x·n dA = ⅓ Σ_faces ∫∫ x · (x_s × x_t) ds dt`.
fn hex_volume_by_divergence(c: &[[f64; 3]]) -> f64 {
    // Faces ordered counter-clockwise seen from outside (outward normal).
    let faces = [
        [0, 3, 2, 1],
        [0, 1, 5, 4],
        [0, 4, 7, 3],
        [1, 2, 6, 5],
        [2, 3, 7, 6],
        [4, 5, 6, 7],
    ];
    let (g, w) = quadrature::gauss_legendre(3);
    let mut v = 0.0;
    for f in faces {
        let p = f.map(|i| c[i]);
        for (s, ws) in g.iter().zip(&w) {
            for (t, wt) in g.iter().zip(&w) {
                let n = [
                    (1.0 - s) * (1.0 - t),
                    (1.0 + s) * (1.0 - t),
                    (1.0 + s) * (1.0 + t),
                    (1.0 - s) * (1.0 + t),
                ];
                let ds = [-(1.0 - t), 1.0 - t, 1.0 + t, -(1.0 + t)];
                let dt = [-(1.0 - s), -(1.0 + s), 1.0 + s, 1.0 - s];
                let comb = |k: &[f64; 4]| -> [f64; 3] {
                    std::array::from_fn(|i| 0.25 * (0..4).map(|a| k[a] * p[a][i]).sum::<f64>())
                };
                let (x, xs, xt) = (comb(&n), comb(&ds), comb(&dt));
                let cr = [
                    xs[1] * xt[2] - xs[2] * xt[1],
                    xs[2] * xt[0] - xs[0] * xt[2],
                    xs[0] * xt[1] - xs[1] * xt[0],
                ];
                v += ws * wt * (x[0] * cr[0] + x[1] * cr[1] + x[2] * cr[2]) / 3.0;
            }
        }
    }
    v
}

#[test]
fn distorted_hex_volume_matches_divergence_theorem() {
    let mut rng = Rng(SEED + 22);
    let unit: Vec<[f64; 3]> = shape::reference_nodes(CellKind::Hex8)
        .iter()
        .map(|p| p.map(|c| 0.5 * (c + 1.0)))
        .collect();
    assert!((hex_volume_by_divergence(&unit) - 1.0).abs() < 1e-15);
    for _ in 0..5 {
        let corners = distorted(CellKind::Hex8, &mut rng, 0.25);
        let want = hex_volume_by_divergence(&corners);
        // Hex20/Hex27 with their extra nodes on the trilinear map describe the same solid.
        for kind in [CellKind::Hex8, CellKind::Hex20, CellKind::Hex27] {
            let mut n8 = [0.0; 8];
            let x: Vec<[f64; 3]> = shape::reference_nodes(kind)
                .iter()
                .map(|&p| {
                    shape::values(CellKind::Hex8, p, &mut n8);
                    std::array::from_fn(|i| (0..8).map(|a| n8[a] * corners[a][i]).sum())
                })
                .collect();
            let v = solid::volume(kind, &x).unwrap();
            assert!((v - want).abs() < 1e-14 * want, "{kind}: {v} vs divergence {want}");
        }
    }
}

#[test]
fn inverted_and_degenerate_elements_return_err() {
    let mut rng = Rng(SEED + 23);
    let m = mat();
    for kind in CellKind::SOLIDS {
        let nn = kind.n_nodes();
        let mut buf = vec![0.0; 9 * nn * nn];
        let ue = vec![0.0; 3 * nn];
        let xi = random_xi(kind, &mut rng);
        // Mirrored: det J < 0 everywhere.
        let x: Vec<[f64; 3]> = distorted(kind, &mut rng, 0.05)
            .iter()
            .map(|p| [-p[0], p[1], p[2]])
            .collect();
        let neg = |r: Result<(), f64>| matches!(r, Err(d) if d < 0.0);
        assert!(neg(solid::stiffness(kind, &x, &m, &mut buf)), "{kind}: stiffness");
        assert!(
            neg(solid::mass(kind, &x, m.density, MassLumping::Consistent, &mut buf)),
            "{kind}: mass"
        );
        assert!(
            neg(solid::mass(kind, &x, m.density, MassLumping::Lumped, &mut buf)),
            "{kind}: lumped"
        );
        assert!(matches!(solid::volume(kind, &x), Err(d) if d < 0.0), "{kind}: volume");
        assert!(
            matches!(solid::stress_at(kind, &x, &m, &ue, xi), Err(d) if d < 0.0),
            "{kind}: stress"
        );
        // Flattened into a plane: det J = 0.
        let x: Vec<[f64; 3]> = affine(kind).iter().map(|p| [p[0], p[1], 0.0]).collect();
        assert_eq!(solid::stiffness(kind, &x, &m, &mut buf), Err(0.0), "{kind}: flat");
        assert!(solid::volume(kind, &x).is_err(), "{kind}: flat volume");
        // Non-finite coordinates are rejected too.
        let mut x = affine(kind);
        x[0][0] = f64::NAN;
        assert!(solid::stiffness(kind, &x, &m, &mut buf).is_err(), "{kind}: NaN");
    }
}

// ---------------------------------------------------------------------------------------------
// element sweep: every formulation through the ElementSet interface

/// One entry of the element sweep: a name, the node coordinates of its single element, the set.
type SweepEntry = (String, Vec<[f64; 3]>, Box<dyn ElementSet>);

/// One single-element set per formulation and variant, on distorted geometry. **Adding an
/// element: add its line here**; the tests below then check it.
fn element_sweep() -> Vec<SweepEntry> {
    let mut rng = Rng(SEED ^ 0xE1E5);
    let mut out: Vec<SweepEntry> = Vec::new();
    for kind in CellKind::SOLIDS {
        let x = distorted(kind, &mut rng, 0.1);
        out.push((
            format!("solid {kind}"),
            x.clone(),
            Box::new(SolidSet::single(kind, x, mat())),
        ));
    }
    let x = distorted(CellKind::Hex8, &mut rng, 0.1);
    let mut im = SolidSet::single(CellKind::Hex8, x.clone(), mat());
    im.hex8 = vibrofem::element::incompatible::Hex8Formulation::Incompatible;
    out.push(("solid hex8 incompatible".into(), x, Box::new(im)));
    let tri = vec![[0.1, 0.0, 0.05], [1.0, 0.2, 0.0], [0.3, 0.9, 0.1]];
    let quad = vec![[0.0, 0.0, 0.0], [1.1, 0.1, 0.03], [1.0, 0.9, -0.02], [0.1, 1.0, 0.04]];
    let (thin, mut offset) = (ShellSection::new(0.02), ShellSection::new(0.02));
    offset.offset = 0.01;
    let shell = |k, x: &Vec<[f64; 3]>, s: &ShellSection| Box::new(ShellSet::single(k, x.clone(), *s, mat()));
    out.push(("shell tri3".into(), tri.clone(), shell(CellKind::Tri3, &tri, &thin)));
    out.push((
        "shell quad4 warped".into(),
        quad.clone(),
        shell(CellKind::Quad4, &quad, &thin),
    ));
    out.push((
        "shell quad4 offset".into(),
        quad.clone(),
        shell(CellKind::Quad4, &quad, &offset),
    ));
    let mut sc = BeamSection::rectangle(0.05, 0.08);
    sc.shear_centre = [0.01, -0.005];
    let mut warp = sc;
    (warp.warping, warp.cw) = (true, 1e-9);
    let line2 = vec![[0.0, 0.0, 0.0], [0.8, 0.3, -0.2]];
    let line3 = vec![[0.0, 0.0, 0.0], [1.0, 0.1, 0.2], [0.5, 0.15, 0.05]];
    let o = [0.0, 0.3, 1.0];
    let beam = |k, x: &Vec<[f64; 3]>, s: &BeamSection| Box::new(BeamSet::single(k, x.clone(), o, *s, mat()));
    out.push(("beam line2".into(), line2.clone(), beam(CellKind::Line2, &line2, &sc)));
    out.push((
        "beam line2 warping".into(),
        line2.clone(),
        beam(CellKind::Line2, &line2, &warp),
    ));
    out.push((
        "beam line3 curved".into(),
        line3.clone(),
        beam(CellKind::Line3, &line3, &sc),
    ));
    // Discrete: a spring between two coincident 3-DOF nodes and a 6-DOF point mass.
    let mut spring = DiscreteSet::new(2, 3);
    let mut ks = vec![0.0; 36];
    for i in 0..3 {
        for (a, b, v) in [(0, 0, 1.0), (1, 1, 1.0), (0, 1, -1.0), (1, 0, -1.0)] {
            ks[(3 * a + i) * 6 + 3 * b + i] = 1e6 * v;
        }
    }
    spring.push(&[0, 1], ks, vec![0.0; 36], "spring".into());
    out.push(("spring".into(), vec![[0.2, 0.1, 0.0]; 2], Box::new(spring)));
    let mut point = DiscreteSet::new(1, 6);
    let mut mp = vec![0.0; 36];
    for (i, v) in [2.0, 2.0, 2.0, 0.1, 0.2, 0.3].into_iter().enumerate() {
        mp[i * 6 + i] = v;
    }
    point.push(&[0], vec![0.0; 36], mp, "point mass".into());
    out.push(("point mass".into(), vec![[0.2, 0.1, 0.0]], Box::new(point)));
    out
}

/// Rigid motion (translation `t`, small rotation `w` about the origin) at nodes `x`, `d`
/// components per node; rotations go to components 3..6, a warping amplitude (7th) stays 0.
fn rigid(x: &[[f64; 3]], d: usize, t: [f64; 3], w: [f64; 3]) -> Vec<f64> {
    let mut u = vec![0.0; d * x.len()];
    for (a, p) in x.iter().enumerate() {
        let r = [
            w[1] * p[2] - w[2] * p[1],
            w[2] * p[0] - w[0] * p[2],
            w[0] * p[1] - w[1] * p[0],
        ];
        for i in 0..3 {
            u[d * a + i] = t[i] + r[i];
            if d >= 6 {
                u[d * a + 3 + i] = w[i];
            }
        }
    }
    u
}

/// Stiffness and mass (the set's own form) of the single element of `set`.
fn set_matrices(set: &dyn ElementSet) -> (Vec<f64>, Vec<f64>) {
    let nd = set.dofs_per_node() * set.nodes(0).len();
    let (mut ke, mut me) = (vec![f64::NAN; nd * nd], vec![f64::NAN; nd * nd]);
    set.matrices(0, &mut ke, &mut me, true).unwrap();
    (ke, me)
}

#[test]
fn sweep_sets_describe_themselves() {
    for (name, x, set) in element_sweep() {
        assert_eq!(set.len(), 1, "{name}");
        assert_eq!(set.nodes(0).len(), x.len(), "{name}");
        assert!(matches!(set.dofs_per_node(), 3 | 6 | 7), "{name}");
        assert!(!set.group().is_empty(), "{name}");
        assert_eq!(set.tag(0).is_some(), set.cell_kind(0).is_some(), "{name}");
        if let Some(kind) = set.cell_kind(0) {
            assert_eq!(kind.n_nodes(), x.len(), "{name}");
            assert!(set.measure(0).unwrap() > 0.0, "{name}: measure");
        } else {
            assert_eq!(set.measure(0).unwrap(), 0.0, "{name}: measure");
        }
    }
}

#[test]
fn sweep_matrices_are_symmetric_and_finite() {
    for (name, _, set) in element_sweep() {
        let (ke, me) = set_matrices(set.as_ref());
        let nd = set.dofs_per_node() * set.nodes(0).len();
        let (sk, sm) = (max_abs(&ke), max_abs(&me));
        assert!(ke.iter().chain(&me).all(|v| v.is_finite()), "{name}");
        for i in 0..nd {
            for j in 0..nd {
                assert!(
                    (ke[i * nd + j] - ke[j * nd + i]).abs() <= 1e-12 * sk,
                    "{name}: K({i}, {j})"
                );
                assert!(
                    (me[i * nd + j] - me[j * nd + i]).abs() <= 1e-12 * sm,
                    "{name}: M({i}, {j})"
                );
            }
        }
    }
}

#[test]
fn sweep_stiffness_annihilates_rigid_motions() {
    for (name, x, set) in element_sweep() {
        let (ke, _) = set_matrices(set.as_ref());
        let d = set.dofs_per_node();
        let size = x.iter().flatten().fold(1.0f64, |m, v| m.max(v.abs()));
        for k in 0..6 {
            let (mut t, mut w) = ([0.0; 3], [0.0; 3]);
            if k < 3 {
                t[k] = 1.0;
            } else {
                w[k - 3] = 1.0 / size;
            }
            let u = rigid(&x, d, t, w);
            let f = matvec(&ke, &u);
            assert!(
                max_abs(&f) <= 1e-9 * max_abs(&ke) * max_abs(&u),
                "{name}: rigid motion {k}: {}",
                max_abs(&f)
            );
        }
    }
}

#[test]
fn sweep_mass_matches_measure_times_density_and_lumping_keeps_it() {
    for (name, x, set) in element_sweep() {
        let d = set.dofs_per_node();
        let nd = d * x.len();
        let mut me = vec![f64::NAN; nd * nd];
        set.consistent_mass(0, &mut me).unwrap();
        let mass = set.mass(0).unwrap();
        if set.cell_kind(0).is_some() {
            let expected = set.measure(0).unwrap() * set.density(0);
            assert!((mass - expected).abs() <= 1e-15 * expected, "{name}");
        }
        // A unit translation in each direction carries the whole mass.
        for i in 0..3 {
            let mut t = [0.0; 3];
            t[i] = 1.0;
            let u = rigid(&x, d, t, [0.0; 3]);
            let m: f64 = matvec(&me, &u).iter().zip(&u).map(|(a, b)| a * b).sum();
            assert!(
                (m - mass).abs() <= 1e-12 * mass.max(1e-300),
                "{name}: direction {i}: {m} vs {mass}"
            );
        }
        // The set's own form (lumped for some) has the same total.
        let (_, ml) = set_matrices(set.as_ref());
        let u = rigid(&x, d, [1.0, 0.0, 0.0], [0.0; 3]);
        let m: f64 = matvec(&ml, &u).iter().zip(&u).map(|(a, b)| a * b).sum();
        assert!((m - mass).abs() <= 1e-12 * mass.max(1e-300), "{name}: own mass form");
    }
}

#[test]
fn sweep_stress_is_available_where_documented() {
    for (name, x, set) in element_sweep() {
        let ue = vec![0.0; 3 * x.len()];
        let r = set.stress_at(0, &ue, [0.25, 0.25, 0.25]);
        assert_eq!(r.is_ok(), set.has_stress(), "{name}");
        if let Ok(s) = r {
            assert_eq!(s, [0.0; 6], "{name}: zero displacement, zero stress");
        }
    }
}
