//! [`Model::build`] in named steps. Each step reads the mesh and the spec and produces one
//! piece of the model; the order is the data dependency:
//!
//! 1. [`materials`]: validate the default and per-group materials;
//! 2. [`solid_parts`], [`shell_parts`], [`beam_parts`]: element sets per formulation;
//! 3. [`reference_nodes`]: one node per coupled group, appended after the mesh nodes;
//! 4. [`point_masses`], [`springs`]: discrete elements on points;
//! 5. [`active_components`]: which components each node carries;
//! 6. [`fixes`], [`couplings`], [`prescribed`]: the constraints;
//! 7. [`lints`]: notes for the user (locking, unused nodes).

use super::Model;
use super::sets::{BeamSet, DiscreteSet, ReferenceNode, ShellSet, SolidSet};
use super::spec::{ModelSpec, Orientation};
use crate::dof::{ALL6, COMPONENT_NAMES, Constraints, DofMap, DofMask, NCOMP, TRANSLATIONS, WARPING};
use crate::material::Material;
use crate::mesh::{CellKind, Group, Mesh};
use crate::{Error, Result};
use std::sync::Arc;

type Nodes = Arc<Vec<[f64; 3]>>;

impl Model {
    /// Bind `spec` to `mesh`: element sets per formulation, reference nodes of couplings,
    /// discrete elements, the constraints and the DOF numbering. `source` names the mesh in
    /// messages.
    pub fn build(mesh: &Mesh, spec: &ModelSpec, source: &str) -> Result<Model> {
        Self::build_in(mesh, spec, source).map_err(|e| e.in_source(source))
    }

    fn build_in(mesh: &Mesh, spec: &ModelSpec, source: &str) -> Result<Model> {
        let (materials, group_materials) = materials(mesh, spec)?;
        let mesh_nodes: Nodes = Arc::new(mesh.nodes.clone());
        let mut solids = solid_parts(mesh, spec, &materials, &group_materials, &mesh_nodes)?;
        let mut shells = shell_parts(mesh, spec, &mesh_nodes)?;
        let orientation_notes = super::orient::orient_shells(&mut shells)?;
        let mut beams = beam_parts(mesh, spec, &mesh_nodes)?;
        if solids.is_empty() && shells.is_empty() && beams.is_empty() {
            return Err(no_elements(mesh, source));
        }
        let mut notes = mesh.notes.clone();
        notes.extend(orientation_notes);
        let (references, coupled) = reference_nodes(mesh, spec)?;
        let mut all_nodes = mesh.nodes.clone();
        all_nodes.extend(references.iter().map(|r| r.position));
        let nodes: Nodes = Arc::new(all_nodes);
        solids.iter_mut().for_each(|s| s.nodes = nodes.clone());
        shells.iter_mut().for_each(|s| s.nodes = nodes.clone());
        beams.iter_mut().for_each(|s| s.nodes = nodes.clone());

        let mut discrete = point_masses(mesh, spec, &references, &mut notes)?;
        discrete.extend(springs(mesh, spec, &references)?);
        let active = active_components(nodes.len(), &solids, &shells, &beams, &discrete, &references);
        let n_mesh = mesh.n_nodes();
        let orphan_nodes = active[..n_mesh].iter().filter(|&&m| m == 0).count();

        let mut cons = Constraints::new(nodes.len());
        let fixed_by = fixes(mesh, spec, &active, &mut cons)?;
        couplings(mesh, spec, &active, &references, &coupled, &fixed_by, &nodes, &mut cons)?;
        notes.extend(pinned_references(&active, &references, &coupled, &nodes, &mut cons));
        prescribed(mesh, spec, &active, &references, &mut cons)?;
        notes.extend(lints(&solids, orphan_nodes));
        notes.extend(singular_supports(mesh, spec, &solids, &shells, &beams));
        let dofs = DofMap::with_constraints(active, cons)?;
        Ok(Model {
            solids,
            discrete,
            shells,
            beams,
            nodes,
            n_mesh_nodes: n_mesh,
            node_tags: mesh.node_tags.clone(),
            spec: spec.clone(),
            references,
            dofs,
            materials,
            orphan_nodes,
            notes,
        })
    }
}

/// Step 1: the materials table (index 0 the default) and the group → material index pairs.
pub(crate) fn materials<'m>(mesh: &'m Mesh, spec: &ModelSpec) -> Result<(Vec<Material>, Vec<(&'m Group, u16)>)> {
    spec.material.validate("(default)")?;
    let mut materials = vec![spec.material];
    let mut group_mat_idx = Vec::new();
    for (g, m) in &spec.group_materials {
        m.validate(&format!("for group '{g}'"))?;
        let grp = mesh.group(g)?;
        // A group material reaches the volume cells of its group, or a shell or beam part of
        // that group (its own material first): on any other group it would do nothing.
        let part = spec.shells.iter().any(|p| p.group == *g) || spec.beams.iter().any(|p| p.group == *g);
        if !part && !grp.cells.iter().any(|c| mesh.blocks[c.block as usize].kind.dim() == 3) {
            return Err(Error::group(
                g.as_str(),
                format!(
                    "a material for group '{g}', which has no volume cells and is no shell or beam part: it would \
                     apply to nothing (a material belongs to solid cells or to a shell or beam part's group)"
                ),
            ));
        }
        materials.push(*m);
        group_mat_idx.push((grp, (materials.len() - 1) as u16));
    }
    if materials.len() > u16::MAX as usize {
        return Err(Error::param("ModelSpec::group_materials", "too many materials"));
    }
    Ok((materials, group_mat_idx))
}

/// The material a group material gives group `g` (the last one named wins, as for cells).
fn group_material(spec: &ModelSpec, g: &str) -> Option<Material> {
    spec.group_materials.iter().rev().find(|(n, _)| n == g).map(|(_, m)| *m)
}

/// Which volume cells are solids: every one when the model names no shell or beam part (a
/// model contains what it names), or those of `spec.solid_groups`.
fn selected_solid_cells(mesh: &Mesh, spec: &ModelSpec) -> Result<Vec<Vec<bool>>> {
    let all_solids = spec.shells.is_empty() && spec.beams.is_empty() && spec.solid_groups.is_none();
    let mut selected: Vec<Vec<bool>> = mesh
        .blocks
        .iter()
        .map(|b| vec![all_solids && b.kind.dim() == 3; b.len()])
        .collect();
    for g in spec.solid_groups.iter().flatten() {
        let grp = mesh.group_of_dim(g, 3)?;
        let mut any = false;
        for c in &grp.cells {
            if mesh.blocks[c.block as usize].kind.dim() == 3 {
                selected[c.block as usize][c.index as usize] = true;
                any = true;
            }
        }
        if !any {
            return Err(Error::group(
                g.as_str(),
                format!("group '{g}' has no volume cells: a solid formulation needs tet, hex or wedge cells"),
            ));
        }
    }
    Ok(selected)
}

/// Step 2a: one solid set per volume cell kind, with a material index per cell.
pub(crate) fn solid_parts(
    mesh: &Mesh,
    spec: &ModelSpec,
    materials: &[Material],
    group_materials: &[(&Group, u16)],
    nodes: &Nodes,
) -> Result<Vec<SolidSet>> {
    let selected = selected_solid_cells(mesh, spec)?;
    let mut solids = Vec::new();
    for (bi, block) in mesh.blocks.iter().enumerate() {
        if block.kind.dim() != 3 || block.is_empty() {
            continue;
        }
        let mut matb = vec![0u16; block.len()];
        for (grp, mi) in group_materials {
            for c in grp.cells.iter().filter(|c| c.block as usize == bi) {
                matb[c.index as usize] = *mi;
            }
        }
        let keep: Vec<usize> = (0..block.len()).filter(|&i| selected[bi][i]).collect();
        if keep.is_empty() {
            continue;
        }
        let mut conn = Vec::with_capacity(keep.len() * block.kind.n_nodes());
        for &i in &keep {
            conn.extend_from_slice(block.cell(i));
        }
        solids.push(SolidSet {
            kind: block.kind,
            conn,
            tags: keep.iter().map(|&i| block.tags[i]).collect(),
            mat: keep.iter().map(|&i| matb[i]).collect(),
            materials: materials.to_vec(),
            lumping: spec.lumping,
            hex8: spec.hex8,
            nodes: nodes.clone(),
        });
    }
    Ok(solids)
}

/// Step 2b: one shell set per shell part (tri3/quad4 cells of its group).
pub(crate) fn shell_parts(mesh: &Mesh, spec: &ModelSpec, nodes: &Nodes) -> Result<Vec<ShellSet>> {
    let mut shells = Vec::new();
    for sp in &spec.shells {
        sp.section.validate(&format!("shell '{}'", sp.group))?;
        let mat = sp
            .material
            .or_else(|| group_material(spec, &sp.group))
            .unwrap_or(spec.material);
        mat.validate(&format!("for shell '{}'", sp.group))?;
        let grp = mesh.group_of_dim(&sp.group, 2)?;
        let mut set = ShellSet {
            group: sp.group.clone(),
            kinds: vec![],
            conn: vec![],
            ptr: vec![0],
            tags: vec![],
            section: sp.section,
            material: mat,
            lumping: spec.lumping,
            nodes: nodes.clone(),
        };
        for c in &grp.cells {
            let b = &mesh.blocks[c.block as usize];
            if !crate::element::shell::supports(b.kind) {
                return Err(Error::group(
                    sp.group.as_str(),
                    format!(
                        "group '{}' has {} cells (element {}): a shell needs tri3 or quad4 surface cells",
                        sp.group, b.kind, b.tags[c.index as usize]
                    ),
                ));
            }
            set.kinds.push(b.kind);
            set.conn.extend_from_slice(b.cell(c.index as usize));
            set.ptr.push(set.conn.len());
            set.tags.push(b.tags[c.index as usize]);
        }
        if set.tags.is_empty() {
            return Err(Error::group(
                sp.group.as_str(),
                format!("shell group '{}' is empty", sp.group),
            ));
        }
        shells.push(set);
    }
    Ok(shells)
}

/// The local y axis of a beam element whose midpoint is `xm`.
pub(crate) fn beam_orientation(orientation: Orientation, xm: [f64; 3]) -> [f64; 3] {
    match orientation {
        Orientation::Vector(v) => v,
        Orientation::Radial { centre, axis } => {
            let r = [xm[0] - centre[0], xm[1] - centre[1], xm[2] - centre[2]];
            let an = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2])
                .sqrt()
                .max(1e-300);
            let u = [axis[0] / an, axis[1] / an, axis[2] / an];
            let t = r[0] * u[0] + r[1] * u[1] + r[2] * u[2];
            [r[0] - t * u[0], r[1] - t * u[1], r[2] - t * u[2]]
        }
    }
}

/// Step 2c: one beam set per beam part (line2/line3 cells of its group; point cells skipped).
pub(crate) fn beam_parts(mesh: &Mesh, spec: &ModelSpec, nodes: &Nodes) -> Result<Vec<BeamSet>> {
    let mut beams = Vec::new();
    for bp in &spec.beams {
        bp.section.validate(&format!("beam '{}'", bp.group))?;
        let mat = bp
            .material
            .or_else(|| group_material(spec, &bp.group))
            .unwrap_or(spec.material);
        mat.validate(&format!("for beam '{}'", bp.group))?;
        let grp = mesh.group_of_dim(&bp.group, 1)?;
        let mut set = BeamSet {
            group: bp.group.clone(),
            kinds: vec![],
            conn: vec![],
            ptr: vec![0],
            tags: vec![],
            orient: vec![],
            section: bp.section,
            material: mat,
            lumping: spec.lumping,
            nodes: nodes.clone(),
        };
        for c in &grp.cells {
            let b = &mesh.blocks[c.block as usize];
            if !crate::element::beam::supports(b.kind) {
                if b.kind.dim() == 0 {
                    continue;
                }
                return Err(Error::group(
                    bp.group.as_str(),
                    format!(
                        "group '{}' has {} cells (element {}): a beam needs line2 or line3 cells",
                        bp.group, b.kind, b.tags[c.index as usize]
                    ),
                ));
            }
            let cell = b.cell(c.index as usize);
            let mut xm = [0.0; 3];
            for &a in cell {
                for d in 0..3 {
                    xm[d] += mesh.nodes[a as usize][d] / cell.len() as f64;
                }
            }
            set.kinds.push(b.kind);
            set.conn.extend_from_slice(cell);
            set.ptr.push(set.conn.len());
            set.tags.push(b.tags[c.index as usize]);
            set.orient.push(beam_orientation(bp.orientation, xm));
        }
        if set.tags.is_empty() {
            return Err(Error::group(
                bp.group.as_str(),
                format!("beam group '{}' has no line cells", bp.group),
            ));
        }
        beams.push(set);
    }
    Ok(beams)
}

/// The error for a model with no element to analyse, listing what the mesh has.
fn no_elements(mesh: &Mesh, source: &str) -> Error {
    let kinds: Vec<String> = mesh.blocks.iter().map(|b| format!("{} {}", b.len(), b.kind)).collect();
    Error::EmptyModel {
        what: format!(
            "{source}: the mesh has no volume elements (it has {}); solid analysis needs tet, hex or wedge \
             cells (surface and line groups need --shell or --beam)",
            if kinds.is_empty() {
                "no elements".to_string()
            } else {
                kinds.join(", ")
            }
        ),
    }
}

/// Step 3: a reference node at the centroid of each coupled group (or where the user placed it) (numbered after the mesh
/// nodes), with the group's nodes.
pub(crate) fn reference_nodes(mesh: &Mesh, spec: &ModelSpec) -> Result<(Vec<ReferenceNode>, Vec<Vec<u32>>)> {
    let mut references: Vec<ReferenceNode> = Vec::new();
    let mut coupled = Vec::new();
    for c in &spec.couplings {
        let grp = mesh.group(&c.group)?;
        let gn = mesh.group_nodes(grp);
        if gn.is_empty() {
            return Err(Error::group(
                c.group.as_str(),
                format!("coupling: group '{}' is empty", c.group),
            ));
        }
        if references.iter().any(|r| r.group == c.group) {
            return Err(Error::group(
                c.group.as_str(),
                format!("group '{}' is coupled twice", c.group),
            ));
        }
        if let Some(ax) = c.guided {
            if ax > 2 {
                return Err(Error::group(
                    c.group.as_str(),
                    format!("coupling '{}': guided axis must be x, y or z", c.group),
                ));
            }
        }
        let p = match c.reference {
            Some(x) if x.iter().all(|v| v.is_finite()) => x,
            Some(x) => {
                return Err(Error::group(
                    c.group.as_str(),
                    format!("coupling '{}': reference point {x:?} is not finite", c.group),
                ));
            }
            None => {
                let mut p = [0.0; 3];
                for &a in &gn {
                    for d in 0..3 {
                        p[d] += mesh.nodes[a as usize][d] / gn.len() as f64;
                    }
                }
                p
            }
        };
        references.push(ReferenceNode {
            group: c.group.clone(),
            node: mesh.n_nodes() + references.len(),
            position: p,
            slaves: gn.len(),
            guided: c.guided,
        });
        coupled.push(gn);
    }
    Ok((references, coupled))
}

/// The node a point element sits on: a coupled group's reference node or a one-node group's
/// node.
fn point_of(mesh: &Mesh, references: &[ReferenceNode], g: &str) -> Result<usize> {
    if let Some(r) = references.iter().find(|r| r.group == g) {
        return Ok(r.node);
    }
    let gn = mesh.group_nodes(mesh.group(g)?);
    match gn.as_slice() {
        [a] => Ok(*a as usize),
        _ => Err(Error::group(
            g,
            format!(
                "group '{g}' has {} nodes: a point mass with inertia or a spring needs a coupled group or a \
             one-node group",
                gn.len()
            ),
        )),
    }
}

/// Step 4a: point masses: with inertia on a point (6 components), or shared equally by a
/// group's nodes (translations only).
pub(crate) fn point_masses(
    mesh: &Mesh,
    spec: &ModelSpec,
    references: &[ReferenceNode],
    notes: &mut Vec<String>,
) -> Result<Vec<DiscreteSet>> {
    let mut masses6 = DiscreteSet::new(1, 6);
    let mut masses3 = DiscreteSet::new(1, 3);
    for pm in &spec.point_masses {
        if !(pm.mass.is_finite() && pm.mass >= 0.0) || pm.inertia.iter().any(|v| !v.is_finite()) {
            return Err(Error::group(
                pm.group.as_str(),
                format!(
                    "point mass on '{}': mass must be non-negative and finite, got {}",
                    pm.group, pm.mass
                ),
            ));
        }
        // As for a density: beyond 1e30 the products of M overflow or swamp K (1e300 kg ended in
        // "zero pivot"); no machine part weighs that much in any unit.
        let big = crate::material::MATERIAL_RANGE.1;
        if pm.mass > big || pm.inertia.iter().any(|v| v.abs() > big) {
            return Err(Error::group(
                pm.group.as_str(),
                format!(
                    "point mass on '{}': mass {} kg, inertia up to {} kg·m²: at most {} each (check the units)",
                    pm.group,
                    crate::io::fmt_plain(pm.mass),
                    crate::io::fmt_plain(pm.inertia.iter().fold(0.0f64, |a, v| a.max(v.abs()))),
                    crate::io::fmt_plain(big)
                ),
            ));
        }
        let rotary = pm.inertia.iter().any(|&v| v != 0.0);
        if rotary {
            // The inertia tensor must be positive semi-definite (every principal minor ≥ 0, to
            // rounding): a negative or indefinite one makes M indefinite and the solve fails.
            let [ixx, iyy, izz, ixy, iyz, ixz] = pm.inertia;
            let scale = ixx
                .abs()
                .max(iyy.abs())
                .max(izz.abs())
                .max(ixy.abs())
                .max(iyz.abs())
                .max(ixz.abs());
            let tol = 1e-12 * scale;
            let minors = [
                ("Ixx", ixx, tol),
                ("Iyy", iyy, tol),
                ("Izz", izz, tol),
                ("Ixx·Iyy − Ixy²", ixx * iyy - ixy * ixy, tol * scale),
                ("Iyy·Izz − Iyz²", iyy * izz - iyz * iyz, tol * scale),
                ("Ixx·Izz − Ixz²", ixx * izz - ixz * ixz, tol * scale),
                (
                    "det",
                    ixx * (iyy * izz - iyz * iyz) - ixy * (ixy * izz - iyz * ixz) + ixz * (ixy * iyz - iyy * ixz),
                    tol * scale * scale,
                ),
            ];
            if let Some((what, v, _)) = minors.iter().find(|(_, v, t)| *v < -t) {
                return Err(Error::group(
                    pm.group.as_str(),
                    format!(
                        "point mass on '{}': the inertia tensor (Ixx,Iyy,Izz,Ixy,Iyz,Ixz = {:?} kg·m²) is not \
                     positive semi-definite ({what} = {v:.3e} < 0)",
                        pm.group, pm.inertia
                    ),
                ));
            }
        }
        let single = references.iter().any(|r| r.group == pm.group)
            || mesh.group(&pm.group).map(|g| mesh.group_nodes(g).len() == 1)?;
        if single {
            let a = point_of(mesh, references, &pm.group)?;
            let mut me = vec![0.0; 36];
            for d in 0..3 {
                me[d * 6 + d] = pm.mass;
            }
            let [ixx, iyy, izz, ixy, iyz, ixz] = pm.inertia;
            let it = [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]];
            for i in 0..3 {
                for j in 0..3 {
                    me[(3 + i) * 6 + 3 + j] = it[i][j];
                }
            }
            masses6.push(
                &[a as u32],
                vec![0.0; 36],
                me,
                format!("point mass {} kg on '{}'", crate::io::fmt_plain(pm.mass), pm.group),
            );
        } else {
            if rotary {
                return Err(Error::group(
                    pm.group.as_str(),
                    format!(
                        "point mass on '{}': rotary inertia needs a coupled group (--couple {})",
                        pm.group, pm.group
                    ),
                ));
            }
            let gn = mesh.group_nodes(mesh.group(&pm.group)?);
            let share = pm.mass / gn.len() as f64;
            for a in gn {
                let mut me = vec![0.0; 9];
                for d in 0..3 {
                    me[d * 3 + d] = share;
                }
                masses3.push(&[a], vec![0.0; 9], me, format!("share of point mass on '{}'", pm.group));
            }
            notes.push(format!(
                "point mass {} kg on '{}' spread equally over its nodes",
                crate::io::fmt_plain(pm.mass),
                pm.group
            ));
        }
    }
    Ok([masses6, masses3]
        .into_iter()
        .filter(|d| !d.labels.is_empty())
        .collect())
}

/// A spring's second point must be another group than its first (`what` names the spring).
fn not_to_itself(a: &str, b: Option<&String>, what: &str) -> Result<()> {
    if b.is_some_and(|b| b == a) {
        return Err(Error::group(
            a,
            format!("{what}: joins '{a}' to itself; a spring joins two points (none named for one to the ground)"),
        ));
    }
    Ok(())
}

/// Step 4b: springs with a diagonal 6×6 stiffness, to the ground or between two points.
pub(crate) fn springs(mesh: &Mesh, spec: &ModelSpec, references: &[ReferenceNode]) -> Result<Vec<DiscreteSet>> {
    let mut springs1 = DiscreteSet::new(1, 6);
    let mut springs2 = DiscreteSet::new(2, 6);
    for sp in &spec.springs {
        if sp.k.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(Error::group(
                sp.a.as_str(),
                format!("spring on '{}': stiffnesses must be non-negative", sp.a),
            ));
        }
        // Beyond 1e30 (N/m, N·m/rad) a spring swamps K's rounding: 1e300 was reported as a free
        // rigid-body motion of a supported model.
        let big = crate::material::MATERIAL_RANGE.1;
        if let Some(k) = sp.k.iter().find(|&&v| v > big) {
            return Err(Error::group(
                sp.a.as_str(),
                format!(
                    "spring on '{}': stiffness {}: at most {} (check the units)",
                    sp.a,
                    crate::io::fmt_plain(*k),
                    crate::io::fmt_plain(big)
                ),
            ));
        }
        not_to_itself(&sp.a, sp.b.as_ref(), &format!("spring on '{}'", sp.a))?;
        let a = point_of(mesh, references, &sp.a)?;
        match &sp.b {
            None => {
                let mut ke = vec![0.0; 36];
                for d in 0..6 {
                    ke[d * 6 + d] = sp.k[d];
                }
                springs1.push(&[a as u32], ke, vec![0.0; 36], format!("spring '{}' to ground", sp.a));
            }
            Some(bg) => {
                let b = point_of(mesh, references, bg)?;
                let mut ke = vec![0.0; 144];
                for d in 0..6 {
                    ke[d * 12 + d] = sp.k[d];
                    ke[(d + 6) * 12 + d + 6] = sp.k[d];
                    ke[d * 12 + d + 6] = -sp.k[d];
                    ke[(d + 6) * 12 + d] = -sp.k[d];
                }
                springs2.push(
                    &[a as u32, b as u32],
                    ke,
                    vec![0.0; 144],
                    format!("spring '{}'–'{bg}'", sp.a),
                );
            }
        }
    }
    for sp in &spec.spring_matrices {
        let n = if sp.b.is_some() { 12 } else { 6 };
        let what = format!("spring '{}' on '{}'", sp.label, sp.a);
        if sp.k.len() != n * n {
            return Err(Error::group(
                sp.a.as_str(),
                format!(
                    "{what}: the stiffness matrix needs {} entries ({n}×{n}), got {}",
                    n * n,
                    sp.k.len()
                ),
            ));
        }
        if sp.k.iter().any(|v| !v.is_finite()) {
            return Err(Error::group(
                sp.a.as_str(),
                format!("{what}: the stiffness matrix is not finite"),
            ));
        }
        let scale = sp.k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let km = nalgebra::DMatrix::from_row_slice(n, n, &sp.k);
        if (0..n).any(|i| (0..n).any(|j| (km[(i, j)] - km[(j, i)]).abs() > 1e-9 * scale)) {
            return Err(Error::group(
                sp.a.as_str(),
                format!("{what}: the stiffness matrix is not symmetric"),
            ));
        }
        // Positive semi-definite to rounding: a negative eigenvalue would make K indefinite.
        let lmin = km.symmetric_eigenvalues().iter().fold(f64::INFINITY, |a, &v| a.min(v));
        if lmin < -1e-9 * scale {
            return Err(Error::group(
                sp.a.as_str(),
                format!("{what}: the stiffness matrix is not positive semi-definite (eigenvalue {lmin:.3e})"),
            ));
        }
        not_to_itself(&sp.a, sp.b.as_ref(), &what)?;
        let a = point_of(mesh, references, &sp.a)?;
        match &sp.b {
            None => springs1.push(&[a as u32], sp.k.clone(), vec![0.0; 36], what),
            Some(bg) => {
                let b = point_of(mesh, references, bg)?;
                springs2.push(&[a as u32, b as u32], sp.k.clone(), vec![0.0; 144], what);
            }
        }
    }
    Ok([springs1, springs2]
        .into_iter()
        .filter(|d| !d.labels.is_empty())
        .collect())
}

/// Step 5: the components each node carries: what its elements use; reference nodes all six.
pub(crate) fn active_components(
    n: usize,
    solids: &[SolidSet],
    shells: &[ShellSet],
    beams: &[BeamSet],
    discrete: &[DiscreteSet],
    references: &[ReferenceNode],
) -> Vec<DofMask> {
    let mut active = vec![0 as DofMask; n];
    let mut mark = |conn: &[u32], mask: DofMask| {
        for &a in conn {
            active[a as usize] |= mask;
        }
    };
    for s in solids {
        mark(&s.conn, TRANSLATIONS);
    }
    for s in shells {
        mark(&s.conn, ALL6);
    }
    for s in beams {
        mark(&s.conn, if s.section.warping { ALL6 | WARPING } else { ALL6 });
    }
    for d in discrete {
        if d.ndpn != 6 {
            mark(&d.nodes, TRANSLATIONS);
            continue;
        }
        // Rotations only where the element gives them stiffness or inertia: a spring with zero
        // rotational stiffness on a solid's node must not add rotations that nothing holds
        // (a zero pivot). A zero diagonal entry of these positive semi-definite matrices means
        // a zero row, so nothing is lost.
        let nd = d.per * 6;
        for (e, nodes) in d.nodes.chunks(d.per).enumerate() {
            for (l, &a) in nodes.iter().enumerate() {
                let mut mask = TRANSLATIONS;
                for c in 3..6 {
                    let i = l * 6 + c;
                    if d.ke[e][i * nd + i] != 0.0 || d.me[e][i * nd + i] != 0.0 {
                        mask |= 1 << c;
                    }
                }
                mark(&[a], mask);
            }
        }
    }
    for r in references {
        active[r.node] |= ALL6;
    }
    active
}

/// Step 6a: fixed components per group. Returns, per node, the index of the fix that holds it.
pub(crate) fn fixes(
    mesh: &Mesh,
    spec: &ModelSpec,
    active: &[DofMask],
    cons: &mut Constraints,
) -> Result<Vec<Option<usize>>> {
    let mut fixed_by: Vec<Option<usize>> = vec![None; active.len()];
    for (gi, (g, mask)) in spec.fixes.iter().enumerate() {
        let grp = mesh.group(g)?;
        let gn = mesh.group_nodes(grp);
        if gn.is_empty() {
            return Err(Error::group(g.as_str(), format!("group '{g}' has no nodes to fix")));
        }
        let mut count = 0;
        for &a in &gn {
            let m = *mask & active[a as usize];
            if m != 0 {
                count += 1;
                fixed_by[a as usize] = Some(gi);
            }
            cons.fixed[a as usize] |= m;
        }
        if count == 0 {
            // Nodes of elements, but none with the components asked (rotations of solid nodes):
            // said so, rather than that the group touches no element.
            let msg = if gn.iter().any(|&a| active[a as usize] != 0) {
                format!(
                    "group '{g}': none of its nodes has the components to fix ({}): solid nodes have no \
                     rotations (shell and beam nodes have; fix the solid nodes' translations)",
                    (0..6)
                        .filter(|&c| *mask & (1 << c) != 0)
                        .map(|c| COMPONENT_NAMES[c])
                        .collect::<Vec<_>>()
                        .join(",")
                )
            } else {
                format!("group '{g}' shares no node with the volume elements: nothing to fix")
            };
            return Err(Error::group(g.as_str(), msg));
        }
    }
    Ok(fixed_by)
}

/// Step 6b: rigid couplings, u_s = u_R + θ_R × (x_s − x_R) and θ_s = θ_R, by elimination of
/// the coupled nodes' components; a guided reference node keeps only its axis.
#[allow(clippy::too_many_arguments)]
pub(crate) fn couplings(
    mesh: &Mesh,
    spec: &ModelSpec,
    active: &[DofMask],
    references: &[ReferenceNode],
    coupled: &[Vec<u32>],
    fixed_by: &[Option<usize>],
    nodes: &[[f64; 3]],
    cons: &mut Constraints,
) -> Result<()> {
    for (ri, (r, gn)) in references.iter().zip(coupled).enumerate() {
        let rnode = r.node;
        let xr = r.position;
        for &s in gn {
            let s = s as usize;
            if let Some(gi) = fixed_by[s] {
                return Err(Error::node(
                    mesh.node_tags[s],
                    format!(
                        "conflicting constraints: group '{}' is coupled, but its node {} is also fixed by '{}'",
                        r.group, mesh.node_tags[s], spec.fixes[gi].0
                    ),
                ));
            }
            if coupled[..ri].iter().any(|g| g.contains(&(s as u32))) {
                return Err(Error::node(
                    mesh.node_tags[s],
                    format!(
                        "conflicting constraints: node {} belongs to two coupled groups",
                        mesh.node_tags[s]
                    ),
                ));
            }
            let d = [nodes[s][0] - xr[0], nodes[s][1] - xr[1], nodes[s][2] - xr[2]];
            let rr = |c: usize| NCOMP * rnode + c;
            // u_s = u_R + θ_R × d
            let rows: [Vec<(usize, f64)>; 3] = [
                vec![(rr(0), 1.0), (rr(4), d[2]), (rr(5), -d[1])],
                vec![(rr(1), 1.0), (rr(5), d[0]), (rr(3), -d[2])],
                vec![(rr(2), 1.0), (rr(3), d[1]), (rr(4), -d[0])],
            ];
            for (c, row) in rows.into_iter().enumerate() {
                if active[s] & (1 << c) != 0 {
                    cons.mpc
                        .insert(NCOMP * s + c, row.into_iter().filter(|(_, k)| *k != 0.0).collect());
                }
            }
            for c in 3..6 {
                if active[s] & (1 << c) != 0 {
                    cons.mpc.insert(NCOMP * s + c, vec![(rr(c), 1.0)]);
                }
            }
        }
        if let Some(ax) = r.guided {
            cons.fixed[rnode] |= ALL6 & !(1 << ax);
        }
    }
    Ok(())
}

/// Step 6b': a coupling whose nodes carry no rotations (solid nodes) can only turn its reference
/// node about axes the nodes' positions resolve. All at one point (a one-node group, wherever the
/// reference node sits): none, so the reference node's rotations are held fixed. On one line (an
/// edge of a solid): not about that line, so the rotation about it is held (a fixed component
/// when the line is along an axis, otherwise θ·n = 0 by elimination). Each case gets a note; left
/// alone they are singular (a zero pivot) although the model is sound.
pub(crate) fn pinned_references(
    active: &[DofMask],
    references: &[ReferenceNode],
    coupled: &[Vec<u32>],
    nodes: &[[f64; 3]],
    cons: &mut Constraints,
) -> Vec<String> {
    const ROTATIONS: DofMask = ALL6 & !TRANSLATIONS;
    let mut notes = Vec::new();
    for (r, gn) in references.iter().zip(coupled) {
        if gn.is_empty() || gn.iter().any(|&s| active[s as usize] & ROTATIONS != 0) {
            continue;
        }
        let free = ROTATIONS & !cons.fixed[r.node];
        if free == 0 {
            continue;
        }
        // Spread of the nodes about their centroid: S = Σ |p|² I − p pᵀ; its null space is the
        // set of axes the nodes cannot turn about.
        let n = gn.len() as f64;
        let mut c = [0.0; 3];
        for &a in gn {
            for d in 0..3 {
                c[d] += nodes[a as usize][d] / n;
            }
        }
        let mut sm = nalgebra::Matrix3::<f64>::zeros();
        let mut size = 0.0f64;
        for &a in gn {
            let p = nalgebra::Vector3::from_fn(|d, _| nodes[a as usize][d] - c[d]);
            sm += nalgebra::Matrix3::identity() * p.norm_squared() - p * p.transpose();
            size = size.max(p.norm());
        }
        let scale = nodes
            .iter()
            .flatten()
            .map(|x| x.abs())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let what = if gn.len() == 1 { "node carries" } else { "nodes carry" };
        if size <= 1e-9 * scale {
            cons.fixed[r.node] |= free;
            notes.push(format!(
                "coupling '{}': its {what} no rotations and {} at one point, so the reference node's \
                 rotations are held fixed (a moment or rotary inertia there has no effect)",
                r.group,
                if gn.len() == 1 { "sits" } else { "all sit" }
            ));
            continue;
        }
        let eig = nalgebra::SymmetricEigen::new(sm);
        let top = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
        let Some(i0) = (0..3).find(|&i| eig.eigenvalues[i] <= 1e-10 * top) else {
            continue;
        };
        // Collinear nodes: the axis n of the line.
        let v = eig.eigenvectors.column(i0);
        let n_axis = [v[0], v[1], v[2]];
        let k = (0..3)
            .filter(|&d| free & (1 << (3 + d)) != 0)
            .max_by(|&a, &b| n_axis[a].abs().total_cmp(&n_axis[b].abs()));
        let Some(k) = k else { continue };
        if n_axis[k].abs() < 1e-12 {
            continue; // the axis lies along rotations already held
        }
        let rr = |d: usize| NCOMP * r.node + 3 + d;
        let others: Vec<(usize, f64)> = (0..3)
            .filter(|&d| d != k && free & (1 << (3 + d)) != 0 && n_axis[d].abs() > 1e-12 * n_axis[k].abs())
            .map(|d| (rr(d), -n_axis[d] / n_axis[k]))
            .collect();
        if others.is_empty() {
            cons.fixed[r.node] |= 1 << (3 + k);
        } else {
            // θ_k = −Σ n_j θ_j / n_k, substituted into the coupled nodes' rows, which name θ_k.
            for &a in gn {
                for comp in 0..3 {
                    if let Some(row) = cons.mpc.get_mut(&(NCOMP * a as usize + comp)) {
                        if let Some(pos) = row.iter().position(|(m, _)| *m == rr(k)) {
                            let (_, coef) = row.remove(pos);
                            for &(m, f) in &others {
                                match row.iter_mut().find(|(x, _)| *x == m) {
                                    Some(e) => e.1 += coef * f,
                                    None => row.push((m, coef * f)),
                                }
                            }
                        }
                    }
                }
            }
            cons.mpc.insert(rr(k), others);
        }
        notes.push(format!(
            "coupling '{}': its nodes lie on one line (direction {:.4}, {:.4}, {:.4}) and carry no rotations, so \
             the reference node cannot turn about that line: that rotation is held",
            r.group, n_axis[0], n_axis[1], n_axis[2]
        ));
    }
    notes
}

/// Step 6c: prescribed displacement values (on a coupled group: its reference node).
pub(crate) fn prescribed(
    mesh: &Mesh,
    spec: &ModelSpec,
    active: &[DofMask],
    references: &[ReferenceNode],
    cons: &mut Constraints,
) -> Result<()> {
    for (g, vals) in &spec.prescribed {
        let targets: Vec<usize> = match references.iter().find(|r| &r.group == g) {
            Some(r) => vec![r.node],
            None => mesh
                .group_nodes(mesh.group(g)?)
                .into_iter()
                .map(|a| a as usize)
                .collect(),
        };
        let reference = references.iter().find(|r| &r.group == g);
        let name = |a: usize| match reference {
            Some(r) if r.node == a => format!("the reference node of '{g}'"),
            _ => format!("node {}", mesh.node_tags.get(a).copied().unwrap_or(a as u64)),
        };
        // The DOF a conflict is at: a mesh node's component, or the group of a reference node.
        let at = |a: usize, comp: &str, msg: String| match mesh.node_tags.get(a) {
            Some(&tag) => Error::dof(tag, comp, msg),
            None => Error::group(g.as_str(), msg),
        };
        for (c, v) in vals.iter().enumerate() {
            let Some(v) = v else { continue };
            if !v.is_finite() {
                return Err(Error::group(
                    g.as_str(),
                    format!("prescribed displacement on '{g}' is not finite"),
                ));
            }
            // A non-zero value on a component no node of the group has (a rotation of solid
            // nodes) would be dropped: the run would answer another question.
            if *v != 0.0 && !targets.iter().any(|&a| active[a] & (1 << c) != 0) {
                return Err(Error::group(
                    g.as_str(),
                    format!(
                        "prescribed displacement on '{g}': {} = {v} but no node of the group has that degree of \
                     freedom ({}); prescribe it on a coupled group (--couple {g}) or on shell or beam nodes",
                        COMPONENT_NAMES[c],
                        if c >= 3 {
                            "solid nodes have no rotations"
                        } else {
                            "it belongs to no element"
                        }
                    ),
                ));
            }
        }
        for &a in &targets {
            for (c, v) in vals.iter().enumerate() {
                let Some(v) = v else { continue };
                if active[a] & (1 << c) == 0 {
                    continue;
                }
                let comp = COMPONENT_NAMES[c];
                if cons.mpc.contains_key(&(NCOMP * a + c)) {
                    return Err(at(
                        a,
                        comp,
                        format!(
                            "conflicting constraints: '{g}' prescribes {comp} of {}, which is coupled; prescribe \
                         the coupled group instead",
                            name(a)
                        ),
                    ));
                }
                match cons.value.get(&(NCOMP * a + c)) {
                    Some(old) if old != v => {
                        return Err(at(
                            a,
                            comp,
                            format!(
                                "conflicting constraints: {comp} of {} is prescribed twice ({old} and {v}, the \
                             second by '{g}')",
                                name(a)
                            ),
                        ));
                    }
                    Some(_) => {}
                    // Held at zero already: prescribing zero agrees (a support sharing an edge).
                    None if cons.fixed[a] & (1 << c) != 0 && *v == 0.0 => continue,
                    None if cons.fixed[a] & (1 << c) != 0 => {
                        let by = match reference {
                            Some(r) if r.node == a && r.guided.is_some() => format!(
                                "the coupling of '{g}' is guided along {} and holds its other components",
                                ["x", "y", "z"][r.guided.unwrap_or(0)]
                            ),
                            _ => spec
                                .fixes
                                .iter()
                                .find(|(f, m)| {
                                    m & (1 << c) != 0
                                        && mesh.group(f).is_ok_and(|fg| mesh.group_nodes(fg).contains(&(a as u32)))
                                })
                                .map(|(f, _)| format!("it is fixed by '{f}'"))
                                .unwrap_or_else(|| "it is already fixed".into()),
                        };
                        return Err(at(
                            a,
                            comp,
                            format!(
                                "conflicting constraints: '{g}' prescribes {comp} = {v} of {}, but {by}",
                                name(a)
                            ),
                        ));
                    }
                    None => {}
                }
                cons.fixed[a] |= 1 << c;
                cons.value.insert(NCOMP * a + c, *v);
            }
        }
    }
    Ok(())
}

/// Step 7: notes a user should read: linear solids that lock at near incompressibility, nodes
/// that belong to no element.
pub(crate) fn lints(solids: &[SolidSet], orphan_nodes: usize) -> Vec<String> {
    let mut notes = Vec::new();
    for set in solids {
        if matches!(set.kind, CellKind::Tet4 | CellKind::Hex8 | CellKind::Wedge6) {
            if let Some(m) = set
                .mat
                .iter()
                .map(|&i| set.materials[i as usize])
                .find(|m| m.poisson > 0.49)
            {
                let hint = if set.kind == CellKind::Hex8 && !set.incompatible() {
                    ", or --hex8 incompatible (incompatible modes: far less locking in volume and in bending)"
                } else {
                    ""
                };
                notes.push(format!(
                    "material ν = {} is nearly incompressible: linear {} elements lock (frequencies and \
                     stiffness too high); use tet10 or hex20{hint}",
                    m.poisson, set.kind
                ));
            }
        }
    }
    notes.extend(curved_cells_note(solids));
    notes.extend(solids.iter().filter_map(flat_linear_cells_note));
    if orphan_nodes > 0 {
        notes.push(format!("{orphan_nodes} nodes belong to no element and are ignored"));
    }
    notes.extend(
        solids
            .iter()
            .filter(|s| flat_linear_cells_note(s).is_none())
            .filter_map(one_layer_note),
    );
    notes
}

/// Linear solids (without incompatible modes) whose every node lies on the part's surface: the
/// part is one cell thick (a plate of one layer of hex8, however well shaped the cells), and such
/// a layer locks in bending: the cell's linear displacement cannot bend, so bending frequencies
/// and stiffness come out far too high. `None` below 8 cells (a single brick is a test, not a
/// part) or when some node is inside.
fn one_layer_note(set: &SolidSet) -> Option<String> {
    if !matches!(set.kind, CellKind::Tet4 | CellKind::Hex8 | CellKind::Wedge6) || set.incompatible() {
        return None;
    }
    let n_cells = set.tags.len();
    if n_cells < 8 {
        return None;
    }
    let nn = set.kind.n_nodes();
    let faces = crate::mesh::generate::faces(set.kind);
    let mut count: std::collections::HashMap<Vec<u32>, u32> = std::collections::HashMap::new();
    for e in 0..n_cells {
        let cell = &set.conn[e * nn..(e + 1) * nn];
        for f in faces {
            let mut key: Vec<u32> = f.iter().map(|&i| cell[i]).collect();
            key.sort_unstable();
            *count.entry(key).or_insert(0) += 1;
        }
    }
    let mut surface = std::collections::HashSet::new();
    for (k, c) in &count {
        if *c == 1 {
            surface.extend(k.iter().copied());
        }
    }
    if !set.conn.iter().all(|a| surface.contains(a)) {
        return None;
    }
    let hex8 = if set.kind == CellKind::Hex8 {
        " or --hex8 incompatible"
    } else {
        ""
    };
    Some(format!(
        "every node of the {n_cells} {} cells lies on the surface: the part is one cell thick, and one layer of \
         linear solids locks in bending (bending frequencies and stiffness far too high); use shells (--shell), \
         quadratic cells (tet10, hex20){hex8}, or several cells through the thickness",
        set.kind
    ))
}

/// Step 7: a note per fixed group that is a line or a point of a solid (no shell or beam node in
/// it): such a support is singular — its reaction concentrates on a line or point, the stress
/// there is infinite in the continuum and grows with refinement, and displacements and
/// frequencies depend on the mesh.
fn singular_supports(
    mesh: &Mesh,
    spec: &ModelSpec,
    solids: &[SolidSet],
    shells: &[ShellSet],
    beams: &[BeamSet],
) -> Vec<String> {
    use crate::element::ElementSet;
    let n = mesh.n_nodes();
    let (mut solid, mut structural) = (vec![false; n], vec![false; n]);
    for s in solids {
        s.conn
            .iter()
            .filter(|&&a| (a as usize) < n)
            .for_each(|&a| solid[a as usize] = true);
    }
    let sets = shells
        .iter()
        .map(|s| s as &dyn ElementSet)
        .chain(beams.iter().map(|s| s as &dyn ElementSet));
    for s in sets {
        for e in 0..s.len() {
            s.nodes(e)
                .iter()
                .filter(|&&a| (a as usize) < n)
                .for_each(|&a| structural[a as usize] = true);
        }
    }
    let mut notes = Vec::new();
    for (g, _) in &spec.fixes {
        let Ok(grp) = mesh.group(g) else { continue };
        if grp.dim > 1 {
            continue;
        }
        let gn = mesh.group_nodes(grp);
        if gn.iter().any(|&a| structural[a as usize]) || !gn.iter().any(|&a| solid[a as usize]) {
            continue;
        }
        let what = if grp.dim == 0 { "a point" } else { "a line" };
        notes.push(format!(
            "support '{g}' is {what} of a solid: a line or point support is singular (the stress there \
             grows without bound with refinement, and displacements and frequencies depend on the \
             mesh); support a face, or for a hinge couple a strip of faces (--couple) and hold its \
             reference node (--displace GROUP=0,0,0)"
        ));
    }
    notes
}

/// Normalised aspect ratio beyond which a linear solid cell counts as flat or slender in
/// [`flat_linear_cells_note`]. A one-layer plate of 20 × 20 mm cells 1 mm thick is 20 (hex8)
/// to 25 (tet4).
pub(crate) const FLAT_ASPECT: f64 = 10.0;

/// Normalised aspect ratio of a linear solid cell: its diameter (largest vertex distance) over
/// its thickness `V / A_max` (volume over the largest face area), divided by the same ratio of
/// the regular cell of the kind (cube √3, regular tetrahedron 3√6/2, equilateral right wedge
/// √2 · 4/√3), so a well-shaped cell is ≈ 1 and a cell 10 times wider than thick ≈ 10.
/// `None` for kinds other than tet4, hex8 and wedge6 or a degenerate cell.
pub(crate) fn linear_aspect(kind: CellKind, x: &[[f64; 3]]) -> Option<f64> {
    let (faces, regular): (&[&[usize]], f64) = match kind {
        CellKind::Tet4 => (&[&[0, 1, 2], &[0, 1, 3], &[0, 2, 3], &[1, 2, 3]], 1.5 * 6f64.sqrt()),
        CellKind::Hex8 => (
            &[
                &[0, 1, 2, 3],
                &[4, 5, 6, 7],
                &[0, 1, 5, 4],
                &[1, 2, 6, 5],
                &[2, 3, 7, 6],
                &[3, 0, 4, 7],
            ],
            3f64.sqrt(),
        ),
        CellKind::Wedge6 => (
            &[&[0, 1, 2], &[3, 4, 5], &[0, 1, 4, 3], &[1, 2, 5, 4], &[2, 0, 3, 5]],
            2f64.sqrt() * 4.0 / 3f64.sqrt(),
        ),
        _ => return None,
    };
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let norm = |a: [f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let mut diam: f64 = 0.0;
    for a in 0..x.len() {
        for b in a + 1..x.len() {
            diam = diam.max(norm(sub(x[a], x[b])));
        }
    }
    // Face area: half the norm of the diagonals' cross product (exact for planar quads and
    // triangles taken as (0, 1, 2) with the third diagonal collapsed).
    let area = |f: &[usize]| match f.len() {
        3 => 0.5 * norm(cross(sub(x[f[1]], x[f[0]]), sub(x[f[2]], x[f[0]]))),
        _ => 0.5 * norm(cross(sub(x[f[2]], x[f[0]]), sub(x[f[3]], x[f[1]]))),
    };
    let amax = faces.iter().map(|f| area(f)).fold(0.0, f64::max);
    let v = crate::element::solid::volume(kind, x).ok()?;
    let r = diam * amax / v / regular;
    r.is_finite().then_some(r)
}

/// Step 7: a note when linear solid cells (tet4, hex8 without incompatible modes, wedge6) are
/// flat or slender ([`linear_aspect`] above [`FLAT_ASPECT`]): a thin part meshed that way
/// locks in bending (a 1 mm plate of one layer of tet4 gave 33 times the shell frequency).
fn flat_linear_cells_note(set: &SolidSet) -> Option<String> {
    if !matches!(set.kind, CellKind::Tet4 | CellKind::Hex8 | CellKind::Wedge6) || set.incompatible() {
        return None;
    }
    let nn = set.kind.n_nodes();
    let mut x = [[0.0; 3]; 8];
    let (mut count, mut worst) = (0usize, 0.0f64);
    for e in 0..set.tags.len() {
        set.coords(e, &mut x[..nn]);
        if let Some(r) = linear_aspect(set.kind, &x[..nn]).filter(|&r| r > FLAT_ASPECT) {
            count += 1;
            worst = worst.max(r);
        }
    }
    if count == 0 {
        return None;
    }
    let hex8 = if set.kind == CellKind::Hex8 {
        ", hex8 with --hex8 incompatible"
    } else {
        ""
    };
    Some(format!(
        "{count} of {} {} cells are flat or slender (aspect ratio up to {worst:.0}; 1 = well shaped): linear \
         solids lock in bending where a part is thin (frequencies and stiffness far too high); use \
         shells (--shell), quadratic cells (tet10, hex20){hex8}, or several cells through the thickness",
        set.tags.len(),
        set.kind
    ))
}

/// The note on curved quadratic cells ([`solid::integration`]): how many of each kind were
/// curved and which rules integrate them and the straight ones; `None` when no cell is curved.
fn curved_cells_note(solids: &[SolidSet]) -> Option<String> {
    use crate::element::solid::{self, Integration};
    let mut parts = Vec::new();
    let mut x = [[0.0; 3]; 27];
    for set in solids {
        let nn = set.kind.n_nodes();
        let curved = (0..set.tags.len())
            .filter(|&e| {
                set.coords(e, &mut x[..nn]);
                solid::integration(set.kind, &x[..nn]) == Integration::Curved
            })
            .count();
        if curved > 0 {
            parts.push(format!(
                "{curved} of {} {} (stiffness {} rule, straight cells {})",
                set.tags.len(),
                set.kind,
                solid::stiffness_rule_name(set.kind, Integration::Curved),
                solid::stiffness_rule_name(set.kind, Integration::Straight),
            ));
        }
    }
    (!parts.is_empty()).then(|| {
        format!(
            "curved quadratic cells (mid-side nodes off the straight edges) integrated with higher-order rules: {}",
            parts.join("; ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::spec::CouplingSpec;

    fn bar() -> Mesh {
        crate::mesh::generate::box_mesh(CellKind::Hex8, [2.0, 1.0, 1.0], [2, 1, 1])
    }

    #[test]
    fn radial_orientation_is_the_offset_from_the_axis() {
        let o = Orientation::Radial {
            centre: [0.0, 0.0, 0.0],
            axis: [0.0, 0.0, 2.0],
        };
        assert_eq!(beam_orientation(o, [1.0, 0.5, 5.0]), [1.0, 0.5, 0.0]);
        assert_eq!(
            beam_orientation(Orientation::Vector([0.0, 1.0, 0.0]), [9.0; 3]),
            [0.0, 1.0, 0.0]
        );
    }

    #[test]
    fn reference_nodes_sit_at_the_centroid_after_the_mesh_nodes() {
        let mesh = bar();
        let spec = ModelSpec {
            couplings: vec![CouplingSpec {
                group: "xmax".into(),
                guided: Some(2),
                reference: None,
            }],
            ..Default::default()
        };
        let (refs, coupled) = reference_nodes(&mesh, &spec).unwrap();
        assert_eq!(refs.len(), 1);
        assert_eq!(refs[0].node, mesh.n_nodes());
        assert_eq!(refs[0].position, [2.0, 0.5, 0.5]);
        assert_eq!(coupled[0].len(), 4);
        let twice = ModelSpec {
            couplings: vec![spec.couplings[0].clone(), spec.couplings[0].clone()],
            ..Default::default()
        };
        assert!(
            reference_nodes(&mesh, &twice)
                .unwrap_err()
                .to_string()
                .contains("coupled twice")
        );
    }

    #[test]
    fn solids_activate_translations_and_references_all_six() {
        let mesh = bar();
        let spec = ModelSpec::default();
        let (materials, gm) = materials(&mesh, &spec).unwrap();
        let nodes: Nodes = Arc::new(mesh.nodes.clone());
        let solids = solid_parts(&mesh, &spec, &materials, &gm, &nodes).unwrap();
        assert_eq!(solids.len(), 1);
        assert_eq!(solids[0].tags.len(), 2);
        let refs = [ReferenceNode {
            group: "g".into(),
            node: mesh.n_nodes(),
            position: [0.0; 3],
            slaves: 0,
            guided: None,
        }];
        let active = active_components(mesh.n_nodes() + 1, &solids, &[], &[], &[], &refs);
        assert!(active[..mesh.n_nodes()].iter().all(|&m| m == TRANSLATIONS));
        assert_eq!(active[mesh.n_nodes()], ALL6);
    }

    #[test]
    fn fixes_report_the_holding_fix_and_refuse_empty_ones() {
        let mesh = bar();
        let spec = ModelSpec {
            fixes: vec![("xmin".into(), TRANSLATIONS)],
            ..Default::default()
        };
        let active = vec![TRANSLATIONS; mesh.n_nodes()];
        let mut cons = Constraints::new(mesh.n_nodes());
        let by = fixes(&mesh, &spec, &active, &mut cons).unwrap();
        assert_eq!(by.iter().filter(|b| b.is_some()).count(), 4);
        assert_eq!(cons.fixed.iter().filter(|&&m| m == TRANSLATIONS).count(), 4);
        // Rotations on a solid's nodes: nothing to fix.
        let rot = ModelSpec {
            fixes: vec![("xmin".into(), ALL6 & !TRANSLATIONS)],
            ..Default::default()
        };
        let mut cons = Constraints::new(mesh.n_nodes());
        assert!(fixes(&mesh, &rot, &active, &mut cons).is_err());
    }

    #[test]
    fn lints_warn_of_locking_and_orphans() {
        let mesh = bar();
        let spec = ModelSpec {
            material: Material {
                poisson: 0.495,
                ..Material::steel()
            },
            ..Default::default()
        };
        let (materials, gm) = materials(&mesh, &spec).unwrap();
        let nodes: Nodes = Arc::new(mesh.nodes.clone());
        let solids = solid_parts(&mesh, &spec, &materials, &gm, &nodes).unwrap();
        let notes = lints(&solids, 3);
        assert!(
            notes[0].contains("nearly incompressible") && notes[0].contains("hex8"),
            "{notes:?}"
        );
        assert!(notes[1].contains("3 nodes"), "{notes:?}");
    }
}
