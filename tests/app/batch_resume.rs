//! `vibrofem batch` resumes by the mesh's path and a hash of the mesh and the template, and two
//! meshes of one stem get their own result files.

use super::support::tmp;
use crate::common::bin;

/// Status column of each row of a batch's summary.csv, in file order.
fn statuses(out: &std::path::Path) -> Vec<String> {
    let csv = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    csv.lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().to_string())
        .collect()
}

/// Item 9: batch resume is keyed by the mesh's path and a hash of the mesh and template:
/// an edited template or mesh is rerun, another mesh of the same name into the same folder is
/// rerun, and two meshes of one stem in one batch get their own result files.
#[test]
fn batch_resume_is_keyed_by_content_and_path() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let d = tmp("resume");
    std::fs::create_dir_all(d.join("a")).unwrap();
    std::fs::create_dir_all(d.join("b")).unwrap();
    let mesh = root.join("meshes/s1_plate_tet4_h30.msh");
    std::fs::copy(&mesh, d.join("a/m.msh")).unwrap();
    std::fs::copy(&mesh, d.join("a/m.msh2")).unwrap();
    std::fs::copy(root.join("meshes/s1_plate_tet4_h20.msh"), d.join("b/m.msh")).unwrap();
    let tpl = std::fs::read_to_string(root.join("scenes/s1_plate_solid.toml")).unwrap();
    std::fs::write(d.join("t.toml"), &tpl).unwrap();
    let batch = |pattern: &str| {
        let o = bin()
            .current_dir(&d)
            .args(["batch", pattern, "--scene", "t.toml", "-o", "out"])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        statuses(&d.join("out"))
    };
    // One stem, two files: two results, neither resumed from the other.
    assert_eq!(batch("a/m.msh*"), ["ok", "ok"]);
    assert!(d.join("out/m.msh.json").is_file() && d.join("out/m.msh2.json").is_file());
    assert_eq!(batch("a/m.msh*"), ["resumed", "resumed"]);
    // The template changed: rerun.
    std::fs::write(d.join("t.toml"), tpl.replace("modes = 7", "modes = 8")).unwrap();
    assert_eq!(batch("a/m.msh*"), ["ok", "ok"]);
    // One mesh changed: only it is rerun.
    let mut text = std::fs::read_to_string(d.join("a/m.msh2")).unwrap();
    text.push_str("$Comments\nedited\n$EndComments\n");
    std::fs::write(d.join("a/m.msh2"), text).unwrap();
    assert_eq!(batch("a/m.msh*"), ["resumed", "ok"]);
    // Another mesh with the same name into the same folder is not the first one's result.
    assert_eq!(batch("a/m.msh"), ["ok"]);
    assert_eq!(batch("a/m.msh"), ["resumed"]);
    let first = std::fs::read_to_string(d.join("out/summary.csv")).unwrap();
    assert_eq!(batch("b/m.msh"), ["ok"]);
    let second = std::fs::read_to_string(d.join("out/summary.csv")).unwrap();
    let dofs = |csv: &str| csv.lines().nth(1).unwrap().split(',').nth(3).unwrap().to_string();
    assert_ne!(dofs(&first), dofs(&second), "{first}\n{second}");
}

/// Names that still collide after taking whole file names (`m.msh` beside `m.msh2`, and
/// `m.msh.msh` whose stem is `m.msh`), and a mesh called `summary`, get their own result files:
/// one report was overwritten and rerun on every resume, and `summary.json` overwrote a case.
#[test]
fn colliding_result_names_and_summary_get_their_own_files() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let d = tmp("collide");
    std::fs::create_dir_all(d.join("a")).unwrap();
    let mesh = root.join("meshes/s1_plate_tet4_h30.msh");
    for name in ["m.msh", "m.msh2", "m.msh.msh", "summary.msh"] {
        std::fs::copy(&mesh, d.join("a").join(name)).unwrap();
    }
    let tpl = std::fs::read_to_string(root.join("scenes/s1_plate_solid.toml")).unwrap();
    std::fs::write(d.join("t.toml"), &tpl).unwrap();
    let batch = || {
        let o = bin()
            .current_dir(&d)
            .args(["batch", "a/*", "--scene", "t.toml", "-o", "out"])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        statuses(&d.join("out"))
    };
    assert_eq!(batch(), ["ok", "ok", "ok", "ok"]);
    assert_eq!(batch(), ["resumed", "resumed", "resumed", "resumed"]);
    let mut cases: Vec<String> = std::fs::read_dir(d.join("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".json") && n != "summary.json")
        .collect();
    cases.sort();
    assert_eq!(cases.len(), 4, "{cases:?}");
}

/// A batch whose template asks for a harmonic response only reports each case's DOFs in the
/// summary (the column was empty: only the modal and static reports were read).
#[test]
fn a_harmonic_batch_reports_its_dofs() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let d = tmp("harmonic_batch");
    std::fs::create_dir_all(d.join("m")).unwrap();
    std::fs::copy(root.join("meshes/s3_leaf_hex20_10x6x1.msh"), d.join("m/leaf.msh")).unwrap();
    let tpl = std::fs::read_to_string(root.join("scenes/s3_leaf_harmonic.toml"))
        .unwrap()
        .replace("sweep_hz = [5.0, 120.0, 116]", "sweep_hz = [5.0, 10.0, 2]")
        .replace("vtu = true", "vtu = false");
    std::fs::write(d.join("t.toml"), tpl).unwrap();
    let o = bin()
        .current_dir(&d)
        .args(["batch", "m/*.msh", "--scene", "t.toml", "-o", "out"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("out/summary.json")).unwrap()).unwrap();
    let dofs = json["rows"][0]["dofs"].as_u64();
    assert!(dofs.is_some_and(|n| n > 100), "{}", json["rows"][0]);
}
