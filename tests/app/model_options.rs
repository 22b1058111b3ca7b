//! The model options on the command line: sections (one per group, dimensions that can
//! exist), point-mass inertias, coupling reference points and the large-rotation note,
//! one-node couplings and springs on a solid, contradictory constraints, and a load whose
//! solution overflows.

use super::support::{expect_error, tmp};
use crate::common::run;

/// Item 9: a force that overflows double precision gave |u| = inf with exit 0; a non-finite
/// solution is a numerical failure (exit 2). The same model at 1 kN stays fine.
#[test]
fn overflowing_static_load_is_a_numerical_failure() {
    let model = ["box:0.1,0.02,0.02:10,2,2:hex8", "--fix", "xmin"];
    let mut args = vec!["static"];
    args.extend(model);
    args.extend(["--force", "xmax=0,0,1e300"]);
    let (code, out, err) = run(&args);
    assert_eq!(code, 2, "{out}{err}");
    assert!(err.contains("not finite"), "{err}");
    let mut args = vec!["static"];
    args.extend(model);
    args.extend(["--force", "xmax=0,0,1e3"]);
    let (code, _, err) = run(&args);
    assert_eq!(code, 0, "{err}");
}

/// Item 9: `--shell G=…` twice stacked two layers (mass ×2); each group takes one section.
#[test]
fn a_group_given_two_sections_is_refused() {
    let (code, _, err) = run(&[
        "modes",
        "box:0.3,0.3,0.02:10,10,1:hex8",
        "--shell",
        "zmin=0.02",
        "--shell",
        "zmin=0.02",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("group 'zmin' is given two sections"), "{err}");
}

/// Item 3: a coupling's reference node can be placed (`GROUP@X,Y,Z`); a linear solution with
/// rotations beyond the small-displacement range says so. The coil's end face has its centroid
/// off the axis: the axial load there tilts the end by about 0.5 rad (flagged); on the axis it
/// does not (the end only twists by the coil's wind-up, 0.0135 rad).
#[test]
fn coupling_reference_point_and_large_rotation_note() {
    let coil = [
        "static",
        "helix:0.032,0.01,6,12,line3",
        "--beam",
        "wire=circle:0.006@radial:0,0,0,0,0,1",
        "--material",
        "2.002e11,0.3,7850",
        "--fix",
        "end_bottom:all",
        "--force",
        "end_top=0,0,-600",
        "--couple",
    ];
    let mut a = coil.to_vec();
    a.push("end_top");
    let (code, out, err) = run(&a);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("note: rotation") && out.contains("small-displacement"),
        "{out}"
    );
    let mut a = coil.to_vec();
    a.push("end_top@0,0,0.06");
    let (code, out, err) = run(&a);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("note: rotation"), "{out}");
    // A malformed point is an input error naming the grammar.
    let mut a = coil.to_vec();
    a.push("end_top@0,0");
    let (code, _, err) = run(&a);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("GROUP[@X,Y,Z][:guided=AXIS]"), "{err}");
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
