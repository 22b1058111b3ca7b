//! Command-line checks of issue 15's numerics: the curved-cell note and the incompatible-mode
//! hex8 (`--hex8`).

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

#[test]
fn converge_pairs_modes_by_mac_across_reordering() {
    use vibrofem::app::converge::{LevelModes, mac, pair_by_mac};
    // A bar along x sampled at nested points (the fine level has the coarse points and their
    // midpoints). Shapes: bending in y (u_y = x²) and in z (u_z = x²), and axial (u_x = x).
    // The coarse level lists z bending first, the fine one y bending first: pairing must pick
    // the coarse level's second mode.
    let pts = |n: usize| -> Vec<[f64; 3]> { (0..=n).map(|i| [i as f64 / n as f64, 0.0, 0.0]).collect() };
    let shape = |p: &[[f64; 3]], c: usize, f: &dyn Fn(f64) -> f64| -> Vec<f64> {
        p.iter()
            .flat_map(|x| (0..3).map(move |k| if k == c { f(x[0]) } else { 0.0 }))
            .collect()
    };
    let level = |n: usize, order: [usize; 3], freqs: Vec<f64>| {
        let p = pts(n);
        let all = [
            shape(&p, 1, &|x| x * x),
            shape(&p, 2, &|x| x * x * (1.0 + 0.01 * x)),
            shape(&p, 0, &|x| x),
        ];
        LevelModes {
            shapes: order.iter().map(|&i| all[i].clone()).collect(),
            points: p,
            freqs,
        }
    };
    let coarse = level(4, [1, 0, 2], vec![10.0, 10.5, 50.0]);
    let fine = level(8, [0, 1, 2], vec![9.8, 9.9, 49.0]);
    let p = pair_by_mac(&[Some(coarse), None, Some(fine)]);
    assert_eq!(p[1], None);
    let (k, m) = p[0].unwrap();
    assert_eq!(k, 1, "coarse level: its second mode is the fine level's first");
    assert!(m > 0.999, "MAC {m}");
    assert_eq!(p[2].unwrap().0, 0);
    assert!((p[2].unwrap().1 - 1.0).abs() < 1e-12);
    // MAC of orthogonal shapes is 0, of scaled ones 1.
    assert_eq!(mac(&[1.0, 0.0], &[0.0, 2.0]), 0.0);
    assert!((mac(&[1.0, 2.0], &[-2.0, -4.0]) - 1.0).abs() < 1e-15);
}

/// Item 8: MAC pairing used to apply only to scene levels; the built-in S7 table levels (shell
/// and hex20 runners) returned no shapes, so a mode swap there went unnoticed. They now hand
/// back their elastic modes: two shell refinements of the table pair their first elastic mode
/// with the finest level's first (the same plate mode; a MAC near 1 shows the shapes are
/// sampled at the same points and consistently normalised).
#[test]
fn converge_table_levels_return_shapes_for_pairing() {
    use vibrofem::app::converge::{LevelSpec, Runner, pair_by_mac, run_level_modes};
    let levels: Vec<_> = [0.1, 0.05]
        .iter()
        .map(|&h| {
            let (value, _, _, _, modes) = run_level_modes(&LevelSpec {
                formulation: "shell".into(),
                mesh: format!("{h}"),
                runner: Runner::TableShell(h),
            })
            .unwrap();
            let m = modes.expect("table levels return their modes");
            assert!(m.freqs.len() >= 4 && m.shapes.len() == m.freqs.len(), "{:?}", m.freqs);
            assert_eq!(m.freqs[0], value);
            assert_eq!(m.shapes[0].len(), 3 * m.points.len());
            Some(m)
        })
        .collect();
    let p = pair_by_mac(&levels);
    for (i, x) in p.iter().enumerate() {
        let (k, m) = x.unwrap();
        assert_eq!(k, 0, "level {i}: paired with elastic mode {}", k + 1);
        assert!(m > 0.95, "level {i}: MAC {m}");
    }
}
