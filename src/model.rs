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
}

impl Default for ModelSpec {
    fn default() -> Self {
        ModelSpec {
            material: Material::steel(),
            group_materials: vec![],
            fixes: vec![],
            lumping: MassLumping::Consistent,
        }
    }
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
    /// Coordinates of cell `e`'s nodes.
    fn coords(&self, e: usize, out: &mut [[f64; 3]]) {
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

    fn inverted(&self, e: usize, det: f64) -> Error {
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
        for (bi, block) in mesh.blocks.iter().enumerate() {
            if block.kind.dim() != 3 || block.is_empty() {
                continue;
            }
            let mut mat = vec![0u16; block.len()];
            for (grp, mi) in &group_mat_idx {
                for c in grp.cells.iter().filter(|c| c.block as usize == bi) {
                    mat[c.index as usize] = *mi;
                }
            }
            solids.push(SolidSet {
                kind: block.kind,
                conn: block.conn.clone(),
                tags: block.tags.clone(),
                mat,
                materials: materials.clone(),
                lumping: spec.lumping,
                nodes: nodes.clone(),
            });
        }
        if solids.is_empty() {
            let kinds: Vec<String> = mesh.blocks.iter().map(|b| format!("{} {}", b.len(), b.kind)).collect();
            return Err(Error::EmptyModel {
                what: format!(
                    "{source}: the mesh has no volume elements (it has {}); solid analysis needs tet, hex or wedge cells",
                    if kinds.is_empty() {
                        "no elements".to_string()
                    } else {
                        kinds.join(", ")
                    }
                ),
            });
        }
        let n = mesh.n_nodes();
        let mut active = vec![0 as DofMask; n];
        for s in &solids {
            for &a in &s.conn {
                active[a as usize] |= TRANSLATIONS;
            }
        }
        let orphan_nodes = active.iter().filter(|&&m| m == 0).count();
        let mut fixed = vec![0 as DofMask; n];
        let mut notes = Vec::new();
        for (g, mask) in &spec.fixes {
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
                }
                fixed[a as usize] |= m;
            }
            if count == 0 {
                return Err(Error::InvalidInput(format!(
                    "group '{g}' shares no node with the volume elements: nothing to fix"
                )));
            }
        }
        if orphan_nodes > 0 {
            notes.push(format!(
                "{orphan_nodes} nodes belong to no volume element and are ignored"
            ));
        }
        let dofs = DofMap::new(active, fixed);
        Ok(Model {
            solids,
            dofs,
            materials,
            orphan_nodes,
            notes,
        })
    }

    /// Element sets for assembly.
    pub fn element_sets(&self) -> Vec<&dyn ElementSet> {
        self.solids.iter().map(|s| s as &dyn ElementSet).collect()
    }

    /// Total volume (m³) and mass (kg) of the solid cells.
    pub fn volume_and_mass(&self) -> Result<(f64, f64)> {
        let (mut v, mut m) = (0.0, 0.0);
        for s in &self.solids {
            for e in 0..s.len() {
                let ve = s.volume(e)?;
                v += ve;
                m += ve * s.materials[s.mat[e] as usize].density;
            }
        }
        Ok((v, m))
    }

    /// Number of solid cells per kind.
    pub fn cell_counts(&self) -> Vec<(CellKind, usize)> {
        self.solids.iter().map(|s| (s.kind, s.len())).collect()
    }
}
