//! Notes a model build gives about meshes and supports that run but answer poorly: thin plates
//! of linear solid cells, a plate one linear cell thick, and a support on a line of a solid.

use super::shell_orientation::plate;
use vibrofem::dof::TRANSLATIONS;
use vibrofem::element::incompatible::Hex8Formulation;
use vibrofem::input::options::ModelOptions;
use vibrofem::input::source;
use vibrofem::mesh::generate::box_mesh;
use vibrofem::mesh::{CellKind, CellRef, Group, Mesh};
use vibrofem::model::{Model, ModelSpec, ShellPart};
use vibrofem::section::ShellSection;

// ---------------------------------------------------------------------------------------------
// Flat linear cells

fn model_notes(src: &str, hex8: Hex8Formulation) -> Vec<String> {
    let mesh = vibrofem::input::source::load(src, 1.0).unwrap();
    let spec = ModelSpec {
        hex8,
        ..Default::default()
    };
    vibrofem::model::Model::build(&mesh, &spec, src).unwrap().notes
}

#[test]
fn thin_plates_of_linear_solids_get_a_note() {
    let flat = |n: &Vec<String>| n.iter().any(|s| s.contains("flat or slender"));
    // 1 m × 1 m × 1 mm, 20 × 20 × 1 cells: every cell is 50 mm wide and 1 mm thick.
    for kind in ["tet4", "hex8", "wedge6"] {
        let n = model_notes(&format!("box:1,1,0.001:20,20,1:{kind}"), Hex8Formulation::Standard);
        assert!(flat(&n), "{kind}: {n:?}");
        // Well-shaped cells (and quadratic ones) get none.
        assert!(
            !flat(&model_notes(
                &format!("box:1,1,1:4,4,4:{kind}"),
                Hex8Formulation::Standard
            )),
            "{kind}"
        );
    }
    let n = model_notes("box:1,1,0.001:20,20,1:hex8", Hex8Formulation::Standard);
    assert!(
        n.iter()
            .any(|s| s.contains("400 of 400 hex8") && s.contains("--hex8 incompatible")),
        "{n:?}"
    );
    assert!(!flat(&model_notes(
        "box:1,1,0.001:20,20,1:tet10",
        Hex8Formulation::Standard
    )));
    assert!(!flat(&model_notes(
        "box:1,1,0.001:20,20,1:hex8",
        Hex8Formulation::Incompatible
    )));
}

/// Item 9: a plate of one layer of well-shaped (cubic) plain hex8 cells passed without a word,
/// although one linear layer cannot bend (its first bending frequency is far too high). It is
/// now named; a chunky block with interior nodes and the incompatible-mode hex8 are not.
#[test]
fn one_layer_of_linear_solids_is_named() {
    let notes = |spec: &str, hex8: &str| {
        let mesh = source::load(spec, 1.0).unwrap();
        let opts = ModelOptions {
            hex8: hex8.into(),
            ..Default::default()
        };
        Model::build(&mesh, &opts.spec().unwrap(), "test").unwrap().notes
    };
    let plate = notes("box:0.1,0.1,0.01:10,10,1:hex8", "standard");
    assert!(plate.iter().any(|n| n.contains("one cell thick")), "{plate:?}");
    assert!(plate.iter().any(|n| n.contains("--hex8 incompatible")), "{plate:?}");
    let block = notes("box:0.4,0.4,0.4:4,4,4:hex8", "standard");
    assert!(!block.iter().any(|n| n.contains("one cell thick")), "{block:?}");
    let inc = notes("box:0.1,0.1,0.01:10,10,1:hex8", "incompatible");
    assert!(!inc.iter().any(|n| n.contains("one cell thick")), "{inc:?}");
}

// ---------------------------------------------------------------------------------------------
// Singular supports

/// Adds a line group `name` of line2 cells through the nodes selected by `on`, ordered by
/// their coordinate `axis`.
fn add_line_group(mesh: &mut Mesh, name: &str, on: impl Fn([f64; 3]) -> bool, axis: usize) {
    let mut ids: Vec<u32> = (0..mesh.nodes.len() as u32)
        .filter(|&a| on(mesh.nodes[a as usize]))
        .collect();
    ids.sort_by(|&a, &b| mesh.nodes[a as usize][axis].total_cmp(&mesh.nodes[b as usize][axis]));
    let bi = mesh.block_index_mut(CellKind::Line2);
    let start = mesh.blocks[bi].len() as u32;
    for w in ids.windows(2) {
        mesh.blocks[bi].push(w, 1000 + w[0] as u64);
    }
    let end = mesh.blocks[bi].len() as u32;
    let tag = 100 + mesh.groups.len() as i32;
    mesh.groups.push(Group {
        name: name.into(),
        dim: 1,
        tag,
        cells: (start..end)
            .map(|index| CellRef {
                block: bi as u32,
                index,
            })
            .collect(),
    });
}

#[test]
fn a_line_support_on_a_solid_gets_a_note_and_a_shell_edge_does_not() {
    let mut mesh = box_mesh(CellKind::Hex20, [1.0, 0.1, 0.1], [10, 1, 1]);
    add_line_group(&mut mesh, "root_edge", |p| p[0] == 0.0 && p[2] == 0.0, 1);
    let notes = |fix: &str, m: &Mesh, shells: Vec<ShellPart>| {
        let spec = ModelSpec {
            fixes: vec![(fix.into(), TRANSLATIONS)],
            shells,
            ..Default::default()
        };
        vibrofem::model::Model::build(m, &spec, "t").unwrap().notes
    };
    let n = notes("root_edge", &mesh, vec![]);
    assert!(
        n.iter().any(|s| s.contains("support 'root_edge' is a line of a solid")),
        "{n:?}"
    );
    let n = notes("xmin", &mesh, vec![]);
    assert!(!n.iter().any(|s| s.contains("support")), "{n:?}");
    // A clamped shell edge is an ordinary support.
    let mut p = plate(|_, _| false);
    add_line_group(&mut p, "edge", |x| x[1] == 0.0, 0);
    let sh = vec![ShellPart {
        group: "plate".into(),
        section: ShellSection::new(0.004),
        material: None,
    }];
    let n = notes("edge", &p, sh);
    assert!(!n.iter().any(|s| s.contains("support")), "{n:?}");
}
