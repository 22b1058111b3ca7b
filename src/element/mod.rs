//! Element kernels: local stiffness and mass matrices, measures and stress recovery, and the
//! [`ElementSet`] interface through which assembly, mass properties and stress recovery see
//! every formulation.
//!
//! Kernels know no global numbering. They write dense row-major local matrices with node-major
//! degrees of freedom (`[n0.ux, n0.uy, n0.uz, n1.ux, …]`) into caller-provided buffers, so
//! assembly can reuse one buffer per chunk of elements and allocate nothing per element. A
//! non-positive Jacobian determinant comes back as `Err(det)`; the caller names the element in
//! the [`crate::Error::InvertedElement`] it reports.
//!
//! - [`solid`]: isoparametric 3D solids (`Tet4/10`, `Hex8/20/27`, `Wedge6/15`).
//! - [`incompatible`]: hex8 with condensed incompatible modes (Wilson–Taylor), chosen per model.
//! - [`shell`]: MITC3/MITC4 flat shells (`Tri3`, `Quad4`).
//! - [`beam`]: Timoshenko beams (`Line2`, `Line3`), optional warping DOF.
//! - [`geometric`]: geometric (initial-stress) stiffness of solids, shells and beams.
//! - [`lumping`]: the [`MassLumping`] choice and the HRZ and row-sum lumping schemes.
//!
//! Geometry (Jacobians, surface and line metrics, vector algebra) is [`crate::fe::geometry`];
//! shape functions and rules are [`crate::fe::shape`] and [`crate::fe::quadrature`].
//!
//! # Adding an element
//!
//! Measured on this tree by listing what a new formulation (say a membrane on `Tri3`) has to
//! change.
//!
//! **Before** the [`ElementSet`] interface carried measure, mass, labels and stress: the
//! kernel file; `model/sets.rs` (the set and its impl); `model/mod.rs` (a field on `Model`,
//! its line in `element_sets`, and its own loop in `volume_and_mass` calling the kernel's
//! area/length function); `post/mass.rs` (its own moments loop, a `Part` variant, its arms in
//! the node and moments lookups, its index loop and its link in the total); `model/build.rs`
//! and the input (`model/spec.rs`, `app/cli.rs`, `app/scene.rs`) to bind it to a group; and
//! `tests/unit/elements.rs`, whose sweeps call the solid kernels by name — 8 files, of which
//! `model/mod.rs` and `post/mass.rs` held a `match`/loop per formulation.
//!
//! **After**:
//! 1. the kernel and its set implementing [`ElementSet`] (`len`, `nodes`, `dofs_per_node`,
//!    `group`, `tag`, `cell_kind`, `matrices`, `consistent_mass`, `measure`, `density`; and
//!    `spurious_inertia`, `has_stress`/`stress_at` where they apply) — one file (the existing
//!    sets live in `model/sets.rs`; a new one can live next to its kernel);
//! 2. its line in the sweep `element_sweep` of `tests/unit/elements.rs`, which checks symmetry,
//!    rigid-body modes, mass against `measure × density`, its own mass form, and the stress
//!    availability of every entry;
//! 3. binding it to the mesh, unchanged: the `Model` field with one line in each of
//!    `Model::element_sets`, `Model::volume_and_mass` and `post::mass::group_mass_properties`
//!    (the last two list the set kinds in their own summation orders — shells, beams, solids
//!    and solids, shells, beams — kept to leave every total bit-identical; they call only the
//!    trait), plus `model/build.rs` and the input files.
//!
//! Assembly, the node graph, volume and mass totals, mass properties and nodal stresses are
//! generic over [`ElementSet`]. A new [`crate::mesh::CellKind`] (rather than a new
//! formulation on existing kinds) also touches `mesh/cell.rs`, `fe/shape.rs` and
//! `fe/quadrature.rs`; every `match` over kinds is exhaustive, so the compiler lists the
//! places (no `_ =>` arm hides one).

pub mod beam;
pub mod geometric;
pub mod incompatible;
pub mod lumping;
pub mod shell;
pub mod solid;

pub use lumping::MassLumping;

use crate::Result;
use crate::mesh::CellKind;

/// A set of elements of one formulation: the one interface through which assembly, mass
/// properties, volume totals and stress recovery see solids, shells, beams and discrete
/// elements alike.
///
/// Each element has a node list and writes dense, row-major element matrices of size
/// `(ndpn·n)²`, node-major: local DOF `a·ndpn + c` is component `c` of its `a`-th node.
pub trait ElementSet: Sync {
    /// Number of elements.
    fn len(&self) -> usize;
    /// True if there are no elements.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Dense node indices of element `e`.
    fn nodes(&self, e: usize) -> &[u32];
    /// Components per node this set's elements use (3: translations; 6: with rotations; 7:
    /// with a warping amplitude).
    fn dofs_per_node(&self) -> usize;
    /// What the set is, for messages: the group name of a shell or beam part, the cell kind of
    /// a solid set, `"discrete"` for point masses and springs.
    fn group(&self) -> &str;
    /// gmsh tag of element `e` (`None` for elements that are not mesh cells).
    fn tag(&self, e: usize) -> Option<u64>;
    /// Mesh cell kind of element `e` (`None` for elements that are not mesh cells).
    fn cell_kind(&self, e: usize) -> Option<CellKind>;
    /// Element stiffness `ke` and mass `me` (each `(ndpn·n)²`, row-major) with the set's mass
    /// form. `me` may be left untouched when `want_mass` is false.
    fn matrices(&self, e: usize, ke: &mut [f64], me: &mut [f64], want_mass: bool) -> Result<()>;
    /// The consistent mass matrix of element `e` whatever the set's lumping (mass properties
    /// take their second moments from it), `(ndpn·n)²`, row-major.
    fn consistent_mass(&self, e: usize, me: &mut [f64]) -> Result<()>;
    /// The measure of element `e`: the volume of a solid cell, area × thickness of a shell,
    /// length × section area of a beam, 0 for discrete elements (m³).
    fn measure(&self, e: usize) -> Result<f64>;
    /// Density of element `e` (kg/m³; 0 for discrete elements).
    fn density(&self, e: usize) -> f64;
    /// Mass of element `e` (kg): `measure × density`; discrete elements give their
    /// translational mass.
    fn mass(&self, e: usize) -> Result<f64> {
        Ok(self.measure(e)? * self.density(e))
    }
    /// Rotary inertia that [`ElementSet::consistent_mass`] carries without a physical
    /// counterpart, to be removed from mass properties: `(c, n)` stands for `c n nᵀ` (the
    /// drilling inertia `ρ t³/12 A` of a shell about its normal). `None` by default.
    fn spurious_inertia(&self, e: usize) -> Result<Option<(f64, [f64; 3])>> {
        let _ = e;
        Ok(None)
    }
    /// True if [`ElementSet::stress_at`] recovers a continuum stress for this set.
    fn has_stress(&self) -> bool {
        false
    }
    /// Continuum stress (Voigt order of [`crate::material`], global axes, Pa) of element `e`
    /// at reference point `xi` for element displacements `ue` (3 per node, node-major).
    /// The default, for formulations without a continuum stress field (shells and beams
    /// report stress resultants through their own kernels; discrete elements have none), is
    /// an error at the element saying so.
    fn stress_at(&self, e: usize, ue: &[f64], xi: [f64; 3]) -> Result<[f64; 6]> {
        let _ = (ue, xi);
        let msg = format!(
            "stress recovery is not available for '{}' (element {})",
            self.group(),
            self.tag(e).map_or_else(|| format!("#{e}"), |t| t.to_string())
        );
        Err(match self.tag(e) {
            Some(tag) => crate::Error::element(tag, msg),
            None => crate::Error::group(self.group(), msg),
        })
    }
}

impl<T: ElementSet + ?Sized> ElementSet for &T {
    fn len(&self) -> usize {
        (**self).len()
    }
    fn nodes(&self, e: usize) -> &[u32] {
        (**self).nodes(e)
    }
    fn dofs_per_node(&self) -> usize {
        (**self).dofs_per_node()
    }
    fn group(&self) -> &str {
        (**self).group()
    }
    fn tag(&self, e: usize) -> Option<u64> {
        (**self).tag(e)
    }
    fn cell_kind(&self, e: usize) -> Option<CellKind> {
        (**self).cell_kind(e)
    }
    fn matrices(&self, e: usize, ke: &mut [f64], me: &mut [f64], want_mass: bool) -> Result<()> {
        (**self).matrices(e, ke, me, want_mass)
    }
    fn consistent_mass(&self, e: usize, me: &mut [f64]) -> Result<()> {
        (**self).consistent_mass(e, me)
    }
    fn measure(&self, e: usize) -> Result<f64> {
        (**self).measure(e)
    }
    fn density(&self, e: usize) -> f64 {
        (**self).density(e)
    }
    fn mass(&self, e: usize) -> Result<f64> {
        (**self).mass(e)
    }
    fn spurious_inertia(&self, e: usize) -> Result<Option<(f64, [f64; 3])>> {
        (**self).spurious_inertia(e)
    }
    fn has_stress(&self) -> bool {
        (**self).has_stress()
    }
    fn stress_at(&self, e: usize, ue: &[f64], xi: [f64; 3]) -> Result<[f64; 6]> {
        (**self).stress_at(e, ue, xi)
    }
}
