//! Structured mesh generators, in pure Rust (tests, benches and the CLI use them without gmsh).
//!
//! [`box_mesh`] meshes the box `[0, lx] × [0, ly] × [0, lz]` split into `nx × ny × nz` hexahedral
//! bricks, each brick filled with cells of the requested kind:
//!
//! - hexahedra: the brick itself;
//! - tetrahedra: 6 tetrahedra around the brick diagonal from its corner `(0,0,0)` to `(1,1,1)`
//!   (Kuhn subdivision). Every brick is a translated copy, so the diagonal of each shared face
//!   is the same seen from both sides and the mesh is conforming;
//! - wedges: 2 prisms, splitting the brick's bottom and top faces along the diagonal from
//!   `(0,0)` to `(1,1)`, extruded along z.
//!
//! All nodes sit on a lattice with half the brick spacing. Every cell is first described by its
//! corners (lattice points); its higher-order nodes are then the lattice midpoints of the
//! edges, faces or body listed in gmsh's order for the kind ([`higher_order_nodes`]). Cells
//! sharing an edge therefore share its midside node: the quadratic meshes are conforming.
//! Nodes are numbered in lattice order (x fastest, then y, then z), tags `1..=N`; element tags
//! are `1..=E`, volume cells first.
//!
//! Groups: `"volume"` (dimension 3, every cell) and the six boundary faces `"xmin"`,
//! `"xmax"`, `"ymin"`, `"ymax"`, `"zmin"`, `"zmax"` (dimension 2), made of the boundary faces
//! of the cells: Tri3/Tri6 for tetrahedra and the wedges' z faces, Quad4/Quad8/Quad9 for the
//! others. Face cells are ordered so that their normal (right-hand rule) points out of the box.
//!
//! All cells are positively oriented (positive Jacobian determinant) in gmsh's convention.

use crate::mesh::{CellBlock, CellKind, CellRef, Group, Mesh};
use crate::{Error, Result};

/// Corner offsets of a brick in gmsh's hexahedron order.
///
/// ```text
///        v
/// 3----------2
/// |\     ^   |\
/// | \    |   | \
/// |  \   |   |  \
/// |   7------+---6
/// |   |  +-- |-- | -> u
/// 0---+---\--1   |
///  \  |    \  \  |
///   \ |     \  \ |
///    \|      w  \|
///     4----------5
/// ```
#[rustfmt::skip]
const BRICK: [[usize; 3]; 8] = [
    [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
    [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1],
];

/// The 6 tetrahedra of a brick (brick corner indices), all containing the diagonal 0–6, each
/// ordered so that its volume is positive.
#[rustfmt::skip]
const BRICK_TETS: [[usize; 4]; 6] = [
    [0, 1, 2, 6], [0, 2, 3, 6], [0, 5, 1, 6],
    [0, 4, 5, 6], [0, 3, 7, 6], [0, 7, 4, 6],
];

/// The 2 wedges of a brick (brick corner indices): bottom triangle counter-clockwise seen from
/// +z, then the top triangle above it.
const BRICK_WEDGES: [[usize; 6]; 2] = [[0, 1, 2, 4, 5, 6], [0, 2, 3, 4, 6, 7]];

/// Faces of each linear solid as lists of its corners, ordered so that the right-hand normal
/// points out of a positively oriented cell.
pub(crate) fn faces(kind: CellKind) -> &'static [&'static [usize]] {
    match kind {
        CellKind::Tet4 | CellKind::Tet10 => &[&[0, 2, 1], &[0, 1, 3], &[0, 3, 2], &[1, 2, 3]],
        CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => &[
            &[0, 3, 2, 1],
            &[0, 1, 5, 4],
            &[0, 4, 7, 3],
            &[1, 2, 6, 5],
            &[2, 3, 7, 6],
            &[4, 5, 6, 7],
        ],
        CellKind::Wedge6 | CellKind::Wedge15 => &[&[0, 2, 1], &[3, 4, 5], &[0, 1, 4, 3], &[0, 3, 5, 2], &[1, 2, 5, 4]],
        // Not solids: no faces.
        CellKind::Point1
        | CellKind::Line2
        | CellKind::Line3
        | CellKind::Tri3
        | CellKind::Tri6
        | CellKind::Quad4
        | CellKind::Quad8
        | CellKind::Quad9 => &[],
    }
}

/// The nodes after the corners, in gmsh's order, each given as the corners whose centroid it
/// is (two corners: an edge midpoint; four: a face centre; eight: the body centre).
///
/// These follow gmsh's reference elements (`gmsh.model.mesh.getElementProperties`):
/// - Tri6: edges 0-1, 1-2, 2-0.
/// - Quad8: edges 0-1, 1-2, 2-3, 3-0; Quad9: the same, then the centre.
/// - Tet10: edges 0-1, 1-2, 2-0, 0-3, 2-3, 1-3.
/// - Hex20: edges 0-1, 0-3, 0-4, 1-2, 1-5, 2-3, 2-6, 3-7, 4-5, 4-7, 5-6, 6-7.
/// - Hex27: the Hex20 edges, then the face centres of 0-1-2-3 (z = 0), 0-1-5-4 (y = 0),
///   0-3-7-4 (x = 0), 1-2-6-5 (x = 1), 2-3-7-6 (y = 1), 4-5-6-7 (z = 1), then the body centre.
/// - Wedge15: edges 0-1, 0-2, 0-3, 1-2, 1-4, 2-5, 3-4, 3-5, 4-5.
#[rustfmt::skip]
pub fn higher_order_nodes(kind: CellKind) -> &'static [&'static [usize]] {
    const HEX20: [&[usize]; 12] = [
        &[0, 1], &[0, 3], &[0, 4], &[1, 2], &[1, 5], &[2, 3],
        &[2, 6], &[3, 7], &[4, 5], &[4, 7], &[5, 6], &[6, 7],
    ];
    const HEX27: [&[usize]; 19] = [
        &[0, 1], &[0, 3], &[0, 4], &[1, 2], &[1, 5], &[2, 3],
        &[2, 6], &[3, 7], &[4, 5], &[4, 7], &[5, 6], &[6, 7],
        &[0, 1, 2, 3], &[0, 1, 5, 4], &[0, 3, 7, 4], // faces z = 0, y = 0, x = 0
        &[1, 2, 6, 5], &[2, 3, 7, 6], &[4, 5, 6, 7], // faces x = 1, y = 1, z = 1
        &[0, 1, 2, 3, 4, 5, 6, 7],                   // centre
    ];
    match kind {
        CellKind::Line3 => &[&[0, 1]],
        CellKind::Tri6 => &[&[0, 1], &[1, 2], &[2, 0]],
        CellKind::Quad8 => &[&[0, 1], &[1, 2], &[2, 3], &[3, 0]],
        CellKind::Quad9 => &[&[0, 1], &[1, 2], &[2, 3], &[3, 0], &[0, 1, 2, 3]],
        CellKind::Tet10 => &[&[0, 1], &[1, 2], &[2, 0], &[0, 3], &[2, 3], &[1, 3]],
        CellKind::Hex20 => &HEX20,
        CellKind::Hex27 => &HEX27,
        CellKind::Wedge15 => &[
            &[0, 1], &[0, 2], &[0, 3], &[1, 2], &[1, 4], &[2, 5], &[3, 4], &[3, 5], &[4, 5],
        ],
        // First-order kinds: corners only.
        CellKind::Point1 | CellKind::Line2 | CellKind::Tri3 | CellKind::Quad4
        | CellKind::Tet4 | CellKind::Hex8 | CellKind::Wedge6 => &[],
    }
}

/// The kind of a face with `n_corners` corners (3 or 4) of a cell of `kind`; `None` for a kind
/// that is not a solid (it has no faces).
fn face_kind(kind: CellKind, n_corners: usize) -> Option<CellKind> {
    let tri = n_corners == 3;
    match kind {
        CellKind::Tet4 | CellKind::Hex8 | CellKind::Wedge6 => Some(if tri { CellKind::Tri3 } else { CellKind::Quad4 }),
        CellKind::Tet10 | CellKind::Hex20 | CellKind::Wedge15 => {
            Some(if tri { CellKind::Tri6 } else { CellKind::Quad8 })
        }
        CellKind::Hex27 => Some(if tri { CellKind::Tri6 } else { CellKind::Quad9 }),
        CellKind::Point1
        | CellKind::Line2
        | CellKind::Line3
        | CellKind::Tri3
        | CellKind::Tri6
        | CellKind::Quad4
        | CellKind::Quad8
        | CellKind::Quad9 => None,
    }
}

/// Largest number of cells (of the highest dimension) a generator builds, here and in
/// [`super::parametric`]: a smaller element size is reported as an error instead of exhausting
/// memory.
pub const MAX_CELLS: usize = 5_000_000;

/// Names of the boundary groups, in the order of their physical tags 1..=6.
pub const FACE_GROUPS: [&str; 6] = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"];

/// A box mesh of `kind` cells; see the [module docs](self) for the layout and groups.
///
/// # Panics
/// If the arguments are invalid (see [`try_box_mesh`], which returns an error instead).
pub fn box_mesh(kind: CellKind, size: [f64; 3], n: [usize; 3]) -> Mesh {
    match try_box_mesh(kind, size, n) {
        Ok(m) => m,
        Err(e) => panic!("box_mesh: {e}"),
    }
}

/// A box mesh of `kind` cells, or [`Error::InvalidInput`] if `kind` is not a solid, a size is
/// not positive and finite, a division count is zero, or the mesh would exceed 2³² nodes.
pub fn try_box_mesh(kind: CellKind, size: [f64; 3], n: [usize; 3]) -> Result<Mesh> {
    let lat = check_box(kind, size, n)?;
    let lid = |p: [usize; 3]| p[0] + lat[0] * (p[1] + lat[1] * p[2]);
    // 1. Cells as lattice points, in gmsh order: corners, then higher-order nodes.
    let (cells, boundary) = lattice_cells(kind, n, lat, &lid)?;
    // 2. Number the lattice points in use, in lattice order.
    let (mut mesh, number) = number_lattice(&cells, size, lat);
    // 3. Blocks and groups.
    add_blocks_and_groups(&mut mesh, kind, &cells, boundary, &number);
    Ok(mesh)
}

/// Points of the half-step lattice per direction (`2n + 1`), once the arguments of
/// [`try_box_mesh`] are checked: a solid kind, positive sizes, at least one division, at most
/// [`MAX_CELLS`] bricks and fewer than 2³² lattice points.
fn check_box(kind: CellKind, size: [f64; 3], n: [usize; 3]) -> Result<[usize; 3]> {
    // Stays Error::InvalidInput: tests/unit/mesh_io.rs matches on the variant.
    if kind.dim() != 3 {
        return Err(Error::InvalidInput(format!(
            "box mesh: {kind} is not a solid cell kind"
        )));
    }
    if size.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return Err(Error::InvalidInput(format!(
            "box mesh: sizes must be positive, got {size:?}"
        )));
    }
    if n.contains(&0) {
        return Err(Error::InvalidInput(format!(
            "box mesh: divisions must be at least 1, got {n:?}"
        )));
    }
    // Refuse meshes far beyond what a 24 GiB machine can solve before allocating anything
    // (the same cap as the parametric generators).
    let bricks = n[0].checked_mul(n[1]).and_then(|v| v.checked_mul(n[2]));
    match bricks {
        Some(b) if b <= MAX_CELLS => {}
        _ => {
            return Err(Error::InvalidInput(format!(
                "box mesh: {n:?} divisions give more than {MAX_CELLS} bricks; use a coarser mesh"
            )));
        }
    }
    // Lattice of half-steps: 2n+1 points per direction.
    let lat = [2 * n[0] + 1, 2 * n[1] + 1, 2 * n[2] + 1];
    lat[0]
        .checked_mul(lat[1])
        .and_then(|v| v.checked_mul(lat[2]))
        .filter(|&v| v < u32::MAX as usize)
        .ok_or_else(|| Error::param("n", format!("box mesh: {n:?} divisions are too many")))?;
    Ok(lat)
}

/// The boundary faces of a box mesh per face group ([`FACE_GROUPS`]): (face kind, lattice ids).
type BoundaryFaces = [Vec<(CellKind, Vec<usize>)>; 6];

/// Step 1 of [`try_box_mesh`]: every cell of every brick as lattice ids (corners, then
/// higher-order nodes, `kind.n_nodes()` per cell), and the cell faces on the box's boundary.
fn lattice_cells(
    kind: CellKind,
    n: [usize; 3],
    lat: [usize; 3],
    lid: &impl Fn([usize; 3]) -> usize,
) -> Result<(Vec<usize>, BoundaryFaces)> {
    let extra = higher_order_nodes(kind);
    let subcells: Vec<&[usize]> = match kind {
        CellKind::Tet4 | CellKind::Tet10 => BRICK_TETS.iter().map(|c| c.as_slice()).collect(),
        CellKind::Wedge6 | CellKind::Wedge15 => BRICK_WEDGES.iter().map(|c| c.as_slice()).collect(),
        CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => vec![&[0, 1, 2, 3, 4, 5, 6, 7]],
        CellKind::Point1
        | CellKind::Line2
        | CellKind::Line3
        | CellKind::Tri3
        | CellKind::Tri6
        | CellKind::Quad4
        | CellKind::Quad8
        | CellKind::Quad9 => {
            return Err(Error::param(
                "kind",
                format!("box mesh: {kind} is not a solid cell kind"),
            ));
        }
    };
    let mut cells: Vec<usize> = Vec::new(); // lattice ids, kind.n_nodes() per cell
    let mut boundary: BoundaryFaces = Default::default();
    let mut corners: Vec<[usize; 3]> = Vec::with_capacity(8);
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                for sub in &subcells {
                    corners.clear();
                    corners.extend(sub.iter().map(|&c| {
                        let o = BRICK[c];
                        [2 * (i + o[0]), 2 * (j + o[1]), 2 * (k + o[2])]
                    }));
                    push_cell(&mut cells, &corners, extra, lid);
                    // Faces of this cell on the box boundary.
                    for face in faces(kind) {
                        let fc: Vec<[usize; 3]> = face.iter().map(|&c| corners[c]).collect();
                        for (g, group) in boundary.iter_mut().enumerate() {
                            let (axis, at_max) = (g / 2, g % 2 == 1);
                            let plane = if at_max { lat[axis] - 1 } else { 0 };
                            if fc.iter().all(|p| p[axis] == plane)
                                && let Some(fkind) = face_kind(kind, fc.len())
                            {
                                let mut ids = Vec::with_capacity(fkind.n_nodes());
                                push_cell(&mut ids, &fc, higher_order_nodes(fkind), lid);
                                group.push((fkind, ids));
                            }
                        }
                    }
                }
            }
        }
    }
    Ok((cells, boundary))
}

/// Step 2 of [`try_box_mesh`]: a mesh with the nodes of the lattice points `cells` use, in
/// lattice order, and the node index of each lattice point (`u32::MAX` for those unused).
fn number_lattice(cells: &[usize], size: [f64; 3], lat: [usize; 3]) -> (Mesh, Vec<u32>) {
    let mut number = vec![u32::MAX; lat[0] * lat[1] * lat[2]];
    for &c in cells {
        number[c] = 0;
    }
    let mut mesh = Mesh::default();
    let h = [
        size[0] / (lat[0] - 1) as f64,
        size[1] / (lat[1] - 1) as f64,
        size[2] / (lat[2] - 1) as f64,
    ];
    for (id, slot) in number.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = mesh.nodes.len() as u32;
            let p = [id % lat[0], (id / lat[0]) % lat[1], id / (lat[0] * lat[1])];
            // Exact end coordinates, so that boundary nodes lie exactly on the box faces.
            let x = |d: usize| {
                if p[d] == lat[d] - 1 {
                    size[d]
                } else {
                    p[d] as f64 * h[d]
                }
            };
            mesh.nodes.push([x(0), x(1), x(2)]);
            mesh.node_tags.push(mesh.nodes.len() as u64);
        }
    }
    (mesh, number)
}

/// Step 3 of [`try_box_mesh`]: the volume block and group `"volume"`, then the boundary faces
/// in their blocks and the six face groups.
fn add_blocks_and_groups(mesh: &mut Mesh, kind: CellKind, cells: &[usize], boundary: BoundaryFaces, number: &[u32]) {
    let mut vol = CellBlock::new(kind);
    vol.conn = cells.iter().map(|&c| number[c]).collect();
    vol.tags = (1..=(cells.len() / kind.n_nodes()) as u64).collect();
    let n_vol = vol.len();
    mesh.blocks.push(vol);
    mesh.groups.push(Group {
        name: "volume".into(),
        dim: 3,
        tag: 1,
        cells: (0..n_vol as u32).map(|index| CellRef { block: 0, index }).collect(),
    });
    let mut next_tag = n_vol as u64 + 1;
    for (g, faces) in boundary.into_iter().enumerate() {
        let mut refs = Vec::with_capacity(faces.len());
        for (fkind, ids) in faces {
            let b = mesh.block_index_mut(fkind);
            let conn: Vec<u32> = ids.iter().map(|&c| number[c]).collect();
            refs.push(CellRef {
                block: b as u32,
                index: mesh.blocks[b].len() as u32,
            });
            mesh.blocks[b].push(&conn, next_tag);
            next_tag += 1;
        }
        refs.sort_unstable();
        mesh.groups.push(Group {
            name: FACE_GROUPS[g].into(),
            dim: 2,
            tag: g as i32 + 1,
            cells: refs,
        });
    }
}

/// Append the lattice ids of a cell: its corners, then the centroids listed in `extra`.
fn push_cell(out: &mut Vec<usize>, corners: &[[usize; 3]], extra: &[&[usize]], lid: &impl Fn([usize; 3]) -> usize) {
    out.extend(corners.iter().map(|&p| lid(p)));
    for set in extra {
        let mut s = [0usize; 3];
        for &c in *set {
            for d in 0..3 {
                s[d] += corners[c][d];
            }
        }
        // Corners are even lattice points of one brick, so the centroid of 2, 4 or 8 of them
        // (edge, face, brick) is a lattice point.
        out.push(lid([s[0] / set.len(), s[1] / set.len(), s[2] / set.len()]));
    }
}
