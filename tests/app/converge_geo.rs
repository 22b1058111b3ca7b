//! `vibrofem converge PART.geo`: a speed–accuracy study on the user's own gmsh geometry (the
//! S2 plate of shared/spec/scenes.md, meshes/s2_plate.geo), a set of meshes the user made, and
//! the errors of a geometry gmsh cannot mesh.
//!
//! gmsh comes from the validation venv (validation/python.sh makes validation/.venv, whose
//! python has the PyPI gmsh module), from the variable VIBROFEM_GMSH, or from PATH; without any
//! the gmsh tests print a line and skip.

use crate::common::{rel, root, run};
use std::path::PathBuf;

/// The gmsh the tests give to `--gmsh`: VIBROFEM_GMSH, else the validation venv's python, else
/// what the CLI itself would find on PATH.
fn gmsh() -> Option<String> {
    if let Some(g) = std::env::var_os("VIBROFEM_GMSH").filter(|g| !g.is_empty()) {
        return Some(g.to_string_lossy().into_owned());
    }
    let venv = root().join("validation/.venv/bin/python");
    if venv.is_file() {
        return Some(venv.display().to_string());
    }
    match vibrofem::app::studies::geo::Gmsh::find(None) {
        Ok(vibrofem::app::studies::geo::Gmsh::Exe(p) | vibrofem::app::studies::geo::Gmsh::Python(p)) => {
            Some(p.display().to_string())
        }
        Err(e) => {
            println!("skipped: no gmsh for the converge tests ({e})");
            None
        }
    }
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vibrofem-converge-geo-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The S2 plate 900 × 400 × 116 mm, free–free, meshed by gmsh at 90, 65 and 45 mm in tet4 and
/// tet10 (a size above about 100 mm gives the same mesh as 100 mm: the 116 mm thickness caps it). The converged first elastic frequency is 722.67 Hz (docs/validation.md: hex20 on
/// refined structured meshes, independent of this study; the published value is 722.01 Hz,
/// spec/scenes.md S2). The tet10 Richardson estimate from three coarse unstructured levels
/// must land within 0.5 % of it, and the finest tet10 level within 0.5 % of that estimate (the
/// issue's acceptance); a cheapest formulation within 1 % is named, and the tet4 levels (a
/// thick plate at 45 mm is still several percent stiff in tet4) are not it.
#[test]
fn converge_on_the_s2_geometry_reproduces_the_converged_frequency() {
    let Some(g) = gmsh() else { return };
    let out = tmp("s2");
    let geo = root().join("meshes/s2_plate.geo");
    let (code, stdout, stderr) = run(&[
        "converge",
        geo.to_str().unwrap(),
        "--length-unit",
        "mm",
        "--sizes",
        "90,65,45",
        "--orders",
        "1,2",
        "--gmsh",
        &g,
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}{stderr}");
    assert!(
        stderr.contains("meshing") && stderr.contains("size 45 (order 2)"),
        "progress lines: {stderr}"
    );
    let j: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let q = &j["quantities"][0];
    assert_eq!(q["name"], "elastic frequency 1");
    let fits = q["fits"].as_array().unwrap();
    let tet10 = fits.iter().find(|f| f["formulation"] == "tet10").expect("a tet10 fit");
    assert_eq!(tet10["levels"], 3);
    let estimate = tet10["extrapolated"].as_f64().expect("a Richardson estimate");
    let finest = tet10["finest"].as_f64().unwrap();
    assert!(
        rel(estimate, 722.67) < 0.005,
        "tet10 Richardson {estimate} Hz against 722.67 Hz"
    );
    assert!(
        rel(finest, estimate) < 0.005,
        "finest tet10 {finest} Hz against its Richardson {estimate} Hz"
    );
    assert!(
        tet10["order"].as_f64().unwrap() > 1.0,
        "observed order {}",
        tet10["order"]
    );
    assert!(
        fits.iter().any(|f| f["formulation"] == "tet4"),
        "tet4 levels ran: {fits:?}"
    );
    let rows = j["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 6);
    let cheapest = &rows[q["cheapest"].as_u64().expect("a cheapest run within 1 %") as usize];
    assert_eq!(cheapest["formulation"], "tet10", "{cheapest}");
    assert!(cheapest["errors"][0].as_f64().unwrap().abs() <= 0.01);
    for f in ["converge.md", "converge.json", "converge.svg"] {
        assert!(out.join(f).is_file(), "{f} written");
    }
    let svg = std::fs::read_to_string(out.join("converge.svg")).unwrap();
    assert!(
        svg.contains("tet10") && svg.contains("tet4"),
        "the plot has both formulations"
    );
    let md = std::fs::read_to_string(out.join("converge.md")).unwrap();
    assert!(md.contains("cheapest within 1 %: tet10 at size"), "{md}");
    // The same meshes as a set the user made: sizes from their mean edge length, one
    // formulation (tet10), the same estimate.
    let (code, stdout, stderr) = run(&[
        "converge",
        out.join("meshes/s2_plate_o2_h*.msh").to_str().unwrap(),
        "--length-unit",
        "mm",
        "--json",
        "-o",
        out.join("set").to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}{stderr}");
    let j: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let fits = j["quantities"][0]["fits"].as_array().unwrap();
    assert_eq!(fits.len(), 1);
    assert!((fits[0]["extrapolated"].as_f64().unwrap() - estimate).abs() < 1e-9 * estimate);
    let _ = std::fs::remove_dir_all(&out);
}

/// A box whose top face is missing: the surface loop is open, gmsh meshes the surfaces and
/// leaves the volume empty (it only warns). Every size fails, and the error names the size and
/// carries gmsh's message.
#[test]
fn converge_names_the_size_where_gmsh_fails() {
    let Some(g) = gmsh() else { return };
    let out = tmp("open");
    let geo = out.join("open_box.geo");
    std::fs::write(
        &geo,
        "Point(1) = {0,0,0}; Point(2) = {1,0,0}; Point(3) = {1,1,0}; Point(4) = {0,1,0};\n\
         Point(5) = {0,0,1}; Point(6) = {1,0,1}; Point(7) = {1,1,1}; Point(8) = {0,1,1};\n\
         Line(1) = {1,2}; Line(2) = {2,3}; Line(3) = {3,4}; Line(4) = {4,1};\n\
         Line(5) = {5,6}; Line(6) = {6,7}; Line(7) = {7,8}; Line(8) = {8,5};\n\
         Line(9) = {1,5}; Line(10) = {2,6}; Line(11) = {3,7}; Line(12) = {4,8};\n\
         Curve Loop(1) = {1,2,3,4}; Plane Surface(1) = {1};\n\
         Curve Loop(2) = {1,10,-5,-9}; Plane Surface(2) = {2};\n\
         Curve Loop(3) = {2,11,-6,-10}; Plane Surface(3) = {3};\n\
         Curve Loop(4) = {3,12,-7,-11}; Plane Surface(4) = {4};\n\
         Curve Loop(5) = {4,9,-8,-12}; Plane Surface(5) = {5};\n\
         Surface Loop(1) = {1,2,3,4,5};\nVolume(1) = {1};\nPhysical Volume(\"body\") = {1};\n",
    )
    .unwrap();
    let (code, stdout, stderr) = run(&[
        "converge",
        geo.to_str().unwrap(),
        "--sizes",
        "0.5,0.25",
        "--orders",
        "1",
        "--gmsh",
        &g,
        // No limit in effect (it panicked converting 1e300 s to a duration).
        "--mesh-timeout",
        "1e300",
        "-o",
        out.join("o").to_str().unwrap(),
    ]);
    assert_ne!(code, 0, "{stdout}{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for needle in [
        "size 0.5 (order 1)",
        "size 0.25 (order 1)",
        "no volume cells",
        "No tetrahedra",
    ] {
        assert!(stderr.contains(needle), "'{needle}' not in: {stderr}");
    }
    // A syntax error: gmsh's own message with its line, at the size it was asked.
    std::fs::write(&geo, "Point(1) = {0,0,0};\nBox(1) = {0, 0 0, 1, 1, 1};\n").unwrap();
    let (code, _, stderr) = run(&[
        "converge",
        geo.to_str().unwrap(),
        "--sizes",
        "0.5,0.25,0.125",
        "--gmsh",
        &g,
        "-o",
        out.join("o").to_str().unwrap(),
    ]);
    assert_eq!(code, 5, "{stderr}");
    assert!(
        stderr.contains("size 0.125 (order 2): gmsh failed") && stderr.contains("line 2"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// Without any gmsh the error says what was looked for; options of a .geo study are refused
/// for a built-in case; a tolerance that is not one is refused naming the option.
#[test]
fn converge_geo_option_errors_name_the_option() {
    let out = tmp("opts");
    let geo = root().join("meshes/s2_plate.geo");
    let (code, _, stderr) = crate::common::run_cmd(
        crate::common::bin()
            .args(["converge", geo.to_str().unwrap(), "--sizes", "200,100,50", "-o"])
            .arg(out.join("o"))
            .env("PATH", "/nonexistent")
            .env_remove("VIBROFEM_GMSH"),
    );
    assert_eq!(code, 5, "{stderr}");
    for needle in [
        "no gmsh found",
        "VIBROFEM_GMSH",
        "`gmsh` on PATH",
        "python3",
        "pip install gmsh",
    ] {
        assert!(stderr.contains(needle), "'{needle}' not in: {stderr}");
    }
    let (code, _, stderr) = run(&["converge", "tiny", "--sizes", "1,2"]);
    assert_eq!(code, 1);
    assert!(stderr.contains("--sizes applies to a study on a .geo"), "{stderr}");
    let (code, _, stderr) = run(&[
        "converge",
        geo.to_str().unwrap(),
        "--sizes",
        "200,100",
        "--tolerance",
        "150%",
    ]);
    assert_eq!(code, 1);
    assert!(stderr.contains("--tolerance '150%'"), "{stderr}");
    let (code, _, stderr) = run(&["converge", geo.to_str().unwrap(), "--sizes", "200,-1"]);
    assert_eq!(code, 1);
    assert!(stderr.contains("--sizes '200,-1'"), "{stderr}");
    let _ = std::fs::remove_dir_all(&out);
}

/// The extrapolation for uneven size ratios recovers v = 10 + 3h² exactly, and levels whose
/// changes grow or flip sign are refused naming the formulation, the quantity and the level.
#[test]
fn converge_richardson_for_any_ratios_and_the_monotone_refusal() {
    use vibrofem::app::converge::{check_monotone, richardson_sizes};
    let h = [0.9, 0.5, 0.3];
    let v = h.map(|h| 10.0 + 3.0 * h * h);
    let (lim, p) = richardson_sizes(h, v).unwrap();
    assert!((lim - 10.0).abs() < 1e-9 && (p - 2.0).abs() < 1e-6, "{lim} {p}");
    let levels = |v: &[f64]| -> Vec<(String, f64)> {
        v.iter()
            .enumerate()
            .map(|(i, &x)| (format!("size {}", 40 >> i), x))
            .collect()
    };
    assert!(check_monotone("tet10", "elastic frequency 1", "Hz", &levels(&[730.0, 724.0, 723.0])).is_ok());
    let e = check_monotone(
        "tet4",
        "elastic frequency 1",
        "Hz",
        &levels(&[800.0, 760.0, 745.0, 746.0]),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("tet4, elastic frequency 1 [Hz]") && e.contains("monotonically at size 5"),
        "{e}"
    );
    let e = check_monotone("hex8", "stiffness", "N/m", &levels(&[1.0, 2.0, 4.0]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("hex8, stiffness [N/m]") && e.contains("at size 10"), "{e}");
    assert!(richardson_sizes(h, [1.0, 2.0, 4.0]).is_none());
}
