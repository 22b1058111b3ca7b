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
//! solve of the machine under the magnet forces less its part in the kept modes), by the shared
//! [`crate::analysis::harmonic::superpose_coupled`]; with a rigid table the 12-DOF machine is
//! solved exactly.

use super::file::{Design, bad};
use super::parts::{coil_stiffness, leaf_end_stiffness, leaf_matrix, table_parts};
use super::reduced;
use crate::analysis::harmonic;
use crate::analysis::modal::{ModalParams, ModalRun, ModalTarget};
use crate::dof::DofMap;
use crate::linalg::sparse::SymMatrix;
use crate::mesh::{CellBlock, CellKind, CellRef, Group, Mesh};
use crate::model::{
    CouplingSpec, Model, ModelSpec, PointMassSpec, ShellPart, SpringMatrixSpec, rigid_offset, transform_blocks,
};
use crate::section::ShellSection;
use crate::system::{System, SystemOptions};
use crate::{Error, Result};
use faer::c64;
use nalgebra::{Complex, DMatrix};
use serde::Serialize;
use std::f64::consts::TAU;

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
    /// Vertical amplitude of the relative motion across each leaf (its table end against its
    /// clamp on the reactive mass), m, in the order of `machine.leaves`.
    pub leaf_relative: Vec<f64>,
    /// Vertical amplitude of the relative motion across each magnet's gap (armature centre
    /// against the core), m, in the order of `machine.magnets`.
    pub magnet_relative: Vec<f64>,
    /// The force on the floor through the isolators at the excitation and at each harmonic of
    /// the force law that is not zero (the flux law has none above the first).
    pub floor: Vec<FloorForce>,
    /// Power dissipated by the machine's dashpots at the excitation, Ω²/2·Σ uᴴ C u, W.
    pub dissipated_power: f64,
    /// The magnets' stiffness at the working gap, all together, N/m (negative).
    pub magnet_stiffness: f64,
    /// Where the leaves' table ends, the magnets and the isolators are (plan, m), for the maps.
    #[serde(skip)]
    pub positions: [Vec<[f64; 2]>; 3],
    /// The machine in the modal coordinates of its forced response, for the start-up.
    #[serde(skip)]
    pub modal: MachineModal,
}

/// The force the isolators put on the floor at one harmonic kΩ of the drive.
#[derive(Clone, Debug, Serialize)]
pub struct FloorForce {
    /// k (1: the excitation).
    pub harmonic: u32,
    /// kΩ/2π, Hz.
    pub frequency_hz: f64,
    /// Amplitude of each isolator's vertical force on the floor, N (order of `machine.isolators`).
    pub per_isolator: Vec<f64>,
    /// Amplitude of their sum (the phases taken into account), N.
    pub total: f64,
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

/// [`patch`], or where it holds no node (a table mesh coarser than the patch) the nearest node
/// not excluded within the patch's half-diagonal plus an element size `elem` of its centre: the
/// rigid part is then tied to the plate at that node. `true` with the fallback's node.
fn patch_or_nearest(
    mesh: &Mesh,
    plate: &[u32],
    c: [f64; 2],
    e: [f64; 2],
    h: [f64; 2],
    exclude: &[bool],
    elem: f64,
) -> (Vec<u32>, bool) {
    let nodes = patch(mesh, plate, c, e, h, exclude);
    if !nodes.is_empty() {
        return (nodes, false);
    }
    let reach = (h[0].hypot(h[1]) + elem).powi(2);
    let nearest = plate
        .iter()
        .copied()
        .filter(|&a| !exclude[a as usize])
        .map(|a| {
            let x = mesh.nodes[a as usize];
            ((x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2), a)
        })
        .filter(|&(d2, _)| d2 <= reach)
        .min_by(|p, q| p.0.total_cmp(&q.0).then(p.1.cmp(&q.1)));
    (nearest.map(|(_, a)| vec![a]).unwrap_or_default(), true)
}

/// What a patch's error adds when the table's mesh is coarser than the patch.
fn coarse_hint(d: &Design, fallback: bool) -> String {
    if fallback {
        format!(
            " (table.element_size = {} m is coarser than the patch: a finer table mesh)",
            d.table.elem_size
        )
    } else {
        String::new()
    }
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

/// The parts condensed from FE: the leaf's end stiffness (6×6) and its 12×12 matrix in its own
/// axes, the coil's axial and lateral stiffness.
struct Condensed {
    kbb: [[f64; 6]; 6],
    leaf_local: Vec<f64>,
    k_ax: f64,
    k_lat: f64,
}

/// The machine's mesh: the table (shells) with the points of the machine, and where things are.
struct Layout {
    mesh: Mesh,
    /// Couplings: web links and leaf shoes (shells), or the whole table (rigid).
    couplings: Vec<CouplingSpec>,
    /// Shell groups and thicknesses.
    thick: Vec<(String, f64)>,
    /// Nodes of the table mesh (the machine's points follow them).
    n_table: usize,
    /// Centre of the table (the rigid table's reference point).
    table_centre: [f64; 3],
    /// Mesh node of the reactive mass's centre.
    reactive: u32,
    /// Work-surface nodes.
    top: Vec<u32>,
    /// Group of each leaf's table end (its shoe, or the rigid table).
    leaf_ends: Vec<String>,
    /// Nodes of each magnet's armature patch.
    armatures: Vec<Vec<u32>>,
    /// Group of each magnet's armature end (its rigid armature, or the rigid table).
    magnet_ends: Vec<String>,
}

/// The spring matrices of the machine, in global axes on their nodes.
struct Springs {
    /// Per leaf: the group of its table end and its 12×12 matrix (clamping coefficient applied).
    leaves: Vec<(String, Vec<f64>)>,
    /// Per isolator: its 6×6 matrix at the reactive mass's centre.
    isolators: Vec<Vec<f64>>,
    /// All of them as model springs.
    specs: Vec<SpringMatrixSpec>,
}

/// The reactive mass as a point mass with inertia, the armatures' and the load's masses.
struct Masses {
    specs: Vec<PointMassSpec>,
    /// Principal moments of inertia of the reactive mass (kg m²).
    inertia_r: [f64; 3],
    /// Load moving with the table (kg).
    load_mass: f64,
}

/// Build and analyse the 3D machine for design `d` with leaves of thickness `h` (m): assemble
/// it, find its modes, solve the forced response at the excitation (and at the force law's
/// harmonics, for the floor force) and name the modes.
///
/// The model without the leaves' and the magnets' stiffness ([`Base`]: the mesh, the masses, the
/// isolators, K and M assembled, the ordering) depends on neither the leaves' section, material
/// and clamping nor the damping nor the drive: it is memoised per geometry and load
/// ([`base_key`]), and each call adds the leaves' and magnets' 12×12 blocks to a copy of its K,
/// on the same pattern. That is what the assembly does with their spring elements, so a call
/// equals a build from scratch up to the order of the sums (rounding).
pub fn analyse(d: &Design, h: f64) -> Result<MachineResult> {
    d.machine.validate(d)?;
    let rigid = d.machine.table_model == "rigid";
    let parts = condensed_parts(d, h)?;
    let key = base_key(d, rigid);
    let plan = if rigid { None } else { reduced::current() };
    let base: std::sync::Arc<Base> = super::cache::get_or_large(key.clone(), || machine_base(d, &parts, rigid))?;
    let springs = machine_springs(d, &parts, &base.layout, rigid);
    let (mut sys, k0) = base.take()?;
    let out = set_stiffness(d, &base, &springs, &mut sys, &k0, rigid)
        .and_then(|()| match plan.as_deref() {
            Some(p) => reduced_run(d, p, &key, &sys, &k0),
            None => Ok(None),
        })
        .and_then(|pre| analyse_on(d, &parts, &base, &springs, &sys, rigid, pre));
    base.give_back(sys, k0);
    out
}

/// The run of `d` in its base's reduced basis under `plan` ([`super::reduced`]), if the plan
/// has a basis for the base `key` and every mode the run uses passes the plan's bar; `None`:
/// run the full model (counted).
fn reduced_run(
    d: &Design,
    plan: &reduced::Plan,
    key: &str,
    sys: &System,
    k0: &SymMatrix,
) -> Result<Option<reduced::ReducedRun>> {
    let Some(basis) = plan.basis(key) else {
        plan.count(None, false);
        return Ok(None);
    };
    let want = sys.n_free().min(SHELL_MODES);
    let lambda_used = (TAU * d.machine.response_range * d.excitation_hz).powi(2);
    match reduced::run_in(&basis, sys.k(), k0, sys.m()?, want, lambda_used, plan.tol)? {
        Ok(r) => {
            plan.count(Some(r.backward), false);
            Ok(Some(r))
        }
        Err(_) => {
            plan.count(None, true);
            Ok(None)
        }
    }
}

/// Build the reduced basis of design `d`'s machine (leaves of its own thickness and the load
/// case's masses as the reference) into `plan`, unless the table is rigid (12 DOFs: every run
/// is full), reduction is off or the plan has one for its base already.
pub fn prepare_basis(d: &Design, plan: &reduced::Plan) -> Result<()> {
    d.machine.validate(d)?;
    let rigid = d.machine.table_model == "rigid";
    let key = base_key(d, rigid);
    if rigid || !plan.enabled || plan.has(&key) {
        return Ok(());
    }
    let parts = condensed_parts(d, d.leaf.thickness)?;
    let base: std::sync::Arc<Base> = super::cache::get_or_large(key.clone(), || machine_base(d, &parts, rigid))?;
    let springs = machine_springs(d, &parts, &base.layout, rigid);
    let (mut sys, k0) = base.take()?;
    let basis = set_stiffness(d, &base, &springs, &mut sys, &k0, rigid).and_then(|()| basis_on(d, &base, &sys, &k0));
    base.give_back(sys, k0);
    plan.insert(key, basis?);
    Ok(())
}

/// The basis of [`super::reduced`] on `sys` (K0: its K; `k_base`: without leaves and magnets):
/// the modes up to [`reduced::REFERENCE_RANGE`] × the response range, the attachment DOFs (the
/// leaves' and magnets' end nodes and the reactive mass's centre) and the magnets' force pattern.
fn basis_on(d: &Design, base: &Base, sys: &System, k_base: &SymMatrix) -> Result<reduced::Basis> {
    let f_ref = reduced::REFERENCE_RANGE * d.machine.response_range * d.excitation_hz;
    let run = crate::analysis::modal::solve(
        sys,
        &ModalParams {
            target: ModalTarget::Band(0.0, f_ref),
            ..Default::default()
        },
    )?;
    if !run.report.complete {
        return Err(Error::Verification("machine reduced basis: a mode was missed".into()));
    }
    let dofs = sys.dofs();
    let mut att = vec![];
    let reactive = base.layout.reactive as usize;
    for &a in base.leaf_nodes.iter().chain(&base.magnet_nodes).chain([&reactive]) {
        for c in 0..6 {
            if let Some(e) = dofs.eq_of(a, c) {
                if !att.contains(&e) {
                    att.push(e);
                }
            }
        }
    }
    let load = harmonic::load_vector(sys, &magnet_forces(d, &base.layout, 1)?)?;
    let pattern: Vec<f64> = load.iter().map(|v| v.re).collect();
    reduced::Basis::build(
        k_base,
        sys.k(),
        sys.m()?,
        sys.symbolic()?.clone(),
        &run,
        att,
        &[pattern],
    )
}

/// Modes a run of the machine with the shell table computes.
const SHELL_MODES: usize = 24;

/// The machine's modes on `sys` (24 with the shell table, 12 rigid), verified complete.
fn machine_run(sys: &System, rigid: bool) -> Result<ModalRun> {
    let want = sys.n_free().min(if rigid { 12 } else { SHELL_MODES });
    let run = crate::analysis::modal::solve(
        sys,
        &ModalParams {
            target: ModalTarget::Modes(want),
            ..Default::default()
        },
    )?;
    if !run.report.complete {
        return Err(Error::Verification("machine modal analysis: a mode was missed".into()));
    }
    Ok(run)
}

/// [`analyse`] on the system `sys` with the leaves and magnets in its K: its modes and static
/// solves from the full model, or from the reduced run `pre`.
fn analyse_on(
    d: &Design,
    parts: &Condensed,
    base: &Base,
    springs: &Springs,
    sys: &System,
    rigid: bool,
    pre: Option<reduced::ReducedRun>,
) -> Result<MachineResult> {
    let layout = &base.layout;
    let masses = &base.masses;
    let (leaf_nodes, table_ref, magnet_nodes) = (&base.leaf_nodes, base.table_ref, &base.magnet_nodes);
    let (run, statics) = match pre {
        Some(p) => (p.run, Some(p.statics)),
        None => (machine_run(sys, rigid)?, None),
    };
    let dofs = sys.dofs().n_free;
    let f_resp = d.machine.response_range * d.excitation_hz;
    let n_use = run
        .lambda
        .iter()
        .position(|&l| l.max(0.0).sqrt() / TAU > f_resp)
        .map_or(run.lambda.len(), |k| k.max(1));
    let dm = sys.dofs();
    let shapes: Vec<Vec<f64>> = (0..n_use)
        .map(|k| dm.expand(&crate::linalg::eigen::column(&run.vectors, k), 6))
        .collect();
    let pots = dashpots(d, parts, layout, springs, leaf_nodes);
    let cr = modal_damping(&pots, &shapes);
    let omega = TAU * d.excitation_hz;
    let full = forced_response(d, layout, sys, &run, &cr, 1, statics.as_ref())?;
    let response: Vec<[Complex<f64>; 3]> = (0..layout.mesh.n_nodes())
        .map(|a| std::array::from_fn(|c| full[a][c]))
        .collect();
    let surface: Vec<(u32, f64)> = layout
        .top
        .iter()
        .map(|&a| (a, response[a as usize][2].norm()))
        .collect();
    let amps: Vec<f64> = surface.iter().map(|x| x.1).collect();
    let mean = amps.iter().sum::<f64>() / amps.len() as f64;
    let min = amps.iter().copied().fold(f64::INFINITY, f64::min);
    let max = amps.iter().copied().fold(0.0, f64::max);
    let modes = name_modes(d, layout, springs, masses, &run, &shapes, leaf_nodes, table_ref);
    let (working, nearest_other) = working_mode(d, modes.as_slice());
    let reactive_amplitude = response[layout.reactive as usize][2].norm();
    let table_mass = run.report.mass_kg - d.masses.reactive - d.masses.active_extra - masses.load_mass;
    let (leaf_relative, magnet_relative) = relative_motions(d, layout, &full, leaf_nodes, magnet_nodes, rigid);
    let mut floor = vec![floor_force(d, parts, layout, &full, 1)];
    for k in 2..=3u32 {
        if d.magnet_drive()?.cos_coefficient(k) != 0.0 {
            let uk = forced_response(d, layout, sys, &run, &cr, k, statics.as_ref())?;
            floor.push(floor_force(d, parts, layout, &uk, k));
        }
    }
    let dissipated_power = 0.5 * omega * omega * pots.iter().map(|p| dissipation(p, &full)).sum::<f64>();
    Ok(MachineResult {
        modal: machine_modal(d, parts, base, sys, &run, &shapes, &cr, &full, &modes, rigid)?,
        modes,
        working,
        nearest_other,
        mean,
        min,
        max,
        nonuniformity: (max - min) / mean,
        reactive_amplitude,
        table_mass,
        leaf_kzz: parts.kbb[2][2],
        coil_axial: parts.k_ax,
        coil_lateral: parts.k_lat,
        dofs,
        response_modes: (n_use, run.lambda[n_use - 1].max(0.0).sqrt() / TAU),
        surface,
        mesh: layout.mesh.clone(),
        response,
        leaf_relative,
        magnet_relative,
        floor,
        dissipated_power,
        magnet_stiffness: d.magnet_stiffness()?,
        positions: [
            d.machine.leaves.iter().map(|l| [l[0], l[1]]).collect(),
            d.machine.magnets.clone(),
            d.machine.isolators.iter().map(|i| [i[0], i[1]]).collect(),
        ],
    })
}

/// Vertical displacement at plan point `p` of a body whose reference node at `r` moves by `u`
/// (6 components): u_z + θ_x·(p_y − r_y) − θ_y·(p_x − r_x).
fn uz_at(u: &[Complex<f64>; 6], r: [f64; 3], p: [f64; 2]) -> Complex<f64> {
    u[2] + u[3] * (p[1] - r[1]) - u[4] * (p[0] - r[0])
}

/// The vertical amplitude across each leaf (table end against clamp) and across each magnet's
/// gap (armature centre against the core below it).
fn relative_motions(
    d: &Design,
    layout: &Layout,
    full: &[[Complex<f64>; 6]],
    leaf_nodes: &[usize],
    magnet_nodes: &[usize],
    rigid: bool,
) -> (Vec<f64>, Vec<f64>) {
    let md = &d.machine;
    let rc = md.reactive_centre;
    let ur = &full[layout.reactive as usize];
    let leaves = md
        .leaves
        .iter()
        .zip(leaf_nodes)
        .map(|(l, &a)| {
            let n = (l[2] * l[2] + l[3] * l[3]).sqrt();
            let clamp = [l[0] + d.leaf.length * l[2] / n, l[1] + d.leaf.length * l[3] / n];
            let a_ref = if rigid {
                layout.table_centre
            } else {
                [l[0], l[1], md.leaf_level]
            };
            (uz_at(&full[a], a_ref, [l[0], l[1]]) - uz_at(ur, rc, clamp)).norm()
        })
        .collect();
    let magnets = md
        .magnets
        .iter()
        .zip(magnet_nodes)
        .map(|(m, &a)| {
            let a_ref = if rigid { layout.table_centre } else { [m[0], m[1], 0.0] };
            (uz_at(&full[a], a_ref, *m) - uz_at(ur, rc, *m)).norm()
        })
        .collect();
    (leaves, magnets)
}

/// The isolators' vertical forces on the floor at harmonic `k`: (k_axial + ikΩ·μ13/n)·u_z at
/// each isolator (the reactive mass's motion there), and their sum.
fn floor_force(d: &Design, parts: &Condensed, layout: &Layout, full: &[[Complex<f64>; 6]], k: u32) -> FloorForce {
    let w = k as f64 * TAU * d.excitation_hz;
    let n = d.coil.count as f64;
    let kz = Complex::new(parts.k_ax, w * d.damping.mu13 / n);
    let ur = &full[layout.reactive as usize];
    let rc = d.machine.reactive_centre;
    let f: Vec<Complex<f64>> = d
        .machine
        .isolators
        .iter()
        .map(|p| kz * uz_at(ur, rc, [p[0], p[1]]))
        .collect();
    FloorForce {
        harmonic: k,
        frequency_hz: k as f64 * d.excitation_hz,
        per_isolator: f.iter().map(|x| x.norm()).collect(),
        total: f.iter().sum::<Complex<f64>>().norm(),
    }
}

/// uᴴ C u over a dashpot's nodes (the mean dissipation is Ω²/2 of it).
fn dissipation(p: &Dashpot, full: &[[Complex<f64>; 6]]) -> f64 {
    let u: Vec<Complex<f64>> = p.nodes.iter().flat_map(|&a| full[a]).collect();
    let n = u.len();
    let mut s = 0.0;
    for i in 0..n {
        for j in 0..n {
            s += (u[i].conj() * p.c[i * n + j] * u[j]).re;
        }
    }
    s
}

/// The leaf and the coil condensed from their FE models.
fn condensed_parts(d: &Design, h: f64) -> Result<Condensed> {
    let kbb = leaf_end_stiffness(d, h)?;
    let leaf_local = leaf_matrix(&kbb, d.leaf.length);
    let (k_ax, k_lat) = coil_stiffness(d)?;
    Ok(Condensed {
        kbb,
        leaf_local,
        k_ax,
        k_lat,
    })
}

/// The table mesh with the machine's points: the reactive mass's centre, the leaves' shoes (or
/// the whole table as one rigid body) and the magnets' armature patches.
fn machine_layout(d: &Design, rigid: bool) -> Result<Layout> {
    let md = &d.machine;
    let (mut mesh, links, thick) = table_parts(d)?;
    let n_table = mesh.n_nodes();
    let hz = d.sandwich().mid_surface_spacing();
    let table_centre = [0.0, 0.0, 0.5 * hz];
    let bottom = mesh.group_nodes(mesh.group("bottom_plate")?);
    let top = mesh.group_nodes(mesh.group("top_plate")?);
    let bp = mesh.blocks.len() as u32;
    let mut block = CellBlock::new(CellKind::Point1);
    mesh.nodes.push(md.reactive_centre);
    mesh.node_tags
        .push(mesh.node_tags.iter().copied().max().unwrap_or(0) + 1);
    let reactive = (mesh.nodes.len() - 1) as u32;
    point_group(&mut mesh, &mut block, bp, "reactive", &[reactive]);
    let mut couplings = vec![];
    let mut shoe_nodes = vec![false; n_table];
    let leaf_ends = if rigid {
        let all: Vec<u32> = (0..n_table as u32).collect();
        point_group(&mut mesh, &mut block, bp, "table_body", &all);
        couplings.push(CouplingSpec {
            group: "table_body".into(),
            guided: None,
            reference: Some(table_centre),
        });
        vec!["table_body".to_string(); md.leaves.len()]
    } else {
        couplings.extend(links);
        leaf_shoes(d, &mut mesh, &mut block, bp, &bottom, &mut shoe_nodes, &mut couplings)?
    };
    let armatures = armature_patches(d, &mut mesh, &mut block, bp, &bottom, shoe_nodes, rigid, &mut couplings)?;
    let magnet_ends = (0..armatures.len())
        .map(|i| {
            if rigid {
                "table_body".to_string()
            } else {
                format!("armature_{}", i + 1)
            }
        })
        .collect();
    load_patch(d, &mut mesh, &mut block, bp, &top)?;
    mesh.blocks.push(block);
    Ok(Layout {
        mesh,
        couplings,
        thick,
        n_table,
        table_centre,
        reactive,
        top,
        leaf_ends,
        armatures,
        magnet_ends,
    })
}

/// Each leaf's shoe: the bottom-plate nodes under it (web-link nodes excepted), tied rigidly to
/// the leaf's end point. Returns the shoes' group names.
fn leaf_shoes(
    d: &Design,
    mesh: &mut Mesh,
    block: &mut CellBlock,
    bp: u32,
    bottom: &[u32],
    used: &mut [bool],
    couplings: &mut Vec<CouplingSpec>,
) -> Result<Vec<String>> {
    let md = &d.machine;
    let n_table = used.len();
    let mut in_link = vec![false; n_table];
    for g in mesh.groups.iter().filter(|g| g.name.starts_with("web_link_")) {
        for a in mesh.group_nodes(g) {
            in_link[a as usize] = true;
        }
    }
    let mut shoes = vec![];
    for (i, l) in md.leaves.iter().enumerate() {
        let n = (l[2] * l[2] + l[3] * l[3]).sqrt();
        let e = [l[2] / n, l[3] / n];
        let (nodes, fallback) = patch_or_nearest(
            mesh,
            bottom,
            [l[0], l[1]],
            e,
            [0.5 * md.shoe_length, 0.5 * d.leaf.width],
            &in_link,
            d.table.elem_size,
        );
        let at = format!("leaf {} at ({}, {}) m", i + 1, l[0], l[1]);
        let hint = coarse_hint(d, fallback);
        if nodes.is_empty() {
            return Err(bad(
                "machine.leaves",
                format!("{at}: its shoe covers no node of the bottom plate{hint}"),
            ));
        }
        if nodes.iter().any(|&a| used[a as usize]) {
            return Err(bad(
                "machine.leaves",
                format!("{at}: its shoe overlaps another leaf's{hint}"),
            ));
        }
        nodes.iter().for_each(|&a| used[a as usize] = true);
        let name = format!("leaf_shoe_{}", i + 1);
        point_group(mesh, block, bp, &name, &nodes);
        couplings.push(CouplingSpec {
            group: name.clone(),
            guided: None,
            reference: Some([l[0], l[1], md.leaf_level]),
        });
        shoes.push(name);
    }
    Ok(shoes)
}

/// Each magnet's armature: the bottom-plate nodes of its patch (group `armature_i`). With the
/// shell table the armature is a rigid block on them (a coupling with its reference at the
/// magnet's centre, where the magnet's stiffness acts); nodes already tied to a web link or a
/// leaf's shoe stay with those.
#[allow(clippy::too_many_arguments)]
fn armature_patches(
    d: &Design,
    mesh: &mut Mesh,
    block: &mut CellBlock,
    bp: u32,
    bottom: &[u32],
    mut tied: Vec<bool>,
    rigid: bool,
    couplings: &mut Vec<CouplingSpec>,
) -> Result<Vec<Vec<u32>>> {
    let md = &d.machine;
    let n_table = tied.len();
    if !rigid {
        for g in mesh.groups.iter().filter(|g| g.name.starts_with("web_link_")) {
            for a in mesh.group_nodes(g) {
                if (a as usize) < n_table {
                    tied[a as usize] = true;
                }
            }
        }
    }
    let mut armatures = vec![];
    for (i, m) in md.magnets.iter().enumerate() {
        let (nodes, fallback) = patch_or_nearest(
            mesh,
            bottom,
            *m,
            [1.0, 0.0],
            [0.5 * md.armature[0], 0.5 * md.armature[1]],
            &tied,
            d.table.elem_size,
        );
        if nodes.is_empty() {
            return Err(bad(
                "machine.magnets",
                format!(
                    "magnet {} at ({}, {}) m: its armature covers no node of the bottom plate{}",
                    i + 1,
                    m[0],
                    m[1],
                    coarse_hint(d, fallback)
                ),
            ));
        }
        let name = format!("armature_{}", i + 1);
        point_group(mesh, block, bp, &name, &nodes);
        if !rigid {
            nodes.iter().for_each(|&a| tied[a as usize] = true);
            couplings.push(CouplingSpec {
                group: name,
                guided: None,
                reference: Some([m[0], m[1], 0.0]),
            });
        }
        armatures.push(nodes);
    }
    Ok(armatures)
}

/// The work-surface nodes carrying an eccentric load (`masses.load_offset` off the centre):
/// those within a quarter of the table's length and width of the offset (group `load_patch`).
fn load_patch(d: &Design, mesh: &mut Mesh, block: &mut CellBlock, bp: u32, top: &[u32]) -> Result<()> {
    let o = d.masses.load_offset;
    if o == [0.0, 0.0] {
        return Ok(());
    }
    let h = [0.25 * d.table.length, 0.25 * d.table.top_width];
    let nodes = patch(mesh, top, o, [1.0, 0.0], h, &vec![false; mesh.n_nodes()]);
    if nodes.is_empty() {
        return Err(bad(
            "masses.load_offset",
            format!("{o:?} m: no work-surface node within {h:?} m of it"),
        ));
    }
    point_group(mesh, block, bp, "load_patch", &nodes);
    Ok(())
}

/// The reactive mass (a uniform block's inertia), the armatures (`masses.active_extra` shared)
/// and the load share spread over the work surface.
fn machine_masses(d: &Design, n_armatures: usize) -> Masses {
    let m2 = d.masses.reactive;
    let [a, b, c] = d.machine.reactive_box;
    let inertia_r = [
        m2 * (b * b + c * c) / 12.0,
        m2 * (a * a + c * c) / 12.0,
        m2 * (a * a + b * b) / 12.0,
    ];
    let mut specs = vec![PointMassSpec {
        group: "reactive".into(),
        mass: m2,
        inertia: [inertia_r[0], inertia_r[1], inertia_r[2], 0.0, 0.0, 0.0],
    }];
    if d.masses.active_extra > 0.0 {
        for i in 0..n_armatures {
            specs.push(PointMassSpec {
                group: format!("armature_{}", i + 1),
                mass: d.masses.active_extra / n_armatures as f64,
                inertia: [0.0; 6],
            });
        }
    }
    let load_mass = d.masses.load_share * d.masses.load;
    if load_mass > 0.0 {
        specs.push(PointMassSpec {
            group: if d.masses.load_offset == [0.0, 0.0] {
                "top_plate"
            } else {
                "load_patch"
            }
            .into(),
            mass: load_mass,
            inertia: [0.0; 6],
        });
    }
    Masses {
        specs,
        inertia_r,
        load_mass,
    }
}

/// The leaves (local → global axes, table end first, moved to their nodes, times the clamping
/// coefficient) and the isolators (axial and lateral springs to the floor, at the reactive
/// mass's centre).
fn machine_springs(d: &Design, parts: &Condensed, layout: &Layout, rigid: bool) -> Springs {
    let md = &d.machine;
    let rc = md.reactive_centre;
    let mut specs = vec![];
    let mut leaves = vec![];
    for (i, l) in md.leaves.iter().enumerate() {
        let kf = leaf_global(d, &parts.leaf_local, l, layout.table_centre, rigid);
        let a_group = layout.leaf_ends[i].clone();
        specs.push(SpringMatrixSpec {
            a: a_group.clone(),
            b: Some("reactive".into()),
            k: kf.clone(),
            label: format!("leaf {}", i + 1),
        });
        leaves.push((a_group, kf));
    }
    // Each magnet's stiffness is negative, which a spring element refuses: an empty spring puts
    // the pair of points in K's pattern, and the stiffness is added to K ([`add_magnet_stiffness`]).
    for (i, g) in layout.magnet_ends.iter().enumerate() {
        specs.push(SpringMatrixSpec {
            a: g.clone(),
            b: Some("reactive".into()),
            k: vec![0.0; 144],
            label: format!("magnet {} (gap stiffness added to K)", i + 1),
        });
    }
    let mut isolators = vec![];
    for (i, pt) in md.isolators.iter().enumerate() {
        let mut kp = vec![0.0; 36];
        kp[0] = parts.k_lat;
        kp[7] = parts.k_lat;
        kp[14] = parts.k_ax;
        let t = rigid_offset([pt[0] - rc[0], pt[1] - rc[1], pt[2] - rc[2]]);
        let k = transform_blocks(&kp, &[t]);
        specs.push(SpringMatrixSpec {
            a: "reactive".into(),
            b: None,
            k: k.clone(),
            label: format!("isolator {}", i + 1),
        });
        isolators.push(k);
    }
    Springs {
        leaves,
        isolators,
        specs,
    }
}

/// One leaf's 12×12 matrix in global axes, its table end first, between its table-end node (the
/// shoe's reference, or the rigid table's centre) and the reactive mass's centre.
fn leaf_global(d: &Design, leaf_local: &[f64], l: &[f64; 4], table_centre: [f64; 3], rigid: bool) -> Vec<f64> {
    let md = &d.machine;
    let rc = md.reactive_centre;
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
    let kg = transform_blocks(leaf_local, &[t, t]);
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
    kf.iter_mut().for_each(|v| *v *= d.leaf.clamping);
    kf
}

/// One magnet's stiffness `k` (N/m, negative) as a 12×12 matrix between its armature end
/// (`a_ref`: the armature's centre, or the rigid table's) and the reactive mass's centre: a
/// vertical spring between the armature's centre and the core below it.
fn magnet_matrix(d: &Design, m: [f64; 2], a_ref: [f64; 3], k: f64) -> Vec<f64> {
    let rc = d.machine.reactive_centre;
    let mut kp = vec![0.0; 144];
    kp[2 * 12 + 2] = k;
    kp[8 * 12 + 8] = k;
    kp[2 * 12 + 8] = -k;
    kp[8 * 12 + 2] = -k;
    let ta = rigid_offset([m[0] - a_ref[0], m[1] - a_ref[1], 0.0 - a_ref[2]]);
    let tc = rigid_offset([m[0] - rc[0], m[1] - rc[1], 0.0]);
    transform_blocks(&kp, &[ta, tc])
}

/// Add the 12×12 block `km` (global axes) between `nodes` to `k` on its pattern.
fn add_block(k: &mut SymMatrix, dofs: &DofMap, nodes: [usize; 2], km: &[f64], what: &str) -> Result<()> {
    for r in 0..12 {
        for c in 0..12 {
            let v = km[r * 12 + c];
            if v == 0.0 {
                continue;
            }
            let (Some(er), Some(ec)) = (dofs.eq_of(nodes[r / 6], r % 6), dofs.eq_of(nodes[c / 6], c % 6)) else {
                continue;
            };
            let pos = k
                .pattern
                .position(er, ec)
                .ok_or_else(|| Error::Verification(format!("machine: {what} is not in the stiffness pattern")))?;
            k.values[pos] += v;
        }
    }
    Ok(())
}

/// K of `sys`: the base's `k0` with each leaf's matrix (clamping coefficient applied) and each
/// magnet's (negative) stiffness at the working gap added between its end node and the reactive
/// mass's node (their pairs are in K's pattern through the base's empty springs).
fn set_stiffness(
    d: &Design,
    base: &Base,
    springs: &Springs,
    sys: &mut System,
    k0: &SymMatrix,
    rigid: bool,
) -> Result<()> {
    let layout = &base.layout;
    let reactive = layout.reactive as usize;
    let mut k = k0.clone();
    let dofs = sys.dofs().clone();
    for (i, (_, kf)) in springs.leaves.iter().enumerate() {
        add_block(
            &mut k,
            &dofs,
            [base.leaf_nodes[i], reactive],
            kf,
            &format!("leaf {}", i + 1),
        )?;
    }
    let k_each = d.magnet_stiffness()? / d.machine.magnets.len() as f64;
    if k_each != 0.0 {
        for (i, m) in d.machine.magnets.iter().enumerate() {
            let a_ref = if rigid { layout.table_centre } else { [m[0], m[1], 0.0] };
            let km = magnet_matrix(d, *m, a_ref, k_each);
            add_block(
                &mut k,
                &dofs,
                [base.magnet_nodes[i], reactive],
                &km,
                &format!("magnet {}", i + 1),
            )?;
        }
    }
    sys.replace_stiffness(k)?;
    Ok(())
}

/// The machine without the leaves' and the magnets' stiffness: its mesh and masses, the model
/// with their springs empty (their pairs of nodes in K's pattern), systems of it (each with its K
/// as assembled) ready for [`analyse`], and the model nodes of each leaf's table end, of the rigid
/// table's centre and of each magnet's armature end.
struct Base {
    layout: Layout,
    masses: Masses,
    spec: ModelSpec,
    leaf_nodes: Vec<usize>,
    table_ref: Option<usize>,
    magnet_nodes: Vec<usize>,
    /// Systems not in use (at most one per thread that ran at once), with their K as assembled.
    pool: std::sync::Mutex<Vec<(System, SymMatrix)>>,
}

impl Base {
    /// A system of the base (from the pool, or built) and its K as assembled.
    fn take(&self) -> Result<(System, SymMatrix)> {
        if let Some(s) = self.pool.lock().unwrap_or_else(|e| e.into_inner()).pop() {
            return Ok(s);
        }
        let model = Model::build(&self.layout.mesh, &self.spec, "machine")?;
        let sys = System::build(model, &SystemOptions::default(), "machine")?;
        let k0 = sys.k().clone();
        Ok((sys, k0))
    }

    /// Return a system taken with [`Base::take`].
    fn give_back(&self, sys: System, k0: SymMatrix) {
        self.pool.lock().unwrap_or_else(|e| e.into_inner()).push((sys, k0));
    }
}

/// The memo key of the machine's base: the design without what [`analyse`] applies on each call
/// (the leaves' thickness, material and clamping, the damping, the excitation and the drive) and
/// without what no part of the machine reads (its name, targets, tuning, search and envelope).
fn base_key(d: &Design, rigid: bool) -> String {
    let paper = Design::paper();
    let mut b = d.clone();
    b.name.clear();
    b.excitation_hz = 0.0;
    b.target_amplitude = 0.0;
    b.target_detuning = 0.0;
    b.tune.clear();
    let (length, width) = (d.leaf.length, d.leaf.width);
    b.leaf = paper.leaf;
    b.leaf.length = length;
    b.leaf.width = width;
    b.drive = paper.drive;
    b.damping = paper.damping;
    b.search = paper.search;
    b.envelope = paper.envelope;
    super::cache::key(if rigid { "machine_base_rigid" } else { "machine_base" }, &b)
}

/// The key under which [`analyse`] memoises design `d`'s machine without its leaves and magnets
/// (see [`base_key`]): equal for designs that differ only in the leaves' thickness, material or
/// clamping, the damping, the drive or the excitation; different when the geometry or the load
/// differs.
pub fn base_memo_key(d: &Design) -> String {
    base_key(d, d.machine.table_model == "rigid")
}

/// Build the machine's [`Base`] for design `d` (the coil from `parts`).
fn machine_base(d: &Design, parts: &Condensed, rigid: bool) -> Result<Base> {
    let layout = machine_layout(d, rigid)?;
    let masses = machine_masses(d, layout.armatures.len());
    let mut springs = machine_springs(d, parts, &layout, rigid);
    for s in springs.specs.iter_mut().filter(|s| s.label.starts_with("leaf ")) {
        s.k = vec![0.0; 144];
    }
    let shells = layout
        .thick
        .iter()
        .map(|(g, t)| ShellPart {
            group: g.clone(),
            section: ShellSection::new(*t),
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
        couplings: layout.couplings.clone(),
        point_masses: masses.specs.clone(),
        spring_matrices: springs.specs.clone(),
        ..Default::default()
    };
    let model = Model::build(&layout.mesh, &spec, "machine")?;
    let node_of = |g: &str| -> Result<usize> {
        if g == "reactive" {
            return Ok(layout.reactive as usize);
        }
        model
            .references
            .iter()
            .find(|r| r.group == g)
            .map(|r| r.node)
            .ok_or_else(|| Error::Verification(format!("machine: no reference node for '{g}'")))
    };
    let leaf_nodes: Vec<usize> = springs.leaves.iter().map(|(g, _)| node_of(g)).collect::<Result<_>>()?;
    let table_ref = if rigid { Some(node_of("table_body")?) } else { None };
    let magnet_nodes: Vec<usize> = layout.magnet_ends.iter().map(|g| node_of(g)).collect::<Result<_>>()?;
    let sys = System::build(model, &SystemOptions::default(), "machine")?;
    let k0 = sys.k().clone();
    Ok(Base {
        layout,
        masses,
        spec,
        leaf_nodes,
        table_ref,
        magnet_nodes,
        pool: std::sync::Mutex::new(vec![(sys, k0)]),
    })
}

/// Node `a`'s six components of shape `s`.
fn at(s: &[f64], a: usize) -> [f64; 6] {
    let mut v = [0.0; 6];
    v.copy_from_slice(&s[6 * a..6 * a + 6]);
    v
}

/// The components of `nodes` in shape `s`, node after node.
fn gather(s: &[f64], nodes: &[usize]) -> Vec<f64> {
    nodes.iter().flat_map(|&a| at(s, a)).collect()
}

/// xᵀ C y for a dense n×n `c`.
fn quad(x: &[f64], c: &[f64], y: &[f64]) -> f64 {
    let n = x.len();
    mat6_mul_vec(c, n, y).iter().zip(x).map(|(a, b)| a * b).sum()
}

/// The two-mass model's dashpots placed where they act: μ12 proportional to each leaf's
/// matrix, μ13 to each isolator's, μ1 shared by the work-surface nodes vertically.
fn dashpots(d: &Design, parts: &Condensed, layout: &Layout, springs: &Springs, leaf_nodes: &[usize]) -> Vec<Dashpot> {
    let reactive = layout.reactive as usize;
    let c12 = d.leaf.count as f64 * d.leaf.clamping * parts.kbb[2][2];
    let c13 = d.coil.count as f64 * parts.k_ax;
    let mut dashpots = vec![];
    for (i, (_, k)) in springs.leaves.iter().enumerate() {
        dashpots.push(Dashpot {
            nodes: vec![leaf_nodes[i], reactive],
            c: k.iter().map(|v| v * d.damping.mu12 / c12).collect(),
        });
    }
    for k in &springs.isolators {
        dashpots.push(Dashpot {
            nodes: vec![reactive],
            c: k.iter().map(|v| v * d.damping.mu13 / c13).collect(),
        });
    }
    for &a in &layout.top {
        let mut c = vec![0.0; 36];
        c[14] = d.damping.mu1 / layout.top.len() as f64;
        dashpots.push(Dashpot {
            nodes: vec![a as usize],
            c,
        });
    }
    dashpots
}

/// The modal damping matrix Φᵀ C Φ of the dashpots over `shapes`.
fn modal_damping(dashpots: &[Dashpot], shapes: &[Vec<f64>]) -> DMatrix<f64> {
    let n_use = shapes.len();
    let mut cr = DMatrix::<f64>::zeros(n_use, n_use);
    for dp in dashpots {
        let loc: Vec<Vec<f64>> = shapes.iter().map(|s| gather(s, &dp.nodes)).collect();
        for i in 0..n_use {
            let ci = mat6_mul_vec(&dp.c, loc[i].len(), &loc[i]);
            for j in 0..n_use {
                cr[(i, j)] += ci.iter().zip(&loc[j]).map(|(a, b)| a * b).sum::<f64>();
            }
        }
    }
    cr
}

/// The magnets' forces at harmonic `k` of the force law: −F_k/n on each armature (shared by its
/// nodes), +F_k/n at each core on the reactive mass (a force and a moment at its centre); F_k
/// the amplitude of the law's cos(kΩt) term.
fn magnet_forces(d: &Design, layout: &Layout, k: u32) -> Result<Vec<(usize, [c64; 6])>> {
    let md = &d.machine;
    let rc = md.reactive_centre;
    let f_mag = d.magnet_drive()?.cos_coefficient(k).abs() / md.magnets.len() as f64;
    let c0 = c64::new(0.0, 0.0);
    let mut forces: Vec<(usize, [c64; 6])> = vec![];
    for nodes in &layout.armatures {
        for &a in nodes {
            let mut f = [c0; 6];
            f[2] = c64::new(-f_mag / nodes.len() as f64, 0.0);
            forces.push((a as usize, f));
        }
    }
    let mut f_r = [c0; 6];
    for m in &md.magnets {
        let r = [m[0] - rc[0], m[1] - rc[1]];
        // f = (0, 0, F): moment r × f = (r_y F, −r_x F, 0).
        f_r[2] += c64::new(f_mag, 0.0);
        f_r[3] += c64::new(r[1] * f_mag, 0.0);
        f_r[4] += c64::new(-r[0] * f_mag, 0.0);
    }
    forces.push((layout.reactive as usize, f_r));
    Ok(forces)
}

/// The steady response at harmonic `k` of the excitation (kΩ) per model node (six
/// components): modal superposition over the modes with the full modal damping matrix `cr`,
/// plus the static correction for the modes left out (it carries the local bending of the
/// plates under the armatures), by the shared
/// [`crate::analysis::harmonic::superpose_coupled`].
fn forced_response(
    d: &Design,
    layout: &Layout,
    sys: &System,
    run: &ModalRun,
    cr: &DMatrix<f64>,
    k: u32,
    statics: Option<&reduced::Statics>,
) -> Result<Vec<[Complex<f64>; 6]>> {
    let omega = k as f64 * TAU * d.excitation_hz;
    let load = harmonic::load_vector(sys, &magnet_forces(d, layout, k)?)?;
    let u = match statics {
        Some(s) => harmonic::superpose_coupled_given(sys, run, &load, omega, cr, s.static_solve(&load))?,
        None => harmonic::superpose_coupled(sys, run, &load, omega, cr, true)?,
    };
    let nodes = harmonic::expand(sys, &u);
    Ok(nodes
        .iter()
        .map(|n| std::array::from_fn(|c| Complex::new(n[c].re, n[c].im)))
        .collect())
}

/// The modes up to `mode_range` × the excitation, each with its strain-energy split and a name
/// from where that energy sits and how the two bodies move ([`unique_names`]).
#[allow(clippy::too_many_arguments)]
fn name_modes(
    d: &Design,
    layout: &Layout,
    springs: &Springs,
    masses: &Masses,
    run: &ModalRun,
    shapes: &[Vec<f64>],
    leaf_nodes: &[usize],
    table_ref: Option<usize>,
) -> Vec<MachineMode> {
    let reactive = layout.reactive as usize;
    let m2 = d.masses.reactive;
    let ir = masses.inertia_r;
    let mr = [m2, m2, m2, ir[0], ir[1], ir[2]];
    let f_list = d.machine.mode_range * d.excitation_hz;
    let table_nodes: Vec<usize> = (0..layout.n_table).collect();
    let mut modes = vec![];
    let mut motion = vec![];
    for (k, s) in shapes.iter().enumerate() {
        let lam = run.lambda[k].max(0.0);
        let f = lam.sqrt() / TAU;
        if f > f_list {
            break;
        }
        let mut u_leaf = 0.0;
        for (i, (_, kk)) in springs.leaves.iter().enumerate() {
            let x = gather(s, &[leaf_nodes[i], reactive]);
            u_leaf += quad(&x, kk, &x);
        }
        let ur = at(s, reactive);
        let u_iso: f64 = springs.isolators.iter().map(|kk| quad(&ur, kk, &ur)).sum();
        let lam_s = lam.max(1e-300);
        let (e_leaf, e_iso) = ((u_leaf / lam_s).clamp(0.0, 1.0), (u_iso / lam_s).clamp(0.0, 1.0));
        let e_table = (1.0 - e_leaf - e_iso).max(0.0);
        let kin_r: f64 = (0..6).map(|c| mr[c] * ur[c] * ur[c]).sum();
        // The table's rigid-body motion at its centre: least squares over its nodes.
        let (pt, deform) = match table_ref {
            Some(a) => (at(s, a), 0.0),
            None => rigid_fit(&layout.mesh, &table_nodes, s, layout.table_centre),
        };
        motion.push(mode_motion(d, layout.table_centre, [e_leaf, e_iso, e_table], &pt, &ur));
        modes.push(MachineMode {
            frequency_hz: f,
            name: String::new(),
            energy_leaves: e_leaf,
            energy_isolators: e_iso,
            energy_table: e_table,
            kinetic_reactive: kin_r,
            table_deformation: deform,
        });
    }
    let names = unique_names(&motion, &modes);
    for (m, n) in modes.iter_mut().zip(names) {
        m.name = n;
    }
    modes
}

/// Names of the isolation modes (the machine as one body on the isolators), by the reactive
/// mass's motion: x, y, z, about x, about y, about z.
pub const ISOLATION_NAMES: [&str; 6] = [
    "isolation: sway x",
    "isolation: sway y",
    "isolation: bounce",
    "isolation: rocking about x",
    "isolation: rocking about y",
    "isolation: yaw",
];

/// Names of the table's modes on the leaves, by its motion against the reactive mass.
pub const LEAF_NAMES: [&str; 6] = [
    "table surge x on the leaves",
    "table sway y on the leaves",
    "working mode (masses in vertical antiphase)",
    "table roll on the leaves (about x)",
    "table pitch on the leaves (about y)",
    "table yaw on the leaves",
];

/// Which family a mode belongs to (0: isolation, 1: on the leaves, 2: table elastic) and the
/// share of each of the six motions in it (the reactive mass's for an isolation mode, the table's
/// relative to the reactive mass for a mode on the leaves; rotations weighted as the motion they
/// give 0.3 m from the centre).
fn mode_motion(
    d: &Design,
    table_centre: [f64; 3],
    energy: [f64; 3],
    pt: &[f64; 6],
    ur: &[f64; 6],
) -> (usize, [f64; 6]) {
    let [e_leaf, e_iso, e_table] = energy;
    let rc = d.machine.reactive_centre;
    let scale = 0.3;
    let weights = |v: &[f64; 6]| -> [f64; 6] {
        let w: [f64; 6] = std::array::from_fn(|c| {
            if c < 3 {
                v[c] * v[c]
            } else {
                scale * scale * v[c] * v[c]
            }
        });
        let sum: f64 = w.iter().sum::<f64>().max(1e-300);
        w.map(|x| x / sum)
    };
    if e_iso >= e_leaf && e_iso >= e_table {
        (0, weights(ur))
    } else if e_table > e_leaf {
        (2, [0.0; 6])
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
        (1, weights(&rel))
    }
}

/// One name per mode, none twice: within the isolation modes and within the modes on the
/// leaves each of the six motions names the mode with the largest share of it (largest share
/// first); a mode left over is named by its largest motion with "(higher)"; table elastic
/// modes are numbered.
fn unique_names(motion: &[(usize, [f64; 6])], modes: &[MachineMode]) -> Vec<String> {
    let mut names = vec![String::new(); motion.len()];
    for (family, list) in [(0usize, ISOLATION_NAMES), (1, LEAF_NAMES)] {
        let members: Vec<usize> = (0..motion.len()).filter(|&i| motion[i].0 == family).collect();
        let mut pairs: Vec<(f64, usize, usize)> = members
            .iter()
            .flat_map(|&i| (0..6).map(move |c| (motion[i].1[c], i, c)))
            .collect();
        pairs.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut used = [false; 6];
        for (_, i, c) in pairs {
            if names[i].is_empty() && !used[c] {
                names[i] = list[c].to_string();
                used[c] = true;
            }
        }
        for &i in &members {
            if names[i].is_empty() {
                let c = (0..6)
                    .max_by(|&a, &b| motion[i].1[a].total_cmp(&motion[i].1[b]))
                    .unwrap_or(2);
                names[i] = format!("{} (higher)", list[c]);
            }
        }
    }
    let mut n_el = 0;
    for (i, m) in modes.iter().enumerate() {
        if motion[i].0 == 2 {
            n_el += 1;
            names[i] = format!(
                "table elastic {n_el} ({:.0} % rigid-body motion)",
                100.0 * (1.0 - m.table_deformation)
            );
        }
    }
    names
}

/// The working mode (the "working" one nearest the excitation) and the other mode nearest the
/// excitation: (frequency Hz, |f − f_e|/f_e).
fn working_mode(d: &Design, modes: &[MachineMode]) -> (Option<usize>, Option<(f64, f64)>) {
    let fe = d.excitation_hz;
    let working = modes
        .iter()
        .enumerate()
        .filter(|(_, m)| m.name.starts_with("working"))
        .min_by(|a, b| (a.1.frequency_hz - fe).abs().total_cmp(&(b.1.frequency_hz - fe).abs()))
        .map(|(i, _)| i);
    let nearest_other = modes
        .iter()
        .enumerate()
        .filter(|(i, _)| Some(*i) != working)
        .map(|(_, m)| (m.frequency_hz, (m.frequency_hz - fe).abs() / fe))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    (working, nearest_other)
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

/// The colour of `v` in [0, 1] on the maps' scale (blue: low, red: high).
pub fn map_colour(v: f64) -> plotters::style::RGBColor {
    let v = v.clamp(0.0, 1.0);
    plotters::style::RGBColor(
        (255.0 * v) as u8,
        (80.0 * (1.0 - (2.0 * v - 1.0).abs())) as u8,
        (255.0 * (1.0 - v)) as u8,
    )
}

/// A vertical colour bar from `lo` to `hi` (labelled in `unit`) on `area`.
pub fn draw_colour_bar<DB: plotters::prelude::DrawingBackend>(
    area: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    lo: f64,
    hi: f64,
    unit: &str,
) -> std::result::Result<(), String> {
    use plotters::prelude::*;
    let mut chart = ChartBuilder::on(area)
        .margin_top(40)
        .margin_bottom(50)
        .margin_right(10)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..1.0, lo..hi.max(lo + 1e-300))
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_x_axis()
        .y_desc(unit)
        .y_labels(6)
        .draw()
        .map_err(|e| e.to_string())?;
    let n = 60;
    let span = hi - lo;
    chart
        .draw_series((0..n).map(|i| {
            let (a, b) = (lo + span * i as f64 / n as f64, lo + span * (i + 1) as f64 / n as f64);
            Rectangle::new([(0.0, a), (1.0, b)], map_colour((i as f64 + 0.5) / n as f64).filled())
        }))
        .map_err(|e| e.to_string())?;
    Ok(())
}

/// Plan view of the work surface coloured by the vertical amplitude (SVG), with its colour bar
/// and where the leaves' table ends (squares), the magnets (circles) and the isolators
/// (triangles) are.
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
    let root = SVGBackend::new(path, (1000, 560)).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| Error::output(path.display(), format!("plotting failed: {e}"));
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (left, right) = root.split_horizontally(880);
    let mut chart = ChartBuilder::on(&left)
        .caption(
            format!(
                "work-surface amplitude at {excitation_hz} Hz: mean {:.4} mm, min {:.4}, max {:.4}, non-uniformity {:.1} %",
                r.mean * 1e3,
                r.min * 1e3,
                r.max * 1e3,
                100.0 * r.nonuniformity
            ),
            ("sans-serif", 15),
        )
        .margin(15)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(lo[0] - 0.02..hi[0] + 0.02, lo[1] - 0.02..hi[1] + 0.02)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("x [m]   (□ leaf table end, ○ magnet, △ isolator)")
        .y_desc("y [m]")
        .draw()
        .map_err(|e| err(&e))?;
    let span = (r.max - r.min).max(1e-300);
    chart
        .draw_series(r.surface.iter().map(|&(a, amp)| {
            let x = mesh.nodes[a as usize];
            Rectangle::new(
                [(x[0] - 0.0115, x[1] - 0.0115), (x[0] + 0.0115, x[1] + 0.0115)],
                map_colour((amp - r.min) / span).filled(),
            )
        }))
        .map_err(|e| err(&e))?;
    let [leaves, magnets, isolators] = &r.positions;
    let ink = BLACK.stroke_width(2);
    chart
        .draw_series(
            leaves
                .iter()
                .map(|p| Rectangle::new([(p[0] - 0.02, p[1] - 0.02), (p[0] + 0.02, p[1] + 0.02)], ink)),
        )
        .map_err(|e| err(&e))?;
    chart
        .draw_series(magnets.iter().map(|p| Circle::new((p[0], p[1]), 9, ink)))
        .map_err(|e| err(&e))?;
    chart
        .draw_series(isolators.iter().map(|p| TriangleMarker::new((p[0], p[1]), 9, ink)))
        .map_err(|e| err(&e))?;
    draw_colour_bar(&right, r.min * 1e3, r.max * 1e3, "amplitude [mm]").map_err(|e| err(&e))?;
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

/// One output of the machine in its modal coordinates q (the modes that carry the forced
/// response): u = Σ_k `shape[k]`·q_k + `residual`·p, with p the pull per magnet (N) and
/// `residual` the static correction of the modes left out per newton of it.
#[derive(Clone, Debug, Default)]
pub struct ModalOutput {
    /// Its value per unit of each modal coordinate (the mass-normalised shapes).
    pub shape: Vec<f64>,
    /// The left-out modes' static part per newton of pull per magnet.
    pub residual: f64,
}

/// The 3D machine reduced to the modes that carry its forced response (up to
/// `machine.response_range` × the excitation), for transients:
/// q'' + C_r q' + Λ q = Φᵀf·p(t), with f the magnets' pull pattern of one newton per magnet (all
/// in phase: down on each armature, up at each core on the reactive mass) and p(t) the pull per
/// magnet; C_r = Φᵀ C Φ the coupled modal damping of the harmonic response. The outputs the
/// start-up reads are rows over the modes plus the static correction the harmonic response
/// adds for the modes left out, so a steady transient has the harmonic response's amplitudes.
#[derive(Clone, Debug, Default)]
pub struct MachineModal {
    /// Eigenvalues ω_k² of the modes used, (rad/s)².
    pub lambda: Vec<f64>,
    /// Their names (the listed modes' names; modes above `machine.mode_range` are numbered).
    pub names: Vec<String>,
    /// C_r = Φᵀ C Φ, n×n row-major, 1/s.
    pub damping: Vec<f64>,
    /// Φᵀ f for one newton of pull per magnet.
    pub force: Vec<f64>,
    /// The reactive mass's vertical displacement at each isolator (order of `machine.isolators`).
    pub isolators: Vec<ModalOutput>,
    /// Vertical motion across each leaf, table end less clamp (order of `machine.leaves`).
    pub leaves: Vec<ModalOutput>,
    /// Vertical motion across each magnet's gap, armature centre less core (order of
    /// `machine.magnets`).
    pub magnets: Vec<ModalOutput>,
    /// One isolator's axial stiffness, N/m.
    pub k_isolator: f64,
    /// One isolator's share of μ13, N s/m (its floor force is k u_z + c u_z').
    pub c_isolator: f64,
}

/// A linear functional of the nodes' six components: Σ weights · u(node).
type Functional = Vec<(usize, [f64; 6])>;

/// u_z at plan point `p` of the body whose node `a` at `r` moves rigidly (see [`uz_at`]).
fn uz_functional(a: usize, r: [f64; 3], p: [f64; 2], sign: f64) -> (usize, [f64; 6]) {
    (a, [0.0, 0.0, sign, sign * (p[1] - r[1]), -sign * (p[0] - r[0]), 0.0])
}

/// The machine's [`MachineModal`] from its run: `shapes` (expanded per model node) and `cr` of
/// the modes used, `full` the harmonic response at the excitation (for the static correction,
/// which is the part of it the modes do not give).
#[allow(clippy::too_many_arguments)]
fn machine_modal(
    d: &Design,
    parts: &Condensed,
    base: &Base,
    sys: &System,
    run: &ModalRun,
    shapes: &[Vec<f64>],
    cr: &DMatrix<f64>,
    full: &[[Complex<f64>; 6]],
    modes: &[MachineMode],
    rigid: bool,
) -> Result<MachineModal> {
    let (layout, md) = (&base.layout, &d.machine);
    let (n, rc, reactive) = (shapes.len(), md.reactive_centre, layout.reactive as usize);
    // The first harmonic per magnet the response `full` was solved for.
    let f1 = d.magnet_drive()?.cos_coefficient(1).abs() / md.magnets.len() as f64;
    if !(f1 > 0.0 && f1.is_finite()) {
        return Err(bad("drive.pull", "gives no pull at the excitation".into()));
    }
    let unit: Vec<(usize, [c64; 6])> = magnet_forces(d, layout, 1)?
        .into_iter()
        .map(|(a, f)| (a, f.map(|x| x / f1)))
        .collect();
    let load = harmonic::load_vector(sys, &unit)?;
    let force: Vec<f64> = (0..n)
        .map(|j| load.iter().enumerate().map(|(i, l)| l.re * run.vectors[(i, j)]).sum())
        .collect();
    // The modal coordinates at the excitation per newton, as the harmonic response solves them.
    let omega = TAU * d.excitation_hz;
    let a = DMatrix::from_fn(n, n, |i, j| {
        let diag = if i == j { run.lambda[i] - omega * omega } else { 0.0 };
        Complex::new(diag, omega * cr[(i, j)])
    });
    let rhs = nalgebra::DVector::from_fn(n, |j, _| Complex::new(force[j], 0.0));
    let x = a
        .lu()
        .solve(&rhs)
        .ok_or_else(|| Error::Verification("machine modal model: singular at the excitation".into()))?;
    let output = |fun: &Functional| -> ModalOutput {
        let shape: Vec<f64> = shapes
            .iter()
            .map(|s| {
                fun.iter()
                    .map(|(a, w)| (0..6).map(|c| w[c] * s[6 * a + c]).sum::<f64>())
                    .sum()
            })
            .collect();
        let whole: Complex<f64> = fun
            .iter()
            .map(|(a, w)| (0..6).map(|c| full[*a][c] * w[c]).sum::<Complex<f64>>())
            .sum();
        let modal: Complex<f64> = shape.iter().zip(x.iter()).map(|(s, q)| q * *s).sum();
        ModalOutput {
            shape,
            residual: (whole / f1 - modal).re,
        }
    };
    let isolators = md
        .isolators
        .iter()
        .map(|p| output(&vec![uz_functional(reactive, rc, [p[0], p[1]], 1.0)]))
        .collect();
    let leaves = md
        .leaves
        .iter()
        .zip(&base.leaf_nodes)
        .map(|(l, &a)| {
            let nl = (l[2] * l[2] + l[3] * l[3]).sqrt();
            let clamp = [l[0] + d.leaf.length * l[2] / nl, l[1] + d.leaf.length * l[3] / nl];
            let a_ref = if rigid {
                layout.table_centre
            } else {
                [l[0], l[1], md.leaf_level]
            };
            output(&vec![
                uz_functional(a, a_ref, [l[0], l[1]], 1.0),
                uz_functional(reactive, rc, clamp, -1.0),
            ])
        })
        .collect();
    let magnets = md
        .magnets
        .iter()
        .zip(&base.magnet_nodes)
        .map(|(m, &a)| {
            let a_ref = if rigid { layout.table_centre } else { [m[0], m[1], 0.0] };
            output(&vec![
                uz_functional(a, a_ref, *m, 1.0),
                uz_functional(reactive, rc, *m, -1.0),
            ])
        })
        .collect();
    Ok(MachineModal {
        lambda: run.lambda[..n].to_vec(),
        names: (0..n)
            .map(|k| {
                modes.get(k).map_or_else(
                    || format!("mode {} (above {} × the excitation)", k + 1, md.mode_range),
                    |m| m.name.clone(),
                )
            })
            .collect(),
        damping: (0..n * n).map(|i| cr[(i / n, i % n)]).collect(),
        force,
        isolators,
        leaves,
        magnets,
        k_isolator: parts.k_ax,
        c_isolator: d.damping.mu13 / d.coil.count as f64,
    })
}
