//! Linear static analysis: K̂ û = Tᵀ(f − K g), u = T û + g, on the same assembly as the modal
//! analysis, with reactions, an equilibrium check and the stiffness along coupled DOFs.
//!
//! Loads (per load case, several cases share one factorisation):
//! - a total force on a group: on a coupled group it acts on the reference node; on a surface
//!   group it is spread as a uniform traction (consistent nodal forces ∫N·t dA); on other groups
//!   it is split equally between the group's nodes;
//! - a pressure on a surface group (positive pushes into the solid, along the inward normal);
//! - a body acceleration (gravity), consistent: f = M·a.
//!
//! An under-constrained model is detected from the factorisation (a pivot at rounding level)
//! and reported with the rigid-body motions it leaves free.

use crate::assembly::ElementSet;
use crate::dof::{DofMap, NCOMP};
use crate::linalg::factor::Factor;
use crate::linalg::sparse::SymMatrix;
use crate::mesh::Mesh;
use crate::model::{Model, ModelSpec};
use crate::system::{System, SystemOptions};
use crate::{Error, Result};
use faer::Mat;
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

// The loads are plain data of the model layer (read by `crate::input` too), re-exported here.
pub use crate::model::Load;

/// A static analysis.
#[derive(Clone, Debug, Default)]
pub struct StaticOptions {
    /// The model (supports, couplings, prescribed displacements, springs).
    pub spec: ModelSpec,
    /// Load cases; each is a list of loads. An empty list means one case with no loads (e.g.
    /// only prescribed displacements).
    pub cases: Vec<Vec<Load>>,
}

/// Resultant of a set of forces: force (N) and moment about the origin (N·m).
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct Resultant {
    /// Fx, Fy, Fz.
    pub force: [f64; 3],
    /// Mx, My, Mz about the origin.
    pub moment: [f64; 3],
}

/// Reaction of one support.
#[derive(Clone, Debug, Serialize)]
pub struct Reaction {
    /// The group (fixed, prescribed or coupled).
    pub group: String,
    /// Resultant of the reactions on it (for a coupled group: at its reference node, moments
    /// about the origin).
    pub resultant: Resultant,
}

/// Displacement of a coupling's reference node.
#[derive(Clone, Debug, Serialize)]
pub struct ReferenceResult {
    /// Coupled group.
    pub group: String,
    /// ux, uy, uz (m), rx, ry, rz (rad).
    pub displacement: [f64; 6],
    /// Force applied to it by loads, N.
    pub applied: [f64; 3],
    /// Reaction on it (its fixed components), N and N·m.
    pub reaction: [f64; 6],
    /// Stiffness along the guided axis: force / displacement (N/m), where defined.
    pub stiffness: Option<f64>,
}

/// Results of one load case.
#[derive(Clone, Debug, Serialize)]
pub struct CaseReport {
    /// Largest displacement magnitude (m) and the file tag of its node.
    pub max_displacement: (f64, u64),
    /// Reference nodes.
    pub references: Vec<ReferenceResult>,
    /// Reactions per support.
    pub reactions: Vec<Reaction>,
    /// Applied loads.
    pub applied: Resultant,
    /// |Σ reactions + Σ applied| / max(|applied|, |reactions|), forces and moments.
    pub equilibrium_error: f64,
    /// ‖K̂û − f̂‖ / ‖f̂‖.
    pub rel_residual: f64,
    /// Warnings about this case (e.g. rotations beyond the small-displacement range).
    pub notes: Vec<String>,
}

/// Rotation (rad) beyond which a linear static solution is flagged: sin θ ≈ θ to 0.04 %,
/// and the geometry change that a linear analysis ignores is no longer small.
pub const SMALL_ROTATION: f64 = 0.05;

/// A static run: report plus the full displacement fields.
pub struct StaticRun {
    /// Free equations.
    pub dofs: usize,
    /// Per case.
    pub cases: Vec<CaseReport>,
    /// Per case: raw displacements (NCOMP per node, all model nodes).
    pub u: Vec<Vec<f64>>,
    /// The model (for stress recovery and output).
    pub model: Arc<Model>,
    /// Wall time per phase.
    pub timings: StaticTimings,
}

/// Wall time of a static analysis per phase, seconds.
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct StaticTimings {
    /// Model, graph, pattern and K.
    pub assemble: f64,
    /// Ordering, symbolic and numeric factorisation.
    pub factor: f64,
    /// Load vectors and the solve.
    pub solve: f64,
    /// Reactions, resultants and checks.
    pub post: f64,
}

/// Consistent nodal forces of a uniform traction over the cells of a surface group, and the
/// group's area. Returns per-node weights w_a = ∫N_a dA (so that force_a = w_a / A · F).
fn surface_weights(mesh: &Mesh, group: &str) -> Result<(Vec<(u32, f64)>, f64, Vec<(u32, [f64; 3])>)> {
    let g = mesh.group(group)?;
    let mut w: std::collections::BTreeMap<u32, f64> = Default::default();
    let mut wn: std::collections::BTreeMap<u32, [f64; 3]> = Default::default();
    let mut area = 0.0;
    for c in &g.cells {
        let b = &mesh.blocks[c.block as usize];
        if b.kind.dim() != 2 {
            continue;
        }
        let kind = b.kind;
        let nodes = b.cell(c.index as usize);
        let nn = kind.n_nodes();
        let rule = crate::fe::quadrature::for_cell(kind, 2 * kind.order() + 1);
        let mut n = [0.0; 9];
        let mut dn = [[0.0; 3]; 9];
        let mut x = [[0.0; 3]; 9];
        for a in 0..nn {
            x[a] = mesh.nodes[nodes[a] as usize];
        }
        for (xi, wq) in rule.points.iter().zip(&rule.weights) {
            crate::fe::shape::values_and_gradients(kind, *xi, &mut n[..nn], &mut dn[..nn]);
            // Area vector (unnormalised normal) of the parametrisation and area element.
            let (nv, ja) = crate::fe::geometry::surface_metric(&x[..nn], &dn[..nn]);
            area += ja * wq;
            for a in 0..nn {
                *w.entry(nodes[a]).or_default() += n[a] * ja * wq;
                let e = wn.entry(nodes[a]).or_default();
                for d in 0..3 {
                    e[d] += n[a] * nv[d] * wq;
                }
            }
        }
    }
    if area <= 0.0 {
        return Err(Error::group(
            group,
            format!("group '{group}' has no surface cells: a distributed force or pressure needs a surface group"),
        ));
    }
    Ok((w.into_iter().collect(), area, wn.into_iter().collect()))
}

/// Raw load vector (NCOMP per node) of one load case.
pub(crate) fn load_vector(mesh: &Mesh, model: &Model, loads: &[Load]) -> Result<Vec<f64>> {
    let n = model.dofs.n_nodes();
    let mut f = vec![0.0; NCOMP * n];
    for load in loads {
        match load {
            Load::Force { group, force } => {
                if force.iter().any(|v| !v.is_finite()) {
                    return Err(Error::group(
                        group.as_str(),
                        format!("force on '{group}' is not finite: {force:?}"),
                    ));
                }
                if let Some(r) = model.references.iter().find(|r| &r.group == group) {
                    force_on_constraints(model, group, force, &[r.node as u32])?;
                    for d in 0..3 {
                        f[NCOMP * r.node + d] += force[d];
                    }
                    continue;
                }
                let g = mesh.group(group)?;
                let (used, all) = used_group_nodes(mesh, model, group)?;
                force_on_constraints(model, group, force, &used)?;
                if g.dim == 2 {
                    let (w, area, _) = surface_weights(mesh, group)?;
                    // Over the nodes the model uses: a node of no element would take its share
                    // out of the model unused. With every node used, the weights sum to the area.
                    let w: Vec<(u32, f64)> = w.into_iter().filter(|&(a, _)| node_used(model, a)).collect();
                    let total = if used.len() == all {
                        area
                    } else {
                        w.iter().map(|x| x.1).sum()
                    };
                    if !(total > 0.0) {
                        return Err(Error::group(
                            group.as_str(),
                            format!("force on '{group}': no element of the model uses its surface"),
                        ));
                    }
                    for (a, wa) in w {
                        for d in 0..3 {
                            f[NCOMP * a as usize + d] += wa / total * force[d];
                        }
                    }
                } else {
                    for a in &used {
                        for d in 0..3 {
                            f[NCOMP * *a as usize + d] += force[d] / used.len() as f64;
                        }
                    }
                }
            }
            Load::Pressure { group, p } => {
                if !p.is_finite() {
                    return Err(Error::group(
                        group.as_str(),
                        format!("pressure on '{group}' is not finite: {p}"),
                    ));
                }
                let (_, _, wn) = surface_weights(mesh, group)?;
                // Orient the surface: its normals must point out of the solid. Compare with the
                // direction from the solid's centroid near the surface (the mean of the solid
                // nodes adjacent to the group's nodes).
                let sign = outward_sign(mesh, model, &wn);
                for (a, v) in wn {
                    for d in 0..3 {
                        f[NCOMP * a as usize + d] -= sign * p * v[d];
                    }
                }
            }
            Load::Acceleration(acc) => {
                if acc.iter().any(|v| !v.is_finite()) {
                    return Err(Error::param(
                        "acceleration",
                        format!("acceleration is not finite: {acc:?}"),
                    ));
                }
                // Consistent body force f = M·a over every element set (solids, shells,
                // beams, point masses): the acceleration acts on the translations.
                for set in model.element_sets() {
                    let ndpn = set.dofs_per_node();
                    for e in 0..set.len() {
                        let nodes = set.nodes(e);
                        let nd = ndpn * nodes.len();
                        let mut ke = vec![0.0; nd * nd];
                        let mut me = vec![0.0; nd * nd];
                        set.matrices(e, &mut ke, &mut me, true)?;
                        for i in 0..nd {
                            let mut fi = 0.0;
                            for j in 0..nd {
                                if j % ndpn < 3 {
                                    fi += me[i * nd + j] * acc[j % ndpn];
                                }
                            }
                            f[NCOMP * nodes[i / ndpn] as usize + i % ndpn] += fi;
                        }
                    }
                }
            }
        }
    }
    Ok(f)
}

/// Whether an element of the model uses node `a` (one of its translations is a DOF).
fn node_used(model: &Model, a: u32) -> bool {
    model.dofs.active.get(a as usize).is_some_and(|&m| m & 0b111 != 0)
}

/// The nodes of group `group` that an element of the model uses, and the group's node count.
/// A group with none is refused: a force on it would act on nothing.
fn used_group_nodes(mesh: &Mesh, model: &Model, group: &str) -> Result<(Vec<u32>, usize)> {
    let nodes = mesh.group_nodes(mesh.group(group)?);
    if nodes.is_empty() {
        return Err(Error::group(
            group,
            format!("force on '{group}': the group has no nodes"),
        ));
    }
    let all = nodes.len();
    let used: Vec<u32> = nodes.into_iter().filter(|&a| node_used(model, a)).collect();
    if used.is_empty() {
        return Err(Error::group(
            group,
            format!(
                "force on '{group}': none of its {all} nodes belongs to an element of the model, the force \
                 would act on nothing (is the part that holds it analysed?)"
            ),
        ));
    }
    Ok((used, all))
}

/// Notes on the forces of `loads` spread over groups some of whose nodes belong to no element
/// of the model: those nodes take no share, the others the whole force.
pub(crate) fn load_notes(mesh: &Mesh, model: &Model, loads: &[Load]) -> Vec<String> {
    let mut notes = Vec::new();
    for load in loads {
        let Load::Force { group, .. } = load else { continue };
        if model.references.iter().any(|r| &r.group == group) {
            continue;
        }
        if let Ok((used, all)) = used_group_nodes(mesh, model, group)
            && used.len() < all
        {
            notes.push(format!(
                "force on '{group}': {} of its {all} nodes belong to no element of the model and take no \
                 share; the whole force acts on the other {}",
                all - used.len(),
                used.len()
            ));
        }
    }
    notes
}

/// Refuse a force component that would act only on held DOFs: every node it is spread over has
/// that translation prescribed or fixed, so it would go straight into a reaction and the run
/// would answer another question (a force and a displacement on the same DOF).
fn force_on_constraints(model: &Model, group: &str, force: &[f64; 3], nodes: &[u32]) -> Result<()> {
    let dofs = &model.dofs;
    for (d, &fd) in force.iter().enumerate() {
        let held = |a: u32| dofs.fixed[a as usize] & (1 << d) != 0 && dofs.active[a as usize] & (1 << d) != 0;
        if fd == 0.0 || nodes.is_empty() || !nodes.iter().all(|&a| held(a)) {
            continue;
        }
        let a = nodes[0] as usize;
        let how = if dofs.value.contains_key(&(NCOMP * a + d)) {
            "has a prescribed displacement"
        } else {
            "is fixed"
        };
        let first = if a < model.n_mesh_nodes {
            format!("node {}", model.node_tags.get(a).copied().unwrap_or(a as u64))
        } else {
            format!("the reference node of '{group}'")
        };
        return Err(Error::group(
            group,
            format!(
                "force on '{group}': its {} component acts only on held degrees of freedom ({first} {} {how}{}); \
             it would go into the reaction unused: give a force or a displacement, not both",
                ["x", "y", "z"][d],
                crate::dof::COMPONENT_NAMES[d],
                if nodes.len() > 1 {
                    ", as every node of the group"
                } else {
                    ""
                }
            ),
        ));
    }
    Ok(())
}

/// +1 if the accumulated area vectors point out of the solid, −1 otherwise.
fn outward_sign(mesh: &Mesh, model: &Model, wn: &[(u32, [f64; 3])]) -> f64 {
    let mut centroid = [0.0; 3];
    let mut count = 0.0f64;
    for s in &model.solids {
        for &a in &s.conn {
            for d in 0..3 {
                centroid[d] += mesh.nodes[a as usize][d];
            }
            count += 1.0;
        }
    }
    for c in &mut centroid {
        *c /= count.max(1.0);
    }
    let mut dot = 0.0;
    for (a, v) in wn {
        let x = mesh.nodes[*a as usize];
        dot += (0..3).map(|d| (x[d] - centroid[d]) * v[d]).sum::<f64>();
    }
    if dot >= 0.0 { 1.0 } else { -1.0 }
}

/// Reduced right-hand side f̂ = Tᵀ(f − K g).
fn reduced_rhs(model: &Model, sets: &[&dyn ElementSet], f_raw: &[f64]) -> Result<Vec<f64>> {
    let dofs = &model.dofs;
    let mut fh = vec![0.0; dofs.n_free];
    for (r, &v) in f_raw.iter().enumerate() {
        if v == 0.0 || dofs.active[r / NCOMP] & (1 << (r % NCOMP)) == 0 {
            continue;
        }
        for (e, c) in dofs.expansion(r).terms {
            fh[e] += c * v;
        }
    }
    // −Tᵀ K g over the elements touching prescribed values.
    for set in sets {
        let ndpn = set.dofs_per_node();
        for e in 0..set.len() {
            let nodes = set.nodes(e);
            if !nodes.iter().any(|&a| dofs.special[a as usize]) {
                continue;
            }
            let nd = ndpn * nodes.len();
            let exps = dofs.local_expansions(nodes, ndpn);
            if exps.iter().all(|x| x.constant == 0.0) {
                continue;
            }
            let mut ke = vec![0.0; nd * nd];
            let mut me = vec![];
            set.matrices(e, &mut ke, &mut me, false)?;
            for i in 0..nd {
                let kg: f64 = (0..nd).map(|j| ke[i * nd + j] * exps[j].constant).sum();
                for &(eq, c) in &exps[i].terms {
                    fh[eq] -= c * kg;
                }
            }
        }
    }
    Ok(fh)
}

/// Internal forces K u at every raw DOF (element by element).
fn internal_forces(model: &Model, sets: &[&dyn ElementSet], u: &[f64]) -> Result<Vec<f64>> {
    let mut r = vec![0.0; u.len()];
    for set in sets {
        let ndpn = set.dofs_per_node();
        for e in 0..set.len() {
            let nodes = set.nodes(e);
            let nd = ndpn * nodes.len();
            let mut ke = vec![0.0; nd * nd];
            let mut me = vec![];
            set.matrices(e, &mut ke, &mut me, false)?;
            let ue: Vec<f64> = (0..nd)
                .map(|i| u[NCOMP * nodes[i / ndpn] as usize + i % ndpn])
                .collect();
            for i in 0..nd {
                let v: f64 = (0..nd).map(|j| ke[i * nd + j] * ue[j]).sum();
                r[NCOMP * nodes[i / ndpn] as usize + i % ndpn] += v;
            }
        }
    }
    let _ = model;
    Ok(r)
}

fn resultant_of(nodes: &[[f64; 3]], f: &[f64], pick: impl Fn(usize, usize) -> bool) -> Resultant {
    let mut out = Resultant::default();
    for (a, x) in nodes.iter().enumerate() {
        let fa = [
            if pick(a, 0) { f[NCOMP * a] } else { 0.0 },
            if pick(a, 1) { f[NCOMP * a + 1] } else { 0.0 },
            if pick(a, 2) { f[NCOMP * a + 2] } else { 0.0 },
        ];
        for d in 0..3 {
            out.force[d] += fa[d];
        }
        out.moment[0] += x[1] * fa[2] - x[2] * fa[1];
        out.moment[1] += x[2] * fa[0] - x[0] * fa[2];
        out.moment[2] += x[0] * fa[1] - x[1] * fa[0];
        for d in 0..3 {
            if pick(a, 3 + d) {
                out.moment[d] += f[NCOMP * a + 3 + d];
            }
        }
    }
    out
}

/// Names of the rigid-body motions (about the centroid) that K̂ leaves free.
fn free_rigid_motions(k: &SymMatrix, dofs: &DofMap, nodes: &[[f64; 3]]) -> Vec<String> {
    let n = dofs.n_free;
    let mut c = [0.0; 3];
    for x in nodes {
        for d in 0..3 {
            c[d] += x[d] / nodes.len() as f64;
        }
    }
    let r = crate::post::modal::rigid_vectors(dofs, nodes, c);
    let mut kr = Mat::zeros(n, 6);
    k.mul_block(r.as_ref(), kr.as_mut());
    let kmax = k.diagonal().iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let names = [
        "translation x",
        "translation y",
        "translation z",
        "rotation about x",
        "rotation about y",
        "rotation about z",
    ];
    let mut out = Vec::new();
    for j in 0..6 {
        let rn: f64 = (0..n).map(|i| r[(i, j)] * r[(i, j)]).sum::<f64>().sqrt();
        if rn == 0.0 {
            continue;
        }
        let krn: f64 = (0..n).map(|i| kr[(i, j)] * kr[(i, j)]).sum::<f64>().sqrt();
        if krn <= 1e-8 * kmax * rn {
            out.push(names[j].to_string());
        }
    }
    out
}

/// Reactions, reference-node results, resultants and the equilibrium check of one solved load
/// case: `f` its raw load vector, `u` the full displacement (NCOMP per node).
fn case_report(
    model: &Model,
    mesh: &Mesh,
    sets: &[&dyn ElementSet],
    f: &[f64],
    u: &[f64],
    rel_residual: f64,
) -> Result<CaseReport> {
    let mut rint = internal_forces(model, sets, u)?;
    // Move slave forces to masters (Tᵀ), so reference nodes carry their group's forces.
    let mut moved = vec![0.0; rint.len()];
    for (&s, masters) in &model.dofs.mpc {
        for &(m, c) in masters {
            moved[m] += c * (rint[s] - f[s]);
        }
    }
    for (&s, _) in &model.dofs.mpc {
        rint[s] = f[s];
    }
    for i in 0..rint.len() {
        rint[i] += moved[i];
    }
    // Reaction at constrained (fixed) raw DOFs: R = K u − f.
    let react: Vec<f64> = rint.iter().zip(f).map(|(a, b)| a - b).collect();
    let fixed_pick = |a: usize, c: usize| model.dofs.fixed[a] & (1 << c) != 0;
    let mut reactions = Vec::new();
    let mut total_react = Resultant::default();
    for (g, _) in &model.spec.fixes {
        let gn: Vec<u32> = mesh.group_nodes(mesh.group(g)?);
        let set: std::collections::HashSet<u32> = gn.into_iter().collect();
        let res = resultant_of(&model.nodes, &react, |a, c| {
            set.contains(&(a as u32)) && fixed_pick(a, c)
        });
        reactions.push(Reaction {
            group: g.clone(),
            resultant: res,
        });
    }
    for (g, _) in &model.spec.prescribed {
        if model.references.iter().any(|r| &r.group == g) {
            continue;
        }
        let set: std::collections::HashSet<u32> = mesh.group_nodes(mesh.group(g)?).into_iter().collect();
        let res = resultant_of(&model.nodes, &react, |a, c| {
            set.contains(&(a as u32)) && fixed_pick(a, c)
        });
        reactions.push(Reaction {
            group: g.clone(),
            resultant: res,
        });
    }
    let all = resultant_of(&model.nodes, &react, fixed_pick);
    for d in 0..3 {
        total_react.force[d] = all.force[d];
        total_react.moment[d] = all.moment[d];
    }
    let applied = resultant_of(&model.nodes, f, |a, c| model.dofs.active[a] & (1 << c) != 0);
    let mut refs = Vec::new();
    for r in &model.references {
        let mut disp = [0.0; 6];
        let mut reac = [0.0; 6];
        for c in 0..6 {
            disp[c] = u[NCOMP * r.node + c];
            if fixed_pick(r.node, c) {
                reac[c] = react[NCOMP * r.node + c];
            }
        }
        let applied_r = [f[NCOMP * r.node], f[NCOMP * r.node + 1], f[NCOMP * r.node + 2]];
        // Along the guided axis the reference node carries either an applied force or a
        // prescribed displacement (then the reaction is the force it takes).
        let stiffness = r.guided.and_then(|ax| {
            let force = applied_r[ax] + reac[ax];
            (disp[ax].abs() > 0.0 && force != 0.0).then(|| force / disp[ax])
        });
        refs.push(ReferenceResult {
            group: r.group.clone(),
            displacement: disp,
            applied: applied_r,
            reaction: reac,
            stiffness,
        });
    }
    for r in &refs {
        let x = model.nodes[model
            .references
            .iter()
            .find(|q| q.group == r.group)
            .map_or(0, |q| q.node)];
        if r.reaction.iter().any(|v| *v != 0.0) {
            let f3 = [r.reaction[0], r.reaction[1], r.reaction[2]];
            let m = [
                x[1] * f3[2] - x[2] * f3[1] + r.reaction[3],
                x[2] * f3[0] - x[0] * f3[2] + r.reaction[4],
                x[0] * f3[1] - x[1] * f3[0] + r.reaction[5],
            ];
            reactions.push(Reaction {
                group: r.group.clone(),
                resultant: Resultant { force: f3, moment: m },
            });
        }
    }
    // Scale: the largest single force involved (the sum of balanced reactions is ~0, so it
    // cannot serve).
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let scale = reactions
        .iter()
        .map(|r| norm(r.resultant.force))
        .fold(norm(applied.force), f64::max)
        .max(f64::MIN_POSITIVE);
    let mut eq_err = 0.0f64;
    for d in 0..3 {
        eq_err = eq_err.max((applied.force[d] + total_react.force[d]).abs() / scale);
    }
    let mut maxd = (0.0f64, 0u64);
    for a in 0..model.n_mesh_nodes {
        let m = (0..3).map(|c| u[NCOMP * a + c].powi(2)).sum::<f64>().sqrt();
        if m > maxd.0 {
            maxd = (m, mesh.node_tags[a]);
        }
    }
    let mut notes = Vec::new();
    let (mut rmax, mut at) = (0.0f64, 0usize);
    for a in 0..model.dofs.n_nodes() {
        for c in 3..6 {
            if u[NCOMP * a + c].abs() > rmax {
                (rmax, at) = (u[NCOMP * a + c].abs(), a);
            }
        }
    }
    if rmax > SMALL_ROTATION {
        let place = match model.references.iter().find(|r| r.node == at) {
            Some(r) => format!("the reference node of '{}'", r.group),
            None => format!("node {}", model.node_tags.get(at).copied().unwrap_or(at as u64)),
        };
        notes.push(format!(
            "rotation {rmax:.3} rad at {place} is beyond the small-displacement range ({SMALL_ROTATION} rad): a \
             linear analysis is not valid there (an eccentric load? place a coupling's reference node with \
             GROUP@X,Y,Z)"
        ));
    }
    Ok(CaseReport {
        max_displacement: maxd,
        references: refs,
        reactions,
        applied,
        equilibrium_error: eq_err,
        rel_residual,
        notes,
    })
}

/// Run a static analysis: build the model and its [`System`] (without mass), then [`solve`].
pub fn run_static(mesh: &Mesh, source: &str, opts: &StaticOptions) -> Result<StaticRun> {
    let t = Instant::now();
    let model = Model::build(mesh, &opts.spec, source)?;
    let t_model = t.elapsed().as_secs_f64();
    let sys = stiffness_system(model, source)?;
    let mut run = solve(&sys, mesh, &opts.cases)?;
    run.timings.assemble += t_model;
    Ok(run)
}

/// The [`System`] of a static analysis of `model`: K and its symbolic factorisation, no mass.
pub fn stiffness_system(model: Model, source: &str) -> Result<System> {
    System::build(
        model,
        &SystemOptions {
            mass: false,
            ..Default::default()
        },
        source,
    )
}

/// Displacements, reactions, reference-node results and equilibrium of each load case on an
/// assembled system; `mesh` is the one the model was built from (its groups carry the loads).
/// An empty `cases` means one case with no loads (e.g. only prescribed displacements).
pub fn solve(sys: &System, mesh: &Mesh, cases: &[Vec<Load>]) -> Result<StaticRun> {
    solve_keeping_factor(sys, mesh, cases).map(|(run, _)| run)
}

/// The factorisation of a static system's K on its symbolic factorisation, proved positive
/// definite; a singular or indefinite K is an error naming the free rigid-body motions (or the
/// equation the factorisation stopped at).
pub fn factor_stiffness(sys: &System) -> Result<Factor> {
    let model = sys.model();
    let km_k = sys.k();
    let singular = |extra: String| {
        let free = free_rigid_motions(km_k, &model.dofs, &model.nodes);
        Error::Factorization(if free.is_empty() {
            format!("the stiffness matrix is singular ({extra}): a part or a DOF is not held")
        } else {
            format!(
                "the model is under-constrained: free rigid-body motion(s): {} ({extra})",
                free.join(", ")
            )
        })
    };
    let sym = sys.symbolic()?.clone();
    let fa = match Factor::new(sym, km_k) {
        Ok(f) => f,
        Err(e) => return Err(singular(e.locate(|eq| sys.describe_equation(eq)).to_string())),
    };
    let ratio = fa.pivot_range.0 / fa.pivot_range.1.max(f64::MIN_POSITIVE);
    if fa.negative_pivots > 0 && ratio > 1e-13 {
        // No pivot at rounding level, so no motion is free: a negative pivot of a supported K
        // (positive definite as assembled) is the rounding of an ill-conditioned elimination
        // (a coupling's reference node 1000 km from its group: one negative pivot, ratio 9e-5).
        return Err(Error::Factorization(format!(
            "the stiffness matrix is too ill-conditioned to factorise reliably: {} negative pivot(s) where a \
             supported K has none (smallest pivot {ratio:.1e} of the largest); stiffness contrasts or lever \
             arms of many orders of magnitude (e.g. a coupling's reference node far from its group, a part \
             much thinner than long)",
            fa.negative_pivots
        )));
    }
    if fa.negative_pivots > 0 || ratio <= 1e-13 {
        return Err(singular(format!(
            "pivot ratio {ratio:.1e}, {} negative pivots",
            fa.negative_pivots
        )));
    }
    Ok(fa)
}

/// The largest solve residual ‖f − Ku‖/‖f‖ a static result is reported with (exit 2 above): the
/// displacements of a well-conditioned model leave 1e-15–1e-12; one that the factor's rounding
/// leaves above 1e-6 after refinement does not satisfy equilibrium to engineering accuracy.
const STATIC_RESIDUAL_BAR: f64 = 1e-6;

/// Iterative refinement steps at most (each a solve and a product with K); a step is taken while
/// some case's residual is above 1e-12 and kept for the cases it improves, until none improves
/// (on an ill-conditioned K the residual falls unevenly: on a bar whose coupling's reference
/// point is 10 km away, 18 unrefined, 6.9e-5 refined so, 2.0 when refining stopped at the first
/// step that did not halve it).
const REFINE_STEPS: usize = 10;

/// K⁻¹·`rhs` (one column per load case) with the factor `fa`, refined while that helps, and the
/// cases' relative residuals ‖f − Ku‖/‖f‖ (‖f − Ku‖ for a zero load).
fn solve_refined(fa: &Factor, k: &SymMatrix, rhs: &Mat<f64>) -> (Mat<f64>, Vec<f64>) {
    let (n, nc) = (rhs.nrows(), rhs.ncols());
    let residual = |x: &Mat<f64>| {
        let mut kx = Mat::zeros(n, nc);
        k.mul_block(x.as_ref(), kx.as_mut());
        let r = rhs - &kx;
        let rel: Vec<f64> = (0..nc)
            .map(|c| {
                let (r2, f2) = (0..n).fold((0.0, 0.0), |(a, b), i| (a + r[(i, c)].powi(2), b + rhs[(i, c)].powi(2)));
                if f2 > 0.0 { (r2 / f2).sqrt() } else { r2.sqrt() }
            })
            .collect();
        (r, rel)
    };
    let mut x = rhs.clone();
    fa.solve_in_place(x.as_mut());
    let (mut r, mut rel) = residual(&x);
    for _ in 0..REFINE_STEPS {
        if !rel.iter().any(|&e| e > 1e-12) {
            break;
        }
        fa.solve_in_place(r.as_mut());
        let x_new = &x + &r;
        let (r_new, rel_new) = residual(&x_new);
        let mut improved = false;
        for c in 0..nc {
            if rel_new[c] < rel[c] {
                improved = true;
                x.col_mut(c).copy_from(x_new.col(c));
                r.col_mut(c).copy_from(r_new.col(c));
                rel[c] = rel_new[c];
            } else {
                // Not improved: no correction for this case in later steps.
                r.col_mut(c).fill(0.0);
            }
        }
        if !improved {
            break;
        }
    }
    (x, rel)
}

/// [`solve`], handing back the factorisation of K it made (positive definite, on the system's
/// symbolic factorisation) for a caller that solves with K again (buckling's iteration).
pub(crate) fn solve_keeping_factor(sys: &System, mesh: &Mesh, cases: &[Vec<Load>]) -> Result<(StaticRun, Factor)> {
    let model = sys.model();
    let sets = model.element_sets();
    let t_asm = sys.timings.assemble;
    let km_k = sys.k();
    let t = Instant::now();
    let fa = factor_stiffness(sys)?;
    let t_fac = t.elapsed().as_secs_f64() + sys.timings.order;

    let t = Instant::now();
    let no_loads = [vec![]];
    let cases = if cases.is_empty() { &no_loads[..] } else { cases };
    let n = model.dofs.n_free;
    let mut raw_f = Vec::new();
    let mut rhs = Mat::zeros(n, cases.len());
    for (ci, loads) in cases.iter().enumerate() {
        let f = load_vector(mesh, &model, loads)?;
        let fh = reduced_rhs(&model, &sets, &f)?;
        for i in 0..n {
            rhs[(i, ci)] = fh[i];
        }
        raw_f.push(f);
    }
    let (x, residuals) = solve_refined(&fa, km_k, &rhs);
    let t_sol = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut reports = Vec::new();
    let mut us = Vec::new();
    for ci in 0..cases.len() {
        let xc: Vec<f64> = (0..n).map(|i| x[(i, ci)]).collect();
        let u = model.dofs.full(&xc);
        let rel_residual = residuals[ci];
        let mut report = case_report(model, mesh, &sets, &raw_f[ci], &u, rel_residual)?;
        report.notes.extend(load_notes(mesh, model, &cases[ci]));
        if !(report.max_displacement.0.is_finite() && report.rel_residual.is_finite()) {
            return Err(Error::Factorization(format!(
                "load case {}: the solution is not finite (largest |u| {:.1e} m, solve residual {:.1e}): \
                 the loads overflow double precision",
                ci + 1,
                report.max_displacement.0,
                report.rel_residual
            )));
        }
        if rel_residual > STATIC_RESIDUAL_BAR {
            return Err(Error::Verification(format!(
                "load case {}: the solve residual ‖f − Ku‖/‖f‖ is {rel_residual:.1e} after iterative refinement \
                 (at most {STATIC_RESIDUAL_BAR:.0e} is accepted): K is too ill-conditioned for double precision \
                 (stiffness contrasts of many orders, or a coupling's reference point far from its face)",
                ci + 1
            )));
        }
        reports.push(report);
        us.push(u);
    }
    let t_post = t.elapsed().as_secs_f64();
    let run = StaticRun {
        dofs: n,
        cases: reports,
        u: us,
        model: sys.model_arc().clone(),
        timings: StaticTimings {
            assemble: t_asm,
            factor: t_fac,
            solve: t_sol,
            post: t_post,
        },
    };
    Ok((run, fa))
}
