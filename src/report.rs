//! Human-readable reports: the mode table and the mesh summary.

use crate::analysis::ModalReport;
use crate::element::solid;
use crate::material::Material;
use crate::mesh::Mesh;
use crate::{Error, Result};
use serde::Serialize;
use std::fmt::Write;

/// The table `vibrofem modes` prints.
pub fn modal_table(r: &ModalReport) -> String {
    let mut s = String::new();
    let cells: Vec<String> = r.cells.iter().map(|(k, n)| format!("{n} {k}")).collect();
    let _ = writeln!(s, "mesh     {}", r.mesh);
    let _ = writeln!(
        s,
        "model    {} nodes, {}, {} free DOFs, {} mass",
        r.nodes,
        cells.join(", "),
        r.dofs,
        r.mass_matrix
    );
    let _ = writeln!(s, "mass     {:.6} kg   volume {:.6e} m³", r.mass_kg, r.volume_m3);
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "{:>5} {:>16} {:>8} {:>10}   {:>7} {:>7} {:>7}",
        "mode", "frequency [Hz]", "kind", "residual", "cum.X", "cum.Y", "cum.Z"
    );
    for m in &r.modes {
        let _ = writeln!(
            s,
            "{:>5} {:>16.6} {:>8} {:>10.2e}   {:>7.4} {:>7.4} {:>7.4}",
            m.mode,
            m.frequency_hz,
            m.kind,
            m.rel_residual,
            m.cumulative_ratio[0],
            m.cumulative_ratio[1],
            m.cumulative_ratio[2]
        );
    }
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "rigid-body modes: {}   elastic: {}",
        r.n_rigid,
        r.modes.len().saturating_sub(r.n_rigid)
    );
    let _ = writeln!(
        s,
        "complete: {}  (Sturm count {} eigenvalues below {:.6} Hz, {} found between the check points)",
        if r.complete { "yes" } else { "NO" },
        r.sturm.upper.1,
        crate::post::modal::hz(r.sturm.upper.0),
        r.sturm.found
    );
    let _ = writeln!(
        s,
        "accuracy: {}  (max residual {:.2e}, M-orthonormality {:.1e})",
        if r.accurate { "ok" } else { "NOT GUARANTEED" },
        r.max_rel_residual,
        r.m_orthonormality
    );
    let t = &r.timings_s;
    let _ = writeln!(
        s,
        "time [s]: read {:.3}  assemble {:.3}  order {:.3}  factor {:.3}  solve {:.3}  verify {:.3}  total {:.3}",
        t.read, t.assemble, t.order, t.factor, t.solve, t.verify, t.total
    );
    let _ = writeln!(
        s,
        "factor: {} entries, {:.3e} flop ({:.2} GFLOP/s); peak memory {}",
        r.factor_nnz,
        r.factor_flops,
        r.factor_gflops,
        r.peak_memory_bytes
            .map_or("n/a".into(), |b| format!("{:.1} MiB", b as f64 / 1048576.0))
    );
    s
}

/// One group of the mesh summary.
#[derive(Clone, Debug, Serialize)]
pub struct GroupInfo {
    /// Name.
    pub name: String,
    /// Dimension.
    pub dim: u8,
    /// Physical tag.
    pub tag: i32,
    /// Cells.
    pub cells: usize,
    /// Nodes.
    pub nodes: usize,
}

/// What `vibrofem mesh-info` reports.
#[derive(Clone, Debug, Serialize)]
pub struct MeshInfo {
    /// File.
    pub mesh: String,
    /// Node count.
    pub nodes: usize,
    /// Cells per kind (all dimensions).
    pub cells: Vec<(String, usize)>,
    /// Physical groups.
    pub groups: Vec<GroupInfo>,
    /// Bounding box min, m.
    pub bbox_min: [f64; 3],
    /// Bounding box max, m.
    pub bbox_max: [f64; 3],
    /// Volume of the 3D cells, m³.
    pub volume_m3: f64,
    /// Mass of the 3D cells with the given density, kg.
    pub mass_kg: f64,
    /// Density used, kg/m³.
    pub density: f64,
}

/// Summarise a mesh.
pub fn mesh_info(mesh: &Mesh, source: &str, mat: &Material) -> Result<MeshInfo> {
    let (lo, hi) = mesh.bounding_box();
    let mut volume = 0.0;
    let mut x = [[0.0; 3]; 27];
    for b in mesh.blocks.iter().filter(|b| b.kind.dim() == 3) {
        let nn = b.kind.n_nodes();
        for e in 0..b.len() {
            for (o, &a) in x.iter_mut().zip(b.cell(e)) {
                *o = mesh.nodes[a as usize];
            }
            volume += solid::volume(b.kind, &x[..nn]).map_err(|det| Error::InvertedElement {
                element: b.tags[e],
                kind: b.kind.name(),
                det,
            })?;
        }
    }
    Ok(MeshInfo {
        mesh: source.into(),
        nodes: mesh.n_nodes(),
        cells: mesh
            .blocks
            .iter()
            .map(|b| (b.kind.name().to_string(), b.len()))
            .collect(),
        groups: mesh
            .groups
            .iter()
            .map(|g| GroupInfo {
                name: g.name.clone(),
                dim: g.dim,
                tag: g.tag,
                cells: g.cells.len(),
                nodes: mesh.group_nodes(g).len(),
            })
            .collect(),
        bbox_min: lo,
        bbox_max: hi,
        volume_m3: volume,
        mass_kg: volume * mat.density,
        density: mat.density,
    })
}

/// Text form of [`MeshInfo`].
pub fn mesh_info_text(i: &MeshInfo) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "mesh    {}", i.mesh);
    let _ = writeln!(s, "nodes   {}", i.nodes);
    for (k, n) in &i.cells {
        let _ = writeln!(s, "cells   {n:>10} {k}");
    }
    let _ = writeln!(s, "groups  {}", if i.groups.is_empty() { "(none)" } else { "" });
    for g in &i.groups {
        let _ = writeln!(
            s,
            "  {:<24} dim {}  tag {:>4}  {:>9} cells  {:>9} nodes",
            g.name, g.dim, g.tag, g.cells, g.nodes
        );
    }
    let _ = writeln!(
        s,
        "bbox    [{:.6}, {:.6}, {:.6}] .. [{:.6}, {:.6}, {:.6}] m",
        i.bbox_min[0], i.bbox_min[1], i.bbox_min[2], i.bbox_max[0], i.bbox_max[1], i.bbox_max[2]
    );
    let _ = writeln!(
        s,
        "size    {:.6} x {:.6} x {:.6} m",
        i.bbox_max[0] - i.bbox_min[0],
        i.bbox_max[1] - i.bbox_min[1],
        i.bbox_max[2] - i.bbox_min[2]
    );
    let _ = writeln!(s, "volume  {:.6e} m³", i.volume_m3);
    let _ = writeln!(s, "mass    {:.6} kg (density {} kg/m³)", i.mass_kg, i.density);
    s
}
