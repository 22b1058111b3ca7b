//! gmsh MSH 4.1 ASCII writer: the mesh plus nodal result views (`$NodeData`), for viewing
//! mode shapes in gmsh.
//!
//! The file holds the nodes, the cells of every block (gmsh node order, so no permutation),
//! the physical groups with their names, and one `$NodeData` section per [`NodeView`]. Open it
//! with `gmsh file.msh`: each view appears in the post-processing tree; a 3-component view
//! can be shown as displaced shape (Options → View → "Displacement" vector display) and
//! animated. Views sharing a name and differing in `step` form one view with time steps.
//!
//! # Entities
//! MSH 4.1 attaches physical groups to geometric entities, not to elements. The writer makes
//! one discrete entity per dimension and distinct set of groups: all cells of a dimension that
//! belong to exactly the same groups share an entity, and the entity carries those groups'
//! physical tags. All nodes are listed in one node block on the first entity of the highest
//! dimension. Reading such a file back (with [`crate::io::gmsh::read`] or gmsh) gives the same
//! cells and groups.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use super::fmt_f64;
use crate::mesh::Mesh;
use crate::{Error, Result};

/// A nodal view: `n_comp` values per node (1 scalar, 3 vector, 9 tensor), node-major
/// (`data[node * n_comp + comp]`).
#[derive(Clone, Debug)]
pub struct NodeView<'a> {
    /// View name shown in gmsh (e.g. `"mode 7: 123.4 Hz"`).
    pub name: String,
    /// Time step index (views with the same name and increasing steps animate).
    pub step: usize,
    /// Time value of the step (e.g. the frequency in Hz for a mode).
    pub time: f64,
    /// Components per node: 1, 3 or 9 (what gmsh accepts).
    pub n_comp: usize,
    /// Values, `n_comp * n_nodes` of them.
    pub data: &'a [f64],
}

/// Write `mesh` and `views` to a MSH 4.1 ASCII file.
///
/// # Errors
/// [`Error::InvalidInput`] if a view has not 1, 3 or 9 components, [`Error::param`] if it has
/// not `n_comp` finite values per node or the mesh has no cells; [`Error::Io`] if the file cannot be
/// created, [`Error::Output`] if it cannot be written (a full disk).
pub fn write_msh_views(path: &Path, mesh: &Mesh, views: &[NodeView]) -> Result<()> {
    let text = msh_string(mesh, views)?;
    let mut f = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    // Created but not written (a full disk): a result lost, exit 4, not an input error.
    f.write_all(text.as_bytes())
        .map_err(|e| Error::output(path.display(), e))
}

/// The MSH 4.1 document as a string (see [`write_msh_views`]).
pub fn msh_string(mesh: &Mesh, views: &[NodeView]) -> Result<String> {
    let n_cells = check_views(mesh, views)?;
    let (node_tags, elem_tags) = file_tags(mesh, n_cells);
    let ent = Entities::of(mesh);
    let mut s = String::new();
    s.push_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    write_physical_names(&mut s, mesh, &ent.phys);
    write_entities(&mut s, &ent);
    write_nodes(&mut s, mesh, &node_tags, &ent.count);
    write_elements(&mut s, mesh, &node_tags, &elem_tags, &ent.element_blocks, n_cells);
    for v in views {
        write_node_data(&mut s, v, &node_tags);
    }
    Ok(s)
}

/// Check the views (1, 3 or 9 components, `n_comp` finite values per node) and that the mesh
/// has cells; the number of cells.
fn check_views(mesh: &Mesh, views: &[NodeView]) -> Result<usize> {
    let n_nodes = mesh.n_nodes();
    for v in views {
        // Stays Error::InvalidInput: tests/unit/mesh_io.rs matches on the variant.
        if !matches!(v.n_comp, 1 | 3 | 9) {
            return Err(Error::InvalidInput(format!(
                "view '{}': gmsh views have 1, 3 or 9 components, not {}",
                v.name, v.n_comp
            )));
        }
        if v.data.len() != v.n_comp * n_nodes {
            return Err(Error::param(
                "views",
                format!(
                    "view '{}': {} values for {} nodes with {} components",
                    v.name,
                    v.data.len(),
                    n_nodes,
                    v.n_comp
                ),
            ));
        }
        if !v.time.is_finite() || v.data.iter().any(|x| !x.is_finite()) {
            return Err(Error::param(
                "views",
                format!("view '{}' has non-finite values", v.name),
            ));
        }
    }
    let n_cells: usize = mesh.blocks.iter().map(|b| b.len()).sum();
    if n_cells == 0 {
        return Err(Error::param("mesh", "cannot write a MSH file of a mesh without cells"));
    }
    Ok(n_cells)
}

/// Node and element tags (per block) in the file: the mesh's own if they are usable
/// (non-zero, unique), else `1..=N`.
fn file_tags(mesh: &Mesh, n_cells: usize) -> (Vec<u64>, Vec<Vec<u64>>) {
    let n_nodes = mesh.n_nodes();
    let node_tags: Vec<u64> = if usable_tags(mesh.node_tags.iter().copied(), n_nodes) {
        mesh.node_tags.clone()
    } else {
        (1..=n_nodes as u64).collect()
    };
    let elem_tags: Vec<Vec<u64>> = if usable_tags(mesh.blocks.iter().flat_map(|b| b.tags.iter().copied()), n_cells) {
        mesh.blocks.iter().map(|b| b.tags.clone()).collect()
    } else {
        let mut next = 0u64;
        mesh.blocks
            .iter()
            .map(|b| {
                (0..b.len())
                    .map(|_| {
                        next += 1;
                        next
                    })
                    .collect()
            })
            .collect()
    };
    (node_tags, elem_tags)
}

/// The discrete entities of the file (see the [module docs](self)) and the element blocks on
/// them.
struct Entities {
    /// Physical tag of each mesh group.
    phys: Vec<i32>,
    /// Number of entities per dimension.
    count: [i32; 4],
    /// The groups of each entity, by (dim, entity tag).
    groups: BTreeMap<(usize, i32), Vec<usize>>,
    /// Cells (indices in their mesh block) by (mesh block, dim, entity tag).
    element_blocks: BTreeMap<(usize, usize, i32), Vec<usize>>,
    /// Bounding box of each entity (its lower corner is the position of a point entity).
    bbox: HashMap<(usize, i32), ([f64; 3], [f64; 3])>,
}

impl Entities {
    fn of(mesh: &Mesh) -> Entities {
        // Physical tag of each group: its own, unless another group of its dimension has it.
        let mut used: HashSet<(u8, i32)> = HashSet::new();
        let mut phys: Vec<i32> = Vec::with_capacity(mesh.groups.len());
        for g in &mesh.groups {
            let mut t = if g.tag > 0 { g.tag } else { 1 };
            while !used.insert((g.dim, t)) {
                t += 1;
            }
            phys.push(t);
        }
        // The groups of each cell.
        let mut cell_groups: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
        for (gi, g) in mesh.groups.iter().enumerate() {
            for c in &g.cells {
                cell_groups.entry((c.block, c.index)).or_default().push(gi);
            }
        }
        // Entities: (dim, sorted group list) → entity tag, numbered per dimension by first use.
        // Element blocks are keyed (mesh block, dim, entity tag), so that the file lists the
        // mesh's blocks in order and a reader gets them back in the same order.
        let mut entity_of: HashMap<(usize, Vec<usize>), i32> = HashMap::new();
        let mut count = [0i32; 4];
        let mut groups_of: BTreeMap<(usize, i32), Vec<usize>> = BTreeMap::new();
        let mut element_blocks: BTreeMap<(usize, usize, i32), Vec<usize>> = BTreeMap::new();
        for (bi, b) in mesh.blocks.iter().enumerate() {
            let dim = b.kind.dim();
            for i in 0..b.len() {
                let mut groups = cell_groups.get(&(bi as u32, i as u32)).cloned().unwrap_or_default();
                groups.sort_unstable();
                groups.dedup();
                let key = (dim, groups);
                let tag = match entity_of.get(&key) {
                    Some(&t) => t,
                    None => {
                        count[dim] += 1;
                        let t = count[dim];
                        groups_of.insert((dim, t), key.1.clone());
                        entity_of.insert(key, t);
                        t
                    }
                };
                element_blocks.entry((bi, dim, tag)).or_default().push(i);
            }
        }
        let bbox = entity_boxes(mesh, &element_blocks);
        Entities {
            phys,
            count,
            groups: groups_of,
            element_blocks,
            bbox,
        }
    }
}

/// Bounding box of each entity over the nodes of its cells.
fn entity_boxes(
    mesh: &Mesh,
    element_blocks: &BTreeMap<(usize, usize, i32), Vec<usize>>,
) -> HashMap<(usize, i32), ([f64; 3], [f64; 3])> {
    let mut bbox: HashMap<(usize, i32), ([f64; 3], [f64; 3])> = HashMap::new();
    for (&(bi, dim, tag), cells) in element_blocks {
        let b = &mesh.blocks[bi];
        let e = bbox
            .entry((dim, tag))
            .or_insert(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]));
        for &i in cells {
            for &n in b.cell(i) {
                for (d, &x) in mesh.nodes[n as usize].iter().enumerate() {
                    e.0[d] = e.0[d].min(x);
                    e.1[d] = e.1[d].max(x);
                }
            }
        }
    }
    bbox
}

/// `$PhysicalNames`: one line per group (none without groups).
fn write_physical_names(s: &mut String, mesh: &Mesh, phys: &[i32]) {
    if !mesh.groups.is_empty() {
        let _ = writeln!(s, "$PhysicalNames\n{}", mesh.groups.len());
        for (g, &t) in mesh.groups.iter().zip(phys) {
            let _ = writeln!(s, "{} {} \"{}\"", g.dim, t, g.name.replace('"', "'"));
        }
        s.push_str("$EndPhysicalNames\n");
    }
}

/// `$Entities`: each discrete entity with its bounding box and physical tags.
fn write_entities(s: &mut String, ent: &Entities) {
    let n = ent.count;
    let _ = writeln!(s, "$Entities\n{} {} {} {}", n[0], n[1], n[2], n[3]);
    for (&(dim, tag), groups) in &ent.groups {
        let (lo, hi) = ent.bbox.get(&(dim, tag)).copied().unwrap_or(([0.0; 3], [0.0; 3]));
        let _ = write!(s, "{tag}");
        let coords: &[f64] = if dim == 0 {
            &lo
        } else {
            &[lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]]
        };
        for &x in coords {
            let _ = write!(s, " {}", fmt_f64(x));
        }
        let _ = write!(s, " {}", groups.len());
        for &g in groups {
            let _ = write!(s, " {}", ent.phys[g]);
        }
        // Curves, surfaces and volumes list their bounding entities: none for discrete ones.
        s.push_str(if dim == 0 { "\n" } else { " 0\n" });
    }
    s.push_str("$EndEntities\n");
}

/// `$Nodes`: one block on the first entity of the highest dimension.
fn write_nodes(s: &mut String, mesh: &Mesh, node_tags: &[u64], n_entities: &[i32; 4]) {
    let n_nodes = mesh.n_nodes();
    let top = (0..4).rev().find(|&d| n_entities[d] > 0).unwrap_or(0);
    let (lo, hi) = (
        node_tags.iter().min().copied().unwrap_or(0),
        node_tags.iter().max().copied().unwrap_or(0),
    );
    let _ = writeln!(s, "$Nodes\n1 {n_nodes} {lo} {hi}\n{top} 1 0 {n_nodes}");
    for t in node_tags {
        let _ = writeln!(s, "{t}");
    }
    for p in &mesh.nodes {
        let _ = writeln!(s, "{} {} {}", fmt_f64(p[0]), fmt_f64(p[1]), fmt_f64(p[2]));
    }
    s.push_str("$EndNodes\n");
}

/// `$Elements`: one block per (entity, kind).
fn write_elements(
    s: &mut String,
    mesh: &Mesh,
    node_tags: &[u64],
    elem_tags: &[Vec<u64>],
    element_blocks: &BTreeMap<(usize, usize, i32), Vec<usize>>,
    n_cells: usize,
) {
    let all = elem_tags.iter().flatten();
    let (lo, hi) = (all.clone().min().copied().unwrap_or(0), all.max().copied().unwrap_or(0));
    let _ = writeln!(s, "$Elements\n{} {n_cells} {lo} {hi}", element_blocks.len());
    for (&(bi, dim, tag), cells) in element_blocks {
        let b = &mesh.blocks[bi];
        let _ = writeln!(s, "{dim} {tag} {} {}", b.kind.gmsh_type(), cells.len());
        for &i in cells {
            let _ = write!(s, "{}", elem_tags[bi][i]);
            for &n in b.cell(i) {
                let _ = write!(s, " {}", node_tags[n as usize]);
            }
            s.push('\n');
        }
    }
    s.push_str("$EndElements\n");
}

/// One `$NodeData` section: the view `v` at its step and time.
fn write_node_data(s: &mut String, v: &NodeView, node_tags: &[u64]) {
    let _ = writeln!(
        s,
        "$NodeData\n1\n\"{}\"\n1\n{}\n3\n{}\n{}\n{}",
        v.name.replace('"', "'"),
        fmt_f64(v.time),
        v.step,
        v.n_comp,
        node_tags.len()
    );
    for (t, row) in node_tags.iter().zip(v.data.chunks(v.n_comp)) {
        let _ = write!(s, "{t}");
        for &x in row {
            let _ = write!(s, " {}", fmt_f64(x));
        }
        s.push('\n');
    }
    s.push_str("$EndNodeData\n");
}

/// True if `tags` are `n` non-zero, distinct values.
fn usable_tags(tags: impl Iterator<Item = u64>, n: usize) -> bool {
    let mut seen = HashSet::with_capacity(n);
    let mut count = 0;
    for t in tags {
        if t == 0 || !seen.insert(t) {
            return false;
        }
        count += 1;
    }
    count == n
}
