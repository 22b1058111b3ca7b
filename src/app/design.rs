//! The vibratory-table design chain: FE parts feeding the two-mass model, with the checks.
//!
//! Steps (each timed and reported):
//! 1. **Work table** (shell sandwich, free–free modal): mass, first six elastic frequencies.
//! 2. **Leaf spring** (hex20 solid, clamped at one end, the other guided through a rigid
//!    coupling): stiffness from a 1000 N load; with `tune = "leaf"` the leaf thickness is
//!    iterated (secant on FE solves) until the detuning z reaches its target.
//! 3. **Coil isolator** (Timoshenko beams along the helix, one end clamped, the other guided
//!    axially): stiffness; shear stress under the static load by Wahl's formula.
//! 4. **Two-mass model**: m1 = FE table mass + other active parts + load share, m2 given;
//!    c12 = n_leaves · k_leaf · k_clamp; c13 = n_isolators · k_coil. Natural frequencies,
//!    steady state at the excitation, dynamic factors, drive force and power, transient
//!    start-up, isolation.
//! 5. **Leaf stress** at the working relative amplitude |X1 − X2| (linear scaling of the FE
//!    stress field of step 2).
//! 6. **Checks** with margins, and a table of every quantity against the published value.
//!
//! Everything is built in code (no mesh files): a design runs from [`Design::paper`] or a
//! TOML file with the same fields (unknown keys are errors).

use crate::analysis::modal::{ModalOptions, ModalTarget, run_modal};
use crate::analysis::statics::{Load, StaticOptions, run_static};
use crate::app::dynamics::electromagnet::RectifiedDrive;
use crate::app::dynamics::isolation::{transmissibility, wahl_factor};
use crate::app::dynamics::transient::{TransientOptions, simulate_startup};
use crate::app::dynamics::two_mass::TwoMass;
use crate::material::Material;
use crate::mesh::CellKind;
use crate::mesh::parametric::{HelixParams, SandwichParams, helix_beam, sandwich_table};
use crate::model::{BeamPart, CouplingSpec, ModelSpec, Orientation, ShellPart};
use crate::section::{BeamSection, ShellSection};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};
use std::time::Instant;

/// A design: every input of the chain, SI units. Defaults are the paper's table.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Design {
    /// Format version (1).
    pub version: u32,
    /// Name of the design.
    pub name: String,
    /// Forced-vibration frequency, Hz.
    pub excitation_hz: f64,
    /// Target work-table amplitude, m.
    pub target_amplitude: f64,
    /// Target detuning z = Ω/ω0 (for `tune`).
    pub target_detuning: f64,
    /// `"none"`, `"leaf"` (iterate the leaf thickness to reach `target_detuning`) or `"mass"`
    /// (report the reactive mass that would reach it, keep the design as given).
    pub tune: String,
    /// Structural steel of the table.
    pub steel: [f64; 3],
    /// Work table.
    pub table: TableDesign,
    /// Masses.
    pub masses: MassDesign,
    /// Leaf springs.
    pub leaf: LeafDesign,
    /// Coil isolators.
    pub coil: CoilDesign,
    /// Electromagnetic drive.
    pub drive: DriveDesign,
    /// Viscous damping, N·s/m.
    pub damping: DampingDesign,
    /// The 3D machine: layout of leaves, magnets and isolators, and its limits.
    pub machine: crate::app::machine3d::MachineDesign,
    /// What spaces the plates: `"plates"` (flat webs, the S7 reconstruction) or `"channel10"`
    /// (the paper's words: channel No. 10 of GOST 8240, h = 100 mm, flanges 46 × 7.6 mm on the
    /// plates, web 4.5 mm; see [`table_parts`]).
    pub spacers: String,
    /// The search for a passing variant when a check fails.
    pub search: crate::app::design_search::SearchDesign,
}

/// The sandwich work table (shell model): the generator's own parameters, read from `[table]`.
pub type TableDesign = SandwichParams;

/// Masses of the two-mass system.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MassDesign {
    /// Load on the table (concrete products and moulds), kg.
    pub load: f64,
    /// Share of the load moving with the table in m1 (k_pr).
    pub load_share: f64,
    /// Other parts of the active mass (armatures, shoes, clamps), kg.
    pub active_extra: f64,
    /// Reactive mass m2 (magnet cores, frame, tuning plates), kg.
    pub reactive: f64,
}

/// Flat leaf springs.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LeafDesign {
    /// Free length, m.
    pub length: f64,
    /// Width, m.
    pub width: f64,
    /// Thickness, m (the starting value when tuning).
    pub thickness: f64,
    /// Number of leaves in parallel.
    pub count: usize,
    /// Clamping coefficient k_c.
    pub clamping: f64,
    /// Spring steel E, ν, ρ.
    pub material: [f64; 3],
    /// Allowable stress [σ₋₁], Pa.
    pub allowable: f64,
    /// hex20 divisions along length, width, thickness.
    pub divisions: [usize; 3],
}

/// Coil isolators.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CoilDesign {
    /// Wire diameter, m.
    pub wire: f64,
    /// Mean coil diameter, m.
    pub mean_diameter: f64,
    /// Active turns.
    pub turns: f64,
    /// Pitch, m.
    pub pitch: f64,
    /// Number of isolators.
    pub count: usize,
    /// Shear modulus G, Pa (E = 2G(1+ν) with ν = 0.3).
    pub shear_modulus: f64,
    /// Allowable shear stress under the static load, Pa.
    pub allowable_shear: f64,
    /// Beam elements (3-node) per turn.
    pub elements_per_turn: usize,
}

/// Electromagnetic drive.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DriveDesign {
    /// Number of single-stroke magnets.
    pub magnets: usize,
    /// Peak pull of one magnet P_em, N.
    pub pull: f64,
    /// Drive efficiency η for eq. (6).
    pub efficiency: f64,
    /// Installed electrical power, W.
    pub installed_power: f64,
    /// Transient simulation length, s.
    pub transient_s: f64,
    /// Overload at which eq. (6) sizes the drive, g (the paper: 11 g, a margin over 8 g).
    pub power_overload_g: f64,
    /// Load share m_pr in eq. (6), kg (the paper: 100 kg, "taken with a margin").
    pub power_load_share: f64,
}

/// Damping coefficients.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DampingDesign {
    /// External damping on m1 (the load), N·s/m.
    pub mu1: f64,
    /// Damping in the leaf springs, N·s/m.
    pub mu12: f64,
    /// Damping in the isolators, N·s/m.
    pub mu13: f64,
}

impl Default for Design {
    fn default() -> Self {
        Design::paper()
    }
}
impl Default for MassDesign {
    fn default() -> Self {
        // The paper's m1 = 206.7 kg is the CAD mass of the active part; its work organ weighs
        // 163 kg, so 43.7 kg are other active parts. The load is carried by μ1 (load_share 0).
        MassDesign {
            load: 120.0,
            load_share: 0.0,
            active_extra: 206.7 - 163.0,
            reactive: 161.8,
        }
    }
}
impl Default for LeafDesign {
    fn default() -> Self {
        LeafDesign {
            length: 0.169,
            width: 0.146,
            thickness: 0.009,
            count: 8,
            clamping: 0.75,
            material: [2.1e11, 0.3, 7850.0],
            allowable: 170e6,
            divisions: [24, 8, 2],
        }
    }
}
impl Default for CoilDesign {
    fn default() -> Self {
        CoilDesign {
            wire: 0.006,
            mean_diameter: 0.032,
            turns: 6.0,
            pitch: 0.010,
            count: 8,
            shear_modulus: 7.7e10,
            allowable_shear: 560e6,
            // Line3 beams, 12 per turn: converged to 0.03 % (validation/springs_s3_s4_s5.py).
            elements_per_turn: 12,
        }
    }
}
impl Default for DriveDesign {
    fn default() -> Self {
        DriveDesign {
            magnets: 8,
            pull: 370.0,
            efficiency: 0.57,
            installed_power: 8.0 * 330.0,
            transient_s: 0.6,
            power_overload_g: 11.0,
            power_load_share: 100.0,
        }
    }
}
impl Default for DampingDesign {
    fn default() -> Self {
        DampingDesign {
            mu1: 2400.0,
            mu12: 1830.0,
            mu13: 230.0,
        }
    }
}

/// Longest start-up transient a design file may ask for (s of machine time).
pub const MAX_TRANSIENT_S: f64 = 30.0;

impl Design {
    /// The paper's 100 Hz table (S3–S8 of docs/spec/scenes.md), with the S7 table reconstruction.
    pub fn paper() -> Design {
        Design {
            version: 1,
            name: "paper 100 Hz two-mass table".into(),
            excitation_hz: 100.0,
            target_amplitude: 0.2e-3,
            target_detuning: 0.97,
            tune: "leaf".into(),
            steel: [2.1e11, 0.3, 7850.0],
            table: TableDesign::default(),
            masses: MassDesign::default(),
            leaf: LeafDesign::default(),
            coil: CoilDesign::default(),
            drive: DriveDesign::default(),
            damping: DampingDesign::default(),
            machine: Default::default(),
            spacers: "plates".into(),
            search: Default::default(),
        }
    }

    /// Read a design TOML file (fields as [`Design`]; missing ones take the paper's values).
    pub fn from_toml(path: &std::path::Path) -> Result<Design> {
        use crate::app::toml_file;
        let text = toml_file::read(path)?;
        let d: Design = toml_file::parse(path, &text)?;
        toml_file::check_version(path, &text, "design", d.version as i64)?;
        d.validate().map_err(|e| toml_file::locate(path, &text, e))?;
        Ok(d)
    }

    /// Check the inputs that the FE and dynamics steps would not catch with a clear message.
    pub fn validate(&self) -> Result<()> {
        let pos = |name: &str, v: f64| -> Result<()> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(crate::app::toml_file::bad_value(
                    name,
                    format!("design: '{name}' must be positive, got {v}"),
                ))
            }
        };
        pos("excitation_hz", self.excitation_hz)?;
        pos("target_amplitude", self.target_amplitude)?;
        pos("target_detuning", self.target_detuning)?;
        pos("masses.reactive", self.masses.reactive)?;
        pos("leaf.thickness", self.leaf.thickness)?;
        pos("leaf.length", self.leaf.length)?;
        pos("leaf.width", self.leaf.width)?;
        pos("leaf.clamping", self.leaf.clamping)?;
        pos("coil.wire", self.coil.wire)?;
        pos("coil.mean_diameter", self.coil.mean_diameter)?;
        pos("coil.shear_modulus", self.coil.shear_modulus)?;
        pos("drive.pull", self.drive.pull)?;
        pos("drive.efficiency", self.drive.efficiency)?;
        pos("drive.transient_s", self.drive.transient_s)?;
        if self.drive.transient_s > MAX_TRANSIENT_S {
            // The start-up settles within about 0.4 s; a run of hours of machine time takes the
            // integrator millions of steps (it used to stop with "more than max_steps" after minutes).
            return Err(crate::app::toml_file::bad_value(
                "drive.transient_s",
                format!(
                    "design: 'drive.transient_s' = {} s is longer than {MAX_TRANSIENT_S} s (the start-up settles \
                     within a second; {MAX_TRANSIENT_S} s is {} periods of the excitation)",
                    self.drive.transient_s,
                    (MAX_TRANSIENT_S * self.excitation_hz).round()
                ),
            ));
        }
        if self.leaf.divisions.contains(&0) || self.leaf.divisions.iter().product::<usize>() > 200_000 {
            return Err(crate::app::toml_file::bad_value(
                "leaf.divisions",
                format!(
                    "design: 'leaf.divisions' must be at least 1 each and at most 200 000 cells in all, got {:?}",
                    self.leaf.divisions
                ),
            ));
        }
        if !(self.table.elem_size >= 0.002 && self.table.elem_size.is_finite()) {
            return Err(crate::app::toml_file::bad_value(
                "table.element_size",
                format!(
                    "design: 'table.element_size' must be at least 0.002 m, got {}",
                    self.table.elem_size
                ),
            ));
        }
        if self.coil.elements_per_turn < 3 || self.coil.elements_per_turn > 1000 {
            return Err(crate::app::toml_file::bad_value(
                "coil.elements_per_turn",
                format!(
                    "design: 'coil.elements_per_turn' must be between 3 and 1000, got {}",
                    self.coil.elements_per_turn
                ),
            ));
        }
        if self.leaf.count == 0 || self.coil.count == 0 || self.drive.magnets == 0 {
            return Err(Error::InvalidInput(
                "design: leaf.count, coil.count and drive.magnets must be ≥ 1".into(),
            ));
        }
        if self.masses.active_extra < 0.0 || self.masses.load < 0.0 || self.masses.load_share < 0.0 {
            return Err(Error::InvalidInput("design: masses must not be negative".into()));
        }
        if !["none", "leaf", "mass"].contains(&self.tune.as_str()) {
            return Err(crate::app::toml_file::bad_value(
                "tune",
                format!("design: 'tune' must be none, leaf or mass, got '{}'", self.tune),
            ));
        }
        // Checks of the parts' own builders, here so that the message names the design key.
        let [young, poisson, density] = self.steel;
        Material {
            young,
            poisson,
            density,
        }
        .validate("'steel'")
        .map_err(|e| crate::app::toml_file::bad_value("steel", e))?;
        self.sandwich()
            .validate()
            .map_err(|e| crate::app::toml_file::bad_value("table", e))?;
        self.machine.validate(self)?;
        if !["plates", "channel10"].contains(&self.spacers.as_str()) {
            return Err(crate::app::toml_file::bad_value(
                "spacers",
                format!("design: 'spacers' must be plates or channel10, got '{}'", self.spacers),
            ));
        }
        self.search.validate()?;
        Ok(())
    }

    /// The table generator's parameters (quad4 shells).
    pub(crate) fn sandwich(&self) -> SandwichParams {
        SandwichParams {
            shell_kind: CellKind::Quad4,
            ..self.table.clone()
        }
    }
}

/// One line of the verdict table.
#[derive(Clone, Debug, Serialize)]
pub struct Quantity {
    /// Stable key in `report.json` (`c12`, `k_leaf`, `x1`, …; docs/design-files.md, *The design report*).
    #[serde(skip)]
    pub id: String,
    /// What.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// vibrofem's value.
    pub value: f64,
    /// The paper's value, if published.
    pub published: Option<f64>,
    /// Where the paper's value comes from / why they differ.
    pub note: String,
}

/// A design check.
#[derive(Clone, Debug, Serialize)]
pub struct Check {
    /// Stable key in `report.json`.
    #[serde(skip)]
    pub id: String,
    /// What is checked.
    pub name: String,
    /// Value.
    pub value: f64,
    /// Limit.
    pub limit: f64,
    /// Margin: how far inside the limit, as a fraction of the limit (negative: violated).
    pub margin: f64,
    /// Passed.
    pub ok: bool,
}

fn by_id<T: Serialize, S: serde::Serializer>(
    items: &[T],
    id: impl Fn(&T) -> &str,
    ser: S,
) -> std::result::Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut m = ser.serialize_map(Some(items.len()))?;
    for x in items {
        m.serialize_entry(id(x), x)?;
    }
    m.end()
}

fn by_id_quantities<S: serde::Serializer>(q: &[Quantity], ser: S) -> std::result::Result<S::Ok, S::Error> {
    by_id(q, |x| x.id.as_str(), ser)
}

fn by_id_checks<S: serde::Serializer>(c: &[Check], ser: S) -> std::result::Result<S::Ok, S::Error> {
    by_id(c, |x| x.id.as_str(), ser)
}

/// Everything the chain computed.
#[derive(Clone, Debug, Serialize)]
pub struct DesignReport {
    /// The design's name.
    pub name: String,
    /// Checks, in the order they are reported (in JSON: an object keyed by each check's id).
    #[serde(serialize_with = "by_id_checks")]
    pub checks: Vec<Check>,
    /// Quantities with published values (in JSON: an object keyed by each quantity's id).
    #[serde(serialize_with = "by_id_quantities")]
    pub quantities: Vec<Quantity>,
    /// Work-table elastic frequencies (first six), Hz.
    pub table_frequencies_hz: Vec<f64>,
    /// Leaf thicknesses tried while tuning (m) and the detuning each gave.
    pub leaf_iterations: Vec<(f64, f64)>,
    /// Modes of the 3D machine up to `machine.mode_range` × the excitation.
    pub machine_modes: Vec<crate::app::machine3d::MachineMode>,
    /// Wall time per step (s).
    pub timings_s: Vec<(String, f64)>,
    /// Notes.
    pub notes: Vec<String>,
}

/// FE stiffness of one leaf (N/m) and the peak von Mises stress per metre of guided
/// displacement (Pa/m), both from a guided 1000 N load.
pub fn leaf_fe(d: &Design, h: f64) -> Result<(f64, f64)> {
    let l = &d.leaf;
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
            guided: Some(2),
            reference: None,
        }],
        ..Default::default()
    };
    let run = run_static(
        &mesh,
        "leaf spring",
        &StaticOptions {
            spec,
            cases: vec![vec![Load::Force {
                group: "xmax".into(),
                force: [0.0, 0.0, 1000.0],
            }]],
        },
    )?;
    let r = &run.cases[0].references[0];
    let uz = r.displacement[2];
    let k = 1000.0 / uz;
    let u = crate::app::report::mesh_displacements(&run, 0);
    let ns = crate::post::stress::nodal_stress(&run.model.solids, run.model.n_mesh_nodes, &u)?;
    let vm = ns.von_mises.iter().fold(0.0f64, |a, &b| a.max(b));
    Ok((k, vm / uz))
}

/// FE axial stiffness of one coil isolator (beam helix), N/m.
pub fn coil_fe(d: &Design) -> Result<f64> {
    coil_stiffness_along(d, 2, -600.0)
}

/// Stiffness of one coil isolator (beam helix, N/m) with its bottom end clamped and its top end
/// guided along `axis` (0 = x, 2 = z) under `force` N along it.
pub fn coil_stiffness_along(d: &Design, axis: usize, force: f64) -> Result<f64> {
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

fn check(id: &str, name: &str, value: f64, limit: f64, upper: bool) -> Check {
    let margin = if upper {
        (limit - value) / limit
    } else {
        (value - limit) / limit
    };
    Check {
        id: id.into(),
        name: name.into(),
        value,
        limit,
        margin,
        ok: margin >= 0.0,
    }
}

fn q(id: &str, name: &str, unit: &str, value: f64, published: Option<f64>, note: &str) -> Quantity {
    Quantity {
        id: id.into(),
        name: name.into(),
        unit: unit.into(),
        value,
        published,
        note: note.into(),
    }
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

/// Run the whole chain; `progress` is told the name of each step as it starts. Plots and
/// the markdown report go to `out_dir` if given.
pub fn run_design(d: &Design, out_dir: Option<&std::path::Path>, progress: &dyn Fn(&str)) -> Result<DesignReport> {
    d.validate()?;
    let mut timings = Vec::new();
    let mut notes = Vec::new();
    let omega = TAU * d.excitation_hz;

    progress("work table: shell modal analysis");
    let t = Instant::now();
    let (m_table, f_table, table_run, table_mesh) = table_fe(d)?;
    timings.push(("work table modal".to_string(), t.elapsed().as_secs_f64()));

    progress("coil isolator: beam helix statics");
    let t = Instant::now();
    let k_coil = coil_fe(d)?;
    timings.push(("coil spring statics".to_string(), t.elapsed().as_secs_f64()));

    let m1 = m_table + d.masses.active_extra + d.masses.load_share * d.masses.load;
    let m2 = d.masses.reactive;
    let m_red = m1 * m2 / (m1 + m2);
    let c13 = d.coil.count as f64 * k_coil;

    progress("leaf spring: solid statics");
    let t = Instant::now();
    let mut h = d.leaf.thickness;
    let (mut k_leaf, mut stress_per_m) = leaf_fe(d, h)?;
    let c12_of = |k: f64| d.leaf.count as f64 * k * d.leaf.clamping;
    let z_of = |c12: f64| omega / (c12 / m_red).sqrt();
    let mut iters = vec![(h, z_of(c12_of(k_leaf)))];
    let (k_leaf_given, h_given) = (k_leaf, h);
    if d.tune == "leaf" {
        // Secant on the thickness for c12 = m_red (Ω/z)²; k grows like h³, so iterate on h³.
        let c12_target = m_red * (omega / d.target_detuning).powi(2);
        let k_target = c12_target / (d.leaf.count as f64 * d.leaf.clamping);
        let mut h_prev = h;
        let mut k_prev = k_leaf;
        h *= (k_target / k_leaf).cbrt();
        for _ in 0..8 {
            progress(&format!("leaf spring: tuning, h = {:.3} mm", h * 1e3));
            (k_leaf, stress_per_m) = leaf_fe(d, h)?;
            iters.push((h, z_of(c12_of(k_leaf))));
            if (k_leaf - k_target).abs() < 1e-6 * k_target {
                break;
            }
            let (a, b) = (h_prev.powi(3), h.powi(3));
            let next = b + (k_target - k_leaf) * (b - a) / (k_leaf - k_prev);
            h_prev = h;
            k_prev = k_leaf;
            h = next.max(1e-12).cbrt();
        }
    }
    timings.push(("leaf spring statics".to_string(), t.elapsed().as_secs_f64()));
    let c12 = c12_of(k_leaf);

    progress("two-mass model");
    let t = Instant::now();
    let model = TwoMass::new(m1, m2, c12, c13, d.damping.mu1, d.damping.mu12, d.damping.mu13)?;
    let drive = RectifiedDrive::from_magnets(d.drive.magnets, d.drive.pull, omega / 2.0)?;
    let force = drive.harmonic_amplitude();
    let ss = model.steady_state(omega, force)?;
    let [w1, w2] = model.natural_frequencies_hz()?;
    let z = omega / model.omega0();
    let x1 = ss.amp1();
    let rel = ss.relative_amp();
    let gamma1 = x1 * m1 * omega * omega / force;
    let gamma2 = ss.amp2() * m2 * omega * omega / force;
    // Eq. (6) as the paper applies it: at the sizing overload (11 g), X2 in the model's ratio
    // to X1, the model's dynamic factors, and the load share taken with a margin.
    let x1p = d.drive.power_overload_g * 9.81 / (omega * omega);
    let x2p = x1p * ss.amp2() / x1;
    let power = crate::app::dynamics::tuning::drive_power(
        omega,
        d.drive.efficiency,
        &[(x1p, m1, gamma1), (x2p, m2, gamma2)],
        x1p,
        d.drive.power_load_share,
    )?;
    let p_req = crate::app::dynamics::electromagnet::required_peak_force(&model, omega, d.target_amplitude)?
        / d.drive.magnets as f64;
    let offset = drive.constant() / c12;
    let m_total = m1 + m2 + d.masses.load;
    let f_iso = (c13 / m_total).sqrt() / TAU;
    let r = d.excitation_hz / f_iso;
    let trans = transmissibility(r, 0.0)?;
    progress("transient start-up (Dormand–Prince)");
    let tr = simulate_startup(
        &model,
        &drive,
        &TransientOptions {
            t_end: d.drive.transient_s,
            ..Default::default()
        },
    )?;
    let trs = tr.summary(10)?;
    timings.push(("two-mass model and transient".to_string(), t.elapsed().as_secs_f64()));

    progress("3D machine: modes and forced response");
    let t = Instant::now();
    let mach = crate::app::machine3d::analyse(d, h)?;
    timings.push(("3D machine".to_string(), t.elapsed().as_secs_f64()));

    // Stresses.
    let sigma_leaf = stress_per_m * rel;
    let q_static = m_total * 9.81 / d.coil.count as f64;
    let cidx = d.coil.mean_diameter / d.coil.wire;
    let kw = wahl_factor(cidx)?;
    let tau = 8.0 * kw * q_static * d.coil.mean_diameter / (PI * d.coil.wire.powi(3));

    let mut quantities = vec![
        q(
            "table_mass",
            "work-table mass (FE shells)",
            "kg",
            m_table,
            Some(163.0),
            "S7 reconstruction: no edge thinning, so heavier",
        ),
        q(
            "table_f1",
            "work-table first elastic frequency",
            "Hz",
            f_table.first().copied().unwrap_or(f64::NAN),
            Some(300.82),
            "S7",
        ),
        q(
            "m1",
            "active mass m1",
            "kg",
            m1,
            Some(206.7),
            "FE table + other active parts",
        ),
        q("m2", "reactive mass m2", "kg", m2, Some(161.8), "given"),
        q("m_red", "reduced mass m_red", "kg", m_red, Some(90.75), "eq. (5)"),
        q(
            "k_leaf_given",
            "FE leaf stiffness, h as given",
            "N/m",
            k_leaf_given,
            Some(5.163e6),
            "S3: 1000 N / 1.937e-4 m",
        ),
        q(
            "leaf_thickness",
            "leaf thickness used",
            "mm",
            h * 1e3,
            Some(9.0),
            if d.tune == "leaf" { "tuned for z by FE" } else { "given" },
        ),
        q("k_leaf", "FE leaf stiffness, used", "N/m", k_leaf, None, ""),
        q(
            "c12",
            "c12 = n · k_leaf · k_c",
            "N/m",
            c12,
            Some(3.808e7),
            "paper: from z = 0.97 (eq. 5)",
        ),
        q("z", "detuning z = Ω/ω0", "-", z, Some(0.97), ""),
        q(
            "k_coil",
            "FE coil stiffness (beam helix)",
            "N/m",
            k_coil,
            Some(60266.0),
            "S5: formula at i = 6.3; FE 9.96 mm → 60 240",
        ),
        q("c13", "c13 = n · k_coil", "N/m", c13, Some(8.0 * 60266.0), ""),
        q(
            "f_n1",
            "natural frequency 1 (isolation)",
            "Hz",
            w1,
            Some(5.0),
            "paper: 5 Hz design",
        ),
        q(
            "f_n2",
            "natural frequency 2 (resonant)",
            "Hz",
            w2,
            Some(103.09),
            "ω0 = Ω/z",
        ),
        q(
            "drive_force",
            "drive force amplitude F = 4/(3π)·n·P_em",
            "N",
            force,
            Some(1256.0),
            "eq. (11)",
        ),
        q(
            "constant_pull",
            "constant pull",
            "N",
            drive.constant(),
            Some(1884.0),
            "eq. (9)",
        ),
        q(
            "static_offset",
            "static offset P_const/c12",
            "mm",
            offset * 1e3,
            Some(0.05),
            "",
        ),
        q(
            "x1",
            "work-table amplitude X1",
            "mm",
            x1 * 1e3,
            Some(0.2),
            "steady state at the excitation",
        ),
        q("x2", "reactive amplitude X2", "mm", ss.amp2() * 1e3, None, ""),
        q(
            "table_acceleration",
            "work-table acceleration",
            "g",
            x1 * omega * omega / 9.81,
            Some(8.0),
            "",
        ),
        q("gamma1", "dynamic factor γ1", "-", gamma1, Some(13.0), "eq. (7)"),
        q("gamma2", "dynamic factor γ2", "-", gamma2, Some(13.0), "eq. (7)"),
        q(
            "relative_amplitude",
            "relative amplitude |X1 − X2|",
            "mm",
            rel * 1e3,
            Some(0.46),
            "A0 = A(1 + m1/m2)",
        ),
        q(
            "leaf_von_mises",
            "leaf von Mises at the working amplitude (FE)",
            "MPa",
            sigma_leaf / 1e6,
            Some(83.0),
            "S3 FE; hand 91 MPa",
        ),
        q(
            "magnet_pull",
            "pull per magnet for the target amplitude",
            "N",
            p_req,
            Some(370.0),
            "eq. (15)",
        ),
        q(
            "drive_power",
            "drive power, eq. (6)",
            "W",
            power,
            Some(2200.0),
            &format!(
                "at {} g, m_pr {} kg, η = {}",
                d.drive.power_overload_g, d.drive.power_load_share, d.drive.efficiency
            ),
        ),
        q(
            "transient_x1",
            "transient: steady X1",
            "mm",
            trs.amplitude1 * 1e3,
            Some(0.2),
            "Fig. 22",
        ),
        q(
            "transient_offset",
            "transient: static offset of x1 − x2",
            "mm",
            trs.relative_mean * 1e3,
            Some(-0.05),
            "Fig. 22",
        ),
        q(
            "transient_settling_time",
            "transient: settling time of x1 (2 %)",
            "s",
            trs.settling_time1.unwrap_or(f64::NAN),
            None,
            "",
        ),
        q("f_isolation", "isolation frequency", "Hz", f_iso, Some(5.0), ""),
        q(
            "transmissibility",
            "transmissibility at the excitation",
            "-",
            trans,
            Some(1.0 / 400.0),
            "1/(r² − 1)",
        ),
        q(
            "coil_shear_stress",
            "coil shear stress at static load (Wahl)",
            "MPa",
            tau / 1e6,
            Some(290.0),
            "K from C = D/d",
        ),
    ];
    let working_hz = mach.working.map_or(f64::NAN, |i| mach.modes[i].frequency_hz);
    quantities.extend([
        q(
            "machine_working_hz",
            "3D machine: working mode",
            "Hz",
            working_hz,
            Some(103.09),
            &format!("two-mass model {w2:.2} Hz; table as {}", d.machine.table_model),
        ),
        q(
            "machine_nearest_mode_hz",
            "3D machine: other mode nearest the excitation",
            "Hz",
            mach.nearest_other.map_or(f64::NAN, |x| x.0),
            None,
            "",
        ),
        q(
            "surface_mean_amplitude",
            "work surface: mean amplitude",
            "mm",
            mach.mean * 1e3,
            Some(0.2),
            &format!("{} nodes; two-mass X1 {:.4} mm", mach.surface.len(), x1 * 1e3),
        ),
        q(
            "surface_min_amplitude",
            "work surface: min amplitude",
            "mm",
            mach.min * 1e3,
            None,
            "",
        ),
        q(
            "surface_max_amplitude",
            "work surface: max amplitude",
            "mm",
            mach.max * 1e3,
            None,
            "",
        ),
        q(
            "surface_nonuniformity",
            "work surface: non-uniformity (max − min)/mean",
            "%",
            mach.nonuniformity * 100.0,
            None,
            "",
        ),
        q(
            "machine_reactive_amplitude",
            "3D machine: reactive-mass amplitude",
            "mm",
            mach.reactive_amplitude * 1e3,
            None,
            &format!("two-mass X2 {:.4} mm", ss.amp2() * 1e3),
        ),
        q(
            "leaf_kzz",
            "condensed leaf: guided vertical stiffness",
            "N/m",
            mach.leaf_kzz,
            None,
            "12×12 from 6 FE statics",
        ),
        q(
            "coil_lateral",
            "FE coil lateral stiffness (beam helix)",
            "N/m",
            mach.coil_lateral,
            None,
            "top end guided along x",
        ),
    ]);
    quantities.retain(|x| x.value.is_finite() || x.published.is_some());
    if d.tune == "mass" {
        let m2_need = crate::app::dynamics::tuning::reactive_mass_for_detuning(m1, c12, omega, d.target_detuning);
        match m2_need {
            Ok(v) => quantities.push(q(
                "m2_for_target_z",
                "reactive mass for the target z",
                "kg",
                v,
                Some(161.8),
                "tuning plates",
            )),
            Err(e) => notes.push(format!("no reactive mass reaches z = {}: {e}", d.target_detuning)),
        }
    }
    if d.tune == "leaf" && (h - h_given).abs() > 1e-9 {
        notes.push(format!(
            "with the clamping coefficient {} the given {:.1} mm leaves give z = {:.3}; the FE-tuned thickness for z = {} is {:.2} mm (eq. (16) with i = {}, k = {}: {:.2} mm)",
            d.leaf.clamping,
            h_given * 1e3,
            iters[0].1,
            d.target_detuning,
            h * 1e3,
            d.leaf.count,
            d.leaf.clamping,
            crate::app::dynamics::tuning::leaf_thickness_for_stiffness(
                m_red * (omega / d.target_detuning).powi(2),
                d.leaf.count,
                d.leaf.material[0],
                d.leaf.width,
                d.leaf.length,
                d.leaf.clamping
            )
            .unwrap_or(f64::NAN)
                * 1e3
        ));
    }
    let f1 = f_table.first().copied().unwrap_or(0.0);
    let checks = vec![
        check(
            "table_f1_vs_excitation",
            "work-table first elastic mode ≥ 3 × excitation [Hz]",
            f1,
            3.0 * d.excitation_hz,
            false,
        ),
        check(
            "isolation",
            "isolation frequency ≤ excitation / 5 [Hz]",
            f_iso,
            d.excitation_hz / 5.0,
            true,
        ),
        check(
            "leaf_stress",
            "leaf stress at working amplitude ≤ allowable [MPa]",
            sigma_leaf / 1e6,
            d.leaf.allowable / 1e6,
            true,
        ),
        check(
            "coil_stress",
            "coil shear stress under static load ≤ allowable [MPa]",
            tau / 1e6,
            d.coil.allowable_shear / 1e6,
            true,
        ),
        check(
            "table_amplitude",
            "work-table amplitude reaches the target [mm]",
            x1 * 1e3,
            d.target_amplitude * 1e3,
            false,
        ),
        check(
            "drive_power",
            "drive power within installed power [W]",
            power,
            d.drive.installed_power,
            true,
        ),
        check(
            "mode_clearance",
            "no other machine mode within the clearance of the excitation [%]",
            mach.nearest_other.map_or(f64::INFINITY, |x| x.1 * 100.0),
            d.machine.mode_clearance * 100.0,
            false,
        ),
        check(
            "surface_uniformity",
            "work-surface amplitude non-uniformity ≤ limit [%]",
            mach.nonuniformity * 100.0,
            d.machine.max_nonuniformity * 100.0,
            true,
        ),
    ];
    if mach.working.is_none() {
        notes.push(format!(
            "the 3D machine has no working mode (leaves strained, masses in vertical antiphase) below {} Hz",
            d.machine.mode_range * d.excitation_hz
        ));
    }
    notes.push(format!(
        "3D machine: {} DOFs; forced response from {} modes up to {:.0} Hz with the two-mass dashpots placed on the leaves, isolators and work surface",
        mach.dofs, mach.response_modes.0, mach.response_modes.1
    ));
    if let Some(dir) = out_dir {
        progress("report and plots");
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        crate::app::dynamics::plot::write_frequency_response_svg(
            dir.join("amplitude_frequency.svg"),
            &model,
            1.0,
            2.0 * d.excitation_hz,
            4000,
            force,
            Some(d.excitation_hz),
        )?;
        crate::app::dynamics::plot::write_transient_svg(dir.join("transient.svg"), &tr, None)?;
        crate::app::dynamics::plot::write_electromagnet_svg(dir.join("electromagnet.svg"), &drive, 8, 2.0)?;
        crate::io::write_mode_shapes(
            &table_mesh,
            &table_run.shapes,
            &table_run.report.frequencies_hz,
            Some(&dir.join("table_modes.vtu")),
            Some(&dir.join("table_modes.msh")),
        )?;
        crate::app::machine3d::write_amplitude_svg(&dir.join("work_surface_amplitude.svg"), &mach, d.excitation_hz)?;
        crate::app::machine3d::write_amplitude_vtu(&dir.join("machine_response.vtu"), &mach)?;
        if let Some(k) = table_run.report.modes.iter().position(|m| m.kind == "elastic") {
            write_mode_svg(
                &dir.join("table_mode7.svg"),
                &table_mesh,
                &table_run.shapes[k],
                table_run.report.frequencies_hz[k],
            )?;
        }
    }
    Ok(DesignReport {
        name: d.name.clone(),
        quantities,
        checks,
        table_frequencies_hz: f_table,
        leaf_iterations: iters,
        machine_modes: mach.modes.clone(),
        timings_s: timings,
        notes,
    })
}

/// A plan view of a mode shape: the top-plate nodes coloured by the vertical displacement.
fn write_mode_svg(path: &std::path::Path, mesh: &crate::mesh::Mesh, shape: &[f64], f: f64) -> Result<()> {
    use plotters::prelude::*;
    let top = mesh.group("top_plate")?;
    let nodes = mesh.group_nodes(top);
    let (lo, hi) = mesh.bounding_box();
    let umax = nodes
        .iter()
        .map(|&a| shape[3 * a as usize + 2].abs())
        .fold(0.0f64, f64::max)
        .max(1e-300);
    let root = SVGBackend::new(path, (900, 520)).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| Error::InvalidInput(format!("{}: plotting failed: {e}", path.display()));
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("work table, first elastic mode: {f:.2} Hz (top plate, vertical displacement)"),
            ("sans-serif", 18),
        )
        .margin(15)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(lo[0]..hi[0], lo[1]..hi[1])
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("x [m]")
        .y_desc("y [m]")
        .draw()
        .map_err(|e| err(&e))?;
    chart
        .draw_series(nodes.iter().map(|&a| {
            let x = mesh.nodes[a as usize];
            let v = shape[3 * a as usize + 2] / umax;
            let c = if v >= 0.0 {
                RGBColor(255, (255.0 * (1.0 - v)) as u8, (255.0 * (1.0 - v)) as u8)
            } else {
                RGBColor((255.0 * (1.0 + v)) as u8, (255.0 * (1.0 + v)) as u8, 255)
            };
            Circle::new((x[0], x[1]), 4, c.filled())
        }))
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// The verdict table as text.
pub fn verdict_text(r: &DesignReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "design: {}\n", r.name);
    let _ = writeln!(s, "checks: {}", checks_summary(r, "FAILED"));
    for c in &r.checks {
        let _ = writeln!(
            s,
            "  [{}] {:<56} {:>10} vs {:>10}  margin {:+.1} %",
            if c.ok { " ok " } else { "FAIL" },
            c.name,
            sig(c.value),
            sig(c.limit),
            c.margin * 100.0
        );
    }
    let _ = writeln!(
        s,
        "\n{:<48} {:>11} {:>11} {:>9}  {:<6} note",
        "quantity", "vibrofem", "published", "diff", "unit"
    );
    for x in &r.quantities {
        let (p, dif) = published(x);
        let _ = writeln!(
            s,
            "{:<48} {:>11} {:>11} {:>9}  {:<6} {}",
            x.name,
            sig(x.value),
            p,
            dif,
            x.unit,
            x.note
        );
    }
    if !r.machine_modes.is_empty() {
        let _ = writeln!(
            s,
            "\n3D machine modes          Hz   strain energy: leaves isolators table   kinetic in m2"
        );
        for (i, m) in r.machine_modes.iter().enumerate() {
            let _ = writeln!(
                s,
                "  {:>3} {:>18} {:>9.1} %  {:>7.1} % {:>7.1} %  {:>9.1} %   {}",
                i + 1,
                sig(m.frequency_hz),
                100.0 * m.energy_leaves,
                100.0 * m.energy_isolators,
                100.0 * m.energy_table,
                100.0 * m.kinetic_reactive,
                m.name
            );
        }
    }
    for n in &r.notes {
        let _ = writeln!(s, "\nnote: {n}");
    }
    let total: f64 = r.timings_s.iter().map(|t| t.1).sum();
    let _ = writeln!(
        s,
        "\ntime: {}  (total {total:.1} s)",
        r.timings_s
            .iter()
            .map(|(n, t)| format!("{n} {t:.1} s"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    s
}

/// "all passed" or "2 of 6 failed" (with `failed` spelt as given).
fn checks_summary(r: &DesignReport, failed_word: &str) -> String {
    let failed = r.checks.iter().filter(|c| !c.ok).count();
    if failed == 0 {
        "all passed".to_string()
    } else {
        format!("{failed} of {} {failed_word}", r.checks.len())
    }
}

/// A reported number: four significant digits, plain or with an exponent (184.2, 4.990e6).
fn sig(x: f64) -> String {
    crate::io::fmt_sig(x, 4)
}

/// The published value (as the paper gives it) and the difference, or dashes.
fn published(x: &Quantity) -> (String, String) {
    match x.published {
        // As the paper gives it: its own digits, with an exponent for large or small values.
        Some(p) => (
            if p != 0.0 && !(1e-3..1e5).contains(&p.abs()) {
                format!("{p:e}")
            } else {
                format!("{p}")
            },
            format!("{:+.1} %", (x.value / p - 1.0) * 100.0),
        ),
        None => ("–".into(), String::new()),
    }
}

fn html_escape(t: &str) -> String {
    t.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// A self-contained HTML report (`report.html`): the checks first, the quantities, notes and
/// the plots inlined from `dir` (SVG files the chain wrote there), readable without the folder.
pub fn report_html(r: &DesignReport, dir: &std::path::Path) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Design report: {}</title>\n<style>\
         body{{font-family:sans-serif;max-width:72em;margin:2em auto;padding:0 1em}}\
         table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:.25em .6em}}\
         td.n{{text-align:right;font-variant-numeric:tabular-nums}}.ok{{color:#070}}.fail{{color:#b00;font-weight:bold}}\
         figure{{margin:1.5em 0}}</style></head><body>\n<h1>Design report: {}</h1>\n",
        html_escape(&r.name),
        html_escape(&r.name)
    );
    let _ = writeln!(
        s,
        "<h2>Checks: {}</h2>\n<table><tr><th>check</th><th>value</th><th>limit</th><th>margin</th><th>verdict</th></tr>",
        checks_summary(r, "failed")
    );
    for c in &r.checks {
        let _ = writeln!(
            s,
            "<tr><td>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{:+.1} %</td><td class={}>{}</td></tr>",
            html_escape(&c.name),
            sig(c.value),
            sig(c.limit),
            c.margin * 100.0,
            if c.ok { "ok" } else { "fail" },
            if c.ok { "ok" } else { "FAIL" }
        );
    }
    let _ = writeln!(
        s,
        "</table>\n<h2>Quantities</h2>\n<table><tr><th>id</th><th>quantity</th><th>vibrofem</th><th>published</th><th>difference</th><th>unit</th><th>note</th></tr>"
    );
    for x in &r.quantities {
        let (p, d) = published(x);
        let _ = writeln!(
            s,
            "<tr><td><code>{}</code></td><td>{}</td><td class=n>{}</td><td class=n>{}</td><td class=n>{}</td><td>{}</td><td>{}</td></tr>",
            x.id,
            html_escape(&x.name),
            sig(x.value),
            p,
            d,
            html_escape(&x.unit),
            html_escape(&x.note)
        );
    }
    let _ = writeln!(
        s,
        "</table>\n<h2>Work-table elastic frequencies (shell model)</h2>\n<ul>"
    );
    for (i, f) in r.table_frequencies_hz.iter().enumerate() {
        let _ = writeln!(s, "<li>mode {}: {} Hz</li>", i + 7, sig(*f));
    }
    let _ = writeln!(s, "</ul>");
    if !r.machine_modes.is_empty() {
        let _ = writeln!(
            s,
            "<h2>3D machine modes</h2>\n<table><tr><th>#</th><th>Hz</th><th>leaves</th><th>isolators</th><th>table</th><th>kinetic in m2</th><th>mode</th></tr>"
        );
        for (i, m) in r.machine_modes.iter().enumerate() {
            let _ = writeln!(
                s,
                "<tr><td>{}</td><td class=n>{}</td><td class=n>{:.1} %</td><td class=n>{:.1} %</td><td class=n>{:.1} %</td><td class=n>{:.1} %</td><td>{}</td></tr>",
                i + 1,
                sig(m.frequency_hz),
                100.0 * m.energy_leaves,
                100.0 * m.energy_isolators,
                100.0 * m.energy_table,
                100.0 * m.kinetic_reactive,
                html_escape(&m.name)
            );
        }
        let _ = writeln!(s, "</table>");
    }
    if !r.notes.is_empty() {
        let _ = writeln!(s, "<h2>Notes</h2>\n<ul>");
        for n in &r.notes {
            let _ = writeln!(s, "<li>{}</li>", html_escape(n));
        }
        let _ = writeln!(s, "</ul>");
    }
    let _ = writeln!(s, "<h2>Plots</h2>");
    for (file, caption) in PLOTS {
        // Inline the SVG (its XML prologue dropped) so the page stands alone.
        if let Ok(svg) = std::fs::read_to_string(dir.join(file)) {
            let body = svg.find("<svg").map_or(svg.as_str(), |i| &svg[i..]);
            let _ = writeln!(s, "<figure>{body}<figcaption>{caption}</figcaption></figure>");
        }
    }
    let _ = writeln!(
        s,
        "<p>Mode shapes: <code>table_modes.vtu</code> (ParaView), <code>table_modes.msh</code> (gmsh), beside this file.</p>\n</body></html>"
    );
    s
}

/// The plots the chain writes, with their captions.
const PLOTS: [(&str, &str); 5] = [
    (
        "work_surface_amplitude.svg",
        "Work-surface vertical amplitude at the excitation (3D machine)",
    ),
    (
        "amplitude_frequency.svg",
        "Amplitude–frequency and phase curves with the operating point",
    ),
    ("transient.svg", "Start-up transient"),
    ("electromagnet.svg", "Electromagnet force and its harmonics"),
    ("table_mode7.svg", "Work-table mode 7"),
];

/// Markdown report.
pub fn report_markdown(r: &DesignReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "# Design report: {}\n", r.name);
    let _ = writeln!(
        s,
        "## Checks: {}\n\n| check | value | limit | margin | verdict |\n|---|---:|---:|---:|---|",
        checks_summary(r, "failed")
    );
    for c in &r.checks {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:+.1} % | {} |",
            c.name,
            sig(c.value),
            sig(c.limit),
            c.margin * 100.0,
            if c.ok { "ok" } else { "**FAIL**" }
        );
    }
    let _ = writeln!(
        s,
        "\n## Quantities\n\n| id | quantity | vibrofem | published | difference | unit | note |\n|---|---|---:|---:|---:|---|---|"
    );
    for x in &r.quantities {
        let (p, d) = published(x);
        let _ = writeln!(
            s,
            "| `{}` | {} | {} | {} | {} | {} | {} |",
            x.id,
            x.name,
            sig(x.value),
            p,
            d,
            x.unit,
            x.note
        );
    }
    let _ = writeln!(s, "\n## Work-table elastic frequencies (shell model)\n");
    for (i, f) in r.table_frequencies_hz.iter().enumerate() {
        let _ = writeln!(s, "- mode {}: {} Hz", i + 7, sig(*f));
    }
    if !r.machine_modes.is_empty() {
        let _ = writeln!(
            s,
            "\n## 3D machine modes\n\n| # | Hz | strain energy in leaves | isolators | table | kinetic in m2 | mode |\n|---:|---:|---:|---:|---:|---:|---|"
        );
        for (i, m) in r.machine_modes.iter().enumerate() {
            let _ = writeln!(
                s,
                "| {} | {} | {:.1} % | {:.1} % | {:.1} % | {:.1} % | {} |",
                i + 1,
                sig(m.frequency_hz),
                100.0 * m.energy_leaves,
                100.0 * m.energy_isolators,
                100.0 * m.energy_table,
                100.0 * m.kinetic_reactive,
                m.name
            );
        }
    }
    if !r.notes.is_empty() {
        let _ = writeln!(s, "\n## Notes\n");
        for n in &r.notes {
            let _ = writeln!(s, "- {n}");
        }
    }
    let _ = writeln!(
        s,
        "\n## Plots\n\n![work-surface amplitude](work_surface_amplitude.svg)\n\n![amplitude-frequency](amplitude_frequency.svg)\n\n![transient](transient.svg)\n\n![electromagnet force](electromagnet.svg)\n\n![work-table mode 7](table_mode7.svg)\n\nMode shapes: `table_modes.vtu` (ParaView), `table_modes.msh` (gmsh); forced response of the 3D machine: `machine_response.vtu`."
    );
    s
}
