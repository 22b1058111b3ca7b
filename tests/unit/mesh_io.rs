//! Mesh input and output: the gmsh reader (MSH 4.1 and 2.2, ASCII and binary), the structured
//! generators, and the VTU and MSH writers.
//!
//! The gmsh files in `tests/data/meshes` are made by `tests/data/make_test_meshes.py` with the
//! PyPI `gmsh` package; `beams.msh` is scikit-fem's (see `shared/meshes/external/README.md`).
//! Reference node positions are gmsh's (`gmsh.model.mesh.getElementProperties`) and VTK's
//! (`GetParametricCoords` of each `vtkCell`).

use crate::common::{cross, dot};
use std::path::{Path, PathBuf};
use std::time::Instant;

use vibrofem::Error;
use vibrofem::io::gmsh::{read, read_bytes};
use vibrofem::io::msh_out::{NodeView, msh_string, write_msh_views};
use vibrofem::io::vtk::{PointField, gmsh_to_vtk, vtu_string, write_vtu};
use vibrofem::mesh::generate::{box_mesh, try_box_mesh};
use vibrofem::mesh::{CellKind, Mesh};

// ---------------------------------------------------------------------------------------------
// Helpers

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/meshes")
        .join(name)
}

fn read_data(name: &str) -> Mesh {
    read(&data(name), 1.0).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(data(name)).unwrap()
}

/// Parse error details, or panic with the actual error.
fn parse_err(r: vibrofem::Result<Mesh>) -> (String, Option<usize>, String) {
    match r {
        Err(Error::MeshParse { section, line, msg, .. }) => (section, line, msg),
        Err(e) => panic!("expected a MeshParse error, got {e}"),
        Ok(_) => panic!("expected a MeshParse error, got a mesh"),
    }
}

/// Assert two meshes are the same: nodes (to rounding), tags, blocks, groups.
fn assert_same_mesh(a: &Mesh, b: &Mesh, what: &str) {
    assert_eq!(a.n_nodes(), b.n_nodes(), "{what}: node count");
    assert_eq!(a.node_tags, b.node_tags, "{what}: node tags");
    for (i, (p, q)) in a.nodes.iter().zip(&b.nodes).enumerate() {
        for d in 0..3 {
            assert!(
                (p[d] - q[d]).abs() <= 1e-14 * (1.0 + p[d].abs()),
                "{what}: node {i}: {p:?} vs {q:?}"
            );
        }
    }
    assert_eq!(a.blocks.len(), b.blocks.len(), "{what}: blocks");
    for (x, y) in a.blocks.iter().zip(&b.blocks) {
        assert_eq!(x.kind, y.kind, "{what}: block kind");
        assert_eq!(x.conn, y.conn, "{what}: {} connectivity", x.kind);
        assert_eq!(x.tags, y.tags, "{what}: {} element tags", x.kind);
    }
    assert_eq!(a.groups.len(), b.groups.len(), "{what}: groups");
    for (g, h) in a.groups.iter().zip(&b.groups) {
        assert_eq!((&g.name, g.dim, g.tag), (&h.name, h.dim, h.tag), "{what}: group");
        assert_eq!(g.cells, h.cells, "{what}: cells of group {}", g.name);
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn det3(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    dot(cross(a, b), c)
}

// ---------------------------------------------------------------------------------------------
// Reference elements.

/// gmsh reference node coordinates (from `gmsh.model.mesh.getElementProperties`).
#[rustfmt::skip]
fn gmsh_ref(kind: CellKind) -> Vec<[f64; 3]> {
    let h = 0.5;
    let hex20: Vec<[f64; 3]> = vec![
        [-1., -1., -1.], [1., -1., -1.], [1., 1., -1.], [-1., 1., -1.],   // corners
        [-1., -1.,  1.], [1., -1.,  1.], [1., 1.,  1.], [-1., 1.,  1.],
        [0., -1., -1.], [-1., 0., -1.], [-1., -1., 0.], [1., 0., -1.],    // edges
        [1., -1., 0.], [0., 1., -1.], [1., 1., 0.], [-1., 1., 0.],
        [0., -1., 1.], [-1., 0., 1.], [1., 0., 1.], [0., 1., 1.],
    ];
    let hex27_faces: [[f64; 3]; 7] = [
        [0., 0., -1.], [0., -1., 0.], [-1., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.],
        [0., 0., 0.],
    ];
    let wedge15: Vec<[f64; 3]> = vec![
        [0., 0., -1.], [1., 0., -1.], [0., 1., -1.], [0., 0., 1.], [1., 0., 1.], [0., 1., 1.],
        [h, 0., -1.], [0., h, -1.], [0., 0., 0.], [h, h, -1.], [1., 0., 0.], [0., 1., 0.],
        [h, 0., 1.], [0., h, 1.], [h, h, 1.],
    ];
    let tet10: Vec<[f64; 3]> = vec![
        [0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.],
        [h, 0., 0.], [h, h, 0.], [0., h, 0.], [0., 0., h], [0., h, h], [h, 0., h],
    ];
    let quad9: Vec<[f64; 3]> = vec![
        [-1., -1., 0.], [1., -1., 0.], [1., 1., 0.], [-1., 1., 0.],
        [0., -1., 0.], [1., 0., 0.], [0., 1., 0.], [-1., 0., 0.], [0., 0., 0.],
    ];
    let tri6: Vec<[f64; 3]> = vec![
        [0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [h, 0., 0.], [h, h, 0.], [0., h, 0.],
    ];
    match kind {
        CellKind::Tet4 => tet10[..4].to_vec(),
        CellKind::Tet10 => tet10,
        CellKind::Hex8 => hex20[..8].to_vec(),
        CellKind::Hex20 => hex20,
        CellKind::Hex27 => [hex20, hex27_faces.to_vec()].concat(),
        CellKind::Wedge6 => wedge15[..6].to_vec(),
        CellKind::Wedge15 => wedge15,
        CellKind::Tri3 => tri6[..3].to_vec(),
        CellKind::Tri6 => tri6,
        CellKind::Quad4 => quad9[..4].to_vec(),
        CellKind::Quad8 => quad9[..8].to_vec(),
        CellKind::Quad9 => quad9,
        k => panic!("no reference for {k}"),
    }
}

/// VTK parametric coordinates of each cell type (`vtkCell::GetParametricCoords`).
#[rustfmt::skip]
fn vtk_ref(kind: CellKind) -> Vec<[f64; 3]> {
    let h = 0.5;
    let hex27: Vec<[f64; 3]> = vec![
        [0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.],           // corners
        [0., 0., 1.], [1., 0., 1.], [1., 1., 1.], [0., 1., 1.],
        [h, 0., 0.], [1., h, 0.], [h, 1., 0.], [0., h, 0.],               // bottom edges
        [h, 0., 1.], [1., h, 1.], [h, 1., 1.], [0., h, 1.],               // top edges
        [0., 0., h], [1., 0., h], [1., 1., h], [0., 1., h],               // vertical edges
        [0., h, h], [1., h, h], [h, 0., h], [h, 1., h], [h, h, 0.], [h, h, 1.], // faces
        [h, h, h],                                                        // centre
    ];
    let wedge15: Vec<[f64; 3]> = vec![
        [0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.], [1., 0., 1.], [0., 1., 1.],
        [h, 0., 0.], [h, h, 0.], [0., h, 0.], [h, 0., 1.], [h, h, 1.], [0., h, 1.],
        [0., 0., h], [1., 0., h], [0., 1., h],
    ];
    let tet10: Vec<[f64; 3]> = vec![
        [0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.],
        [h, 0., 0.], [h, h, 0.], [0., h, 0.], [0., 0., h], [h, 0., h], [0., h, h],
    ];
    match kind {
        CellKind::Tet4 => tet10[..4].to_vec(),
        CellKind::Tet10 => tet10,
        CellKind::Hex8 => hex27[..8].to_vec(),
        CellKind::Hex20 => hex27[..20].to_vec(),
        CellKind::Hex27 => hex27,
        CellKind::Wedge6 => wedge15[..6].to_vec(),
        CellKind::Wedge15 => wedge15,
        k => panic!("no VTK reference for {k}"),
    }
}

/// The reference nodes that span a cell's affine map from its first node (u, v[, w] axes).
fn basis_nodes(kind: CellKind) -> Vec<usize> {
    match kind.dim() {
        2 if matches!(kind, CellKind::Tri3 | CellKind::Tri6) => vec![1, 2],
        2 => vec![1, 3],
        _ if matches!(kind, CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27) => vec![1, 3, 4],
        _ => vec![1, 2, 3],
    }
}

/// Check that the nodes `pts` of a cell are the affine image of the reference nodes `refs`,
/// and return the map's columns (∂x/∂ξ_k).
fn check_affine(kind: CellKind, refs: &[[f64; 3]], pts: &[[f64; 3]], what: &str) -> Vec<[f64; 3]> {
    assert_eq!(refs.len(), pts.len(), "{what}");
    let basis = basis_nodes(kind);
    // Reference differences along the basis are axis-aligned: one non-zero coordinate each.
    let cols: Vec<[f64; 3]> = basis
        .iter()
        .enumerate()
        .map(|(k, &b)| {
            let dr = refs[b][k] - refs[0][k];
            let dp = sub(pts[b], pts[0]);
            [dp[0] / dr, dp[1] / dr, dp[2] / dr]
        })
        .collect();
    let scale = cols.iter().map(|c| dot(*c, *c).sqrt()).fold(0.0, f64::max);
    for (i, (r, p)) in refs.iter().zip(pts).enumerate() {
        let mut x = pts[0];
        for (k, c) in cols.iter().enumerate() {
            for d in 0..3 {
                x[d] += c[d] * (r[k] - refs[0][k]);
            }
        }
        let err = sub(x, *p);
        assert!(
            dot(err, err).sqrt() <= 1e-12 * scale,
            "{what}: node {i} at {p:?}, expected {x:?}"
        );
    }
    cols
}

// ---------------------------------------------------------------------------------------------
// gmsh reader: the same box in six files

const BOX_FILES: [&str; 6] = [
    "box_41.msh",
    "box_41_bin.msh",
    "box_41_param.msh",
    "box_41_param_bin.msh",
    "box_22.msh",
    "box_22_bin.msh",
];

#[test]
fn box_41_ascii_contents() {
    let m = read_data("box_41.msh");
    assert_eq!(m.n_nodes(), 147);
    assert_eq!(m.node_tags, (1..=147).collect::<Vec<u64>>());
    let kinds: Vec<(CellKind, usize)> = m.blocks.iter().map(|b| (b.kind, b.len())).collect();
    assert_eq!(kinds, vec![(CellKind::Tri6, 8), (CellKind::Tet10, 60)]);
    let groups: Vec<(&str, u8, i32, usize)> = m
        .groups
        .iter()
        .map(|g| (g.name.as_str(), g.dim, g.tag, g.cells.len()))
        .collect();
    assert_eq!(groups, vec![("fixed", 2, 2, 4), ("load", 2, 3, 4), ("body", 3, 1, 60)]);
    // Groups lie where the script put them, and cover the right blocks.
    for (name, x) in [("fixed", 0.0), ("load", 1.0)] {
        let g = m.group(name).unwrap();
        assert!(
            m.group_nodes(g)
                .iter()
                .all(|&n| (m.nodes[n as usize][0] - x).abs() < 1e-12),
            "{name}"
        );
        assert!(
            g.cells
                .iter()
                .all(|c| m.blocks[c.block as usize].kind == CellKind::Tri6)
        );
    }
    let body = m.group("body").unwrap();
    assert!(body.cells.windows(2).all(|w| w[0] < w[1]), "group cells are sorted");
    // gmsh's tet10s are positively oriented with midside nodes at edge midpoints.
    let tets = &m.blocks[1];
    for i in 0..tets.len() {
        let pts: Vec<[f64; 3]> = tets.cell(i).iter().map(|&n| m.nodes[n as usize]).collect();
        let cols = check_affine(CellKind::Tet10, &gmsh_ref(CellKind::Tet10), &pts, "gmsh tet10");
        assert!(det3(cols[0], cols[1], cols[2]) > 0.0);
    }
    let (lo, hi) = m.bounding_box();
    assert_eq!((lo, hi), ([0.0; 3], [1.0, 0.4, 0.2]));
}

#[test]
fn all_box_formats_agree() {
    let reference = read_data("box_41.msh");
    for name in &BOX_FILES[1..] {
        let m = read_data(name);
        assert_same_mesh(&reference, &m, name);
    }
}

#[test]
fn mshio_cross_check_on_41_files() {
    // mshio is an independent MSH 4.1 parser; it rejects the parametric files.
    for name in ["box_41.msh", "box_41_bin.msh", "nophys_41.msh"] {
        let raw = bytes(name);
        let ours = read(&data(name), 1.0).unwrap();
        let theirs = mshio::parse_msh_bytes(&raw).unwrap_or_else(|e| panic!("{name}: {e:?}"));
        let nodes = theirs.data.nodes.as_ref().unwrap();
        assert_eq!(nodes.num_nodes as usize, ours.n_nodes(), "{name}");
        let their_coords: Vec<[f64; 3]> = nodes
            .node_blocks
            .iter()
            .flat_map(|b| b.nodes.iter().map(|n| [n.x, n.y, n.z]))
            .collect();
        assert_eq!(their_coords, ours.nodes, "{name}");
        let n_cells: usize = ours.blocks.iter().map(|b| b.len()).sum();
        assert_eq!(theirs.total_element_count(), n_cells, "{name}");
    }
}

#[test]
fn beams_msh_from_scikit_fem() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes/external/beams.msh");
    let m = read(&path, 1.0).unwrap();
    assert_eq!(m.n_nodes(), 289);
    let kinds: Vec<(CellKind, usize)> = m.blocks.iter().map(|b| (b.kind, b.len())).collect();
    assert_eq!(kinds, vec![(CellKind::Tri3, 8), (CellKind::Tet4, 851)]);
    assert_eq!(m.group("fixed").unwrap().cells.len(), 8);
    assert_eq!(m.group("fixed").unwrap().dim, 2);
    assert_eq!(m.group("all").unwrap().cells.len(), 851);
    assert_eq!(m.group("all").unwrap().dim, 3);
    assert_eq!(m.blocks[1].tags.first(), Some(&9));
}

#[test]
fn file_without_physical_groups() {
    let a = read_data("nophys_41.msh");
    assert!(a.groups.is_empty());
    let kinds: Vec<(CellKind, usize)> = a.blocks.iter().map(|b| (b.kind, b.len())).collect();
    assert_eq!(
        kinds,
        vec![
            (CellKind::Point1, 8),
            (CellKind::Line2, 12),
            (CellKind::Tri3, 24),
            (CellKind::Tet4, 24)
        ]
    );
    let b = read_data("nophys_22.msh");
    assert!(b.groups.is_empty());
    assert_eq!(a.nodes, b.nodes);
    for (x, y) in a.blocks.iter().zip(&b.blocks) {
        assert_eq!((x.kind, &x.conn), (y.kind, &y.conn));
    }
}

#[test]
fn element_in_two_groups() {
    // MSH 4.1: the volume entity carries both physical tags.
    let a = read_data("two_groups_41.msh");
    assert_eq!(a.blocks.len(), 1);
    assert_eq!(a.blocks[0].len(), 24);
    for g in ["a", "b"] {
        assert_eq!(a.group(g).unwrap().cells.len(), 24, "{g}");
    }
    // MSH 2.2 repeats each element per group; the repeats are merged into one cell.
    for name in ["two_groups_22.msh", "two_groups_22_bin.msh"] {
        let b = read_data(name);
        assert_eq!(b.blocks.len(), 1, "{name}");
        assert_eq!(b.blocks[0].conn, a.blocks[0].conn, "{name}");
        assert_eq!(b.group("a").unwrap().cells, a.group("a").unwrap().cells, "{name}");
        assert_eq!(b.group("b").unwrap().cells, a.group("b").unwrap().cells, "{name}");
    }
}

#[test]
fn length_scale_multiplies_coordinates() {
    let m = read(&data("box_22.msh"), 1e-3).unwrap();
    assert_eq!(m.bounding_box().1, [1e-3, 0.4e-3, 0.2e-3]);
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(
            matches!(read(&data("box_22.msh"), bad), Err(Error::InvalidInput(_))),
            "{bad}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// gmsh reader: bad input

#[test]
fn missing_file_is_an_io_error() {
    let p = data("no_such_file.msh");
    match read(&p, 1.0) {
        Err(e @ Error::Io { .. }) => assert!(e.to_string().contains("no_such_file.msh"), "{e}"),
        other => panic!("expected Io error, got {other:?}"),
    }
}

/// The file cut after its first `k` lines.
fn first_lines(text: &str, k: usize) -> String {
    text.lines().take(k).map(|l| format!("{l}\n")).collect()
}

/// 1-based line number of the first line equal to `s`.
fn line_of(text: &str, s: &str) -> usize {
    text.lines().position(|l| l == s).unwrap() + 1
}

#[test]
fn truncated_ascii_files_name_section_and_line() {
    for name in ["box_41.msh", "box_22.msh"] {
        let text = String::from_utf8(bytes(name)).unwrap();
        for section in ["$Nodes", "$Elements"] {
            // Cut 20 lines into the section: the error is at the last line kept.
            let k = line_of(&text, section) + 20;
            let cut = first_lines(&text, k);
            let (sec, line, msg) = parse_err(read_bytes(cut.as_bytes(), Path::new(name), 1.0));
            assert_eq!(sec, section, "{name}: {msg}");
            assert_eq!(line, Some(k), "{name} {section}: {msg}");
            assert!(msg.contains("unexpected end of file"), "{msg}");
            // Cut in the middle of a line too.
            let mid = &cut[..cut.len() - 4];
            let (sec, line, _) = parse_err(read_bytes(mid.as_bytes(), Path::new(name), 1.0));
            assert_eq!((sec.as_str(), line), (section, Some(k)), "{name}");
        }
    }
    // The message names file, section and line.
    let text = String::from_utf8(bytes("box_41.msh")).unwrap();
    let k = line_of(&text, "$Nodes") + 3;
    let e = read_bytes(first_lines(&text, k).as_bytes(), Path::new("cut.msh"), 1.0).unwrap_err();
    assert!(
        e.to_string()
            .starts_with(&format!("cut.msh: $Nodes, line {k}: unexpected end of file")),
        "{e}"
    );
}

#[test]
fn truncated_binary_files_name_section() {
    for name in ["box_41_bin.msh", "box_22_bin.msh"] {
        let raw = bytes(name);
        for section in ["$Nodes", "$Elements"] {
            let at = raw
                .windows(section.len() + 1)
                .position(|w| w == format!("{section}\n").as_bytes())
                .unwrap();
            let cut = &raw[..at + section.len() + 200];
            let (sec, line, msg) = parse_err(read_bytes(cut, Path::new(name), 1.0));
            assert_eq!((sec.as_str(), line), (section, None), "{name}: {msg}");
            assert!(msg.contains("byte offset"), "{msg}");
        }
    }
}

#[test]
fn garbage_number_names_line() {
    let text = String::from_utf8(bytes("box_22.msh")).unwrap();
    let k = line_of(&text, "$Nodes") + 5; // 4th node line
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut f: Vec<&str> = lines[k - 1].split(' ').collect();
    f[2] = "1.5x"; // the y coordinate
    lines[k - 1] = f.join(" ");
    let bad = lines.join("\n");
    let (sec, line, msg) = parse_err(read_bytes(bad.as_bytes(), Path::new("g.msh"), 1.0));
    assert_eq!((sec.as_str(), line), ("$Nodes", Some(k)));
    assert!(msg.contains("expected y, found '1.5x'"), "{msg}");
    // A non-finite coordinate.
    let bad = text.replacen("\n4 0 0.4 0\n", "\n4 0 nan 0\n", 1);
    assert_ne!(bad, text);
    let (sec, _, msg) = parse_err(read_bytes(bad.as_bytes(), Path::new("g.msh"), 1.0));
    assert_eq!(sec, "$Nodes");
    assert!(msg.contains("not finite"), "{msg}");
}

#[test]
fn element_referencing_missing_node() {
    // 2.2: element 1 is "1 9 2 2 1 ..." (a tri6 of group 2); make it reference node 9999.
    let text = String::from_utf8(bytes("box_22.msh")).unwrap();
    let k = line_of(&text, "$Elements") + 2;
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut f: Vec<String> = lines[k - 1].split(' ').map(String::from).collect();
    let elem = f[0].clone();
    f[6] = "9999".into();
    lines[k - 1] = f.join(" ");
    let (sec, line, msg) = parse_err(read_bytes(lines.join("\n").as_bytes(), Path::new("x.msh"), 1.0));
    assert_eq!((sec.as_str(), line), ("$Elements", Some(k)));
    assert!(msg.contains(&format!("element {elem} references node 9999")), "{msg}");

    // 4.1: same for the first element of the first block.
    let text = String::from_utf8(bytes("box_41.msh")).unwrap();
    let k = line_of(&text, "$Elements") + 3;
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut f: Vec<String> = lines[k - 1].split_whitespace().map(String::from).collect();
    f[2] = "12345".into();
    let elem = f[0].clone();
    lines[k - 1] = f.join(" ");
    let (sec, line, msg) = parse_err(read_bytes(lines.join("\n").as_bytes(), Path::new("x.msh"), 1.0));
    assert_eq!((sec.as_str(), line), ("$Elements", Some(k)));
    assert!(msg.contains(&format!("element {elem} references node 12345")), "{msg}");
}

#[test]
fn unsupported_pyramid_names_type_and_group() {
    for name in ["pyramid_41.msh", "pyramid_22.msh"] {
        match read(&data(name), 1.0) {
            Err(e @ Error::UnsupportedElement { .. }) => {
                let Error::UnsupportedElement {
                    gmsh_type,
                    name: tname,
                    group,
                    ..
                } = &e
                else {
                    unreachable!()
                };
                assert_eq!(
                    (*gmsh_type, tname.as_str(), group.as_str()),
                    (7, "5-node pyramid", "pyr")
                );
                assert!(e.to_string().contains("type 7 (5-node pyramid) in pyr"), "{e}");
            }
            other => panic!("{name}: expected UnsupportedElement, got {other:?}"),
        }
    }
    // Without physical groups the entity is named.
    let text = String::from_utf8(bytes("pyramid_41.msh")).unwrap();
    let no_names = text.replace("1 0 0 0 1 1 1 1 1 0", "1 0 0 0 1 1 1 0 0");
    match read_bytes(no_names.as_bytes(), Path::new("p.msh"), 1.0) {
        Err(Error::UnsupportedElement { group, .. }) => assert_eq!(group, "entity 3:1"),
        other => panic!("expected UnsupportedElement, got {other:?}"),
    }
}

#[test]
fn huge_counts_fail_fast() {
    // Counts no file of this size could hold: nothing is allocated for them, and the error at
    // the end of the file recalls the count.
    let cases: [(&str, &str, &str); 6] = [
        (
            "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1000000000000 1 1000000000000\n3 1 0 1000000000000\n1\n0 0 0\n$EndNodes\n",
            "$Nodes",
            "1000000000000 nodes in the block",
        ),
        (
            "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1000000000000 1 1 1\n",
            "$Nodes",
            "1000000000000 node entity blocks",
        ),
        (
            "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n1 1000000000000 1 1\n3 1 4 1000000000000\n1 1 2 3 4\n$EndElements\n",
            "$Elements",
            "1000000000000 elements in the block",
        ),
        (
            "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n1000000000000 0 0 0\n$EndEntities\n",
            "$Entities",
            "1000000000000 point entities",
        ),
        (
            "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1000000000000\n1 0 0 0\n$EndNodes\n",
            "$Nodes",
            "1000000000000 nodes",
        ),
        (
            "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n18446744073709551615\n$EndPhysicalNames\n",
            "$PhysicalNames",
            "18446744073709551615 physical names",
        ),
    ];
    for (text, section, claim) in cases {
        let t = Instant::now();
        let (sec, line, msg) = parse_err(read_bytes(text.as_bytes(), Path::new("huge.msh"), 1.0));
        assert!(t.elapsed().as_secs_f64() < 0.5);
        assert_eq!(sec, section, "{msg}");
        assert!(line.is_some());
        assert!(
            msg.contains(&format!("announced {claim}, more than a file of")),
            "{msg}"
        );
    }
    // Binary 4.1: the header of $Nodes claiming 2^62 nodes.
    let mut raw = bytes("box_41_bin.msh");
    let at = raw.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 7;
    raw[at + 8..at + 16].copy_from_slice(&(1u64 << 62).to_le_bytes()); // numNodes
    let (sec, line, msg) = parse_err(read_bytes(&raw, Path::new("huge.msh"), 1.0));
    assert_eq!((sec.as_str(), line), ("$Nodes", None), "{msg}");
    // ... and a node block claiming 2^62 nodes, more than the header's count leaves: named at
    // the block (a block beyond its header's count is refused whatever the file's size).
    let mut raw = bytes("box_41_bin.msh");
    raw[at + 32 + 12..at + 32 + 20].copy_from_slice(&(1u64 << 62).to_le_bytes());
    let (sec, line, msg) = parse_err(read_bytes(&raw, Path::new("huge.msh"), 1.0));
    assert_eq!((sec.as_str(), line), ("$Nodes", None), "{msg}");
    assert!(
        msg.contains("4611686018427387904 nodes in the block: more than the"),
        "{msg}"
    );
}

#[test]
fn malformed_headers_and_structure() {
    let cases: [(&str, &str, &str); 8] = [
        ("", "$MeshFormat", "empty file"),
        ("hello\n", "$MeshFormat", "not a gmsh MSH file"),
        (
            "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n",
            "$MeshFormat",
            "unsupported MSH format version '3.0'",
        ),
        (
            "$MeshFormat\n4.0 0 8\n$EndMeshFormat\n",
            "$MeshFormat",
            "unsupported MSH format version '4.0'",
        ),
        ("$MeshFormat\n4.1 7 8\n$EndMeshFormat\n", "$MeshFormat", "file type"),
        (
            "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n3 1 0 2\n1\n1\n0 0 0\n1 1 1\n$EndNodes\n",
            "$Nodes",
            "node 1 is defined twice",
        ),
        (
            "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n3 1 0 1\n1\n0 0 0\n$EndNodes\n",
            "$Nodes",
            "announces 2 nodes but the blocks hold 1",
        ),
        (
            "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Comments\nno end\n",
            "$Comments",
            "has no $EndComments",
        ),
    ];
    for (text, section, expect) in cases {
        let (sec, _, msg) = parse_err(read_bytes(text.as_bytes(), Path::new("bad.msh"), 1.0));
        assert_eq!(sec, section, "{msg}");
        assert!(msg.contains(expect), "{msg} (expected '{expect}')");
    }
    // A file with nodes but no elements.
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n";
    assert!(matches!(
        read_bytes(text.as_bytes(), Path::new("e.msh"), 1.0),
        Err(Error::EmptyModel { .. })
    ));
}

/// Every prefix and many single-byte corruptions of each file give a result or an error,
/// never a panic or a runaway allocation.
#[test]
fn no_panic_on_truncation_or_corruption() {
    let mut state = 0x9e3779b97f4a7c15u64; // seeded xorshift
    let mut rand = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let names = [
        &BOX_FILES[..],
        &["nophys_41.msh", "nophys_22.msh", "two_groups_22_bin.msh"],
    ]
    .concat();
    for name in names {
        let raw = bytes(name);
        for cut in (0..raw.len()).step_by(3) {
            let _ = read_bytes(&raw[..cut], Path::new(name), 1.0);
        }
        for _ in 0..3000 {
            let mut m = raw.clone();
            let n = 1 + (rand() % 3) as usize;
            for _ in 0..n {
                let i = (rand() % m.len() as u64) as usize;
                m[i] = match rand() % 4 {
                    0 => b'9',
                    1 => 0xff,
                    2 => b' ',
                    _ => rand() as u8,
                };
            }
            let _ = read_bytes(&m, Path::new(name), 1.0);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Structured generators

const N: [usize; 3] = [2, 3, 2];
const SIZE: [f64; 3] = [2.0, 1.5, 1.0];

fn expected_counts(kind: CellKind) -> (usize, usize) {
    let [nx, ny, nz] = N;
    let corners = (nx + 1) * (ny + 1) * (nz + 1);
    let axis_edges = nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz;
    let face_centres = nx * ny * (nz + 1) + nx * (ny + 1) * nz + (nx + 1) * ny * nz;
    let bricks = nx * ny * nz;
    match kind {
        CellKind::Tet4 => (corners, 6 * bricks),
        // Kuhn tets add one diagonal per brick face and one per brick.
        CellKind::Tet10 => (corners + axis_edges + face_centres + bricks, 6 * bricks),
        CellKind::Hex8 => (corners, bricks),
        CellKind::Hex20 => (corners + axis_edges, bricks),
        CellKind::Hex27 => ((2 * nx + 1) * (2 * ny + 1) * (2 * nz + 1), bricks),
        CellKind::Wedge6 => (corners, 2 * bricks),
        // Wedges add one diagonal per z face of each brick.
        CellKind::Wedge15 => (corners + axis_edges + nx * ny * (nz + 1), 2 * bricks),
        _ => unreachable!(),
    }
}

#[test]
fn generated_counts_and_tags() {
    for kind in CellKind::SOLIDS {
        let m = box_mesh(kind, SIZE, N);
        let (nodes, cells) = expected_counts(kind);
        assert_eq!(m.n_nodes(), nodes, "{kind}");
        assert_eq!(m.n_cells_of_dim(3), cells, "{kind}");
        assert_eq!(m.blocks[0].kind, kind);
        assert_eq!(m.node_tags, (1..=nodes as u64).collect::<Vec<_>>(), "{kind}");
        let tags: Vec<u64> = m.blocks.iter().flat_map(|b| b.tags.iter().copied()).collect();
        assert_eq!(tags, (1..=tags.len() as u64).collect::<Vec<_>>(), "{kind}");
        assert_eq!(m.group("volume").unwrap().cells.len(), cells);
        let names: Vec<&str> = m.groups.iter().map(|g| g.name.as_str()).collect();
        assert_eq!(names, ["volume", "xmin", "xmax", "ymin", "ymax", "zmin", "zmax"]);
        // Face group sizes: a brick face is one quad or two triangles.
        let split = |tri: bool| if tri { 2 } else { 1 };
        let tet = matches!(kind, CellKind::Tet4 | CellKind::Tet10);
        let wedge = matches!(kind, CellKind::Wedge6 | CellKind::Wedge15);
        let [nx, ny, nz] = N;
        assert_eq!(m.group("xmin").unwrap().cells.len(), ny * nz * split(tet), "{kind}");
        assert_eq!(m.group("ymax").unwrap().cells.len(), nx * nz * split(tet), "{kind}");
        assert_eq!(
            m.group("zmin").unwrap().cells.len(),
            nx * ny * split(tet || wedge),
            "{kind}"
        );
        let (lo, hi) = m.bounding_box();
        assert_eq!((lo, hi), ([0.0; 3], SIZE));
    }
}

#[test]
fn generated_cells_follow_gmsh_reference_and_are_positive() {
    for kind in CellKind::SOLIDS {
        let m = box_mesh(kind, SIZE, N);
        for b in &m.blocks {
            let refs = gmsh_ref(b.kind);
            for i in 0..b.len() {
                let pts: Vec<[f64; 3]> = b.cell(i).iter().map(|&n| m.nodes[n as usize]).collect();
                let cols = check_affine(b.kind, &refs, &pts, &format!("{kind}: {} {i}", b.kind));
                if b.kind.dim() == 3 {
                    // Affine cells: the Jacobian is constant, its determinant positive.
                    assert!(det3(cols[0], cols[1], cols[2]) > 0.0, "{kind}: cell {i} inverted");
                }
            }
        }
    }
}

#[test]
fn generated_face_groups_lie_on_their_planes_facing_out() {
    for kind in CellKind::SOLIDS {
        let m = box_mesh(kind, SIZE, N);
        for (gi, name) in ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"].iter().enumerate() {
            let g = m.group(name).unwrap();
            assert_eq!(g.dim, 2);
            let (axis, at_max) = (gi / 2, gi % 2 == 1);
            let plane = if at_max { SIZE[axis] } else { 0.0 };
            let mut outward = [0.0; 3];
            outward[axis] = if at_max { 1.0 } else { -1.0 };
            let mut area = 0.0;
            for c in &g.cells {
                let b = &m.blocks[c.block as usize];
                let pts: Vec<[f64; 3]> = b.cell(c.index as usize).iter().map(|&n| m.nodes[n as usize]).collect();
                assert!(
                    pts.iter().all(|p| p[axis] == plane),
                    "{kind} {name}: node off the plane"
                );
                let normal = cross(sub(pts[1], pts[0]), sub(pts[2], pts[0]));
                assert!(dot(normal, outward) > 0.0, "{kind} {name}: face points inwards");
                let tri = matches!(b.kind, CellKind::Tri3 | CellKind::Tri6);
                area += dot(normal, outward) * if tri { 0.5 } else { 1.0 };
            }
            let expect = SIZE
                .iter()
                .enumerate()
                .filter(|&(d, _)| d != axis)
                .map(|(_, s)| s)
                .product::<f64>();
            assert!((area - expect).abs() < 1e-12, "{kind} {name}: area {area} vs {expect}");
        }
    }
}

#[test]
fn generated_meshes_are_conforming() {
    for kind in CellKind::SOLIDS {
        let m = box_mesh(kind, SIZE, N);
        let vol = &m.blocks[0];
        let n_corners = match kind {
            CellKind::Tet4 | CellKind::Tet10 => 4,
            CellKind::Wedge6 | CellKind::Wedge15 => 6,
            _ => 8,
        };
        // Each face (as a sorted corner set) is shared by two cells, or lies on the boundary.
        let faces: &[&[usize]] = match n_corners {
            4 => &[&[0, 1, 2], &[0, 1, 3], &[0, 2, 3], &[1, 2, 3]],
            6 => &[&[0, 1, 2], &[3, 4, 5], &[0, 1, 4, 3], &[0, 2, 5, 3], &[1, 2, 5, 4]],
            _ => &[
                &[0, 1, 2, 3],
                &[4, 5, 6, 7],
                &[0, 1, 5, 4],
                &[1, 2, 6, 5],
                &[2, 3, 7, 6],
                &[0, 3, 7, 4],
            ],
        };
        let mut count = std::collections::HashMap::<Vec<u32>, usize>::new();
        // Midside nodes: an edge has the same midside node in every cell that has the edge.
        let mut mid = std::collections::HashMap::<(u32, u32), u32>::new();
        let edges = vibrofem::mesh::generate::higher_order_nodes(kind);
        for i in 0..vol.len() {
            let c = vol.cell(i);
            for f in faces {
                let mut k: Vec<u32> = f.iter().map(|&j| c[j]).collect();
                k.sort_unstable();
                *count.entry(k).or_default() += 1;
            }
            for (e, set) in edges.iter().enumerate() {
                if set.len() == 2 {
                    let (a, b) = (c[set[0]].min(c[set[1]]), c[set[0]].max(c[set[1]]));
                    let node = c[n_corners + e];
                    assert_eq!(*mid.entry((a, b)).or_insert(node), node, "{kind}: edge {a}-{b}");
                }
            }
        }
        assert!(count.values().all(|&n| n <= 2), "{kind}: a face is shared by 3 cells");
        let mut boundary: Vec<Vec<u32>> = count.into_iter().filter(|(_, n)| *n == 1).map(|(k, _)| k).collect();
        boundary.sort();
        let mut from_groups: Vec<Vec<u32>> = m.groups[1..]
            .iter()
            .flat_map(|g| g.cells.iter())
            .map(|c| {
                let b = &m.blocks[c.block as usize];
                let corners = if matches!(b.kind, CellKind::Tri3 | CellKind::Tri6) {
                    3
                } else {
                    4
                };
                let mut k = b.cell(c.index as usize)[..corners].to_vec();
                k.sort_unstable();
                k
            })
            .collect();
        from_groups.sort();
        assert_eq!(
            boundary, from_groups,
            "{kind}: open faces are exactly the boundary groups"
        );
    }
}

#[test]
fn generator_rejects_bad_arguments() {
    assert!(matches!(
        try_box_mesh(CellKind::Tri3, SIZE, N),
        Err(Error::InvalidInput(_))
    ));
    assert!(matches!(
        try_box_mesh(CellKind::Hex8, [1.0, 0.0, 1.0], N),
        Err(Error::InvalidInput(_))
    ));
    assert!(matches!(
        try_box_mesh(CellKind::Hex8, SIZE, [1, 0, 1]),
        Err(Error::InvalidInput(_))
    ));
    assert!(matches!(
        try_box_mesh(CellKind::Hex8, SIZE, [1 << 30, 1 << 30, 1]),
        Err(Error::InvalidInput(_))
    ));
}

// ---------------------------------------------------------------------------------------------
// VTU writer

/// VTK's node order puts every node where VTK's parametric coordinates say, with a positive
/// Jacobian (which VTK 9's vtkCellValidator requires, wedges included).
#[test]
fn vtk_permutations_match_vtk_reference_cells() {
    for kind in CellKind::SOLIDS {
        let m = box_mesh(kind, SIZE, N);
        let b = &m.blocks[0];
        let (vtk_type, perm) = gmsh_to_vtk(kind);
        let refs = vtk_ref(kind);
        for i in 0..b.len() {
            let gmsh: Vec<[f64; 3]> = b.cell(i).iter().map(|&n| m.nodes[n as usize]).collect();
            let vtk: Vec<[f64; 3]> = match perm {
                Some(p) => p.iter().map(|&j| gmsh[j]).collect(),
                None => gmsh.clone(),
            };
            let cols = check_affine(kind, &refs, &vtk, &format!("VTK type {vtk_type} ({kind}) cell {i}"));
            assert!(det3(cols[0], cols[1], cols[2]) > 0.0, "{kind}: VTK orientation");
        }
        if let Some(p) = perm {
            let mut sorted = p.to_vec();
            sorted.sort_unstable();
            assert_eq!(sorted, (0..kind.n_nodes()).collect::<Vec<_>>(), "{kind}: permutation");
        }
    }
}

#[test]
fn vtu_file_has_cells_fields_and_types() {
    let m = box_mesh(CellKind::Hex20, [1.0, 1.0, 1.0], [2, 1, 1]);
    let n = m.n_nodes();
    let phi7: Vec<f64> = (0..3 * n).map(|i| i as f64 * 1e-3).collect();
    let phi8: Vec<f64> = (0..3 * n).map(|i| -(i as f64)).collect();
    let fields = [
        PointField::mode(7, &phi7),
        PointField::mode(8, &phi8),
        PointField::new("s<&>", 1, &phi7[..n]),
    ];
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("mesh_io_hex20.vtu");
    write_vtu(&path, &m, &fields).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(
        text.contains(&format!("NumberOfPoints=\"{n}\" NumberOfCells=\"2\"")),
        "only the 2 hexes"
    );
    assert!(text.contains("Name=\"mode_7\" NumberOfComponents=\"3\""));
    assert!(text.contains("Name=\"mode_8\" NumberOfComponents=\"3\""));
    assert!(text.contains("Name=\"s&lt;&amp;&gt;\" NumberOfComponents=\"1\""));
    let types = text.split("Name=\"types\" format=\"ascii\">\n").nth(1).unwrap();
    assert!(types.starts_with("25\n25\n</DataArray>"));
    let offsets = text.split("Name=\"offsets\" format=\"ascii\">\n").nth(1).unwrap();
    assert!(offsets.starts_with("20\n40\n</DataArray>"));
    // Connectivity of the first cell is the gmsh cell permuted by VTK_HEX20.
    let conn = text.split("Name=\"connectivity\" format=\"ascii\">\n").nth(1).unwrap();
    let first: Vec<u32> = conn
        .lines()
        .next()
        .unwrap()
        .split(' ')
        .map(|t| t.parse().unwrap())
        .collect();
    let expect: Vec<u32> = vibrofem::io::vtk::VTK_HEX20
        .iter()
        .map(|&j| m.blocks[0].cell(0)[j])
        .collect();
    assert_eq!(first, expect);
    // Values read back exactly.
    let pts = text
        .split("NumberOfComponents=\"3\" format=\"ascii\">\n")
        .nth(3)
        .unwrap();
    let coords: Vec<f64> = pts
        .lines()
        .take(n)
        .flat_map(|l| l.split(' ').map(|t| t.parse::<f64>().unwrap()))
        .collect();
    assert_eq!(coords, m.nodes.iter().flatten().copied().collect::<Vec<_>>());

    // A surface-only mesh writes its 2D cells.
    let mut surf = m.clone();
    surf.blocks.remove(0);
    let text = vtu_string(&surf, &[]).unwrap();
    assert!(text.contains("NumberOfCells=\"10\""), "{}", &text[..300]);

    // Bad fields.
    assert!(matches!(
        vtu_string(&m, &[PointField::new("x", 3, &phi7[..10])]),
        Err(Error::InvalidInput(_))
    ));
    let nan = vec![f64::NAN; n];
    assert!(matches!(
        vtu_string(&m, &[PointField::new("x", 1, &nan)]),
        Err(Error::InvalidInput(_))
    ));
    let missing = Path::new(env!("CARGO_TARGET_TMPDIR")).join("no/such/dir/x.vtu");
    assert!(matches!(write_vtu(&missing, &m, &[]), Err(Error::Io { .. })));
}

// ---------------------------------------------------------------------------------------------
// MSH writer

#[test]
fn msh_views_round_trip_through_the_reader() {
    for kind in CellKind::SOLIDS {
        let m = box_mesh(kind, SIZE, [1, 2, 1]);
        let n = m.n_nodes();
        let phi: Vec<f64> = (0..3 * n).map(|i| (i as f64).sin()).collect();
        let views = [
            NodeView {
                name: "mode 1: 12.5 Hz".into(),
                step: 0,
                time: 12.5,
                n_comp: 3,
                data: &phi,
            },
            NodeView {
                name: "energy".into(),
                step: 0,
                time: 0.0,
                n_comp: 1,
                data: &phi[..n],
            },
        ];
        let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("mesh_io_{kind}.msh"));
        write_msh_views(&path, &m, &views).unwrap();
        let back = read(&path, 1.0).unwrap();
        // Groups come back ordered by (dimension, tag).
        let mut expect = m.clone();
        expect.groups.sort_by_key(|g| (g.dim, g.tag));
        assert_same_mesh(&expect, &back, &format!("{kind} round trip"));
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.matches("$NodeData").count(), 2);
        assert!(text.contains("$NodeData\n1\n\"mode 1: 12.5 Hz\"\n1\n12.5\n3\n0\n3\n"));
    }
    // A gmsh-made mesh survives a round trip too (its cell in several groups included).
    for name in ["box_41.msh", "two_groups_22.msh", "nophys_22.msh"] {
        let m = read_data(name);
        let text = msh_string(&m, &[]).unwrap();
        let back = read_bytes(text.as_bytes(), Path::new(name), 1.0).unwrap();
        assert_same_mesh(&m, &back, name);
    }
    let m = box_mesh(CellKind::Tet4, SIZE, [1, 1, 1]);
    let two = vec![0.0; 2 * m.n_nodes()];
    let bad = NodeView {
        name: "x".into(),
        step: 0,
        time: 0.0,
        n_comp: 2,
        data: &two,
    };
    assert!(matches!(msh_string(&m, &[bad]), Err(Error::InvalidInput(_))));
}
