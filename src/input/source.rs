//! Where a mesh comes from: a gmsh file, or a built-in generator. One grammar for the command
//! line, scene files, studies and the bindings.
//!
//! | spec | mesh | groups |
//! |---|---|---|
//! | `box:LX,LY,LZ:NX,NY,NZ:KIND` | structured box of solid cells ([`crate::mesh::generate::box_mesh`]), e.g. `box:0.3,0.3,0.02:20,20,4:hex20` | `volume`, `xmin`, `xmax`, `ymin`, `ymax`, `zmin`, `zmax` |
//! | `helix:D,PITCH,TURNS,ELEMENTS_PER_TURN[,line3]` | helical coil centreline of line cells ([`crate::mesh::parametric::helix_beam`]) | `wire`, `end_bottom`, `end_top` |
//! | `sandwich:paper[,SIZE]` | the double-T work table of the paper as quad4 shells ([`crate::mesh::parametric::sandwich_table`]) | `top_plate`, `bottom_plate`, `webs_long`, `table`, … |
//! | `ibeam-line:LENGTH,N` | a straight beam line | `beam`, `end_a`, `end_b` |
//! | `ibeam-shell:H,B,S,T,LENGTH,SIZE` | an I-beam of quad4 shells | `flange_top`, `flange_bottom`, `web`, `beam` |
//! | `ibeam-solid:H,B,S,T,LENGTH,SIZE,KIND` | an I-beam of solid cells | as `ibeam-shell` |
//! | anything else | a gmsh MSH 2.2 or 4.1 file (ASCII or binary) | its physical groups |
//!
//! Sizes are in the length unit given (`length_scale` converts them to metres, so
//! `--length-unit mm` works with `box:300,...` as with a file drawn in millimetres).

use crate::mesh::{CellKind, Mesh, generate};
use crate::{Error, Result};
use std::path::Path;

/// The generator prefixes, for messages.
pub const GENERATORS: &str = "box:, helix:, sandwich:, ibeam-line:, ibeam-shell:, ibeam-solid:";

/// True if `spec` names a built-in generator rather than a file.
pub fn is_generator(spec: &str) -> bool {
    [
        "box:",
        "helix:",
        "sandwich:",
        "ibeam-line:",
        "ibeam-shell:",
        "ibeam-solid:",
    ]
    .iter()
    .any(|p| spec.starts_with(p))
}

/// Load a mesh from a file path or a generator spec (see the module table); `length_scale`
/// converts the spec's lengths, or the file's coordinates, to metres. A spec that is neither a
/// generator nor an existing file is an error that lists the generators.
pub fn load(spec: &str, length_scale: f64) -> Result<Mesh> {
    if let Some(m) = structured(spec, length_scale)? {
        return Ok(m);
    }
    if let Some(m) = parametric(spec, length_scale)? {
        return Ok(m);
    }
    let path = Path::new(spec);
    if !path.exists() {
        if let Some((prefix, _)) = spec.split_once(':') {
            if !prefix.is_empty() && !prefix.contains(['/', '\\', '.']) {
                return Err(Error::param(
                    "spec",
                    format!("unknown generator '{spec}' (known generators: {GENERATORS}); no file of that name either"),
                ));
            }
        }
    }
    let mut mesh = crate::io::gmsh::read(path, length_scale)?;
    if let Some(note) = unit_hint(&mesh, length_scale) {
        mesh.notes.push(note);
    }
    Ok(mesh)
}

/// Largest extent, m, of a mesh read in metres that passes for one of this tool's machines; a
/// larger one is most often a drawing in millimetres read as metres.
const UNIT_HINT_EXTENT: f64 = 50.0;

/// A note when a file read in metres (`length_scale` 1) is more than [`UNIT_HINT_EXTENT`]
/// across: the unit the file was drawn in is not in it, so the reader can only ask.
fn unit_hint(mesh: &Mesh, length_scale: f64) -> Option<String> {
    if length_scale != 1.0 || mesh.n_nodes() == 0 {
        return None;
    }
    let (lo, hi) = mesh.bounding_box();
    let extent = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    (extent > UNIT_HINT_EXTENT).then(|| {
        format!(
            "the mesh is {} m across, read in metres: if it was drawn in millimetres, give --length-unit mm",
            crate::io::fmt_short(extent, 4)
        )
    })
}

/// The `sandwich:` and `ibeam-*` generators; `None` for any other spec.
fn parametric(spec: &str, length_scale: f64) -> Result<Option<Mesh>> {
    use crate::mesh::parametric as pm;
    let nums = |rest: &str, n: usize, usage: &str| -> Result<Vec<f64>> {
        let v: std::result::Result<Vec<f64>, _> = rest.split(',').map(|s| s.trim().parse::<f64>()).collect();
        match v {
            Ok(v) if v.len() == n && v.iter().all(|x| x.is_finite()) => Ok(v),
            _ => Err(Error::param("spec", format!("generator '{spec}': expected {usage}"))),
        }
    };
    let mut m = if let Some(sw) = SandwichSpec::parse(spec)? {
        pm::sandwich_table(&sw.params())?
    } else if let Some(rest) = spec.strip_prefix("ibeam-line:") {
        let v = nums(rest, 2, "ibeam-line:LENGTH,N_ELEMENTS")?;
        if v[1] < 1.0 || v[1].fract() != 0.0 {
            return Err(Error::param(
                "spec",
                format!("generator '{spec}': the element count must be a whole number ≥ 1"),
            ));
        }
        pm::i_beam_line(v[0], v[1] as usize)?
    } else if let Some(rest) = spec.strip_prefix("ibeam-shell:") {
        let v = nums(rest, 6, "ibeam-shell:H,B,S,T,LENGTH,ELEMENT_SIZE")?;
        pm::i_beam_shell(v[0], v[1], v[2], v[3], v[4], v[5])?
    } else if let Some(rest) = spec.strip_prefix("ibeam-solid:") {
        let (nums_part, kind) = rest.rsplit_once(',').unwrap_or((rest, ""));
        let v = nums(nums_part, 6, "ibeam-solid:H,B,S,T,LENGTH,ELEMENT_SIZE,KIND")?;
        let kind = CellKind::SOLIDS
            .iter()
            .copied()
            .find(|k| k.name() == kind.trim())
            .ok_or_else(|| Error::param("spec", format!("generator '{spec}': unknown cell kind '{kind}'")))?;
        pm::i_beam_solid(v[0], v[1], v[2], v[3], v[4], v[5], kind)?
    } else {
        return Ok(None);
    };
    m.scale(length_scale);
    Ok(Some(m))
}

/// The `box:` and `helix:` generators; `None` for any other spec.
fn structured(spec: &str, length_scale: f64) -> Result<Option<Mesh>> {
    if let Some(b) = BoxSpec::parse(spec)? {
        return b.mesh(length_scale).map(Some);
    }
    if let Some(h) = HelixSpec::parse(spec)? {
        return h.mesh(length_scale).map(Some);
    }
    Ok(None)
}

/// A `box:LX,LY,LZ:NX,NY,NZ:KIND` spec: a structured box of solid cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxSpec {
    /// Edge lengths (in the spec's length unit).
    pub size: [f64; 3],
    /// Divisions along x, y, z.
    pub divisions: [usize; 3],
    /// Solid cell kind.
    pub kind: CellKind,
}

impl BoxSpec {
    /// The spec parsed; `None` if `spec` is not a `box:` spec.
    pub fn parse(spec: &str) -> Result<Option<BoxSpec>> {
        let Some(rest) = spec.strip_prefix("box:") else {
            return Ok(None);
        };
        let bad = |why: &str| {
            Error::param(
                "spec",
                format!(
                    "mesh '{spec}': {why}; expected box:LX,LY,LZ:NX,NY,NZ:KIND, e.g. box:0.3,0.3,0.02:20,20,4:hex20"
                ),
            )
        };
        let parts: Vec<&str> = rest.split(':').collect();
        if parts.len() != 3 {
            return Err(bad("three ':'-separated fields needed"));
        }
        let size: Vec<f64> = parts[0]
            .split(',')
            .map(|s| s.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| bad("sizes must be numbers"))?;
        let n: Vec<usize> = parts[1]
            .split(',')
            .map(|s| s.trim().parse::<usize>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| bad("divisions must be whole numbers"))?;
        if size.len() != 3 || n.len() != 3 {
            return Err(bad("three sizes and three divisions needed"));
        }
        let kind = CellKind::SOLIDS
            .iter()
            .copied()
            .find(|k| k.name() == parts[2].trim())
            .ok_or_else(|| bad("unknown cell kind (tet4, tet10, hex8, hex20, hex27, wedge6, wedge15)"))?;
        Ok(Some(BoxSpec {
            size: [size[0], size[1], size[2]],
            divisions: [n[0], n[1], n[2]],
            kind,
        }))
    }

    /// The mesh, lengths scaled to metres by `length_scale`.
    pub fn mesh(&self, length_scale: f64) -> Result<Mesh> {
        let s = self.size.map(|x| x * length_scale);
        generate::try_box_mesh(self.kind, s, self.divisions)
    }
}

impl std::fmt::Display for BoxSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [lx, ly, lz] = self.size;
        let [nx, ny, nz] = self.divisions;
        write!(f, "box:{lx},{ly},{lz}:{nx},{ny},{nz}:{}", self.kind.name())
    }
}

/// A `helix:D,PITCH,TURNS,ELEMENTS_PER_TURN[,KIND]` spec: a helical coil centreline of line
/// cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HelixSpec {
    /// Mean coil diameter (in the spec's length unit).
    pub diameter: f64,
    /// Pitch (in the spec's length unit).
    pub pitch: f64,
    /// Number of turns.
    pub turns: f64,
    /// Elements per turn.
    pub per_turn: usize,
    /// `line2` or `line3`, if written (default `line2`).
    pub kind: Option<CellKind>,
}

impl HelixSpec {
    /// The spec parsed; `None` if `spec` is not a `helix:` spec.
    pub fn parse(spec: &str) -> Result<Option<HelixSpec>> {
        let Some(rest) = spec.strip_prefix("helix:") else {
            return Ok(None);
        };
        let parts: Vec<&str> = rest.split(',').map(str::trim).collect();
        let bad = |why: &str| {
            Error::param(
                "spec",
                format!(
                    "mesh '{spec}': {why}; expected helix:D,PITCH,TURNS,ELEMENTS_PER_TURN[,line3], e.g. helix:0.032,0.01,6,24"
                ),
            )
        };
        if parts.len() != 4 && parts.len() != 5 {
            return Err(bad("four or five fields needed"));
        }
        let num = |i: usize| parts[i].parse::<f64>().map_err(|_| bad("numbers expected"));
        let kind = match parts.get(4) {
            None => None,
            Some(&"line2") => Some(CellKind::Line2),
            Some(&"line3") => Some(CellKind::Line3),
            Some(_) => return Err(bad("the element kind is line2 or line3")),
        };
        let per_turn = parts[3]
            .parse::<usize>()
            .map_err(|_| bad("elements per turn must be a whole number"))?;
        Ok(Some(HelixSpec {
            diameter: num(0)?,
            pitch: num(1)?,
            turns: num(2)?,
            per_turn,
            kind,
        }))
    }

    /// The mesh, lengths scaled to metres by `length_scale`.
    pub fn mesh(&self, length_scale: f64) -> Result<Mesh> {
        let p = crate::mesh::parametric::HelixParams {
            mean_diameter: self.diameter * length_scale,
            pitch: self.pitch * length_scale,
            turns: self.turns,
            elems_per_turn: self.per_turn,
            // The wire diameter belongs to the beam section (--beam); the generator only checks
            // that coils do not touch, so give it a value below the pitch.
            wire_diameter: 0.5 * self.pitch * length_scale,
            kind: self.kind.unwrap_or(CellKind::Line2),
        };
        crate::mesh::parametric::helix_beam(&p)
    }
}

impl std::fmt::Display for HelixSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "helix:{},{},{},{}",
            self.diameter, self.pitch, self.turns, self.per_turn
        )?;
        match self.kind {
            Some(k) => write!(f, ",{}", k.name()),
            None => Ok(()),
        }
    }
}

/// A `sandwich:paper[,ELEMENT_SIZE]` spec: the paper's work table as quad4 shells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SandwichSpec {
    /// Shell element size (in the spec's length unit), if written (default: the paper
    /// reconstruction's, [`crate::mesh::parametric::SandwichParams::paper`]).
    pub elem_size: Option<f64>,
}

impl SandwichSpec {
    /// The spec parsed; `None` if `spec` is not a `sandwich:` spec.
    pub fn parse(spec: &str) -> Result<Option<SandwichSpec>> {
        let Some(rest) = spec.strip_prefix("sandwich:") else {
            return Ok(None);
        };
        let mut it = rest.splitn(2, ',');
        let preset = it.next().unwrap_or("").trim();
        if preset != "paper" {
            return Err(Error::param(
                "spec",
                format!("generator '{spec}': the sandwich preset is 'paper' (sandwich:paper[,ELEMENT_SIZE])"),
            ));
        }
        let elem_size = match it.next() {
            None => None,
            Some(h) => match h.trim().parse::<f64>() {
                Ok(x) if x.is_finite() => Some(x),
                _ => {
                    return Err(Error::param(
                        "spec",
                        format!("generator '{spec}': expected sandwich:paper[,ELEMENT_SIZE]"),
                    ));
                }
            },
        };
        Ok(Some(SandwichSpec { elem_size }))
    }

    /// The table's parameters: the paper reconstruction with this element size.
    pub fn params(&self) -> crate::mesh::parametric::SandwichParams {
        let mut p = crate::mesh::parametric::SandwichParams::paper();
        if let Some(h) = self.elem_size {
            p.elem_size = h;
        }
        p
    }
}

impl std::fmt::Display for SandwichSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.elem_size {
            Some(h) => write!(f, "sandwich:paper,{h}"),
            None => write!(f, "sandwich:paper"),
        }
    }
}
