//! A model: a mesh bound to formulations, materials and supports.
//!
//! [`Model::build`] checks the user's choices ([`ModelSpec`]) against the mesh (groups exist,
//! materials are valid, there are elements to analyse), builds the element sets ([`sets`]) and
//! the DOF map, in the named steps of [`build`].

mod build;
mod coarse;
pub mod load;
pub(crate) mod orient;
pub mod sets;
pub mod spec;

pub use load::{GroupForce, Load};
pub use sets::{BeamSet, DiscreteSet, ReferenceNode, ShellSet, SolidSet};
pub use spec::{
    BeamPart, CouplingSpec, ModelSpec, Orientation, PointMassSpec, ShellPart, SpringMatrixSpec, SpringSpec,
    rigid_offset, transform_blocks,
};

use crate::Result;
use crate::dof::DofMap;
use crate::element::ElementSet;
use crate::material::Material;
use crate::mesh::CellKind;

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

    /// The cells the model is made of (solids, shells, beams; not the springs and masses), as
    /// blocks of one kind each on the mesh's nodes: what a result file should draw. A mesh's
    /// cells of another dimension that no element uses (the bricks of a box meshed for a shell
    /// model, the faces of a solid) are not among them. Cells on nodes beyond the mesh's (a
    /// reference node) are left out.
    pub fn cell_blocks(&self) -> Vec<crate::mesh::CellBlock> {
        use crate::mesh::{CellBlock, CellKind};
        let mut blocks: Vec<CellBlock> = Vec::new();
        let n_mesh = self.n_mesh_nodes as u32;
        let mut push = |kind: CellKind, cell: &[u32], tag: u64| {
            if cell.iter().any(|&a| a >= n_mesh) {
                return;
            }
            let i = match blocks.iter().position(|b| b.kind == kind) {
                Some(i) => i,
                None => {
                    blocks.push(CellBlock::new(kind));
                    blocks.len() - 1
                }
            };
            blocks[i].conn.extend_from_slice(cell);
            blocks[i].tags.push(tag);
        };
        for s in &self.solids {
            let nn = s.kind.n_nodes();
            for (cell, &tag) in s.conn.chunks(nn).zip(&s.tags) {
                push(s.kind, cell, tag);
            }
        }
        for s in &self.shells {
            for e in 0..s.tags.len() {
                push(s.kinds[e], &s.conn[s.ptr[e]..s.ptr[e + 1]], s.tags[e]);
            }
        }
        for b in &self.beams {
            for e in 0..b.tags.len() {
                push(b.kinds[e], &b.conn[b.ptr[e]..b.ptr[e + 1]], b.tags[e]);
            }
        }
        blocks
    }

    /// The nodal rotations (3 per mesh node, rad) of each column of `vectors` (over the free
    /// DOFs), scaled as `shapes[j]` (the column's translations as written: a buckling shape is
    /// scaled to a largest translation of 1, its vector is not, and its sign may differ):
    /// `None` for a column without rotations, as every column of a model without shells or
    /// beams. For the result files, beside the translations.
    pub fn node_rotations(&self, vectors: faer::MatRef<'_, f64>, shapes: &[Vec<f64>]) -> Vec<Option<Vec<f64>>> {
        if vectors.nrows() != self.dofs.n_free {
            return vec![None; vectors.ncols()];
        }
        (0..vectors.ncols())
            .map(|j| {
                let col: Vec<f64> = (0..vectors.nrows()).map(|i| vectors[(i, j)]).collect();
                let full = self.dofs.full(&col);
                let mut r = crate::dof::node_triplets(&full, self.n_mesh_nodes, 3);
                // The factor that takes the vector's translations to the shape's (least squares:
                // exact when one is a multiple of the other).
                let t = crate::dof::node_triplets(&full, self.n_mesh_nodes, 0);
                let tt: f64 = t.iter().map(|v| v * v).sum();
                let st: f64 = shapes
                    .get(j)
                    .map_or(0.0, |s| s.iter().zip(&t).map(|(a, b)| a * b).sum());
                let scale = if tt > 0.0 { st / tt } else { 1.0 };
                r.iter_mut().for_each(|v| *v *= scale);
                r.iter().any(|&v| v != 0.0).then_some(r)
            })
            .collect()
    }

    /// Total volume (m³) and mass (kg) of the continuum elements (solids, shells, beams): the
    /// sums of [`ElementSet::measure`] and `measure × density` (discrete elements have measure
    /// 0 and their mass is [`Model::discrete_mass`]). Summed shells first, then beams, then
    /// solids.
    pub fn volume_and_mass(&self) -> Result<(f64, f64)> {
        let sets = (self.shells.iter().map(|s| s as &dyn ElementSet))
            .chain(self.beams.iter().map(|s| s as &dyn ElementSet))
            .chain(self.solids.iter().map(|s| s as &dyn ElementSet));
        let (mut v, mut m) = (0.0, 0.0);
        for s in sets {
            for e in 0..s.len() {
                let ve = s.measure(e)?;
                v += ve;
                m += ve * s.density(e);
            }
        }
        Ok((v, m))
    }

    /// Total translational mass of the point masses, kg ([`ElementSet::mass`] of the discrete
    /// elements).
    pub fn discrete_mass(&self) -> f64 {
        self.discrete
            .iter()
            .flat_map(|d| (0..d.len()).map(move |e| d.point_mass(e)))
            .sum()
    }

    /// Number of mesh cells in the model per kind (solids, shells and beams; discrete elements
    /// are not cells), in order of first appearance.
    pub fn cell_counts(&self) -> Vec<(CellKind, usize)> {
        let mut out: Vec<(CellKind, usize)> = Vec::new();
        for set in self.element_sets() {
            for e in 0..set.len() {
                let Some(k) = set.cell_kind(e) else { continue };
                match out.iter_mut().find(|(q, _)| *q == k) {
                    Some((_, n)) => *n += 1,
                    None => out.push((k, 1)),
                }
            }
        }
        out
    }
}
