//! Linear statics, rigid couplings and point masses against beam theory, consistency checks
//! and bad input.

use vibrofem::Error;
use vibrofem::analysis::modal::{ModalOptions, ModalTarget, run_modal};
use vibrofem::analysis::statics::{Load, StaticOptions, run_static};
use vibrofem::dof::TRANSLATIONS;
use vibrofem::input::source;
use vibrofem::material::Material;
use vibrofem::model::{CouplingSpec, ModelSpec, PointMassSpec};

fn spec(fix: &[&str], couple: &[(&str, Option<usize>)]) -> ModelSpec {
    ModelSpec {
        fixes: fix.iter().map(|g| (g.to_string(), TRANSLATIONS)).collect(),
        couplings: couple
            .iter()
            .map(|(g, a)| CouplingSpec {
                group: g.to_string(),
                guided: *a,
                reference: None,
            })
            .collect(),
        ..Default::default()
    }
}

/// Reference-node displacement along z for a force or prescribed displacement.
fn guided_uz(mesh: &str, spec: ModelSpec, loads: Vec<Load>) -> (f64, Option<f64>, f64) {
    let m = source::load(mesh, 1.0).unwrap();
    let run = run_static(
        &m,
        mesh,
        &StaticOptions {
            spec,
            cases: vec![loads],
        },
    )
    .unwrap();
    let c = &run.cases[0];
    (
        c.references[0].displacement[2],
        c.references[0].stiffness,
        c.equilibrium_error,
    )
}

#[test]
fn cantilever_tip_deflection_matches_timoshenko() {
    // Steel bar 400 × 10 × 10 mm, clamped at x = 0, tip force 100 N in z through a rigid
    // coupling of the end face. Timoshenko: δ = PL³/(3EI) + PL/(κGA), κ = 5/6 (rectangle).
    // The fully clamped 3D root face and the coupled (rigid) tip face both stiffen the 3D model
    // slightly relative to beam theory (≈ 0.2 % at L/h = 40): tolerance 0.5 %.
    let (l, h, p) = (0.4, 0.01, 100.0);
    let (e, nu) = (2.1e11, 0.3);
    let i = h * h * h * h / 12.0;
    let g = e / (2.0 * (1.0 + nu));
    let delta = p * l * l * l / (3.0 * e * i) + p * l / (5.0 / 6.0 * g * h * h);
    let m = "box:0.4,0.01,0.01:80,2,2:hex20";
    let (uz, _, eq) = guided_uz(
        m,
        spec(&["xmin"], &[("xmax", None)]),
        vec![Load::Force {
            group: "xmax".into(),
            force: [0.0, 0.0, p],
        }],
    );
    assert!((uz - delta).abs() / delta < 5e-3, "tip {uz} vs Timoshenko {delta}");
    assert!(eq < 1e-8, "equilibrium {eq}");
}

#[test]
fn guided_leaf_stiffness_lies_between_beam_and_plate_formulas() {
    // S3 leaf 169 × 146 × 9 mm, clamped at x = 0, guided end at x = l (no rotation). A wide
    // leaf bends between the beam (E) and plate-strain (E/(1−ν²)) limits of k = E b h³ / l³
    // (plus a small shear compliance); the 3D answer must lie between them.
    let (l, b, h, e, nu) = (0.169, 0.146, 0.009, 2.1e11, 0.3);
    let k_beam = e * b * h * h * h / (l * l * l);
    let k_plate = k_beam / (1.0 - nu * nu);
    let m = "box:0.169,0.146,0.009:24,8,2:hex20";
    let (uz, k, eq) = guided_uz(
        m,
        spec(&["xmin"], &[("xmax", Some(2))]),
        vec![Load::Force {
            group: "xmax".into(),
            force: [0.0, 0.0, 1000.0],
        }],
    );
    let k = k.unwrap();
    assert!((k - 1000.0 / uz).abs() < 1e-9 * k);
    assert!(
        k > 0.97 * k_beam && k < k_plate,
        "k {k:.4e} not within [{k_beam:.4e}, {k_plate:.4e}]"
    );
    assert!(eq < 1e-8);
}

#[test]
fn prescribed_displacement_and_force_give_the_same_stiffness() {
    // Linear model: the force needed for Δ equals k·Δ with k from the force case, to solver
    // precision (1e-9).
    let m = "box:0.169,0.146,0.009:12,4,2:hex20";
    let (_, k_force, _) = guided_uz(
        m,
        spec(&["xmin"], &[("xmax", Some(2))]),
        vec![Load::Force {
            group: "xmax".into(),
            force: [0.0, 0.0, 1000.0],
        }],
    );
    let mut s = spec(&["xmin"], &[("xmax", Some(2))]);
    s.prescribed
        .push(("xmax".into(), [None, None, Some(0.46e-3), None, None, None]));
    let (uz, k_disp, eq) = guided_uz(m, s, vec![]);
    assert!((uz - 0.46e-3).abs() < 1e-15);
    let (a, b) = (k_force.unwrap(), k_disp.unwrap());
    assert!((a - b).abs() < 1e-9 * a, "{a} vs {b}");
    assert!(eq < 1e-8, "reactions balance: {eq}");
}

#[test]
fn leaf_with_point_mass_frequency_equals_sqrt_k_over_m() {
    // S4 structure: a massless (ρ = 1 kg/m³, 2e-4 kg) leaf carrying 11.34 kg on its guided end.
    // A one-DOF system: f = √(k/m)/(2π) with k from the static run on the same mesh. The leaf's
    // own mass shifts f by ~1e-5 relative; tolerance 1e-4. Density contrast to the point mass
    // (virtual 78 500 kg/m³ in the paper) tests the solver at ~1e5; residuals must stay small.
    let m = "box:0.169,0.146,0.009:24,8,2:hex20";
    let (_, k, _) = guided_uz(
        m,
        spec(&["xmin"], &[("xmax", Some(2))]),
        vec![Load::Force {
            group: "xmax".into(),
            force: [0.0, 0.0, 1000.0],
        }],
    );
    let k = k.unwrap();
    let mut s = spec(&["xmin"], &[("xmax", Some(2))]);
    s.material = Material {
        young: 2.1e11,
        poisson: 0.3,
        density: 1.0,
    };
    s.point_masses.push(PointMassSpec {
        group: "xmax".into(),
        mass: 11.34,
        inertia: [0.0; 6],
    });
    let mesh = source::load(m, 1.0).unwrap();
    let rep = run_modal(
        &mesh,
        m,
        &ModalOptions {
            spec: s,
            target: ModalTarget::Modes(3),
            ..Default::default()
        },
        0.0,
    )
    .unwrap()
    .report;
    let f = (k / 11.34).sqrt() / (2.0 * std::f64::consts::PI);
    assert_eq!(rep.n_rigid, 0);
    assert!(
        (rep.frequencies_hz[0] - f).abs() < 1e-4 * f,
        "{} vs {f}",
        rep.frequencies_hz[0]
    );
    assert!(
        rep.complete && rep.accurate && rep.max_rel_residual < 1e-8,
        "{:?}",
        rep.notes
    );
}

#[test]
fn gravity_reaction_equals_weight() {
    // A cantilever under its own weight: the clamp carries exactly m·g (consistent body force).
    let m = "box:0.2,0.02,0.01:10,2,1:hex20";
    let mesh = source::load(m, 1.0).unwrap();
    let run = run_static(
        &mesh,
        m,
        &StaticOptions {
            spec: spec(&["xmin"], &[]),
            cases: vec![vec![Load::Acceleration([0.0, 0.0, -9.81])]],
        },
    )
    .unwrap();
    let w = 0.2 * 0.02 * 0.01 * 7850.0 * 9.81;
    let rz = run.cases[0].reactions[0].resultant.force[2];
    assert!((rz - w).abs() < 1e-9 * w, "{rz} vs {w}");
}

#[test]
fn pressure_resultant_is_pressure_times_area_inward() {
    // 1 MPa on the top face (z = 0.01) of a clamped block pushes down: resultant −p·A in z.
    let m = "box:0.1,0.05,0.01:4,2,1:hex20";
    let mesh = source::load(m, 1.0).unwrap();
    let run = run_static(
        &mesh,
        m,
        &StaticOptions {
            spec: spec(&["zmin"], &[]),
            cases: vec![vec![Load::Pressure {
                group: "zmax".into(),
                p: 1e6,
            }]],
        },
    )
    .unwrap();
    let fz = run.cases[0].applied.force[2];
    assert!((fz + 1e6 * 0.1 * 0.05).abs() < 1e-6, "{fz}");
}

fn static_err(m: &str, s: ModelSpec, loads: Vec<Load>) -> Error {
    let mesh = source::load(m, 1.0).unwrap();
    match run_static(
        &mesh,
        m,
        &StaticOptions {
            spec: s,
            cases: vec![loads],
        },
    ) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e,
    }
}

#[test]
fn unconstrained_model_names_the_free_motions() {
    let e = static_err("box:0.1,0.05,0.01:2,2,1:hex8", ModelSpec::default(), vec![]);
    let msg = e.to_string();
    assert!(
        msg.contains("under-constrained") && msg.contains("translation x") && msg.contains("rotation about z"),
        "{msg}"
    );
    assert_eq!(e.exit_code(), 2);
    // Fixing only uz of one face leaves in-plane motions free.
    let mut s = ModelSpec::default();
    s.fixes.push(("zmin".into(), 0b100));
    let msg = static_err("box:0.1,0.05,0.01:2,2,1:hex8", s, vec![]).to_string();
    assert!(
        msg.contains("translation x") && msg.contains("rotation about z") && !msg.contains("translation z"),
        "{msg}"
    );
}

#[test]
fn bad_input_is_reported_clearly() {
    let m = "box:0.1,0.05,0.01:2,2,1:hex8";
    let f = |g: &str| {
        vec![Load::Force {
            group: g.into(),
            force: [0.0, 0.0, 1.0],
        }]
    };
    let msg = static_err(m, spec(&["xmin"], &[]), f("tip")).to_string();
    assert!(msg.contains("'tip'"), "{msg}");
    let msg = static_err(m, spec(&["xmin"], &[("xmin", None)]), vec![]).to_string();
    assert!(msg.contains("conflicting constraints") && msg.contains("xmin"), "{msg}");
    let msg = static_err(
        m,
        spec(&["xmin"], &[]),
        vec![Load::Force {
            group: "xmax".into(),
            force: [f64::NAN, 0.0, 0.0],
        }],
    )
    .to_string();
    assert!(msg.contains("not finite"), "{msg}");
    let msg = static_err(
        m,
        spec(&["xmin"], &[]),
        vec![Load::Pressure {
            group: "xmax".into(),
            p: f64::INFINITY,
        }],
    )
    .to_string();
    assert!(msg.contains("not finite"), "{msg}");
    let mut s = spec(&["xmin"], &[]);
    s.point_masses.push(PointMassSpec {
        group: "xmax".into(),
        mass: 1.0,
        inertia: [1.0, 1.0, 1.0, 0.0, 0.0, 0.0],
    });
    let msg = static_err(m, s, vec![]).to_string();
    assert!(msg.contains("rotary inertia needs a coupled group"), "{msg}");
}

#[test]
fn gravity_acts_on_shells_and_beams_too() {
    // MITC4 plate 1 × 0.5 × 0.01 m under its own weight: the clamp carries ρ·t·A·g (consistent
    // shell mass, translations only; 1e-9).
    let m = "box:1,0.5,0.01:10,5,1:hex8";
    let mesh = source::load(m, 1.0).unwrap();
    let mut s = ModelSpec::default();
    s.shells.push(vibrofem::model::ShellPart {
        group: "zmin".into(),
        section: vibrofem::section::ShellSection::new(0.01),
        material: None,
    });
    s.fixes.push(("xmin".into(), vibrofem::dof::ALL6));
    let run = run_static(
        &mesh,
        m,
        &StaticOptions {
            spec: s,
            cases: vec![vec![Load::Acceleration([0.0, 0.0, -9.81])]],
        },
    )
    .unwrap();
    let w = 1.0 * 0.5 * 0.01 * 7850.0 * 9.81;
    let rz = run.cases[0].reactions[0].resultant.force[2];
    assert!((rz - w).abs() < 1e-9 * w, "{rz} vs {w}");
}
