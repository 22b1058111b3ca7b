//! Solid element options through the command line: the note on curved quadratic cells (text
//! and JSON) and the incompatible-mode hex8 (`--hex8`).

use crate::common::run;
use vibrofem::mesh::CellKind;
use vibrofem::mesh::generate::box_mesh;

fn json(out: &str) -> serde_json::Value {
    serde_json::from_str(out).unwrap_or_else(|e| panic!("{e}: {out}"))
}

/// A MSH 2.2 file of a 2 × 6 × 1 tet10 box mapped onto a 60° ring sector (mean radius 20 mm,
/// 6 × 3 mm section), every node on the exact cylinder when `curved`, else the box itself.
fn ring_msh(curved: bool) -> std::path::PathBuf {
    let mesh = box_mesh(CellKind::Tet10, [0.006, 1.0, 0.003], [2, 6, 1]);
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n");
    s += &format!("{}\n", mesh.nodes.len());
    for (i, p) in mesh.nodes.iter().enumerate() {
        let q = if curved {
            let (r, th) = (0.017 + p[0], std::f64::consts::FRAC_PI_3 * p[1]);
            [r * th.cos(), r * th.sin(), p[2]]
        } else {
            [p[0], 0.02 * p[1], p[2]]
        };
        s += &format!("{} {:.17e} {:.17e} {:.17e}\n", i + 1, q[0], q[1], q[2]);
    }
    let b = mesh.blocks.iter().find(|b| b.kind == CellKind::Tet10).unwrap();
    s += &format!("$EndNodes\n$Elements\n{}\n", b.len());
    for e in 0..b.len() {
        let conn: Vec<String> = b.cell(e).iter().map(|a| (a + 1).to_string()).collect();
        s += &format!("{} 11 2 1 1 {}\n", e + 1, conn.join(" "));
    }
    s += "$EndElements\n";
    let path = std::env::temp_dir().join(format!("vibrofem_ring_{}_{curved}.msh", std::process::id()));
    std::fs::write(&path, s).unwrap();
    path
}

#[test]
fn curved_tet10_cells_are_reported_in_text_and_json() {
    let curved = ring_msh(true);
    let (code, out, err) = run(&["modes", curved.to_str().unwrap(), "--modes", "7", "--json"]);
    assert_eq!(code, 0, "{err}");
    let notes = json(&out)["notes"].to_string();
    assert!(notes.contains("curved quadratic cells"), "{notes}");
    assert!(notes.contains("72 of 72 tet10"), "{notes}");
    assert!(notes.contains("24-point degree 6"), "{notes}");
    // Text mode: notes are printed on stderr, after the table.
    let (code, _, err) = run(&["modes", curved.to_str().unwrap(), "--modes", "7"]);
    assert_eq!(code, 0);
    assert!(err.contains("note: curved quadratic cells"), "{err}");
    // The same topology straight: no note.
    let straight = ring_msh(false);
    let (code, out, err) = run(&["modes", straight.to_str().unwrap(), "--modes", "7", "--json"]);
    assert_eq!(code, 0, "{err}");
    assert!(!json(&out)["notes"].to_string().contains("curved"), "{out}");
    let _ = std::fs::remove_file(curved);
    let _ = std::fs::remove_file(straight);
}

#[test]
fn hex8_incompatible_modes_from_the_command_line() {
    // Cantilever 200 × 10 × 10 mm, 20 × 1 × 1 hex8, steel: Euler–Bernoulli f1 = 204.6 Hz
    // (L/h = 20, the Timoshenko correction is 0.3 %). Incompatible: within 2 %; standard: > 20 %
    // high (shear locking).
    let (e, rho, l, h) = (2.1e11_f64, 7850.0_f64, 0.2_f64, 0.01_f64);
    let f1 = 1.875_104_068_7_f64.powi(2) / (2.0 * std::f64::consts::PI * l * l) * (e * h * h / 12.0 / rho).sqrt();
    let freq = |form: &str| {
        let (code, out, err) = run(&[
            "modes",
            "box:0.2,0.01,0.01:20,1,1:hex8",
            "--material",
            "2.1e11,0.3,7850",
            "--fix",
            "xmin",
            "--modes",
            "1",
            "--hex8",
            form,
            "--json",
        ]);
        assert_eq!(code, 0, "{err}");
        json(&out)["modes"][0]["frequency_hz"].as_f64().unwrap()
    };
    let (fi, fs) = (freq("incompatible"), freq("standard"));
    assert!((fi / f1 - 1.0).abs() < 0.02, "incompatible {fi} vs {f1}");
    assert!(fs / f1 - 1.0 > 0.2, "standard {fs} vs {f1}");
    let (code, _, err) = run(&["modes", "box:0.2,0.01,0.01:20,1,1:hex8", "--hex8", "wilson"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("expected 'standard' or 'incompatible'"), "{err}");
}
