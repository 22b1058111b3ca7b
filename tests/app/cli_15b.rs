//! Command-line regressions of issue 15 (items 9, 12, 13, 14, 15): memory refusals before
//! assembly and under `ulimit -v`, conflicting options, output paths checked up front.

use crate::common::{bin, run};
use std::process::Command;

/// Item 14: a model far beyond `--max-memory` is refused from the estimate (exit 1, the
/// estimate and the limit in the message), not aborted in assembly.
#[test]
fn max_memory_refuses_before_assembly() {
    let (code, _, err) = run(&["modes", "box:1,1,1:30,30,30:hex20", "--max-memory", "200M"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("needs at least") && err.contains("--max-memory is 200 MiB"),
        "{err}"
    );
}

/// Item 14: `ulimit -v` is honoured: the same model is refused naming the limit, and with
/// `--max-memory` set beyond it the allocation failure is still a clear error, never an abort.
#[test]
fn ulimit_is_honoured_and_allocation_failure_is_an_error() {
    let exe = env!("CARGO_BIN_EXE_vibrofem");
    for extra in ["", "--max-memory 100G"] {
        let o = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "ulimit -v 1500000 && exec {exe} modes box:1,1,1:30,30,30:hex20 --modes 3 {extra}"
            ))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{extra}: {err}");
        assert!(
            err.contains("ulimit -v") || err.contains("cannot allocate"),
            "{extra}: {err}"
        );
    }
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("vibrofem_cli15b_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

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

fn expect_error(args: &[&str], needles: &[&str]) {
    let (code, out, err) = run(args);
    assert_eq!(code, 1, "{args:?}: {out}{err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: '{n}' not in: {err}");
    }
}

const ROD: &str = "box:0.2,0.02,0.02:10,1,1:hex8";

/// Item 9: contradictory constraints are refused naming the group, node and DOF; consistent
/// ones (zero on a fixed edge) pass.
#[test]
fn conflicting_constraints_are_refused() {
    expect_error(
        &["static", ROD, "--fix", "xmin", "--displace", "xmin=0.001,-,-"],
        &["conflicting constraints", "'xmin'", "ux", "node ", "fixed by 'xmin'"],
    );
    expect_error(
        &[
            "static",
            ROD,
            "--fix",
            "xmin",
            "--couple",
            "xmax:guided=z",
            "--displace",
            "xmax=-,-,0.001,0.01,-,-",
        ],
        &["rx", "reference node of 'xmax'", "guided along z"],
    );
    expect_error(
        &["static", ROD, "--fix", "xmin", "--displace", "xmax=-,-,-,0.01,-,-"],
        &["'xmax'", "rx = 0.01", "no rotations"],
    );
    expect_error(
        &[
            "static",
            ROD,
            "--fix",
            "xmin",
            "--couple",
            "xmax:guided=z",
            "--displace",
            "xmax=-,-,0.001",
            "--force",
            "xmax=0,0,100",
        ],
        &[
            "force on 'xmax'",
            "z component",
            "reference node of 'xmax' uz",
            "prescribed displacement",
        ],
    );
    expect_error(
        &[
            "static",
            ROD,
            "--fix",
            "xmin",
            "--displace",
            "xmax=-,-,0.001",
            "--force",
            "xmax=0,0,100",
        ],
        &["force on 'xmax'", "uz", "prescribed displacement"],
    );
    // Consistent: a zero displacement where a support already holds zero; a force across the
    // prescribed component; a zero rotation on a guided coupling.
    for args in [
        &["static", ROD, "--fix", "xmin", "--displace", "zmin=-,-,0"][..],
        &[
            "static",
            ROD,
            "--fix",
            "xmin",
            "--displace",
            "xmax=-,-,0.001",
            "--force",
            "xmax=100,0,0",
        ][..],
        &[
            "static",
            ROD,
            "--fix",
            "xmin",
            "--couple",
            "xmax:guided=z",
            "--displace",
            "xmax=-,-,0.001,0,-,-",
        ][..],
    ] {
        let (code, out, err) = run(args);
        assert_eq!(code, 0, "{args:?}: {out}{err}");
    }
}

/// Item 12: beam sections that cannot exist, a radial orientation without an axis and an
/// indefinite point-mass inertia are refused at input, naming the option.
#[test]
fn impossible_sections_and_inertias_are_refused() {
    let coil = "helix:0.032,0.01,6,12,line3";
    for (beam, needle) in [
        ("wire=circle:-0.006@radial:0,0,0,0,0,1", "d = -0.006"),
        ("wire=tube:0.006,0.004@radial:0,0,0,0,0,1", "exceeds the radius"),
        ("wire=i:0.01,0.01,0.001,0.006@radial:0,0,0,0,0,1", "fill the height"),
        ("wire=circle:0.006@radial:0,0,0,0,0,0", "axis"),
    ] {
        expect_error(&["modes", coil, "--beam", beam, "--modes", "7"], &["--beam", needle]);
    }
    let (code, out, err) = run(&[
        "modes",
        coil,
        "--beam",
        "wire=tube:0.006,0.003@radial:0,0,0,0,0,1",
        "--modes",
        "7",
    ]);
    assert_eq!(code, 0, "a tube with wall d/2 is a solid circle: {out}{err}");
    let cube = "box:0.1,0.1,0.1:2,2,2:hex8";
    expect_error(
        &["modes", cube, "--couple", "xmax", "--point-mass", "xmax=1,-1,1,1,0,0,0"],
        &["point mass on 'xmax'", "positive semi-definite", "Ixx"],
    );
    expect_error(
        &["modes", cube, "--couple", "xmax", "--point-mass", "xmax=1,1,1,1,5,0,0"],
        &["positive semi-definite", "Ixy"],
    );
    let (code, out, err) = run(&[
        "modes",
        cube,
        "--couple",
        "xmax",
        "--point-mass",
        "xmax=1,1,1,1,0.1,0,0",
    ]);
    assert_eq!(code, 0, "{out}{err}");
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

/// Item 12: a file that is not a gmsh mesh (`/dev/zero`, text) is refused from its first
/// bytes, not read until memory runs out.
#[test]
fn non_mesh_files_are_refused_at_once() {
    expect_error(&["modes", "/dev/zero"], &["/dev/zero", "not a gmsh MSH file"]);
    let d = tmp("notmesh");
    let f = d.join("a.msh");
    std::fs::write(&f, "solid cube\nfacet normal 0 0 1\n").unwrap();
    expect_error(
        &["mesh-info", f.to_str().unwrap()],
        &["a.msh", "not a gmsh MSH file", "solid cube"],
    );
}

/// Item 12: mesh-info's bounding box covers the nodes the cells use, and says how many are
/// unused.
#[test]
fn mesh_info_bounding_box_skips_unused_nodes() {
    let d = tmp("bbox");
    let f = d.join("stray.msh");
    std::fs::write(
        &f,
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 100 100 100\n$EndNodes\n\
         $Elements\n1\n1 4 2 1 1 1 2 3 4\n$EndElements\n",
    )
    .unwrap();
    let (code, out, err) = run(&["mesh-info", f.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("1 belong to no element"), "{out}");
    assert!(out.contains("size    1.000000 x 1.000000 x 1.000000 m"), "{out}");
}

/// Item 13: a coupling on a one-node group of a solid works: the reference node's rotations,
/// which nothing can hold, are fixed with a note (it was a zero pivot).
#[test]
fn one_node_coupling_on_a_solid_is_solved() {
    let d = tmp("onenode");
    let f = d.join("pt.msh");
    std::fs::write(
        &f,
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n0 3 \"pt\"\n3 1 \"body\"\n$EndPhysicalNames\n\
         $Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n\
         $Elements\n3\n1 4 2 1 1 1 2 3 4\n2 4 2 1 1 2 3 4 5\n3 15 2 3 1 5\n$EndElements\n",
    )
    .unwrap();
    let (code, out, err) = run(&["modes", f.to_str().unwrap(), "--couple", "pt", "--modes", "3"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(
        err.contains("coupling 'pt'") && err.contains("rotations are held fixed"),
        "{err}"
    );
    // A translational spring to ground on the same one-node group (no coupling) is solved too.
    let (code, out, err) = run(&[
        "modes",
        f.to_str().unwrap(),
        "--spring",
        "pt=1e6,1e6,1e6,0,0,0",
        "--modes",
        "3",
    ]);
    assert_eq!(code, 0, "{out}{err}");
}

/// Item 12: design-file values within range that make minutes of work, and studies of tens of
/// thousands of designs, are refused with their size before any analysis unless `--yes`.
#[test]
fn large_designs_and_studies_need_yes() {
    let dir = std::env::temp_dir().join(format!("vibrofem-yes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = crate::common::root();
    let text = std::fs::read_to_string(root.join("scenes/designs/s8_transverse_webs.toml")).unwrap();
    assert!(text.contains("element_size = 0.025"));
    let big = dir.join("big.toml");
    std::fs::write(&big, text.replace("element_size = 0.025", "element_size = 0.004")).unwrap();
    let (code, _, err) = run(&["design", big.to_str().unwrap(), "-o", dir.join("d").to_str().unwrap()]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("DOFs") && err.contains("--yes"), "{err}");
    // The estimate is the models' size from their meshes: the built-in design is far below it.
    let paper = vibrofem::app::design::Design::paper();
    let n = vibrofem::app::design::estimate_dofs(&paper).unwrap();
    assert!(n > 1000 && n < vibrofem::app::design::LARGE_DESIGN_DOFS, "{n}");
    let study = root.join("scenes/studies/study_s7_table.toml");
    let (code, _, err) = run(&[
        "sweep",
        study.to_str().unwrap(),
        "--set",
        "top_thickness=0.01:0.03:0.0005",
        "--set",
        "bottom_thickness=0.005:0.02:0.0005",
        "-o",
        dir.join("s").to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("designs (more than 1000)") && err.contains("--yes"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
