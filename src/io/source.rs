//! Where a mesh comes from: a gmsh file, or a built-in structured generator.
//!
//! A mesh argument of the form `box:LX,LY,LZ:NX,NY,NZ:KIND` (metres, divisions, cell kind,
//! e.g. `box:0.3,0.3,0.02:20,20,4:hex20`) builds a structured box mesh with the groups
//! `volume`, `xmin`, `xmax`, `ymin`, `ymax`, `zmin` and `zmax` (see
//! [`crate::mesh::generate::box_mesh`]); anything else is a gmsh file path.

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
    crate::io::gmsh::read(Path::new(spec), length_scale)
}
