//! Validation of modal analysis against independent references.
//!
//! 1. scikit-fem on the very same gmsh meshes (`validation/reference/*.json`, produced by
//!    `validation/skfem_modes.py`): same mesh, same element, consistent mass, exact
//!    quadrature on both sides → the same discrete eigenproblem. Elastic frequencies must agree
//!    to 1e-6 relative (both solvers converge eigenvalues to ~1e-10; 1e-6 is the project's
//!    "same discrete problem" criterion and leaves room for ARPACK's tolerance).
//! 2. Analytic beam theory (Euler–Bernoulli with a Timoshenko correction) on generated meshes.
//! 3. Repeated eigenvalues: triple roots of a free cube, pairs of a square bar.

use vibrofem::analysis::modal::{ModalOptions, ModalTarget, run_modal};
use vibrofem::dof::TRANSLATIONS;
use vibrofem::input::source;
use vibrofem::material::Material;
use vibrofem::model::ModelSpec;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn solve(mesh_spec: &str, scale: f64, mat: Material, fix: &[&str], n: usize) -> vibrofem::analysis::modal::ModalReport {
    let mesh = source::load(mesh_spec, scale).unwrap();
    let spec = ModelSpec {
        material: mat,
        fixes: fix.iter().map(|g| (g.to_string(), TRANSLATIONS)).collect(),
        ..Default::default()
    };
    let opts = ModalOptions {
        spec,
        target: ModalTarget::Modes(n),
        ..Default::default()
    };
    run_modal(&mesh, mesh_spec, &opts, 0.0).unwrap().report
}

#[test]
fn scikit_fem_same_mesh_same_element() {
    let dir = format!("{ROOT}/validation/reference");
    let mut cases: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            // Modal references only (the static_*, harmonic_* and two_mass_* files have their own
            // tests).
            p.extension().is_some_and(|e| e == "json")
                && !name.starts_with("two_mass")
                && !name.starts_with("static_")
                && !name.starts_with("harmonic_")
        })
        .collect();
    cases.sort();
    assert!(
        cases.len() >= 15,
        "expected the committed scikit-fem references in {dir}"
    );
    let mut worst = 0.0f64;
    for case in &cases {
        let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(case).unwrap()).unwrap();
        let mesh = format!("{ROOT}/{}", r["mesh"].as_str().unwrap());
        let scale = if r["length_unit"].as_str() == Some("mm") {
            1e-3
        } else {
            1.0
        };
        let m = &r["material"];
        let mat = Material {
            young: m["young"].as_f64().unwrap(),
            poisson: m["poisson"].as_f64().unwrap(),
            density: m["density"].as_f64().unwrap(),
        };
        let fixed: Vec<String> = r["fixed_groups"]
            .as_array()
            .unwrap()
            .iter()
            .map(|g| g.as_str().unwrap().to_string())
            .collect();
        let fixed: Vec<&str> = fixed.iter().map(|s| s.as_str()).collect();
        let reff: Vec<f64> = r["frequencies_hz"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let n_rigid = r["n_rigid"].as_u64().unwrap() as usize;
        let rep = solve(&mesh, scale, mat, &fixed, reff.len());
        let name = case.file_name().unwrap().to_string_lossy();
        assert_eq!(rep.dofs as u64, r["dofs"].as_u64().unwrap(), "{name}: dofs");
        assert_eq!(rep.n_rigid, n_rigid, "{name}: rigid-body modes");
        assert!(
            rep.complete && rep.accurate,
            "{name}: verification failed: {:?}",
            rep.notes
        );
        // Mass: exact integration on both sides.
        let mref = r["mass_kg"].as_f64().unwrap();
        assert!(
            (rep.mass_kg - mref).abs() <= 1e-9 * mref,
            "{name}: mass {} vs {mref}",
            rep.mass_kg
        );
        for (i, (&got, &want)) in rep.frequencies_hz.iter().zip(&reff).enumerate().skip(n_rigid) {
            let rel = (got - want).abs() / want;
            worst = worst.max(rel);
            assert!(
                rel <= 1e-6,
                "{name}: mode {} {got} Hz vs scikit-fem {want} Hz (rel {rel:.2e})",
                i + 1
            );
        }
        // Rigid-body modes are at rounding level on both sides: below 1e-3 of the first
        // elastic frequency.
        for &f in &rep.frequencies_hz[..n_rigid] {
            assert!(f.abs() < 1e-3 * reff[n_rigid], "{name}: rigid mode at {f} Hz");
        }
    }
    eprintln!("{} cases, worst relative difference {worst:.2e}", cases.len());
}

/// Square steel bar, h = 10 mm, L = 400 mm (L/h = 40), hex20 80×2×2.
/// Reference: Euler–Bernoulli f = (βL)²/(2πL²)·√(EI/ρA).
const L: f64 = 0.4;
const H: f64 = 0.01;

fn eb(beta_l: f64) -> f64 {
    let (e, rho) = (2.1e11, 7850.0);
    let (i, a) = (H.powi(4) / 12.0, H * H);
    beta_l * beta_l / (2.0 * std::f64::consts::PI * L * L) * (e * i / (rho * a)).sqrt()
}

#[test]
fn free_free_bar_matches_timoshenko_and_has_pairs() {
    let rep = solve("box:0.4,0.01,0.01:80,2,2:hex20", 1.0, Material::steel(), &[], 10);
    assert_eq!(rep.n_rigid, 6);
    let f = &rep.frequencies_hz;
    // Square section: bending in y and z are the same eigenvalue (a pair); block Lanczos must
    // return both copies. They agree to rounding (1e-9).
    assert!(
        (f[6] - f[7]).abs() <= 1e-9 * f[6] && (f[8] - f[9]).abs() <= 1e-9 * f[8],
        "{f:?}"
    );
    // First free–free root βL = 4.730041 with the first-order Timoshenko correction
    // (shear and rotary inertia): f ≈ f_EB·[1 − ½(βL)²(r/L)²(1 + E/(κG))], r² = I/A, κ = 5/6.
    // Neglected terms are O((βL r/L)⁴) ≈ 1e-6; the hex20 80×2×2 mesh error is ~1e-4 (it
    // changes by less than that on refinement). Tolerance 5e-4.
    let r2 = H * H / 12.0;
    let (e, g) = (2.1e11, 2.1e11 / 2.6);
    let bl: f64 = 4.730040744862704;
    let ft = eb(bl) * (1.0 - 0.5 * bl * bl * r2 / (L * L) * (1.0 + e / (5.0 / 6.0 * g)));
    let rel = (f[6] - ft).abs() / ft;
    assert!(rel < 5e-4, "f7 {} vs Timoshenko {ft} (rel {rel:.2e})", f[6]);
}

#[test]
fn cantilever_matches_euler_bernoulli() {
    let rep = solve("box:0.4,0.01,0.01:80,2,2:hex20", 1.0, Material::steel(), &["xmin"], 4);
    assert_eq!(rep.n_rigid, 0);
    let f = &rep.frequencies_hz;
    assert!((f[0] - f[1]).abs() <= 1e-8 * f[0], "bending pair {f:?}");
    // First cantilever root βL = 1.8751. Two effects of opposite sign remain: the Timoshenko
    // correction (≈ −0.03 % at L/h = 40) and the fully clamped 3D root face, which also
    // stops Poisson contraction there (≈ +0.1 %). Tolerance 0.3 %.
    let fe = eb(1.875104068711961);
    assert!((f[0] - fe).abs() / fe < 3e-3, "f1 {} vs {fe}", f[0]);
    // Second bending root βL = 4.694091: f2/f1 = (4.694091/1.875104)² = 6.267 (the first
    // torsion and axial modes lie in between, so look it up by value).
    let f2 = eb(4.694091132974174);
    assert!(f.iter().all(|&x| x < f2 * 1.1), "only the lowest 4 requested");
}

#[test]
fn free_cube_has_triple_roots_and_all_copies_are_found() {
    // A free cube's spectrum has exact triples (cubic symmetry). Request enough modes to
    // cut through several multiplets; the Sturm count proves none was skipped.
    let rep = solve(
        &format!("{ROOT}/meshes/cube_hex20_4x4x4.msh"),
        1.0,
        Material::steel(),
        &[],
        30,
    );
    assert!(rep.complete);
    let f = &rep.frequencies_hz[6..];
    let mut triples = 0;
    let mut i = 0;
    while i < f.len() {
        let mut j = i + 1;
        while j < f.len() && (f[j] - f[i]).abs() <= 1e-7 * f[i] {
            j += 1;
        }
        if j - i == 3 {
            triples += 1;
        }
        i = j;
    }
    assert!(triples >= 3, "expected several triple roots: {f:?}");
}

#[test]
fn mm_and_m_meshes_give_identical_frequencies() {
    let a = solve(
        &format!("{ROOT}/meshes/s1_plate_tet10_h30.msh"),
        1.0,
        Material::steel(),
        &[],
        10,
    );
    let b = solve(
        &format!("{ROOT}/meshes/s1_plate_tet10_h30_mm.msh"),
        1e-3,
        Material::steel(),
        &[],
        10,
    );
    for (x, y) in a.frequencies_hz.iter().zip(&b.frequencies_hz).skip(6) {
        // The mm file was written by gmsh with its own rounding of coordinates, so the
        // meshes differ at ~1e-12; frequencies then agree to ~1e-10.
        assert!((x - y).abs() <= 1e-8 * x, "{x} vs {y}");
    }
}

#[test]
fn lumped_mass_converges_to_the_same_frequency() {
    // HRZ lumping changes the discrete problem; on a fine hex20 plate the first elastic
    // frequency moves by well under 1 % and lies below the consistent-mass value (a lumped
    // mass lowers quadratic-element frequencies for bending modes).
    let mesh = "box:0.3,0.3,0.02:12,12,2:hex20";
    let c = solve(mesh, 1.0, Material::steel(), &[], 7);
    let m = source::load(mesh, 1.0).unwrap();
    let spec = ModelSpec {
        lumping: vibrofem::element::MassLumping::Lumped,
        ..Default::default()
    };
    let opts = ModalOptions {
        spec,
        target: ModalTarget::Modes(7),
        ..Default::default()
    };
    let l = run_modal(&m, mesh, &opts, 0.0).unwrap().report;
    assert_eq!(l.n_rigid, 6);
    assert!(l.complete && l.accurate);
    let (fc, fl) = (c.frequencies_hz[6], l.frequencies_hz[6]);
    assert!((fc - fl).abs() / fc < 1e-2, "consistent {fc} lumped {fl}");
    assert!((c.mass_kg - l.mass_kg).abs() < 1e-12 * c.mass_kg);
}

#[test]
fn effective_masses_sum_to_the_total_mass() {
    // With every mode of a small model the cumulative effective mass reaches exactly the
    // total mass (completeness of the M-orthonormal basis); rigid-body modes alone carry it
    // all for a free body.
    let rep = solve("box:0.1,0.05,0.02:2,1,1:hex8", 1.0, Material::steel(), &[], 6);
    let last = rep.modes.last().unwrap().cumulative_ratio;
    for (d, v) in last.iter().enumerate() {
        assert!((v - 1.0).abs() < 1e-9, "direction {d}: {v}");
    }
    let total_mass = rep.participation_total[0];
    assert!((total_mass - 0.1 * 0.05 * 0.02 * 7850.0).abs() < 1e-9 * total_mass);
}
