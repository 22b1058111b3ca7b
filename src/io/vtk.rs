//! VTK XML unstructured-grid writer (`.vtu`, ASCII), for ParaView.
//!
//! The file holds all nodes, the cells of the model ([`write_vtu_cells`]: the solids, shells
//! and beams the analysis used, from [`crate::model::Model::cell_blocks`]) or, without a model,
//! the cells of the mesh's highest dimension ([`write_vtu`]), one point-data array per
//! [`PointField`] (e.g. one 3-component array per mode shape, `mode_7`, ...) and the gmsh
//! element tag of each cell as cell data `element_tag`.
//!
//! # Node ordering
//! vibrofem stores cells in gmsh's node ordering; VTK orders the nodes of some cells
//! differently. [`gmsh_to_vtk`] gives, for each kind, the table `T` such that VTK node `i` is
//! gmsh node `T[i]`:
//!
//! | kind | VTK type | difference |
//! |---|---|---|
//! | tet10 | `VTK_QUADRATIC_TETRA` (24) | VTK edges 0-1, 1-2, 2-0, 0-3, 1-3, 2-3: gmsh nodes 8 (2-3) and 9 (1-3) swap |
//! | hex20 | `VTK_QUADRATIC_HEXAHEDRON` (25) | VTK edges: bottom ring 0-1, 1-2, 2-3, 3-0, top ring 4-5, 5-6, 6-7, 7-4, then verticals 0-4, 1-5, 2-6, 3-7; gmsh: 0-1, 0-3, 0-4, 1-2, 1-5, 2-3, 2-6, 3-7, 4-5, 4-7, 5-6, 6-7 |
//! | hex27 | `VTK_TRIQUADRATIC_HEXAHEDRON` (29) | edges as hex20, then VTK faces x-min, x-max, y-min, y-max, z-min, z-max (gmsh: z-min, y-min, x-min, x-max, y-max, z-max), centre |
//! | wedge15 | `VTK_QUADRATIC_WEDGE` (26) | VTK edges 0-1, 1-2, 2-0, 3-4, 4-5, 5-3, 0-3, 1-4, 2-5; gmsh: 0-1, 0-2, 0-3, 1-2, 1-4, 2-5, 3-4, 3-5, 4-5 |
//!
//! The other kinds (points, lines, triangles, quadrangles, tet4, hex8, wedge6) have the same
//! order in both. In particular the wedge corners are *not* reordered: VTK's parametric
//! coordinates put 0-1-2 at the bottom, counter-clockwise seen from 3-4-5, as gmsh does. (An
//! old comment in `vtkWedge.h` says the opposite, and gmsh's own VTK export swaps the linear
//! wedge's corners; VTK 9's `vtkCellValidator` flags such swapped wedges as wrongly oriented
//! and `vtkCellSizeFilter` gives them negative volumes, while the unswapped ones pass.)
//! The tables are checked in `tests/unit/mesh_io.rs` against VTK's parametric coordinates of each
//! cell type.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use super::fmt_f64;
use crate::mesh::{CellBlock, CellKind, Mesh};
use crate::{Error, Result};

/// A nodal field to write: `n_comp` values per node, node-major
/// (`data[node * n_comp + comp]`). Three components display as a vector in ParaView.
#[derive(Clone, Debug)]
pub struct PointField<'a> {
    /// Array name shown in ParaView (e.g. `"mode_7"`).
    pub name: String,
    /// Components per node (1 scalar, 3 vector, 6 or 9 tensor).
    pub n_comp: usize,
    /// Values, `n_comp * n_nodes` of them.
    pub data: &'a [f64],
}

impl<'a> PointField<'a> {
    /// A field named `name` with `n_comp` components per node.
    pub fn new(name: impl Into<String>, n_comp: usize, data: &'a [f64]) -> Self {
        PointField {
            name: name.into(),
            n_comp,
            data,
        }
    }

    /// The 3-component field `mode_<number>` of a mode shape (`[ux, uy, uz]` per node).
    pub fn mode(number: usize, data: &'a [f64]) -> Self {
        PointField::new(format!("mode_{number}"), 3, data)
    }
}

/// gmsh → VTK node order of tet10: VTK node `i` is gmsh node `VTK_TET10[i]`.
pub const VTK_TET10: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];

/// gmsh → VTK node order of hex20.
#[rustfmt::skip]
pub const VTK_HEX20: [usize; 20] = [
    0, 1, 2, 3, 4, 5, 6, 7,
    8, 11, 13, 9,     // bottom ring: 0-1, 1-2, 2-3, 3-0
    16, 18, 19, 17,   // top ring:    4-5, 5-6, 6-7, 7-4
    10, 12, 14, 15,   // verticals:   0-4, 1-5, 2-6, 3-7
];

/// gmsh → VTK node order of hex27.
#[rustfmt::skip]
pub const VTK_HEX27: [usize; 27] = [
    0, 1, 2, 3, 4, 5, 6, 7,
    8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15,
    22, 23, 21, 24, 20, 25, // faces: x-min, x-max, y-min, y-max, z-min, z-max
    26,                     // centre
];

/// gmsh → VTK node order of wedge15 (corners unchanged).
#[rustfmt::skip]
pub const VTK_WEDGE15: [usize; 15] = [
    0, 1, 2, 3, 4, 5,
    6, 9, 7,     // bottom: 0-1, 1-2, 2-0
    12, 14, 13,  // top:    3-4, 4-5, 5-3
    8, 10, 11,   // sides:  0-3, 1-4, 2-5
];

/// VTK cell type id and gmsh → VTK node permutation of a kind (`None`: same order).
pub fn gmsh_to_vtk(kind: CellKind) -> (u8, Option<&'static [usize]>) {
    match kind {
        CellKind::Point1 => (1, None),
        CellKind::Line2 => (3, None),
        CellKind::Line3 => (21, None),
        CellKind::Tri3 => (5, None),
        CellKind::Tri6 => (22, None),
        CellKind::Quad4 => (9, None),
        CellKind::Quad8 => (23, None),
        CellKind::Quad9 => (28, None),
        CellKind::Tet4 => (10, None),
        CellKind::Tet10 => (24, Some(&VTK_TET10)),
        CellKind::Hex8 => (12, None),
        CellKind::Hex20 => (25, Some(&VTK_HEX20)),
        CellKind::Hex27 => (29, Some(&VTK_HEX27)),
        CellKind::Wedge6 => (13, None),
        CellKind::Wedge15 => (26, Some(&VTK_WEDGE15)),
    }
}

/// Write `mesh` and its nodal fields to a `.vtu` file.
///
/// ```no_run
/// # use vibrofem::io::vtk::{write_vtu, PointField};
/// # let mesh = vibrofem::mesh::generate::box_mesh(vibrofem::mesh::CellKind::Hex8, [1.0; 3], [2; 3]);
/// # let (phi7, phi8) = (vec![0.0; 3 * mesh.n_nodes()], vec![0.0; 3 * mesh.n_nodes()]);
/// // Two mode shapes as separate vector fields of one file.
/// let fields = [PointField::mode(7, &phi7), PointField::mode(8, &phi8)];
/// write_vtu("modes.vtu".as_ref(), &mesh, &fields)?;
/// # Ok::<(), vibrofem::Error>(())
/// ```
///
/// # Errors
/// [`Error::InvalidInput`] if a field does not have `n_comp` finite values per node,
/// [`Error::param`] if the mesh has no cells, [`Error::Io`] if the file cannot be created,
/// [`Error::Output`] if it cannot be written (a full disk).
pub fn write_vtu(path: &Path, mesh: &Mesh, point_data: &[PointField]) -> Result<()> {
    write_vtu_cells(path, mesh, None, point_data)
}

/// [`write_vtu`] with the cells `cells` (on the mesh's nodes) instead of the mesh's own of its
/// highest dimension (`None`).
pub fn write_vtu_cells(path: &Path, mesh: &Mesh, cells: Option<&[CellBlock]>, point_data: &[PointField]) -> Result<()> {
    write_vtu_with(path, mesh, cells, point_data, &[])
}

/// [`write_vtu_cells`] with arrays of the whole data set (`<FieldData>`, e.g. the modes'
/// `frequencies_hz`), which ParaView shows in its *Information* panel and scripts read as
/// `field_data`.
pub fn write_vtu_with(
    path: &Path,
    mesh: &Mesh,
    cells: Option<&[CellBlock]>,
    point_data: &[PointField],
    field_data: &[(&str, &[f64])],
) -> Result<()> {
    let text = vtu_string_cells(mesh, cells, point_data, field_data)?;
    let mut f = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    // Created but not written (a full disk): a result lost, exit 4, not an input error.
    f.write_all(text.as_bytes())
        .map_err(|e| Error::output(path.display(), e))
}

/// The `.vtu` document as a string (see [`write_vtu`]).
pub fn vtu_string(mesh: &Mesh, point_data: &[PointField]) -> Result<String> {
    vtu_string_cells(mesh, None, point_data, &[])
}

/// The `.vtu` document of `cells` with `field_data` (see [`write_vtu_with`]).
pub fn vtu_string_cells(
    mesh: &Mesh,
    cells: Option<&[CellBlock]>,
    point_data: &[PointField],
    field_data: &[(&str, &[f64])],
) -> Result<String> {
    let n_nodes = mesh.n_nodes();
    if let Some((name, _)) = field_data.iter().find(|(_, v)| v.iter().any(|x| !x.is_finite())) {
        return Err(Error::InvalidInput(format!("field data '{name}': a non-finite value")));
    }
    for f in point_data {
        // Stays Error::InvalidInput: tests/unit/mesh_io.rs matches on the variant.
        if f.n_comp == 0 || f.data.len() != f.n_comp * n_nodes {
            return Err(Error::InvalidInput(format!(
                "field '{}': {} values for {} nodes with {} components",
                f.name,
                f.data.len(),
                n_nodes,
                f.n_comp
            )));
        }
        if let Some(i) = f.data.iter().position(|v| !v.is_finite()) {
            return Err(Error::InvalidInput(format!(
                "field '{}': non-finite value at node {}",
                f.name,
                mesh.node_tags
                    .get(i / f.n_comp)
                    .copied()
                    .unwrap_or((i / f.n_comp) as u64)
            )));
        }
    }
    // The cells given, or those of the mesh's highest dimension.
    let all = cells.unwrap_or(&mesh.blocks);
    let top = all.iter().filter(|b| !b.is_empty()).map(|b| b.kind.dim()).max();
    let Some(top) = top else {
        return Err(Error::param("mesh", "cannot write a VTU file of a mesh without cells"));
    };
    let blocks: Vec<&CellBlock> = all
        .iter()
        .filter(|b| !b.is_empty() && (cells.is_some() || b.kind.dim() == top))
        .collect();
    if let Some(a) = blocks
        .iter()
        .flat_map(|b| b.conn.iter())
        .find(|&&a| a as usize >= n_nodes)
    {
        return Err(Error::InvalidInput(format!(
            "cell node {a} beyond the mesh's {n_nodes} nodes"
        )));
    }
    let n_cells: usize = blocks.iter().map(|b| b.len()).sum();

    // `write!` into a String cannot fail, so its results are ignored below.
    let mut s = String::with_capacity(64 * (n_nodes + n_cells) + 256);
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
    );
    s.push_str("<UnstructuredGrid>\n");
    if !field_data.is_empty() {
        s.push_str("<FieldData>\n");
        for (name, v) in field_data {
            let _ = writeln!(
                s,
                "<DataArray type=\"Float64\" Name=\"{}\" NumberOfTuples=\"{}\" format=\"ascii\">",
                xml_escape(name),
                v.len()
            );
            push_floats(&mut s, v);
            s.push_str("</DataArray>\n");
        }
        s.push_str("</FieldData>\n");
    }
    let _ = writeln!(s, "<Piece NumberOfPoints=\"{n_nodes}\" NumberOfCells=\"{n_cells}\">");

    if !point_data.is_empty() {
        s.push_str("<PointData>\n");
        for f in point_data {
            let _ = writeln!(
                s,
                "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"ascii\">",
                xml_escape(&f.name),
                f.n_comp
            );
            for row in f.data.chunks(f.n_comp) {
                push_floats(&mut s, row);
            }
            s.push_str("</DataArray>\n");
        }
        s.push_str("</PointData>\n");
    }

    s.push_str("<CellData>\n<DataArray type=\"Int64\" Name=\"element_tag\" format=\"ascii\">\n");
    for b in &blocks {
        for t in &b.tags {
            let _ = writeln!(s, "{t}");
        }
    }
    s.push_str("</DataArray>\n</CellData>\n");

    s.push_str("<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for p in &mesh.nodes {
        push_floats(&mut s, p);
    }
    s.push_str("</DataArray>\n</Points>\n");

    s.push_str("<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for b in &blocks {
        let (_, perm) = gmsh_to_vtk(b.kind);
        for i in 0..b.len() {
            let cell = b.cell(i);
            let mut line = String::new();
            match perm {
                Some(perm) => perm.iter().for_each(|&j| {
                    let _ = write!(line, "{} ", cell[j]);
                }),
                None => cell.iter().for_each(|n| {
                    let _ = write!(line, "{n} ");
                }),
            }
            s.push_str(line.trim_end());
            s.push('\n');
        }
    }
    s.push_str("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    let mut offset = 0usize;
    for b in &blocks {
        for _ in 0..b.len() {
            offset += b.kind.n_nodes();
            let _ = writeln!(s, "{offset}");
        }
    }
    s.push_str("</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for b in &blocks {
        let (t, _) = gmsh_to_vtk(b.kind);
        for _ in 0..b.len() {
            let _ = writeln!(s, "{t}");
        }
    }
    s.push_str("</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    Ok(s)
}

/// Append one line of space-separated floats in round-trip exponent form.
fn push_floats(s: &mut String, v: &[f64]) {
    for (i, x) in v.iter().enumerate() {
        if i > 0 {
            s.push(' ');
        }
        s.push_str(&fmt_f64(*x));
    }
    s.push('\n');
}

/// Escape a string for an XML attribute value.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}
