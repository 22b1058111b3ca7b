//! Prestressed modes (`K + K_σ`) against closed forms, and the geometric stiffness kernels'
//! exact properties.
//!
//! Reference: a pinned–pinned Euler–Bernoulli beam under an axial force `P` (tension
//! positive) has the mode shapes `sin(nπx/L)` whatever `P`, and
//! `ω_n² ρA = EI (nπ/L)⁴ + P (nπ/L)²`, i.e.
//! `f_n = f_n0 √(1 + P L²/(n²π² EI))` (Blevins, *Formulas for Natural Frequency and Mode
//! Shape*, 1979, Table 8-16 "beams with axial load"; Timoshenko, Young and Weaver, *Vibration
//! Problems in Engineering*, 4th ed. 1974, §5.13). The frequency of mode 1 reaches zero at the
//! Euler load `P = −π² EI/L²`.

use std::f64::consts::PI;

use vibrofem::analysis::modal::{ModalOptions, ModalTarget};
use vibrofem::analysis::prestress::{PrestressRun, run_prestressed_modes};
use vibrofem::analysis::statics::Load;
use vibrofem::dof::DofMask;
use vibrofem::element::geometric;
use vibrofem::element::solid::Integration;
use vibrofem::material::Material;
use vibrofem::mesh::generate::box_mesh;
use vibrofem::mesh::{CellKind, Mesh};
use vibrofem::model::{BeamPart, CouplingSpec, ModelSpec, Orientation};
use vibrofem::section::BeamSection;

const UX: DofMask = 1;
const UY: DofMask = 2;
const UZ: DofMask = 4;
const RX: DofMask = 8;
const RZ: DofMask = 32;

fn run(mesh: &Mesh, spec: &ModelSpec, loads: Vec<Load>, n: usize) -> PrestressRun {
    let opts = ModalOptions {
        spec: spec.clone(),
        target: ModalTarget::Modes(n),
        ..Default::default()
    };
    let r = run_prestressed_modes(mesh, "test", &opts, &loads, 0.0).unwrap();
    let rep = &r.modal.report;
    assert!(
        rep.complete && rep.accurate,
        "unverified prestressed run: {:?}",
        rep.notes
    );
    assert!(
        r.statics.rel_residual < 1e-8,
        "static residual {}",
        r.statics.rel_residual
    );
    r
}

/// Beam: L = 1 m, rectangle b = 40 mm (local y = global y) × h = 10 mm (local z = global z),
/// steel; 40 line2 elements; held in the x–z plane (uy, rx, rz fixed everywhere), pinned at
/// both ends, axial translation held at end_a. Returns the mesh, the spec and E·Iy.
fn beam_model() -> (Mesh, ModelSpec, f64) {
    let mesh = vibrofem::mesh::parametric::i_beam_line(1.0, 40).unwrap();
    let sec = BeamSection::rectangle(0.04, 0.01);
    let spec = ModelSpec {
        beams: vec![BeamPart {
            group: "beam".into(),
            section: sec,
            orientation: Orientation::Vector([0.0, 1.0, 0.0]),
            material: None,
        }],
        fixes: vec![
            ("beam".into(), UY | RX | RZ),
            ("end_a".into(), UX | UZ),
            ("end_b".into(), UZ),
        ],
        ..Default::default()
    };
    let ei = Material::steel().young * sec.iy;
    (mesh, spec, ei)
}

fn axial(group: &str, p: f64) -> Vec<Load> {
    vec![Load::Force {
        group: group.into(),
        force: [p, 0.0, 0.0],
    }]
}

/// f_n(P)/f_n(0) of the Euler–Bernoulli beam.
fn ratio(p: f64, l: f64, ei: f64, n: usize) -> f64 {
    (1.0 + p * l * l / ((n * n) as f64 * PI * PI * ei)).sqrt()
}

#[test]
fn prestress_pinned_beam_in_tension_and_compression() {
    // Tolerance 0.5 % (the issue's): the 40-element Timoshenko beam of L/h = 100 differs from
    // the Euler–Bernoulli closed form by shear and rotary inertia, (nπ r/L)²(1 + E/κG)/2 ≈
    // 1.5e-3 on f_3 (r² = h²/12), and by discretisation, below 1e-4 with the exact
    // (interdependent) element; in the ratio f_n(P)/f_n(0) these largely cancel. Measured
    // worst deviation 1.5e-3 (printed).
    let (mesh, spec, ei) = beam_model();
    let l = 1.0;
    let p_cr = PI * PI * ei / (l * l);
    let f0 = run(&mesh, &spec, vec![], 3).modal.report.frequencies_hz.clone();
    // Unloaded: f_n0 = (n²π/2L²) √(EI/ρA).
    let sec = BeamSection::rectangle(0.04, 0.01);
    let rho_a = Material::steel().density * sec.area;
    let mut worst: f64 = 0.0;
    for n in 1..=3 {
        let exact = (n * n) as f64 * PI / (2.0 * l * l) * (ei / rho_a).sqrt();
        let e = (f0[n - 1] / exact - 1.0).abs();
        worst = worst.max(e);
        assert!(e < 5e-3, "unloaded f{n}: {} Hz against {exact} Hz", f0[n - 1]);
    }
    for factor in [2.0, -0.5] {
        let p = factor * p_cr;
        let r = run(&mesh, &spec, axial("end_b", p), 3);
        let f = &r.modal.report.frequencies_hz;
        for n in 1..=3 {
            let expect = f0[n - 1] * ratio(p, l, ei, n);
            let e = (f[n - 1] / expect - 1.0).abs();
            worst = worst.max(e);
            assert!(
                e < 5e-3,
                "P = {factor} P_cr, mode {n}: {} Hz against {expect} Hz",
                f[n - 1]
            );
        }
        // The preload: axial stress P/A everywhere.
        let s = p / sec.area;
        let (hi, lo) = (r.tension.value, r.compression.value);
        let got = if p > 0.0 { hi } else { lo };
        assert!((got / s - 1.0).abs() < 1e-9, "axial stress {got} against {s}");
    }
    eprintln!("beam prestress: worst deviation from the closed form {worst:.2e}");
}

#[test]
fn prestress_first_frequency_vanishes_at_the_euler_load() {
    // For the pinned–pinned beam λ_1 = ω_1² is linear in P (the mode shape does not change),
    // so λ_1(P) at two loads extrapolates to its zero, the buckling load of the discrete model.
    // It must be the Euler load π²EI/L² to 0.1 %: the Timoshenko beam's buckling load is
    // P_E/(1 + P_E/κGA), lower by P_E/κGA = 1e-4 here, and the 40-element discretisation adds
    // less than 1e-5.
    let (mesh, spec, ei) = beam_model();
    let p_e = PI * PI * ei;
    let lam = |p: f64| {
        let r = run(&mesh, &spec, axial("end_b", p), 1);
        r.modal.report.modes[0].eigenvalue
    };
    let l0 = lam(0.0);
    let mut prev = 1.0;
    for frac in [0.5, 0.9, 0.99] {
        let l1 = lam(-frac * p_e);
        let f_ratio = (l1 / l0).sqrt();
        // Closed form √(1 − P/P_E), within the 1e-4 shift of the buckling load above.
        let expect = (1.0 - frac).sqrt();
        assert!(f_ratio < prev, "f1 must fall with the load: {f_ratio} after {prev}");
        assert!(
            (f_ratio * f_ratio - expect * expect).abs() < 1e-3,
            "P = {frac} P_E: f1/f10 = {f_ratio}, closed form {expect}"
        );
        prev = f_ratio;
    }
    let l1 = lam(-0.5 * p_e);
    let p_zero = 0.5 * p_e * l0 / (l0 - l1);
    assert!(
        (p_zero / p_e - 1.0).abs() < 1e-3,
        "λ1 vanishes at {p_zero} N, Euler load {p_e} N"
    );
}

/// The hex20 bar: L = 0.5 m, b = 30 mm (y), h = 10 mm (z), 40 × 3 × 1 cells; each end face
/// rigidly coupled to a reference node at its centre, pinned there (translations held, and
/// the twist at xmin; the ends rotate freely about y and z), axial translation held at xmin.
fn bar_model() -> (Mesh, ModelSpec, f64, f64) {
    let (l, b, h) = (0.5, 0.03, 0.01);
    let mesh = box_mesh(CellKind::Hex20, [l, b, h], [40, 3, 1]);
    let coupling = |g: &str| CouplingSpec {
        group: g.into(),
        guided: None,
        reference: None,
    };
    let spec = ModelSpec {
        couplings: vec![coupling("xmin"), coupling("xmax")],
        // A coupled group is held through its reference node: zero prescribed displacements.
        prescribed: vec![
            ("xmin".into(), [Some(0.0), Some(0.0), Some(0.0), Some(0.0), None, None]),
            ("xmax".into(), [None, Some(0.0), Some(0.0), None, None, None]),
        ],
        ..Default::default()
    };
    let ei = Material::steel().young * b * h * h * h / 12.0;
    (mesh, spec, ei, l)
}

/// Frequencies of the modes bending in the x–z plane (uz dominant), in order.
fn z_bending(r: &PrestressRun) -> Vec<f64> {
    let rep = &r.modal.report;
    let mut out = Vec::new();
    for (k, s) in r.modal.shapes.iter().enumerate() {
        let mut e = [0.0; 3];
        for (i, v) in s.iter().enumerate() {
            e[i % 3] += v * v;
        }
        if e[2] > 0.9 * (e[0] + e[1] + e[2]) {
            out.push(rep.frequencies_hz[k]);
        }
    }
    out
}

#[test]
fn prestress_pinned_hex20_bar_in_tension_and_compression() {
    // Tolerance 1 % on f_n(P)/f_n(0): the solid's shear flexibility changes the factor
    // P L²/(n²π²EI) by (nπ/L)² EI/(κGA) ≈ 1 % at n = 3 (L/h = 50), i.e. the ratio by less than
    // 0.1 %; the rigid end faces and the one-element thickness (hex20 bends exactly
    // there) add less. Measured worst deviation 4.2e-3 (printed).
    let (mesh, spec, ei, l) = bar_model();
    let p_cr = PI * PI * ei / (l * l);
    let base = run(&mesh, &spec, vec![], 8);
    let f0 = z_bending(&base);
    assert!(f0.len() >= 3, "z-bending modes of the bar: {f0:?}");
    let mut worst: f64 = 0.0;
    for factor in [2.0, -0.5] {
        let r = run(&mesh, &spec, axial("xmax", factor * p_cr), 8);
        let f = z_bending(&r);
        for n in 1..=3 {
            let expect = f0[n - 1] * ratio(factor * p_cr, l, ei, n);
            let e = (f[n - 1] / expect - 1.0).abs();
            worst = worst.max(e);
            assert!(
                e < 1e-2,
                "P = {factor} P_cr, mode {n}: {} Hz against {expect} Hz",
                f[n - 1]
            );
        }
    }
    eprintln!("hex20 bar prestress: worst deviation from the closed form {worst:.2e}");
}

// ---------------------------------------------------------------------------------------------
// Kernel properties

fn unit_box(kind: CellKind) -> Vec<[f64; 3]> {
    // The reference cell under a sheared, stretched affine map: every integrand of K_σ under a
    // uniform stress is then a polynomial the stiffness rule integrates exactly.
    vibrofem::fe::shape::reference_nodes(kind)
        .iter()
        .map(|q| {
            [
                0.3 * q[0] + 0.02 * q[1] + 1.0,
                0.2 * q[1] + 0.03 * q[2] - 0.5,
                0.25 * q[2] + 0.01 * q[0],
            ]
        })
        .collect()
}

const SOLIDS: [CellKind; 7] = [
    CellKind::Tet4,
    CellKind::Tet10,
    CellKind::Hex8,
    CellKind::Hex20,
    CellKind::Hex27,
    CellKind::Wedge6,
    CellKind::Wedge15,
];

#[test]
fn prestress_solid_kernel_is_symmetric_and_ignores_rigid_translations() {
    // Exact properties (to rounding): K_σ is symmetric for any stress, and a rigid translation
    // has no displacement gradient, so K_σ·u = 0.
    for kind in SOLIDS {
        let x = unit_box(kind);
        let n = x.len();
        let rule = geometric::solid_rule(kind, Integration::Straight).unwrap();
        let sigma: Vec<[f64; 6]> = (0..rule.len())
            .map(|q| {
                let t = q as f64;
                [3e6 + t, -2e6, 1e6 * t, 0.5e6, -0.7e6 + t, 0.9e6]
            })
            .collect();
        let mut kg = vec![0.0; 9 * n * n];
        geometric::solid(kind, &x, Integration::Straight, &sigma, &mut kg).unwrap();
        let nd = 3 * n;
        let scale = kg.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..nd {
            for j in 0..nd {
                assert!(
                    (kg[i * nd + j] - kg[j * nd + i]).abs() <= 1e-13 * scale,
                    "{kind}: not symmetric"
                );
            }
        }
        for d in 0..3 {
            for i in 0..nd {
                let r: f64 = (0..n).map(|b| kg[i * nd + 3 * b + d]).sum();
                assert!(
                    r.abs() <= 1e-12 * scale,
                    "{kind}: K_σ·(translation {d}) = {r} at row {i}"
                );
            }
        }
    }
}

#[test]
fn prestress_solid_kernel_patch_uniaxial_stress() {
    // Patch property: for a uniform σ_xx = σ, K_σ = σ ∫ ∂N_a/∂x ∂N_b/∂x dV on each component
    // and 0 between components. The integral is formed here independently: by a rule of much
    // higher degree (12) than the stiffness rule; on an affine cell both are exact, so they
    // agree to rounding.
    let sigma = 7.5e6;
    for kind in SOLIDS {
        let x = unit_box(kind);
        let n = x.len();
        let rule = geometric::solid_rule(kind, Integration::Straight).unwrap();
        let mut kg = vec![0.0; 9 * n * n];
        geometric::solid(
            kind,
            &x,
            Integration::Straight,
            &vec![[sigma, 0.0, 0.0, 0.0, 0.0, 0.0]; rule.len()],
            &mut kg,
        )
        .unwrap();
        let fine = vibrofem::fe::quadrature::for_cell(kind, 12);
        let mut s = vec![0.0; n * n];
        let mut dn = vec![[0.0; 3]; n];
        for (p, w) in fine.points.iter().zip(&fine.weights) {
            vibrofem::fe::shape::gradients(kind, *p, &mut dn);
            let (det, inv) = vibrofem::fe::geometry::volume_jacobian(&x, &dn).unwrap();
            let g: Vec<[f64; 3]> = dn
                .iter()
                .map(|d| vibrofem::fe::geometry::physical_gradient(&inv, *d))
                .collect();
            for a in 0..n {
                for b in 0..n {
                    s[a * n + b] += w * det * g[a][0] * g[b][0];
                }
            }
        }
        let nd = 3 * n;
        let scale = s.iter().fold(0.0f64, |m, v| m.max(v.abs())) * sigma;
        let tol = 1e-12;
        for a in 0..n {
            for b in 0..n {
                for i in 0..3 {
                    for j in 0..3 {
                        let got = kg[(3 * a + i) * nd + 3 * b + j];
                        let want = if i == j { sigma * s[a * n + b] } else { 0.0 };
                        assert!(
                            (got - want).abs() <= tol * scale,
                            "{kind} ({a},{b}) components ({i},{j}): {got} against {want}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn prestress_shell_kernel_uniform_membrane_force() {
    // A unit square MITC4 under a uniform N_11 = N (e1 = x here): on each translation the
    // matrix is N ∫ ∂N_a/∂x ∂N_b/∂x dA, for the bilinear square (1/6)[2 −2 −1 1; −2 2 1 −1;
    // −1 1 2 −2; 1 −1 −2 2] (closed form; the 2 × 2 rule is exact on it); nothing on the
    // rotations without offset, and K_σ·(rigid translation) = 0. Exact to rounding.
    let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let n = 3.0e4;
    let m = [
        [2.0, -2.0, -1.0, 1.0],
        [-2.0, 2.0, 1.0, -1.0],
        [-1.0, 1.0, 2.0, -2.0],
        [1.0, -1.0, -2.0, 2.0],
    ];
    let sec = vibrofem::section::ShellSection::new(0.01);
    let mut kg = [0.0; 576];
    geometric::shell(CellKind::Quad4, &x, &sec, &[[n, 0.0, 0.0]; 4], &mut kg).unwrap();
    for a in 0..4 {
        for b in 0..4 {
            for i in 0..6 {
                for j in 0..6 {
                    let got = kg[(6 * a + i) * 24 + 6 * b + j];
                    let want = if i == j && i < 3 { n * m[a][b] / 6.0 } else { 0.0 };
                    assert!(
                        (got - want).abs() <= 1e-12 * n,
                        "({a},{b}) ({i},{j}): {got} against {want}"
                    );
                }
            }
        }
    }
}

#[test]
fn prestress_simply_supported_plate_in_tension() {
    // MITC4 plate a = b = 1 m, t = 10 mm, simply supported (uz held on the four edges),
    // stretched along x by a prescribed edge displacement: a uniform N_x = E t ε (uniaxial:
    // the y edges are free to contract). Mode (1,1): ω² ρt = D π⁴ (2/a²)² + N_x π²/a²
    // (Timoshenko and Woinowsky-Krieger; Leissa, Vibration of Plates, NASA SP-160, 1969, §4.1
    // "in-plane forces"), so f/f0 = √(1 + N_x/(4π²D)); ε is chosen to make that √2.
    let (a, t): (f64, f64) = (1.0, 0.01);
    let mat = Material::steel();
    let d = mat.young * t.powi(3) / (12.0 * (1.0 - mat.poisson * mat.poisson));
    let nx = 4.0 * PI * PI * d;
    let eps = nx / (mat.young * t);
    let mesh = box_mesh(CellKind::Hex8, [a, a, t], [16, 16, 1]);
    let spec = ModelSpec {
        solid_groups: Some(vec![]),
        shells: vec![vibrofem::model::ShellPart {
            group: "zmin".into(),
            section: vibrofem::section::ShellSection::new(t),
            material: None,
        }],
        fixes: vec![
            ("xmin".into(), UX | UZ),
            ("ymin".into(), UY | UZ),
            ("ymax".into(), UZ),
            ("xmax".into(), UZ),
        ],
        prescribed: vec![("xmax".into(), [Some(eps * a), None, None, None, None, None])],
        ..Default::default()
    };
    let unloaded = ModelSpec {
        prescribed: vec![],
        ..spec.clone()
    };
    let f0 = run(&mesh, &unloaded, vec![], 1).modal.report.frequencies_hz[0];
    let r = run(&mesh, &spec, vec![], 1);
    let f = r.modal.report.frequencies_hz[0];
    eprintln!("plate prestress: f0 {f0} Hz, f {f} Hz, ratio {}", f / f0);
    // Tolerance 1 %: the 16 × 16 mesh resolves the (1,1) half-waves with 16 cells each (its
    // unloaded f_11 is 0.3 % above the closed form), and the membrane state is uniform.
    // Measured: f/f0 = 1.41305, 8e-4 below √2.
    assert!((f / f0 / 2f64.sqrt() - 1.0).abs() < 1e-2, "f/f0 = {}", f / f0);
    assert!(
        (r.tension.value / (nx / t) - 1.0).abs() < 1e-6,
        "membrane stress {:?}",
        r.tension
    );
}
