//! Input and resource regressions of issue 15 (items 9, 12, 13, 14, 15): the memory estimate
//! before assembly, memory units, conflicting constraints, duplicate elements and gmsh
//! bookkeeping errors.

use vibrofem::assembly::NodeGraph;
use vibrofem::input::source;
use vibrofem::linalg::ordering::{factor_entries, node_nested_dissection};
use vibrofem::model::{Model, ModelSpec};
use vibrofem::system::{System, SystemOptions, memory_budget};

/// Item 14: the factor size known before assembly (elimination tree of the node graph) is a
/// lower bound of what the symbolic analysis finds, and close to it (supernode padding only).
#[test]
fn factor_estimate_before_assembly_bounds_the_symbolic_count() {
    for (src, fix) in [
        ("box:0.1,0.1,0.1:8,8,8:hex8", false),
        ("box:0.1,0.1,0.1:5,5,5:hex20", true),
        ("box:0.3,0.3,0.02:10,10,2:tet10", true),
    ] {
        let mesh = source::load(src, 1.0).unwrap();
        let spec = ModelSpec {
            fixes: if fix {
                vec![("xmin".into(), vibrofem::dof::TRANSLATIONS)]
            } else {
                vec![]
            },
            ..Default::default()
        };
        let model = Model::build(&mesh, &spec, src).unwrap();
        let sets = model.element_sets();
        let graph = NodeGraph::build(model.dofs.n_nodes(), &sets, Some(&model.dofs));
        let order = node_nested_dissection(&graph, &model.dofs).unwrap();
        let est = factor_entries(&graph, &model.dofs, &order, u64::MAX);
        // A cap stops the count early, above the cap.
        let capped = factor_entries(&graph, &model.dofs, &order, est / 10);
        assert!(capped > est / 10 && capped < est, "{src}: capped {capped} of {est}");
        drop(sets);
        let sys = System::build(model, &SystemOptions::default(), src).unwrap();
        let nnz_l = sys.symbolic().unwrap().nnz_l as u64;
        assert!(est <= nnz_l, "{src}: estimate {est} above the symbolic count {nnz_l}");
        assert!(
            est as f64 >= 0.9 * nnz_l as f64,
            "{src}: estimate {est} far below {nnz_l}"
        );
    }
}

/// Item 14: a model beyond the memory limit is refused before assembly with the estimate,
/// as an input error; the same model under a sufficient limit builds.
#[test]
fn memory_limit_is_checked_before_assembly() {
    let src = "box:0.1,0.1,0.1:6,6,6:hex20";
    let mesh = source::load(src, 1.0).unwrap();
    let build = |limit: u64| {
        let model = Model::build(&mesh, &ModelSpec::default(), src).unwrap();
        let opts = SystemOptions {
            max_memory: Some(limit),
            ..Default::default()
        };
        System::build(model, &opts, src)
    };
    let e = build(1 << 20).err().expect("1 MiB must be refused");
    let msg = e.to_string();
    assert_eq!(e.exit_code(), 1, "{msg}");
    assert!(
        msg.contains("needs at least") && msg.contains("--max-memory is 1.00 MiB"),
        "{msg}"
    );
    assert!(build(1 << 30).is_ok());
}

/// Item 14: the budget is the smallest of the limits that apply; an explicit limit is one of
/// them and below every other here.
#[test]
fn memory_budget_takes_the_smallest_limit() {
    let b = memory_budget(Some(1234)).unwrap();
    assert_eq!(b.bytes, 1234);
    assert_eq!(b.what, "--max-memory is");
    if let Some(sys) = memory_budget(None) {
        assert!(sys.bytes > 0, "{}", sys.what);
        assert!(memory_budget(Some(u64::MAX)).unwrap().bytes <= u64::MAX);
    }
}

/// Item 12: byte counts print in the unit that fits (not "0.00 GiB" for a KiB).
#[test]
fn byte_counts_print_with_sensible_units() {
    use vibrofem::io::fmt_bytes;
    assert_eq!(fmt_bytes(1024), "1.00 KiB");
    assert_eq!(fmt_bytes(500 << 20), "500 MiB");
    assert_eq!(fmt_bytes(4 << 30), "4.00 GiB");
    assert_eq!(fmt_bytes(12), "12 bytes");
}

// ---- Item 9: repeated elements and gmsh bookkeeping errors ----

use std::path::Path;
use vibrofem::io::gmsh::read_bytes;

const MSH2_NODES: &str = "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n";

fn msh2(elements: &[&str]) -> String {
    format!(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n3 1 \"body\"\n3 2 \"other\"\n$EndPhysicalNames\n\
         {MSH2_NODES}$Elements\n{}\n{}\n$EndElements\n",
        elements.len(),
        elements.join("\n")
    )
}

fn volume_and_mass(text: &str) -> (f64, f64, Vec<String>) {
    let mesh = read_bytes(text.as_bytes(), Path::new("t.msh"), 1.0).unwrap();
    let model = Model::build(&mesh, &ModelSpec::default(), "t.msh").unwrap();
    let (v, m) = model.volume_and_mass().unwrap();
    (v, m, model.notes.clone())
}

/// A tetrahedron repeated further down the file (any node order) is one cell, with a note
/// naming both tags; the same tetrahedron under a second physical group (gmsh's MSH 2.2
/// output for a volume in two groups) is one cell in both groups, without a note.
#[test]
fn repeated_elements_count_once() {
    let t1 = "1 4 2 1 1 1 2 3 4";
    let t2 = "2 4 2 1 1 2 3 4 5";
    let (v0, m0, n0) = volume_and_mass(&msh2(&[t1, t2]));
    assert!(n0.iter().all(|n| !n.contains("repeat")), "{n0:?}");
    let (v, m, notes) = volume_and_mass(&msh2(&[t1, t2, "3 4 2 1 1 4 3 2 1"]));
    assert_eq!((v, m), (v0, m0));
    assert!(
        notes
            .iter()
            .any(|n| n.contains("element 3 = element 1") && n.contains("counted once")),
        "{notes:?}"
    );
    let two = msh2(&[t1, t2, "3 4 2 2 1 1 2 3 4"]);
    let (v, m, notes) = volume_and_mass(&two);
    assert_eq!((v, m), (v0, m0));
    assert!(notes.iter().all(|n| !n.contains("repeat")), "{notes:?}");
    let mesh = read_bytes(two.as_bytes(), Path::new("t.msh"), 1.0).unwrap();
    let other = mesh.groups.iter().find(|g| g.name == "other").unwrap();
    assert_eq!(other.cells.len(), 1);
    // One tag for two different elements is refused, naming the tag.
    let e = read_bytes(msh2(&[t1, t2, "2 4 2 1 1 1 3 4 5"]).as_bytes(), Path::new("t.msh"), 1.0).unwrap_err();
    assert!(
        e.to_string()
            .contains("element tag 2 is used for two different elements"),
        "{e}"
    );
    assert_eq!(e.exit_code(), 1);
}

fn msh4(names: &str, entities: &str, blocks: &str) -> String {
    format!(
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n{names}$EndPhysicalNames\n$Entities\n{entities}$EndEntities\n\
         $Nodes\n1 5 1 5\n3 1 0 5\n1\n2\n3\n4\n5\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n$EndNodes\n$Elements\n{blocks}$EndElements\n"
    )
}

const NAMES: &str = "1\n3 1 \"body\"\n";
const ENTITIES: &str = "0 0 0 1\n1 0 0 0 1 1 1 1 1 0\n";
const BLOCKS: &str = "1 2 1 2\n3 1 4 2\n1 1 2 3 4\n2 2 3 4 5\n";

fn msh4_error(text: &str) -> String {
    let e = read_bytes(text.as_bytes(), Path::new("t.msh"), 1.0).unwrap_err();
    assert_eq!(e.exit_code(), 1, "{e}");
    e.to_string()
}

/// MSH 4.1: a block whose entity has the wrong dimension, an entity missing from or listed
/// twice in `$Entities`, and `$PhysicalNames` naming one group twice or two groups alike are
/// refused naming the tags; a repeated element is counted once with a note.
#[test]
fn msh41_bookkeeping_errors_are_refused() {
    let (v0, m0, _) = volume_and_mass(&msh4(NAMES, ENTITIES, BLOCKS));
    assert!(v0 > 0.0 && m0 > 0.0);
    let e = msh4_error(&msh4(NAMES, ENTITIES, "1 2 1 2\n2 1 4 2\n1 1 2 3 4\n2 2 3 4 5\n"));
    assert!(e.contains("entity 2:1") && e.contains("tet4"), "{e}");
    let e = msh4_error(&msh4(NAMES, ENTITIES, "1 2 1 2\n3 7 4 2\n1 1 2 3 4\n2 2 3 4 5\n"));
    assert!(e.contains("entity 3:7") && e.contains("does not list"), "{e}");
    let e = msh4_error(&msh4(
        NAMES,
        "0 0 0 2\n1 0 0 0 1 1 1 1 1 0\n1 0 0 0 1 1 1 1 1 0\n",
        BLOCKS,
    ));
    assert!(e.contains("entity 3:1 is listed twice"), "{e}");
    let e = msh4_error(&msh4("2\n3 1 \"body\"\n3 1 \"part\"\n", ENTITIES, BLOCKS));
    assert!(
        e.contains("3:1 is named twice") && e.contains("'body'") && e.contains("'part'"),
        "{e}"
    );
    let e = msh4_error(&msh4("2\n3 1 \"body\"\n3 2 \"body\"\n", ENTITIES, BLOCKS));
    assert!(e.contains("'body'") && e.contains("tags 1 and 2"), "{e}");
    // The same name and tag twice is harmless.
    let (v, _, _) = volume_and_mass(&msh4("2\n3 1 \"body\"\n3 1 \"body\"\n", ENTITIES, BLOCKS));
    assert_eq!(v, v0);
    let (v, m, notes) = volume_and_mass(&msh4(
        NAMES,
        ENTITIES,
        "1 3 1 3\n3 1 4 3\n1 1 2 3 4\n2 2 3 4 5\n3 2 1 4 3\n",
    ));
    assert_eq!((v, m), (v0, m0));
    assert!(notes.iter().any(|n| n.contains("element 3 = element 1")), "{notes:?}");
}
