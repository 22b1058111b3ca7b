//! Meshes: nodes, cells in blocks of one kind, and named physical groups.
//!
//! A [`Mesh`] knows no physics. Node coordinates are in metres once a mesh is loaded (readers
//! apply `--length-unit`). Node and element ids of the source file are kept for messages and
//! output, while all internal indexing is dense and 0-based.

pub mod cell;
pub mod generate;
pub mod parametric;

pub use cell::CellKind;

/// A block of cells of one kind, e.g. all tet10 of the mesh.
#[derive(Clone, Debug)]
pub struct CellBlock {
    /// The cell kind.
    pub kind: CellKind,
    /// Connectivity: `kind.n_nodes()` dense node indices per cell, in gmsh node order.
    pub conn: Vec<u32>,
    /// The file's element tag of each cell (used in messages and output).
    pub tags: Vec<u64>,
}

impl CellBlock {
    /// A new empty block.
    pub fn new(kind: CellKind) -> Self {
        CellBlock {
            kind,
            conn: Vec::new(),
            tags: Vec::new(),
        }
    }
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.tags.len()
    }
    /// True if the block has no cells.
    pub fn is_empty(&self) -> bool {
        self.tags.is_empty()
    }
    /// Node indices of cell `i`.
    pub fn cell(&self, i: usize) -> &[u32] {
        let n = self.kind.n_nodes();
        &self.conn[i * n..(i + 1) * n]
    }
    /// Append a cell.
    pub fn push(&mut self, nodes: &[u32], tag: u64) {
        debug_assert_eq!(nodes.len(), self.kind.n_nodes());
        self.conn.extend_from_slice(nodes);
        self.tags.push(tag);
    }
}

/// A reference to one cell: its block and its index in the block.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CellRef {
    /// Block index in [`Mesh::blocks`].
    pub block: u32,
    /// Cell index in that block.
    pub index: u32,
}

/// A gmsh physical group: a name, a dimension and the cells in it.
#[derive(Clone, Debug)]
pub struct Group {
    /// Name from `$PhysicalNames`, or `"<dim>:<tag>"` (e.g. `"3:1"`) when the file names none.
    pub name: String,
    /// Dimension of the group's entities (0..=3).
    pub dim: u8,
    /// The physical tag.
    pub tag: i32,
    /// The cells of the group, sorted.
    pub cells: Vec<CellRef>,
}

/// A mesh: nodes, cell blocks and physical groups.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Node coordinates in metres.
    pub nodes: Vec<[f64; 3]>,
    /// The source file's node tag of each node (1-based in gmsh files).
    pub node_tags: Vec<u64>,
    /// Cell blocks, one per kind present (any dimension).
    pub blocks: Vec<CellBlock>,
    /// Physical groups.
    pub groups: Vec<Group>,
    /// What the reader merged or repaired (repeated elements), for the user to read.
    pub notes: Vec<String>,
}

impl Mesh {
    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Number of cells of dimension `dim`.
    pub fn n_cells_of_dim(&self, dim: usize) -> usize {
        self.blocks
            .iter()
            .filter(|b| b.kind.dim() == dim)
            .map(|b| b.len())
            .sum()
    }

    /// The block of `kind`, creating it if needed; returns its index.
    pub fn block_index_mut(&mut self, kind: CellKind) -> usize {
        if let Some(i) = self.blocks.iter().position(|b| b.kind == kind) {
            return i;
        }
        self.blocks.push(CellBlock::new(kind));
        self.blocks.len() - 1
    }

    /// The group named `name`, or given as `dimension:tag` (how unnamed groups are listed). A
    /// name that several groups share (in different dimensions) is an error that lists them;
    /// [`Mesh::group_of_dim`] resolves it by dimension.
    pub fn group(&self, name: &str) -> crate::Result<&Group> {
        self.group_in(name, None)
    }

    /// The group called `name` among those of dimension `dim` when the name is used in several
    /// dimensions (gmsh allows a volume and a surface group of the same name); the formulation
    /// that asks knows which it means.
    pub fn group_of_dim(&self, name: &str, dim: u8) -> crate::Result<&Group> {
        self.group_in(name, Some(dim))
    }

    fn group_in(&self, name: &str, dim: Option<u8>) -> crate::Result<&Group> {
        let hits: Vec<&Group> = self.groups.iter().filter(|g| g.name == name).collect();
        match hits.as_slice() {
            [g] => return Ok(g),
            [] => {}
            several => {
                if let Some(g) = dim.and_then(|d| several.iter().find(|g| g.dim == d)) {
                    return Ok(g);
                }
                let ids: Vec<String> = several.iter().map(|g| format!("{}:{}", g.dim, g.tag)).collect();
                return Err(crate::Error::group(
                    name,
                    format!(
                        "group name '{name}' is used by {} groups ({}, as dimension:tag); rename them in \
                     the mesh, or name one by its dimension:tag",
                        several.len(),
                        ids.join(", ")
                    ),
                ));
            }
        }
        // "D:T": a group by dimension and physical tag (unnamed groups are listed so).
        if let Some((d, t)) = name.split_once(':') {
            if let (Ok(d), Ok(t)) = (d.parse::<u8>(), t.parse::<i32>()) {
                if let Some(g) = self.groups.iter().find(|g| g.dim == d && g.tag == t) {
                    return Ok(g);
                }
            }
        }
        Err(crate::Error::UnknownGroup {
            name: name.to_string(),
            available: self.group_names(),
        })
    }

    /// Comma-separated group names, for messages.
    pub fn group_names(&self) -> String {
        if self.groups.is_empty() {
            return "no physical groups".into();
        }
        self.groups
            .iter()
            .map(|g| g.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Sorted, deduplicated dense node indices of the cells of a group.
    pub fn group_nodes(&self, g: &Group) -> Vec<u32> {
        let mut v: Vec<u32> = g
            .cells
            .iter()
            .flat_map(|c| self.blocks[c.block as usize].cell(c.index as usize).iter().copied())
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// Axis-aligned bounding box `(min, max)`; zeros for an empty mesh.
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        bounding_box(&self.nodes)
    }

    /// Multiply all coordinates by `s` (length-unit conversion).
    pub fn scale(&mut self, s: f64) {
        for p in &mut self.nodes {
            for c in p.iter_mut() {
                *c *= s;
            }
        }
    }
}

/// Axis-aligned bounding box `(min, max)` of points; zeros for none.
pub fn bounding_box(nodes: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    if nodes.is_empty() {
        return ([0.0; 3], [0.0; 3]);
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in nodes {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (lo, hi)
}
