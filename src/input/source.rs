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
    crate::io::gmsh::read(path, length_scale)
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
    let mut m = if let Some(rest) = spec.strip_prefix("sandwich:") {
        let mut it = rest.splitn(2, ',');
        let preset = it.next().unwrap_or("").trim();
        if preset != "paper" {
            return Err(Error::param(
                "spec",
                format!("generator '{spec}': the sandwich preset is 'paper' (sandwich:paper[,ELEMENT_SIZE])"),
            ));
        }
        let mut p = pm::SandwichParams::paper();
        if let Some(h) = it.next() {
            p.elem_size = nums(h, 1, "sandwich:paper[,ELEMENT_SIZE]")?[0];
        }
        pm::sandwich_table(&p)?
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
    if let Some(rest) = spec.strip_prefix("box:") {
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
        let s = [size[0] * length_scale, size[1] * length_scale, size[2] * length_scale];
        return generate::try_box_mesh(kind, s, [n[0], n[1], n[2]]).map(Some);
    }
    if let Some(rest) = spec.strip_prefix("helix:") {
        // helix:D,PITCH,TURNS,ELEMENTS_PER_TURN[,line3]
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
            None | Some(&"line2") => CellKind::Line2,
            Some(&"line3") => CellKind::Line3,
            Some(_) => return Err(bad("the element kind is line2 or line3")),
        };
        let per_turn = parts[3]
            .parse::<usize>()
            .map_err(|_| bad("elements per turn must be a whole number"))?;
        let p = crate::mesh::parametric::HelixParams {
            mean_diameter: num(0)? * length_scale,
            pitch: num(1)? * length_scale,
            turns: num(2)?,
            elems_per_turn: per_turn,
            // The wire diameter belongs to the beam section (--beam); the generator only checks
            // that coils do not touch, so give it a value below the pitch.
            wire_diameter: 0.5 * num(1)? * length_scale,
            kind,
        };
        return crate::mesh::parametric::helix_beam(&p).map(Some);
    }
    Ok(None)
}
