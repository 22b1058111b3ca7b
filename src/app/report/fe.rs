//! Human-readable reports: the mode table and the mesh summary.

use crate::analysis::modal::ModalReport;
use crate::element::solid;
use crate::io::{fmt_fixed, fmt_plain};
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
    let _ = writeln!(
        s,
        "mass     {} kg   volume {:.6e} m³",
        fmt_fixed(r.mass_kg, 6),
        r.volume_m3
    );
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "{:>5} {:>16} {:>8} {:>10}   {:>7} {:>7} {:>7}",
        "mode", "frequency [Hz]", "kind", "residual", "cum.X", "cum.Y", "cum.Z"
    );
    for m in &r.modes {
        let _ = writeln!(
            s,
            "{:>5} {:>16} {:>8} {:>10.2e}   {:>7.4} {:>7.4} {:>7.4}",
            m.mode,
            fmt_fixed(m.frequency_hz, 6),
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
        "complete: {}  (Sturm count {} eigenvalues below {} Hz, {} found between the check points)",
        if r.complete { "yes" } else { "NO" },
        r.sturm.upper.1,
        fmt_fixed(crate::post::modal::hz(r.sturm.upper.0), 6),
        r.sturm.found
    );
    let _ = writeln!(
        s,
        "accuracy: {}  (max residual {:.2e}, backward error {:.1e}, M-orthonormality {:.1e})",
        if r.accurate { "ok" } else { "NOT GUARANTEED" },
        r.max_rel_residual,
        r.max_backward_error,
        r.m_orthonormality
    );
    let t = &r.timings_s;
    let _ = writeln!(
        s,
        "time [s]: read {:.3}  assemble {:.3}  order {:.3}  factor {:.3}  solve {:.3}  verify {:.3}  total {:.3}",
        t.read, t.assemble, t.order, t.factor, t.solve, t.verify, t.total
    );
    let peak = r
        .peak_memory_bytes
        .map_or("n/a".into(), |b| format!("{:.1} MiB", b as f64 / 1048576.0));
    if r.factor_nnz > 0 {
        let _ = writeln!(
            s,
            "factor: {} entries, {:.3e} flop ({:.2} GFLOP/s); peak memory {peak}",
            r.factor_nnz, r.factor_flops, r.factor_gflops,
        );
    } else {
        // Another engine factorised (SLEPc + MUMPS): this process only assembled and verified.
        let _ = writeln!(s, "factor: by the external engine; peak memory of this process {peak}");
    }
    s.push_str(&r.floor.as_ref().map_or(String::new(), |f| f.table()));
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
    /// Nodes that belong to no cell (left out of the bounding box).
    pub unused_nodes: usize,
    /// Bounding box of the nodes used by cells, min, m.
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
    // The bounding box of the nodes the cells use: a stray node far away (a construction
    // point, a node left from a deleted part) is not part of the model.
    let mut used = vec![false; mesh.n_nodes()];
    for b in &mesh.blocks {
        for e in 0..b.len() {
            for &a in b.cell(e) {
                used[a as usize] = true;
            }
        }
    }
    let unused_nodes = used.iter().filter(|u| !**u).count();
    let (lo, hi) = if unused_nodes == 0 || unused_nodes == used.len() {
        mesh.bounding_box()
    } else {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (x, _) in mesh.nodes.iter().zip(&used).filter(|(_, u)| **u) {
            for d in 0..3 {
                lo[d] = lo[d].min(x[d]);
                hi[d] = hi[d].max(x[d]);
            }
        }
        (lo, hi)
    };
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
                file: Some(source.to_string()),
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
        unused_nodes,
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
    if i.unused_nodes > 0 {
        let _ = writeln!(
            s,
            "nodes   {} ({} belong to no element: left out of the bounding box and the model)",
            i.nodes, i.unused_nodes
        );
    } else {
        let _ = writeln!(s, "nodes   {}", i.nodes);
    }
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
        "bbox    [{}] .. [{}] m",
        fixed3(i.bbox_min, 6),
        fixed3(i.bbox_max, 6)
    );
    let _ = writeln!(
        s,
        "size    {} m",
        (0..3)
            .map(|k| fmt_fixed(i.bbox_max[k] - i.bbox_min[k], 6))
            .collect::<Vec<_>>()
            .join(" x ")
    );
    let _ = writeln!(s, "volume  {:.6e} m³", i.volume_m3);
    let _ = writeln!(
        s,
        "mass    {} kg (density {} kg/m³)",
        fmt_fixed(i.mass_kg, 6),
        fmt_plain(i.density)
    );
    s
}

/// Stress summary of one load case.
#[derive(Clone, Debug, Serialize)]
pub struct StressSummary {
    /// Maximum von Mises (averaged nodal) per group and overall.
    pub von_mises: Vec<crate::post::stress::GroupMax>,
    /// Maximum unaveraged element von Mises at nodes, overall.
    pub von_mises_unaveraged: Vec<crate::post::stress::GroupMax>,
    /// Maximum Tresca per group and overall.
    pub tresca: Vec<crate::post::stress::GroupMax>,
    /// Maximum shear stress (Tresca/2) per group and overall.
    pub max_shear: Vec<crate::post::stress::GroupMax>,
    /// Shells: maximum von Mises (averaged nodal) on the top face (the side of the normal),
    /// per group and overall; absent without shells.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub shell_von_mises_top: Vec<crate::post::stress::GroupMax>,
    /// Shells: the same on the bottom face.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub shell_von_mises_bottom: Vec<crate::post::stress::GroupMax>,
    /// Beams: the largest normal stress at the extreme fibres, overall (`"(all)"`) and per
    /// beam group, with the element's resultants there; absent without beam stresses.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub beam_normal_stress: Vec<crate::post::stress::BeamMax>,
    /// Beams of round section: the largest torsion shear stress `T r / J`, in the same form.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub beam_torsion_shear: Vec<crate::post::stress::BeamMax>,
}

/// The `--json` document of `vibrofem static`.
#[derive(Clone, Debug, Serialize)]
pub struct StaticReport {
    /// Mesh.
    pub mesh: String,
    /// Free equations.
    pub dofs: usize,
    /// Load cases.
    pub cases: Vec<crate::analysis::statics::CaseReport>,
    /// Stress summaries per case.
    pub stress: Vec<StressSummary>,
    /// Wall time of assembly, factorisation, solution and post-processing, s.
    pub timings_s: crate::analysis::statics::StaticTimings,
    /// Notes.
    pub notes: Vec<String>,
}

/// Displacements of the mesh nodes (3 per node) from a raw solution.
pub fn mesh_displacements(run: &crate::analysis::statics::StaticRun, case: usize) -> Vec<f64> {
    crate::dof::node_triplets(&run.u[case], run.model.n_mesh_nodes, 0)
}

/// The stresses of one load case of a static run, recovered once for the report and the files.
pub struct CaseStresses {
    /// The solids' nodal stresses (zero at nodes of no solid element).
    pub solids: crate::post::stress::NodalStress,
    /// The shells' on both faces, where the model has shells.
    pub shells: Option<crate::post::stress::ShellFaces>,
    /// The beams', where the model has beams.
    pub beams: Option<crate::post::stress::BeamStress>,
}

/// The stresses of every load case of `run` ([`CaseStresses`]).
pub fn case_stresses(mesh: &Mesh, run: &crate::analysis::statics::StaticRun) -> Result<Vec<CaseStresses>> {
    use crate::post::stress::{beam_stress, nodal_stress, shell_face_stress};
    let n = run.model.n_mesh_nodes;
    (0..run.cases.len())
        .map(|ci| {
            Ok(CaseStresses {
                solids: nodal_stress(&run.model.solids, n, &mesh_displacements(run, ci))?,
                shells: shell_face_stress(&run.model.shells, n, &run.u[ci])?,
                beams: beam_stress(&run.model.beams, mesh, &run.u[ci])?,
            })
        })
        .collect()
}

/// Build the static report from the run and its stresses ([`case_stresses`]).
pub fn static_report(
    mesh: &Mesh,
    source: &str,
    run: &crate::analysis::statics::StaticRun,
    stresses: &[CaseStresses],
) -> Result<StaticReport> {
    use crate::post::stress::{StressField, group_maxima};
    let mut stress = Vec::new();
    let mut notes = run.model.notes.clone();
    for (ci, cs) in stresses.iter().enumerate() {
        let ns = &cs.solids;
        let (shell_von_mises_top, shell_von_mises_bottom) = match &cs.shells {
            Some(f) => (
                group_maxima(mesh, &f.top, StressField::VonMises)?,
                group_maxima(mesh, &f.bottom, StressField::VonMises)?,
            ),
            None => (Vec::new(), Vec::new()),
        };
        let beams = cs.beams.as_ref();
        if ci == 0 {
            notes.extend(beams.iter().flat_map(|b| b.notes.iter().cloned()));
        }
        stress.push(StressSummary {
            shell_von_mises_top,
            shell_von_mises_bottom,
            beam_normal_stress: beams.map(|b| b.normal_max.clone()).unwrap_or_default(),
            beam_torsion_shear: beams.map(|b| b.torsion_max.clone()).unwrap_or_default(),
            von_mises: group_maxima(mesh, ns, StressField::VonMises)?,
            von_mises_unaveraged: group_maxima(mesh, ns, StressField::VonMisesMaxUnaveraged)?
                .into_iter()
                .filter(|g| g.group == "(all)")
                .collect(),
            tresca: group_maxima(mesh, ns, StressField::Tresca)?,
            max_shear: group_maxima(mesh, ns, StressField::MaxShear)?,
        });
    }
    Ok(StaticReport {
        mesh: source.into(),
        dofs: run.dofs,
        cases: run.cases.clone(),
        stress,
        timings_s: run.timings,
        notes,
    })
}

/// A point's three coordinates with `decimals` decimals each ([`fmt_fixed`]), comma-separated.
fn fixed3(p: [f64; 3], decimals: usize) -> String {
    p.iter().map(|&x| fmt_fixed(x, decimals)).collect::<Vec<_>>().join(", ")
}

/// Text form of a static report.
pub fn static_text(r: &StaticReport) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "mesh     {}", r.mesh);
    let _ = writeln!(s, "model    {} free DOFs", r.dofs);
    for (ci, c) in r.cases.iter().enumerate() {
        let _ = writeln!(s);
        let _ = writeln!(s, "load case {}", ci + 1);
        for n in &c.notes {
            let _ = writeln!(s, "  note: {n}");
        }
        let _ = writeln!(
            s,
            "  applied force   [{:.6e}, {:.6e}, {:.6e}] N",
            c.applied.force[0], c.applied.force[1], c.applied.force[2]
        );
        if c.max_displacement.0 > 0.0 {
            let _ = writeln!(
                s,
                "  max |u|         {:.6e} m at node {}",
                c.max_displacement.0, c.max_displacement.1
            );
        } else {
            // No node moves (no load and no prescribed motion): no node to name.
            let _ = writeln!(s, "  max |u|         0 m (nothing moves: the case has no load)");
        }
        for rf in &c.references {
            let d = rf.displacement;
            let _ = writeln!(
                s,
                "  reference '{}': u = [{:.6e}, {:.6e}, {:.6e}] m, rot = [{:.3e}, {:.3e}, {:.3e}] rad",
                rf.group, d[0], d[1], d[2], d[3], d[4], d[5]
            );
            if let Some(k) = rf.stiffness {
                let _ = writeln!(s, "    stiffness along the guided axis: {k:.6e} N/m");
            }
        }
        for re in &c.reactions {
            let f = re.resultant.force;
            let _ = writeln!(
                s,
                "  reaction '{}': F = [{:.6e}, {:.6e}, {:.6e}] N",
                re.group, f[0], f[1], f[2]
            );
        }
        let _ = writeln!(s, "  equilibrium     |ΣR + ΣF| / |F| = {:.2e}", c.equilibrium_error);
        let _ = writeln!(s, "  solve residual  {:.2e}", c.rel_residual);
        if let Some(st) = r.stress.get(ci) {
            // The solids' nodal von Mises, then the shells' on each face.
            let faces = [
                ("", &st.von_mises),
                ("shell top    ", &st.shell_von_mises_top),
                ("shell bottom ", &st.shell_von_mises_bottom),
            ];
            for (what, maxima) in faces {
                for g in maxima {
                    let _ = writeln!(
                        s,
                        "  {what}von Mises max {:<16} {:>10} MPa at node {} ({}) m",
                        g.group,
                        fmt_fixed(g.value / 1e6, 3),
                        g.node.unwrap_or(0),
                        fixed3(g.coords, 4)
                    );
                }
            }
            for g in st.max_shear.iter().filter(|g| g.group == "(all)") {
                let _ = writeln!(
                    s,
                    "  max shear stress             {:>10} MPa at node {}",
                    fmt_fixed(g.value / 1e6, 3),
                    g.node.unwrap_or(0)
                );
            }
            let beams = [
                ("normal stress", &st.beam_normal_stress),
                ("torsion shear", &st.beam_torsion_shear),
            ];
            for (what, maxima) in beams {
                for b in maxima {
                    // Resultants at rounding level (−1e-14 N of an unloaded direction) print as 0.
                    let scale = b.resultants.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    let r = b.resultants.map(|v| if v.abs() <= 1e-9 * scale { 0.0 } else { v });
                    let _ = writeln!(
                        s,
                        "  beam {what} max {:<12} {:>10} MPa in element {} at node {} (N = {} N, T = {} N·m, M_y = {} N·m, M_z = {} N·m)",
                        b.group,
                        fmt_fixed(b.value / 1e6, 3),
                        b.element,
                        b.node,
                        crate::io::fmt_sig(r[0], 4),
                        crate::io::fmt_sig(r[3], 4),
                        crate::io::fmt_sig(r[4], 4),
                        crate::io::fmt_sig(r[5], 4)
                    );
                }
            }
        }
    }
    let t = r.timings_s;
    let _ = writeln!(
        s,
        "\ntime [s]: assemble {:.3}  factor {:.3}  solve {:.3}  post {:.3}",
        t.assemble, t.factor, t.solve, t.post
    );
    s
}

/// Write displacement and stress fields of every case to VTU and/or gmsh.
pub fn write_static_fields(
    mesh: &Mesh,
    run: &crate::analysis::statics::StaticRun,
    stresses: &[CaseStresses],
    vtu: Option<&std::path::Path>,
    msh: Option<&std::path::Path>,
) -> Result<()> {
    use crate::io::{msh_out, vtk};
    use crate::post::stress::StressFields;
    let mut disps = Vec::new();
    let mut fields = Vec::new();
    // Shells: the stresses on their two faces and the normal that says which face is the top.
    let mut shell_fields = Vec::new();
    let mut shell_normal = None;
    // Beams: per case, the largest normal stress at the extreme fibres and (round sections)
    // torsion shear of the elements at each node.
    let mut beam_fields = Vec::new();
    // The solids' stress fields: a model without solids gets none rather than fields of zeros
    // that read as an unloaded part.
    let solids = !run.model.solids.is_empty();
    for (ci, cs) in stresses.iter().enumerate() {
        let u = mesh_displacements(run, ci);
        let case = if run.cases.len() > 1 {
            format!("case{}_", ci + 1)
        } else {
            String::new()
        };
        if let Some(f) = &cs.shells {
            shell_fields.push([
                StressFields::new(&f.top, &format!("{case}shell_top_")),
                StressFields::new(&f.bottom, &format!("{case}shell_bottom_")),
            ]);
            shell_normal = Some(&f.normal);
        }
        if let Some(b) = &cs.beams {
            let mut f: Vec<(&str, &[f64])> = Vec::new();
            if !b.normal_max.is_empty() {
                f.push(("beam_normal_stress", &b.normal));
            }
            if !b.torsion_max.is_empty() {
                f.push(("beam_torsion_shear", &b.torsion));
            }
            beam_fields.push((case.clone(), f));
        }
        if solids {
            fields.push(StressFields::new(&cs.solids, &case));
        }
        disps.push(u);
    }
    // Shells' and beams' rotations (rad), where the model has any.
    let rots: Vec<Option<Vec<f64>>> = (0..run.cases.len())
        .map(|ci| {
            let r = crate::dof::node_triplets(&run.u[ci], run.model.n_mesh_nodes, 3);
            r.iter().any(|&v| v != 0.0).then_some(r)
        })
        .collect();
    if let Some(p) = vtu {
        let mut pf = Vec::new();
        for (ci, u) in disps.iter().enumerate() {
            let name = if disps.len() > 1 {
                format!("case{}_displacement", ci + 1)
            } else {
                "displacement".into()
            };
            pf.push(vtk::PointField::new(name.clone(), 3, u));
            if let Some(r) = &rots[ci] {
                pf.push(vtk::PointField::new(name.replace("displacement", "rotation"), 3, r));
            }
            if let Some(f) = fields.get(ci) {
                pf.extend(f.point_fields());
            }
            for f in shell_fields.get(ci).into_iter().flatten() {
                pf.extend(f.point_fields());
            }
            if let Some((case, f)) = beam_fields.get(ci) {
                for (name, data) in f {
                    pf.push(vtk::PointField::new(format!("{case}{name}"), 1, data));
                }
            }
        }
        if let Some(nrm) = &shell_normal {
            pf.push(vtk::PointField::new("shell_normal", 3, nrm));
        }
        vtk::write_vtu_cells(p, mesh, Some(&run.model.cell_blocks()), &pf)?;
    }
    if let Some(p) = msh {
        let mut views = Vec::new();
        for (ci, u) in disps.iter().enumerate() {
            views.push(msh_out::NodeView {
                name: "displacement".into(),
                step: ci,
                time: ci as f64,
                n_comp: 3,
                data: u,
            });
            if let Some(r) = &rots[ci] {
                views.push(msh_out::NodeView {
                    name: "rotation".into(),
                    step: ci,
                    time: ci as f64,
                    n_comp: 3,
                    data: r,
                });
            }
            if let Some(f) = fields.get(ci) {
                views.extend(f.node_views(ci, ci as f64));
            }
            if let Some([top, bottom]) = shell_fields.get(ci) {
                views.extend(top.node_views_named("shell_top_", ci, ci as f64));
                views.extend(bottom.node_views_named("shell_bottom_", ci, ci as f64));
            }
            for (name, data) in beam_fields.get(ci).map_or(&[][..], |(_, f)| &f[..]) {
                views.push(msh_out::NodeView {
                    name: name.to_string(),
                    step: ci,
                    time: ci as f64,
                    n_comp: 1,
                    data,
                });
            }
        }
        if let Some(nrm) = &shell_normal {
            views.push(msh_out::NodeView {
                name: "shell_normal".into(),
                step: 0,
                time: 0.0,
                n_comp: 3,
                data: nrm,
            });
        }
        msh_out::write_msh_views(p, mesh, &views)?;
    }
    Ok(())
}
