//! Mesh files on the command line: a file that is not a gmsh mesh is refused from its first
//! bytes, and `mesh-info`'s bounding box covers only the nodes the cells use.

use super::support::{expect_error, tmp};
use crate::common::run;

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
