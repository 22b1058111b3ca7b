//! Numerical extremes (issue 7, scope 2): each test states the accuracy it expects and why.
//!
//! Every model is small (a few thousand DOFs at most) so that the whole file runs in seconds.
//! References are either exact (static condensation, integer spring chains), an independent
//! solve of the very same K and M (the dense path), an equivalent model (rigid limit, unit
//! change), or classical theory (Euler–Bernoulli/Timoshenko beams, Kirchhoff plates).
//!
//! Some extremes expose solver defects (reported with the test that shows each). Those tests
//! assert what must hold today — a run either is verified *and* right, or fails with exit
//! code 2 / flags its report — and print `KNOWN BUG` when they take the failure branch.
//! Once a defect is fixed, the failure branch of its test should be removed.

use crate::common::rel;
use std::f64::consts::PI;
use std::process::Command;
use std::sync::Arc;
use vibrofem::analysis::modal::{ModalOptions, ModalReport, ModalTarget, run_modal};
use vibrofem::dof::TRANSLATIONS;
use vibrofem::element::MassLumping;
use vibrofem::input::source;
use vibrofem::linalg::eigen::{EigenParams, EigenSolution, Target, solve};
use vibrofem::linalg::factor::{Factor, SymbolicFactor};
use vibrofem::linalg::sparse::SymMatrix;
use vibrofem::material::Material;
use vibrofem::mesh::generate::box_mesh;
use vibrofem::mesh::{CellKind, CellRef, Group, Mesh};
use vibrofem::model::{CouplingSpec, Model, ModelSpec, PointMassSpec, ShellPart, SpringSpec};
use vibrofem::post::modal::{hz, lambda_of_hz};
use vibrofem::section::ShellSection;
use vibrofem::system::{System, SystemOptions};

// ---------------------------------------------------------------------------------------------
// helpers

fn mat(e: f64, nu: f64, rho: f64) -> Material {
    Material {
        young: e,
        poisson: nu,
        density: rho,
    }
}

fn modal(mesh: &Mesh, name: &str, spec: ModelSpec, target: ModalTarget, shift_hz: Option<f64>) -> ModalReport {
    let opts = ModalOptions {
        spec,
        target,
        shift_hz,
        ..Default::default()
    };
    run_modal(mesh, name, &opts, 0.0).unwrap().report
}

fn fixed(groups: &[&str]) -> Vec<(String, u8)> {
    groups.iter().map(|g| (g.to_string(), TRANSLATIONS)).collect()
}

/// The verified report's own checks: every residual small, modes M-orthonormal, Sturm count
/// complete, nothing flagged.
fn assert_verified(what: &str, r: &ModalReport, max_res: f64) {
    assert!(r.complete, "{what}: Sturm check {:?} notes {:?}", r.sturm, r.notes);
    assert!(
        r.sturm.complete && r.sturm.expected == r.sturm.found,
        "{what}: {:?}",
        r.sturm
    );
    assert!(r.accurate, "{what}: notes {:?}", r.notes);
    assert!(
        r.max_rel_residual < max_res,
        "{what}: largest residual {:.2e} (wanted < {max_res:.0e})",
        r.max_rel_residual
    );
    assert!(
        r.m_orthonormality < 1e-8,
        "{what}: M-orthonormality {:.2e}",
        r.m_orthonormality
    );
    assert!(
        r.frequencies_hz.iter().all(|f| f.is_finite()),
        "{what}: {:?}",
        r.frequencies_hz
    );
}

/// K and M of a model, exactly as `run_modal` assembles them (through its `System`).
fn assemble_km(mesh: &Mesh, spec: &ModelSpec) -> (SymMatrix, SymMatrix) {
    let model = Model::build(mesh, spec, "test").unwrap();
    let sys = System::build(model, &SystemOptions::default(), "test").unwrap();
    (sys.k().clone(), sys.m().unwrap().clone())
}

/// The dense oracle on the same K and M (every finite eigenvalue, exact to rounding).
fn dense_reference(k: &SymMatrix, m: &SymMatrix, n: usize) -> EigenSolution {
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let p = EigenParams {
        target: Target::Nearest(n),
        dense_below: usize::MAX,
        ..Default::default()
    };
    solve(k, m, &sym, &p).unwrap()
}

/// Adds the volume groups "left" (cell centroid x < cut) and "right" (the rest): `box_mesh`
/// has a single "volume" group.
fn split_by_x(mesh: &mut Mesh, cut: f64) {
    let (mut left, mut right) = (Vec::new(), Vec::new());
    for (bi, b) in mesh.blocks.iter().enumerate() {
        if b.kind.dim() != 3 {
            continue;
        }
        for i in 0..b.len() {
            let c = b.cell(i);
            let xc = c.iter().map(|&a| mesh.nodes[a as usize][0]).sum::<f64>() / c.len() as f64;
            let r = CellRef {
                block: bi as u32,
                index: i as u32,
            };
            if xc < cut { left.push(r) } else { right.push(r) }
        }
    }
    let tag = mesh.groups.iter().map(|g| g.tag).max().unwrap_or(0);
    for (k, (name, cells)) in [("left", left), ("right", right)].into_iter().enumerate() {
        assert!(!cells.is_empty());
        mesh.groups.push(Group {
            name: name.into(),
            dim: 3,
            tag: tag + 1 + k as i32,
            cells,
        });
    }
}

/// Adds a free node at `x` with a one-node group `name` (a point cell).
fn add_point(mesh: &mut Mesh, name: &str, x: [f64; 3]) {
    let a = mesh.nodes.len() as u32;
    mesh.nodes.push(x);
    let tag = mesh.node_tags.iter().copied().max().unwrap_or(0) + 1;
    mesh.node_tags.push(tag);
    let bi = mesh.block_index_mut(CellKind::Point1);
    let etag = mesh
        .blocks
        .iter()
        .flat_map(|b| b.tags.iter().copied())
        .max()
        .unwrap_or(0)
        + 1;
    mesh.blocks[bi].push(&[a], etag);
    let gtag = mesh.groups.iter().map(|g| g.tag).max().unwrap_or(0) + 1;
    mesh.groups.push(Group {
        name: name.into(),
        dim: 0,
        tag: gtag,
        cells: vec![CellRef {
            block: bi as u32,
            index: (mesh.blocks[bi].len() - 1) as u32,
        }],
    });
}

/// `[1.2e-3, ...]` for messages.
fn sci(v: &[f64]) -> String {
    let s: Vec<String> = v.iter().map(|x| format!("{x:.1e}")).collect();
    format!("[{}]", s.join(", "))
}

fn residuals(r: &ModalReport) -> String {
    sci(&r.modes.iter().map(|m| m.rel_residual).collect::<Vec<_>>())
}

/// A report that failed its own checks must say so in its notes (the CLI then exits with 2).
fn assert_flagged(what: &str, r: &ModalReport) {
    assert!(!(r.complete && r.accurate), "{what}: not flagged");
    assert!(
        r.notes
            .iter()
            .any(|n| n.contains("accuracy not guaranteed") || n.contains("Sturm check failed")),
        "{what}: flagged report without a note: {:?}",
        r.notes
    );
}

// ---------------------------------------------------------------------------------------------
// free–free: default shift, and a user shift exactly on an eigenvalue

const PLATE: &str = "box:0.3,0.3,0.02:4,4,1:hex20"; // 465 DOFs: above the dense cut-off (300)

#[test]
fn free_free_default_shift_gives_six_rigid_modes_and_the_exact_first_elastic_one() {
    let mesh = source::load(PLATE, 1.0).unwrap();
    let spec = ModelSpec::default();
    let r = modal(&mesh, PLATE, spec.clone(), ModalTarget::Modes(10), None);
    assert_verified("free plate", &r, 1e-8);
    // Exactly six rigid-body modes: classified by shape, and numerically zero. Their
    // eigenvalues carry the rounding of a factor of K − σM with σ = −1e-7·median(Kii/Mii),
    // about |σ|·1e-9 here; anything above 1e-6·λ7 would be a spurious soft mode.
    assert_eq!(r.n_rigid, 6, "{:?}", r.frequencies_hz);
    let l7 = r.modes[6].eigenvalue;
    for m in &r.modes[..6] {
        assert_eq!(m.kind, "rigid");
        assert!(
            m.eigenvalue.abs() < 1e-6 * l7,
            "rigid mode {}: λ = {:e}",
            m.mode,
            m.eigenvalue
        );
    }
    assert!(r.modes[6..].iter().all(|m| m.kind == "elastic"));
    // Reference: the dense generalised eigensolver on the very same K and M. Lanczos converges
    // θ to 1e-10 (λ to ~tol² relative), the dense solver is exact to ~1e-13: 1e-9 relative.
    let (k, m) = assemble_km(&mesh, &spec);
    let d = dense_reference(&k, &m, 10);
    for i in 6..10 {
        let e = rel(r.modes[i].eigenvalue, d.lambda[i]);
        eprintln!(
            "free plate mode {}: {:.9} Hz, dense {:.9} Hz, rel {e:.1e}",
            i + 1,
            r.frequencies_hz[i],
            hz(d.lambda[i])
        );
        assert!(
            e < 1e-9,
            "mode {}: {} vs dense {}",
            i + 1,
            r.modes[i].eigenvalue,
            d.lambda[i]
        );
    }
    eprintln!(
        "free plate: shift {:e}, rigid λ max {:e}, λ7 {:e}, max residual {:.2e}",
        r.shift,
        r.modes[..6].iter().map(|m| m.eigenvalue.abs()).fold(0.0, f64::max),
        l7,
        r.max_rel_residual
    );
}

#[test]
fn user_shift_on_an_eigenvalue_gives_verified_modes_or_says_so() {
    // Compute λ7 of the free plate, then ask for the 4 modes nearest f7 exactly.
    let mesh = source::load(PLATE, 1.0).unwrap();
    let spec = ModelSpec::default();
    let first = modal(&mesh, PLATE, spec.clone(), ModalTarget::Modes(7), None);
    let f7 = first.frequencies_hz[6];
    let (k, m) = assemble_km(&mesh, &spec);
    let d = dense_reference(&k, &m, 12);
    let nearest = |sigma: f64| {
        let mut v = d.lambda.clone();
        v.sort_by(|a, b| (a - sigma).abs().total_cmp(&(b - sigma).abs()));
        v.truncate(4);
        v.sort_by(f64::total_cmp);
        v
    };
    let l7 = d.lambda[6];
    let check = |what: &str, r: &ModalReport| {
        // The four modes nearest the shift: λ7 and three rigid-body modes (λ8 ≈ 2.2 λ7 is
        // farther than 0). λ7 equal to the dense reference to 1e-9 (Lanczos tolerance 1e-10
        // on θ; the dense solver is exact to ~1e-13), the rigid ones zero to 1e-6 λ7.
        let want = nearest(lambda_of_hz(f7));
        let got: Vec<f64> = r.modes.iter().map(|m| m.eigenvalue).collect();
        assert_eq!(got.len(), 4, "{what}");
        for (g, w) in got.iter().zip(&want) {
            let ok = if w.abs() < 1e-6 * l7 {
                g.abs() < 1e-6 * l7
            } else {
                rel(*g, *w) < 1e-9
            };
            assert!(ok, "{what}: {got:?} vs dense {want:?}");
        }
        assert_eq!(r.n_rigid, 3, "{what}");
    };
    // A shift 1e-6 (relative) off λ7 is handled: θ7 = 1/(λ7 − σ) dominates the others by
    // ~1e6, which block Lanczos with full reorthogonalisation resolves.
    let near = modal(
        &mesh,
        PLATE,
        spec.clone(),
        ModalTarget::Modes(4),
        Some(f7 * (1.0 + 5e-7)),
    );
    assert_verified("shift 1e-6 off λ7", &near, 1e-8);
    check("shift 1e-6 off λ7", &near);
    // Exactly on λ7 (to the ~1e-13 that λ7 is known): K − σM has a pivot ratio of ~1e-13,
    // just above the 1e-14 at which `factor_at` nudges σ.
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let fa = Factor::new(sym, &k.sub_scaled(lambda_of_hz(f7), &m)).unwrap();
    eprintln!("K − λ7·M: pivot ratio {:.1e}", fa.pivot_range.0 / fa.pivot_range.1);
    let r = modal(&mesh, PLATE, spec, ModalTarget::Modes(4), Some(f7));
    eprintln!(
        "shift on λ7: asked σ = {:e}, used {:e}, f = {:?}",
        lambda_of_hz(f7),
        r.shift,
        r.frequencies_hz
    );
    if r.complete && r.accurate {
        assert_verified("shift on λ7", &r, 1e-8);
        check("shift on λ7", &r);
    } else {
        // KNOWN BUG (reported): the shift is not nudged, θ7 ~ 1e13× the others swamps the
        // Krylov basis, and the three rigid-body modes come back as ghosts (a few hundred Hz,
        // residual ≈ 1, Sturm: 1 expected, 6 found) beside a correct λ7. The report is flagged (exit code 2 from the CLI), which is the least we require.
        eprintln!(
            "KNOWN BUG: shift exactly on λ7 returns ghost modes: {:?}",
            r.frequencies_hz
        );
        assert_flagged("shift on λ7", &r);
        assert!(
            r.frequencies_hz.iter().any(|f| rel(*f, f7) < 1e-9),
            "λ7 itself is returned"
        );
    }
}

#[test]
fn shift_on_an_exactly_singular_integer_pencil_is_nudged() {
    // A free–free chain of 300 unit masses and unit springs: λ_j = 4 sin²(jπ/600), so λ_100
    // = 4 sin²(π/6) = 1 exactly, and K − 1·M (integer entries) is exactly singular. The solver
    // must move the shift off the eigenvalue and still return the 6 nearest, exact to 1e-10
    // relative (the spectrum near 1 is spaced ~1e-2, far above the tolerance).
    let n = 300;
    let mut kt = Vec::new();
    let mut mt = Vec::new();
    for i in 0..n {
        mt.push((i, i, 1.0));
        if i + 1 < n {
            kt.push((i, i, 1.0));
            kt.push((i + 1, i + 1, 1.0));
            kt.push((i, i + 1, -1.0));
        }
    }
    let k = SymMatrix::from_triplets(n, &kt);
    let m = SymMatrix::from_triplets(n, &mt).on_pattern(k.pattern.clone());
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    match Factor::new(sym.clone(), &k.sub_scaled(1.0, &m)) {
        Ok(f) => eprintln!("K − M factors with pivot range {:?}", f.pivot_range),
        Err(e) => eprintln!("K − M does not factor: {e}"),
    }
    let p = EigenParams {
        target: Target::Nearest(6),
        shift: Some(1.0),
        dense_below: 0,
        ..Default::default()
    };
    let sol = solve(&k, &m, &sym, &p).unwrap();
    eprintln!("integer pencil: shift used {:e}", sol.shift);
    let mut exact: Vec<f64> = (0..n)
        .map(|j| 4.0 * (j as f64 * PI / (2.0 * n as f64)).sin().powi(2))
        .collect();
    exact.sort_by(|a, b| (a - 1.0).abs().total_cmp(&(b - 1.0).abs()));
    exact.truncate(6);
    exact.sort_by(f64::total_cmp);
    assert_eq!(sol.lambda.len(), 6);
    for (g, w) in sol.lambda.iter().zip(&exact) {
        assert!(rel(*g, *w) < 1e-10, "{:?} vs {exact:?}", sol.lambda);
    }
    assert!(sol.lambda.iter().any(|l| (l - 1.0).abs() < 1e-10));
    assert!(sol.sturm.complete, "{:?}", sol.sturm);
    assert!(sol.rel_residual.iter().all(|&r| r < 1e-8), "{:?}", sol.rel_residual);
}

// ---------------------------------------------------------------------------------------------
// density and stiffness contrasts between parts

#[test]
fn solid_density_contrast_1e5_stays_verified() {
    // Cantilever 200 × 20 × 20 mm, clamped at x = 0: the clamped half has ρ = 1 kg/m³ (the
    // S4 "virtual" density), the free half ρ = 1e5 kg/m³ (contrast 1e5), both E = 2.1e11.
    // M's diagonal spans 1e5; residuals and M-orthonormality must stay at rounding level
    // (< 1e-8) and the Sturm count complete. Reference: the dense solver on the same K and M,
    // agreement 1e-9 (Lanczos tolerance). Measured: residuals ≤ 6e-11, dense agreement ≤ 5e-11.
    let mut mesh = box_mesh(CellKind::Hex20, [0.2, 0.02, 0.02], [8, 2, 2]);
    split_by_x(&mut mesh, 0.1);
    let spec = ModelSpec {
        material: mat(2.1e11, 0.3, 1.0),
        group_materials: vec![("right".into(), mat(2.1e11, 0.3, 1e5))],
        fixes: fixed(&["xmin"]),
        ..Default::default()
    };
    let r = modal(&mesh, "contrast", spec.clone(), ModalTarget::Modes(8), None);
    assert_verified("density contrast", &r, 1e-8);
    let expect_mass = 0.1 * 0.02 * 0.02 * (1.0 + 1e5);
    assert!(rel(r.mass_kg, expect_mass) < 1e-12, "{} vs {expect_mass}", r.mass_kg);
    let (k, m) = assemble_km(&mesh, &spec);
    let d = dense_reference(&k, &m, 8);
    for i in 0..8 {
        let e = rel(r.modes[i].eigenvalue, d.lambda[i]);
        eprintln!(
            "density contrast mode {}: {:.6} Hz (dense rel {e:.1e}, residual {:.1e})",
            i + 1,
            r.frequencies_hz[i],
            r.modes[i].rel_residual
        );
        assert!(e < 1e-9, "mode {}: {} vs {}", i + 1, r.modes[i].eigenvalue, d.lambda[i]);
    }
    // Physics check. Monotonicity (exact): with less mass every eigenvalue rises; the same
    // mesh with ρ = 1e5 everywhere has M ≥ this M, so its frequencies bound these from below.
    // The heavy free half dominates the first bending mode, so f1 lies only a little above
    // the bound (measured 120.60 vs 117.52 Hz, +2.6 %); the heavy density on the clamped half instead, or ignored
    // group materials, would put it far above: f1 < 1.2 × bound.
    let heavy = ModelSpec {
        material: mat(2.1e11, 0.3, 1e5),
        group_materials: vec![],
        ..spec
    };
    let h = modal(&mesh, "uniform heavy", heavy, ModalTarget::Modes(8), None);
    eprintln!(
        "density contrast: f1 {:.4} Hz, uniform ρ = 1e5 bound {:.4} Hz",
        r.frequencies_hz[0], h.frequencies_hz[0]
    );
    for i in 0..8 {
        assert!(
            r.frequencies_hz[i] >= h.frequencies_hz[i] * (1.0 - 1e-12),
            "mode {}",
            i + 1
        );
    }
    assert!(
        r.frequencies_hz[0] < 1.2 * h.frequencies_hz[0],
        "{} vs {}",
        r.frequencies_hz[0],
        h.frequencies_hz[0]
    );
}

/// Cantilever 200 × 20 × 20 mm (hex20 10 × 2 × 2), clamped at x = 0; the half x > 0.1 is
/// the group `right`, the other `left`.
fn contrast_mesh() -> Mesh {
    let mut mesh = box_mesh(CellKind::Hex20, [0.2, 0.02, 0.02], [10, 2, 2]);
    split_by_x(&mut mesh, 0.1);
    mesh
}

#[test]
fn stiffness_contrast_approaches_the_rigid_limit_or_says_so() {
    // The free half is `ratio` times stiffer than the clamped half (steel). In the limit it is
    // a rigid body of mass m = ρV on the soft half. The reference model analyses only the soft
    // half as solid, couples the stiff half's group (all its nodes, the interface ones
    // included) to a reference node at its centroid, and puts a point mass m with the block's
    // central inertia there: exact rigid-body kinetic energy and interface kinematics.
    let mesh = contrast_mesh();
    let (rho, a, b, c) = (7850.0, 0.1, 0.02, 0.02);
    let m = rho * a * b * c;
    let rigid = ModelSpec {
        material: Material::steel(),
        fixes: fixed(&["xmin"]),
        solid_groups: Some(vec!["left".into()]),
        couplings: vec![CouplingSpec {
            group: "right".into(),
            guided: None,
            reference: None,
        }],
        point_masses: vec![PointMassSpec {
            group: "right".into(),
            mass: m,
            inertia: [
                m * (b * b + c * c) / 12.0,
                m * (a * a + c * c) / 12.0,
                m * (a * a + b * b) / 12.0,
                0.0,
                0.0,
                0.0,
            ],
        }],
        ..Default::default()
    };
    let rr = modal(&mesh, "rigid limit", rigid, ModalTarget::Modes(6), None);
    // The reference is compared at 1e-4 below. Its relative residuals are those of the
    // one-factorisation solve after one inverse-iteration step (measured 1.1e-9; the bar is the
    // solver's own, 1e-8): a Rayleigh quotient's error is of the order of the residual squared.
    assert_verified("rigid-limit reference", &rr, 1e-8);
    let stiff = |ratio: f64| ModelSpec {
        material: Material::steel(),
        group_materials: vec![("right".into(), mat(2.1e11 * ratio, 0.3, rho))],
        fixes: fixed(&["xmin"]),
        ..Default::default()
    };
    // Contrast 1e4: verified, and within the physical distance to the rigid limit. That
    // distance is the stiff half's compliance share, ∝ 1/ratio: measured 3.3e-3 at 1e2 and
    // 3.4e-5 at 1e4 (modes 3–4, the second bending pair). Tolerance 1e-4.
    let r = modal(&mesh, "contrast 1e4", stiff(1e4), ModalTarget::Modes(6), None);
    assert_verified("contrast 1e4", &r, 1e-6);
    assert!(rel(r.mass_kg, rr.mass_kg) < 1e-12, "{} vs {}", r.mass_kg, rr.mass_kg);
    for i in 0..6 {
        let e = rel(r.frequencies_hz[i], rr.frequencies_hz[i]);
        eprintln!(
            "contrast 1e4 mode {}: {:.6} Hz, rigid limit {:.6} Hz, rel {e:.1e}",
            i + 1,
            r.frequencies_hz[i],
            rr.frequencies_hz[i]
        );
        assert!(
            e < 1e-4,
            "mode {}: {} vs {}",
            i + 1,
            r.frequencies_hz[i],
            rr.frequencies_hz[i]
        );
    }
    // Contrast 1e8: the physical distance is ~3e-10, but double precision cannot resolve it:
    // the soft part's stiffness is 1e-8 of the assembled K's scale, and rounding in K and its
    // LDLᵀ (≈ eps·1e8·λmax/λ1) moves the low modes by ~1e-3 (measured: 1.2e-3 on mode 1 with
    // the default shift, ~1e-3 with shifts of −1…−100 Hz; the error grows ∝ ratio from 1e5).
    // What the run must do is say so: fail with exit code 2, or flag its report. We also check
    // that the answer is not wildly off (1 %).
    for n in [2, 6] {
        let opts = ModalOptions {
            spec: stiff(1e8),
            target: ModalTarget::Modes(n),
            ..Default::default()
        };
        match run_modal(&mesh, "contrast 1e8", &opts, 0.0) {
            Ok(run) => {
                let r = run.report;
                let errs: Vec<f64> = (0..n).map(|i| rel(r.frequencies_hz[i], rr.frequencies_hz[i])).collect();
                eprintln!(
                    "contrast 1e8, {n} modes: errors vs rigid limit {}, residuals {}, complete {}, accurate {}",
                    sci(&errs),
                    residuals(&r),
                    r.complete,
                    r.accurate
                );
                assert!(errs.iter().all(|&e| e < 1e-2), "{errs:?}");
                if r.complete && r.accurate {
                    // Accepted by the backward error (each pair is exact for a K perturbed at
                    // rounding level, which is all the data allow). The run must then say that the
                    // model is ill-conditioned, and the residual relative to ‖Kx‖ it reports
                    // must bound the error (to first order it bounds δλ/λ ≥ δf/f).
                    assert!(
                        r.notes.iter().any(|n| n.contains("ill-conditioned")),
                        "not flagged: {:?}",
                        r.notes
                    );
                    for i in 0..n {
                        assert!(
                            errs[i] < 1e-6 || errs[i] <= r.modes[i].rel_residual,
                            "mode {}: error {:.1e} above its residual {:.1e}",
                            i + 1,
                            errs[i],
                            r.modes[i].rel_residual
                        );
                    }
                } else {
                    assert_flagged("contrast 1e8", &r);
                }
            }
            Err(e) => {
                eprintln!("contrast 1e8, {n} modes: {e}");
                assert_eq!(e.exit_code(), 2, "{e}");
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// units

#[test]
fn the_same_plate_in_mm_and_in_m_has_the_same_frequencies() {
    // S1 plate 300 × 300 × 20 mm, hex20 10 × 10 × 2. The two meshes differ only in the last
    // bit of the coordinates (300·1e-3 vs 0.3): eigenvalues are well conditioned (δλ/λ ~
    // δx/x ~ 1e-16), and the solver converges each run to ~1e-13, far inside 1e-10.
    let mm = source::load("box:300,300,20:10,10,2:hex20", 1e-3).unwrap();
    let m = source::load("box:0.3,0.3,0.02:10,10,2:hex20", 1.0).unwrap();
    let a = modal(&mm, "mm", ModelSpec::default(), ModalTarget::Modes(12), None);
    let b = modal(&m, "m", ModelSpec::default(), ModalTarget::Modes(12), None);
    assert_verified("mm", &a, 1e-8);
    assert_verified("m", &b, 1e-8);
    assert_eq!((a.n_rigid, b.n_rigid), (6, 6));
    assert!(rel(a.mass_kg, b.mass_kg) < 1e-12);
    let mut worst = 0.0f64;
    for i in 6..12 {
        let e = rel(a.frequencies_hz[i], b.frequencies_hz[i]);
        worst = worst.max(e);
        assert!(
            e < 1e-10,
            "mode {}: {} (mm) vs {} (m)",
            i + 1,
            a.frequencies_hz[i],
            b.frequencies_hz[i]
        );
    }
    eprintln!(
        "mm vs m: f7 = {:.9} Hz, worst rel difference {worst:.1e}",
        b.frequencies_hz[6]
    );
}

// ---------------------------------------------------------------------------------------------
// aspect ratio 1000

#[test]
fn cells_with_aspect_ratio_1000_solve_and_match_beam_theory() {
    // A cantilever strip, length L = 0.1 m (x), thickness t = 1 mm (z), width b = 1 m (y),
    // hex20 20 × 1 × 1: cells 5 × 1000 × 1 mm, aspect ratio 1000 (width to thickness). With
    // ν = 0 there is no Poisson coupling, so the wide strip bends exactly like a beam of
    // bending stiffness E b t³/12 (no anticlastic curvature, no plate-strain factor).
    // Euler–Bernoulli: f1 = 1.875104²/(2π L²)·√(EI/(ρA)). Remaining differences: shear and
    // rotary inertia (L/t = 100: ~1e-4), discretisation (20 quadratic elements along L,
    // aspect 5 in the bending plane: ~1e-4). Measured +2.9e-4; tolerance 1e-3.
    // Conditioning: the cells' stiffness spans (1000)² between directions, so the relative
    // residual's rounding floor rises (measured 2e-7 and 5e-7 on modes 1–2, against the
    // solver's verification tolerance 1e-6) and Lanczos and the dense solver agree to 1e-7
    // only (measured 9.8e-8): tolerance 1e-6 for both.
    let (l, b, t) = (0.1, 1.0, 0.001);
    let mesh = box_mesh(CellKind::Hex20, [l, b, t], [20, 1, 1]);
    let spec = ModelSpec {
        material: mat(2.1e11, 0.0, 7850.0),
        fixes: fixed(&["xmin"]),
        ..Default::default()
    };
    let r = modal(&mesh, "strip", spec.clone(), ModalTarget::Modes(3), None);
    assert_verified("aspect 1000", &r, 1e-6);
    let (k, m) = assemble_km(&mesh, &spec);
    let d = dense_reference(&k, &m, 3);
    for i in 0..3 {
        let e = rel(r.modes[i].eigenvalue, d.lambda[i]);
        assert!(
            e < 1e-6,
            "mode {}: {} vs dense {}",
            i + 1,
            r.modes[i].eigenvalue,
            d.lambda[i]
        );
    }
    let f_eb = 1.875104068711961f64.powi(2) / (2.0 * PI * l * l) * (2.1e11 * t * t / 12.0 / 7850.0).sqrt();
    let e = rel(r.frequencies_hz[0], f_eb);
    eprintln!(
        "aspect 1000: f1 {:.6} Hz vs Euler–Bernoulli {f_eb:.6} Hz, rel {e:.2e}; residuals {}",
        r.frequencies_hz[0],
        residuals(&r)
    );
    assert!(e < 1e-3, "f1 {} vs {f_eb}", r.frequencies_hz[0]);
}

// ---------------------------------------------------------------------------------------------
// nearly incompressible material

/// Free–free square bar 200 × 10 × 10 mm, 20 × 2 × 2 bricks of `kind`: f7 (first bending).
fn bar_f7(kind: CellKind, nu: f64) -> (f64, Vec<String>) {
    let mesh = box_mesh(kind, [0.2, 0.01, 0.01], [20, 2, 2]);
    let spec = ModelSpec {
        material: mat(2.1e11, nu, 7850.0),
        ..Default::default()
    };
    let r = modal(&mesh, kind.name(), spec, ModalTarget::Modes(8), None);
    // ν = 0.4999 raises the bulk stiffness, and with it the residual's rounding floor
    // (measured 3e-8 hex20, 7e-8 tet10): the solver's own tolerance 1e-6 applies.
    assert_verified(&format!("{} ν = {nu}", kind.name()), &r, 1e-6);
    assert_eq!(r.n_rigid, 6);
    (r.frequencies_hz[6], r.notes)
}

/// Free–free first bending frequency with the first-order Timoshenko correction (as in
/// tests/validation.rs): f ≈ f_EB·[1 − ½(βL)²(r/L)²(1 + E/(κG))], κ = 5/6, r² = h²/12.
fn timoshenko_free_free(nu: f64) -> f64 {
    let (l, h, e, rho): (f64, f64, f64, f64) = (0.2, 0.01, 2.1e11, 7850.0);
    let bl: f64 = 4.730040744862704;
    let r2 = h * h / 12.0;
    let f_eb = bl * bl / (2.0 * PI * l * l) * (e * r2 / rho).sqrt();
    let g = e / (2.0 * (1.0 + nu));
    f_eb * (1.0 - 0.5 * bl * bl * r2 / (l * l) * (1.0 + e / (5.0 / 6.0 * g)))
}

#[test]
fn nearly_incompressible_quadratic_elements_stay_accurate_linear_ones_lock() {
    // Bending of a slender free bar depends on E and ρ (plus a small shear correction through
    // G = E/(2(1+ν))), not on the bulk modulus: at ν = 0.4999 (bulk modulus 2800× its ν = 0.3
    // value) an element free of volumetric locking keeps f7 at its ν = 0.3 accuracy.
    // Measured on 20 × 2 × 2 bricks against Timoshenko: hex20 +0.09 % (ν 0.3), +0.16 %
    // (0.4999); tet10 +0.11 %, +0.31 % (f8 +0.42 %: the Kuhn tets break the square symmetry).
    // Tolerance 0.5 % for both, and f7 may not rise by more than 0.5 % from ν = 0.3 to 0.4999.
    // Linear elements lock: hex8 (already shear-locked at ν 0.3, ×1.20) rises ×1.29 more to
    // ×1.54 of Timoshenko, tet4 ×4.1 more to ×6.6. Asserted: ×1.2 and ×3 over their own
    // ν = 0.3 values, and ×1.5 over Timoshenko.
    // MISSING (reported): no warning in `notes` for tet4/hex8 with ν > 0.49.
    for kind in [CellKind::Hex20, CellKind::Tet10] {
        let (f3, _) = bar_f7(kind, 0.3);
        let (f5, notes) = bar_f7(kind, 0.4999);
        for (nu, f) in [(0.3, f3), (0.4999, f5)] {
            let ft = timoshenko_free_free(nu);
            let e = rel(f, ft);
            eprintln!(
                "{} ν = {nu}: f7 {f:.3} Hz, Timoshenko {ft:.3} Hz, rel {e:.2e}; notes {notes:?}",
                kind.name()
            );
            assert!(e < 5e-3, "{} ν = {nu}: f7 {f} vs Timoshenko {ft}", kind.name());
        }
        assert!(f5 / f3 < 1.005, "{}: ×{}", kind.name(), f5 / f3);
    }
    for (kind, min_ratio) in [(CellKind::Hex8, 1.2), (CellKind::Tet4, 3.0)] {
        let (f3, _) = bar_f7(kind, 0.3);
        let (f5, notes) = bar_f7(kind, 0.4999);
        let ft = timoshenko_free_free(0.4999);
        eprintln!(
            "{}: f7 {f3:.1} Hz at ν = 0.3, {f5:.1} Hz at ν = 0.4999 (×{:.2}; ×{:.2} of Timoshenko {ft:.1}); notes {notes:?}",
            kind.name(),
            f5 / f3,
            f5 / ft
        );
        assert!(f5 / f3 > min_ratio, "{}: locking ratio {}", kind.name(), f5 / f3);
        assert!(f5 / ft > 1.5, "{}: {} vs Timoshenko {ft}", kind.name(), f5);
    }
}

// ---------------------------------------------------------------------------------------------
// very thin shell

/// Free square plate a × a (a = 1 m, steel), MITC4 n × n on the zmin face of a hex8 box mesh,
/// thickness t: λ = ω a²√(ρt/D) of mode 7 and the report.
fn plate(n: usize, t: f64, shift_hz: Option<f64>) -> vibrofem::Result<(f64, ModalReport)> {
    let mesh = box_mesh(CellKind::Hex8, [1.0, 1.0, 0.01], [n, n, 1]);
    let m = Material::steel();
    let spec = ModelSpec {
        shells: vec![ShellPart {
            group: "zmin".into(),
            section: ShellSection::new(t),
            material: None,
        }],
        ..Default::default()
    };
    let opts = ModalOptions {
        spec,
        target: ModalTarget::Modes(8),
        shift_hz,
        ..Default::default()
    };
    let r = run_modal(&mesh, "plate", &opts, 0.0)?.report;
    let d = m.young * t.powi(3) / (12.0 * (1.0 - m.poisson * m.poisson));
    let w = 2.0 * PI * r.frequencies_hz[6];
    Ok((w * (m.density * t / d).sqrt(), r))
}

#[test]
fn shell_at_thickness_ratio_1e_4_does_not_lock() {
    // Kirchhoff: the first elastic mode of a free square plate (ν = 0.3) has λ = ω a²√(ρh/D)
    // = 13.468 (Leissa 1969; docs/spec/scenes.md rounds to 13.49). At h/a = 1e-4 shear deformation is
    // ~1e-8: Mindlin = Kirchhoff. A shear-locking element would be stiffer by orders of
    // magnitude ((a/(n h))² ~ 4e6 here); MITC4 converges at O(1/n²): measured λ = 13.565,
    // 13.493, 13.474 on 8², 16², 32² (+0.72 %, +0.18 %, +0.05 %; Richardson 13.468).
    // Tolerance on 16 × 16: 0.5 %. And λ at h/a = 1e-4 equals λ at h/a = 1e-2 up to the thick
    // plate's shear (measured 13.4815, −0.085 %): tolerance 0.5 %.
    // The shift: −1 Hz (a λ shift of −39.5 rad²/s², about 9 λ7). See below for the default.
    let (l16, r) = plate(16, 1e-4, Some(-1.0)).unwrap();
    assert_verified("shell h/a = 1e-4", &r, 1e-6);
    assert_eq!(r.n_rigid, 6, "{:?}", r.frequencies_hz);
    let (l16_thick, _) = plate(16, 1e-2, None).unwrap();
    eprintln!(
        "thin plate: λ(16², h/a 1e-4) = {l16:.5}, λ(16², h/a 1e-2) = {l16_thick:.5}, f7 = {:.6} Hz, residuals {}",
        r.frequencies_hz[6],
        residuals(&r)
    );
    assert!(rel(l16, 13.468) < 5e-3, "λ = {l16}");
    assert!(rel(l16, l16_thick) < 5e-3, "{l16} vs {l16_thick}");
    // With the default shift σ = −1e-7·median(Kii/Mii): the rotational diagonal of a plate
    // scales as κG·12/(ρt²), so σ = −1.2e8 rad²/s² (−1760 Hz) at t = 1e-4, 2.7e7 times λ7.
    // All θ = 1/(λ − σ) of the low modes then agree to ~1e-7 and Lanczos does not converge.
    // KNOWN BUG (reported): today this fails with EigenNotConverged (exit code 2).
    match plate(16, 1e-4, None) {
        Ok((l, r)) => {
            assert_verified("shell h/a = 1e-4, default shift", &r, 1e-6);
            assert!(rel(l, l16) < 1e-6, "{l} vs {l16}");
        }
        Err(e) => {
            eprintln!("KNOWN BUG: thin shell with the default shift: {e}");
            assert!(matches!(e, vibrofem::Error::EigenNotConverged(_)), "{e}");
            assert_eq!(e.exit_code(), 2);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// massless degrees of freedom with lumped mass

#[test]
fn lumped_mass_with_a_massless_coupled_reference_node() {
    // Cantilever 200 × 20 × 20 mm, clamped at x = 0, its free end face coupled rigidly to a
    // reference node (6 DOFs, no point mass: the node carries mass only through its slaves).
    // With HRZ lumping no mode may be zero or infinite, and the frequencies differ from the
    // consistent-mass ones by the lumping error only. HRZ on hex20 10 × 2 × 2, measured:
    // bending pairs −0.34 % and −1.29 %, torsion −12.5 % (HRZ puts little mass on hex20
    // corner nodes, which on a 2 × 2 section carry most of the polar inertia; −3.7 % on 4 × 4,
    // ∝ h²), axial −0.2 %. Tolerances: 2 % (bending, axial), 15 % (torsion, mode 5). The
    // coupling itself changes the consistent frequencies by < 1e-5 (measured against the
    // uncoupled bar), so it adds nothing to these errors.
    let mesh = box_mesh(CellKind::Hex20, [0.2, 0.02, 0.02], [10, 2, 2]);
    let spec = |lumping| ModelSpec {
        fixes: fixed(&["xmin"]),
        couplings: vec![CouplingSpec {
            group: "xmax".into(),
            guided: None,
            reference: None,
        }],
        lumping,
        ..Default::default()
    };
    let l = modal(&mesh, "lumped", spec(MassLumping::Lumped), ModalTarget::Modes(6), None);
    let c = modal(
        &mesh,
        "consistent",
        spec(MassLumping::Consistent),
        ModalTarget::Modes(6),
        None,
    );
    assert_verified("lumped", &l, 1e-8);
    assert_verified("consistent", &c, 1e-8);
    assert_eq!(l.n_rigid, 0);
    assert!(rel(l.mass_kg, c.mass_kg) < 1e-12);
    for i in 0..6 {
        let e = rel(l.frequencies_hz[i], c.frequencies_hz[i]);
        eprintln!(
            "coupled cantilever mode {}: lumped {:.4} Hz, consistent {:.4} Hz, rel {e:.2e}",
            i + 1,
            l.frequencies_hz[i],
            c.frequencies_hz[i]
        );
        let tol = if i == 4 { 0.15 } else { 0.02 };
        assert!(
            l.frequencies_hz[i] > 100.0 && e < tol,
            "mode {}: {} vs {}",
            i + 1,
            l.frequencies_hz[i],
            c.frequencies_hz[i]
        );
    }
}

#[test]
fn lumped_cantilevers_restarted_by_the_sturm_check_converge_or_say_so() {
    // KNOWN BUG (reported): when the Sturm check finds one more eigenvalue than the first
    // Lanczos pass returned, `solve` resumes with more wanted modes; `Lanczos::set_want`
    // grows the basis by less than a block (m_max = want + 6b grows by Δwant = 5 < b = 6),
    // the next block no longer fits, and the run fails with "internal basis overflow". These
    // two lumped cantilevers hit it (CLI: `vibrofem modes box:0.2,0.02,0.02:10,2,2:hex20
    // --fix xmin --mass lumped --modes 6` → exit 2). Required today: a verified answer within
    // the lumping error of the consistent one (as above, 2 % bending / 15 % torsion), or an
    // EigenNotConverged error (exit code 2).
    for (ny, couple) in [(2, false), (4, true)] {
        let mesh = box_mesh(CellKind::Hex20, [0.2, 0.02, 0.02], [10, ny, ny]);
        let spec = |lumping| ModelSpec {
            fixes: fixed(&["xmin"]),
            couplings: if couple {
                vec![CouplingSpec {
                    group: "xmax".into(),
                    guided: None,
                    reference: None,
                }]
            } else {
                vec![]
            },
            lumping,
            ..Default::default()
        };
        let c = modal(
            &mesh,
            "consistent",
            spec(MassLumping::Consistent),
            ModalTarget::Modes(6),
            None,
        );
        let opts = ModalOptions {
            spec: spec(MassLumping::Lumped),
            target: ModalTarget::Modes(6),
            ..Default::default()
        };
        match run_modal(&mesh, "lumped", &opts, 0.0) {
            Ok(run) => {
                let l = run.report;
                assert_verified("lumped", &l, 1e-8);
                for i in 0..6 {
                    let tol = if i == 4 { 0.15 } else { 0.02 };
                    assert!(rel(l.frequencies_hz[i], c.frequencies_hz[i]) < tol, "mode {}", i + 1);
                }
            }
            Err(e) => {
                eprintln!("KNOWN BUG: lumped cantilever {ny}×{ny}, coupled {couple}: {e}");
                assert!(matches!(e, vibrofem::Error::EigenNotConverged(_)), "{e}");
                assert_eq!(e.exit_code(), 2);
            }
        }
    }
}

#[test]
fn massless_spring_node_gives_no_spurious_modes() {
    // A steel cube 100 mm (hex20 3 × 3 × 3, lumped mass), its bottom face coupled to a
    // reference node R; R is joined to a free point P by a 6-component spring k1, and P to
    // the ground by k2. P has stiffness in all six components and no mass at all: M is
    // singular (six infinite eigenvalues). Static condensation of P is exact: the model is
    // the same as R on a spring k1 k2/(k1 + k2) to the ground. The lowest 12 modes (six
    // suspension modes, then elastic ones) must equal the condensed model's to 1e-9 (both
    // converged to the Lanczos tolerance), all finite and none spurious (the Sturm count of
    // the singular-M pencil must still be complete).
    let k1 = [2e6, 3e6, 4e6, 1e4, 2e4, 3e4];
    let k2 = [1e6, 1e6, 2e6, 3e4, 1e4, 1e4];
    let kser: Vec<f64> = k1.iter().zip(&k2).map(|(a, b)| a * b / (a + b)).collect();
    let mut mesh = box_mesh(CellKind::Hex20, [0.1, 0.1, 0.1], [3, 3, 3]);
    add_point(&mut mesh, "p", [0.05, 0.05, -0.05]);
    let base = ModelSpec {
        lumping: MassLumping::Lumped,
        couplings: vec![CouplingSpec {
            group: "zmin".into(),
            guided: None,
            reference: None,
        }],
        ..Default::default()
    };
    let with_p = ModelSpec {
        springs: vec![
            SpringSpec {
                a: "zmin".into(),
                b: Some("p".into()),
                k: k1,
            },
            SpringSpec {
                a: "p".into(),
                b: None,
                k: k2,
            },
        ],
        ..base.clone()
    };
    let condensed = ModelSpec {
        springs: vec![SpringSpec {
            a: "zmin".into(),
            b: None,
            k: [kser[0], kser[1], kser[2], kser[3], kser[4], kser[5]],
        }],
        ..base
    };
    let a = modal(&mesh, "massless P", with_p, ModalTarget::Modes(12), None);
    let b = modal(&mesh, "condensed", condensed, ModalTarget::Modes(12), None);
    assert_verified("massless P", &a, 1e-8);
    assert_verified("condensed", &b, 1e-8);
    assert_eq!(a.frequencies_hz.len(), 12);
    for i in 0..12 {
        let e = rel(a.frequencies_hz[i], b.frequencies_hz[i]);
        eprintln!(
            "massless P mode {}: {:.6} Hz, condensed {:.6} Hz, rel {e:.1e}",
            i + 1,
            a.frequencies_hz[i],
            b.frequencies_hz[i]
        );
        assert!(
            a.frequencies_hz[i] > 1.0 && e < 1e-9,
            "mode {}: {} vs {}",
            i + 1,
            a.frequencies_hz[i],
            b.frequencies_hz[i]
        );
    }
}

// ---------------------------------------------------------------------------------------------
// clustered spectrum

#[test]
fn twenty_modes_clustered_within_a_tenth_of_a_percent_are_all_found() {
    // 20 uncoupled chains of 50 unit masses, each grounded at one end (fixed–free), chain c
    // with springs k_c = 1 + 1e-4·c: the lowest root of each chain, λ_1 = 4 k_c sin²(π/202),
    // gives 20 eigenvalues whose frequencies span 0.095 % — more than three times the block
    // size. The next roots are 9× higher. All 20 must be found, each exact to 1e-9 relative
    // (the solver's Ritz tolerance is 1e-10 on θ), and the Sturm count must be complete.
    let (n, copies) = (50, 20);
    let idx = |c: usize, i: usize| i * copies + c;
    let mut kt = Vec::new();
    let mut mt = Vec::new();
    for c in 0..copies {
        let k = 1.0 + 1e-4 * c as f64;
        for i in 0..n {
            mt.push((idx(c, i), idx(c, i), 1.0));
            kt.push((idx(c, i), idx(c, i), k)); // spring to the left (ground for i = 0)
            if i + 1 < n {
                kt.push((idx(c, i), idx(c, i), k));
                kt.push((idx(c, i), idx(c, i + 1), -k));
            }
        }
    }
    let nd = n * copies;
    let k = SymMatrix::from_triplets(nd, &kt);
    let m = SymMatrix::from_triplets(nd, &mt).on_pattern(k.pattern.clone());
    let mut exact: Vec<f64> = (0..copies)
        .flat_map(|c| {
            let kc = 1.0 + 1e-4 * c as f64;
            (1..=n).map(move |j| 4.0 * kc * ((2 * j - 1) as f64 * PI / (4 * n + 2) as f64).sin().powi(2))
        })
        .collect();
    exact.sort_by(f64::total_cmp);
    let spread = (exact[19] / exact[0]).sqrt() - 1.0;
    assert!(spread < 1e-3 && exact[20] > 8.0 * exact[19], "spread {spread}");
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    for want in [20, 24] {
        let p = EigenParams {
            target: Target::Nearest(want),
            dense_below: 0,
            ..Default::default()
        };
        let sol = solve(&k, &m, &sym, &p).unwrap();
        eprintln!(
            "cluster: {want} wanted, {} returned, spread {spread:.2e}, applications {}, factorizations {}",
            sol.lambda.len(),
            sol.applications,
            sol.factorizations
        );
        assert_eq!(sol.lambda.len(), want);
        for (i, (g, w)) in sol.lambda.iter().zip(&exact).enumerate() {
            assert!(rel(*g, *w) < 1e-9, "mode {i}: {g} vs {w}");
        }
        assert!(sol.sturm.complete, "{:?}", sol.sturm);
        assert!(sol.rel_residual.iter().all(|&r| r < 1e-8), "{:?}", sol.rel_residual);
        assert!(sol.m_orthonormality < 1e-10);
    }
}

// ---------------------------------------------------------------------------------------------
// when accuracy cannot be guaranteed, the run says so

#[test]
fn unconverged_iteration_is_reported_with_exit_code_2() {
    // One block of operator applications cannot converge 12 modes of a 465-DOF plate: the CLI
    // must say so on stderr and exit with 2 (numerical failure), with nothing on stdout.
    let o = Command::new(env!("CARGO_BIN_EXE_vibrofem"))
        .args(["modes", PLATE, "--max-applications", "1", "--json"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(
        err.contains("did not converge") && err.contains("operator applications"),
        "{err}"
    );
    assert!(o.stdout.is_empty(), "no report for a failed run");
    // The library error is the documented variant with exit code 2.
    let mesh = source::load(PLATE, 1.0).unwrap();
    let e = run_modal(
        &mesh,
        PLATE,
        &ModalOptions {
            max_applications: 1,
            ..Default::default()
        },
        0.0,
    )
    .err()
    .unwrap();
    assert!(matches!(e, vibrofem::Error::EigenNotConverged(_)), "{e}");
    assert_eq!(e.exit_code(), 2);
}
