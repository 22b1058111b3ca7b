//! A model: a mesh bound to formulations, materials and supports.
//!
//! [`Model::build`] checks the user's choices ([`ModelSpec`]) against the mesh (groups exist,
//! materials are valid, there are elements to analyse), builds the element sets ([`sets`]) and
//! the DOF map, in the named steps of [`build`].

mod build;
pub mod sets;
pub mod spec;

pub use sets::{BeamSet, DiscreteSet, ReferenceNode, ShellSet, SolidSet};
pub use spec::{BeamPart, CouplingSpec, ModelSpec, Orientation, PointMassSpec, ShellPart, SpringSpec};

use crate::assembly::ElementSet;
use crate::dof::DofMap;
use crate::material::Material;
use crate::mesh::CellKind;
use crate::{Error, Result};

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
    /// gmsh tags of the mesh nodes (for messages naming a node).
    pub node_tags: Vec<u64>,
    /// What the model was built from.
    pub spec: ModelSpec,
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
