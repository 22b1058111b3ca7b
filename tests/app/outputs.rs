//! Where the results go: a closed pipe on stdout ends quietly, a full disk is an output error
//! (exit 4), and output paths are checked (and missing folders created) before the run.

use super::support::{BAR, expect_error, tmp};
use crate::common::{bin, run};
use std::process::Stdio;

/// Item 10: stdout closed before anything is written: no panic (101); quiet exit 0 or 141.
#[test]
fn closed_stdout_is_quiet() {
    for args in [
        &["modes", BAR, "--fix", "xmin", "--modes", "2"][..],
        &["modes", BAR, "--fix", "xmin", "--modes", "2", "--json"][..],
        &["mesh-info", BAR][..],
    ] {
        // The reader is gone before the child starts, so the first write meets a closed pipe.
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let child = bin().args(args).stdout(writer).stderr(Stdio::piped()).spawn().unwrap();
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        let code = o.status.code();
        assert_eq!(code, Some(141), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// Item 10: a full disk on stdout is an output error (exit 4), not a panic.
#[test]
fn full_stdout_exits_4() {
    if !std::path::Path::new("/dev/full").exists() {
        return;
    }
    for args in [
        &["modes", BAR, "--fix", "xmin", "--modes", "2"][..],
        &["mesh-info", BAR][..],
    ] {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let o = bin().args(args).stdout(full).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(4), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// An output folder (or a folder on a result file's path) that is an existing file: the
/// message was the system's bare "File exists (os error 17)"; now it says which path is a file.
#[test]
fn an_output_folder_that_is_a_file_is_named() {
    let f = tmp("folder_is_file").join("results");
    std::fs::write(&f, "").unwrap();
    let fs = f.to_str().unwrap();
    expect_error(
        &["sweep", "scenes/studies/study_s7_table.toml", "-o", fs],
        &["is a file, not a folder"],
    );
    let inner = format!("{fs}/sub/modes.vtu");
    expect_error(
        &["modes", BAR, "--fix", "xmin", "--modes", "2", "--vtu", &inner],
        &[&format!("'{fs}' in the path is a file")],
    );
}

/// The same for a result file on a full disk (`--vtu`, `--msh-out`): created, not written,
/// exit 4 as the README's table says, where it was 1 (an input error).
#[test]
fn full_disk_for_a_result_file_exits_4() {
    if !std::path::Path::new("/dev/full").exists() {
        return;
    }
    for opt in ["--vtu", "--msh-out"] {
        let (code, _, err) = run(&["modes", BAR, "--fix", "xmin", "--modes", "2", opt, "/dev/full"]);
        assert_eq!(code, 4, "{opt}: {err}");
        assert!(err.contains("/dev/full") && !err.contains("panicked"), "{opt}: {err}");
    }
}

/// Item 12: an output path that cannot be written is refused before the run, naming it; a
/// missing folder is created.
#[test]
fn output_paths_are_checked_before_the_run() {
    let cube = "box:0.1,0.1,0.1:2,2,2:hex8";
    expect_error(&["modes", cube, "--vtu", "/proc/no/such/x.vtu"], &["/proc/no"]);
    let d = tmp("outputs");
    expect_error(&["modes", cube, "--vtu", d.to_str().unwrap()], &["is a folder"]);
    expect_error(
        &["static", cube, "--fix", "xmin", "--msh-out", "/proc/no/x.msh"],
        &["/proc/no"],
    );
    expect_error(
        &["run", "scenes/s3_leaf_stiffness.toml", "-o", "/proc/no/run"],
        &["/proc/no/run"],
    );
    let f = d.join("new/folder/m.vtu");
    let (code, out, err) = run(&["modes", cube, "--modes", "7", "--vtu", f.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(f.is_file());
}

/// A result file draws the model that was solved: a shell model meshed on a box's bricks is
/// written as its quad4 shells (the bricks were written, with the shells left out), with the
/// shells' rotations beside the translations and the frequencies as field data; in gmsh each
/// mode is a view of its own at time step 0 (at step k − 1, gmsh showed mode k's first, empty
/// step). The VTU's cells are counted from the file's `types` array (VTK_QUAD = 9,
/// VTK_HEXAHEDRON = 12).
#[test]
fn result_files_draw_the_model_solved() {
    let d = tmp("model_cells");
    let (vtu, msh) = (d.join("sh.vtu"), d.join("sh.msh"));
    let (code, out, err) = run(&[
        "modes",
        "box:0.3,0.3,0.02:6,6,1:hex8",
        "--shell",
        "zmin=0.02",
        "--modes",
        "8",
        "--vtu",
        vtu.to_str().unwrap(),
        "--msh-out",
        msh.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let text = std::fs::read_to_string(&vtu).unwrap();
    let types = text.split("Name=\"types\" format=\"ascii\">\n").nth(1).unwrap();
    let types: Vec<&str> = types.split("</DataArray>").next().unwrap().split_whitespace().collect();
    assert_eq!(types.len(), 36, "6 × 6 shells");
    assert!(types.iter().all(|t| *t == "9"), "quads only: {types:?}");
    assert!(text.contains("Name=\"mode_8_rotation\""), "rotations of the shells");
    assert!(text.contains("<FieldData>") && text.contains("Name=\"frequencies_hz\" NumberOfTuples=\"8\""));
    // Every $NodeData section: 1, name, 1, time value, 3, then the time step index (0 for
    // every mode).
    let msh_text = std::fs::read_to_string(&msh).unwrap();
    let steps: Vec<&str> = msh_text
        .split("$NodeData\n")
        .skip(1)
        .map(|s| s.lines().nth(5).unwrap())
        .collect();
    assert!(
        steps.len() >= 8 && steps.iter().all(|s| *s == "0"),
        "time steps {steps:?}"
    );
}

/// A shell model has no recovered stresses: its static VTU holds displacements and rotations,
/// not stress fields of zeros that read as an unloaded part. The harmonic msh has its
/// `amplitude` view as documented.
#[test]
fn no_zero_stresses_for_shells_and_the_harmonic_amplitude_in_gmsh() {
    let d = tmp("shell_static");
    let vtu = d.join("s.vtu");
    let (code, out, err) = run(&[
        "static",
        "box:0.3,0.05,0.002:10,2,1:hex8",
        "--shell",
        "zmin=0.002",
        "--fix",
        "xmin:all",
        "--force",
        "xmax=0,0,10",
        "--vtu",
        vtu.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let text = std::fs::read_to_string(&vtu).unwrap();
    assert!(text.contains("Name=\"displacement\"") && text.contains("Name=\"rotation\""));
    assert!(!text.contains("von_mises") && !text.contains("Name=\"stress\""));
    let msh = d.join("h.msh");
    let (code, out, err) = run(&[
        "harmonic",
        "box:0.5,0.05,0.02:10,1,1:hex20",
        "--fix",
        "xmin",
        "--force",
        "xmax=0,0,10",
        "--freq",
        "50",
        "--damping",
        "0.02",
        "--msh-out",
        msh.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        std::fs::read_to_string(&msh)
            .unwrap()
            .contains("\"amplitude at 50.000 Hz\"")
    );
}

/// A file named otherwise than its format is refused before the run (a VTU named `.msh` was
/// written, and gmsh could not open it); devices keep working (the /dev/full test above).
#[test]
fn an_output_named_for_another_format_is_refused() {
    let d = tmp("extensions");
    let p = |n: &str| d.join(n).to_str().unwrap().to_string();
    let cube = "box:0.1,0.1,0.1:2,2,2:hex8";
    expect_error(&["modes", cube, "--vtu", &p("m.msh")], &["--vtu", "m.msh", ".vtu"]);
    expect_error(&["modes", cube, "--msh-out", &p("m.vtu")], &["--msh-out", ".msh"]);
    expect_error(&["modes", cube, "--vtu", &p("m")], &["has no extension"]);
    assert!(std::fs::read_dir(&d).unwrap().next().is_none(), "nothing written");
    let (code, out, err) = run(&["modes", cube, "--modes", "2", "--vtu", &p("M.VTU")]);
    assert_eq!(code, 0, "{out}{err}");
}

/// `mesh-info` on a file drawn in millimetres read as metres says so (a 300 m plate of 14 Gt
/// went without a word), and on a model of surfaces that its volume and mass count solids only.
#[test]
fn mesh_info_notes_units_and_surfaces() {
    let (code, _, err) = run(&["mesh-info", "meshes/s1_plate_tet10_h30_mm.msh"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("300 m across") && err.contains("--length-unit mm"),
        "{err}"
    );
    let (code, _, err) = run(&["mesh-info", "meshes/s1_plate_tet10_h30_mm.msh", "--length-unit", "mm"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("across"), "{err}");
    let (code, _, err) = run(&["mesh-info", "sandwich:paper"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("no volume elements"), "{err}");
}

/// The floats of the VTU array that follows `marker` (e.g. `Name="mode_1"`).
fn vtu_array(text: &str, marker: &str) -> Vec<f64> {
    let body = text.split(marker).nth(1).unwrap();
    let body = &body[body.find('>').unwrap() + 1..];
    body.split("</DataArray>")
        .next()
        .unwrap()
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect()
}

/// A buckling shape's rotations are scaled and signed as its translations (they came from the
/// solver's vector as it was, 208 times too small and of the other sign at the tip of a shell
/// strip). Kirchhoff kinematics: u_z = −x·r_y, so along a strip bent in its x–z plane the
/// nodal r_y equals −∂u_z/∂x; at the tip of 20 elements the one-sided difference of the last
/// element agrees within 10 % (its error is half the element's change of slope).
#[test]
fn buckling_rotations_are_scaled_as_the_translations() {
    let d = tmp("buckling_rotations");
    let vtu = d.join("b.vtu");
    let (code, out, err) = run(&[
        "buckling",
        "box:0.5,0.1,0.01:20,4,1:hex8",
        "--shell",
        "zmin=0.01",
        "--fix",
        "xmin:ux,uy,uz,rx,ry,rz",
        "--force",
        "xmax=-1,0,0",
        "--modes",
        "1",
        "--vtu",
        vtu.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let text = std::fs::read_to_string(&vtu).unwrap();
    let (x, u, r) = (
        vtu_array(&text, "<Points>"),
        vtu_array(&text, "Name=\"mode_1\""),
        vtu_array(&text, "Name=\"mode_1_rotation\""),
    );
    // The node at the tip's mid-width on the shell plane (z = 0) and its neighbour along x.
    let node = |px: f64| {
        (0..x.len() / 3)
            .find(|&a| (x[3 * a] - px).abs() < 1e-9 && (x[3 * a + 1] - 0.05).abs() < 1e-9 && x[3 * a + 2].abs() < 1e-9)
            .unwrap()
    };
    let (tip, before) = (node(0.5), node(0.475));
    let slope = (u[3 * tip + 2] - u[3 * before + 2]) / 0.025;
    let ry = r[3 * tip + 1];
    assert!(
        (ry + slope).abs() < 0.1 * slope.abs(),
        "r_y {ry} against −∂u_z/∂x {}",
        -slope
    );
}
