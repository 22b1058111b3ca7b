//! MSH 4.1 (ASCII and binary).
//!
//! Layout of the sections read (gmsh reference manual, "MSH file format"; `size_t` values are
//! `data-size` bytes in binary files, `int` 4 bytes, `double` 8 bytes):
//!
//! ```text
//! $Entities
//!   numPoints numCurves numSurfaces numVolumes                    (size_t)
//!   point:  tag(int) x y z(double) numPhys(size_t) phys(int)...
//!   curve, surface, volume: tag(int) minX minY minZ maxX maxY maxZ(double)
//!           numPhys(size_t) phys(int)... numBounding(size_t) bounding(int)...
//! $Nodes
//!   numEntityBlocks numNodes minNodeTag maxNodeTag                (size_t)
//!   per block: entityDim entityTag parametric(int) numNodesInBlock(size_t)
//!              nodeTag(size_t) x numNodesInBlock
//!              x y z [u [v [w]]](double) x numNodesInBlock      (u.. only if parametric)
//! $Elements
//!   numEntityBlocks numElements minElementTag maxElementTag       (size_t)
//!   per block: entityDim entityTag elementType(int) numElementsInBlock(size_t)
//!              elementTag nodeTag...(size_t) x numElementsInBlock
//! ```
//!
//! With `parametric = 1` a node of an entity of dimension `d` carries `d` parametric
//! coordinates after x, y, z (none on points); they are skipped.

use std::collections::HashMap;

use super::{Builder, Cursor, Header, check_dim, read_physical_names, shown};
use crate::Result;
use crate::mesh::CellKind;

/// Physical tags of each entity `(dim, tag)`, from `$Entities` (every entity listed, with or
/// without groups); `read` is false while no `$Entities` section was read.
#[derive(Default)]
struct EntityGroups {
    read: bool,
    phys: HashMap<(u8, i32), Vec<i32>>,
}

/// Read the sections after `$MeshFormat`.
pub(super) fn read(cur: &mut Cursor, header: &Header, b: &mut Builder) -> Result<()> {
    let mut entities = EntityGroups::default();
    loop {
        cur.set_section("file");
        let Some(tok) = cur.next_token() else { break };
        let name = match tok.strip_prefix(b"$") {
            Some(n) if !n.is_empty() && !n.starts_with(b"End") => n,
            _ => {
                return Err(cur.err(format!("expected a section ($Name), found '{}'", shown(tok))));
            }
        };
        let name = String::from_utf8_lossy(name).into_owned();
        cur.set_section(&format!("${name}"));
        match name.as_str() {
            "PhysicalNames" => read_physical_names(cur, b)?,
            "Entities" => binary_section(cur, header, "$EndEntities", |c| read_entities(c, &mut entities))?,
            "Nodes" => binary_section(cur, header, "$EndNodes", |c| read_nodes(c, b))?,
            "Elements" => binary_section(cur, header, "$EndElements", |c| read_elements(c, b, &entities))?,
            // $Periodic, $NodeData, $Parametrizations, ... are not needed.
            _ => cur.skip_section(&name)?,
        }
    }
    Ok(())
}

/// Run `body` on a section whose content is binary in binary files, then expect `end`.
fn binary_section<'a>(
    cur: &mut Cursor<'a>,
    header: &Header,
    end: &str,
    body: impl FnOnce(&mut Cursor<'a>) -> Result<()>,
) -> Result<()> {
    if header.binary.is_some() {
        cur.end_of_line()?;
        cur.set_binary(header.binary);
    }
    body(cur)?;
    cur.set_binary(None);
    cur.expect(end)
}

/// `$Entities`: keep the physical tags of each entity.
fn read_entities(cur: &mut Cursor, entities: &mut EntityGroups) -> Result<()> {
    let (i, s, f) = (cur.int_bytes(), cur.size_bytes(), cur.float_bytes());
    let point_bytes = i + 3 * f + s;
    let other_bytes = i + 6 * f + 2 * s;
    let n_points = cur.count("point entities", point_bytes)?;
    let n_curves = cur.count("curve entities", other_bytes)?;
    let n_surfaces = cur.count("surface entities", other_bytes)?;
    let n_volumes = cur.count("volume entities", other_bytes)?;
    entities.read = true;
    for (dim, n) in [(0u8, n_points), (1, n_curves), (2, n_surfaces), (3, n_volumes)] {
        for _ in 0..n {
            let tag = cur.int("entity tag")?;
            // A point has its coordinates, the others their bounding box.
            let n_coords = if dim == 0 { 3 } else { 6 };
            for _ in 0..n_coords {
                cur.float("entity coordinate")?;
            }
            let n_phys = cur.count("physical tags", i)?;
            let mut phys = Vec::with_capacity(cur.cap(n_phys, i));
            for _ in 0..n_phys {
                phys.push(cur.int("physical tag")?);
            }
            if dim > 0 {
                let n_bound = cur.count("bounding entities", i)?;
                for _ in 0..n_bound {
                    cur.int("bounding entity tag")?;
                }
            }
            if entities.phys.insert((dim, tag), phys).is_some() {
                return Err(cur.err(format!("entity {dim}:{tag} is listed twice")));
            }
        }
    }
    Ok(())
}

/// `$Nodes`.
fn read_nodes(cur: &mut Cursor, b: &mut Builder) -> Result<()> {
    let (i, s, f) = (cur.int_bytes(), cur.size_bytes(), cur.float_bytes());
    let n_blocks = cur.count("node entity blocks", 3 * i + s)?;
    let n_nodes = cur.count("nodes", s + 3 * f)?;
    cur.size("minimum node tag")?;
    cur.size("maximum node tag")?;
    b.reserve_nodes(cur.cap(n_nodes, s + 3 * f));
    let mut read = 0usize;
    let mut tags = Vec::new();
    for _ in 0..n_blocks {
        let dim = cur.int("entity dimension")?;
        let dim = check_dim(cur, dim)?;
        cur.int("entity tag")?;
        let parametric = cur.int("parametric flag")?;
        // Parametric coordinates: one per dimension of the entity (u on curves, u v on
        // surfaces, u v w in volumes), none on points.
        let n_param = match parametric {
            0 => 0,
            1 => usize::from(dim),
            p => return Err(cur.err(format!("parametric flag must be 0 or 1, found {p}"))),
        };
        let n = cur.count("nodes in the block", s + (3 + n_param) * f)?;
        if n > n_nodes - read {
            return Err(cur.err(format!(
                "{n} nodes in the block: more than the {} of the {n_nodes} in the section's header that the \
                 blocks before it leave",
                n_nodes - read
            )));
        }
        tags.clear();
        tags.reserve(cur.cap(n, s + (3 + n_param) * f));
        for _ in 0..n {
            tags.push(cur.size("node tag")?);
        }
        for &tag in &tags {
            let x = super::node_coords(cur, tag, n_param, false)?;
            b.add_node(cur, tag, x)?;
        }
        read += n;
    }
    if read != n_nodes {
        return Err(cur.err(format!(
            "the header announces {n_nodes} nodes but the blocks hold {read}"
        )));
    }
    Ok(())
}

/// `$Elements`.
fn read_elements(cur: &mut Cursor, b: &mut Builder, entities: &EntityGroups) -> Result<()> {
    let (i, s) = (cur.int_bytes(), cur.size_bytes());
    let n_blocks = cur.count("element entity blocks", 3 * i + s)?;
    let n_elements = cur.count("elements", 2 * s)?;
    cur.size("minimum element tag")?;
    cur.size("maximum element tag")?;
    let mut read = 0usize;
    let mut nodes = Vec::new();
    let no_groups = Vec::new();
    for _ in 0..n_blocks {
        let dim = cur.int("entity dimension")?;
        let dim = check_dim(cur, dim)?;
        let entity = cur.int("entity tag")?;
        let gmsh_type = cur.int("element type")?;
        let n = cur.size("number of elements in the block")?;
        if let Some(kind) = CellKind::from_gmsh_type(gmsh_type).filter(|k| k.dim() != dim as usize) {
            return Err(cur.err(format!(
                "a block of entity {dim}:{entity} (dimension {dim}) holds {} elements of dimension {}",
                kind.name(),
                kind.dim()
            )));
        }
        let phys = match entities.phys.get(&(dim, entity)) {
            Some(p) => p,
            None if entities.read => {
                return Err(cur.err(format!(
                    "a block of elements belongs to entity {dim}:{entity}, which $Entities does not list"
                )));
            }
            None => &no_groups,
        };
        let Some(kind) = CellKind::from_gmsh_type(gmsh_type) else {
            let group = if phys.is_empty() {
                format!("entity {dim}:{entity}")
            } else {
                let labels: Vec<String> = phys.iter().map(|&p| b.group_label(dim, p)).collect();
                labels.join(", ")
            };
            return Err(b.unsupported(cur.path(), gmsh_type, group));
        };
        let nn = kind.n_nodes();
        if n > (n_elements - read) as u64 {
            return Err(cur.err(format!(
                "{n} elements in the block of entity {dim}:{entity}: more than the {} of the {n_elements} \
                 in the section's header that the blocks before it leave",
                n_elements - read
            )));
        }
        let n = cur.check_count(n, "elements in the block", (1 + nn) * s)?;
        for _ in 0..n {
            let tag = cur.size("element tag")?;
            nodes.clear();
            for k in 0..nn {
                cur.more_on_line(|| {
                    format!(
                        "element {tag}: its line ends after {k} of the {nn} node tags of a {} (gmsh type {gmsh_type})",
                        kind.name()
                    )
                })?;
                let node = cur.size("node tag")?;
                nodes.push(b.node(cur, tag, node)?);
            }
            cur.line_done(|extra| {
                format!(
                    "element {tag} (a {} of {nn} nodes): more values on its line than expected, starting at '{extra}'",
                    kind.name()
                )
            })?;
            // Within 4.1 an element in several groups is written once (its entity carries the
            // groups): any repeat is a duplicate, counted once, with a note.
            let (cell, merged) = b.add_cell(cur, kind, tag, &nodes)?;
            if merged {
                b.note_merged(cell, tag);
            }
            for &p in phys {
                b.add_to_group(dim, p, cell);
            }
        }
        read += n;
    }
    if read != n_elements {
        return Err(cur.err(format!(
            "the header announces {n_elements} elements but the blocks hold {read}"
        )));
    }
    Ok(())
}
