//! MSH 2.2 (ASCII and binary). `mshio` does not read this legacy format, which gmsh still
//! writes with `-format msh22` / `Mesh.MshFileVersion = 2.2`, and meshio with `gmsh22`.
//!
//! ```text
//! $Nodes
//!   numNodes                                  (ASCII line, also in binary files)
//!   ASCII:  tag x y z                         one line per node
//!   binary: tag(int) x y z(double)            numNodes records
//! $Elements
//!   numElements                               (ASCII line, also in binary files)
//!   ASCII:  tag type numTags tag... node...   one line per element
//!   binary: blocks of  type numInBlock numTags (int)
//!           then numInBlock records  tag(int) tags(int)... nodes(int)...
//!           until numElements records are read
//! ```
//!
//! The first element tag is the physical group, the second the elementary entity. gmsh
//! writes an element that belongs to several physical groups once per group, on consecutive
//! records with new element numbers; such repeats (same kind, entity and nodes as the record
//! before) become one cell that belongs to all those groups.

use super::{Builder, Cursor, Header, gmsh_type_dim, read_physical_names, shown};
use crate::Result;
use crate::mesh::{CellKind, CellRef};

/// Read the sections after `$MeshFormat`.
pub(super) fn read(cur: &mut Cursor, header: &Header, b: &mut Builder) -> Result<()> {
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
            "Nodes" => read_nodes(cur, header, b)?,
            "Elements" => read_elements(cur, header, b)?,
            _ => cur.skip_section(&name)?,
        }
    }
    Ok(())
}

/// Read the ASCII record count of a section and, in binary files, switch to binary data.
fn section_count(cur: &mut Cursor, header: &Header, what: &str, ascii: usize, bin: usize) -> Result<usize> {
    let n = cur.tok_count(what, if header.binary.is_some() { bin } else { ascii })?;
    if header.binary.is_some() {
        cur.end_of_line()?;
        cur.set_binary(header.binary);
    }
    Ok(n)
}

/// `$Nodes`.
fn read_nodes(cur: &mut Cursor, header: &Header, b: &mut Builder) -> Result<()> {
    // ASCII: 4 tokens of at least 2 bytes; binary: int + 3 doubles.
    let min_bytes = if header.binary.is_some() { 28 } else { 8 };
    let n = section_count(cur, header, "nodes", 8, 28)?;
    b.reserve_nodes(cur.cap(n, min_bytes));
    for _ in 0..n {
        let tag = cur.int_tag("node tag")?;
        let x = super::node_coords(cur, tag, 0, true)?;
        b.add_node(cur, tag, x)?;
    }
    cur.set_binary(None);
    cur.expect("$EndNodes")
}

/// State shared by the records of `$Elements`.
struct Elements {
    /// The elementary entity of each cell, to tell gmsh's repeats of an element for several
    /// physical groups (same entity) from other duplicates.
    entity_of: std::collections::HashMap<CellRef, i64>,
    /// (cell, physical tag) pairs read: a repeat for a group the cell is already in is a
    /// duplicate, not gmsh's repeat for another group.
    groups_of: std::collections::HashSet<(CellRef, i64)>,
    /// Scratch: tags and dense node indices of the current record.
    tags: Vec<i64>,
    nodes: Vec<u32>,
}

/// `$Elements`.
fn read_elements(cur: &mut Cursor, header: &Header, b: &mut Builder) -> Result<()> {
    // ASCII: tag type numTags node, 2 bytes each; binary: a record is at least tag + node.
    let n = section_count(cur, header, "elements", 8, 8)?;
    let mut st = Elements {
        entity_of: std::collections::HashMap::new(),
        groups_of: std::collections::HashSet::new(),
        tags: Vec::new(),
        nodes: Vec::new(),
    };
    if header.binary.is_none() {
        for _ in 0..n {
            let tag = cur.tok_u64("element tag")?;
            let gmsh_type = cur.tok_i32("element type")?;
            let n_tags = cur.tok_count("element tags", 2)?;
            read_tags(cur, &mut st, n_tags)?;
            record(cur, b, &mut st, tag, gmsh_type, true)?;
            // One element a line: a node too many is named here rather than read as the next
            // element's tag (which reported the line after, "expected $EndElements").
            cur.line_done(|extra| {
                format!(
                    "element {tag}: more node tags on its line than its type (gmsh type {gmsh_type}) has, \
                     starting at '{extra}'"
                )
            })?;
        }
    } else {
        let mut read = 0usize;
        while read < n {
            let gmsh_type = cur.int("element type")?;
            let in_block = cur.int("number of elements in the block")?;
            let n_tags = cur.int("number of element tags")?;
            let (Ok(in_block), Ok(n_tags)) = (usize::try_from(in_block), usize::try_from(n_tags)) else {
                return Err(cur.err("negative count in an element block header"));
            };
            if in_block == 0 || in_block > n - read {
                return Err(cur.err(format!(
                    "element block of {in_block} elements does not fit the {} elements left",
                    n - read
                )));
            }
            cur.check_count(n_tags as u64, "element tags", 4)?;
            for _ in 0..in_block {
                let tag = cur.int_tag("element tag")?;
                read_tags(cur, &mut st, n_tags)?;
                record(cur, b, &mut st, tag, gmsh_type, false)?;
            }
            read += in_block;
        }
        cur.set_binary(None);
    }
    cur.expect("$EndElements")
}

/// Read `n_tags` element tags into `st.tags`.
fn read_tags(cur: &mut Cursor, st: &mut Elements, n_tags: usize) -> Result<()> {
    st.tags.clear();
    for _ in 0..n_tags {
        st.tags.push(i64::from(cur.int("element tag value")?));
    }
    Ok(())
}

/// The nodes of one element record (its tags already in `st.tags`): add the cell, or merge it
/// into the previous one if it repeats it for another physical group.
/// In ASCII (`one_line`) the record must end on its line.
fn record(
    cur: &mut Cursor,
    b: &mut Builder,
    st: &mut Elements,
    tag: u64,
    gmsh_type: i32,
    one_line: bool,
) -> Result<()> {
    let phys = st.tags.first().copied().unwrap_or(0);
    let entity = st.tags.get(1).copied().unwrap_or(0);
    let Some(kind) = CellKind::from_gmsh_type(gmsh_type) else {
        let group = match (i32::try_from(phys), gmsh_type_dim(gmsh_type)) {
            (Ok(p), Some(dim)) if p != 0 => b.group_label(dim, p),
            (Ok(p), None) if p != 0 => format!("physical group {p}"),
            _ => match gmsh_type_dim(gmsh_type) {
                Some(dim) => format!("entity {dim}:{entity}"),
                None => format!("entity {entity}"),
            },
        };
        return Err(b.unsupported(cur.path(), gmsh_type, group));
    };
    st.nodes.clear();
    for k in 0..kind.n_nodes() {
        if one_line {
            cur.more_on_line(|| {
                format!(
                    "element {tag}: its line ends after {k} of the {} node tags of a {} (gmsh type {gmsh_type})",
                    kind.n_nodes(),
                    kind.name()
                )
            })?;
        }
        let node = cur.int_tag("node tag")?;
        st.nodes.push(b.node(cur, tag, node)?);
    }
    // A cell read before (same kind and nodes) is merged: gmsh's repeat of an element for
    // another physical group (same entity) silently, any other duplicate with a note.
    let (cell, merged) = b.add_cell(cur, kind, tag, &st.nodes)?;
    let new_group = st.groups_of.insert((cell, phys));
    if merged {
        let gmsh_repeat = new_group && matches!(st.entity_of.get(&cell), Some(&e) if e == entity && phys != 0);
        if !gmsh_repeat {
            b.note_merged(cell, tag);
        }
    } else {
        st.entity_of.insert(cell, entity);
    }
    if phys != 0 {
        let p = i32::try_from(phys).map_err(|_| cur.err(format!("physical tag {phys} out of range")))?;
        b.add_to_group(kind.dim() as u8, p, cell);
    }
    Ok(())
}
