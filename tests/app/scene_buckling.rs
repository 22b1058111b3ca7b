//! `[buckling]` and `[modal] prestress = N` in scene files (issue 30): the scene's results equal
//! the library's buckling and prestressed-modes runs on the same model (to rounding), the
//! static case after a prestressed modal run still uses K, and bad case numbers name the line.

use std::path::Path;
use vibrofem::analysis::buckling::{BucklingOptions, run_buckling};
use vibrofem::analysis::modal::{ModalOptions, ModalTarget};
use vibrofem::analysis::prestress::run_prestressed_modes;
use vibrofem::analysis::statics::Load;
use vibrofem::app::studies::scene::Scene;
use vibrofem::mesh::CellKind;
use vibrofem::mesh::generate::box_mesh;
use vibrofem::model::ModelSpec;

const SCENE: &str = r#"
[scene]
version = 1
name = "column"

[mesh]
generator = "box:0.5,0.03,0.01:20,3,1:hex20"

[[part]]
group = "volume"
formulation = "solid"

[[fix]]
group = "xmin"
dofs = ["ux", "uy", "uz"]

[[load_case]]
[[load_case.load]]
group = "xmax"
force = [-1.0, 0.0, 0.0]

[[load_case]]
[[load_case.load]]
group = "xmax"
force = [-1000.0, 0.0, 0.0]

[modal]
modes = 2
prestress = 2

[buckling]
modes = 2
case = 1
"#;

#[test]
fn scene_buckling_and_prestress_match_the_library() {
    let scene = Scene::parse(Path::new("column.toml"), SCENE).unwrap();
    let r = scene.run(None).unwrap();
    assert!(r.verified(), "{:?}", r.notes);
    let mesh = box_mesh(CellKind::Hex20, [0.5, 0.03, 0.01], [20, 3, 1]);
    let spec = ModelSpec {
        fixes: vec![("xmin".into(), 7)],
        ..Default::default()
    };
    let force = |p: f64| {
        vec![Load::Force {
            group: "xmax".into(),
            force: [p, 0.0, 0.0],
        }]
    };
    let b = run_buckling(
        &mesh,
        "column",
        &BucklingOptions {
            spec: spec.clone(),
            modes: 2,
            ..Default::default()
        },
        &force(-1.0),
        0.0,
    )
    .unwrap();
    let got = &r.buckling.as_ref().expect("buckling report").load_factors;
    assert_eq!(got.len(), 2);
    for (g, w) in got.iter().zip(&b.report.load_factors) {
        assert!((g / w - 1.0).abs() < 1e-9, "{g} vs {w}");
    }
    let opts = ModalOptions {
        spec,
        target: ModalTarget::Modes(2),
        ..Default::default()
    };
    let p = run_prestressed_modes(&mesh, "column", &opts, &force(-1000.0), 0.0).unwrap();
    let f = &r.modal.as_ref().unwrap().frequencies_hz;
    for (g, w) in f.iter().zip(&p.modal.report.frequencies_hz) {
        assert!((g / w - 1.0).abs() < 1e-9, "{g} vs {w}");
    }
    // The static cases after the prestressed modal run see K, not K + K_σ: the tip
    // displacement of case 2 is 1000 × that of case 1 (linear).
    let st = r.statics.as_ref().unwrap();
    let (u1, u2) = (st.cases[0].max_displacement.0, st.cases[1].max_displacement.0);
    assert!((u2 / u1 / 1000.0 - 1.0).abs() < 1e-9, "{u1} {u2}");
}

/// With `[output] vtu = true` a scene's buckling shapes are written as `buckling.vtu`, with the
/// load factors as field data equal to the report's (the shapes were in no file).
#[test]
fn scene_buckling_shapes_are_written() {
    let dir = std::env::temp_dir().join(format!("vibrofem_scene_buckling_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = Scene::parse(Path::new("column.toml"), &format!("{SCENE}\n[output]\nvtu = true\n")).unwrap();
    let r = scene.run(Some((&dir, ""))).unwrap();
    let vtu = dir.join("buckling.vtu");
    assert!(r.outputs.iter().any(|o| Path::new(o) == vtu), "{:?}", r.outputs);
    let text = std::fs::read_to_string(&vtu).unwrap();
    let lf = &r.buckling.as_ref().unwrap().load_factors;
    let field = text.split("Name=\"load_factors\"").nth(1).unwrap();
    let field: Vec<f64> = field[field.find('>').unwrap() + 1..]
        .split("</DataArray>")
        .next()
        .unwrap()
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(&field, lf);
    assert!(text.contains("Name=\"mode_2\""));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn scene_case_numbers_are_checked_by_line() {
    let bad = SCENE.replace("prestress = 2", "prestress = 3");
    let e = Scene::parse(Path::new("column.toml"), &bad).unwrap_err().to_string();
    assert!(
        e.contains("column.toml") && e.contains("load case number from 1 to 2"),
        "{e}"
    );
    let bad = SCENE.replace("case = 1", "case = 0");
    let e = Scene::parse(Path::new("column.toml"), &bad).unwrap_err().to_string();
    assert!(e.contains("[buckling] 'case'"), "{e}");
}
