//! The corner space of a quadratic mesh: every free DOF of a corner node kept, every mid-side
//! (face, centre) node's value interpolated linearly from its cell's corners. On straight
//! cells it is exactly the space of the mesh's linear elements (tet4 inside tet10, hex8 inside
//! hex20), so the Galerkin pencil (PᵀKP, PᵀMP) is the linear-element model of the same mesh,
//! at an eighth of the DOFs of a tet10 mesh. Its eigenvalues bound the model's from above
//! ([`crate::linalg::coarse`]).

use super::Model;
use crate::dof::NCOMP;
use crate::fe::shape;
use crate::linalg::coarse::Prolongation;
use crate::mesh::CellKind;

impl Model {
    /// The corner space of this model, or `None` when it would not be much smaller than the
    /// model (linear meshes: every node is a corner).
    pub fn corner_space(&self) -> Option<Prolongation> {
        let n_nodes = self.dofs.n_nodes();
        // A node is a corner unless it is only ever a cell's higher-order node; discrete
        // elements, reference nodes and constraint masters keep all their nodes.
        let mut corner = vec![false; n_nodes];
        let mut seen = vec![false; n_nodes];
        let sets = self.element_sets();
        for set in &sets {
            for e in 0..set.len() {
                let nodes = set.nodes(e);
                let n_lin = set.cell_kind(e).map_or(nodes.len(), |k| k.linear().n_nodes());
                for (j, &a) in nodes.iter().enumerate() {
                    seen[a as usize] = true;
                    if j < n_lin {
                        corner[a as usize] = true;
                    }
                }
            }
        }
        for masters in self.dofs.mpc.values() {
            for &(raw, _) in masters {
                corner[raw / NCOMP] = true;
            }
        }
        for a in 0..n_nodes {
            if !seen[a] {
                corner[a] = true;
            }
        }
        // Interpolation of each higher-order node from the first cell that has it: the
        // linear shape functions at the node's reference coordinates.
        let mut weights: Vec<Option<Vec<(u32, f64)>>> = vec![None; n_nodes];
        let mut local: std::collections::HashMap<CellKind, Vec<Vec<(usize, f64)>>> = Default::default();
        for set in &sets {
            for e in 0..set.len() {
                let Some(kind) = set.cell_kind(e) else { continue };
                if kind.linear() == kind {
                    continue;
                }
                let nodes = set.nodes(e);
                let n_lin = kind.linear().n_nodes();
                let local = local.entry(kind).or_insert_with(|| shape::corner_weights(kind));
                for (k, &a) in nodes.iter().enumerate().skip(n_lin) {
                    let a = a as usize;
                    if corner[a] || weights[a].is_some() {
                        continue;
                    }
                    weights[a] = Some(local[k - n_lin].iter().map(|&(i, w)| (nodes[i], w)).collect());
                }
            }
        }
        // Coarse unknowns: the free components of the corners, in equation order.
        let n = self.dofs.n_free;
        let mut coarse_of = vec![u32::MAX; n];
        let mut n_coarse = 0usize;
        for a in 0..n_nodes {
            if !corner[a] {
                continue;
            }
            for c in 0..NCOMP {
                if let Some(e) = self.dofs.eq_of(a, c) {
                    coarse_of[e] = n_coarse as u32;
                    n_coarse += 1;
                }
            }
        }
        if n_coarse == 0 || 2 * n_coarse > n {
            return None;
        }
        let mut rows = vec![Vec::new(); n];
        for a in 0..n_nodes {
            for c in 0..NCOMP {
                let Some(e) = self.dofs.eq_of(a, c) else { continue };
                rows[e] = match &weights[a] {
                    _ if corner[a] => vec![(coarse_of[e], 1.0)],
                    Some(w) => w
                        .iter()
                        .filter_map(|&(b, wb)| self.dofs.eq_of(b as usize, c).map(|eb| (coarse_of[eb], wb)))
                        .collect(),
                    None => vec![],
                };
            }
        }
        Some(Prolongation::from_rows(n_coarse, &rows))
    }
}
