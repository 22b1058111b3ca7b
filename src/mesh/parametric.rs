//! Built-in parametric geometry: structured meshes of the users' part families, in pure Rust.
//!
//! Design iteration (issue 6: sweeps over the work table's parameters) needs no mesher: each
//! generator validates its parameters up front ([`Error::param`] naming the parameter)
//! and returns a [`Mesh`] with **named** physical groups.
//!
//! | generator | cells | groups |
//! |---|---|---|
//! | [`sandwich_table`] | shell mid-surfaces, `Quad4` (or `Quad8`/`Quad9`) | `top_plate`, `bottom_plate`, `webs_long`, `webs_trans`, `table`; lines `bottom_edges`, `top_edges` |
//! | [`sandwich_table_solid`] | `Hex8`/`Hex20`/`Hex27` | `top_plate`, `bottom_plate`, `webs_long`, `webs_trans`, `table`; faces `xmin` … `zmax` |
//! | [`helix_beam`] | `Line2`/`Line3` along a coil's centreline | `wire`, `coil`; points `end_bottom`, `end_top` |
//! | [`i_beam_shell`] | `Quad4` flanges and web | `flange_top`, `flange_bottom`, `web`, `beam`; lines `end_a`, `end_b` |
//! | [`i_beam_line`] | `Line2` along `x` | `beam`; points `end_a`, `end_b` |
//! | [`i_beam_solid`] | `Hex8`/`Hex20`/`Hex27` | `flange_top`, `flange_bottom`, `web`, `volume`, `beam`; faces `end_a`, `end_b`, `xmin` … `zmax` |
//! | [`grid_solid`], [`grid_solid_groups`] | hexahedra on any rectilinear grid, keeping selected cells | `volume` (and named groups); faces `xmin` … `zmax` |
//!
//! A group is only present when it has cells (a table without transverse webs has no
//! `webs_trans` group, and [`SandwichParams::thicknesses`] does not list it).
//!
//! # Conformity and numbering
//!
//! Every generator except the helix works on a **rectilinear grid**: the grid lines of each axis
//! contain every coordinate the geometry needs (plate edges, web positions, web faces) and are
//! subdivided so that no spacing exceeds the requested element size. A node is identified by
//! its integer key on the lattice of half-steps of that grid (corner nodes on even keys,
//! midside/face/body nodes of quadratic cells on odd keys, as in
//! [`crate::mesh::generate::box_mesh`]); nodes are merged by key, never by comparing floating
//! point coordinates. Two cells that share a grid line therefore share its nodes (and its
//! midside nodes): plates and webs are conforming along every junction line, and quadratic
//! meshes are conforming along every edge. Nodes are numbered in lattice order (`x` fastest,
//! then `y`, then `z`), tags `1..=N`; element tags are `1..=E`, block by block, the cells of
//! the highest dimension first.
//!
//! # Orientation
//!
//! Every cell is in gmsh's node order ([`crate::fe::shape`]) and positively oriented: hexahedra
//! have a positive Jacobian; a shell cell's normal (right-hand rule on its nodes) is the same
//! for the whole group, as listed at each generator; boundary faces of solids point out of the
//! grid's bounding box.

use std::f64::consts::PI;

use crate::mesh::generate::higher_order_nodes;
use crate::mesh::{CellKind, CellRef, Group, Mesh};
use crate::{Error, Result};

pub use crate::mesh::generate::MAX_CELLS;

/// Relative tolerance under which two required grid coordinates are the same line.
const MERGE_TOL: f64 = 1e-9;

// ---------------------------------------------------------------------------------------------
// Validation helpers

/// A bad value of the generator parameter `name`.
fn invalid(name: &str, msg: String) -> Error {
    Error::param(name, msg)
}

/// `v` must be positive and finite.
fn positive(what: &str, name: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(invalid(
            name,
            format!("{what}: {name} must be positive and finite, got {v}"),
        ))
    }
}

// ---------------------------------------------------------------------------------------------
// Grid lines

/// Grid lines of one axis: every coordinate of `required` (merged when closer than
/// [`MERGE_TOL`] × their extent), each interval between them divided into
/// `max(min_div, ⌈len/h⌉)` equal parts. `what`/`size_name` name the generator and the element
/// size parameter in errors.
fn grid_lines(what: &str, size_name: &str, required: &[f64], h: f64, min_div: usize) -> Result<Vec<f64>> {
    let mut r: Vec<f64> = required.to_vec();
    r.sort_by(f64::total_cmp);
    let extent = r.last().copied().unwrap_or(0.0) - r.first().copied().unwrap_or(0.0);
    let tol = MERGE_TOL * extent;
    let mut pts: Vec<f64> = Vec::with_capacity(r.len());
    for v in r {
        match pts.last() {
            Some(&last) if v - last <= tol => {}
            _ => pts.push(v),
        }
    }
    let mut total = 1.0;
    for w in pts.windows(2) {
        total += ((w[1] - w[0]) / h - 1e-9).ceil().max(min_div as f64);
    }
    if total > MAX_CELLS as f64 && !(extent <= 1e6) {
        // Not the element size's fault: a dimension beyond any machine (over 1000 km, 1e308 m,
        // infinite).
        return Err(Error::InvalidInput(format!(
            "{what}: the geometry spans {extent:.3e} m along one axis: check its dimensions (the element size \
             {size_name} = {h} is not the cause)"
        )));
    }
    if total > MAX_CELLS as f64 {
        return Err(invalid(
            size_name,
            format!("{what}: {size_name} = {h} is too small: {total:.0} grid lines along one axis (limit {MAX_CELLS})"),
        ));
    }
    let mut lines = Vec::with_capacity(total as usize);
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let n = (((b - a) / h - 1e-9).ceil() as usize).max(min_div).max(1);
        for k in 0..n {
            lines.push(a + (b - a) * k as f64 / n as f64);
        }
    }
    if let Some(&last) = pts.last() {
        lines.push(last);
    }
    Ok(lines)
}

/// Index of the grid line nearest to `v` (a coordinate that was required when the lines were
/// built, so it is one of them up to the merge tolerance).
fn line_index(lines: &[f64], v: f64) -> u32 {
    let i = lines.partition_point(|&x| x < v);
    let best = if i == 0 {
        0
    } else if i == lines.len() || (v - lines[i - 1]) < (lines[i] - v) {
        i - 1
    } else {
        i
    };
    best as u32
}

/// A cell count `n` checked against [`MAX_CELLS`]; `cause` names the parameter responsible.
fn check_cell_count(what: &str, cause: &str, n: f64) -> Result<()> {
    if n <= MAX_CELLS as f64 {
        Ok(())
    } else {
        Err(invalid(
            cause,
            format!("{what}: {cause} gives {n:.0} cells (limit {MAX_CELLS})"),
        ))
    }
}

// ---------------------------------------------------------------------------------------------
// Lattice mesh builder

/// Builds a mesh from cells given by their corner grid indices. Keys live on the lattice of
/// half-steps: corner `(i, j, k)` has key `(2i, 2j, 2k)`; higher-order nodes get the centroid
/// keys of the corner sets in gmsh's order ([`higher_order_nodes`]).
struct Builder {
    lines: [Vec<f64>; 3],
    kinds: Vec<CellKind>,
    starts: Vec<usize>,
    keys: Vec<[u32; 3]>,
    groups: Vec<(String, u8, Vec<usize>)>,
}

impl Builder {
    fn new(lines: [Vec<f64>; 3]) -> Self {
        Builder {
            lines,
            kinds: Vec::new(),
            starts: Vec::new(),
            keys: Vec::new(),
            groups: Vec::new(),
        }
    }

    /// Declare a group; returns its id.
    fn group(&mut self, name: &str, dim: u8) -> usize {
        self.groups.push((name.to_string(), dim, Vec::new()));
        self.groups.len() - 1
    }

    /// Add a cell of `kind` with corners at grid indices `corners` (in gmsh corner order, all
    /// corners of one grid brick, face or edge), member of `groups`.
    fn push(&mut self, kind: CellKind, corners: &[[u32; 3]], groups: &[usize]) {
        let id = self.kinds.len();
        self.kinds.push(kind);
        self.starts.push(self.keys.len());
        self.keys.extend(corners.iter().map(|c| c.map(|v| 2 * v)));
        for set in higher_order_nodes(kind) {
            let mut s = [0u32; 3];
            for &c in *set {
                for d in 0..3 {
                    s[d] += 2 * corners[c][d];
                }
            }
            // Corners of one brick differ by at most one index per axis: the centroid of 2, 4
            // or 8 of them is a lattice point.
            self.keys.push(s.map(|v| v / set.len() as u32));
        }
        for &g in groups {
            self.groups[g].2.push(id);
        }
    }

    /// Coordinate of a half-step key along `axis`.
    fn coord(&self, axis: usize, k: u32) -> f64 {
        let l = &self.lines[axis];
        let i = (k / 2) as usize;
        if k.is_multiple_of(2) {
            l[i]
        } else {
            0.5 * (l[i] + l[i + 1])
        }
    }

    fn finish(self) -> Mesh {
        // Nodes: the distinct keys in lattice order (z slowest, x fastest).
        let mut sorted: Vec<[u32; 3]> = self.keys.iter().map(|k| [k[2], k[1], k[0]]).collect();
        sorted.sort_unstable();
        sorted.dedup();
        let mut mesh = Mesh::default();
        mesh.nodes = sorted
            .iter()
            .map(|k| [self.coord(0, k[2]), self.coord(1, k[1]), self.coord(2, k[0])])
            .collect();
        mesh.node_tags = (1..=mesh.nodes.len() as u64).collect();
        let number = |k: &[u32; 3]| sorted.binary_search(&[k[2], k[1], k[0]]).expect("key of a cell") as u32;

        // Blocks, highest dimension first.
        let mut order: Vec<usize> = (0..self.kinds.len()).collect();
        order.sort_by_key(|&c| std::cmp::Reverse(self.kinds[c].dim()));
        let mut refs = vec![CellRef { block: 0, index: 0 }; self.kinds.len()];
        let mut conn: Vec<u32> = Vec::new();
        for c in order {
            let kind = self.kinds[c];
            let start = self.starts[c];
            conn.clear();
            conn.extend(self.keys[start..start + kind.n_nodes()].iter().map(number));
            let b = mesh.block_index_mut(kind);
            refs[c] = CellRef {
                block: b as u32,
                index: mesh.blocks[b].len() as u32,
            };
            mesh.blocks[b].push(&conn, 0);
        }
        let mut tag = 1u64;
        for b in &mut mesh.blocks {
            for t in &mut b.tags {
                *t = tag;
                tag += 1;
            }
        }
        for (name, dim, cells) in self.groups {
            if cells.is_empty() {
                continue;
            }
            let mut cells: Vec<CellRef> = cells.iter().map(|&c| refs[c]).collect();
            cells.sort_unstable();
            let tag = mesh.groups.len() as i32 + 1;
            mesh.groups.push(Group { name, dim, tag, cells });
        }
        mesh
    }
}

/// The line kind matching the edges of a 2D kind (`Line3` for quadratic cells).
fn edge_kind(kind: CellKind) -> CellKind {
    if kind.order() == 2 {
        CellKind::Line3
    } else {
        CellKind::Line2
    }
}

/// A quad with corners on grid lines: `p(a, b)` gives the grid indices at `(u_a, v_b)`,
/// `a, b ∈ {0, 1}`; the normal is `u × v`.
fn quad(p: impl Fn(u32, u32) -> [u32; 3]) -> [[u32; 3]; 4] {
    [p(0, 0), p(1, 0), p(1, 1), p(0, 1)]
}

// ---------------------------------------------------------------------------------------------
// Structured hexahedral meshes on rectilinear grids

/// Corner offsets of a brick in gmsh's hexahedron order (see [`crate::fe::shape`]).
#[rustfmt::skip]
const BRICK: [[u32; 3]; 8] = [
    [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
    [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1],
];

/// Faces of a hexahedron (corner indices, outward normal by the right-hand rule) with the
/// axis they are normal to and whether they are at the brick's high side.
#[rustfmt::skip]
const HEX_FACES: [([usize; 4], usize, bool); 6] = [
    ([0, 4, 7, 3], 0, false), ([1, 2, 6, 5], 0, true),
    ([0, 1, 5, 4], 1, false), ([2, 3, 7, 6], 1, true),
    ([0, 3, 2, 1], 2, false), ([4, 5, 6, 7], 2, true),
];

/// Names of the boundary-face groups of [`grid_solid`], in [`HEX_FACES`] order.
const FACE_NAMES: [&str; 6] = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"];

/// A structured hexahedral mesh on the rectilinear grid `lines` (x, y and z coordinates, each
/// strictly increasing, at least 2), keeping the grid cells whose centre satisfies `keep`.
///
/// `kind` is `Hex8`, `Hex20` or `Hex27`. Cells that share a face share all its nodes (the mesh
/// is conforming, also for the quadratic kinds). Groups: `"volume"` (dimension 3, every kept
/// cell) and the boundary faces on the six planes of the grid's bounding box, `"xmin"`,
/// `"xmax"`, `"ymin"`, `"ymax"`, `"zmin"`, `"zmax"` (dimension 2, `Quad4`/`Quad8`/`Quad9`,
/// normals pointing out; a group without faces is omitted).
///
/// ```
/// use vibrofem::mesh::{parametric, CellKind};
/// // An L-shaped block: the unit cube's grid without the cells above z = 0.5 for x > 0.5.
/// let l = [0.0, 0.5, 1.0];
/// let m = parametric::grid_solid([&l, &l, &l], CellKind::Hex8, |c| c[0] < 0.5 || c[2] < 0.5).unwrap();
/// assert_eq!(m.n_cells_of_dim(3), 6);
/// ```
pub fn grid_solid(lines: [&[f64]; 3], kind: CellKind, keep: impl Fn([f64; 3]) -> bool) -> Result<Mesh> {
    grid_solid_impl(lines, kind, &["volume"], |c| keep(c).then_some(0), None)
}

/// As [`grid_solid`], with the kept cells sorted into named groups: `classify` maps a cell
/// centre to the index of its group in `names`, or `None` to leave the cell out. Groups: each
/// of `names` (dimension 3; omitted when empty), `"volume"` (every kept cell) and the six
/// boundary-face groups of [`grid_solid`].
///
/// Errors ([`Error::param`]): `kind` not a hexahedron, grid lines not finite and
/// strictly increasing, more than [`MAX_CELLS`] grid cells, a group index out of range, or no
/// cell kept.
pub fn grid_solid_groups(
    lines: [&[f64]; 3],
    kind: CellKind,
    names: &[&str],
    classify: impl Fn([f64; 3]) -> Option<usize>,
) -> Result<Mesh> {
    grid_solid_impl(lines, kind, names, classify, Some("volume"))
}

fn grid_solid_impl(
    lines: [&[f64]; 3],
    kind: CellKind,
    names: &[&str],
    classify: impl Fn([f64; 3]) -> Option<usize>,
    all: Option<&str>,
) -> Result<Mesh> {
    const WHAT: &str = "grid solid";
    if !matches!(kind, CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27) {
        return Err(invalid(
            "kind",
            format!("{WHAT}: cell kind must be hex8, hex20 or hex27, got {kind}"),
        ));
    }
    for (axis, l) in lines.iter().enumerate() {
        let name = ["x", "y", "z"][axis];
        if l.len() < 2 || l.iter().any(|v| !v.is_finite()) || l.windows(2).any(|w| w[1] <= w[0]) {
            return Err(invalid(
                "lines",
                format!("{WHAT}: the {name} grid lines must be at least 2 finite, strictly increasing values"),
            ));
        }
    }
    let n = [lines[0].len() - 1, lines[1].len() - 1, lines[2].len() - 1];
    check_cell_count(WHAT, "the grid", n[0] as f64 * n[1] as f64 * n[2] as f64)?;
    let face_kind = match kind {
        CellKind::Hex8 => CellKind::Quad4,
        CellKind::Hex20 => CellKind::Quad8,
        CellKind::Hex27 => CellKind::Quad9,
        other => {
            return Err(invalid(
                "kind",
                format!("{WHAT}: the solid table is meshed with hexahedra (hex8, hex20, hex27), not {other}"),
            ));
        }
    };
    let mut b = Builder::new([lines[0].to_vec(), lines[1].to_vec(), lines[2].to_vec()]);
    let named: Vec<usize> = names.iter().map(|nm| b.group(nm, 3)).collect();
    let all_group = all.map(|nm| b.group(nm, 3));
    let faces: Vec<usize> = FACE_NAMES.iter().map(|nm| b.group(nm, 2)).collect();
    let mut kept = 0usize;
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let c = [
                    0.5 * (lines[0][i] + lines[0][i + 1]),
                    0.5 * (lines[1][j] + lines[1][j + 1]),
                    0.5 * (lines[2][k] + lines[2][k + 1]),
                ];
                let Some(g) = classify(c) else { continue };
                if g >= named.len() {
                    return Err(invalid(
                        "names",
                        format!("{WHAT}: group index {g} out of range ({} group names)", named.len()),
                    ));
                }
                kept += 1;
                let base = [i as u32, j as u32, k as u32];
                let corners: Vec<[u32; 3]> = BRICK
                    .iter()
                    .map(|o| [base[0] + o[0], base[1] + o[1], base[2] + o[2]])
                    .collect();
                let mut groups = vec![named[g]];
                groups.extend(all_group);
                b.push(kind, &corners, &groups);
                let ijk = [i, j, k];
                for (f, &(fc, axis, high)) in HEX_FACES.iter().enumerate() {
                    let on_boundary = if high { ijk[axis] + 1 == n[axis] } else { ijk[axis] == 0 };
                    if on_boundary {
                        let fcorners: Vec<[u32; 3]> = fc.iter().map(|&c| corners[c]).collect();
                        b.push(face_kind, &fcorners, &[faces[f]]);
                    }
                }
            }
        }
    }
    if kept == 0 {
        return Err(invalid("keep", format!("{WHAT}: no grid cell is kept")));
    }
    Ok(b.finish())
}

/// Copy group `from` under the name `to` (same cells and dimension), if `from` exists.
fn alias_group(mesh: &mut Mesh, from: &str, to: &str) {
    if let Some(g) = mesh.groups.iter().find(|g| g.name == from) {
        let mut g = g.clone();
        g.name = to.to_string();
        g.tag = mesh.groups.len() as i32 + 1;
        mesh.groups.push(g);
    }
}

// ---------------------------------------------------------------------------------------------
// Sandwich work table

/// Parameters of the double-T sandwich work table (scene S7): a top plate over a bottom plate,
/// spaced by longitudinal webs (along `x`) and optional transverse webs (along `y`).
///
/// # Coordinates and conventions
///
/// - The table's axis is `x`; coordinates are centred: `x ∈ [−length/2, length/2]`, the top
///   plate spans `y ∈ [−top_width/2, top_width/2]`, the bottom plate
///   `y ∈ [−bottom_width/2, bottom_width/2]` (centred under it).
/// - `z` is vertical. The **bottom plate's mid-surface is at `z = 0`**, the top plate's
///   mid-surface at `z = H` = [`mid_surface_spacing`](Self::mid_surface_spacing)
///   `= web_height + (top_thickness + bottom_thickness)/2`.
/// - **`web_height` is the clear height** of the webs, between the inner faces of the two
///   plates (S7's "webs 100 mm high": channels No. 10 welded between the plates). The shell
///   model's web surfaces run from mid-surface to mid-surface (`z ∈ [0, H]`) and share their
///   nodes with both plates along the junction lines; the solid model's webs fill exactly the
///   clear gap.
/// - Longitudinal webs: mid-planes at `y = long_webs[i]`, along the whole length. Transverse
///   webs: mid-planes at `x = trans_webs[j]`, across the **narrower of the two plates**
///   (`|y| ≤ min(top_width, bottom_width)/2`, the width both plates cover), crossing the
///   longitudinal webs.
/// - Every web must lie, with its whole thickness, within both plates (`|y_i| + t/2 ≤
///   min(top_width, bottom_width)/2`, `|x_j| + t/2 ≤ length/2`), and webs of one direction
///   must not overlap (centre distance ≥ thickness).
///
/// The mesh controls are `elem_size` (the largest grid spacing of the shell mesh) and
/// `shell_kind`; the solid generator takes its own size and kind.
///
/// In a design file this is the `[table]` table: the same keys, with `element_size` for
/// `elem_size` (the shell kind is not a file key).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SandwichParams {
    /// Length along `x` of both plates and of the longitudinal webs (m).
    pub length: f64,
    /// Width (along `y`) of the top plate (m).
    pub top_width: f64,
    /// Thickness of the top plate (m).
    pub top_thickness: f64,
    /// Width (along `y`) of the bottom plate, centred under the top plate (m).
    pub bottom_width: f64,
    /// Thickness of the bottom plate (m).
    pub bottom_thickness: f64,
    /// Clear height of the webs between the plates' inner faces (m).
    pub web_height: f64,
    /// `y` positions of the longitudinal webs' mid-planes (m).
    pub long_webs: Vec<f64>,
    /// Thickness of the longitudinal webs (m).
    pub long_web_thickness: f64,
    /// `x` positions of the transverse webs' mid-planes (m); may be empty.
    pub trans_webs: Vec<f64>,
    /// Thickness of the transverse webs (m).
    pub trans_web_thickness: f64,
    /// Target element size of the shell mesh: no grid spacing exceeds it (m).
    #[serde(rename = "element_size")]
    pub elem_size: f64,
    /// Shell cell kind: `Quad4` (the MITC4 shell), or `Quad8`/`Quad9` for quadratic meshes.
    #[serde(skip)]
    pub shell_kind: CellKind,
}

impl Default for SandwichParams {
    /// The paper's table ([`SandwichParams::paper`]).
    fn default() -> Self {
        SandwichParams::paper()
    }
}

/// Elements along one side of a sandwich table at most ([`SandwichParams::oversized_side`]):
/// 2 000 at 2 mm is a 4 m table. More is a unit slip (millimetres read as metres) or an element
/// size far too small, refused with the side's name before any mesh is built.
pub const MAX_TABLE_DIVISIONS: f64 = 2000.0;

impl SandwichParams {
    /// The first side (its parameter's name and length) with more than
    /// [`MAX_TABLE_DIVISIONS`] elements of size `h` (a side that is not a number is left to
    /// [`SandwichParams::validate`], which names it).
    pub fn oversized_side(&self, h: f64) -> Option<(&'static str, f64)> {
        [
            ("length", self.length),
            ("top_width", self.top_width),
            ("bottom_width", self.bottom_width),
            ("web_height", self.web_height),
        ]
        .into_iter()
        .find(|(_, v)| v / h > MAX_TABLE_DIVISIONS)
    }

    /// The S7 reconstruction (docs/spec/scenes.md): 1200 × 600 × 25 mm top plate, 1200 × 400 × 8 mm
    /// bottom plate, three longitudinal webs 100 mm high (clear) and 4.5 mm thick at
    /// `y = −150, 0, 150` mm, no transverse webs; 25 mm `Quad4` shells.
    pub fn paper() -> Self {
        SandwichParams {
            length: 1.2,
            top_width: 0.6,
            top_thickness: 0.025,
            bottom_width: 0.4,
            bottom_thickness: 0.008,
            web_height: 0.1,
            long_webs: vec![-0.15, 0.0, 0.15],
            long_web_thickness: 0.0045,
            trans_webs: Vec::new(),
            trans_web_thickness: 0.0045,
            elem_size: 0.025,
            shell_kind: CellKind::Quad4,
        }
    }

    /// `n` positions evenly spaced from `first` to `last` inclusive (one position: their
    /// mean), for web layouts in sweeps: `evenly_spaced(3, -0.15, 0.15)` gives the paper's webs.
    pub fn evenly_spaced(n: usize, first: f64, last: f64) -> Vec<f64> {
        match n {
            0 => Vec::new(),
            1 => vec![0.5 * (first + last)],
            _ => (0..n)
                .map(|i| first + (last - first) * i as f64 / (n - 1) as f64)
                .collect(),
        }
    }

    /// Distance between the plates' mid-surfaces, `web_height + (top_thickness +
    /// bottom_thickness)/2`: the height of the shell model's webs and the `z` of the top plate.
    pub fn mid_surface_spacing(&self) -> f64 {
        self.web_height + 0.5 * (self.top_thickness + self.bottom_thickness)
    }

    /// Width of the transverse webs: `min(top_width, bottom_width)`.
    pub fn trans_web_width(&self) -> f64 {
        self.top_width.min(self.bottom_width)
    }

    /// Shell thickness of each 2D group of [`sandwich_table`], for assigning a shell section
    /// per group. Lists only the groups the mesh has (no web group without webs).
    pub fn thicknesses(&self) -> Vec<(String, f64)> {
        let mut v = vec![
            ("top_plate".to_string(), self.top_thickness),
            ("bottom_plate".to_string(), self.bottom_thickness),
        ];
        if !self.long_webs.is_empty() {
            v.push(("webs_long".to_string(), self.long_web_thickness));
        }
        if !self.trans_webs.is_empty() {
            v.push(("webs_trans".to_string(), self.trans_web_thickness));
        }
        v
    }

    /// Steel volume of the real table (m³), the volume of [`sandwich_table_solid`]: both
    /// plates, the webs over their clear height, each crossing of a longitudinal and a
    /// transverse web counted once.
    pub fn volume(&self) -> f64 {
        let (nl, nt) = (self.long_webs.len() as f64, self.trans_webs.len() as f64);
        let (tl, tt) = (self.long_web_thickness, self.trans_web_thickness);
        let hw = self.web_height;
        self.length * (self.top_width * self.top_thickness + self.bottom_width * self.bottom_thickness)
            + nl * self.length * hw * tl
            + nt * self.trans_web_width() * hw * tt
            - nl * nt * tl * tt * hw
    }

    /// Mass of the real table (kg) for `density` (kg/m³): `density ×` [`volume`](Self::volume).
    pub fn mass(&self, density: f64) -> f64 {
        density * self.volume()
    }

    /// Volume the shell model of [`sandwich_table`] carries (m³): `Σ area × thickness` over the
    /// groups. It exceeds [`volume`](Self::volume) because the web surfaces run between the
    /// mid-surfaces: each web's junction strips (half of each plate's thickness) are counted in
    /// both the web and the plate, and crossing webs count their crossing twice:
    /// `shell_volume − volume = (H − web_height)(n_l L t_l + n_t W t_t) + n_l n_t t_l t_t
    /// web_height`, with `H` the mid-surface spacing and `W` the transverse web width
    /// (+1.1 % on the S7 reconstruction).
    pub fn shell_volume(&self) -> f64 {
        let h = self.mid_surface_spacing();
        self.length * (self.top_width * self.top_thickness + self.bottom_width * self.bottom_thickness)
            + self.long_webs.len() as f64 * self.length * h * self.long_web_thickness
            + self.trans_webs.len() as f64 * self.trans_web_width() * h * self.trans_web_thickness
    }

    /// Mass the shell model carries (kg): `density ×` [`shell_volume`](Self::shell_volume).
    pub fn shell_mass(&self, density: f64) -> f64 {
        density * self.shell_volume()
    }

    /// Check every parameter; the error names the offending one. Called by
    /// [`sandwich_table`]; [`sandwich_table_solid`] checks the same geometry but not the shell
    /// mesh controls (`elem_size`, `shell_kind`).
    pub fn validate(&self) -> Result<()> {
        const W: &str = "sandwich table";
        self.validate_geometry()?;
        positive(W, "elem_size", self.elem_size)?;
        if !matches!(self.shell_kind, CellKind::Quad4 | CellKind::Quad8 | CellKind::Quad9) {
            return Err(invalid(
                "shell_kind",
                format!("{W}: shell_kind must be quad4, quad8 or quad9, got {}", self.shell_kind),
            ));
        }
        Ok(())
    }

    /// Check the geometric parameters (everything but the shell mesh controls).
    fn validate_geometry(&self) -> Result<()> {
        const W: &str = "sandwich table";
        positive(W, "length", self.length)?;
        positive(W, "top_width", self.top_width)?;
        positive(W, "top_thickness", self.top_thickness)?;
        positive(W, "bottom_width", self.bottom_width)?;
        positive(W, "bottom_thickness", self.bottom_thickness)?;
        positive(W, "web_height", self.web_height)?;
        if self.long_webs.is_empty() && self.trans_webs.is_empty() {
            return Err(Error::InvalidInput(format!(
                "{W}: long_webs and trans_webs are both empty: the plates need at least one web between them"
            )));
        }
        let half_w = 0.5 * self.trans_web_width();
        let tol = MERGE_TOL * self.length.max(self.top_width).max(self.bottom_width);
        let webs = [
            (
                "long_webs",
                "long_web_thickness",
                &self.long_webs,
                self.long_web_thickness,
                half_w,
                "y",
                "min(top_width, bottom_width)/2",
            ),
            (
                "trans_webs",
                "trans_web_thickness",
                &self.trans_webs,
                self.trans_web_thickness,
                0.5 * self.length,
                "x",
                "length/2",
            ),
        ];
        for (name, tname, pos, t, half, axis, limit) in webs {
            if pos.is_empty() {
                continue;
            }
            positive(W, tname, t)?;
            for &p in pos.iter() {
                if !p.is_finite() {
                    return Err(invalid(name, format!("{W}: {name}: position {p} is not finite")));
                }
                if p.abs() + 0.5 * t > half + tol {
                    return Err(invalid(
                        name,
                        format!(
                            "{W}: {name}: the web at {axis} = {p} (thickness {tname} = {t}) lies outside the plates: \
                         |{axis}| + {tname}/2 = {} exceeds {limit} = {half}",
                            p.abs() + 0.5 * t
                        ),
                    ));
                }
            }
            let mut s: Vec<f64> = pos.to_vec();
            s.sort_by(f64::total_cmp);
            for w in s.windows(2) {
                if w[1] - w[0] < t - tol {
                    return Err(invalid(
                        name,
                        format!(
                            "{W}: {name}: the webs at {axis} = {} and {axis} = {} overlap: their distance {} is less \
                         than {tname} = {t}",
                            w[0],
                            w[1],
                            w[1] - w[0]
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// The sandwich work table as a shell mid-surface model; see [`SandwichParams`] for the
/// geometry and conventions.
///
/// The mesh is a rectilinear grid in `x` and `y` containing the plate edges and every web
/// position, each interval divided evenly with spacing ≤ `elem_size`; the webs are divided
/// into `max(2, ⌈H/elem_size⌉)` cells over their height `H` (mid-surface to mid-surface). All
/// junctions are conforming: the bottom plate, the top plate and every web share their nodes
/// along each junction line (and at web crossings).
///
/// Cells: `p.shell_kind` (`Quad4`, `Quad8` or `Quad9`); edges `Line2` (`Line3` for quadratic).
/// Groups (dimension 2 unless noted), with the normal of their cells:
/// - `"top_plate"` (`z = H`, normal `+z`), `"bottom_plate"` (`z = 0`, normal `+z`),
///   `"webs_long"` (normal `+y`), `"webs_trans"` (normal `+x`; only with transverse webs),
///   `"table"`: every 2D cell;
/// - `"bottom_edges"`, `"top_edges"` (dimension 1): the perimeters of the bottom and top
///   plates, counter-clockwise seen from `+z` (supports, isolator attachment lines).
///
/// ```
/// use vibrofem::mesh::parametric::{sandwich_table, SandwichParams};
/// let m = sandwich_table(&SandwichParams::paper()).unwrap();
/// assert!(m.group("webs_long").is_ok() && m.group("webs_trans").is_err());
/// ```
pub fn sandwich_table(p: &SandwichParams) -> Result<Mesh> {
    const W: &str = "sandwich table";
    p.validate()?;
    let h = p.elem_size;
    let (hx, ht, hb, hw) = (
        0.5 * p.length,
        0.5 * p.top_width,
        0.5 * p.bottom_width,
        0.5 * p.trans_web_width(),
    );
    let hz = p.mid_surface_spacing();
    let mut xr = vec![-hx, hx];
    xr.extend(&p.trans_webs);
    let mut yr = vec![-ht, ht, -hb, hb];
    yr.extend(&p.long_webs);
    let xl = grid_lines(W, "elem_size", &xr, h, 1)?;
    let yl = grid_lines(W, "elem_size", &yr, h, 1)?;
    let zl = grid_lines(W, "elem_size", &[0.0, hz], h, 2)?;
    let (nx, ny, nz) = (xl.len() - 1, yl.len() - 1, zl.len() - 1);
    let n_cells = (nx * ny) as f64 * 2.0 + (p.long_webs.len() * nx * nz) as f64 + (p.trans_webs.len() * ny * nz) as f64;
    check_cell_count(W, &format!("elem_size = {h}"), n_cells)?;

    let iy = |v: f64| line_index(&yl, v);
    let ix = |v: f64| line_index(&xl, v);
    let (top_y, bot_y, web_y) = ((iy(-ht), iy(ht)), (iy(-hb), iy(hb)), (iy(-hw), iy(hw)));
    let (x0, x1) = (0u32, nx as u32);
    let ztop = nz as u32;
    let kind = p.shell_kind;
    let ekind = edge_kind(kind);

    let mut b = Builder::new([xl.clone(), yl.clone(), zl]);
    let g_top = b.group("top_plate", 2);
    let g_bot = b.group("bottom_plate", 2);
    let g_long = b.group("webs_long", 2);
    let g_trans = b.group("webs_trans", 2);
    let g_all = b.group("table", 2);
    let g_bot_edges = b.group("bottom_edges", 1);
    let g_top_edges = b.group("top_edges", 1);

    // Plates: u = x, v = y, normal +z.
    for (g, (ya, yb), z) in [(g_bot, bot_y, 0u32), (g_top, top_y, ztop)] {
        for j in ya..yb {
            for i in x0..x1 {
                b.push(kind, &quad(|a, c| [i + a, j + c, z]), &[g, g_all]);
            }
        }
    }
    // Longitudinal webs: u = z, v = x, normal +y.
    for &y in &p.long_webs {
        let j = iy(y);
        for k in 0..ztop {
            for i in x0..x1 {
                b.push(kind, &quad(|a, c| [i + c, j, k + a]), &[g_long, g_all]);
            }
        }
    }
    // Transverse webs: u = y, v = z, normal +x.
    for &x in &p.trans_webs {
        let i = ix(x);
        for k in 0..ztop {
            for j in web_y.0..web_y.1 {
                b.push(kind, &quad(|a, c| [i, j + a, k + c]), &[g_trans, g_all]);
            }
        }
    }
    // Plate perimeters, counter-clockwise seen from +z.
    for (g, (ya, yb), z) in [(g_bot_edges, bot_y, 0u32), (g_top_edges, top_y, ztop)] {
        for i in x0..x1 {
            b.push(ekind, &[[i, ya, z], [i + 1, ya, z]], &[g]);
        }
        for j in ya..yb {
            b.push(ekind, &[[x1, j, z], [x1, j + 1, z]], &[g]);
        }
        for i in (x0..x1).rev() {
            b.push(ekind, &[[i + 1, yb, z], [i, yb, z]], &[g]);
        }
        for j in (ya..yb).rev() {
            b.push(ekind, &[[x0, j + 1, z], [x0, j, z]], &[g]);
        }
    }
    Ok(b.finish())
}

/// The sandwich work table as a solid: plates and webs as real volumes of hexahedra (`kind`
/// = `Hex8`, `Hex20` or `Hex27`) on a rectilinear grid with spacing ≤ `h` that contains every
/// plate and web face (each thickness gets at least one cell).
///
/// Geometry (same coordinates as [`sandwich_table`], whose mid-surfaces are the solid plates'
/// mid-planes): bottom plate `z ∈ [−t_b/2, t_b/2]`, webs `z ∈ [t_b/2, t_b/2 + web_height]`,
/// top plate `z ∈ [t_b/2 + web_height, t_b/2 + web_height + t_t]`; web `i` fills
/// `|y − y_i| ≤ t_l/2`, transverse web `j` fills `|x − x_j| ≤ t_t/2, |y| ≤ W/2`. The volume
/// is [`SandwichParams::volume`] exactly. `p.elem_size` and `p.shell_kind` are not used.
///
/// Groups: `"top_plate"`, `"bottom_plate"`, `"webs_long"` (including the crossings with
/// transverse webs), `"webs_trans"` (only with transverse webs), `"table"` (every cell), all
/// dimension 3; boundary faces on the bounding box planes `"xmin"`, `"xmax"` (the ends),
/// `"ymin"`, `"ymax"` (the top plate's long edges), `"zmin"` (the bottom plate's underside),
/// `"zmax"` (the top face).
pub fn sandwich_table_solid(p: &SandwichParams, h: f64, kind: CellKind) -> Result<Mesh> {
    const W: &str = "sandwich table solid";
    p.validate_geometry()?;
    positive(W, "h", h)?;
    let (hx, ht, hb, hw) = (
        0.5 * p.length,
        0.5 * p.top_width,
        0.5 * p.bottom_width,
        0.5 * p.trans_web_width(),
    );
    let (tl, tt) = (0.5 * p.long_web_thickness, 0.5 * p.trans_web_thickness);
    let z1 = 0.5 * p.bottom_thickness;
    let z2 = z1 + p.web_height;
    let z3 = z2 + p.top_thickness;
    let mut xr = vec![-hx, hx];
    for &x in &p.trans_webs {
        xr.extend([x - tt, x + tt]);
    }
    let mut yr = vec![-ht, ht, -hb, hb];
    for &y in &p.long_webs {
        yr.extend([y - tl, y + tl]);
    }
    let xl = grid_lines(W, "h", &xr, h, 1)?;
    let yl = grid_lines(W, "h", &yr, h, 1)?;
    let zl = grid_lines(W, "h", &[-z1, z1, z2, z3], h, 1)?;
    check_cell_count(
        W,
        &format!("h = {h}"),
        (xl.len() - 1) as f64 * (yl.len() - 1) as f64 * (zl.len() - 1) as f64,
    )?;
    let names = ["top_plate", "bottom_plate", "webs_long", "webs_trans"];
    let classify = |c: [f64; 3]| {
        let [x, y, z] = c;
        if z < z1 {
            (y.abs() < hb).then_some(1)
        } else if z > z2 {
            (y.abs() < ht).then_some(0)
        } else if p.long_webs.iter().any(|&w| (y - w).abs() < tl) {
            Some(2)
        } else if y.abs() < hw && p.trans_webs.iter().any(|&w| (x - w).abs() < tt) {
            Some(3)
        } else {
            None
        }
    };
    let mut mesh = grid_solid_groups([&xl, &yl, &zl], kind, &names, classify)?;
    if let Some(g) = mesh.groups.iter_mut().find(|g| g.name == "volume") {
        g.name = "table".into();
    }
    Ok(mesh)
}

// ---------------------------------------------------------------------------------------------
// Helical coil spring

/// Parameters of a helical coil spring modelled as a beam along its centreline (scene S5).
///
/// The helix is right-handed about `+z`, starts at `(D/2, 0, 0)` and rises by `pitch` per
/// turn: `x = (D/2) cos θ`, `y = (D/2) sin θ`, `z = pitch θ/(2π)`, `θ ∈ [0, 2π turns]`.
/// Only active turns are modelled (no closed or ground end coils).
#[derive(Clone, Debug, PartialEq)]
pub struct HelixParams {
    /// Mean coil diameter `D` (m).
    pub mean_diameter: f64,
    /// Axial rise per turn (m); must exceed the wire diameter so that coils do not touch.
    pub pitch: f64,
    /// Number of turns (may be fractional).
    pub turns: f64,
    /// Elements per turn (at least 3); the element count is `⌈turns × elems_per_turn⌉`.
    pub elems_per_turn: usize,
    /// Wire diameter `d` (m): the beam section's, kept here for convenience (solid circle).
    pub wire_diameter: f64,
    /// `Line2` or `Line3` (the midside node on the helix).
    pub kind: CellKind,
}

impl Default for HelixParams {
    fn default() -> Self {
        HelixParams::paper()
    }
}

impl HelixParams {
    /// The S5 isolator spring: D = 32 mm, pitch 10 mm, 6 active turns, wire d = 6 mm; 24
    /// `Line2` elements per turn.
    pub fn paper() -> Self {
        HelixParams {
            mean_diameter: 0.032,
            pitch: 0.010,
            turns: 6.0,
            elems_per_turn: 24,
            wire_diameter: 0.006,
            kind: CellKind::Line2,
        }
    }

    /// Check every parameter; the error names the offending one. Called by the generators.
    pub fn validate(&self) -> Result<()> {
        const W: &str = "helix";
        positive(W, "mean_diameter", self.mean_diameter)?;
        positive(W, "pitch", self.pitch)?;
        positive(W, "turns", self.turns)?;
        positive(W, "wire_diameter", self.wire_diameter)?;
        if self.elems_per_turn < 3 {
            return Err(invalid(
                "elems_per_turn",
                format!("{W}: elems_per_turn must be at least 3, got {}", self.elems_per_turn),
            ));
        }
        if !matches!(self.kind, CellKind::Line2 | CellKind::Line3) {
            return Err(invalid(
                "kind",
                format!("{W}: kind must be line2 or line3, got {}", self.kind),
            ));
        }
        if self.wire_diameter >= self.mean_diameter {
            return Err(invalid(
                "wire_diameter",
                format!(
                    "{W}: wire_diameter = {} must be less than mean_diameter = {}",
                    self.wire_diameter, self.mean_diameter
                ),
            ));
        }
        if self.pitch <= self.wire_diameter {
            return Err(invalid(
                "pitch",
                format!(
                    "{W}: pitch = {} must exceed wire_diameter = {}: the coils would touch",
                    self.pitch, self.wire_diameter
                ),
            ));
        }
        let n = self.turns * self.elems_per_turn as f64;
        check_cell_count(W, "turns × elems_per_turn", n)
    }

    /// Number of elements, `⌈turns × elems_per_turn⌉`.
    pub fn n_elements(&self) -> usize {
        ((self.turns * self.elems_per_turn as f64 - 1e-9).ceil() as usize).max(1)
    }

    /// Exact length of the helix, `turns × √((πD)² + pitch²)` (m).
    pub fn wire_length(&self) -> f64 {
        self.turns * ((PI * self.mean_diameter).powi(2) + self.pitch * self.pitch).sqrt()
    }

    /// Free height of the centreline, `turns × pitch` (m).
    pub fn height(&self) -> f64 {
        self.turns * self.pitch
    }

    /// Mass of the wire (kg): `density × π d²/4 ×` [`wire_length`](Self::wire_length).
    pub fn mass(&self, density: f64) -> f64 {
        density * 0.25 * PI * self.wire_diameter.powi(2) * self.wire_length()
    }

    /// Point of the centreline at angle `theta` (rad).
    pub fn point(&self, theta: f64) -> [f64; 3] {
        let r = 0.5 * self.mean_diameter;
        [r * theta.cos(), r * theta.sin(), self.pitch * theta / (2.0 * PI)]
    }

    /// Angle of the `k`-th of `n` equal steps along the helix.
    fn angle(&self, k: usize, n: usize) -> f64 {
        2.0 * PI * self.turns * k as f64 / n as f64
    }
}

/// The centreline of a helical coil spring as beam elements; see [`HelixParams`].
///
/// Nodes are on the helix (for `Line3` also the midside nodes, at the mid-angle). Groups:
/// `"wire"` and `"coil"` (dimension 1, every line cell; `"coil"` names the whole spring in
/// scenes), `"end_bottom"` and `"end_top"` (dimension 0, a `Point1` cell at the first node,
/// `z = 0`, and at the last, `z` = [`HelixParams::height`]).
///
/// A beam on a helix needs an orientation vector per element (a single global vector is
/// parallel to some element's axis or rotates with the coil): use [`helix_orientations`].
pub fn helix_beam(p: &HelixParams) -> Result<Mesh> {
    p.validate()?;
    let ne = p.n_elements();
    let q = if p.kind == CellKind::Line3 { 2 } else { 1 };
    let nn = q * ne + 1;
    let mut mesh = Mesh {
        nodes: (0..nn).map(|k| p.point(p.angle(k, nn - 1))).collect(),
        node_tags: (1..=nn as u64).collect(),
        ..Mesh::default()
    };
    let bl = mesh.block_index_mut(p.kind);
    for e in 0..ne {
        let a = (q * e) as u32;
        let conn: Vec<u32> = if q == 2 { vec![a, a + 2, a + 1] } else { vec![a, a + 1] };
        mesh.blocks[bl].push(&conn, e as u64 + 1);
    }
    let bp = mesh.block_index_mut(CellKind::Point1);
    mesh.blocks[bp].push(&[0], ne as u64 + 1);
    mesh.blocks[bp].push(&[(nn - 1) as u32], ne as u64 + 2);
    let lines: Vec<CellRef> = (0..ne as u32)
        .map(|index| CellRef {
            block: bl as u32,
            index,
        })
        .collect();
    let point = |index| {
        vec![CellRef {
            block: bp as u32,
            index,
        }]
    };
    for (tag, (name, dim, cells)) in [
        ("wire", 1, lines.clone()),
        ("coil", 1, lines),
        ("end_bottom", 0, point(0)),
        ("end_top", 0, point(1)),
    ]
    .into_iter()
    .enumerate()
    {
        mesh.groups.push(Group {
            name: name.into(),
            dim,
            tag: tag as i32 + 1,
            cells,
        });
    }
    Ok(mesh)
}

/// Orientation vector of each element of [`helix_beam`] (in cell order): the outward radial
/// direction `(cos θ_m, sin θ_m, 0)` at the element's mid-angle `θ_m`. It is exactly
/// perpendicular to the element's chord (and to the helix tangent at `θ_m`), so the beam's
/// local `y` points away from the coil axis and local `z` is along the wire's binormal-like
/// direction; for a circular wire any perpendicular vector gives the same stiffness, but one
/// global vector cannot serve every element of a helix.
pub fn helix_orientations(p: &HelixParams) -> Result<Vec<[f64; 3]>> {
    p.validate()?;
    let ne = p.n_elements();
    Ok((0..ne)
        .map(|e| {
            let t = p.angle(2 * e + 1, 2 * ne);
            [t.cos(), t.sin(), 0.0]
        })
        .collect())
}

// ---------------------------------------------------------------------------------------------
// I-beam (scene S6)

/// Validate I-section dimensions and a length.
fn check_i_section(what: &str, h: f64, b: f64, s: f64, t: f64, length: f64) -> Result<()> {
    positive(what, "h", h)?;
    positive(what, "b", b)?;
    positive(what, "s", s)?;
    positive(what, "t", t)?;
    positive(what, "length", length)?;
    if 2.0 * t >= h {
        return Err(invalid(
            "t",
            format!("{what}: flange thickness t = {t} leaves no web: 2t must be less than the depth h = {h}"),
        ));
    }
    if s >= b {
        return Err(invalid(
            "s",
            format!("{what}: web thickness s = {s} must be less than the flange width b = {b}"),
        ));
    }
    Ok(())
}

/// Shell thickness of each 2D group of [`i_beam_shell`]: flanges `t`, web `s`.
pub fn i_beam_thicknesses(s: f64, t: f64) -> Vec<(String, f64)> {
    vec![
        ("flange_top".to_string(), t),
        ("flange_bottom".to_string(), t),
        ("web".to_string(), s),
    ]
}

/// An I-beam (double-T; S6: GOST 8239 No. 10 is `h` 0.1, `b` 0.055, `s` 0.0045, `t` 0.0072)
/// as shell mid-surfaces along `x ∈ [0, length]`: depth `h` along `z`, flange width `b` along
/// `y`, web thickness `s`, flange thickness `t`, fillets ignored.
///
/// The flanges are at `z = ±(h − t)/2` (`|y| ≤ b/2`), the web at `y = 0` spans
/// `z ∈ [−(h − t)/2, (h − t)/2]` (height `h − t` between the flanges' mid-surfaces: the
/// junction strips are counted twice in the mass, `2 · s · t/2` per unit length). The web
/// shares its nodes with both flanges along the junction lines. Grid spacing ≤ `elem_size`;
/// the web has at least 2 cells over its height, each half-flange at least 1.
///
/// Cells `Quad4`. Groups: `"flange_top"`, `"flange_bottom"` (normal `+z`), `"web"` (normal
/// `+y`), `"beam"` (every 2D cell); `"end_a"` (`x = 0`) and `"end_b"` (`x = length`),
/// dimension 1: the `Line2` edges of the end sections. Thicknesses: [`i_beam_thicknesses`].
pub fn i_beam_shell(h: f64, b: f64, s: f64, t: f64, length: f64, elem_size: f64) -> Result<Mesh> {
    const W: &str = "I-beam shell";
    check_i_section(W, h, b, s, t, length)?;
    positive(W, "elem_size", elem_size)?;
    let zf = 0.5 * (h - t);
    let xl = grid_lines(W, "elem_size", &[0.0, length], elem_size, 1)?;
    let yl = grid_lines(W, "elem_size", &[-0.5 * b, 0.0, 0.5 * b], elem_size, 1)?;
    let zl = grid_lines(W, "elem_size", &[-zf, zf], elem_size, 2)?;
    let (nx, ny, nz) = ((xl.len() - 1) as u32, (yl.len() - 1) as u32, (zl.len() - 1) as u32);
    check_cell_count(
        W,
        &format!("elem_size = {elem_size}"),
        nx as f64 * (2.0 * ny as f64 + nz as f64),
    )?;
    let jw = line_index(&yl, 0.0);
    let mut bd = Builder::new([xl, yl, zl]);
    let g_top = bd.group("flange_top", 2);
    let g_bot = bd.group("flange_bottom", 2);
    let g_web = bd.group("web", 2);
    let g_all = bd.group("beam", 2);
    let g_a = bd.group("end_a", 1);
    let g_b = bd.group("end_b", 1);
    for (g, k) in [(g_bot, 0), (g_top, nz)] {
        for j in 0..ny {
            for i in 0..nx {
                bd.push(CellKind::Quad4, &quad(|a, c| [i + a, j + c, k]), &[g, g_all]);
            }
        }
    }
    for k in 0..nz {
        for i in 0..nx {
            bd.push(CellKind::Quad4, &quad(|a, c| [i + c, jw, k + a]), &[g_web, g_all]);
        }
    }
    for (g, i) in [(g_a, 0), (g_b, nx)] {
        for k in [0, nz] {
            for j in 0..ny {
                bd.push(CellKind::Line2, &[[i, j, k], [i, j + 1, k]], &[g]);
            }
        }
        for k in 0..nz {
            bd.push(CellKind::Line2, &[[i, jw, k], [i, jw, k + 1]], &[g]);
        }
    }
    Ok(bd.finish())
}

/// A straight beam of `n_elem` equal `Line2` elements along `x ∈ [0, length]` (`y = z = 0`),
/// for the beam model of S6. Groups: `"beam"` (dimension 1), `"end_a"` (`x = 0`) and
/// `"end_b"` (`x = length`), dimension 0 (`Point1`). With the section of
/// [`crate::section::BeamSection::i_beam`] (depth along local `z`), the orientation vector
/// `(0, 1, 0)` puts the depth along global `z` as in [`i_beam_shell`] and [`i_beam_solid`].
pub fn i_beam_line(length: f64, n_elem: usize) -> Result<Mesh> {
    const W: &str = "I-beam line";
    positive(W, "length", length)?;
    if n_elem == 0 {
        return Err(invalid("n_elem", format!("{W}: n_elem must be at least 1, got 0")));
    }
    check_cell_count(W, "n_elem", n_elem as f64)?;
    let xl: Vec<f64> = (0..=n_elem)
        .map(|i| {
            if i == n_elem {
                length
            } else {
                length * i as f64 / n_elem as f64
            }
        })
        .collect();
    let mut bd = Builder::new([xl, vec![0.0], vec![0.0]]);
    let g = bd.group("beam", 1);
    let ga = bd.group("end_a", 0);
    let gb = bd.group("end_b", 0);
    for i in 0..n_elem as u32 {
        bd.push(CellKind::Line2, &[[i, 0, 0], [i + 1, 0, 0]], &[g]);
    }
    bd.push(CellKind::Point1, &[[0, 0, 0]], &[ga]);
    bd.push(CellKind::Point1, &[[n_elem as u32, 0, 0]], &[gb]);
    Ok(bd.finish())
}

/// An I-beam as a solid: the cross-section (depth `h` along `z`, flange width `b` along `y`,
/// web `s`, flanges `t`, centred on the axis, fillets ignored) extruded along
/// `x ∈ [0, length]`, meshed with `kind` (`Hex8`, `Hex20`, `Hex27`) on a rectilinear grid
/// with spacing ≤ `elem_size` that contains the faces of the web and flanges (the web and each
/// flange get at least one cell through their thickness).
///
/// Groups: `"flange_top"`, `"flange_bottom"` (the full flanges, `|z| ≥ h/2 − t`), `"web"`
/// (between them), `"volume"` and `"beam"` (every cell), dimension 3; the end faces
/// `"end_a"` (`x = 0`) and `"end_b"` (`x = length`) and the bounding-box faces `"xmin"` …
/// `"zmax"` of [`grid_solid`], dimension 2.
pub fn i_beam_solid(h: f64, b: f64, s: f64, t: f64, length: f64, elem_size: f64, kind: CellKind) -> Result<Mesh> {
    const W: &str = "I-beam solid";
    check_i_section(W, h, b, s, t, length)?;
    positive(W, "elem_size", elem_size)?;
    let (hh, hb, hs) = (0.5 * h, 0.5 * b, 0.5 * s);
    let zi = hh - t;
    let xl = grid_lines(W, "elem_size", &[0.0, length], elem_size, 1)?;
    let yl = grid_lines(W, "elem_size", &[-hb, -hs, hs, hb], elem_size, 1)?;
    let zl = grid_lines(W, "elem_size", &[-hh, -zi, zi, hh], elem_size, 1)?;
    check_cell_count(
        W,
        &format!("elem_size = {elem_size}"),
        (xl.len() - 1) as f64 * (yl.len() - 1) as f64 * (zl.len() - 1) as f64,
    )?;
    let classify = |c: [f64; 3]| {
        if c[2] > zi {
            Some(0)
        } else if c[2] < -zi {
            Some(1)
        } else if c[1].abs() < hs {
            Some(2)
        } else {
            None
        }
    };
    let mut mesh = grid_solid_groups([&xl, &yl, &zl], kind, &["flange_top", "flange_bottom", "web"], classify)?;
    alias_group(&mut mesh, "volume", "beam");
    alias_group(&mut mesh, "xmin", "end_a");
    alias_group(&mut mesh, "xmax", "end_b");
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_lines_insert_required_and_respect_spacing() {
        let l = grid_lines("t", "h", &[0.0, 1.0, 0.3, 0.3 + 1e-13], 0.25, 1).unwrap();
        assert_eq!(l.len(), 6); // [0, 0.15, 0.3] + [0.3..1] in 3 parts + end
        assert_eq!(l[2], 0.3);
        assert!(l.windows(2).all(|w| w[1] - w[0] <= 0.25 + 1e-12));
        assert_eq!(line_index(&l, 0.3), 2);
        assert_eq!(line_index(&l, 1.0), 5);
        assert_eq!(line_index(&l, 0.0), 0);
        // An exact multiple does not get an extra division.
        assert_eq!(grid_lines("t", "h", &[0.0, 1.0], 0.1, 1).unwrap().len(), 11);
        assert_eq!(grid_lines("t", "h", &[0.0, 1.0], 5.0, 2).unwrap().len(), 3);
    }
}
