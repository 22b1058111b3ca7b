//! Element sets of a bound model: solid cells of one kind, shell and beam parts, discrete
//! masses and springs. Each implements [`ElementSet`], the one interface assembly, mass
//! properties and stress recovery use.

use crate::element::incompatible::{self, Hex8Formulation};
use crate::element::{ElementSet, MassLumping, beam, shell, solid};
use crate::material::Material;
use crate::mesh::CellKind;
use crate::{Error, Result};
use std::sync::Arc;

/// Copies the coordinates of `nodes` into the front of `buf` and returns that slice: element
/// coordinates on the stack, no allocation per element.
fn gather<'a>(all: &[[f64; 3]], nodes: &[u32], buf: &'a mut [[f64; 3]; 27]) -> &'a [[f64; 3]] {
    for (o, &a) in buf.iter_mut().zip(nodes) {
        *o = all[a as usize];
    }
    &buf[..nodes.len()]
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
    pub(crate) nodes: Arc<Vec<[f64; 3]>>,
}

impl ShellSet {
    /// A set of one element of `kind` on its own nodes `x` (numbered 0..n), for sweeps and
    /// examples.
    pub fn single(kind: CellKind, x: Vec<[f64; 3]>, section: crate::section::ShellSection, material: Material) -> Self {
        let n = x.len();
        ShellSet {
            group: format!("{kind} shell"),
            kinds: vec![kind],
            conn: (0..n as u32).collect(),
            ptr: vec![0, n],
            tags: vec![1],
            section,
            material,
            lumping: MassLumping::Consistent,
            nodes: Arc::new(x),
        }
    }

    fn inverted(&self, e: usize, det: f64) -> Error {
        Error::InvertedElement {
            element: self.tags[e],
            kind: self.kinds[e].name(),
            det,
            file: None,
        }
    }

    /// Area of the (projected, mean-plane) element `e` ([`shell::area`]).
    pub fn area(&self, e: usize) -> Result<f64> {
        let mut buf = [[0.0; 3]; 27];
        let x = gather(&self.nodes, self.nodes(e), &mut buf);
        shell::area(self.kinds[e], x).map_err(|det| self.inverted(e, det))
    }
}

impl ElementSet for ShellSet {
    fn len(&self) -> usize {
        self.tags.len()
    }
    fn nodes(&self, e: usize) -> &[u32] {
        &self.conn[self.ptr[e]..self.ptr[e + 1]]
    }
    fn dofs_per_node(&self) -> usize {
        shell::DOFS_PER_NODE
    }
    fn group(&self) -> &str {
        &self.group
    }
    fn tag(&self, e: usize) -> Option<u64> {
        Some(self.tags[e])
    }
    fn cell_kind(&self, e: usize) -> Option<CellKind> {
        Some(self.kinds[e])
    }
    fn matrices(&self, e: usize, ke: &mut [f64], me: &mut [f64], want_mass: bool) -> Result<()> {
        let mut buf = [[0.0; 3]; 27];
        let x = gather(&self.nodes, self.nodes(e), &mut buf);
        let k = self.kinds[e];
        let bad = |det: f64| self.inverted(e, det);
        shell::stiffness(k, x, &self.section, &self.material, ke).map_err(bad)?;
        if want_mass {
            shell::mass(k, x, &self.section, self.material.density, self.lumping, me).map_err(bad)?;
        }
        Ok(())
    }
    fn consistent_mass(&self, e: usize, me: &mut [f64]) -> Result<()> {
        let mut buf = [[0.0; 3]; 27];
        let x = gather(&self.nodes, self.nodes(e), &mut buf);
        let k = self.kinds[e];
        shell::mass(k, x, &self.section, self.material.density, MassLumping::Consistent, me)
            .map_err(|det| self.inverted(e, det))
    }
    fn measure(&self, e: usize) -> Result<f64> {
        Ok(self.area(e)? * self.section.thickness)
    }
    fn density(&self, _e: usize) -> f64 {
        self.material.density
    }
    /// The drilling inertia `ρ t³/12 A n nᵀ` (see [`crate::post::mass`]).
    fn spurious_inertia(&self, e: usize) -> Result<Option<(f64, [f64; 3])>> {
        let mut buf = [[0.0; 3]; 27];
        let x = gather(&self.nodes, self.nodes(e), &mut buf);
        let k = self.kinds[e];
        let bad = |det: f64| self.inverted(e, det);
        let area = shell::area(k, x).map_err(bad)?;
        let normal = shell::local_frame(k, x).map_err(bad)?[2];
        let t = self.section.thickness;
        Ok(Some((self.material.density * t.powi(3) / 12.0 * area, normal)))
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
    pub(crate) nodes: Arc<Vec<[f64; 3]>>,
}

impl BeamSet {
    /// A set of one element of `kind` on its own nodes `x` (numbered 0..n) with orientation
    /// vector `orient`, for sweeps and examples.
    pub fn single(
        kind: CellKind,
        x: Vec<[f64; 3]>,
        orient: [f64; 3],
        section: crate::section::BeamSection,
        material: Material,
    ) -> Self {
        let n = x.len();
        BeamSet {
            group: format!("{kind} beam"),
            kinds: vec![kind],
            conn: (0..n as u32).collect(),
            ptr: vec![0, n],
            tags: vec![1],
            orient: vec![orient],
            section,
            material,
            lumping: MassLumping::Consistent,
            nodes: Arc::new(x),
        }
    }

    fn context(&self, e: usize) -> impl Fn(Error) -> Error + '_ {
        move |err: Error| {
            Error::element(
                self.tags[e],
                format!("beam '{}', element {}: {err}", self.group, self.tags[e]),
            )
        }
    }

    /// Length of element `e` ([`beam::length`]).
    pub fn length(&self, e: usize) -> f64 {
        let mut buf = [[0.0; 3]; 27];
        let x = gather(&self.nodes, self.nodes(e), &mut buf);
        beam::length(self.kinds[e], x)
    }
}

impl ElementSet for BeamSet {
    fn len(&self) -> usize {
        self.tags.len()
    }
    fn nodes(&self, e: usize) -> &[u32] {
        &self.conn[self.ptr[e]..self.ptr[e + 1]]
    }
    fn dofs_per_node(&self) -> usize {
        beam::dofs_per_node(&self.section)
    }
    fn group(&self) -> &str {
        &self.group
    }
    fn tag(&self, e: usize) -> Option<u64> {
        Some(self.tags[e])
    }
    fn cell_kind(&self, e: usize) -> Option<CellKind> {
        Some(self.kinds[e])
    }
    fn matrices(&self, e: usize, ke: &mut [f64], me: &mut [f64], want_mass: bool) -> Result<()> {
        let mut buf = [[0.0; 3]; 27];
        let x = gather(&self.nodes, self.nodes(e), &mut buf);
        let k = self.kinds[e];
        let ctx = self.context(e);
        beam::stiffness(k, x, self.orient[e], &self.section, &self.material, ke).map_err(&ctx)?;
        if want_mass {
            beam::mass(k, x, self.orient[e], &self.section, &self.material, self.lumping, me).map_err(&ctx)?;
        }
        Ok(())
    }
    fn consistent_mass(&self, e: usize, me: &mut [f64]) -> Result<()> {
        let mut buf = [[0.0; 3]; 27];
        let x = gather(&self.nodes, self.nodes(e), &mut buf);
        let k = self.kinds[e];
        beam::mass(
            k,
            x,
            self.orient[e],
            &self.section,
            &self.material,
            MassLumping::Consistent,
            me,
        )
        .map_err(self.context(e))
    }
    fn measure(&self, e: usize) -> Result<f64> {
        Ok(self.length(e) * self.section.area)
    }
    fn density(&self, _e: usize) -> f64 {
        self.material.density
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

    /// Translational mass of element `e`, kg: the first diagonal entry of its mass matrix per
    /// node (0 for a spring).
    pub fn point_mass(&self, e: usize) -> f64 {
        self.me[e][0] / self.per as f64
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
    fn group(&self) -> &str {
        "discrete"
    }
    fn tag(&self, _e: usize) -> Option<u64> {
        None
    }
    fn cell_kind(&self, _e: usize) -> Option<CellKind> {
        None
    }
    fn matrices(&self, e: usize, ke: &mut [f64], me: &mut [f64], want_mass: bool) -> Result<()> {
        ke.copy_from_slice(&self.ke[e]);
        if want_mass {
            me.copy_from_slice(&self.me[e]);
        }
        Ok(())
    }
    fn consistent_mass(&self, e: usize, me: &mut [f64]) -> Result<()> {
        me.copy_from_slice(&self.me[e]);
        Ok(())
    }
    fn measure(&self, _e: usize) -> Result<f64> {
        Ok(0.0)
    }
    fn density(&self, _e: usize) -> f64 {
        0.0
    }
    /// The translational mass ([`DiscreteSet::point_mass`]).
    fn mass(&self, e: usize) -> Result<f64> {
        Ok(self.point_mass(e))
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
    /// Formulation of hex8 cells (ignored for other kinds).
    pub hex8: Hex8Formulation,
    /// Node coordinates (shared copy of the mesh's).
    pub(crate) nodes: Arc<Vec<[f64; 3]>>,
}

impl SolidSet {
    /// A set of one cell of `kind` on its own nodes `x` (numbered 0..n, gmsh order), for
    /// sweeps and examples.
    pub fn single(kind: CellKind, x: Vec<[f64; 3]>, material: Material) -> Self {
        SolidSet {
            kind,
            conn: (0..x.len() as u32).collect(),
            tags: vec![1],
            mat: vec![0],
            materials: vec![material],
            lumping: MassLumping::Consistent,
            hex8: Hex8Formulation::Standard,
            nodes: Arc::new(x),
        }
    }

    /// True if the cells are hex8 with incompatible modes ([`crate::element::incompatible`]).
    pub fn incompatible(&self) -> bool {
        self.kind == CellKind::Hex8 && self.hex8 == Hex8Formulation::Incompatible
    }

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
            file: None,
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
    fn group(&self) -> &str {
        self.kind.name()
    }
    fn tag(&self, e: usize) -> Option<u64> {
        Some(self.tags[e])
    }
    fn cell_kind(&self, _e: usize) -> Option<CellKind> {
        Some(self.kind)
    }
    fn matrices(&self, e: usize, ke: &mut [f64], me: &mut [f64], want_mass: bool) -> Result<()> {
        let mut x = [[0.0; 3]; 27];
        let nn = self.kind.n_nodes();
        self.coords(e, &mut x[..nn]);
        let mat = &self.materials[self.mat[e] as usize];
        if self.incompatible() {
            incompatible::stiffness(&x[..nn], mat, ke).map_err(|det| self.inverted(e, det))?;
        } else {
            solid::stiffness(self.kind, &x[..nn], mat, ke).map_err(|det| self.inverted(e, det))?;
        }
        if want_mass {
            solid::mass(self.kind, &x[..nn], mat.density, self.lumping, me).map_err(|det| self.inverted(e, det))?;
        }
        Ok(())
    }
    fn consistent_mass(&self, e: usize, me: &mut [f64]) -> Result<()> {
        let mut x = [[0.0; 3]; 27];
        let nn = self.kind.n_nodes();
        self.coords(e, &mut x[..nn]);
        let rho = self.materials[self.mat[e] as usize].density;
        solid::mass(self.kind, &x[..nn], rho, MassLumping::Consistent, me).map_err(|det| self.inverted(e, det))
    }
    fn measure(&self, e: usize) -> Result<f64> {
        self.volume(e)
    }
    fn density(&self, e: usize) -> f64 {
        self.materials[self.mat[e] as usize].density
    }
    fn has_stress(&self) -> bool {
        true
    }
    fn stress_at(&self, e: usize, ue: &[f64], xi: [f64; 3]) -> Result<[f64; 6]> {
        let mut x = [[0.0; 3]; 27];
        let nn = self.kind.n_nodes();
        self.coords(e, &mut x[..nn]);
        let mat = &self.materials[self.mat[e] as usize];
        if self.incompatible() {
            incompatible::stress_at(&x[..nn], mat, ue, xi).map_err(|det| self.inverted(e, det))
        } else {
            solid::stress_at(self.kind, &x[..nn], mat, ue, xi).map_err(|det| self.inverted(e, det))
        }
    }
}
