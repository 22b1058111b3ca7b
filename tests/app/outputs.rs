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

/// A shell model has no solid stresses: its static VTU holds displacements, rotations and the
/// shells' face stresses, not solid stress fields of zeros that read as an unloaded part. The
/// harmonic msh has its `amplitude` view as documented.
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
    assert!(!text.contains("Name=\"von_mises\"") && !text.contains("Name=\"stress\""));
    assert!(text.contains("Name=\"shell_top_von_mises\""));
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

/// Shell stresses against the textbook beam formula σ = M c / I = 6 M / (b t²) (Gere and
/// Timoshenko, *Mechanics of Materials*, flexure formula): a cantilever strip of shells
/// (0.5 × 0.05 m, t = 5 mm, 20 × 2 quad4) clamped at x = 0 with 10 N across its free end. The
/// strip is a beam (b²/(R t) ≪ 1 for its curvature radius R: the anticlastic curvature is
/// free, σ_yy ≈ 0), so σ_xx = ∓ 6 F (L − x)/(b t²) on the faces, the sign by the side the
/// normal points to. A quad4's bending strain is constant along x, the moment at its centre;
/// the two elements averaged at a node give the linear moment at the node itself, so the
/// nodal values at x = L/4, L/2 and 3L/4 (the mean over the three nodes across) agree within
/// 1e-3 (measured 9.6e-5, 1.3e-7, 3.3e-6: the clamp's boundary layer, where the strip cannot
/// curl across, σ_yy = ν σ_xx, decays within a few widths; at the clamp itself 1.9 %). The
/// bottom face is the top's opposite; the report's maxima are the files' maxima.
#[test]
fn shell_face_stresses_follow_the_flexure_formula() {
    let d = tmp("shell_faces");
    let (vtu, msh) = (d.join("s.vtu"), d.join("s.msh"));
    let (code, out, err) = run(&[
        "static",
        "box:0.5,0.05,0.005:20,2,1:hex8",
        "--shell",
        "zmin=0.005",
        "--fix",
        "xmin:all",
        "--force",
        "xmax=0,0,10",
        "--vtu",
        vtu.to_str().unwrap(),
        "--msh-out",
        msh.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let text = std::fs::read_to_string(&vtu).unwrap();
    let points = vtu_array(&text, "<Points>");
    let top = vtu_array(&text, "Name=\"shell_top_stress\"");
    let bottom = vtu_array(&text, "Name=\"shell_bottom_stress\"");
    let normal = vtu_array(&text, "Name=\"shell_normal\"");
    let (l, b, t, f) = (0.5, 0.05, 0.005, 10.0);
    for x in [0.125, 0.25, 0.375] {
        let at: Vec<usize> = (0..points.len() / 3)
            .filter(|&a| (points[3 * a] - x).abs() < 1e-9 && points[3 * a + 2].abs() < 1e-9)
            .collect();
        assert_eq!(at.len(), 3, "three shell nodes across the strip at x = {x}");
        let mean = |v: &[f64]| at.iter().map(|&a| v[6 * a]).sum::<f64>() / 3.0;
        let nz = normal[3 * at[0] + 2];
        assert!((nz.abs() - 1.0).abs() < 1e-12, "normal ±z: {nz}");
        let expected = -nz * 6.0 * f * (l - x) / (b * t * t);
        let (st, sb) = (mean(&top), mean(&bottom));
        assert!(
            (st / expected - 1.0).abs() < 1e-3,
            "x = {x}: σ_xx top {st:.6e} Pa, flexure formula {expected:.6e}"
        );
        assert!(
            (sb + st).abs() < 1e-9 * st.abs(),
            "bottom {sb:.6e} against top {st:.6e}"
        );
    }
    let vm_top = vtu_array(&text, "Name=\"shell_top_von_mises\"");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    let all = &report["stress"][0]["shell_von_mises_top"][0];
    assert_eq!(all["group"], "(all)");
    let max = vm_top.iter().fold(0.0f64, |a, &v| a.max(v));
    assert!(
        (all["value"].as_f64().unwrap() - max).abs() <= 1e-6 * max,
        "{all} against {max}"
    );
    let views = std::fs::read_to_string(&msh).unwrap();
    for name in ["shell_top_stress", "shell_bottom_von_mises", "shell_normal"] {
        assert!(views.contains(&format!("\"{name}\"")), "{name} in the gmsh file");
    }
}

/// Beam stresses against the flexure formula σ = M c / I (Gere and Timoshenko, *Mechanics of
/// Materials*): a 1 m cantilever of ten two-node beams, a 20 × 40 mm rectangle with its depth
/// along z, 100 N along z at the free end: M_y = F L = 100 N·m at the clamp, σ = 6 M/(b h²) =
/// 18.75 MPa at its extreme fibres. The end forces K_e u_e of a two-node element balance the
/// nodal loads to the solve's residual (~1e-12 here), so the maximum is that value within
/// 1e-9, in the element at the clamp; the VTU field holds it at the clamped node. A section
/// given by its properties has no fibres: no stress, a note saying why.
#[test]
fn beam_stresses_follow_the_flexure_formula() {
    let d = tmp("beam_stress");
    let vtu = d.join("b.vtu");
    let args = |section: &'static str| {
        vec![
            "static".to_string(),
            "ibeam-line:1.0,10".into(),
            "--beam".into(),
            format!("beam={section}@0,1,0"),
            "--fix".into(),
            "end_a:all".into(),
            "--force".into(),
            "end_b=0,0,100".into(),
            "--json".into(),
            "--vtu".into(),
            vtu.to_str().unwrap().into(),
        ]
    };
    let a = args("rect:0.02,0.04");
    let (code, out, err) = run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{out}{err}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    let all = &report["stress"][0]["beam_normal_stress"][0];
    assert_eq!(all["group"], "(all)");
    let sigma = 6.0 * 100.0 / (0.02 * 0.04 * 0.04);
    let value = all["value"].as_f64().unwrap();
    assert!((value / sigma - 1.0).abs() < 1e-9, "{value} Pa against {sigma} Pa");
    assert!(
        (all["resultants"][4].as_f64().unwrap().abs() - 100.0).abs() < 1e-7,
        "{all}"
    );
    assert!(all["coords"][0].as_f64().unwrap().abs() < 1e-12, "at the clamp: {all}");
    let text = std::fs::read_to_string(&vtu).unwrap();
    let field = vtu_array(&text, "Name=\"beam_normal_stress\"");
    let max = field.iter().fold(0.0f64, |m, &v| m.max(v));
    assert!((max / sigma - 1.0).abs() < 1e-9, "{max}");
    let a = args("custom:8e-4,1.0667e-7,2.6667e-8,7.3e-8,0.85,0.85,0");
    let (code, out, err) = run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{out}{err}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(
        report["stress"][0].get("beam_normal_stress").is_none(),
        "{}",
        report["stress"][0]
    );
    assert!(out.contains("has no extreme fibres"), "{out}");
}

/// The `static --json` report of the beams of `mesh` (`--beam` part `beam`) clamped at the
/// group `clamp` with 100 N along z on the group `tip`.
fn cantilever_json(mesh: &std::path::Path, beam: &str) -> serde_json::Value {
    let (code, out, err) = run(&[
        "static",
        mesh.to_str().unwrap(),
        "--beam",
        beam,
        "--fix",
        "clamp:all",
        "--force",
        "tip=0,0,100",
        "--json",
    ]);
    assert_eq!(code, 0, "{out}{err}");
    serde_json::from_str(&out).unwrap()
}

/// Three-node beams and the torsion of round sections against statics: an L-shaped frame of
/// line3 elements (a 1 m arm along x clamped at the origin, a 0.4 m lever along y at its end,
/// a 20 mm round bar) with 100 N along z at the lever's tip. Statically determinate: at the
/// clamp the arm carries M = F·1 m about y and T = F·0.4 m about its axis, so σ = M r / I =
/// 127.3 MPa and τ = T r / J = 25.46 MPa (Gere and Timoshenko, flexure and torsion
/// formulas). The end forces of the elements are the section's resultants whenever the loads
/// sit at the nodes, so both agree within 1e-9 (the solve's residual).
#[test]
fn three_node_beams_and_torsion_follow_statics() {
    let d = tmp("beam_line3");
    let mesh = d.join("frame.msh");
    std::fs::write(
        &mesh,
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n0 2 \"clamp\"\n0 3 \"tip\"\n1 1 \"frame\"\n\
         $EndPhysicalNames\n$Nodes\n7\n1 0 0 0\n2 0.25 0 0\n3 0.5 0 0\n4 0.75 0 0\n5 1 0 0\n6 1 0.2 0\n7 1 0.4 0\n\
         $EndNodes\n$Elements\n5\n1 15 2 2 1 1\n2 15 2 3 2 7\n3 8 2 1 1 1 3 2\n4 8 2 1 1 3 5 4\n5 8 2 1 1 5 7 6\n$EndElements\n",
    )
    .unwrap();
    let report = cantilever_json(&mesh, "frame=circle:0.02@0,0,1");
    let pi = std::f64::consts::PI;
    let (r, i) = (0.01, pi * 0.02f64.powi(4) / 64.0);
    for (key, expected) in [
        ("beam_normal_stress", 100.0 * r / i),
        ("beam_torsion_shear", 40.0 * r / (2.0 * i)),
    ] {
        let all = &report["stress"][0][key][0];
        let value = all["value"].as_f64().unwrap();
        assert!(
            (value / expected - 1.0).abs() < 1e-9,
            "{key}: {value} Pa against {expected} Pa"
        );
        assert_eq!(all["element"], 3, "{key} in the element at the clamp: {all}");
    }
}

/// A gmsh 2.2 file of `nodes` (x, y, z) and `elements` (gmsh type, physical tag, nodes), with
/// the physical names `names` (dimension, tag, name).
fn msh22(names: &[(u8, u32, &str)], nodes: &[[f64; 3]], elements: &[(u32, u32, &[u32])]) -> String {
    let mut s = format!(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n{}\n",
        names.len()
    );
    for (d, t, n) in names {
        s += &format!("{d} {t} \"{n}\"\n");
    }
    s += &format!("$EndPhysicalNames\n$Nodes\n{}\n", nodes.len());
    for (i, p) in nodes.iter().enumerate() {
        s += &format!("{} {} {} {}\n", i + 1, p[0], p[1], p[2]);
    }
    s += &format!("$EndNodes\n$Elements\n{}\n", elements.len());
    for (i, (kind, tag, conn)) in elements.iter().enumerate() {
        let conn: Vec<String> = conn.iter().map(|n| n.to_string()).collect();
        s += &format!("{} {kind} 2 {tag} {tag} {}\n", i + 1, conn.join(" "));
    }
    s + "$EndElements\n"
}

/// A strip of four quads meshed with alternate orientations (no offset: the model keeps them
/// as read) has one top face: the normal and the sign of σ_xx on top are the same at every
/// node (the top switched sides from node to node, so a bent strip read tension, compression,
/// tension along its top). A quad with a degenerate corner (a straight angle, valid at its
/// integration points, accepted by the analysis) gives its centre's stress to its nodes
/// instead of failing the run.
#[test]
fn a_shell_surface_has_one_top_face() {
    let d = tmp("shell_top");
    let mesh = d.join("strip.msh");
    let nodes: Vec<[f64; 3]> = (0..10)
        .map(|i| [0.1 * (i / 2) as f64, 0.05 * (i % 2) as f64, 0.0])
        .collect();
    let quads: [&[u32]; 4] = [&[1, 3, 4, 2], &[3, 4, 6, 5], &[5, 7, 8, 6], &[7, 8, 10, 9]];
    let mut elements: Vec<(u32, u32, &[u32])> = vec![(1, 1, &[1, 2]), (1, 2, &[9, 10])];
    elements.extend(quads.iter().map(|q| (3, 3, *q)));
    let names = [(1, 1, "clamp"), (1, 2, "tip"), (2, 3, "plate")];
    std::fs::write(&mesh, msh22(&names, &nodes, &elements)).unwrap();
    let vtu = d.join("s.vtu");
    let (code, out, err) = run(&[
        "static",
        mesh.to_str().unwrap(),
        "--shell",
        "plate=0.005",
        "--fix",
        "clamp:all",
        "--force",
        "tip=0,0,10",
        "--vtu",
        vtu.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{out}{err}");
    let text = std::fs::read_to_string(&vtu).unwrap();
    let normal = vtu_array(&text, "Name=\"shell_normal\"");
    let top = vtu_array(&text, "Name=\"shell_top_stress\"");
    for a in 0..10 {
        assert_eq!(
            normal[3 * a + 2],
            normal[2],
            "node {a}: {:?}",
            &normal[3 * a..3 * a + 3]
        );
        // σ_xx on the top face: −n_z · 6 F (L − x)/(b t²) in sign (the strip bends up).
        assert!(
            top[6 * a] * normal[2] < 0.0 || a >= 8,
            "node {a}: σ_xx {} Pa",
            top[6 * a]
        );
    }
    let corner = d.join("corner.msh");
    let nodes = [
        [0.0, 0.0, 0.0],
        [0.1, 0.0, 0.0],
        [0.1, 0.1, 0.0],
        [0.0, 0.1, 0.0],
        [0.0505, 0.0495, 0.0],
    ];
    let elements: [(u32, u32, &[u32]); 4] = [
        (1, 1, &[1, 4]),
        (15, 2, &[2]),
        (3, 3, &[1, 2, 3, 5]),
        (3, 3, &[1, 5, 3, 4]),
    ];
    std::fs::write(
        &corner,
        msh22(&[(1, 1, "clamp"), (0, 2, "tip"), (2, 3, "plate")], &nodes, &elements),
    )
    .unwrap();
    let (code, out, err) = run(&[
        "static",
        corner.to_str().unwrap(),
        "--shell",
        "plate=0.005",
        "--fix",
        "clamp:all",
        "--force",
        "tip=0,0,10",
    ]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("shell top    von Mises max (all)"), "{out}");
}

/// What beam stresses leave out is said in a note, in the text report too (a `custom:` arm
/// beside a round lever printed the lever's stress as the model's largest and nothing else);
/// a line3 beam with its midside node at a quarter point (a vanishing end tangent) is
/// recovered along its chord: a 2 m cantilever of two such elements, 20 × 40 mm, 100 N at the
/// tip: σ = 6 F L/(b h²) = 37.5 MPa at the clamp (statics; the solve's residual, 1e-9).
#[test]
fn beam_stress_notes_and_a_quarter_point_line3() {
    let d = tmp("beam_notes");
    let frame = d.join("frame.msh");
    let nodes = [
        [0.0, 0.0, 0.0],
        [0.5, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 0.2, 0.0],
        [1.0, 0.4, 0.0],
    ];
    let elements: [(u32, u32, &[u32]); 6] = [
        (15, 1, &[1]),
        (15, 2, &[5]),
        (1, 3, &[1, 2]),
        (1, 3, &[2, 3]),
        (1, 4, &[3, 4]),
        (1, 4, &[4, 5]),
    ];
    let names = [(0, 1, "clamp"), (0, 2, "tip"), (1, 3, "arm"), (1, 4, "lever")];
    std::fs::write(&frame, msh22(&names, &nodes, &elements)).unwrap();
    let run_frame = |arm: &str| {
        let (code, out, err) = run(&[
            "static",
            frame.to_str().unwrap(),
            "--beam",
            arm,
            "--beam",
            "lever=circle:0.05@0,0,1",
            "--fix",
            "clamp:all",
            "--force",
            "tip=0,0,100",
        ]);
        assert_eq!(code, 0, "{out}{err}");
        err
    };
    let err = run_frame("arm=custom:8e-4,1.0667e-7,2.6667e-8,7.3e-8,0.85,0.85,0@0,1,0");
    assert!(err.contains("beam 'arm': stresses not recovered"), "{err}");
    let err = run_frame("arm=gost8239-10+warping@0,1,0");
    assert!(
        err.contains("warping (bimoment)") && err.contains("round sections only (torque up to 40"),
        "{err}"
    );
    let line3 = d.join("l3.msh");
    let nodes = [
        [0.0, 0.0, 0.0],
        [0.25, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.5, 0.0, 0.0],
        [2.0, 0.0, 0.0],
    ];
    let elements: [(u32, u32, &[u32]); 4] = [(15, 1, &[1]), (15, 2, &[5]), (8, 3, &[1, 3, 2]), (8, 3, &[3, 5, 4])];
    std::fs::write(
        &line3,
        msh22(&[(0, 1, "clamp"), (0, 2, "tip"), (1, 3, "beam")], &nodes, &elements),
    )
    .unwrap();
    let report = cantilever_json(&line3, "beam=rect:0.02,0.04@0,1,0");
    let value = report["stress"][0]["beam_normal_stress"][0]["value"].as_f64().unwrap();
    assert!((value / 37.5e6 - 1.0).abs() < 1e-9, "{value}");
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
