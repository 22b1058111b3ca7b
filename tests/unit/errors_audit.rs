//! Errors audit (issue 7, item 5): every `Error` variant is produced by at least one test.
//!
//! Most variants already have tests elsewhere (`mesh_io.rs`: `Io` on a missing mesh,
//! `MeshParse`, `UnsupportedElement`, `EmptyModel`; `stress.rs`: `InvertedElement`;
//! `elements.rs`: `InvalidMaterial`; `extremes.rs`: `EigenNotConverged`). This file covers the
//! ones no test matched by variant — `Io` on a write, `UnknownGroup` through the library,
//! `Factorization`, `Singular` and `Verification` — and checks each variant's exit code.

use std::path::Path;
use std::sync::Arc;

use vibrofem::Error;
use vibrofem::analysis::statics::{StaticOptions, run_static};
use vibrofem::input::source;
use vibrofem::linalg::eigen::{EigenParams, Target, solve};
use vibrofem::linalg::factor::SymbolicFactor;
use vibrofem::linalg::sparse::SymMatrix;
use vibrofem::model::ModelSpec;

fn box_mesh() -> vibrofem::mesh::Mesh {
    source::load("box:0.1,0.05,0.01:2,2,1:hex8", 1.0).unwrap()
}

#[test]
fn io_error_on_an_unwritable_output_path() {
    let mesh = box_mesh();
    // A directory that does not exist: the write fails, the error names the path.
    let out = Path::new("/nonexistent-vibrofem-dir/sub/modes.vtu");
    let e = vibrofem::io::vtk::write_vtu(out, &mesh, &[]).unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e:?}");
    assert!(e.to_string().contains("/nonexistent-vibrofem-dir/sub/modes.vtu"), "{e}");
    assert_eq!(e.exit_code(), 1);
    let out = Path::new("/nonexistent-vibrofem-dir/sub/modes.msh");
    let e = vibrofem::io::msh_out::write_msh_views(out, &mesh, &[]).unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e:?}");
    assert_eq!(e.exit_code(), 1);
}

#[test]
fn io_error_on_a_missing_input_file() {
    let p = Path::new("/nonexistent-vibrofem-dir/mesh.msh");
    let e = vibrofem::io::gmsh::read(p, 1.0).unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e:?}");
    let e = vibrofem::app::scene::Scene::load(Path::new("/nonexistent-vibrofem-dir/s.toml")).unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e:?}");
    let e = vibrofem::app::design::Design::from_toml(Path::new("/nonexistent-vibrofem-dir/d.toml")).unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e:?}");
}

#[test]
fn unknown_group_names_the_groups_that_exist() {
    let mesh = box_mesh();
    let mut spec = ModelSpec::default();
    spec.fixes.push(("no_such_face".into(), 0b111));
    let e = run_static(
        &mesh,
        "box",
        &StaticOptions {
            spec,
            cases: vec![vec![]],
        },
    )
    .err()
    .expect("an unknown group is an error");
    assert!(matches!(e, Error::UnknownGroup { .. }), "{e:?}");
    let msg = e.to_string();
    assert!(msg.contains("no_such_face") && msg.contains("xmin"), "{msg}");
    assert_eq!(e.exit_code(), 1);
}

#[test]
fn factorization_error_for_an_unconstrained_static_model() {
    let mesh = box_mesh();
    let e = run_static(
        &mesh,
        "box",
        &StaticOptions {
            spec: ModelSpec::default(),
            cases: vec![vec![]],
        },
    )
    .err()
    .expect("a free body has a singular stiffness");
    assert!(matches!(e, Error::Factorization(_)), "{e:?}");
    assert!(e.to_string().starts_with("factorization failed:"), "{e}");
    assert_eq!(e.exit_code(), 2);
}

/// K = diag(1..n) with a diagonal pattern.
fn diag(n: usize, f: impl Fn(usize) -> f64) -> SymMatrix {
    let t: Vec<(usize, usize, f64)> = (0..n).map(|i| (i, i, f(i))).collect();
    SymMatrix::from_triplets(n, &t)
}

#[test]
fn verification_error_for_a_massless_eigenproblem() {
    // M = 0: no eigenvalue exists. The Lanczos path (dense oracle switched off) must end in a
    // numerical-failure error, never in NaN frequencies or a panic: the final Rayleigh–Ritz
    // step finds no M-independent Ritz vector and reports `Error::Verification`.
    let n = 40;
    let k = diag(n, |i| 1.0 + i as f64);
    // M on K's pattern (the solver requires the two to share it), all zero.
    let mut m = k.clone();
    m.values.fill(0.0);
    let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
    let p = EigenParams {
        target: Target::Nearest(4),
        shift: Some(-1.0),
        dense_below: 0,
        ..Default::default()
    };
    match solve(&k, &m, &sym, &p) {
        Ok(s) => panic!("M = 0 gave a solution: {:?}", s.lambda),
        Err(e) => {
            eprintln!("M = 0: {e:?}");
            assert!(
                matches!(
                    e,
                    Error::Verification(_) | Error::EigenNotConverged(_) | Error::Factorization(_)
                ),
                "{e:?}"
            );
            assert_eq!(e.exit_code(), 2);
        }
    }
}

#[test]
fn every_variant_maps_to_its_documented_exit_code() {
    let io = || std::io::Error::other("x");
    let p = || std::path::PathBuf::from("f");
    let cases: Vec<(Error, i32)> = vec![
        (Error::io(p(), io()), 1),
        (
            Error::MeshParse {
                path: p(),
                section: "$Nodes".into(),
                line: Some(3),
                msg: "m".into(),
            },
            1,
        ),
        (
            Error::UnsupportedElement {
                path: p(),
                gmsh_type: 7,
                name: "pyramid".into(),
                group: "g".into(),
            },
            1,
        ),
        (
            Error::UnknownGroup {
                name: "a".into(),
                available: "b".into(),
            },
            1,
        ),
        (
            Error::InvertedElement {
                element: 1,
                kind: "hex8",
                det: -1.0,
                file: None,
            },
            1,
        ),
        (
            Error::InvalidMaterial {
                name: "s".into(),
                msg: "m".into(),
            },
            1,
        ),
        (Error::EmptyModel { what: "w".into() }, 1),
        (Error::InvalidInput("i".into()), 1),
        (Error::EigenNotConverged("e".into()), 2),
        (Error::Verification("v".into()), 2),
        (Error::Factorization("f".into()), 2),
        (
            Error::Input {
                file: "a.toml".into(),
                line: Some(3),
                key: Some("modal.modes".into()),
                msg: "m".into(),
            },
            1,
        ),
        (
            Error::Singular {
                equation: Some(0),
                at: None,
                msg: "s".into(),
            },
            2,
        ),
        (Error::output("summary.json", "disk full"), 4),
        (
            Error::Engine {
                engine: "SLEPc engine".into(),
                msg: "mpirun not found".into(),
            },
            5,
        ),
    ];
    for (e, code) in cases {
        assert_eq!(e.exit_code(), code, "{e:?}");
    }
}

#[test]
fn a_zero_pivot_names_its_equation_then_its_node_and_component() {
    // K = diag(1, 2, 3, 4) with one entry zeroed on a diagonal pattern: that equation has no
    // stiffness. The factorisation must report that equation (whatever the ordering did to it),
    // and the model layer names it.
    for z in 0..4 {
        let k = diag(4, |i| if i == z { 0.0 } else { 1.0 + i as f64 });
        let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
        let e = vibrofem::linalg::factor::Factor::new(sym, &k).err().expect("singular");
        match &e {
            Error::Singular { equation, .. } => assert_eq!(*equation, Some(z), "{e:?}"),
            other => panic!("expected Error::Singular, got {other:?}"),
        }
        assert_eq!(e.exit_code(), 2);
        let located = e.locate(|eq| format!("node {} uz", 100 + eq));
        assert!(
            located.to_string().contains(&format!("(at node {} uz)", 100 + z)),
            "{located}"
        );
    }
}

#[test]
fn equations_are_named_by_node_tag_and_component() {
    // box 2×2×1 hex8: 18 nodes; fixing xmin leaves the other 12 nodes' translations free.
    let mesh = box_mesh();
    let spec = ModelSpec {
        fixes: vec![("xmin".into(), vibrofem::dof::TRANSLATIONS)],
        ..Default::default()
    };
    let model = vibrofem::model::Model::build(&mesh, &spec, "box").unwrap();
    let sys = vibrofem::system::System::build(model, &vibrofem::system::SystemOptions::default(), "box").unwrap();
    for eq in [0, 1, 2, sys.n_free() - 1] {
        let (a, c) = sys.dofs().node_comp_of(eq);
        let want = format!("node {} {}", mesh.node_tags[a], ["ux", "uy", "uz"][c]);
        assert_eq!(sys.describe_equation(eq), want);
    }
}
