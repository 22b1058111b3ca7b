//! gmsh MSH reader: format 4.1 and 2.2, ASCII and binary.
//!
//! The version is detected from `$MeshFormat`. Both versions are read by our own small
//! parsers (`msh4` and `msh2` below) over one bounds-checked `cursor`: that is what lets
//! every error name the section and line, keeps allocations bounded by the file's size
//! whatever its headers claim, and reads 4.1 files saved with parametric node coordinates
//! (`Mesh.SaveParametric = 1`), which `mshio` 0.4 rejects. (`mshio` also `unwrap`s in its
//! header parser and preallocates nothing we could bound; the tests use it as an independent
//! cross-check on 4.1 files instead.)
//!
//! What the reader produces:
//! - nodes renumbered densely in file order, with the file's tags kept in
//!   [`Mesh::node_tags`]; coordinates multiplied by `length_scale`;
//! - one [`CellBlock`](crate::mesh::CellBlock) per [`CellKind`] present, of every dimension,
//!   connectivity in gmsh node order, element tags kept;
//! - one [`Group`] per physical group: named from `$PhysicalNames`, else `"<dim>:<tag>"`. In
//!   MSH 4.1 a physical group is attached to entities (`$Entities`), and every element of an
//!   entity belongs to all of the entity's groups; in MSH 2.2 the first element tag is the
//!   physical tag. A file without physical groups gives a mesh without groups.
//!
//! Element types outside [`CellKind`] (pyramids, 18-node prisms, ...) are rejected with
//! [`Error::UnsupportedElement`].

mod cursor;
mod msh2;
mod msh4;

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use crate::mesh::{CellKind, CellRef, Group, Mesh, cell::gmsh_type_name};
use crate::{Error, Result};
use cursor::{BinaryLayout, Cursor, shown};

/// Read a gmsh mesh file (MSH 4.1 or 2.2, ASCII or binary).
///
/// `length_scale` multiplies all coordinates (e.g. `1e-3` for a mesh drawn in millimetres).
///
/// # Errors
/// [`Error::Io`] if the file cannot be read, [`Error::MeshParse`] for a malformed or truncated
/// file, [`Error::UnsupportedElement`] for an element type vibrofem does not know,
/// [`Error::EmptyModel`] for a file without elements, [`Error::InvalidInput`] for a
/// non-positive `length_scale`.
pub fn read(path: &Path, length_scale: f64) -> Result<Mesh> {
    read_bytes(&read_file(path)?, path, length_scale)
}

/// The bytes of a mesh file, read only after its first bytes show a gmsh header: `/dev/zero`,
/// a FIFO or a large file of another kind is refused at once instead of read until memory runs
/// out. A stream without a known size is read up to the memory this process may use.
fn read_file(path: &Path) -> Result<Vec<u8>> {
    use std::io::Read;
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let size = f.metadata().ok().filter(|m| m.is_file()).map(|m| m.len());
    // "$MeshFormat" after at most a little leading white space.
    let mut head = Vec::new();
    (&mut f)
        .take(64)
        .read_to_end(&mut head)
        .map_err(|e| Error::io(path, e))?;
    let start = head.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(head.len());
    if !head[start..].starts_with(b"$MeshFormat") {
        let shown: String = head[start..]
            .iter()
            .take(16)
            .map(|&b| {
                if b.is_ascii_graphic() || b == b' ' {
                    b as char
                } else {
                    '.'
                }
            })
            .collect();
        return Err(Error::MeshParse {
            path: path.to_path_buf(),
            section: "$MeshFormat".into(),
            line: Some(1),
            msg: if head.is_empty() {
                "empty file: expected $MeshFormat".into()
            } else {
                format!("not a gmsh MSH file: it starts with '{shown}', not $MeshFormat")
            },
        });
    }
    let cap = match size {
        Some(n) => n,
        None => crate::util::memory::available_memory().unwrap_or(u64::MAX) / 2,
    };
    let mut bytes = head;
    if let Some(n) = size {
        bytes
            .try_reserve_exact((n as usize).saturating_sub(bytes.len()))
            .map_err(|_| Error::out_of_memory(&format!("reading {}", path.display()), n))?;
    }
    (&mut f)
        .take(cap.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if size.is_none() && bytes.len() as u64 > cap {
        return Err(Error::MeshParse {
            path: path.to_path_buf(),
            section: "file".into(),
            line: None,
            msg: format!(
                "the stream goes on beyond {}, half the memory available: not a mesh this machine can hold",
                crate::util::fmt::fmt_bytes(cap)
            ),
        });
    }
    Ok(bytes)
}

/// Read a gmsh mesh from the bytes of a file; `path` is used in messages only.
///
/// See [`read`].
pub fn read_bytes(bytes: &[u8], path: &Path, length_scale: f64) -> Result<Mesh> {
    // Stays Error::InvalidInput: tests/unit/mesh_io.rs matches on the variant.
    if !(length_scale.is_finite() && length_scale > 0.0) {
        return Err(Error::InvalidInput(format!(
            "{}: length scale must be a positive number, got {length_scale}",
            path.display()
        )));
    }
    let mut cur = Cursor::new(bytes, path);
    let header = read_header(&mut cur)?;
    let mut b = Builder::default();
    match header.version {
        Version::V2 => msh2::read(&mut cur, &header, &mut b)?,
        Version::V41 => msh4::read(&mut cur, &header, &mut b)?,
    }
    b.finish(path, length_scale)
}

/// The two supported format versions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Version {
    /// MSH 2.x (2.0, 2.1, 2.2 share the layout read here).
    V2,
    /// MSH 4.1.
    V41,
}

/// What `$MeshFormat` says.
struct Header {
    version: Version,
    /// Binary layout of binary files, `None` for ASCII files.
    binary: Option<BinaryLayout>,
}

/// Read `$MeshFormat ... $EndMeshFormat`.
fn read_header(cur: &mut Cursor) -> Result<Header> {
    cur.set_section("$MeshFormat");
    match cur.next_token() {
        Some(t) if t == b"$MeshFormat" => {}
        Some(t) => {
            return Err(cur.err(format!(
                "not a gmsh MSH file: expected $MeshFormat at the start, found '{}'",
                shown(t)
            )));
        }
        None => return Err(cur.err("empty file: expected $MeshFormat")),
    }
    let v = cur.token("the format version")?;
    let version = match v {
        b"4.1" => Version::V41,
        b"2" | b"2.0" | b"2.1" | b"2.2" => Version::V2,
        _ => {
            return Err(cur.err(format!(
                "unsupported MSH format version '{}': vibrofem reads 4.1 and 2.2 \
                 (re-save the mesh in gmsh with Mesh.MshFileVersion = 4.1)",
                shown(v)
            )));
        }
    };
    let file_type = cur.tok_i32("file type (0 = ASCII, 1 = binary)")?;
    let data_size = cur.tok_i32("data size")?;
    let binary = match file_type {
        0 => None,
        1 => {
            // MSH 4.1: data-size is sizeof(size_t); MSH 2.2: sizeof(double), must be 8.
            let size_t = match (version, data_size) {
                (Version::V41, 4 | 8) => data_size as usize,
                (Version::V2, 8) => 8,
                _ => return Err(cur.err(format!("unsupported binary data size {data_size}"))),
            };
            cur.end_of_line()?;
            cur.set_file_binary(true);
            let big_endian = cur.endianness()?;
            Some(BinaryLayout { big_endian, size_t })
        }
        t => {
            return Err(cur.err(format!("file type must be 0 (ASCII) or 1 (binary), found {t}")));
        }
    };
    cur.expect("$EndMeshFormat")?;
    Ok(Header { version, binary })
}

/// Read `$PhysicalNames` (always ASCII): `n` lines `dim tag "name"`.
fn read_physical_names(cur: &mut Cursor, b: &mut Builder) -> Result<()> {
    // A record is at least `d t "x"` (7 bytes with separators).
    let n = cur.tok_count("physical names", 7)?;
    for _ in 0..n {
        let dim = cur.tok_i32("physical group dimension")?;
        let dim = check_dim(cur, dim)?;
        let tag = cur.tok_i32("physical tag")?;
        let raw = cur.rest_of_line();
        // gmsh quotes names; an unquoted one is taken as it stands, a half-quoted one is a
        // damaged line (its group would be looked up by a name no one typed).
        let name = match (raw.strip_prefix(b"\""), raw.len() >= 2 && raw.ends_with(b"\"")) {
            (Some(r), true) => r.strip_suffix(b"\"").unwrap_or(r),
            (None, false) => raw,
            _ => {
                return Err(cur.err(format!(
                    "physical group {dim}:{tag}: the name {} lacks a quote (gmsh writes \"name\")",
                    shown(raw)
                )));
            }
        };
        if name.is_empty() {
            return Err(cur.err(format!("physical group {dim}:{tag} has an empty name")));
        }
        let name = String::from_utf8_lossy(name).into_owned();
        // The same group named twice, or one name for two groups of a dimension: which one a
        // command means would be a guess.
        if let Some(old) = b.names.get(&(dim, tag)) {
            if *old != name {
                return Err(cur.err(format!(
                    "physical group {dim}:{tag} is named twice ('{old}' and '{name}')"
                )));
            }
            continue;
        }
        if let Some(((_, other), _)) = b.names.iter().find(|((d, _), n)| *d == dim && **n == name) {
            return Err(cur.err(format!(
                "the name '{name}' is given to two physical groups of dimension {dim} (tags {other} and {tag}); \
                 give them one tag or two names"
            )));
        }
        b.names.insert((dim, tag), name);
    }
    cur.expect("$EndPhysicalNames")
}

/// A node's x, y, z (then `n_param` parametric coordinates, skipped); in ASCII on the line of its
/// tag (MSH 2) or on a line of its own (MSH 4), nothing missing and nothing more.
fn node_coords(cur: &mut Cursor, tag: u64, n_param: usize, after_tag: bool) -> Result<[f64; 3]> {
    let mut x = [0.0; 3];
    for (d, axis) in ["x", "y", "z"].into_iter().enumerate() {
        if d > 0 || after_tag {
            cur.more_on_line(|| format!("node {tag}: its line ends before its {axis} coordinate"))?;
        }
        x[d] = cur.coord(axis)?;
    }
    for _ in 0..n_param {
        cur.more_on_line(|| format!("node {tag}: its line ends before its parametric coordinates"))?;
        cur.float("parametric coordinate")?;
    }
    cur.line_done(|extra| format!("node {tag}: more values on its line than expected, starting at '{extra}'"))?;
    Ok(x)
}

/// An entity or group dimension, which must be 0..=3.
fn check_dim(cur: &Cursor, dim: i32) -> Result<u8> {
    match u8::try_from(dim) {
        Ok(d) if d <= 3 => Ok(d),
        _ => Err(cur.err(format!("dimension must be 0, 1, 2 or 3, found {dim}"))),
    }
}

/// Dimension of a gmsh element type, including types vibrofem does not support (for the
/// group lookup of the error message).
fn gmsh_type_dim(t: i32) -> Option<u8> {
    if let Some(k) = CellKind::from_gmsh_type(t) {
        return Some(k.dim() as u8);
    }
    match t {
        7 | 13 | 14 | 19 | 29..=31 | 92 | 93 => Some(3),
        20..=25 | 36 | 37 => Some(2),
        26..=28 => Some(1),
        _ => None,
    }
}

/// Accumulates what the section readers find and turns it into a [`Mesh`].
#[derive(Default)]
struct Builder {
    mesh: Mesh,
    /// File node tag → dense index.
    index: HashMap<u64, u32>,
    /// `$PhysicalNames`: (dim, tag) → name.
    names: HashMap<(u8, i32), String>,
    /// Physical group (dim, tag) → its cells.
    members: BTreeMap<(u8, i32), Vec<CellRef>>,
    /// (kind, sorted nodes) → the cell: an element written twice is one cell.
    cell_by_nodes: HashMap<(CellKind, Box<[u32]>), (CellRef, u64)>,
    /// Element tag → the cell.
    cell_by_tag: HashMap<u64, CellRef>,
    /// Duplicates merged that are not gmsh's own repeats: (first tag, repeated tag).
    merged: Vec<(u64, u64)>,
}

impl Builder {
    /// Reserve room for `n` more nodes (`n` already checked against the file size).
    fn reserve_nodes(&mut self, n: usize) {
        self.mesh.nodes.reserve(n);
        self.mesh.node_tags.reserve(n);
        self.index.reserve(n);
    }

    /// Add a node; its dense index is the number of nodes read before it.
    fn add_node(&mut self, cur: &Cursor, tag: u64, x: [f64; 3]) -> Result<()> {
        let i =
            u32::try_from(self.mesh.nodes.len()).map_err(|_| cur.err("more than 2^32 - 1 nodes are not supported"))?;
        if self.index.insert(tag, i).is_some() {
            return Err(cur.err(format!("node {tag} is defined twice")));
        }
        self.mesh.nodes.push(x);
        self.mesh.node_tags.push(tag);
        Ok(())
    }

    /// Dense index of node `tag`, referenced by element `elem`.
    fn node(&self, cur: &Cursor, elem: u64, tag: u64) -> Result<u32> {
        self.index
            .get(&tag)
            .copied()
            .ok_or_else(|| cur.err(format!("element {elem} references node {tag}, which is not in $Nodes")))
    }

    /// Append a cell of `kind` with dense node indices `nodes`, or return the cell already read
    /// with the same kind and nodes (in any order: the same element written twice, e.g. once
    /// per physical group) with `true`. An element tag used for two different cells is an error.
    fn add_cell(&mut self, cur: &Cursor, kind: CellKind, tag: u64, nodes: &[u32]) -> Result<(CellRef, bool)> {
        let mut key: Box<[u32]> = nodes.into();
        key.sort_unstable();
        if let Some(&(cell, first_tag)) = self.cell_by_nodes.get(&(kind, key.clone())) {
            match self.cell_by_tag.get(&tag) {
                Some(&c) if c != cell => {
                    return Err(cur.err(format!("element tag {tag} is used for two different elements")));
                }
                Some(_) => {}
                None => {
                    self.cell_by_tag.insert(tag, cell);
                }
            }
            let _ = first_tag;
            return Ok((cell, true));
        }
        if self.cell_by_tag.contains_key(&tag) {
            return Err(cur.err(format!("element tag {tag} is used for two different elements")));
        }
        let block = self.mesh.block_index_mut(kind);
        let blk = &mut self.mesh.blocks[block];
        let index =
            u32::try_from(blk.len()).map_err(|_| cur.err("more than 2^32 - 1 cells of one kind are not supported"))?;
        blk.push(nodes, tag);
        let cell = CellRef {
            block: block as u32,
            index,
        };
        self.cell_by_nodes.insert((kind, key), (cell, tag));
        self.cell_by_tag.insert(tag, cell);
        Ok((cell, false))
    }

    /// Note that element `tag` repeats the cell first read as `cell` (not a gmsh repeat for
    /// another physical group): it is counted once.
    fn note_merged(&mut self, cell: CellRef, tag: u64) {
        let first = self.mesh.blocks[cell.block as usize].tags[cell.index as usize];
        self.merged.push((first, tag));
    }

    /// Record that `cell` belongs to physical group (`dim`, `tag`).
    fn add_to_group(&mut self, dim: u8, tag: i32, cell: CellRef) {
        self.members.entry((dim, tag)).or_default().push(cell);
    }

    /// Label of a physical group for messages: its name, else `"<dim>:<tag>"`.
    fn group_label(&self, dim: u8, tag: i32) -> String {
        self.names
            .get(&(dim, tag))
            .cloned()
            .unwrap_or_else(|| format!("{dim}:{tag}"))
    }

    /// The error for an element type outside [`CellKind`].
    fn unsupported(&self, path: &Path, gmsh_type: i32, group: String) -> Error {
        Error::UnsupportedElement {
            path: path.to_path_buf(),
            gmsh_type,
            name: gmsh_type_name(gmsh_type).to_string(),
            group,
        }
    }

    /// Build the mesh: groups from names and memberships, scaled coordinates.
    fn finish(self, path: &Path, length_scale: f64) -> Result<Mesh> {
        let Builder {
            mut mesh,
            names,
            mut members,
            merged,
            ..
        } = self;
        if !merged.is_empty() {
            let shown: Vec<String> = merged
                .iter()
                .take(5)
                .map(|(a, b)| {
                    if a == b {
                        format!("element {a} twice")
                    } else {
                        format!("element {b} = element {a}")
                    }
                })
                .collect();
            mesh.notes.push(format!(
                "{}: {} elements repeat another (same type and nodes) and are counted once: {}{}",
                path.display(),
                merged.len(),
                shown.join(", "),
                if merged.len() > 5 { ", ..." } else { "" }
            ));
        }
        if mesh.blocks.iter().all(|b| b.is_empty()) {
            return Err(Error::EmptyModel {
                what: format!("{}: the mesh file contains no elements", path.display()),
            });
        }
        // Groups named in $PhysicalNames but without elements are kept (empty), so that a
        // scene naming them gets a clear message later rather than "unknown group".
        for key in names.keys() {
            members.entry(*key).or_default();
        }
        mesh.groups = members
            .into_iter()
            .map(|((dim, tag), mut cells)| {
                cells.sort_unstable();
                cells.dedup();
                let name = names
                    .get(&(dim, tag))
                    .cloned()
                    .unwrap_or_else(|| format!("{dim}:{tag}"));
                Group { name, dim, tag, cells }
            })
            .collect();
        if length_scale != 1.0 {
            mesh.scale(length_scale);
        }
        Ok(mesh)
    }
}
