//! Element sets of a bound model: solid cells of one kind, shell and beam parts, discrete
//! masses and springs. Each implements [`ElementSet`], the one interface assembly, mass
//! properties and stress recovery use.

use crate::assembly::ElementSet;
use crate::element::{MassLumping, solid};
use crate::material::Material;
use crate::mesh::CellKind;
use crate::{Error, Result};

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
    pub(crate) nodes: std::sync::Arc<Vec<[f64; 3]>>,
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
    pub(crate) nodes: std::sync::Arc<Vec<[f64; 3]>>,
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

impl DiscreteSet {
    /// An empty set of elements with `per` nodes of `ndpn` components each.
    pub fn new(per: usize, ndpn: usize) -> Self {
        DiscreteSet {
            per,
            ndpn,
            nodes: vec![],
            ke: vec![],
            me: vec![],
            labels: vec![],
        }
    }

    /// Add an element on `nodes` with stiffness `ke` and mass `me` (`(per·ndpn)²`, row-major).
    pub fn push(&mut self, nodes: &[u32], ke: Vec<f64>, me: Vec<f64>, label: String) {
        debug_assert_eq!(nodes.len(), self.per);
        debug_assert_eq!(ke.len(), (self.per * self.ndpn).pow(2));
        self.nodes.extend_from_slice(nodes);
        self.ke.push(ke);
        self.me.push(me);
        self.labels.push(label);
    }
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
    pub(crate) nodes: std::sync::Arc<Vec<[f64; 3]>>,
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
