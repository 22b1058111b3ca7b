//! Shell normals oriented before offsets apply: cells whose node order disagrees with their
//! neighbours' are reversed (keeping each connected surface's majority), and a one-sided
//! (Möbius-like) surface with an offset is refused.

use vibrofem::analysis::modal::{ModalOptions, ModalTarget, run_modal};
use vibrofem::mesh::{CellBlock, CellKind, CellRef, Group, Mesh};
use vibrofem::model::{ModelSpec, ShellPart};
use vibrofem::section::ShellSection;

/// A quad4 surface mesh, one group "plate" of every cell.
fn quad_mesh(nodes: Vec<[f64; 3]>, quads: Vec<[u32; 4]>) -> Mesh {
    let mut b = CellBlock::new(CellKind::Quad4);
    for (i, q) in quads.iter().enumerate() {
        b.push(q, i as u64 + 1);
    }
    let n = quads.len();
    Mesh {
        node_tags: (1..=nodes.len() as u64).collect(),
        nodes,
        blocks: vec![b],
        groups: vec![Group {
            name: "plate".into(),
            dim: 2,
            tag: 1,
            cells: (0..n as u32).map(|index| CellRef { block: 0, index }).collect(),
        }],
        ..Default::default()
    }
}

/// A 0.3 × 0.2 m plate of 12 × 8 quad4; `flip(i, j)` reverses cell (i, j).
pub(crate) fn plate(flip: impl Fn(usize, usize) -> bool) -> Mesh {
    let (nx, ny) = (12, 8);
    let nodes = (0..=ny)
        .flat_map(|j| (0..=nx).map(move |i| [0.3 * i as f64 / nx as f64, 0.2 * j as f64 / ny as f64, 0.0]))
        .collect();
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut quads = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let q = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
            quads.push(if flip(i, j) { [q[0], q[3], q[2], q[1]] } else { q });
        }
    }
    quad_mesh(nodes, quads)
}

fn shell_frequencies(mesh: &Mesh, offset: f64) -> (Vec<f64>, Vec<String>) {
    let t = 0.004;
    let spec = ModelSpec {
        shells: vec![ShellPart {
            group: "plate".into(),
            section: ShellSection {
                offset,
                ..ShellSection::new(t)
            },
            material: None,
        }],
        ..Default::default()
    };
    let run = run_modal(
        mesh,
        "plate",
        &ModalOptions {
            spec,
            target: ModalTarget::Modes(12),
            ..Default::default()
        },
        0.0,
    )
    .unwrap();
    (run.report.frequencies_hz[6..].to_vec(), run.report.notes)
}

#[test]
fn flipped_shell_cells_with_an_offset_give_the_consistent_answer() {
    // A free plate: a uniform offset only moves the whole plate, so the elastic frequencies with
    // offset t/2 equal those without (the independent reference). Cells flipped in a
    // checkerboard, and the half plate x > 0.15 m flipped as one surface (a second, reversed
    // gmsh surface), are reoriented and give the same frequencies; the note says how many.
    let (f0, _) = shell_frequencies(&plate(|_, _| false), 0.0);
    let (f1, n1) = shell_frequencies(&plate(|_, _| false), 0.002);
    let (f2, n2) = shell_frequencies(&plate(|i, j| (i + j) % 2 == 1), 0.002);
    let (f3, n3) = shell_frequencies(&plate(|i, _| i >= 6), 0.002);
    for (f, what) in [(&f1, "offset"), (&f2, "checkerboard"), (&f3, "half reversed")] {
        for (a, b) in f.iter().zip(&f0) {
            // Different but equivalent element frames: agreement to solver accuracy.
            assert!((a / b - 1.0).abs() < 1e-7, "{what}: {a} vs {b}");
        }
    }
    assert!(!n1.iter().any(|n| n.contains("reversed")), "{n1:?}");
    assert!(n2.iter().any(|n| n.contains("48 of 96 cells reversed")), "{n2:?}");
    // The majority is kept: 48 of 96 in each half → the first-visited side wins a tie.
    assert!(n3.iter().any(|n| n.contains("48 of 96 cells reversed")), "{n3:?}");
    // With one cell flipped, that one cell is reversed (majority kept).
    let (f4, n4) = shell_frequencies(&plate(|i, j| i == 3 && j == 2), 0.002);
    assert!(n4.iter().any(|n| n.contains("1 of 96 cells reversed")), "{n4:?}");
    assert!((f4[0] / f0[0] - 1.0).abs() < 1e-7);
}

#[test]
fn a_one_sided_shell_with_an_offset_is_refused_and_without_one_runs() {
    // Möbius strip: 24 quads around a circle of radius 0.1 m, width 0.02 m, half a twist.
    let n = 24;
    let mut nodes = Vec::new();
    for k in 0..n {
        let th = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
        let tw = 0.5 * th;
        for s in [-0.01, 0.01] {
            let r = 0.1 + s * tw.cos();
            nodes.push([r * th.cos(), r * th.sin(), s * tw.sin()]);
        }
    }
    let quads: Vec<[u32; 4]> = (0..n)
        .map(|k| {
            let (a, b) = (2 * k as u32, 2 * ((k + 1) % n) as u32);
            // The last cell closes the strip with the sides swapped (the half twist).
            if k + 1 == n {
                [a, b + 1, b, a + 1]
            } else {
                [a, b, b + 1, a + 1]
            }
        })
        .collect();
    let mesh = quad_mesh(nodes, quads);
    let spec = |offset| ModelSpec {
        shells: vec![ShellPart {
            group: "plate".into(),
            section: ShellSection {
                offset,
                ..ShellSection::new(0.001)
            },
            material: None,
        }],
        ..Default::default()
    };
    let err = vibrofem::model::Model::build(&mesh, &spec(0.0005), "moebius")
        .err()
        .expect("refused");
    let msg = err.to_string();
    assert!(msg.contains("one-sided") && msg.contains("of 'plate'"), "{msg}");
    let model = vibrofem::model::Model::build(&mesh, &spec(0.0), "moebius").unwrap();
    assert!(model.notes.iter().all(|n| !n.contains("reversed")));
}
