//! Stress recovery (`post::stress`): patch tests, bending, averaging, equivalent stresses,
//! group maxima, output fields and bad input.

use vibrofem::element::solid;
use vibrofem::error::Error;
use vibrofem::io::{msh_out, vtk};
use vibrofem::material::Material;
use vibrofem::mesh::generate::box_mesh;
use vibrofem::mesh::{CellKind, Mesh};
use vibrofem::model::{Model, ModelSpec};
use vibrofem::post::stress::{
    GroupMax, Recovery, StressField, StressFields, gauss_point_stress, group_maxima, nodal_stress, nodal_stress_with,
    principal, tresca, von_mises,
};

const SOLIDS: [CellKind; 7] = [
    CellKind::Tet4,
    CellKind::Tet10,
    CellKind::Hex8,
    CellKind::Hex20,
    CellKind::Hex27,
    CellKind::Wedge6,
    CellKind::Wedge15,
];

/// Deterministic xorshift generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

fn steel() -> Material {
    Material::steel()
}

fn model(mesh: &Mesh, mat: Material) -> Model {
    let spec = ModelSpec {
        material: mat,
        ..Default::default()
    };
    Model::build(mesh, &spec, "test mesh").unwrap()
}

/// Displacements `u(x)` at every node.
fn field(mesh: &Mesh, f: impl Fn([f64; 3]) -> [f64; 3]) -> Vec<f64> {
    mesh.nodes.iter().flat_map(|&x| f(x)).collect()
}

fn max_abs6(s: &[f64; 6]) -> f64 {
    s.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

fn diff6(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// Voigt strain (engineering shear) of a constant displacement gradient `g[i][j] = ∂u_i/∂x_j`.
fn voigt(g: [[f64; 3]; 3]) -> [f64; 6] {
    [
        g[0][0],
        g[1][1],
        g[2][2],
        g[1][2] + g[2][1],
        g[0][2] + g[2][0],
        g[0][1] + g[1][0],
    ]
}

/// Voigt tensor of `R diag(d) Rᵀ` for a rotation about the axis `n` by angle `t`.
fn rotated(d: [f64; 3], n: [f64; 3], t: f64) -> [f64; 6] {
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let n = n.map(|v| v / l);
    let (c, s) = (t.cos(), t.sin());
    let k = [[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]];
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = (if i == j { c } else { 0.0 }) + s * k[i][j] + (1.0 - c) * n[i] * n[j];
        }
    }
    let m = |i: usize, j: usize| (0..3).map(|a| r[i][a] * d[a] * r[j][a]).sum::<f64>();
    [m(0, 0), m(1, 1), m(2, 2), m(1, 2), m(0, 2), m(0, 1)]
}

/// Invariants I1, I2, I3 of a Voigt stress.
fn invariants(s: &[f64; 6]) -> [f64; 3] {
    let [xx, yy, zz, yz, xz, xy] = *s;
    [
        xx + yy + zz,
        xx * yy + yy * zz + zz * xx - yz * yz - xz * xz - xy * xy,
        xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz),
    ]
}

#[test]
fn known_tensors() {
    let t = 123.0e6;
    // uniaxial
    let s = [t, 0.0, 0.0, 0.0, 0.0, 0.0];
    assert_eq!(von_mises(&s), t);
    assert_eq!(principal(&s), [t, 0.0, 0.0]);
    assert_eq!(tresca(&s), t);
    let s = [0.0, 0.0, -t, 0.0, 0.0, 0.0];
    assert_eq!(principal(&s), [0.0, 0.0, -t]);
    assert_eq!(tresca(&s), t);
    // pure shear in each plane: principal (τ, 0, −τ), von Mises √3 τ, Tresca 2τ
    for c in 3..6 {
        let mut s = [0.0; 6];
        s[c] = t;
        let p = principal(&s);
        assert!(
            (p[0] - t).abs() < 1e-9 && p[1].abs() < 1e-9 && (p[2] + t).abs() < 1e-9,
            "{p:?}"
        );
        assert!((von_mises(&s) - 3f64.sqrt() * t).abs() < 1e-6);
        assert!((tresca(&s) - 2.0 * t).abs() < 1e-8);
    }
    // hydrostatic: three equal roots, no equivalent stress
    let s = [-t, -t, -t, 0.0, 0.0, 0.0];
    assert_eq!(principal(&s), [-t, -t, -t]);
    assert_eq!(von_mises(&s), 0.0);
    assert_eq!(tresca(&s), 0.0);
    // zero
    assert_eq!(principal(&[0.0; 6]), [0.0; 3]);
    // plane stress σ_xx = 80, σ_yy = −40, τ_xy = 30: centre 20, radius √(60² + 30²)
    let s = [80.0, -40.0, 0.0, 0.0, 0.0, 30.0];
    let r = (60.0f64 * 60.0 + 30.0 * 30.0).sqrt();
    let p = principal(&s);
    assert!((p[0] - (20.0 + r)).abs() < 1e-12 && p[1].abs() < 1e-12 && (p[2] - (20.0 - r)).abs() < 1e-12);
    let vm = (80.0f64 * 80.0 + 40.0 * 40.0 + 80.0 * 40.0 + 3.0 * 900.0).sqrt();
    assert!((von_mises(&s) - vm).abs() < 1e-12);
}

#[test]
fn principal_stresses_of_rotated_tensors_with_repeated_roots() {
    let mut rng = Rng(0x9e3779b97f4a7c15);
    let cases: [[f64; 3]; 6] = [
        [5.0, 5.0, -2.0],
        [3.0, -1.0, -1.0],
        [7.0, 7.0, 7.0],
        [1.0, 1.0 + 1e-9, 1.0 - 1e-9],
        [2.0e8, 0.0, 0.0],
        [4.0, 1.0, -3.0],
    ];
    for d in cases {
        for _ in 0..50 {
            let n = [rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)];
            let s = rotated(d, n, rng.uniform(0.0, 6.3));
            let p = principal(&s);
            let mut want = d;
            want.sort_by(|a, b| b.total_cmp(a));
            let scale = d.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..3 {
                assert!((p[i] - want[i]).abs() < 1e-14 * scale * 8.0, "{d:?}: {p:?}");
            }
            assert!((tresca(&s) - (want[0] - want[2])).abs() < 1e-13 * scale);
            let vm = (0.5 * ((d[0] - d[1]).powi(2) + (d[1] - d[2]).powi(2) + (d[2] - d[0]).powi(2))).sqrt();
            assert!((von_mises(&s) - vm).abs() < 1e-7 * scale, "{} vs {vm}", von_mises(&s));
        }
    }
    // random full tensors: the principal values keep the invariants and are sorted
    for _ in 0..500 {
        let s: [f64; 6] = std::array::from_fn(|_| rng.uniform(-1e8, 1e8));
        let p = principal(&s);
        assert!(p[0] >= p[1] && p[1] >= p[2]);
        let a = invariants(&s);
        let b = invariants(&[p[0], p[1], p[2], 0.0, 0.0, 0.0]);
        let m = 1e8;
        assert!((a[0] - b[0]).abs() < 1e-13 * m);
        assert!((a[1] - b[1]).abs() < 1e-13 * m * m);
        assert!((a[2] - b[2]).abs() < 1e-13 * m * m * m);
        let vm_p = von_mises(&[p[0], p[1], p[2], 0.0, 0.0, 0.0]);
        assert!((von_mises(&s) - vm_p).abs() < 1e-13 * m);
    }
}

/// A box mesh whose corner (vertex) nodes are moved by up to `amp` of the cell size in each
/// direction, and whose other nodes by up to `amp / 4` (so quadratic cells get curved edges).
fn distorted_box(kind: CellKind, rng: &mut Rng, amp: f64) -> Mesh {
    let size = [0.3, 0.2, 0.1];
    let n = [3, 2, 2];
    let mut mesh = box_mesh(kind, size, n);
    for p in &mut mesh.nodes {
        let h: [f64; 3] = std::array::from_fn(|d| size[d] / n[d] as f64);
        // box_mesh nodes sit on a lattice of half the cell size; vertices on the even points
        let vertex = (0..3).all(|d| ((p[d] / (0.5 * h[d])).round() as i64) % 2 == 0);
        let a = if vertex { amp } else { amp / 4.0 };
        for d in 0..3 {
            p[d] += a * h[d] * rng.uniform(-1.0, 1.0);
        }
    }
    mesh
}

#[test]
fn constant_stress_patch_on_distorted_meshes_is_exact() {
    let mut rng = Rng(0x2545f4914f6cdd1d);
    let mat = steel();
    for kind in SOLIDS {
        let mesh = distorted_box(kind, &mut rng, 0.12);
        let m = model(&mesh, mat);
        let g: [[f64; 3]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| rng.uniform(-1e-3, 1e-3)));
        let b = [1e-4, -2e-4, 3e-4];
        let u = field(&mesh, |x| {
            std::array::from_fn(|i| b[i] + g[i][0] * x[0] + g[i][1] * x[1] + g[i][2] * x[2])
        });
        let want = mat.stress(&voigt(g));
        let tol = 1e-10 * max_abs6(&want);
        for rec in [Recovery::Direct, Recovery::Extrapolated] {
            let ns = nodal_stress_with(&m.solids, mesh.n_nodes(), &u, rec).unwrap();
            assert_eq!(ns.recovery, rec);
            for a in 0..mesh.n_nodes() {
                assert!(ns.count[a] > 0);
                let err = diff6(&ns.stress[a], &want);
                assert!(err < tol, "{kind} {rec:?} node {a}: error {err:e} (tol {tol:e})");
                assert!((ns.von_mises[a] - von_mises(&want)).abs() < tol);
                assert!((ns.von_mises_max_unaveraged[a] - von_mises(&want)).abs() < tol);
                assert!((ns.tresca[a] - tresca(&want)).abs() < tol);
            }
        }
        let gp = gauss_point_stress(&m.solids, mesh.n_nodes(), &u).unwrap();
        let n_cells: usize = m.solids.iter().map(|s| s.tags.len()).sum();
        let per_cell = vibrofem::fe::quadrature::for_cell(kind, solid::stiffness_degree(kind)).len();
        assert_eq!(gp.len(), n_cells * per_cell);
        for (i, s) in gp.stress.iter().enumerate() {
            assert!(diff6(s, &want) < tol, "{kind} gauss point {i}");
            // u = A x + b is interpolated exactly, so the displacement at the point's
            // coordinates is consistent: the point lies inside the (distorted) box's hull
            let x = gp.points[i];
            assert!(x[0] > -0.02 && x[0] < 0.32 && x[1] > -0.02 && x[1] < 0.22 && x[2] > -0.01 && x[2] < 0.11);
        }
    }
}

#[test]
fn gauss_points_map_to_their_element() {
    // On an undistorted hex20 box the 27 points of each cell lie inside the cell's brick.
    let mesh = box_mesh(CellKind::Hex20, [0.3, 0.2, 0.1], [3, 2, 2]);
    let m = model(&mesh, steel());
    let u = vec![0.0; 3 * mesh.n_nodes()];
    let gp = gauss_point_stress(&m.solids, mesh.n_nodes(), &u).unwrap();
    let set = &m.solids[0];
    for (i, x) in gp.points.iter().enumerate() {
        let e = set.tags.iter().position(|&t| t == gp.element[i]).unwrap();
        let mut xe = [[0.0; 3]; 20];
        set.coords(e, &mut xe);
        for d in 0..3 {
            let lo = xe.iter().map(|p| p[d]).fold(f64::INFINITY, f64::min);
            let hi = xe.iter().map(|p| p[d]).fold(f64::NEG_INFINITY, f64::max);
            assert!(x[d] > lo && x[d] < hi);
        }
    }
}

/// Pure bending about y: `σ_xx = −E κ (z − z0)`, every other component zero. The displacement
/// field is quadratic, so the quadratic elements interpolate it exactly.
fn bending(mesh: &Mesh, mat: Material, kappa: f64, z0: f64) -> Vec<f64> {
    let nu = mat.poisson;
    field(mesh, |x| {
        let z = x[2] - z0;
        [
            -kappa * x[0] * z,
            nu * kappa * x[1] * z,
            0.5 * kappa * (x[0] * x[0] + nu * (z * z - x[1] * x[1])),
        ]
    })
}

#[test]
fn pure_bending_is_exact_at_the_nodes_of_quadratic_elements() {
    let mat = steel();
    let (kappa, c) = (2e-3, 0.01);
    for kind in [CellKind::Hex20, CellKind::Hex27, CellKind::Tet10, CellKind::Wedge15] {
        let mut mesh = box_mesh(kind, [0.2, 0.05, c], [8, 3, 2]);
        // an affine shear of the box keeps the field quadratic in the reference coordinates
        for p in &mut mesh.nodes {
            p[0] += 0.3 * p[1];
            p[1] += 0.2 * p[2];
        }
        let m = model(&mesh, mat);
        let u = bending(&mesh, mat, kappa, c / 2.0);
        let smax = mat.young * kappa * c / 2.0;
        let tol = 1e-10 * smax;
        let want = |x: [f64; 3]| [-mat.young * kappa * (x[2] - c / 2.0), 0.0, 0.0, 0.0, 0.0, 0.0];
        for rec in [Recovery::Direct, Recovery::Extrapolated] {
            let ns = nodal_stress_with(&m.solids, mesh.n_nodes(), &u, rec).unwrap();
            for (a, x) in mesh.nodes.iter().enumerate() {
                let err = diff6(&ns.stress[a], &want(*x));
                assert!(err < tol, "{kind} {rec:?} node {a} at {x:?}: error {err:e}");
            }
        }
        let gp = gauss_point_stress(&m.solids, mesh.n_nodes(), &u).unwrap();
        for (s, x) in gp.stress.iter().zip(&gp.points) {
            assert!(diff6(s, &want(*x)) < tol, "{kind} gauss point at {x:?}");
        }
        // maxima: |σ_xx| = E κ c / 2 on the top and bottom faces
        let ns = nodal_stress(&m.solids, mesh.n_nodes(), &u).unwrap();
        let maxima = group_maxima(&mesh, &ns, StressField::VonMises).unwrap();
        let get = |name: &str| maxima.iter().find(|g| g.group == name).unwrap().clone();
        assert_eq!(maxima[0].group, "(all)");
        for g in ["(all)", "zmin", "zmax", "xmin", "volume"] {
            assert!((get(g).value - smax).abs() < tol, "{g}: {}", get(g).value);
        }
        let top = get("zmax");
        assert!((top.coords[2] - c).abs() < 1e-12);
        let idx = mesh.node_tags.iter().position(|&t| Some(t) == top.node).unwrap();
        assert_eq!(mesh.nodes[idx], top.coords);
        let minp = group_maxima(&mesh, &ns, StressField::MinPrincipal).unwrap();
        assert!((minp[0].value + smax).abs() < tol && (minp[0].coords[2] - c).abs() < 1e-12);
        let maxp = group_maxima(&mesh, &ns, StressField::MaxPrincipal).unwrap();
        assert!((maxp[0].value - smax).abs() < tol && maxp[0].coords[2].abs() < 1e-12);
        let sxx = group_maxima(&mesh, &ns, StressField::Component(0)).unwrap();
        assert!((sxx[0].value.abs() - smax).abs() < tol);
        let shear = group_maxima(&mesh, &ns, StressField::MaxShear).unwrap();
        assert!((shear[0].value - smax / 2.0).abs() < tol);
        // mid-plane nodes carry no stress
        let mid = mesh.nodes.iter().position(|x| (x[2] - c / 2.0).abs() < 1e-12).unwrap();
        assert!(ns.von_mises[mid] < tol);
        // Gauss points peak inside the thickness
        let peak = gp.peak(StressField::VonMises).unwrap().unwrap();
        assert!(peak.value < smax && peak.value > 0.5 * smax && peak.element.is_some());
    }
}

#[test]
fn averaging_and_unaveraged_maximum() {
    // A field hex8 cannot represent: element stresses jump between elements at shared nodes.
    let mat = Material {
        young: 1.0e3,
        poisson: 0.25,
        density: 1.0,
    };
    let mesh = box_mesh(CellKind::Hex8, [1.0, 1.0, 1.0], [2, 2, 2]);
    let m = model(&mesh, mat);
    let u = field(&mesh, |x| {
        [
            x[0] * x[0] + 0.3 * x[1] * x[2],
            x[1] * x[1] * x[0] - x[2],
            (x[0] * x[1]).sin() + x[2] * x[2] * x[2],
        ]
    });
    let ns = nodal_stress(&m.solids, mesh.n_nodes(), &u).unwrap();
    let set = &m.solids[0];
    let mut sum = vec![[0.0; 6]; mesh.n_nodes()];
    let mut count = vec![0u32; mesh.n_nodes()];
    let mut vmax = vec![0.0f64; mesh.n_nodes()];
    let mut arg = vec![0u64; mesh.n_nodes()];
    for e in 0..set.tags.len() {
        let nodes = &set.conn[8 * e..8 * e + 8];
        let mut x = [[0.0; 3]; 8];
        set.coords(e, &mut x);
        let ue: Vec<f64> = nodes
            .iter()
            .flat_map(|&a| u[3 * a as usize..3 * a as usize + 3].to_vec())
            .collect();
        for (i, &a) in nodes.iter().enumerate() {
            let xi = vibrofem::fe::shape::reference_nodes(CellKind::Hex8)[i];
            let s = solid::stress_at(CellKind::Hex8, &x, &mat, &ue, xi).unwrap();
            let a = a as usize;
            for c in 0..6 {
                sum[a][c] += s[c];
            }
            count[a] += 1;
            if von_mises(&s) > vmax[a] {
                vmax[a] = von_mises(&s);
                arg[a] = set.tags[e];
            }
        }
    }
    let centre = mesh.nodes.iter().position(|x| *x == [0.5, 0.5, 0.5]).unwrap();
    assert_eq!(ns.count[centre], 8);
    let corner = mesh.nodes.iter().position(|x| *x == [0.0, 0.0, 0.0]).unwrap();
    assert_eq!(ns.count[corner], 1);
    let mut jumps = 0;
    for a in 0..mesh.n_nodes() {
        assert_eq!(ns.count[a], count[a]);
        let avg = sum[a].map(|v| v / count[a] as f64);
        assert!(diff6(&ns.stress[a], &avg) < 1e-12 * (1.0 + max_abs6(&avg)));
        assert!((ns.von_mises_max_unaveraged[a] - vmax[a]).abs() < 1e-12 * vmax[a]);
        assert_eq!(ns.max_element[a], arg[a]);
        assert!(ns.von_mises_max_unaveraged[a] >= ns.von_mises[a] * (1.0 - 1e-14));
        if ns.von_mises_max_unaveraged[a] > ns.von_mises[a] * (1.0 + 1e-6) {
            jumps += 1;
        }
    }
    assert!(jumps > 0, "the test field should make element stresses differ");
    let un = group_maxima(&mesh, &ns, StressField::VonMisesMaxUnaveraged).unwrap();
    let avg = group_maxima(&mesh, &ns, StressField::VonMises).unwrap();
    assert!(un[0].value >= avg[0].value);
    assert!(un[0].element.is_some() && avg[0].element.is_none());
    let a = mesh.node_tags.iter().position(|&t| Some(t) == un[0].node).unwrap();
    assert_eq!(un[0].element, Some(ns.max_element[a]));
}

#[test]
fn nodes_without_solids_are_skipped() {
    let mut mesh = box_mesh(CellKind::Tet10, [0.1, 0.1, 0.1], [1, 1, 1]);
    // an orphan node far away, with a group holding only a point cell on it
    mesh.nodes.push([5.0, 5.0, 5.0]);
    mesh.node_tags.push(9999);
    let m = model(&mesh, steel());
    let u = vec![1e-3; 3 * mesh.n_nodes()];
    let ns = nodal_stress(&m.solids, mesh.n_nodes(), &u).unwrap();
    let last = mesh.n_nodes() - 1;
    assert_eq!(ns.count[last], 0);
    assert_eq!(ns.stress[last], [0.0; 6]);
    let gm = group_maxima(&mesh, &ns, StressField::Tresca).unwrap();
    assert!(gm.iter().all(|g| g.node != Some(9999)));
    // a rigid translation gives zero stress everywhere
    assert!(ns.von_mises.iter().all(|&v| v.abs() < 1e-3));
}

#[test]
fn output_fields_for_vtu_and_msh() {
    let mat = steel();
    let mesh = box_mesh(CellKind::Hex20, [0.2, 0.05, 0.01], [4, 2, 1]);
    let m = model(&mesh, mat);
    let g = [[1e-4, 2e-4, -3e-4], [0.5e-4, -1e-4, 0.7e-4], [0.0, 0.2e-4, 1e-4]];
    let u = field(&mesh, |x| {
        std::array::from_fn(|i| g[i][0] * x[0] + g[i][1] * x[1] + g[i][2] * x[2])
    });
    let ns = nodal_stress(&m.solids, mesh.n_nodes(), &u).unwrap();
    let f = StressFields::new(&ns, "lc1_");
    let n = mesh.n_nodes();
    let s = ns.stress[3];
    assert_eq!(f.stress_vtk[18..24], [s[0], s[1], s[2], s[5], s[3], s[4]]);
    assert_eq!(
        f.stress_tensor9[27..36],
        [s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2]]
    );
    let pf = f.point_fields();
    let names: Vec<&str> = pf.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "lc1_stress",
            "lc1_von_mises",
            "lc1_von_mises_max_unaveraged",
            "lc1_principal_1",
            "lc1_principal_2",
            "lc1_principal_3",
            "lc1_tresca"
        ]
    );
    for p in &pf {
        assert_eq!(p.data.len(), p.n_comp * n);
    }
    let text = vtk::vtu_string(&mesh, &pf).unwrap();
    assert!(text.contains("Name=\"lc1_stress\" NumberOfComponents=\"6\""));
    let views = f.node_views(1, 0.0);
    assert_eq!(views.len(), 7);
    assert_eq!(views[0].n_comp, 9);
    let text = msh_out::msh_string(&mesh, &views).unwrap();
    // In gmsh the load cases are a view's time steps: the names carry no case prefix.
    assert!(text.contains("\"von_mises\"") && !text.contains("lc1_"));
    // principal arrays hold the descending principal stresses
    for a in 0..n {
        assert!(f.principal[0][a] >= f.principal[1][a] && f.principal[1][a] >= f.principal[2][a]);
        assert_eq!(f.von_mises[a], ns.von_mises[a]);
    }
    // GroupMax is serialisable
    let gm: Vec<GroupMax> = group_maxima(&mesh, &ns, StressField::VonMises).unwrap();
    let json = serde_json::to_string(&gm).unwrap();
    assert!(json.contains("\"group\":\"(all)\"") && json.contains("\"VonMises\""));
    let json = serde_json::to_string(&ns).unwrap();
    assert!(json.contains("von_mises_max_unaveraged"));
}

#[test]
fn bad_input_is_reported() {
    let mesh = box_mesh(CellKind::Hex8, [0.1, 0.1, 0.1], [2, 1, 1]);
    let mut m = model(&mesh, steel());
    let n = mesh.n_nodes();
    let e = nodal_stress(&m.solids, n, &vec![0.0; 3 * n - 1]).unwrap_err();
    assert!(
        matches!(e, Error::InvalidInput(_)) && e.to_string().contains("3 per node"),
        "{e}"
    );
    let mut u = vec![0.0; 3 * n];
    u[7] = f64::NAN;
    let e = gauss_point_stress(&m.solids, n, &u).unwrap_err();
    assert!(
        e.to_string().contains("non-finite") && e.to_string().contains("node index 2"),
        "{e}"
    );
    u[7] = 0.0;
    let ns = nodal_stress(&m.solids, n, &u).unwrap();
    let e = group_maxima(&mesh, &ns, StressField::Component(6)).unwrap_err();
    assert!(e.to_string().contains("component 6"), "{e}");
    let other = box_mesh(CellKind::Hex8, [0.1, 0.1, 0.1], [3, 1, 1]);
    let e = group_maxima(&other, &ns, StressField::VonMises).unwrap_err();
    assert!(e.to_string().contains("nodes"), "{e}");
    // fewer nodes than the elements use
    let e = nodal_stress(&m.solids, 4, &[0.0; 12]).unwrap_err();
    assert!(e.to_string().contains("node index"), "{e}");
    // an inverted element is named
    m.solids[0].conn.swap(0, 1);
    let e = nodal_stress(&m.solids, n, &u).unwrap_err();
    assert!(matches!(e, Error::InvertedElement { element: 1, .. }), "{e}");
    let e = nodal_stress_with(&m.solids, n, &u, Recovery::Extrapolated).unwrap_err();
    assert!(matches!(e, Error::InvertedElement { .. }), "{e}");
}

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The scikit-fem static references (`validation/skfem_static.py`) store the displacement of
/// every node and the nodal stresses obtained the same way as `nodal_stress` (direct nodal
/// evaluation in each cell, simple average), computed independently with skfem's P2 / S2
/// spaces. Feeding the reference displacements to `nodal_stress` must give the same stresses.
#[test]
fn nodal_stress_matches_scikit_fem_on_the_reference_displacements() {
    let cases = [
        "static_s3_leaf_hex20_10x6x1_guided",
        "static_s3_leaf_hex20_20x12x2_traction",
        "static_s3_leaf_tet10_h9_guided",
        "static_cantilever_hex20_40x2x2_tip",
    ];
    for case in cases {
        let path = format!("{ROOT}/validation/reference/{case}.json");
        let text = std::fs::read_to_string(&path).unwrap();
        let r: serde_json::Value = serde_json::from_str(&text).unwrap();
        let mesh_path = format!("{ROOT}/{}", r["mesh"].as_str().unwrap());
        let mesh = vibrofem::io::gmsh::read(std::path::Path::new(&mesh_path), 1.0).unwrap();
        let mat = Material {
            young: r["material"]["young"].as_f64().unwrap(),
            poisson: r["material"]["poisson"].as_f64().unwrap(),
            density: r["material"]["density"].as_f64().unwrap(),
        };
        let m = model(&mesh, mat);
        let tags: Vec<u64> = r["node_tags"]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| t.as_u64().unwrap())
            .collect();
        assert_eq!(tags, mesh.node_tags, "{case}: node order");
        let u: Vec<f64> = r["displacement"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|row| row.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()))
            .collect();
        let ns = nodal_stress(&m.solids, mesh.n_nodes(), &u).unwrap();
        let want: Vec<[f64; 6]> = r["stress"]["nodal"]
            .as_array()
            .unwrap()
            .iter()
            .map(|row| std::array::from_fn(|c| row[c].as_f64().unwrap()))
            .collect();
        let vm: Vec<f64> = r["stress"]["von_mises"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let vmu: Vec<f64> = r["stress"]["von_mises_max_unaveraged"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let smax = want.iter().map(max_abs6).fold(0.0, f64::max);
        let mut worst = 0.0f64;
        for a in 0..mesh.n_nodes() {
            worst = worst.max(diff6(&ns.stress[a], &want[a]) / smax);
            worst = worst.max((ns.von_mises[a] - vm[a]).abs() / smax);
            worst = worst.max((ns.von_mises_max_unaveraged[a] - vmu[a]).abs() / smax);
        }
        assert!(worst < 1e-10, "{case}: max relative difference {worst:e}");
        let top = group_maxima(&mesh, &ns, StressField::VonMises).unwrap();
        let ref_max = r["results"]["max_von_mises"]["value"].as_f64().unwrap();
        assert!((top[0].value - ref_max).abs() < 1e-9 * ref_max, "{case}");
        eprintln!(
            "{case}: nodal stresses agree to {worst:.1e}; max von Mises {:.3} MPa",
            top[0].value / 1e6
        );
    }
}

/// The committed spring meshes (`meshes/make_springs.py`) load with their groups, have the
/// expected volumes, and every cell has a positive Jacobian at its nodes (stress recovery of a
/// zero field evaluates there).
#[test]
fn spring_meshes_load_with_groups_and_valid_cells() {
    let leaf_volume = 0.169 * 0.146 * 0.009;
    let helix = 6.0 * (std::f64::consts::PI * 0.032f64).hypot(0.010);
    let wire_volume = std::f64::consts::PI * 0.006f64.powi(2) / 4.0 * helix;
    let meshes: [(&str, &[&str], f64, f64); 7] = [
        (
            "s3_leaf_hex20_10x6x1",
            &["leaf", "clamp_fixed", "clamp_guided", "top", "bottom"],
            leaf_volume,
            1e-12,
        ),
        (
            "s3_leaf_hex20_20x12x2",
            &["leaf", "clamp_fixed", "clamp_guided"],
            leaf_volume,
            1e-12,
        ),
        (
            "s3_leaf_hex20_40x24x4",
            &["leaf", "clamp_fixed", "clamp_guided"],
            leaf_volume,
            1e-12,
        ),
        (
            "s3_leaf_tet10_h9",
            &["leaf", "clamp_fixed", "clamp_guided"],
            leaf_volume,
            1e-12,
        ),
        (
            "s3_leaf_tet10_h6",
            &["leaf", "clamp_fixed", "clamp_guided"],
            leaf_volume,
            1e-12,
        ),
        (
            "s5_coil_tet10_h2p5",
            &["wire", "end_bottom", "end_top", "surface"],
            wire_volume,
            3e-3,
        ),
        (
            "s5_coil_tet10_h2",
            &["wire", "end_bottom", "end_top", "surface"],
            wire_volume,
            1e-3,
        ),
    ];
    for (name, groups, volume, tol) in meshes {
        let path = format!("{ROOT}/meshes/{name}.msh");
        let mesh = vibrofem::io::gmsh::read(std::path::Path::new(&path), 1.0).unwrap();
        for g in groups {
            let grp = mesh.group(g).unwrap();
            assert!(!mesh.group_nodes(grp).is_empty(), "{name}: group {g} is empty");
        }
        let m = model(&mesh, steel());
        let v: f64 = m
            .solids
            .iter()
            .map(|s| (0..s.tags.len()).map(|e| s.volume(e).unwrap()).sum::<f64>())
            .sum();
        assert!((v / volume - 1.0).abs() < tol, "{name}: volume {v:e} vs {volume:e}");
        let u = vec![0.0; 3 * mesh.n_nodes()];
        nodal_stress(&m.solids, mesh.n_nodes(), &u).unwrap();
        assert!(
            ns_all_nodes_used(&mesh, &m),
            "{name}: every node belongs to a volume cell"
        );
        if name.starts_with("s5") {
            // the end faces: disks of the wire at z = 0 and z = 6 pitches
            for (g, z) in [("end_bottom", 0.0), ("end_top", 0.06)] {
                let nodes = mesh.group_nodes(mesh.group(g).unwrap());
                let zc = nodes.iter().map(|&a| mesh.nodes[a as usize][2]).sum::<f64>() / nodes.len() as f64;
                assert!((zc - z).abs() < 1e-4, "{name} {g}: mean z {zc}");
            }
        }
    }
}

fn ns_all_nodes_used(mesh: &Mesh, m: &Model) -> bool {
    let mut used = vec![false; mesh.n_nodes()];
    for s in &m.solids {
        for &a in &s.conn {
            used[a as usize] = true;
        }
    }
    used.iter().all(|&u| u)
}
