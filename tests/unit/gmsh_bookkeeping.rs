//! gmsh bookkeeping: a repeated element counts once (with a note naming the tags, silently for
//! MSH 2.2's repeat in a second physical group); one tag for two elements, MSH 4.1 blocks whose
//! entity is missing, listed twice or of another dimension, and clashing `$PhysicalNames` are
//! refused naming the tags.

use std::path::Path;
use vibrofem::io::gmsh::read_bytes;
use vibrofem::model::{Model, ModelSpec};

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
