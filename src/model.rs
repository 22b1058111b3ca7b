//! A model: a mesh bound to formulations, materials and supports.
//!
//! [`Model::build`] checks the user's choices against the mesh (groups exist, materials are
//! valid, there are volume elements), builds the element sets and the DOF map.

use crate::assembly::ElementSet;
use crate::dof::{DofMap, DofMask, TRANSLATIONS};
use crate::element::{MassLumping, solid};
use crate::material::Material;
use crate::mesh::{CellKind, Mesh};
use crate::{Error, Result};

/// What to build from a mesh.
#[derive(Clone, Debug)]
pub struct ModelSpec {
    /// Material of every solid cell not in a group with its own.
    pub material: Material,
    /// Per-group materials (later entries win where groups overlap).
    pub group_materials: Vec<(String, Material)>,
    /// Fixed components per group: `(group, mask)`.
    pub fixes: Vec<(String, DofMask)>,
    /// Mass matrix form.
    pub lumping: MassLumping,
    /// Rigid couplings of groups to reference nodes.
    pub couplings: Vec<CouplingSpec>,
    /// Prescribed displacements per group: `(group, [ux, uy, uz, rx, ry, rz])`, `None` = free.
    /// On a coupled group they apply to its reference node.
    pub prescribed: Vec<(String, [Option<f64>; 6])>,
    /// Point masses.
    pub point_masses: Vec<PointMassSpec>,
    /// Discrete springs.
    pub springs: Vec<SpringSpec>,
    /// Groups meshed with surface cells analysed as shells.
    pub shells: Vec<ShellPart>,
    /// Groups meshed with line cells analysed as beams.
    pub beams: Vec<BeamPart>,
    /// Volume groups analysed as solids; `None`: every volume cell of the mesh when there are no
    /// shell or beam parts, none otherwise.
    pub solid_groups: Option<Vec<String>>,
}

/// A shell part: a surface group with a section and (optionally) its own material.
#[derive(Clone, Debug, PartialEq)]
pub struct ShellPart {
    /// Surface group (tri3/quad4 cells).
    pub group: String,
    /// Thickness, offset, drilling.
    pub section: crate::section::ShellSection,
    /// Material (default: the model's).
    pub material: Option<Material>,
}

/// How a beam's local y axis is oriented.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Orientation {
    /// One vector for all elements (must not be parallel to any element axis).
    Vector([f64; 3]),
    /// Radial from an axis through `centre` along `axis` (helices, rings): the element
    /// midpoint's offset from the axis.
    Radial {
        /// A point on the axis.
        centre: [f64; 3],
        /// Axis direction.
        axis: [f64; 3],
    },
}

/// A beam part: a line group with a section and an orientation.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamPart {
    /// Line group (line2/line3 cells).
    pub group: String,
    /// Section properties.
    pub section: crate::section::BeamSection,
    /// Local y axis.
    pub orientation: Orientation,
    /// Material (default: the model's).
    pub material: Option<Material>,
}

impl Default for ModelSpec {
    fn default() -> Self {
        ModelSpec {
            material: Material::steel(),
            group_materials: vec![],
            fixes: vec![],
            lumping: MassLumping::Consistent,
            couplings: vec![],
            prescribed: vec![],
            point_masses: vec![],
            springs: vec![],
            shells: vec![],
            beams: vec![],
            solid_groups: None,
        }
    }
}

/// Shell cells of one group.
pub struct ShellSet {
    /// Group name.
    pub group: String,
    /// Cell kind of each cell.
    pub kinds: Vec<CellKind>,
    /// Node lists (offsets into `conn`).
    pub conn: Vec<u32>,
    /// Offsets: cell `e` has nodes `conn[ptr[e]..ptr[e+1]]`.
    pub ptr: Vec<usize>,
    /// gmsh element tags.
    pub tags: Vec<u64>,
    /// Section.
    pub section: crate::section::ShellSection,
    /// Material.
    pub material: Material,
    /// Mass form.
    pub lumping: MassLumping,
    nodes: std::sync::Arc<Vec<[f64; 3]>>,
}

impl ElementSet for ShellSet {
    fn len(&self) -> usize {
        self.tags.len()
    }
    fn nodes(&self, e: usize) -> &[u32] {
        &self.conn[self.ptr[e]..self.ptr[e + 1]]
    }
    fn dofs_per_node(&self) -> usize {
        6
    }
    fn matrices(&self, e: usize, ke: &mut [f64], me: &mut [f64], want_mass: bool) -> Result<()> {
        let x: Vec<[f64; 3]> = self.nodes(e).iter().map(|&a| self.nodes[a as usize]).collect();
        let k = self.kinds[e];
        let bad = |det: f64| Error::InvertedElement {
            element: self.tags[e],
            kind: k.name(),
            det,
        };
        crate::element::shell::stiffness(k, &x, &self.section, &self.material, ke).map_err(bad)?;
        if want_mass {
            crate::element::shell::mass(k, &x, &self.section, self.material.density, self.lumping, me).map_err(bad)?;
        }
        Ok(())
    }
}

/// Beam cells of one group.
pub struct BeamSet {
    /// Group name.
    pub group: String,
    /// Cell kind (line2 or line3) of each cell.
    pub kinds: Vec<CellKind>,
    /// Node lists.
    pub conn: Vec<u32>,
    /// Offsets into `conn`.
    pub ptr: Vec<usize>,
    /// gmsh element tags.
    pub tags: Vec<u64>,
    /// Orientation vector per element.
    pub orient: Vec<[f64; 3]>,
    /// Section.
    pub section: crate::section::BeamSection,
    /// Material.
    pub material: Material,
    /// Mass form.
    pub lumping: MassLumping,
    nodes: std::sync::Arc<Vec<[f64; 3]>>,
}

impl ElementSet for BeamSet {
    fn len(&self) -> usize {
        self.tags.len()
    }
    fn nodes(&self, e: usize) -> &[u32] {
        &self.conn[self.ptr[e]..self.ptr[e + 1]]
    }
    fn dofs_per_node(&self) -> usize {
        crate::element::beam::dofs_per_node(&self.section)
    }
    fn matrices(&self, e: usize, ke: &mut [f64], me: &mut [f64], want_mass: bool) -> Result<()> {
        let x: Vec<[f64; 3]> = self.nodes(e).iter().map(|&a| self.nodes[a as usize]).collect();
        let k = self.kinds[e];
        let ctx = |err: Error| Error::InvalidInput(format!("beam '{}', element {}: {err}", self.group, self.tags[e]));
        crate::element::beam::stiffness(k, &x, self.orient[e], &self.section, &self.material, ke).map_err(ctx)?;
        if want_mass {
            crate::element::beam::mass(k, &x, self.orient[e], &self.section, &self.material, self.lumping, me)
                .map_err(ctx)?;
        }
        Ok(())
    }
}

/// A rigid coupling (RBE2 / kinematic coupling): every node of `group` follows a reference node
/// at the group's centroid as a rigid body, u_s = u_R + θ_R × (x_s − x_R) (and θ_s = θ_R for
/// nodes with rotations). Implemented by eliminating the slave DOFs, not by penalty springs.
#[derive(Clone, Debug, PartialEq)]
pub struct CouplingSpec {
    /// The coupled group.
    pub group: String,
    /// "Guided": the reference node may only translate along this axis (0 = x, 1 = y, 2 = z)
    /// and may not rotate.
    pub guided: Option<usize>,
}

/// A point mass with rotary inertia.
#[derive(Clone, Debug, PartialEq)]
pub struct PointMassSpec {
    /// Where: a coupled group (its reference node), a one-node group, or a group whose nodes
    /// share the mass equally (translations only).
    pub group: String,
    /// Mass, kg.
    pub mass: f64,
    /// Inertia tensor about the point, kg·m²: Ixx, Iyy, Izz, Ixy, Iyz, Ixz.
    pub inertia: [f64; 6],
}

/// A discrete spring with a diagonal 6×6 stiffness, between two groups' points or from one
/// point to the ground. A point is a coupled group's reference node or a one-node group.
#[derive(Clone, Debug, PartialEq)]
pub struct SpringSpec {
    /// First end.
    pub a: String,
    /// Second end, or `None` for the ground.
    pub b: Option<String>,
    /// Stiffness in ux, uy, uz (N/m) and rx, ry, rz (N·m/rad).
    pub k: [f64; 6],
}

/// Discrete elements (point masses, springs) with precomputed matrices.
pub struct DiscreteSet {
    /// Nodes per element (1 or 2).
    pub per: usize,
    /// Components per node (3 or 6).
    pub ndpn: usize,
    /// Node indices, `per` per element.
    pub nodes: Vec<u32>,
    /// Stiffness matrices, `(per·ndpn)²` each, row-major.
    pub ke: Vec<Vec<f64>>,
    /// Mass matrices.
    pub me: Vec<Vec<f64>>,
    /// What each element is, for messages and reports.
    pub labels: Vec<String>,
}

impl ElementSet for DiscreteSet {
    fn len(&self) -> usize {
        self.labels.len()
    }
    fn nodes(&self, e: usize) -> &[u32] {
        &self.nodes[e * self.per..(e + 1) * self.per]
    }
    fn dofs_per_node(&self) -> usize {
        self.ndpn
    }
    fn matrices(&self, e: usize, ke: &mut [f64], me: &mut [f64], want_mass: bool) -> Result<()> {
        ke.copy_from_slice(&self.ke[e]);
        if want_mass {
            me.copy_from_slice(&self.me[e]);
        }
        Ok(())
    }
}

/// A reference node created for a coupling.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ReferenceNode {
    /// The coupled group.
    pub group: String,
    /// Node index in the model (after the mesh's nodes).
    pub node: usize,
    /// Position (centroid of the group's nodes), m.
    pub position: [f64; 3],
    /// Number of coupled nodes.
    pub slaves: usize,
    /// Guided axis, if any.
    pub guided: Option<usize>,
}

/// The solid cells of one kind, with their materials.
pub struct SolidSet {
    /// Cell kind.
    pub kind: CellKind,
    /// Connectivity, `kind.n_nodes()` per cell (dense node indices, gmsh order).
    pub conn: Vec<u32>,
    /// gmsh element tags.
    pub tags: Vec<u64>,
    /// Material index per cell into [`Model::materials`].
    pub mat: Vec<u16>,
    /// Materials table (shared copy).
    pub materials: Vec<Material>,
    /// Mass form.
    pub lumping: MassLumping,
    /// Node coordinates (shared copy of the mesh's).
    nodes: std::sync::Arc<Vec<[f64; 3]>>,
}

impl SolidSet {
    /// Coordinates of cell `e`'s nodes, written to `out` (length `kind.n_nodes()`).
    pub fn coords(&self, e: usize, out: &mut [[f64; 3]]) {
        for (o, &a) in out.iter_mut().zip(self.nodes(e)) {
            *o = self.nodes[a as usize];
        }
    }

    /// Volume of cell `e`.
    pub fn volume(&self, e: usize) -> Result<f64> {
        let mut x = [[0.0; 3]; 27];
        let nn = self.kind.n_nodes();
        self.coords(e, &mut x[..nn]);
        solid::volume(self.kind, &x[..nn]).map_err(|det| self.inverted(e, det))
    }

    /// The error for a non-positive Jacobian in cell `e`.
    pub fn inverted(&self, e: usize, det: f64) -> Error {
        Error::InvertedElement {
            element: self.tags[e],
            kind: self.kind.name(),
            det,
        }
    }
}

impl ElementSet for SolidSet {
    fn len(&self) -> usize {
        self.tags.len()
    }
    fn nodes(&self, e: usize) -> &[u32] {
        let n = self.kind.n_nodes();
        &self.conn[e * n..(e + 1) * n]
    }
    fn dofs_per_node(&self) -> usize {
        3
    }
    fn matrices(&self, e: usize, ke: &mut [f64], me: &mut [f64], want_mass: bool) -> Result<()> {
        let mut x = [[0.0; 3]; 27];
        let nn = self.kind.n_nodes();
        self.coords(e, &mut x[..nn]);
        let mat = &self.materials[self.mat[e] as usize];
        solid::stiffness(self.kind, &x[..nn], mat, ke).map_err(|det| self.inverted(e, det))?;
        if want_mass {
            solid::mass(self.kind, &x[..nn], mat.density, self.lumping, me).map_err(|det| self.inverted(e, det))?;
        }
        Ok(())
    }
}

/// A mesh bound to elements, materials and supports.
pub struct Model {
    /// Solid element sets, one per cell kind present.
    pub solids: Vec<SolidSet>,
    /// Point masses and springs (each set has one node count and DOFs per node).
    pub discrete: Vec<DiscreteSet>,
    /// Shell parts.
    pub shells: Vec<ShellSet>,
    /// Beam parts.
    pub beams: Vec<BeamSet>,
    /// All node coordinates: the mesh's, then the reference nodes.
    pub nodes: std::sync::Arc<Vec<[f64; 3]>>,
    /// Number of mesh nodes (reference nodes follow).
    pub n_mesh_nodes: usize,
    /// Reference nodes of couplings.
    pub references: Vec<ReferenceNode>,
    /// The DOF numbering.
    pub dofs: DofMap,
    /// Materials table (index 0 is the default material).
    pub materials: Vec<Material>,
    /// Nodes carrying no element (ignored, reported).
    pub orphan_nodes: usize,
    /// Notes for the user (groups ignored, nodes unused, ...).
    pub notes: Vec<String>,
}

impl Model {
    /// Bind `spec` to `mesh`.
    pub fn build(mesh: &Mesh, spec: &ModelSpec, source: &str) -> Result<Model> {
        spec.material.validate("(default)")?;
        let mut materials = vec![spec.material];
        let mut group_mat_idx = Vec::new();
        for (g, m) in &spec.group_materials {
            m.validate(&format!("for group '{g}'"))?;
            let grp = mesh.group(g)?;
            materials.push(*m);
            group_mat_idx.push((grp, (materials.len() - 1) as u16));
        }
        if materials.len() > u16::MAX as usize {
            return Err(Error::InvalidInput("too many materials".into()));
        }
        let nodes = std::sync::Arc::new(mesh.nodes.clone());
        let mut solids = Vec::new();
        let _ = &nodes;
        // Solid cells: all volume cells, or those of the chosen groups.
        // With shell or beam parts and no explicit solid groups, no volume cell is used: a model
        // contains what it names.
        let all_solids = spec.shells.is_empty() && spec.beams.is_empty();
        let mut selected: Vec<Vec<bool>> = mesh
            .blocks
            .iter()
            .map(|b| vec![all_solids && b.kind.dim() == 3; b.len()])
            .collect();
        if let Some(groups) = &spec.solid_groups {
            for v in &mut selected {
                v.iter_mut().for_each(|x| *x = false);
            }
            for g in groups {
                let grp = mesh.group(g)?;
                let mut any = false;
                for c in &grp.cells {
                    if mesh.blocks[c.block as usize].kind.dim() == 3 {
                        selected[c.block as usize][c.index as usize] = true;
                        any = true;
                    }
                }
                if !any {
                    return Err(Error::InvalidInput(format!(
                        "group '{g}' has no volume cells: a solid formulation needs tet, hex or wedge cells"
                    )));
                }
            }
        }
        for (bi, block) in mesh.blocks.iter().enumerate() {
            if block.kind.dim() != 3 || block.is_empty() {
                continue;
            }
            let mut matb = vec![0u16; block.len()];
            for (grp, mi) in &group_mat_idx {
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
                materials: materials.clone(),
                lumping: spec.lumping,
                nodes: nodes.clone(),
            });
        }
        // Shell and beam parts.
        let mut shells = Vec::new();
        for sp in &spec.shells {
            sp.section.validate(&format!("shell '{}'", sp.group))?;
            let mat = sp.material.unwrap_or(spec.material);
            mat.validate(&format!("for shell '{}'", sp.group))?;
            let grp = mesh.group(&sp.group)?;
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
                    return Err(Error::InvalidInput(format!(
                        "group '{}' has {} cells (element {}): a shell needs tri3 or quad4 surface cells",
                        sp.group, b.kind, b.tags[c.index as usize]
                    )));
                }
                set.kinds.push(b.kind);
                set.conn.extend_from_slice(b.cell(c.index as usize));
                set.ptr.push(set.conn.len());
                set.tags.push(b.tags[c.index as usize]);
            }
            if set.tags.is_empty() {
                return Err(Error::InvalidInput(format!("shell group '{}' is empty", sp.group)));
            }
            shells.push(set);
        }
        let mut beams = Vec::new();
        for bp in &spec.beams {
            bp.section.validate(&format!("beam '{}'", bp.group))?;
            let mat = bp.material.unwrap_or(spec.material);
            mat.validate(&format!("for beam '{}'", bp.group))?;
            let grp = mesh.group(&bp.group)?;
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
                    return Err(Error::InvalidInput(format!(
                        "group '{}' has {} cells (element {}): a beam needs line2 or line3 cells",
                        bp.group, b.kind, b.tags[c.index as usize]
                    )));
                }
                let cell = b.cell(c.index as usize);
                let xm = {
                    let mut m = [0.0; 3];
                    for &a in cell {
                        for d in 0..3 {
                            m[d] += mesh.nodes[a as usize][d] / cell.len() as f64;
                        }
                    }
                    m
                };
                let o = match bp.orientation {
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
                };
                set.kinds.push(b.kind);
                set.conn.extend_from_slice(cell);
                set.ptr.push(set.conn.len());
                set.tags.push(b.tags[c.index as usize]);
                set.orient.push(o);
            }
            if set.tags.is_empty() {
                return Err(Error::InvalidInput(format!(
                    "beam group '{}' has no line cells",
                    bp.group
                )));
            }
            beams.push(set);
        }
        if solids.is_empty() && shells.is_empty() && beams.is_empty() {
            let kinds: Vec<String> = mesh.blocks.iter().map(|b| format!("{} {}", b.len(), b.kind)).collect();
            return Err(Error::EmptyModel {
                what: format!(
                    "{source}: the mesh has no volume elements (it has {}); solid analysis needs tet, hex or wedge \
                     cells (surface and line groups need --shell or --beam)",
                    if kinds.is_empty() {
                        "no elements".to_string()
                    } else {
                        kinds.join(", ")
                    }
                ),
            });
        }
        let n_mesh = mesh.n_nodes();
        let mut notes = Vec::new();
        // Reference nodes of couplings, appended after the mesh nodes.
        let mut all_nodes = mesh.nodes.clone();
        let mut references = Vec::new();
        let mut coupled_nodes: Vec<(usize, Vec<u32>)> = Vec::new();
        for c in &spec.couplings {
            let grp = mesh.group(&c.group)?;
            let gn = mesh.group_nodes(grp);
            if gn.is_empty() {
                return Err(Error::InvalidInput(format!("coupling: group '{}' is empty", c.group)));
            }
            if references.iter().any(|r: &ReferenceNode| r.group == c.group) {
                return Err(Error::InvalidInput(format!("group '{}' is coupled twice", c.group)));
            }
            if let Some(ax) = c.guided {
                if ax > 2 {
                    return Err(Error::InvalidInput(format!(
                        "coupling '{}': guided axis must be x, y or z",
                        c.group
                    )));
                }
            }
            let mut p = [0.0; 3];
            for &a in &gn {
                for d in 0..3 {
                    p[d] += mesh.nodes[a as usize][d] / gn.len() as f64;
                }
            }
            references.push(ReferenceNode {
                group: c.group.clone(),
                node: all_nodes.len(),
                position: p,
                slaves: gn.len(),
                guided: c.guided,
            });
            coupled_nodes.push((all_nodes.len(), gn));
            all_nodes.push(p);
        }
        let n = all_nodes.len();
        let nodes = std::sync::Arc::new(all_nodes);
        for s in &mut solids {
            s.nodes = nodes.clone();
        }
        for s in &mut shells {
            s.nodes = nodes.clone();
        }
        for s in &mut beams {
            s.nodes = nodes.clone();
        }
        let point_of = |g: &str| -> Result<usize> {
            if let Some(r) = references.iter().find(|r| r.group == g) {
                return Ok(r.node);
            }
            let gn = mesh.group_nodes(mesh.group(g)?);
            match gn.as_slice() {
                [a] => Ok(*a as usize),
                _ => Err(Error::InvalidInput(format!(
                    "group '{g}' has {} nodes: a point mass with inertia or a spring needs a coupled group or a \
                     one-node group",
                    gn.len()
                ))),
            }
        };
        // Discrete elements.
        let mut discrete = Vec::new();
        let mut masses6 = DiscreteSet {
            per: 1,
            ndpn: 6,
            nodes: vec![],
            ke: vec![],
            me: vec![],
            labels: vec![],
        };
        let mut masses3 = DiscreteSet {
            per: 1,
            ndpn: 3,
            nodes: vec![],
            ke: vec![],
            me: vec![],
            labels: vec![],
        };
        for pm in &spec.point_masses {
            if !(pm.mass.is_finite() && pm.mass >= 0.0) || pm.inertia.iter().any(|v| !v.is_finite()) {
                return Err(Error::InvalidInput(format!(
                    "point mass on '{}': mass must be non-negative and finite, got {}",
                    pm.group, pm.mass
                )));
            }
            let rotary = pm.inertia.iter().any(|&v| v != 0.0);
            let single = references.iter().any(|r| r.group == pm.group)
                || mesh.group(&pm.group).map(|g| mesh.group_nodes(g).len() == 1)?;
            if single {
                let a = point_of(&pm.group)?;
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
                masses6.nodes.push(a as u32);
                masses6.ke.push(vec![0.0; 36]);
                masses6.me.push(me);
                masses6
                    .labels
                    .push(format!("point mass {} kg on '{}'", pm.mass, pm.group));
            } else {
                if rotary {
                    return Err(Error::InvalidInput(format!(
                        "point mass on '{}': rotary inertia needs a coupled group (--couple {})",
                        pm.group, pm.group
                    )));
                }
                let gn = mesh.group_nodes(mesh.group(&pm.group)?);
                let share = pm.mass / gn.len() as f64;
                for a in gn {
                    let mut me = vec![0.0; 9];
                    for d in 0..3 {
                        me[d * 3 + d] = share;
                    }
                    masses3.nodes.push(a);
                    masses3.ke.push(vec![0.0; 9]);
                    masses3.me.push(me);
                    masses3.labels.push(format!("share of point mass on '{}'", pm.group));
                }
                notes.push(format!(
                    "point mass {} kg on '{}' spread equally over its nodes",
                    pm.mass, pm.group
                ));
            }
        }
        let mut springs1 = DiscreteSet {
            per: 1,
            ndpn: 6,
            nodes: vec![],
            ke: vec![],
            me: vec![],
            labels: vec![],
        };
        let mut springs2 = DiscreteSet {
            per: 2,
            ndpn: 6,
            nodes: vec![],
            ke: vec![],
            me: vec![],
            labels: vec![],
        };
        for sp in &spec.springs {
            if sp.k.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(Error::InvalidInput(format!(
                    "spring on '{}': stiffnesses must be non-negative",
                    sp.a
                )));
            }
            let a = point_of(&sp.a)?;
            match &sp.b {
                None => {
                    let mut ke = vec![0.0; 36];
                    for d in 0..6 {
                        ke[d * 6 + d] = sp.k[d];
                    }
                    springs1.nodes.push(a as u32);
                    springs1.ke.push(ke);
                    springs1.me.push(vec![0.0; 36]);
                    springs1.labels.push(format!("spring '{}' to ground", sp.a));
                }
                Some(bg) => {
                    let b = point_of(bg)?;
                    let mut ke = vec![0.0; 144];
                    for d in 0..6 {
                        ke[d * 12 + d] = sp.k[d];
                        ke[(d + 6) * 12 + d + 6] = sp.k[d];
                        ke[d * 12 + d + 6] = -sp.k[d];
                        ke[(d + 6) * 12 + d] = -sp.k[d];
                    }
                    springs2.nodes.extend([a as u32, b as u32]);
                    springs2.ke.push(ke);
                    springs2.me.push(vec![0.0; 144]);
                    springs2.labels.push(format!("spring '{}'–'{bg}'", sp.a));
                }
            }
        }
        for d in [masses6, masses3, springs1, springs2] {
            if !d.labels.is_empty() {
                discrete.push(d);
            }
        }

        // Active components: what the elements use; reference nodes carry all six.
        let mut active = vec![0 as DofMask; n];
        for s in &solids {
            for &a in &s.conn {
                active[a as usize] |= TRANSLATIONS;
            }
        }
        for s in &shells {
            for &a in &s.conn {
                active[a as usize] |= crate::dof::ALL6;
            }
        }
        for s in &beams {
            let mask = if s.section.warping {
                crate::dof::ALL6 | crate::dof::WARPING
            } else {
                crate::dof::ALL6
            };
            for &a in &s.conn {
                active[a as usize] |= mask;
            }
        }
        for d in &discrete {
            let mask: DofMask = if d.ndpn == 6 { crate::dof::ALL6 } else { TRANSLATIONS };
            for &a in &d.nodes {
                active[a as usize] |= mask;
            }
        }
        for r in &references {
            active[r.node] |= crate::dof::ALL6;
        }
        let orphan_nodes = active[..n_mesh].iter().filter(|&&m| m == 0).count();

        // Constraints: fixes, couplings, prescribed values.
        let mut cons = crate::dof::Constraints::new(n);
        let mut fixed_by: Vec<Option<usize>> = vec![None; n];
        for (gi, (g, mask)) in spec.fixes.iter().enumerate() {
            let grp = mesh.group(g)?;
            let gn = mesh.group_nodes(grp);
            if gn.is_empty() {
                return Err(Error::InvalidInput(format!("group '{g}' has no nodes to fix")));
            }
            let mut count = 0;
            for a in gn {
                let m = *mask & active[a as usize];
                if m != 0 {
                    count += 1;
                    fixed_by[a as usize] = Some(gi);
                }
                cons.fixed[a as usize] |= m;
            }
            if count == 0 {
                return Err(Error::InvalidInput(format!(
                    "group '{g}' shares no node with the volume elements: nothing to fix"
                )));
            }
        }
        use crate::dof::NCOMP;
        for (r, (rnode, gn)) in references.iter().zip(&coupled_nodes) {
            let xr = r.position;
            for &s in gn {
                let s = s as usize;
                if let Some(gi) = fixed_by[s] {
                    return Err(Error::InvalidInput(format!(
                        "conflicting constraints: group '{}' is coupled, but its node {} is also fixed by '{}'",
                        r.group, mesh.node_tags[s], spec.fixes[gi].0
                    )));
                }
                if references.iter().any(|o| {
                    o.group != r.group
                        && coupled_nodes
                            .iter()
                            .any(|(rn, g)| *rn == o.node && g.contains(&(s as u32)))
                        && o.node < r.node
                }) {
                    return Err(Error::InvalidInput(format!(
                        "conflicting constraints: node {} belongs to two coupled groups",
                        mesh.node_tags[s]
                    )));
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
                cons.fixed[*rnode] |= crate::dof::ALL6 & !(1 << ax);
            }
        }
        for (g, vals) in &spec.prescribed {
            let targets: Vec<usize> = match references.iter().find(|r| &r.group == g) {
                Some(r) => vec![r.node],
                None => mesh
                    .group_nodes(mesh.group(g)?)
                    .into_iter()
                    .map(|a| a as usize)
                    .collect(),
            };
            for a in targets {
                for (c, v) in vals.iter().enumerate() {
                    let Some(v) = v else { continue };
                    if !v.is_finite() {
                        return Err(Error::InvalidInput(format!(
                            "prescribed displacement on '{g}' is not finite"
                        )));
                    }
                    if active[a] & (1 << c) == 0 {
                        continue;
                    }
                    if cons.mpc.contains_key(&(NCOMP * a + c)) {
                        return Err(Error::InvalidInput(format!(
                            "conflicting constraints: '{g}' prescribes a coupled node; prescribe the coupled group instead"
                        )));
                    }
                    cons.fixed[a] |= 1 << c;
                    cons.value.insert(NCOMP * a + c, *v);
                }
            }
        }
        for set in &solids {
            if matches!(set.kind, CellKind::Tet4 | CellKind::Hex8 | CellKind::Wedge6) {
                if let Some(m) = set
                    .mat
                    .iter()
                    .map(|&i| set.materials[i as usize])
                    .find(|m| m.poisson > 0.49)
                {
                    notes.push(format!(
                        "material ν = {} is nearly incompressible: linear {} elements lock (frequencies and \
                         stiffness too high); use tet10 or hex20",
                        m.poisson, set.kind
                    ));
                }
            }
        }
        if orphan_nodes > 0 {
            notes.push(format!("{orphan_nodes} nodes belong to no element and are ignored"));
        }
        let dofs = DofMap::with_constraints(active, cons)?;
        Ok(Model {
            solids,
            discrete,
            shells,
            beams,
            nodes,
            n_mesh_nodes: n_mesh,
            references,
            dofs,
            materials,
            orphan_nodes,
            notes,
        })
    }

    /// Element sets for assembly.
    pub fn element_sets(&self) -> Vec<&dyn ElementSet> {
        self.solids
            .iter()
            .map(|s| s as &dyn ElementSet)
            .chain(self.shells.iter().map(|d| d as &dyn ElementSet))
            .chain(self.beams.iter().map(|d| d as &dyn ElementSet))
            .chain(self.discrete.iter().map(|d| d as &dyn ElementSet))
            .collect()
    }

    /// Total volume (m³) and mass (kg) of the solid cells.
    pub fn volume_and_mass(&self) -> Result<(f64, f64)> {
        let (mut v, mut m) = (0.0, 0.0);
        for s in &self.shells {
            for e in 0..s.len() {
                let x: Vec<[f64; 3]> = s.nodes(e).iter().map(|&a| self.nodes[a as usize]).collect();
                let a = crate::element::shell::area(s.kinds[e], &x).map_err(|det| Error::InvertedElement {
                    element: s.tags[e],
                    kind: s.kinds[e].name(),
                    det,
                })?;
                v += a * s.section.thickness;
                m += a * s.section.thickness * s.material.density;
            }
        }
        for b in &self.beams {
            for e in 0..b.len() {
                let x: Vec<[f64; 3]> = b.nodes(e).iter().map(|&a| self.nodes[a as usize]).collect();
                let l = crate::element::beam::length(b.kinds[e], &x);
                v += l * b.section.area;
                m += l * b.section.area * b.material.density;
            }
        }
        for s in &self.solids {
            for e in 0..s.len() {
                let ve = s.volume(e)?;
                v += ve;
                m += ve * s.materials[s.mat[e] as usize].density;
            }
        }
        Ok((v, m))
    }

    /// Total translational mass of the point masses, kg.
    pub fn discrete_mass(&self) -> f64 {
        self.discrete
            .iter()
            .flat_map(|d| d.me.iter().map(move |m| m[0] / d.per as f64))
            .sum()
    }

    /// Number of solid cells per kind.
    pub fn cell_counts(&self) -> Vec<(CellKind, usize)> {
        self.solids.iter().map(|s| (s.kind, s.len())).collect()
    }
}
