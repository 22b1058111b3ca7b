//! Where a mesh comes from: a gmsh file, or a built-in structured generator.
//!
//! A mesh argument of the form `box:LX,LY,LZ:NX,NY,NZ:KIND` (metres, divisions, cell kind,
//! e.g. `box:0.3,0.3,0.02:20,20,4:hex20`) builds a structured box mesh with the groups
//! `volume`, `xmin`, `xmax`, `ymin`, `ymax`, `zmin` and `zmax` (see
//! [`crate::mesh::generate::box_mesh`]); `helix:D,PITCH,TURNS,ELEMENTS_PER_TURN[,line3]` builds a
//! helical coil centreline of line cells (groups `wire`, `end_bottom`, `end_top`; see
//! [`crate::mesh::parametric::helix_beam`]); anything else is a gmsh file path.

use crate::mesh::{CellKind, Mesh, generate};
use crate::{Error, Result};
use std::path::Path;

/// Load a mesh from a file path or a generator spec; `length_scale` converts file units to
/// metres (a generator's sizes are scaled too, so `--length-unit mm` works with `box:300,...`).
pub fn load(spec: &str, length_scale: f64) -> Result<Mesh> {
    if let Some(rest) = spec.strip_prefix("box:") {
        let bad = |why: &str| {
            Error::InvalidInput(format!(
                "mesh '{spec}': {why}; expected box:LX,LY,LZ:NX,NY,NZ:KIND, e.g. box:0.3,0.3,0.02:20,20,4:hex20"
            ))
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
        return generate::try_box_mesh(kind, s, [n[0], n[1], n[2]]);
    }
    if let Some(rest) = spec.strip_prefix("helix:") {
        // helix:D,PITCH,TURNS,ELEMENTS_PER_TURN[,line3]
        let parts: Vec<&str> = rest.split(',').map(str::trim).collect();
        let bad = |why: &str| {
            Error::InvalidInput(format!(
                "mesh '{spec}': {why}; expected helix:D,PITCH,TURNS,ELEMENTS_PER_TURN[,line3], e.g. helix:0.032,0.01,6,24"
            ))
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
        return crate::mesh::parametric::helix_beam(&p);
    }
    crate::io::gmsh::read(Path::new(spec), length_scale)
}
