//! The vibratory table as one 3D machine: the work table (FE shells, or a rigid body for the
//! consistency check), the reactive mass as a rigid body with its inertia, the leaf springs as
//! 12×12 stiffness matrices condensed from the FE leaf, the coil isolators as 6-DOF springs to
//! the floor (axial and lateral stiffness from the FE helix) and the electromagnets as force
//! pairs between the two masses.
//!
//! Reports the machine's modes up to `mode_range` × the excitation, each named from where its
//! strain energy sits (isolators, leaves, table shells) and from the rigid-body motion of the two
//! bodies, and the steady forced response at the excitation over every work-surface node.
//!
//! # The reconstruction (defaults of `[machine]`)
//! The paper gives the parts, not their layout; the defaults place them symmetrically about the
//! table centre (x along the 1200 mm length, y across, z up, origin at the centre of the bottom
//! plate's mid-surface):
//! - 8 leaves along x at y = ±0.12 m, their table ends at x = ±0.55 and ±0.25 m, running
//!   169 mm towards the centre to their clamps on the reactive mass, 60 mm below the bottom
//!   plate; each table end is a rigid shoe over 50 mm × the leaf width of the bottom plate.
//! - 8 magnets at x = ±0.1, ±0.4 m, y = ±0.1 m; each armature is a 100 × 100 mm patch of the
//!   bottom plate (the force is shared by its nodes, the armature mass `masses.active_extra`
//!   spread over the patches), each core a point of the reactive mass.
//! - 8 isolators under the reactive mass at x = ±0.15, ±0.45 m, y = ±0.15 m, z = −0.2 m.
//! - The reactive mass: a uniform steel block 1000 × 350 × 60 mm (the 161.8 kg of steel in a
//!   plate of the table's footprint) centred at z = −0.17 m.
//!
//! # Damping
//! The two-mass model's dashpots, placed where they act: μ12 proportional to each leaf's
//! stiffness matrix (so that the leaves together give μ12 in relative vertical motion), μ13 to
//! each isolator's, μ1 shared by the work-surface nodes vertically. The response is solved in the
//! basis of the machine's modes up to `response_range` × the excitation with the full (not
//! diagonal) modal damping matrix, plus the static correction for the modes left out (a static
//! solve of the machine under the magnet forces less its part in the kept modes); with a rigid
//! table the 12-DOF machine is solved exactly.

use crate::analysis::modal::{ModalParams, ModalTarget};
use crate::analysis::statics::{StaticOptions, run_static};
use crate::app::design::Design;
use crate::mesh::{CellBlock, CellKind, CellRef, Group, Mesh};
use crate::model::{
    CouplingSpec, Model, ModelSpec, PointMassSpec, ShellPart, SpringMatrixSpec, rigid_offset, transform_blocks,
};
use crate::section::ShellSection;
use crate::system::{System, SystemOptions};
use crate::{Error, Result};
use nalgebra::{Complex, DMatrix, DVector};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// The 3D machine's layout and limits (`[machine]` of a design file).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MachineDesign {
    /// `"shells"` (the FE work table) or `"rigid"` (the table as one rigid body with the shell
    /// model's mass and inertia).
    pub table_model: String,
    /// One per leaf: `[x, y, dx, dy]`, the table end (m, from the table centre) and the
    /// horizontal direction from it to the clamp on the reactive mass.
    pub leaves: Vec<[f64; 4]>,
    /// Height of the leaves' mid-plane (m; the bottom plate's mid-surface is z = 0).
    pub leaf_level: f64,
    /// Length of a leaf's shoe on the bottom plate (m, along the leaf; across: the leaf width).
    pub shoe_length: f64,
    /// One per magnet: `[x, y]` (m) of its armature centre (on the bottom plate) and its core.
    pub magnets: Vec<[f64; 2]>,
    /// Armature patch on the bottom plate, `[along x, along y]` (m).
    pub armature: [f64; 2],
    /// One per isolator: `[x, y, z]` (m), where it holds the reactive mass.
    pub isolators: Vec<[f64; 3]>,
    /// Centre of the reactive mass (m).
    pub reactive_centre: [f64; 3],
    /// The reactive mass as a uniform block `[a, b, c]` (m) for its inertia.
    pub reactive_box: [f64; 3],
    /// Modes are reported up to this multiple of the excitation.
    pub mode_range: f64,
    /// Modes up to this multiple of the excitation carry the forced response.
    pub response_range: f64,
    /// No mode but the working one may lie within this fraction of the excitation.
    pub mode_clearance: f64,
    /// Limit on the work surface's amplitude non-uniformity (max − min)/mean.
    pub max_nonuniformity: f64,
}

impl Default for MachineDesign {
    fn default() -> Self {
        let mut leaves = vec![];
        for x in [0.55, 0.25] {
            for sx in [1.0, -1.0] {
                for y in [0.12, -0.12] {
                    leaves.push([sx * x, y, -sx, 0.0]);
                }
            }
        }
        let mut magnets = vec![];
        let mut isolators = vec![];
        for x in [-0.4, -0.1, 0.1, 0.4] {
            for y in [-0.1, 0.1] {
                magnets.push([x, y]);
            }
        }
        for x in [-0.45, -0.15, 0.15, 0.45] {
            for y in [-0.15, 0.15] {
                isolators.push([x, y, -0.2]);
            }
        }
        MachineDesign {
            table_model: "shells".into(),
            leaves,
            leaf_level: -0.06,
            shoe_length: 0.05,
            magnets,
            armature: [0.1, 0.1],
            isolators,
            reactive_centre: [0.0, 0.0, -0.17],
            reactive_box: [1.0, 0.35, 0.06],
            mode_range: 3.0,
            response_range: 6.0,
            mode_clearance: 0.10,
            max_nonuniformity: 0.10,
        }
    }
}

fn bad(key: &str, msg: String) -> Error {
    crate::app::toml_file::bad_value(key, format!("design: '{key}' {msg}"))
}

impl MachineDesign {
    /// Check the layout against the rest of the design (counts, finite positions, limits).
    pub fn validate(&self, d: &Design) -> Result<()> {
        if !["shells", "rigid"].contains(&self.table_model.as_str()) {
            return Err(bad(
                "machine.table_model",
                format!("must be shells or rigid, got '{}'", self.table_model),
            ));
        }
        let counts = [
            ("machine.leaves", self.leaves.len(), d.leaf.count, "leaf.count"),
            ("machine.magnets", self.magnets.len(), d.drive.magnets, "drive.magnets"),
            ("machine.isolators", self.isolators.len(), d.coil.count, "coil.count"),
        ];
        for (key, n, want, other) in counts {
            if n != want {
                return Err(bad(key, format!("lists {n} positions but '{other}' is {want}")));
            }
        }
        let finite = |key: &str, v: &[f64]| -> Result<()> {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(bad(key, format!("must be finite, got {v:?}")))
            }
        };
        for l in &self.leaves {
            finite("machine.leaves", l)?;
            if (l[2] * l[2] + l[3] * l[3]).sqrt() < 1e-9 {
                return Err(bad("machine.leaves", format!("{l:?}: the direction (dx, dy) is zero")));
            }
        }
        for m in &self.magnets {
            finite("machine.magnets", m)?;
        }
        for i in &self.isolators {
            finite("machine.isolators", i)?;
        }
        finite("machine.reactive_centre", &self.reactive_centre)?;
        finite("machine.leaf_level", &[self.leaf_level])?;
        let pos = |key: &str, v: f64| -> Result<()> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(bad(key, format!("must be positive, got {v}")))
            }
        };
        pos("machine.shoe_length", self.shoe_length)?;
        pos("machine.armature", self.armature[0].min(self.armature[1]))?;
        pos(
            "machine.reactive_box",
            self.reactive_box.iter().copied().fold(f64::INFINITY, f64::min),
        )?;
        pos("machine.mode_range", self.mode_range)?;
        pos("machine.mode_clearance", self.mode_clearance)?;
        pos("machine.max_nonuniformity", self.max_nonuniformity)?;
        if !(self.response_range >= self.mode_range) {
            return Err(bad(
                "machine.response_range",
                format!(
                    "must be at least machine.mode_range ({}), got {}",
                    self.mode_range, self.response_range
                ),
            ));
        }
        Ok(())
    }
}

/// Stiffness of the leaf's guided end against its clamp, 6×6 (row-major, N/m, N, N·m/rad), in
/// the leaf's axes (x along the leaf from the clamp, z through its thickness), at the centroid of
/// the end face, the clamp face held: six FE statics with one component of the end's rigid
/// coupling prescribed each, the column the reaction it takes.
pub fn leaf_end_stiffness(d: &Design, h: f64) -> Result<[[f64; 6]; 6]> {
    let l = &d.leaf;
    let mesh = crate::mesh::generate::try_box_mesh(CellKind::Hex20, [l.length, l.width, h], l.divisions)?;
    let mut k = [[0.0; 6]; 6];
    // Small unit motions (m, rad): linear, and well inside the small-rotation range.
    let delta = 1e-5;
    for j in 0..6 {
        let mut pres = [Some(0.0); 6];
        pres[j] = Some(delta);
        let spec = ModelSpec {
            material: crate::material::Material {
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
            prescribed: vec![("xmax".into(), pres)],
            ..Default::default()
        };
        let run = run_static(
            &mesh,
            "leaf spring (condensation)",
            &StaticOptions {
                spec,
                cases: vec![vec![]],
            },
        )?;
        let r = &run.cases[0].references[0];
        for i in 0..6 {
            k[i][j] = r.reaction[i] / delta;
        }
    }
    // Symmetrise (the FE matrix is symmetric; this removes solver rounding).
    for i in 0..6 {
        for j in 0..i {
            let m = 0.5 * (k[i][j] + k[j][i]);
            k[i][j] = m;
            k[j][i] = m;
        }
    }
    Ok(k)
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
    Ok((
        crate::app::design::coil_stiffness_along(d, 2, 600.0)?,
        crate::app::design::coil_stiffness_along(d, 0, 600.0)?,
    ))
}

/// One mode of the machine.
#[derive(Clone, Debug, Serialize)]
pub struct MachineMode {
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// What it is.
    pub name: String,
    /// Share of the strain energy in the leaves, the isolators and the table shells.
    pub energy_leaves: f64,
    /// Isolators' share.
    pub energy_isolators: f64,
    /// Table shells' share.
    pub energy_table: f64,
    /// Share of the kinetic energy in the reactive mass.
    pub kinetic_reactive: f64,
    /// Part of the table's motion that is not a rigid-body motion (0: rigid).
    pub table_deformation: f64,
}

/// What the 3D machine gave.
#[derive(Clone, Debug, Serialize)]
pub struct MachineResult {
    /// Modes up to `mode_range` × the excitation.
    pub modes: Vec<MachineMode>,
    /// Index in `modes` of the working mode (leaves strained, the masses in vertical antiphase),
    /// if one lies in the range.
    pub working: Option<usize>,
    /// The mode other than the working one nearest the excitation: (frequency Hz, |f − f_e|/f_e).
    pub nearest_other: Option<(f64, f64)>,
    /// Vertical amplitude over the work surface, m: mean, min, max.
    pub mean: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
    /// (max − min)/mean.
    pub nonuniformity: f64,
    /// Vertical amplitude of the reactive mass's centre, m.
    pub reactive_amplitude: f64,
    /// Mass of the table shells, kg.
    pub table_mass: f64,
    /// The leaf's guided-end vertical stiffness (before the clamping coefficient), N/m.
    pub leaf_kzz: f64,
    /// Coil axial and lateral stiffness, N/m.
    pub coil_axial: f64,
    /// Lateral.
    pub coil_lateral: f64,
    /// Free DOFs of the machine model.
    pub dofs: usize,
    /// Modes carrying the forced response, and the highest one's frequency (Hz).
    pub response_modes: (usize, f64),
    /// Work-surface nodes (mesh indices) and their amplitude (m), for plots.
    #[serde(skip)]
    pub surface: Vec<(u32, f64)>,
    /// The machine's mesh (table shells plus points), for output.
    #[serde(skip)]
    pub mesh: Mesh,
    /// Complex displacement per mesh node `[ux, uy, uz]` (real and imaginary parts), for output.
    #[serde(skip)]
    pub response: Vec<[Complex<f64>; 3]>,
}

/// A dashpot on one or two nodes (model indices) with its 6n×6n matrix.
struct Dashpot {
    nodes: Vec<usize>,
    c: Vec<f64>,
}

/// Bottom-plate nodes inside a rectangle centred at `c` with half-sizes `h` along the unit
/// vector `e` and across it.
fn patch(mesh: &Mesh, plate: &[u32], c: [f64; 2], e: [f64; 2], h: [f64; 2], exclude: &[bool]) -> Vec<u32> {
    let tol = 1e-9;
    plate
        .iter()
        .copied()
        .filter(|&a| !exclude[a as usize])
        .filter(|&a| {
            let x = mesh.nodes[a as usize];
            let (dx, dy) = (x[0] - c[0], x[1] - c[1]);
            let along = dx * e[0] + dy * e[1];
            let across = -dx * e[1] + dy * e[0];
            along.abs() <= h[0] + tol && across.abs() <= h[1] + tol
        })
        .collect()
}

fn point_group(mesh: &mut Mesh, block: &mut CellBlock, bp: u32, name: &str, nodes: &[u32]) {
    let mut tag = mesh
        .blocks
        .iter()
        .chain(std::iter::once(&*block))
        .flat_map(|b| b.tags.iter().copied())
        .max()
        .unwrap_or(0);
    let mut cells = vec![];
    for &n in nodes {
        tag += 1;
        cells.push(CellRef {
            block: bp,
            index: block.len() as u32,
        });
        block.push(&[n], tag);
    }
    let gtag = -100_000 - mesh.groups.len() as i32;
    mesh.groups.push(Group {
        name: name.into(),
        dim: 0,
        tag: gtag,
        cells,
    });
}

fn mat6_mul_vec(k: &[f64], n: usize, x: &[f64]) -> Vec<f64> {
    (0..n).map(|i| (0..n).map(|j| k[i * n + j] * x[j]).sum()).collect()
}

/// Build and analyse the 3D machine for design `d` with leaves of thickness `h` (m).
pub fn analyse(d: &Design, h: f64) -> Result<MachineResult> {
    let md = &d.machine;
    md.validate(d)?;
    let p = d.sandwich();
    let omega = TAU * d.excitation_hz;
    let rigid = md.table_model == "rigid";

    // Parts condensed from FE.
    let kbb = leaf_end_stiffness(d, h)?;
    let kc = d.leaf.clamping;
    let leaf_local = leaf_matrix(&kbb, d.leaf.length);
    let (k_ax, k_lat) = coil_stiffness(d)?;

    // The table mesh, with the points of the machine.
    let (mut mesh, links, thick) = crate::app::design::table_parts(d)?;
    let n_table = mesh.n_nodes();
    let hz = p.mid_surface_spacing();
    let table_centre = [0.0, 0.0, 0.5 * hz];
    let mut in_link = vec![false; n_table];
    for g in mesh.groups.iter().filter(|g| g.name.starts_with("web_link_")) {
        for a in mesh.group_nodes(g) {
            in_link[a as usize] = true;
        }
    }
    let bottom = mesh.group_nodes(mesh.group("bottom_plate")?);
    let top = mesh.group_nodes(mesh.group("top_plate")?);
    let bp = mesh.blocks.len() as u32;
    let mut block = CellBlock::new(CellKind::Point1);
    // The reactive mass's centre.
    let rc = md.reactive_centre;
    mesh.nodes.push(rc);
    mesh.node_tags
        .push(mesh.node_tags.iter().copied().max().unwrap_or(0) + 1);
    let reactive = (mesh.nodes.len() - 1) as u32;
    point_group(&mut mesh, &mut block, bp, "reactive", &[reactive]);

    let mut couplings = vec![];
    let mut shoes = vec![];
    let mut used = vec![false; n_table];
    if rigid {
        let all: Vec<u32> = (0..n_table as u32).collect();
        point_group(&mut mesh, &mut block, bp, "table_body", &all);
        couplings.push(CouplingSpec {
            group: "table_body".into(),
            guided: None,
            reference: Some(table_centre),
        });
    } else {
        couplings.extend(links);
        for (i, l) in md.leaves.iter().enumerate() {
            let n = (l[2] * l[2] + l[3] * l[3]).sqrt();
            let e = [l[2] / n, l[3] / n];
            let nodes = patch(
                &mesh,
                &bottom,
                [l[0], l[1]],
                e,
                [0.5 * md.shoe_length, 0.5 * d.leaf.width],
                &in_link,
            );
            if nodes.is_empty() {
                return Err(bad(
                    "machine.leaves",
                    format!(
                        "leaf {} at ({}, {}) m: its shoe covers no node of the bottom plate",
                        i + 1,
                        l[0],
                        l[1]
                    ),
                ));
            }
            if nodes.iter().any(|&a| used[a as usize]) {
                return Err(bad(
                    "machine.leaves",
                    format!(
                        "leaf {} at ({}, {}) m: its shoe overlaps another leaf's",
                        i + 1,
                        l[0],
                        l[1]
                    ),
                ));
            }
            nodes.iter().for_each(|&a| used[a as usize] = true);
            let name = format!("leaf_shoe_{}", i + 1);
            point_group(&mut mesh, &mut block, bp, &name, &nodes);
            couplings.push(CouplingSpec {
                group: name.clone(),
                guided: None,
                reference: Some([l[0], l[1], md.leaf_level]),
            });
            shoes.push(name);
        }
    }
    let mut armatures = vec![];
    for (i, m) in md.magnets.iter().enumerate() {
        let nodes = patch(
            &mesh,
            &bottom,
            *m,
            [1.0, 0.0],
            [0.5 * md.armature[0], 0.5 * md.armature[1]],
            &vec![false; n_table],
        );
        if nodes.is_empty() {
            return Err(bad(
                "machine.magnets",
                format!(
                    "magnet {} at ({}, {}) m: its armature covers no node of the bottom plate",
                    i + 1,
                    m[0],
                    m[1]
                ),
            ));
        }
        point_group(&mut mesh, &mut block, bp, &format!("armature_{}", i + 1), &nodes);
        armatures.push(nodes);
    }
    mesh.blocks.push(block);

    // Masses.
    let m2 = d.masses.reactive;
    let [a, b, c] = md.reactive_box;
    let inertia_r = [
        m2 * (b * b + c * c) / 12.0,
        m2 * (a * a + c * c) / 12.0,
        m2 * (a * a + b * b) / 12.0,
    ];
    let mut point_masses = vec![PointMassSpec {
        group: "reactive".into(),
        mass: m2,
        inertia: [inertia_r[0], inertia_r[1], inertia_r[2], 0.0, 0.0, 0.0],
    }];
    if d.masses.active_extra > 0.0 {
        for i in 0..armatures.len() {
            point_masses.push(PointMassSpec {
                group: format!("armature_{}", i + 1),
                mass: d.masses.active_extra / armatures.len() as f64,
                inertia: [0.0; 6],
            });
        }
    }
    let load_mass = d.masses.load_share * d.masses.load;
    if load_mass > 0.0 {
        point_masses.push(PointMassSpec {
            group: "top_plate".into(),
            mass: load_mass,
            inertia: [0.0; 6],
        });
    }

    // Leaves: local → global axes, ends reordered (table end first), moved to their nodes.
    let mut springs = vec![];
    let mut leaf_globals = vec![];
    for (i, l) in md.leaves.iter().enumerate() {
        let n = (l[2] * l[2] + l[3] * l[3]).sqrt();
        let dir = [l[2] / n, l[3] / n, 0.0];
        let ex = [-dir[0], -dir[1], 0.0];
        let ez = [0.0, 0.0, 1.0];
        let ey = [
            ez[1] * ex[2] - ez[2] * ex[1],
            ez[2] * ex[0] - ez[0] * ex[2],
            ez[0] * ex[1] - ez[1] * ex[0],
        ];
        // u_global = R u_local with R's columns the local axes; T = blockdiag(Rᵀ, Rᵀ) gives
        // Tᵀ K T = Q K Qᵀ.
        let mut t = [[0.0; 6]; 6];
        for r in 0..3 {
            for s in 0..3 {
                let v = [ex, ey, ez][r][s]; // (Rᵀ)[r][s] = R[s][r] = e_r[s]
                t[r][s] = v;
                t[r + 3][s + 3] = v;
            }
        }
        let kg = transform_blocks(&leaf_local, &[t, t]);
        // Reorder [clamp, table end] → [table end, clamp].
        let mut kp = vec![0.0; 144];
        let sw = |i: usize| if i < 6 { i + 6 } else { i - 6 };
        for r in 0..12 {
            for s in 0..12 {
                kp[r * 12 + s] = kg[sw(r) * 12 + sw(s)];
            }
        }
        let end = [l[0], l[1], md.leaf_level];
        let clamp = [end[0] + d.leaf.length * dir[0], end[1] + d.leaf.length * dir[1], end[2]];
        let t_table = if rigid {
            rigid_offset([
                end[0] - table_centre[0],
                end[1] - table_centre[1],
                end[2] - table_centre[2],
            ])
        } else {
            rigid_offset([0.0; 3])
        };
        let t_react = rigid_offset([clamp[0] - rc[0], clamp[1] - rc[1], clamp[2] - rc[2]]);
        let mut kf = transform_blocks(&kp, &[t_table, t_react]);
        kf.iter_mut().for_each(|v| *v *= kc);
        let a_group = if rigid {
            "table_body".to_string()
        } else {
            shoes[i].clone()
        };
        springs.push(SpringMatrixSpec {
            a: a_group.clone(),
            b: Some("reactive".into()),
            k: kf.clone(),
            label: format!("leaf {}", i + 1),
        });
        leaf_globals.push((a_group, kf));
    }
    let mut iso_k = vec![];
    for (i, pt) in md.isolators.iter().enumerate() {
        let mut kp = vec![0.0; 36];
        kp[0] = k_lat;
        kp[7] = k_lat;
        kp[14] = k_ax;
        let t = rigid_offset([pt[0] - rc[0], pt[1] - rc[1], pt[2] - rc[2]]);
        let k = transform_blocks(&kp, &[t]);
        springs.push(SpringMatrixSpec {
            a: "reactive".into(),
            b: None,
            k: k.clone(),
            label: format!("isolator {}", i + 1),
        });
        iso_k.push(k);
    }

    let shells = thick
        .into_iter()
        .map(|(g, t)| ShellPart {
            group: g,
            section: ShellSection::new(t),
            material: None,
        })
        .collect();
    let spec = ModelSpec {
        material: crate::material::Material {
            young: d.steel[0],
            poisson: d.steel[1],
            density: d.steel[2],
        },
        shells,
        couplings,
        point_masses,
        spring_matrices: springs,
        ..Default::default()
    };
    let model = Model::build(&mesh, &spec, "machine")?;
    let node_of = |g: &str| -> Result<usize> {
        if g == "reactive" {
            return Ok(reactive as usize);
        }
        model
            .references
            .iter()
            .find(|r| r.group == g)
            .map(|r| r.node)
            .ok_or_else(|| Error::Verification(format!("machine: no reference node for '{g}'")))
    };
    let leaf_nodes: Vec<usize> = leaf_globals.iter().map(|(g, _)| node_of(g)).collect::<Result<_>>()?;
    let table_ref = if rigid { Some(node_of("table_body")?) } else { None };
    let sys = System::build(model, &SystemOptions::default(), "machine")?;
    let dofs = sys.n_free();
    let want = dofs.min(if rigid { 12 } else { 24 });
    let run = crate::analysis::modal::solve(
        &sys,
        &ModalParams {
            target: ModalTarget::Modes(want),
            ..Default::default()
        },
    )?;
    if !run.report.complete {
        return Err(Error::Verification("machine modal analysis: a mode was missed".into()));
    }
    let f_resp = md.response_range * d.excitation_hz;
    let nm = run.lambda.len();
    let n_use = run
        .lambda
        .iter()
        .position(|&l| l.max(0.0).sqrt() / TAU > f_resp)
        .map_or(nm, |k| k.max(1));
    let dm = sys.dofs();
    let shapes: Vec<Vec<f64>> = (0..n_use)
        .map(|k| dm.expand(&crate::linalg::eigen::column(&run.vectors, k), 6))
        .collect();
    let at = |s: &[f64], a: usize| -> [f64; 6] {
        let mut v = [0.0; 6];
        v.copy_from_slice(&s[6 * a..6 * a + 6]);
        v
    };

    // Dashpots.
    let c12 = d.leaf.count as f64 * kc * kbb[2][2];
    let c13 = d.coil.count as f64 * k_ax;
    let mut dashpots = vec![];
    for (i, (_, k)) in leaf_globals.iter().enumerate() {
        dashpots.push(Dashpot {
            nodes: vec![leaf_nodes[i], reactive as usize],
            c: k.iter().map(|v| v * d.damping.mu12 / c12).collect(),
        });
    }
    for k in &iso_k {
        dashpots.push(Dashpot {
            nodes: vec![reactive as usize],
            c: k.iter().map(|v| v * d.damping.mu13 / c13).collect(),
        });
    }
    for &a in &top {
        let mut c = vec![0.0; 36];
        c[14] = d.damping.mu1 / top.len() as f64;
        dashpots.push(Dashpot {
            nodes: vec![a as usize],
            c,
        });
    }
    let gather = |s: &[f64], nodes: &[usize]| -> Vec<f64> { nodes.iter().flat_map(|&a| at(s, a)).collect() };
    let quad = |x: &[f64], c: &[f64], y: &[f64]| -> f64 {
        let n = x.len();
        mat6_mul_vec(c, n, y).iter().zip(x).map(|(a, b)| a * b).sum()
    };
    let mut cr = DMatrix::<f64>::zeros(n_use, n_use);
    let local: Vec<Vec<Vec<f64>>> = dashpots
        .iter()
        .map(|dp| shapes.iter().map(|s| gather(s, &dp.nodes)).collect())
        .collect();
    for (dp, loc) in dashpots.iter().zip(&local) {
        for i in 0..n_use {
            let ci = mat6_mul_vec(&dp.c, loc[i].len(), &loc[i]);
            for j in 0..n_use {
                cr[(i, j)] += ci.iter().zip(&loc[j]).map(|(a, b)| a * b).sum::<f64>();
            }
        }
    }

    // Forces: −F/n on each armature (shared by its nodes), +F/n at each core on the reactive
    // mass (a force and a moment at its centre).
    let drive =
        crate::app::dynamics::electromagnet::RectifiedDrive::from_magnets(d.drive.magnets, d.drive.pull, omega / 2.0)?;
    let f_mag = drive.harmonic_amplitude() / md.magnets.len() as f64;
    let mut fr = DVector::<f64>::zeros(n_use);
    for (k, s) in shapes.iter().enumerate() {
        let mut g = 0.0;
        for nodes in &armatures {
            for &a in nodes {
                g -= f_mag / nodes.len() as f64 * s[6 * a as usize + 2];
            }
        }
        let ur = at(s, reactive as usize);
        for m in &md.magnets {
            let r = [m[0] - rc[0], m[1] - rc[1]];
            // f = (0, 0, F): moment r × f = (r_y F, −r_x F, 0).
            g += f_mag * (ur[2] + r[1] * ur[3] - r[0] * ur[4]);
        }
        fr[k] = g;
    }
    let mut a_mat = DMatrix::<Complex<f64>>::zeros(n_use, n_use);
    for i in 0..n_use {
        for j in 0..n_use {
            a_mat[(i, j)] = Complex::new(
                if i == j { run.lambda[i] - omega * omega } else { 0.0 },
                omega * cr[(i, j)],
            );
        }
    }
    let rhs = fr.map(|v| Complex::new(v, 0.0));
    let q = a_mat.lu().solve(&rhs).ok_or_else(|| {
        Error::Verification("machine forced response: the reduced dynamic stiffness is singular".into())
    })?;
    // Static correction for the modes left out: u_res = K⁻¹F − Σ φ_k φ_kᵀF / λ_k (quasi-static
    // at the excitation, far below their frequencies); it carries the local bending of the
    // plates under the armatures. Zero (to rounding) when every mode is kept.
    let c0 = faer::c64::new(0.0, 0.0);
    let mut forces: Vec<(usize, [faer::c64; 6])> = vec![];
    for nodes in &armatures {
        for &a in nodes {
            let mut f = [c0; 6];
            f[2] = faer::c64::new(-f_mag / nodes.len() as f64, 0.0);
            forces.push((a as usize, f));
        }
    }
    let mut f_r = [c0; 6];
    for m in &md.magnets {
        let r = [m[0] - rc[0], m[1] - rc[1]];
        f_r[2] += faer::c64::new(f_mag, 0.0);
        f_r[3] += faer::c64::new(r[1] * f_mag, 0.0);
        f_r[4] += faer::c64::new(-r[0] * f_mag, 0.0);
    }
    forces.push((reactive as usize, f_r));
    let load = crate::analysis::harmonic::load_vector(&sys, &forces)?;
    // K⁻¹F with the real LDLᵀ on the system's ordering (the isolators hold the machine, so K is
    // positive definite; the load is real).
    let fac = crate::linalg::factor::Factor::new(sys.symbolic()?.clone(), sys.k())
        .map_err(|e| e.locate(|eq| sys.describe_equation(eq)))?;
    let mut b = faer::Mat::from_fn(load.len(), 1, |i, _| load[i].re);
    fac.solve_in_place(b.as_mut());
    let mut u_res: Vec<faer::c64> = (0..load.len()).map(|i| faer::c64::new(b[(i, 0)], 0.0)).collect();
    for k in 0..n_use {
        let c = fr[k] / run.lambda[k];
        for (i, u) in u_res.iter_mut().enumerate() {
            *u -= faer::c64::new(c * run.vectors[(i, k)], 0.0);
        }
    }
    let res_nodes = crate::analysis::harmonic::expand(&sys, &u_res);
    let n_mesh = mesh.n_nodes();
    let mut response = vec![[Complex::new(0.0, 0.0); 3]; n_mesh];
    for (a, r) in response.iter_mut().enumerate() {
        for c in 0..3 {
            r[c] = Complex::new(res_nodes[a][c].re, res_nodes[a][c].im);
        }
    }
    for (k, s) in shapes.iter().enumerate() {
        for (a, r) in response.iter_mut().enumerate() {
            for c in 0..3 {
                r[c] += q[k] * s[6 * a + c];
            }
        }
    }
    let surface: Vec<(u32, f64)> = top.iter().map(|&a| (a, response[a as usize][2].norm())).collect();
    let amps: Vec<f64> = surface.iter().map(|x| x.1).collect();
    let mean = amps.iter().sum::<f64>() / amps.len() as f64;
    let min = amps.iter().copied().fold(f64::INFINITY, f64::min);
    let max = amps.iter().copied().fold(0.0, f64::max);

    // Modes: energy split and names.
    let mr = [m2, m2, m2, inertia_r[0], inertia_r[1], inertia_r[2]];
    let mut modes = vec![];
    let f_list = md.mode_range * d.excitation_hz;
    let table_nodes: Vec<usize> = (0..n_table).collect();
    for (k, s) in shapes.iter().enumerate() {
        let lam = run.lambda[k].max(0.0);
        let f = lam.sqrt() / TAU;
        if f > f_list {
            break;
        }
        let mut u_leaf = 0.0;
        for (i, (_, kk)) in leaf_globals.iter().enumerate() {
            let x = gather(s, &[leaf_nodes[i], reactive as usize]);
            u_leaf += quad(&x, kk, &x);
        }
        let ur = at(s, reactive as usize);
        let u_iso: f64 = iso_k.iter().map(|kk| quad(&ur, kk, &ur)).sum();
        let lam_s = lam.max(1e-300);
        let (e_leaf, e_iso) = ((u_leaf / lam_s).clamp(0.0, 1.0), (u_iso / lam_s).clamp(0.0, 1.0));
        let e_table = (1.0 - e_leaf - e_iso).max(0.0);
        let kin_r: f64 = (0..6).map(|c| mr[c] * ur[c] * ur[c]).sum();
        // The table's rigid-body motion at its centre: least squares over its nodes.
        let (pt, deform) = match table_ref {
            Some(a) => (at(s, a), 0.0),
            None => rigid_fit(&mesh, &table_nodes, s, table_centre),
        };
        let scale = 0.3; // m: rotations as the motion they give this far from the centre
        let dominant = |v: &[f64; 6]| -> usize {
            (0..6)
                .max_by(|&i, &j| {
                    let w = |c: usize| if c < 3 { v[c].abs() } else { scale * v[c].abs() };
                    w(i).total_cmp(&w(j))
                })
                .unwrap_or(2)
        };
        let name = if e_iso >= e_leaf && e_iso >= e_table {
            [
                "isolation: sway along x",
                "isolation: sway along y",
                "isolation: bounce",
                "isolation: rocking about x",
                "isolation: rocking about y",
                "isolation: yaw",
            ][dominant(&ur)]
            .to_string()
        } else if e_table > e_leaf {
            format!("table elastic mode ({:.0} % rigid-body motion)", 100.0 * (1.0 - deform))
        } else {
            // Relative motion of the table against the reactive mass, at the table centre.
            let t = rigid_offset([
                table_centre[0] - rc[0],
                table_centre[1] - rc[1],
                table_centre[2] - rc[2],
            ]);
            let mut rel = [0.0; 6];
            for i in 0..6 {
                rel[i] = pt[i] - (0..6).map(|j| t[i][j] * ur[j]).sum::<f64>();
            }
            [
                "table surge along x on the leaves",
                "table sway along y on the leaves",
                "working mode (masses in vertical antiphase)",
                "table roll on the leaves (about x)",
                "table pitch on the leaves (about y)",
                "table yaw on the leaves",
            ][dominant(&rel)]
            .to_string()
        };
        modes.push(MachineMode {
            frequency_hz: f,
            name,
            energy_leaves: e_leaf,
            energy_isolators: e_iso,
            energy_table: e_table,
            kinetic_reactive: kin_r,
            table_deformation: deform,
        });
    }
    let working = modes
        .iter()
        .enumerate()
        .filter(|(_, m)| m.name.starts_with("working"))
        .min_by(|a, b| {
            (a.1.frequency_hz - d.excitation_hz)
                .abs()
                .total_cmp(&(b.1.frequency_hz - d.excitation_hz).abs())
        })
        .map(|(i, _)| i);
    for (i, m) in modes.iter_mut().enumerate() {
        if m.name.starts_with("working") && Some(i) != working {
            m.name = "vertical antiphase (second)".into();
        }
    }
    let nearest_other = modes
        .iter()
        .enumerate()
        .filter(|(i, _)| Some(*i) != working)
        .map(|(_, m)| {
            (
                m.frequency_hz,
                (m.frequency_hz - d.excitation_hz).abs() / d.excitation_hz,
            )
        })
        .min_by(|a, b| a.1.total_cmp(&b.1));
    let reactive_amplitude = {
        let rz = res_nodes[reactive as usize][2];
        let mut z = Complex::new(rz.re, rz.im);
        for (k, s) in shapes.iter().enumerate() {
            z += q[k] * s[6 * reactive as usize + 2];
        }
        z.norm()
    };
    let table_mass = run.report.mass_kg - m2 - d.masses.active_extra - load_mass;
    Ok(MachineResult {
        modes,
        working,
        nearest_other,
        mean,
        min,
        max,
        nonuniformity: (max - min) / mean,
        reactive_amplitude,
        table_mass,
        leaf_kzz: kbb[2][2],
        coil_axial: k_ax,
        coil_lateral: k_lat,
        dofs,
        response_modes: (n_use, run.lambda[n_use - 1].max(0.0).sqrt() / TAU),
        surface,
        mesh,
        response,
    })
}

/// The rigid-body motion (at `c`) nearest the translations of `nodes` in shape `s` (6 per node),
/// and the part of the motion it leaves, |u − u_rigid|² / |u|².
fn rigid_fit(mesh: &Mesh, nodes: &[usize], s: &[f64], c: [f64; 3]) -> ([f64; 6], f64) {
    let mut ata = nalgebra::Matrix6::<f64>::zeros();
    let mut atb = nalgebra::Vector6::<f64>::zeros();
    for &a in nodes {
        let x = mesh.nodes[a];
        let t = rigid_offset([x[0] - c[0], x[1] - c[1], x[2] - c[2]]);
        for r in 0..3 {
            for i in 0..6 {
                atb[i] += t[r][i] * s[6 * a + r];
                for j in 0..6 {
                    ata[(i, j)] += t[r][i] * t[r][j];
                }
            }
        }
    }
    let p = ata.lu().solve(&atb).unwrap_or_else(nalgebra::Vector6::zeros);
    let (mut res, mut tot) = (0.0, 0.0);
    for &a in nodes {
        let x = mesh.nodes[a];
        let t = rigid_offset([x[0] - c[0], x[1] - c[1], x[2] - c[2]]);
        for r in 0..3 {
            let fit: f64 = (0..6).map(|i| t[r][i] * p[i]).sum();
            let u = s[6 * a + r];
            res += (u - fit) * (u - fit);
            tot += u * u;
        }
    }
    let mut out = [0.0; 6];
    out.copy_from_slice(p.as_slice());
    (out, if tot > 0.0 { res / tot } else { 0.0 })
}

/// Plan view of the work surface coloured by the vertical amplitude (SVG).
pub fn write_amplitude_svg(path: &std::path::Path, r: &MachineResult, excitation_hz: f64) -> Result<()> {
    use plotters::prelude::*;
    let mesh = &r.mesh;
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &(a, _) in &r.surface {
        let x = mesh.nodes[a as usize];
        for d in 0..2 {
            lo[d] = lo[d].min(x[d]);
            hi[d] = hi[d].max(x[d]);
        }
    }
    let root = SVGBackend::new(path, (900, 560)).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| Error::InvalidInput(format!("{}: plotting failed: {e}", path.display()));
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "work-surface amplitude at {excitation_hz} Hz: mean {:.4} mm, min {:.4}, max {:.4}, non-uniformity {:.1} %",
                r.mean * 1e3,
                r.min * 1e3,
                r.max * 1e3,
                100.0 * r.nonuniformity
            ),
            ("sans-serif", 16),
        )
        .margin(15)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(lo[0] - 0.02..hi[0] + 0.02, lo[1] - 0.02..hi[1] + 0.02)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("x [m]")
        .y_desc("y [m]  (colour: blue = min, red = max)")
        .draw()
        .map_err(|e| err(&e))?;
    let span = (r.max - r.min).max(1e-300);
    chart
        .draw_series(r.surface.iter().map(|&(a, amp)| {
            let x = mesh.nodes[a as usize];
            let v = ((amp - r.min) / span).clamp(0.0, 1.0);
            let c = RGBColor(
                (255.0 * v) as u8,
                (80.0 * (1.0 - (2.0 * v - 1.0).abs())) as u8,
                (255.0 * (1.0 - v)) as u8,
            );
            Rectangle::new(
                [(x[0] - 0.0115, x[1] - 0.0115), (x[0] + 0.0115, x[1] + 0.0115)],
                c.filled(),
            )
        }))
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// The response over the machine's mesh as VTU: the vertical amplitude (scalar, m) and the
/// displacement's real and imaginary parts (vectors) at every node.
pub fn write_amplitude_vtu(path: &std::path::Path, r: &MachineResult) -> Result<()> {
    use crate::io::vtk::{PointField, write_vtu};
    let amp: Vec<f64> = r.response.iter().map(|u| u[2].norm()).collect();
    let re: Vec<f64> = r.response.iter().flat_map(|u| u.map(|c| c.re)).collect();
    let im: Vec<f64> = r.response.iter().flat_map(|u| u.map(|c| c.im)).collect();
    write_vtu(
        path,
        &r.mesh,
        &[
            PointField::new("amplitude_z", 1, &amp),
            PointField::new("displacement_re", 3, &re),
            PointField::new("displacement_im", 3, &im),
        ],
    )
}
