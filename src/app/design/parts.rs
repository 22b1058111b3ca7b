//! The design's FE parts, each built in code from the design file (no mesh files): the leaf
//! spring (hex20 solid), the coil isolator (beam helix), the work table (shell sandwich), and the
//! leaf's end stiffness condensed for the 3D machine.
//!
//! Each part is a function of the [`Design`] alone: the chain and the 3D machine assemble them.

use super::file::Design;
use crate::analysis::modal::{ModalOptions, ModalTarget, run_modal};
use crate::analysis::statics::{Load, StaticOptions, run_static};
use crate::material::Material;
use crate::mesh::CellKind;
use crate::mesh::parametric::{HelixParams, SandwichParams, helix_beam, sandwich_table};
use crate::model::{BeamPart, CouplingSpec, ModelSpec, Orientation, ShellPart, rigid_offset};
use crate::section::{BeamSection, ShellSection};
use crate::{Error, Result};

/// FE stiffness of one leaf (N/m) and the peak von Mises stress per metre of guided
/// displacement (Pa/m), both from a guided 1000 N load ([`leaf_fe_stresses`]).
pub fn leaf_fe(d: &Design, h: f64) -> Result<(f64, f64)> {
    let s = leaf_fe_stresses(d, h)?;
    Ok((s.k, s.von_mises_per_m))
}

/// What the leaf's FE statics give per metre of guided displacement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeafStresses {
    /// Stiffness of one leaf (N/m).
    pub k: f64,
    /// Peak von Mises stress per metre (Pa/m).
    pub von_mises_per_m: f64,
    /// |Signed principal stress| (the principal of largest magnitude) per metre at the node of
    /// the von Mises peak (Pa/m): the fatigue stress of a bending leaf (docs/fatigue.md).
    pub principal_per_m: f64,
}

/// The leaf's FE statics under a guided 1000 N load: stiffness and peak stresses per metre of
/// guided displacement (nodal stresses of the hex20 solid, clamped at one end).
pub fn leaf_fe_stresses(d: &Design, h: f64) -> Result<LeafStresses> {
    let s = leaf_fe_memo(d, h)?.stresses;
    let f = d.leaf.material[0] / LEAF_REF_YOUNG;
    Ok(LeafStresses {
        k: f * s.k,
        von_mises_per_m: f * s.von_mises_per_m,
        principal_per_m: f * s.principal_per_m,
    })
}

/// The Young's modulus the leaf's FE runs use, Pa: linear elasticity at a fixed Poisson's ratio
/// gives stiffness and stress per metre of displacement proportional to E, so one run per
/// geometry and ν serves every E (the envelope's temperature band), scaled by E / this value
/// (1 for the paper's 2.1e11 Pa: its numbers are those of a run at its own E).
pub const LEAF_REF_YOUNG: f64 = 2.1e11;

/// The leaf's material with E at [`LEAF_REF_YOUNG`].
fn ref_material(d: &Design) -> [f64; 3] {
    [LEAF_REF_YOUNG, d.leaf.material[1], d.leaf.material[2]]
}

/// `d` with the leaf's E at [`LEAF_REF_YOUNG`].
fn at_ref_young(d: &Design) -> Design {
    let mut r = d.clone();
    r.leaf.material = ref_material(d);
    r
}

/// The leaf's FE at one thickness, from one factorisation: what [`leaf_fe_stresses`] and
/// [`leaf_end_stiffness`] give.
#[derive(Clone, Copy, Debug)]
struct LeafFe {
    stresses: LeafStresses,
    end: [[f64; 6]; 6],
}

/// The memoised [`LeafFe`] of `d`'s leaf at thickness `h`, at E = [`LEAF_REF_YOUNG`].
fn leaf_fe_memo(d: &Design, h: f64) -> Result<LeafFe> {
    let l = &d.leaf;
    let key = super::cache::key("leaf_fe", &(l.length, l.width, h, ref_material(d), l.divisions));
    Ok(*super::cache::get_or(key, || leaf_fe_fresh(&at_ref_young(d), h))?)
}

/// [`LeafFe`] computed (not memoised): the hex20 leaf clamped at `xmin` (translations held), its
/// `xmax` face rigidly coupled to a reference node at the face's centroid whose six components
/// are free. One factorisation of K and six solves, one per unit load on a reference component,
/// give the end's flexibility F (6×6); its inverse is the end stiffness, the Schur complement of
/// K on the reference node (what six runs with one component prescribed each would give). The
/// guided case (a unit vertical motion, the other five held) is the field F⁻¹e_z applied: its
/// stiffness is the (z, z) entry and its stresses per metre come from that field.
fn leaf_fe_fresh(d: &Design, h: f64) -> Result<LeafFe> {
    let l = &d.leaf;
    let source = "leaf spring";
    let mesh = crate::mesh::generate::try_box_mesh(CellKind::Hex20, [l.length, l.width, h], l.divisions)?;
    let spec = ModelSpec {
        material: Material {
            young: l.material[0],
            poisson: l.material[1],
            density: l.material[2],
        },
        fixes: vec![("xmin".into(), crate::dof::TRANSLATIONS)],
        couplings: vec![CouplingSpec {
            group: "xmax".into(),
            guided: None,
            reference: None,
        }],
        ..Default::default()
    };
    let sys = crate::analysis::statics::stiffness_system(crate::model::Model::build(&mesh, &spec, source)?, source)?;
    let model = sys.model();
    let node = model
        .references
        .first()
        .map(|r| r.node)
        .ok_or_else(|| Error::Verification(format!("{source}: the end face's coupling has no reference node")))?;
    let mut eqs = [0usize; 6];
    for (c, e) in eqs.iter_mut().enumerate() {
        *e = sys.dofs().eq_of(node, c).ok_or_else(|| {
            Error::Verification(format!(
                "{source}: component {c} of the end's reference node is not free"
            ))
        })?;
    }
    let fa = crate::analysis::statics::factor_stiffness(&sys)?;
    let n = sys.n_free();
    let mut x = faer::Mat::<f64>::zeros(n, 6);
    for (j, &e) in eqs.iter().enumerate() {
        x[(e, j)] = 1.0;
    }
    fa.solve_in_place(x.as_mut());
    // F symmetrised (K is symmetric; this removes solver rounding), then inverted.
    let mut f = faer::Mat::<f64>::zeros(6, 6);
    for i in 0..6 {
        for j in 0..6 {
            f[(i, j)] = 0.5 * (x[(eqs[i], j)] + x[(eqs[j], i)]);
        }
    }
    let llt = f
        .llt(faer::Side::Lower)
        .map_err(|_| Error::Factorization(format!("{source}: the end's flexibility is not positive definite")))?;
    let s = faer::linalg::solvers::Solve::solve(&llt, faer::Mat::<f64>::identity(6, 6));
    let mut end = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..6 {
            end[i][j] = 0.5 * (s[(i, j)] + s[(j, i)]);
        }
    }
    // The guided case at uz = 1 m: the field X F⁻¹ e_z.
    let xg: Vec<f64> = (0..n).map(|r| (0..6).map(|j| x[(r, j)] * end[j][2]).sum()).collect();
    let nm = model.n_mesh_nodes;
    let u = model.dofs.expand_nodes(&xg, 3, nm);
    let ns = crate::post::stress::nodal_stress(&model.solids, nm, &u)?;
    // The von Mises peak's node (the reference check's hot spot) and its signed principal
    // stress: the largest |principal| over all nodes would be a free-edge corner of the rigid
    // clamp, whose value grows with the mesh (docs/fatigue.md, *A rigid clamp is singular*).
    let (hot, vm) = ns
        .von_mises
        .iter()
        .copied()
        .enumerate()
        .fold((0, 0.0f64), |a, (i, v)| if v > a.1 { (i, v) } else { a });
    let pr = ns.principal.get(hot).map_or(0.0, |p| p[0].abs().max(p[2].abs()));
    Ok(LeafFe {
        stresses: LeafStresses {
            k: end[2][2],
            von_mises_per_m: vm,
            principal_per_m: pr,
        },
        end,
    })
}

/// FE axial stiffness of one coil isolator (beam helix), N/m.
pub fn coil_fe(d: &Design) -> Result<f64> {
    coil_stiffness_along(d, 2, -600.0)
}

/// Stiffness of one coil isolator (beam helix, N/m) with its bottom end clamped and its top end
/// guided along `axis` (0 = x, 2 = z) under `force` N along it.
pub fn coil_stiffness_along(d: &Design, axis: usize, force: f64) -> Result<f64> {
    let key = super::cache::key("coil", &(&d.coil, axis, force));
    Ok(*super::cache::get_or(key, || coil_stiffness_fresh(d, axis, force))?)
}

/// [`coil_stiffness_along`] computed (not memoised).
fn coil_stiffness_fresh(d: &Design, axis: usize, force: f64) -> Result<f64> {
    let c = &d.coil;
    let hp = HelixParams {
        mean_diameter: c.mean_diameter,
        pitch: c.pitch,
        turns: c.turns,
        elems_per_turn: c.elements_per_turn,
        wire_diameter: c.wire,
        kind: CellKind::Line3,
    };
    let mesh = helix_beam(&hp)?;
    let nu = 0.3;
    let mat = Material {
        young: 2.0 * c.shear_modulus * (1.0 + nu),
        poisson: nu,
        density: 7850.0,
    };
    let spec = ModelSpec {
        material: mat,
        fixes: vec![("end_bottom".into(), crate::dof::ALL6)],
        couplings: vec![CouplingSpec {
            group: "end_top".into(),
            guided: Some(axis),
            reference: None,
        }],
        beams: vec![BeamPart {
            group: "wire".into(),
            section: BeamSection::circle(c.wire),
            orientation: Orientation::Radial {
                centre: [0.0; 3],
                axis: [0.0, 0.0, 1.0],
            },
            material: None,
        }],
        ..Default::default()
    };
    let mut f = [0.0; 3];
    f[axis] = force;
    let run = run_static(
        &mesh,
        "coil spring",
        &StaticOptions {
            spec,
            cases: vec![vec![Load::Force {
                group: "end_top".into(),
                force: f,
            }]],
        },
    )?;
    Ok(force / run.cases[0].references[0].displacement[axis])
}

/// The sandwich as shells with the webs at their real (clear) height: mid-surface webs would
/// run between the plates' mid-surfaces, 16.5 % too tall for the paper's table, and racking
/// stiffness goes with 1/height³ (mid-surface shells come out 10 % low against a converged solid,
/// these within 1 %: docs/formulations.md). Each web node on a junction line is copied to the
/// plate's face and tied to the plate node by a two-node rigid coupling.
pub fn sandwich_clear_webs(p: &SandwichParams) -> Result<(crate::mesh::Mesh, Vec<CouplingSpec>)> {
    use crate::mesh::{CellBlock, CellRef, Group};
    use std::collections::HashMap;
    let mut mesh = sandwich_table(p)?;
    let hz = p.mid_surface_spacing();
    let (z0, z1) = (0.5 * p.bottom_thickness, 0.5 * p.bottom_thickness + p.web_height);
    let web_cells: Vec<CellRef> = mesh
        .groups
        .iter()
        .filter(|g| g.name == "webs_long" || g.name == "webs_trans")
        .flat_map(|g| g.cells.iter().copied())
        .collect();
    let mut copy: HashMap<u32, u32> = HashMap::new();
    let mut moved: HashMap<u32, ()> = HashMap::new();
    let mut links: Vec<(u32, u32)> = vec![];
    let tol = 1e-9 * hz.max(1.0);
    for c in &web_cells {
        let b = c.block as usize;
        let nn = mesh.blocks[b].kind.n_nodes();
        for k in 0..nn {
            let a = mesh.blocks[b].conn[c.index as usize * nn + k];
            let z = mesh.nodes[a as usize][2];
            let new = if z.abs() < tol || (z - hz).abs() < tol {
                *copy.entry(a).or_insert_with(|| {
                    let mut q = mesh.nodes[a as usize];
                    q[2] = if z.abs() < tol { z0 } else { z1 };
                    mesh.nodes.push(q);
                    mesh.node_tags.push(mesh.nodes.len() as u64);
                    links.push((a, (mesh.nodes.len() - 1) as u32));
                    (mesh.nodes.len() - 1) as u32
                })
            } else {
                if moved.insert(a, ()).is_none() {
                    mesh.nodes[a as usize][2] = z0 + z / hz * (z1 - z0);
                }
                a
            };
            mesh.blocks[b].conn[c.index as usize * nn + k] = new;
        }
    }
    let mut points = CellBlock::new(CellKind::Point1);
    let mut tag = mesh
        .blocks
        .iter()
        .flat_map(|b| b.tags.iter().copied())
        .max()
        .unwrap_or(0);
    let bp = mesh.blocks.len() as u32;
    let mut couplings = Vec::with_capacity(links.len());
    for (i, (a, b)) in links.iter().enumerate() {
        let first = points.len() as u32;
        for n in [*a, *b] {
            tag += 1;
            points.push(&[n], tag);
        }
        let name = format!("web_link_{i}");
        mesh.groups.push(Group {
            name: name.clone(),
            dim: 0,
            tag: -(i as i32) - 1,
            cells: vec![
                CellRef {
                    block: bp,
                    index: first,
                },
                CellRef {
                    block: bp,
                    index: first + 1,
                },
            ],
        });
        couplings.push(CouplingSpec {
            group: name,
            guided: None,
            reference: None,
        });
    }
    mesh.blocks.push(points);
    Ok((mesh, couplings))
}

/// GOST 8240 channel No. 10: flange width and mean flange thickness (m).
pub const CHANNEL10_FLANGE: (f64, f64) = (0.046, 0.0076);

/// The work table's shell model: mesh (webs at their clear height, [`sandwich_clear_webs`]),
/// rigid web links and the thickness of each shell group. With `spacers = "channel10"` every
/// longitudinal web is a channel No. 10 whose flanges lie on the plates: the plate cells whose
/// centres fall in the flange's 46 mm strip beside the web (towards the table axis; +y for a
/// web on it) form the groups `top_flanges`/`bottom_flanges`, with the plate's thickness plus
/// 7.6 mm scaled by the strip's width over the cells' (so the steel's mass is exact); the rest
/// of each plate is `top_plain`/`bottom_plain`. `top_plate` and `bottom_plate` stay whole for
/// selecting nodes. The flange's offset from the plate's mid-surface is not modelled.
pub fn table_parts(d: &Design) -> Result<(crate::mesh::Mesh, Vec<CouplingSpec>, Vec<(String, f64)>)> {
    use crate::mesh::Group;
    let p = d.sandwich();
    let (mut mesh, links) = sandwich_clear_webs(&p)?;
    let mut thick = p.thicknesses();
    if d.spacers == "channel10" && !p.long_webs.is_empty() {
        let (bf, tf) = CHANNEL10_FLANGE;
        for (plate, t) in [("top_plate", p.top_thickness), ("bottom_plate", p.bottom_thickness)] {
            let g = mesh.group(plate)?.clone();
            let (mut strip, mut plain) = (vec![], vec![]);
            let mut area = 0.0;
            for c in &g.cells {
                let b = &mesh.blocks[c.block as usize];
                let nn = b.kind.n_nodes();
                let x: Vec<[f64; 3]> = b.conn[c.index as usize * nn..(c.index as usize + 1) * nn]
                    .iter()
                    .map(|&a| mesh.nodes[a as usize])
                    .collect();
                let yc = x.iter().map(|q| q[1]).sum::<f64>() / nn as f64;
                let inside = p.long_webs.iter().any(|&yw| {
                    let side = if yw > 1e-9 { -1.0 } else { 1.0 };
                    let u = (yc - yw) * side;
                    u > 0.0 && u < bf
                });
                if inside {
                    // Quad area from its diagonals (the plates are flat).
                    let (d1, d2) = (
                        [x[2][0] - x[0][0], x[2][1] - x[0][1]],
                        [x[3][0] - x[1][0], x[3][1] - x[1][1]],
                    );
                    area += 0.5 * (d1[0] * d2[1] - d1[1] * d2[0]).abs();
                    strip.push(*c);
                } else {
                    plain.push(*c);
                }
            }
            if strip.is_empty() {
                continue;
            }
            let flange_area = bf * p.length * p.long_webs.len() as f64;
            let short = plate.split('_').next().unwrap_or(plate);
            let tag = -200_000 - mesh.groups.len() as i32;
            mesh.groups.push(Group {
                name: format!("{short}_flanges"),
                dim: 2,
                tag,
                cells: strip,
            });
            mesh.groups.push(Group {
                name: format!("{short}_plain"),
                dim: 2,
                tag: tag - 1,
                cells: plain,
            });
            thick.retain(|(n, _)| n != plate);
            thick.push((format!("{short}_flanges"), t + tf * flange_area / area));
            thick.push((format!("{short}_plain"), t));
        }
    }
    thick.retain(|(g, _)| mesh.groups.iter().any(|gr| &gr.name == g && !gr.cells.is_empty()));
    Ok((mesh, links, thick))
}

/// Work-table modal analysis (shells, free–free): mass and the first six elastic frequencies.
pub fn table_fe(d: &Design) -> Result<(f64, Vec<f64>, crate::analysis::modal::ModalRun, crate::mesh::Mesh)> {
    let key = super::cache::key("table_fe", &(&d.table, d.steel, &d.spacers));
    let r = super::cache::get_or(key, || table_fe_fresh(d))?;
    Ok((r.0, r.1.clone(), super::cache::clone_run(&r.2), r.3.clone()))
}

/// [`table_fe`] computed (not memoised).
fn table_fe_fresh(d: &Design) -> Result<(f64, Vec<f64>, crate::analysis::modal::ModalRun, crate::mesh::Mesh)> {
    let (mesh, links, thick) = table_parts(d)?;
    let mat = Material {
        young: d.steel[0],
        poisson: d.steel[1],
        density: d.steel[2],
    };
    let shells = thick
        .into_iter()
        .filter(|(g, _)| mesh.groups.iter().any(|gr| &gr.name == g && !gr.cells.is_empty()))
        .map(|(g, t)| ShellPart {
            group: g,
            section: ShellSection::new(t),
            material: None,
        })
        .collect();
    let spec = ModelSpec {
        material: mat,
        shells,
        couplings: links,
        ..Default::default()
    };
    let run = run_modal(
        &mesh,
        "work table",
        &ModalOptions {
            spec,
            target: ModalTarget::Modes(12),
            ..Default::default()
        },
        0.0,
    )?;
    if !run.report.complete {
        return Err(Error::Verification(
            "work-table modal analysis: a mode was missed".into(),
        ));
    }
    let el: Vec<f64> = run.report.elastic_frequencies().into_iter().take(6).collect();
    Ok((run.report.mass_kg, el, run, mesh))
}

/// Designs whose FE models exceed this many DOFs start only when asked for explicitly (`--yes`).
pub const LARGE_DESIGN_DOFS: usize = 300_000;

/// The DOFs of the design's FE models (work table as shells, one leaf as hex20), from their
/// meshes, before any analysis: what `vibrofem design` checks against [`LARGE_DESIGN_DOFS`].
pub fn estimate_dofs(d: &Design) -> Result<usize> {
    d.validate()?;
    let (table, _, _) = table_parts(d)?;
    let l = &d.leaf;
    let leaf = crate::mesh::generate::try_box_mesh(CellKind::Hex20, [l.length, l.width, l.thickness], l.divisions)?;
    Ok(6 * table.n_nodes() + 3 * leaf.n_nodes())
}

/// Stiffness of the leaf's guided end against its clamp, 6×6 (row-major, N/m, N, N·m/rad), in
/// the leaf's axes (x along the leaf from the clamp, z through its thickness), at the centroid of
/// the end face, the clamp face held: six FE statics with one component of the end's rigid
/// coupling prescribed each, the column the reaction it takes.
pub fn leaf_end_stiffness(d: &Design, h: f64) -> Result<[[f64; 6]; 6]> {
    let k = leaf_fe_memo(d, h)?.end;
    // Proportional to E, as [`leaf_fe_stresses`].
    let f = d.leaf.material[0] / LEAF_REF_YOUNG;
    Ok(k.map(|row| row.map(|v| f * v)))
}

/// The leaf's 12×12 stiffness between its clamp (first six components) and its guided end, in
/// its own axes, from the end stiffness `kbb` ([`leaf_end_stiffness`]) and its length: a rigid
/// motion, u_B = T(r) u_A with r = (L, 0, 0), strains nothing, so K_ba = −K_bb T,
/// K_ab = −Tᵀ K_bb, K_aa = Tᵀ K_bb T.
pub fn leaf_matrix(kbb: &[[f64; 6]; 6], length: f64) -> Vec<f64> {
    let t = rigid_offset([length, 0.0, 0.0]);
    let mut kbt = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..6 {
            kbt[i][j] = (0..6).map(|l| kbb[i][l] * t[l][j]).sum();
        }
    }
    let mut k = vec![0.0; 144];
    for i in 0..6 {
        for j in 0..6 {
            let aa: f64 = (0..6).map(|l| t[l][i] * kbt[l][j]).sum();
            k[i * 12 + j] = aa;
            k[(i + 6) * 12 + j] = -kbt[i][j];
            k[i * 12 + j + 6] = -kbt[j][i];
            k[(i + 6) * 12 + j + 6] = kbb[i][j];
        }
    }
    k
}

/// Axial and lateral stiffness of one coil isolator (N/m): the FE helix with its top end guided
/// along z and then along x.
pub fn coil_stiffness(d: &Design) -> Result<(f64, f64)> {
    Ok((coil_stiffness_along(d, 2, 600.0)?, coil_stiffness_along(d, 0, 600.0)?))
}

/// Steel mass of the design's table (kg): shell areas × thickness × density.
pub fn table_mass(d: &Design) -> Result<f64> {
    let (mesh, _, thick) = table_parts(d)?;
    let mut m = 0.0;
    for (g, t) in thick {
        let grp = mesh.group(&g)?;
        for c in &grp.cells {
            let b = &mesh.blocks[c.block as usize];
            let nn = b.kind.n_nodes();
            let x: Vec<[f64; 3]> = b.conn[c.index as usize * nn..(c.index as usize + 1) * nn]
                .iter()
                .map(|&a| mesh.nodes[a as usize])
                .collect();
            if nn < 4 {
                continue;
            }
            // Planar quad: half the cross product of its diagonals.
            let d1 = [x[2][0] - x[0][0], x[2][1] - x[0][1], x[2][2] - x[0][2]];
            let d2 = [x[3][0] - x[1][0], x[3][1] - x[1][1], x[3][2] - x[1][2]];
            let cr = [
                d1[1] * d2[2] - d1[2] * d2[1],
                d1[2] * d2[0] - d1[0] * d2[2],
                d1[0] * d2[1] - d1[1] * d2[0],
            ];
            m += 0.5 * (cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]).sqrt() * t * d.steel[2];
        }
    }
    Ok(m)
}
