//! Stress recovery: stresses at the integration points, nodal stresses, equivalent stresses and
//! their maxima per group.
//!
//! Stresses are in the Voigt order of [`crate::material`]: `[σ_xx, σ_yy, σ_zz, σ_yz, σ_xz, σ_xy]`
//! (Pa). Displacements `u` are node-major with three components per node (m), indexed by the
//! dense node index of the mesh (`u[3 a + i]`).
//!
//! # Nodal stresses
//!
//! The displacement-based stress field is discontinuous between elements, so a nodal value is
//! made in two steps:
//!
//! 1. **per element**, the stress at each of its nodes, by one of two [`Recovery`] methods:
//!    - [`Recovery::Direct`] (the default, [`nodal_stress`]): `σ = D B(ξ_a) u_e` evaluated at
//!      the node's own reference coordinates `ξ_a` ([`shape::reference_nodes`]). For the
//!      quadratic elements (tet10, hex20, hex27, wedge15) this is the standard direct nodal
//!      evaluation of the element's own stress polynomial: no extrapolation, exact whenever the
//!      element represents the displacement field exactly (e.g. linear-in-z bending stress on
//!      hex20 or tet10). For tet4 it is the element's constant stress.
//!    - [`Recovery::Extrapolated`]: the stresses at a low-order set of integration points
//!      (2 × 2 × 2 Gauss for hexahedra, the 4-point degree-2 rule for tetrahedra, 3 × 2 points
//!      for wedges) are fitted by the linear element's shape functions (trilinear / linear /
//!      wedge-linear, an exact interpolation through those points) and the fit is evaluated at
//!      every node, corners and midside nodes alike. This is what many commercial codes do;
//!      the 2 × 2 × 2 points are the superconvergent (Barlow) points of hex20. It reproduces any
//!      stress field that is linear in the reference coordinates exactly. tet4 (one point,
//!      constant stress) gives the constant.
//! 2. **between elements**, a simple (unweighted) average over the elements sharing the node.
//!    Averaging smooths stress peaks at re-entrant corners and material interfaces, so the
//!    per-node maximum over the contributing elements of the element von Mises stress is kept
//!    as [`NodalStress::von_mises_max_unaveraged`], with the element that produced it.
//!
//! The equivalent stresses ([`NodalStress::von_mises`], principal stresses, Tresca) are
//! computed from the *averaged* tensor.
//!
//! # Integration points
//!
//! [`gauss_point_stress`] evaluates the stress at the points of each element's stiffness rule
//! (the rule of [`solid::stiffness_degree`]): 27 points for hex20/hex27, 4 for tet10, 1 for
//! tet4, and so on. These are the most accurate stresses of a displacement solution.
//!
//! # Output
//!
//! [`StressFields`] flattens a [`NodalStress`] into the per-node arrays that
//! [`crate::io::vtk::write_vtu`] ([`PointField`]) and [`crate::io::msh_out::write_msh_views`]
//! ([`NodeView`]) take.

use serde::Serialize;

use crate::assembly::ElementSet;
use crate::element::solid;
use crate::fe::quadrature;
use crate::fe::shape::{self, MAX_NODES};
use crate::io::msh_out::NodeView;
use crate::io::vtk::PointField;
use crate::mesh::{CellKind, Mesh};
use crate::model::SolidSet;
use crate::{Error, Result};

/// How the stress at an element's nodes is obtained before averaging (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum Recovery {
    /// Direct evaluation of `D B u` at each node's reference coordinates.
    #[default]
    Direct,
    /// Fit of low-order integration-point stresses by the linear element's shape functions,
    /// evaluated at the nodes.
    Extrapolated,
}

/// Stresses recovered at the nodes (one entry per mesh node, dense node index).
///
/// Nodes that belong to no solid element have zero stress and `count == 0`; they are skipped
/// by [`group_maxima`].
#[derive(Clone, Debug, Serialize)]
pub struct NodalStress {
    /// The recovery used per element before averaging.
    pub recovery: Recovery,
    /// Averaged stress tensor per node, Voigt order `xx, yy, zz, yz, xz, xy` (Pa).
    pub stress: Vec<[f64; 6]>,
    /// von Mises stress of the averaged tensor (Pa).
    pub von_mises: Vec<f64>,
    /// Principal stresses of the averaged tensor, descending `σ1 ≥ σ2 ≥ σ3` (Pa).
    pub principal: Vec<[f64; 3]>,
    /// Tresca equivalent stress `σ1 − σ3` of the averaged tensor (twice the maximum shear) (Pa).
    pub tresca: Vec<f64>,
    /// Per node, the maximum over the elements sharing it of that element's von Mises stress at
    /// the node, before averaging (Pa). Always `≥` the von Mises stress of the average.
    pub von_mises_max_unaveraged: Vec<f64>,
    /// The gmsh tag of the element giving [`NodalStress::von_mises_max_unaveraged`] (0 where
    /// `count == 0`).
    pub max_element: Vec<u64>,
    /// Number of elements averaged at each node.
    pub count: Vec<u32>,
}

/// Stresses at the integration points of every solid element.
#[derive(Clone, Debug, Serialize)]
pub struct GaussPointStress {
    /// Physical coordinates of each point (m).
    pub points: Vec<[f64; 3]>,
    /// Stress at each point, Voigt order `xx, yy, zz, yz, xz, xy` (Pa).
    pub stress: Vec<[f64; 6]>,
    /// von Mises stress at each point (Pa).
    pub von_mises: Vec<f64>,
    /// gmsh tag of the element each point belongs to.
    pub element: Vec<u64>,
}

/// A scalar stress measure, for [`group_maxima`] and [`GaussPointStress::peak`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum StressField {
    /// von Mises stress of the averaged tensor.
    VonMises,
    /// Largest unaveraged element von Mises stress at the node ([`NodalStress::von_mises_max_unaveraged`]).
    VonMisesMaxUnaveraged,
    /// Tresca equivalent stress `σ1 − σ3`.
    Tresca,
    /// Maximum shear stress `(σ1 − σ3) / 2`.
    MaxShear,
    /// Largest principal stress `σ1`.
    MaxPrincipal,
    /// Smallest principal stress `σ3`; its extreme is the *minimum* (most compressive) value.
    MinPrincipal,
    /// One Voigt component (`0..6`: `xx, yy, zz, yz, xz, xy`); its extreme is the value of
    /// largest magnitude, reported with its sign.
    Component(usize),
}

impl StressField {
    /// The measure of one stress tensor (Voigt order). `VonMisesMaxUnaveraged` is the von
    /// Mises stress of the tensor.
    ///
    /// # Panics
    /// For `Component(i)` with `i ≥ 6`.
    pub fn of_tensor(self, s: &[f64; 6]) -> f64 {
        match self {
            StressField::VonMises | StressField::VonMisesMaxUnaveraged => von_mises(s),
            StressField::Tresca => tresca(s),
            StressField::MaxShear => 0.5 * tresca(s),
            StressField::MaxPrincipal => principal(s)[0],
            StressField::MinPrincipal => principal(s)[2],
            StressField::Component(i) => s[i],
        }
    }

    /// Short name for reports (`"von_mises"`, `"sigma_xx"`, ...).
    pub fn name(self) -> &'static str {
        match self {
            StressField::VonMises => "von_mises",
            StressField::VonMisesMaxUnaveraged => "von_mises_max_unaveraged",
            StressField::Tresca => "tresca",
            StressField::MaxShear => "max_shear",
            StressField::MaxPrincipal => "principal_1",
            StressField::MinPrincipal => "principal_3",
            StressField::Component(0) => "sigma_xx",
            StressField::Component(1) => "sigma_yy",
            StressField::Component(2) => "sigma_zz",
            StressField::Component(3) => "sigma_yz",
            StressField::Component(4) => "sigma_xz",
            StressField::Component(5) => "sigma_xy",
            StressField::Component(_) => "invalid component",
        }
    }

    /// True if `a` is more extreme than `b` for this field (see the variants).
    fn beats(self, a: f64, b: f64) -> bool {
        match self {
            StressField::MinPrincipal => a < b,
            StressField::Component(_) => a.abs() > b.abs(),
            _ => a > b,
        }
    }

    fn check(self) -> Result<()> {
        match self {
            StressField::Component(i) if i >= 6 => Err(Error::param(
                "StressField::Component",
                format!("stress component {i} does not exist (Voigt components are 0..6: xx, yy, zz, yz, xz, xy)"),
            )),
            _ => Ok(()),
        }
    }
}

/// The extreme of a stress measure over one physical group (or the whole model).
#[derive(Clone, Debug, Serialize)]
pub struct GroupMax {
    /// Group name; `"(all)"` for the whole model, `"(gauss points)"` for [`GaussPointStress::peak`].
    pub group: String,
    /// The field.
    pub field: StressField,
    /// The extreme value (Pa).
    pub value: f64,
    /// File tag of the node where it occurs (nodal results).
    pub node: Option<u64>,
    /// gmsh tag of the element: the element giving the unaveraged maximum for
    /// [`StressField::VonMisesMaxUnaveraged`], the element of the point for Gauss-point results.
    pub element: Option<u64>,
    /// Coordinates of the node or point (m).
    pub coords: [f64; 3],
}

/// von Mises equivalent stress of a Voigt stress `[σ_xx, σ_yy, σ_zz, σ_yz, σ_xz, σ_xy]`:
/// `√(½[(σ_xx−σ_yy)² + (σ_yy−σ_zz)² + (σ_zz−σ_xx)²] + 3(σ_yz² + σ_xz² + σ_xy²))`.
///
/// ```
/// use vibrofem::post::stress::von_mises;
/// assert_eq!(von_mises(&[100.0, 0.0, 0.0, 0.0, 0.0, 0.0]), 100.0);
/// assert!((von_mises(&[0.0, 0.0, 0.0, 0.0, 0.0, 1.0]) - 3f64.sqrt()).abs() < 1e-15);
/// ```
pub fn von_mises(s: &[f64; 6]) -> f64 {
    let (a, b, c) = (s[0] - s[1], s[1] - s[2], s[2] - s[0]);
    (0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5])).sqrt()
}

/// Principal stresses of a Voigt stress, in descending order `σ1 ≥ σ2 ≥ σ3`.
///
/// Cyclic Jacobi rotations on the symmetric 3 × 3 tensor (scaled by its largest entry): robust
/// for repeated and nearly repeated roots (no trigonometric closed form, whose `acos` loses
/// accuracy there), accurate to a few ulps of the largest entry.
///
/// ```
/// use vibrofem::post::stress::principal;
/// let p = principal(&[0.0, 0.0, 0.0, 0.0, 0.0, 5.0]); // pure shear τ_xy = 5
/// assert!((p[0] - 5.0).abs() < 1e-14 && p[1].abs() < 1e-14 && (p[2] + 5.0).abs() < 1e-14);
/// ```
pub fn principal(s: &[f64; 6]) -> [f64; 3] {
    let scale = s.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return if scale == 0.0 { [0.0; 3] } else { [f64::NAN; 3] };
    }
    let k = 1.0 / scale;
    let mut a = [
        [s[0] * k, s[5] * k, s[4] * k],
        [s[5] * k, s[1] * k, s[3] * k],
        [s[4] * k, s[3] * k, s[2] * k],
    ];
    for _sweep in 0..50 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        if off < 1e-40 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let apq = a[p][q];
            if apq == 0.0 {
                continue;
            }
            // Rotation zeroing a[p][q] (Numerical Recipes' `jacobi`): θ = (a_qq − a_pp)/(2 a_pq),
            // t = tan φ the smaller root of t² + 2θt − 1 = 0.
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let t = if theta.abs() > 1e150 {
                0.5 / theta
            } else {
                theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
            };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let sn = t * c;
            a[p][p] -= t * apq;
            a[q][q] += t * apq;
            a[p][q] = 0.0;
            a[q][p] = 0.0;
            let r = 3 - p - q; // the third index
            let (arp, arq) = (a[r][p], a[r][q]);
            a[r][p] = c * arp - sn * arq;
            a[p][r] = a[r][p];
            a[r][q] = sn * arp + c * arq;
            a[q][r] = a[r][q];
        }
    }
    let mut d = [a[0][0] * scale, a[1][1] * scale, a[2][2] * scale];
    d.sort_by(|x, y| y.total_cmp(x));
    d
}

/// Tresca equivalent stress `σ1 − σ3` (twice the maximum shear stress) of a Voigt stress.
///
/// ```
/// use vibrofem::post::stress::tresca;
/// assert!((tresca(&[0.0, 0.0, 0.0, 0.0, 0.0, 5.0]) - 10.0).abs() < 1e-13);
/// ```
pub fn tresca(s: &[f64; 6]) -> f64 {
    let p = principal(s);
    p[0] - p[2]
}

/// Checks `u` against the node count.
fn check_displacements(n_nodes: usize, u: &[f64]) -> Result<()> {
    // Stays Error::InvalidInput: tests/unit/stress.rs matches on the variant.
    if u.len() != 3 * n_nodes {
        return Err(Error::InvalidInput(format!(
            "stress recovery: the displacement vector has {} values, expected 3 per node = {} for {} nodes",
            u.len(),
            3 * n_nodes,
            n_nodes
        )));
    }
    if let Some(i) = u.iter().position(|v| !v.is_finite()) {
        return Err(Error::param(
            "u",
            format!(
                "stress recovery: non-finite displacement {} at node index {} (component {})",
                u[i],
                i / 3,
                i % 3
            ),
        ));
    }
    Ok(())
}

/// Gathers the displacements of element `e` of `set`.
fn gather_u(set: &impl ElementSet, e: usize, n_nodes: usize, u: &[f64], ue: &mut [f64]) -> Result<()> {
    let nodes = set.nodes(e);
    for (a, &g) in nodes.iter().enumerate() {
        let g = g as usize;
        if g >= n_nodes {
            return Err(Error::param(
                "n_nodes",
                format!(
                    "stress recovery: element {} uses node index {g}, but only {n_nodes} nodes were given",
                    set.tag(e).unwrap_or(e as u64)
                ),
            ));
        }
        ue[3 * a..3 * a + 3].copy_from_slice(&u[3 * g..3 * g + 3]);
    }
    Ok(())
}

/// Gathers the coordinates and displacements of element `e` of `set`.
fn gather(set: &SolidSet, e: usize, n_nodes: usize, u: &[f64], x: &mut [[f64; 3]], ue: &mut [f64]) -> Result<()> {
    gather_u(set, e, n_nodes, u, ue)?;
    set.coords(e, x);
    Ok(())
}

/// The sampling points and extrapolation matrix of [`Recovery::Extrapolated`] for `kind`:
/// `(points, E)` with `E` row-major `n_nodes × n_points`, so that the stress at node `a` is
/// `Σ_q E[a][q] σ(ξ_q)`.
/// [`Error::param`] for a kind that is not a solid.
fn extrapolation(kind: CellKind) -> Result<(Vec<[f64; 3]>, Vec<f64>)> {
    let nodes = shape::reference_nodes(kind);
    let nn = nodes.len();
    let linear = match kind {
        CellKind::Tet4 => {
            // One point: the constant stress of the element.
            let pts = quadrature::for_cell(kind, 1).points;
            return Ok((pts, vec![1.0; nn]));
        }
        CellKind::Tet10 => CellKind::Tet4,
        CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => CellKind::Hex8,
        CellKind::Wedge6 | CellKind::Wedge15 => CellKind::Wedge6,
        CellKind::Point1
        | CellKind::Line2
        | CellKind::Line3
        | CellKind::Tri3
        | CellKind::Tri6
        | CellKind::Quad4
        | CellKind::Quad8
        | CellKind::Quad9 => {
            return Err(Error::param(
                "kind",
                format!("stress extrapolation: {kind} is not a solid cell kind"),
            ));
        }
    };
    let nl = linear.n_nodes();
    let pts = quadrature::for_cell(linear, 2).points;
    assert_eq!(pts.len(), nl, "extrapolation rule of {kind}");
    // A[q][b] = N_b(ξ_q) of the linear element; the fit's nodal values are A⁻¹ σ_q.
    let mut a = nalgebra::DMatrix::<f64>::zeros(nl, nl);
    let mut n = [0.0; MAX_NODES];
    for (q, &p) in pts.iter().enumerate() {
        shape::values(linear, p, &mut n[..nl]);
        for b in 0..nl {
            a[(q, b)] = n[b];
        }
    }
    let inv = a.try_inverse().expect("extrapolation points are unisolvent");
    let mut e = vec![0.0; nn * nl];
    for (i, &xi) in nodes.iter().enumerate() {
        shape::values(linear, xi, &mut n[..nl]);
        for q in 0..nl {
            e[i * nl + q] = (0..nl).map(|b| n[b] * inv[(b, q)]).sum();
        }
    }
    Ok((pts, e))
}

/// Nodal stresses by direct evaluation at the nodes, averaged over the elements sharing each
/// node ([`Recovery::Direct`]; see the module docs).
///
/// - `solids`: element sets (e.g. [`crate::model::Model::solids`], or all of
///   [`crate::model::Model::element_sets`]); sets without a continuum stress
///   ([`ElementSet::has_stress`]) are skipped;
/// - `n_nodes`: number of mesh nodes;
/// - `u`: displacements, node-major, 3 per node (m).
///
/// # Errors
/// [`Error::InvalidInput`] if `u` does not have `3 n_nodes` values, [`Error::param`] if one
/// is not finite or an element uses a node index `≥ n_nodes`; [`Error::InvertedElement`] if the
/// Jacobian determinant is not positive at a node of an element.
pub fn nodal_stress<S: ElementSet>(solids: &[S], n_nodes: usize, u: &[f64]) -> Result<NodalStress> {
    nodal_stress_with(solids, n_nodes, u, Recovery::Direct)
}

/// Nodal stresses with the chosen per-element [`Recovery`], averaged over the elements sharing
/// each node. Errors as [`nodal_stress`].
pub fn nodal_stress_with<S: ElementSet>(
    solids: &[S],
    n_nodes: usize,
    u: &[f64],
    recovery: Recovery,
) -> Result<NodalStress> {
    check_displacements(n_nodes, u)?;
    let mut sums = Sums::new(n_nodes);
    let mut ue = [0.0; 3 * MAX_NODES];
    let mut node_stress = [[0.0; 6]; MAX_NODES];
    let mut point_stress = [[0.0; 6]; MAX_NODES];
    // Extrapolation tables per kind, built on first use.
    let mut tables: Vec<(CellKind, (Vec<[f64; 3]>, Vec<f64>))> = Vec::new();
    for set in solids {
        if !set.has_stress() {
            continue;
        }
        for e in 0..set.len() {
            let Some(kind) = set.cell_kind(e) else {
                continue;
            };
            let nn = kind.n_nodes();
            let xi_nodes = shape::reference_nodes(kind);
            gather_u(set, e, n_nodes, u, &mut ue[..3 * nn])?;
            let eval = |xi: [f64; 3]| set.stress_at(e, &ue[..3 * nn], xi);
            let mut extrapolate = recovery == Recovery::Extrapolated;
            if !extrapolate {
                for (a, &xi) in xi_nodes.iter().enumerate() {
                    match eval(xi) {
                        Ok(st) => node_stress[a] = st,
                        // A Jacobian that vanishes at a node but not at the integration points
                        // (a quarter-point tet10 at its crack tip): the element is valid, the
                        // same test as assembly's; recover its nodal stresses from the points.
                        Err(Error::InvertedElement { .. }) => {
                            extrapolate = true;
                            break;
                        }
                        Err(err) => return Err(err),
                    }
                }
            }
            if extrapolate {
                let i = match tables.iter().position(|(k, _)| *k == kind) {
                    Some(i) => i,
                    None => {
                        tables.push((kind, extrapolation(kind)?));
                        tables.len() - 1
                    }
                };
                let (pts, ex) = &tables[i].1;
                let np = pts.len();
                for (q, &p) in pts.iter().enumerate() {
                    point_stress[q] = eval(p)?;
                }
                for a in 0..nn {
                    let mut st = [0.0; 6];
                    for q in 0..np {
                        let w = ex[a * np + q];
                        for c in 0..6 {
                            st[c] += w * point_stress[q][c];
                        }
                    }
                    node_stress[a] = st;
                }
            }
            for (a, &g) in set.nodes(e).iter().enumerate() {
                sums.add(g as usize, &node_stress[a], set.tag(e).unwrap_or(e as u64));
            }
        }
    }
    Ok(sums.averaged(recovery))
}

/// Per-node sums of the element stresses at the node, before averaging.
struct Sums {
    sum: Vec<[f64; 6]>,
    count: Vec<u32>,
    vm_max: Vec<f64>,
    max_element: Vec<u64>,
}

impl Sums {
    fn new(n_nodes: usize) -> Sums {
        Sums {
            sum: vec![[0.0; 6]; n_nodes],
            count: vec![0; n_nodes],
            vm_max: vec![0.0; n_nodes],
            max_element: vec![0; n_nodes],
        }
    }

    /// Adds element `tag`'s stress `s` at node `g`.
    fn add(&mut self, g: usize, s: &[f64; 6], tag: u64) {
        for c in 0..6 {
            self.sum[g][c] += s[c];
        }
        self.count[g] += 1;
        let vm = von_mises(s);
        if self.count[g] == 1 || vm > self.vm_max[g] {
            self.vm_max[g] = vm;
            self.max_element[g] = tag;
        }
    }

    /// The simple average at every node, with its equivalent stresses.
    fn averaged(self, recovery: Recovery) -> NodalStress {
        let stress: Vec<[f64; 6]> = self
            .sum
            .iter()
            .zip(&self.count)
            .map(|(s, &c)| {
                if c == 0 {
                    [0.0; 6]
                } else {
                    let k = 1.0 / c as f64;
                    s.map(|v| v * k)
                }
            })
            .collect();
        let von_mises_avg = stress.iter().map(von_mises).collect();
        let principal_avg: Vec<[f64; 3]> = stress.iter().map(principal).collect();
        let tresca_avg = principal_avg.iter().map(|p| p[0] - p[2]).collect();
        NodalStress {
            recovery,
            stress,
            von_mises: von_mises_avg,
            principal: principal_avg,
            tresca: tresca_avg,
            von_mises_max_unaveraged: self.vm_max,
            max_element: self.max_element,
            count: self.count,
        }
    }
}

/// The largest stress of one kind in one beam set ([`beam_stress`]).
#[derive(Clone, Debug, Serialize)]
pub struct BeamMax {
    /// The beam set's group; `"(all)"` for the largest over every set.
    pub group: String,
    /// The stress (Pa).
    pub value: f64,
    /// gmsh tag of the element where it occurs.
    pub element: u64,
    /// File tag of the element's end node where it occurs.
    pub node: u64,
    /// Coordinates of that node (m).
    pub coords: [f64; 3],
    /// The element's resultants at that end, local axes: `[N, Q_y, Q_z, T, M_y, M_z]` (N, N·m).
    pub resultants: [f64; 6],
}

/// Beam stresses of a static solution ([`beam_stress`]).
#[derive(Clone, Debug)]
pub struct BeamStress {
    /// Per node, the largest extreme-fibre normal stress of the beam elements ending there
    /// (Pa; zero at nodes of no beam with recovered stresses).
    pub normal: Vec<f64>,
    /// Per node, the largest torsion shear stress `T r / J` of the round-section beams ending
    /// there (Pa; zero elsewhere).
    pub torsion: Vec<f64>,
    /// The largest normal stress per beam set, after the largest over all sets (`"(all)"`).
    pub normal_max: Vec<BeamMax>,
    /// The same for the torsion shear of round sections.
    pub torsion_max: Vec<BeamMax>,
    /// Sets whose stresses are not recovered, with the reason.
    pub notes: Vec<String>,
}

/// The torque `t` of the resultants `r`, or 0 when it is rounding beside their moments
/// (1e-14 N·m of a beam bent in a plane).
fn significant(t: f64, r: &[f64; 6]) -> f64 {
    let m = r[3].abs().max(r[4].abs()).max(r[5].abs());
    if t.abs() <= 1e-9 * m { 0.0 } else { t }
}

/// The largest of `(value, candidate)` pairs of one beam set, kept as a [`BeamMax`].
fn keep_max(best: &mut Option<BeamMax>, value: f64, candidate: impl FnOnce() -> BeamMax) {
    if best.as_ref().is_none_or(|b| value > b.value) {
        *best = Some(BeamMax { value, ..candidate() });
    }
}

/// `maxima` with the largest of them first again, as group `"(all)"`.
fn with_overall(mut maxima: Vec<BeamMax>) -> Vec<BeamMax> {
    if let Some(top) = maxima.iter().max_by(|a, b| a.value.total_cmp(&b.value)) {
        let all = BeamMax {
            group: "(all)".into(),
            ..top.clone()
        };
        maxima.insert(0, all);
    }
    maxima
}

/// Stresses of the beam elements of `beams` at both ends of every element, from their
/// resultants there ([`crate::element::geometric::beam_end_resultants`]) for displacements and rotations `u`
/// ([`crate::dof::NCOMP`] per node): the normal stress at the section's extreme fibres
/// ([`crate::section::BeamSection::extreme_normal_stress`]: the axial force and both bending
/// moments, the flexure formula) and, for round sections, the torsion shear `τ = T r / J`
/// ([`crate::section::BeamSection::torsion_shear`]; the transverse shear is left out). Sections
/// given by their properties (no fibres) are left out with a note. `mesh` names the nodes.
/// `None` without beams.
///
/// # Errors
/// [`Error::InvalidInput`] if `u` is shorter than the nodes; an element's error from its
/// stiffness (a zero length).
pub fn beam_stress(beams: &[crate::model::BeamSet], mesh: &Mesh, u: &[f64]) -> Result<Option<BeamStress>> {
    use crate::dof::NCOMP;
    use crate::section::Fibres;
    if beams.iter().all(|b| b.len() == 0) {
        return Ok(None);
    }
    let n_nodes = mesh.n_nodes();
    let mut out = BeamStress {
        normal: vec![0.0; n_nodes],
        torsion: vec![0.0; n_nodes],
        normal_max: Vec::new(),
        torsion_max: Vec::new(),
        notes: Vec::new(),
    };
    for set in beams {
        if set.section.fibres == Fibres::Unknown {
            out.notes.push(format!(
                "beam '{}': stresses not recovered (a section given by its properties has no extreme fibres; name its shape)",
                set.group
            ));
            continue;
        }
        if set.section.warping {
            out.notes.push(format!(
                "beam '{}': the normal stress of its warping (bimoment) is not included in its stresses",
                set.group
            ));
        }
        let nd = set.dofs_per_node();
        let (mut normal, mut torsion) = (None, None);
        // The largest torque of a section without a torsion stress, against its moments.
        let (mut torque, mut moment) = (0.0f64, 0.0f64);
        for e in 0..set.len() {
            let nodes = set.nodes(e);
            let mut ue = [0.0; 21];
            for (l, &a) in nodes.iter().enumerate() {
                let a = a as usize;
                if NCOMP * (a + 1) > u.len() || a >= n_nodes {
                    return Err(Error::InvalidInput(format!(
                        "beam stresses: element {} uses node index {a} beyond the {} displacements",
                        set.tags[e],
                        u.len() / NCOMP
                    )));
                }
                ue[nd * l..nd * l + nd].copy_from_slice(&u[NCOMP * a..NCOMP * a + nd]);
            }
            let x: Vec<[f64; 3]> = nodes.iter().map(|&a| set.nodes[a as usize]).collect();
            let (kind, orient) = (set.kinds[e], set.orient[e]);
            let res = crate::element::geometric::beam_end_resultants(
                kind,
                &x,
                orient,
                &set.section,
                &set.material,
                &ue[..nd * nodes.len()],
            )
            .map_err(|err| {
                Error::element(
                    set.tags[e],
                    format!("beam '{}', element {}: {err}", set.group, set.tags[e]),
                )
            })?;
            for r in &res {
                torque = torque.max(r[3].abs());
                moment = moment.max(r[3].abs()).max(r[4].abs()).max(r[5].abs());
            }
            // A three-node element's midside node: the mean of its ends' resultants (the
            // resultants are linear between the ends of an element loaded at its ends).
            if let Some(&m) = nodes.get(2) {
                let r: [f64; 6] = std::array::from_fn(|i| 0.5 * (res[0][i] + res[1][i]));
                let m = m as usize;
                if let Some(sigma) = set.section.extreme_normal_stress(&r) {
                    out.normal[m] = out.normal[m].max(sigma);
                }
                if let Some(tau) = set.section.torsion_shear(significant(r[3], &r)) {
                    out.torsion[m] = out.torsion[m].max(tau);
                }
            }
            for (end, r) in res.iter().enumerate() {
                let a = nodes[end] as usize;
                let at = || BeamMax {
                    group: set.group.clone(),
                    value: 0.0,
                    element: set.tags[e],
                    node: mesh.node_tags.get(a).copied().unwrap_or(a as u64 + 1),
                    coords: x[end],
                    resultants: *r,
                };
                if let Some(sigma) = set.section.extreme_normal_stress(r) {
                    out.normal[a] = out.normal[a].max(sigma);
                    keep_max(&mut normal, sigma, at);
                }
                if let Some(tau) = set.section.torsion_shear(significant(r[3], r)) {
                    out.torsion[a] = out.torsion[a].max(tau);
                    keep_max(&mut torsion, tau, at);
                }
            }
        }
        out.normal_max.extend(normal);
        // A round section without torque has no torsion stress to report.
        out.torsion_max.extend(torsion.filter(|t| t.value > 0.0));
        if set.section.torsion_shear(1.0).is_none() && significant(torque, &[0.0, 0.0, 0.0, moment, 0.0, 0.0]) > 0.0 {
            out.notes.push(format!(
                "beam '{}': torsion shear is recovered for round sections only (torque up to {} N·m here)",
                set.group,
                crate::io::fmt_sig(torque, 4)
            ));
        }
    }
    out.normal_max = with_overall(out.normal_max);
    out.torsion_max = with_overall(out.torsion_max);
    Ok(Some(out))
}

/// Stresses on the two faces of the shell elements, averaged at the nodes
/// ([`shell_face_stress`]).
#[derive(Clone, Debug)]
pub struct ShellFaces {
    /// On the face on the side of [`ShellFaces::normal`] (`z = +t/2`).
    pub top: NodalStress,
    /// On the opposite face (`z = −t/2`).
    pub bottom: NodalStress,
    /// Unit normal per node (3 per node; zero at nodes of no shell element): the normal of the
    /// connected surface through the node, the way most of its cells point (the first such
    /// surface at a node where several meet, in the order of the model's shell sets).
    pub normal: Vec<f64>,
}

/// Nodal stresses on the top and bottom faces of the shell elements of `shells` (global axes,
/// Pa), for displacements and rotations `u` ([`crate::dof::NCOMP`] components per node; only
/// the first `n_nodes` nodes are read): each element's stresses evaluated at its nodes (the
/// element's own through-thickness model, [`crate::element::shell::stress_at`]), then averaged
/// over the shell elements sharing a node as [`nodal_stress`] does for solids. Each connected
/// surface has one top side, the side most of its cells' normals point to (the walk of
/// [`crate::model::orient`], which reorients the cells of surfaces with an offset; without an
/// offset a mesh's cells may point either way): a cell meshed the other way round contributes
/// its faces swapped and its normal reversed, as does one whose normal points away from the
/// node's [`ShellFaces::normal`] where surfaces meet. `None` when there are no shell elements.
///
/// # Errors
/// [`Error::InvalidInput`] if `u` is shorter than `n_nodes` nodes, [`Error::param`] for a
/// value that is not finite, [`Error::InvertedElement`] for a degenerate element.
pub fn shell_face_stress(shells: &[crate::model::ShellSet], n_nodes: usize, u: &[f64]) -> Result<Option<ShellFaces>> {
    use crate::dof::NCOMP;
    use crate::element::shell;
    if shells.iter().all(|s| s.len() == 0) {
        return Ok(None);
    }
    if u.len() < NCOMP * n_nodes {
        return Err(Error::InvalidInput(format!(
            "shell stresses: {} values for {n_nodes} nodes of {NCOMP} components",
            u.len()
        )));
    }
    if let Some(i) = u[..NCOMP * n_nodes].iter().position(|v| !v.is_finite()) {
        return Err(Error::param(
            "u",
            format!("value {} at node index {} is not finite", u[i], i / NCOMP),
        ));
    }
    let (mut top, mut bottom) = (Sums::new(n_nodes), Sums::new(n_nodes));
    let mut normal = vec![0.0; 3 * n_nodes];
    let orientation = crate::model::orient::orientation(shells);
    let mut sign = orientation.sign.iter();
    for set in shells {
        for e in 0..set.len() {
            let agrees = sign.next().is_none_or(|&s| s > 0);
            let (kind, nodes, tag) = (set.kinds[e], set.nodes(e), set.tags[e]);
            let bad = |det: f64| Error::InvertedElement {
                element: tag,
                kind: kind.name(),
                det,
                file: None,
            };
            let x: Vec<[f64; 3]> = nodes.iter().map(|&a| set.nodes[a as usize]).collect();
            let mut ue = [0.0; 6 * 4];
            for (l, &a) in nodes.iter().enumerate() {
                let a = a as usize;
                if a >= n_nodes {
                    return Err(Error::param(
                        "shells",
                        format!("element {tag} uses node index {a} of {n_nodes}"),
                    ));
                }
                ue[6 * l..6 * l + 6].copy_from_slice(&u[NCOMP * a..NCOMP * a + 6]);
            }
            let ue = &ue[..6 * nodes.len()];
            let n_e = shell::local_frame(kind, &x).map_err(bad)?[2].map(|v| if agrees { v } else { -v });
            let at = |xi: [f64; 3]| shell::stress_at(kind, &x, &set.section, &set.material, ue, xi);
            let corners = shape::reference_nodes(kind);
            // A corner whose Jacobian vanishes (a straight angle where a quad meets two
            // neighbours, valid at the integration points): the element's stress at its
            // centre for every node, as analysis accepted it.
            let stresses: Vec<shell::ShellStress> = match corners.iter().map(|&xi| at(xi)).collect() {
                Ok(s) => s,
                Err(_) => {
                    let centre = if nodes.len() == 3 {
                        [1.0 / 3.0, 1.0 / 3.0, 0.0]
                    } else {
                        [0.0; 3]
                    };
                    vec![at(centre).map_err(bad)?; nodes.len()]
                }
            };
            for (&a, s) in nodes.iter().zip(stresses) {
                let g = a as usize;
                let nref = &mut normal[3 * g..3 * g + 3];
                if nref.iter().all(|&v| v == 0.0) {
                    nref.copy_from_slice(&n_e);
                }
                let flipped = ((0..3).map(|i| nref[i] * n_e[i]).sum::<f64>() < 0.0) == agrees;
                let (t, b) = if flipped { (s.bottom, s.top) } else { (s.top, s.bottom) };
                top.add(g, &t, tag);
                bottom.add(g, &b, tag);
            }
        }
    }
    Ok(Some(ShellFaces {
        top: top.averaged(Recovery::Direct),
        bottom: bottom.averaged(Recovery::Direct),
        normal,
    }))
}

/// Stresses at the integration points of the stiffness rule of every element (see the module
/// docs), with the points' physical coordinates.
///
/// # Errors
/// As [`nodal_stress`].
pub fn gauss_point_stress(solids: &[SolidSet], n_nodes: usize, u: &[f64]) -> Result<GaussPointStress> {
    check_displacements(n_nodes, u)?;
    let mut out = GaussPointStress {
        points: Vec::new(),
        stress: Vec::new(),
        von_mises: Vec::new(),
        element: Vec::new(),
    };
    let mut x = [[0.0; 3]; MAX_NODES];
    let mut ue = [0.0; 3 * MAX_NODES];
    let mut n = [0.0; MAX_NODES];
    for set in solids {
        let kind = set.kind;
        let nn = kind.n_nodes();
        let rule = quadrature::for_cell(kind, solid::stiffness_degree(kind));
        let total = set.len() * rule.len();
        out.points.reserve(total);
        out.stress.reserve(total);
        out.von_mises.reserve(total);
        out.element.reserve(total);
        for e in 0..set.len() {
            gather(set, e, n_nodes, u, &mut x[..nn], &mut ue[..3 * nn])?;
            for &p in &rule.points {
                let s = set.stress_at(e, &ue[..3 * nn], p)?;
                shape::values(kind, p, &mut n[..nn]);
                let mut xp = [0.0; 3];
                for a in 0..nn {
                    for d in 0..3 {
                        xp[d] += n[a] * x[a][d];
                    }
                }
                out.points.push(xp);
                out.stress.push(s);
                out.von_mises.push(von_mises(&s));
                out.element.push(set.tags[e]);
            }
        }
    }
    Ok(out)
}

impl GaussPointStress {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True if there are no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The extreme of `field` over all points, with the element and point (group
    /// `"(gauss points)"`); `None` if there are no points.
    ///
    /// # Errors
    /// [`Error::param`] for `StressField::Component(i)` with `i ≥ 6`.
    pub fn peak(&self, field: StressField) -> Result<Option<GroupMax>> {
        field.check()?;
        let mut best: Option<(usize, f64)> = None;
        for (i, s) in self.stress.iter().enumerate() {
            let v = field.of_tensor(s);
            if best.is_none_or(|(_, b)| field.beats(v, b)) {
                best = Some((i, v));
            }
        }
        Ok(best.map(|(i, v)| GroupMax {
            group: "(gauss points)".into(),
            field,
            value: v,
            node: None,
            element: Some(self.element[i]),
            coords: self.points[i],
        }))
    }
}

impl NodalStress {
    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.stress.len()
    }

    /// True if there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.stress.is_empty()
    }

    /// The value of `field` at node `a` (dense index).
    ///
    /// # Panics
    /// If `a` is out of range or `field` is `Component(i)` with `i ≥ 6`.
    pub fn value(&self, field: StressField, a: usize) -> f64 {
        match field {
            StressField::VonMises => self.von_mises[a],
            StressField::VonMisesMaxUnaveraged => self.von_mises_max_unaveraged[a],
            StressField::Tresca => self.tresca[a],
            StressField::MaxShear => 0.5 * self.tresca[a],
            StressField::MaxPrincipal => self.principal[a][0],
            StressField::MinPrincipal => self.principal[a][2],
            StressField::Component(i) => self.stress[a][i],
        }
    }
}

/// The extreme of `field` over the nodes of each physical group of `mesh` (any dimension), and
/// over all nodes. The first entry is the whole model (group `"(all)"`), then the groups in the
/// mesh's order. Nodes without a solid element (`count == 0`) are skipped, and so is a group
/// with no such node. Ties go to the lowest node index.
///
/// "Extreme" is the maximum, except for [`StressField::MinPrincipal`] (minimum) and
/// [`StressField::Component`] (largest magnitude, signed).
///
/// # Errors
/// [`Error::param`] if `ns` was computed for another node count than `mesh` has, or
/// for `Component(i)` with `i ≥ 6`.
pub fn group_maxima(mesh: &Mesh, ns: &NodalStress, field: StressField) -> Result<Vec<GroupMax>> {
    field.check()?;
    if ns.len() != mesh.n_nodes() {
        return Err(Error::param(
            "ns",
            format!(
                "stress maxima: {} nodal stresses for a mesh of {} nodes",
                ns.len(),
                mesh.n_nodes()
            ),
        ));
    }
    let entry = |group: &str, nodes: &mut dyn Iterator<Item = usize>| -> Option<GroupMax> {
        let mut best: Option<(usize, f64)> = None;
        for a in nodes {
            if ns.count[a] == 0 {
                continue;
            }
            let v = ns.value(field, a);
            if best.is_none_or(|(_, b)| field.beats(v, b)) {
                best = Some((a, v));
            }
        }
        best.map(|(a, v)| GroupMax {
            group: group.to_string(),
            field,
            value: v,
            node: Some(mesh.node_tags.get(a).copied().unwrap_or(a as u64 + 1)),
            element: (field == StressField::VonMisesMaxUnaveraged).then(|| ns.max_element[a]),
            coords: mesh.nodes[a],
        })
    };
    let mut out = Vec::with_capacity(mesh.groups.len() + 1);
    out.extend(entry("(all)", &mut (0..mesh.n_nodes())));
    for g in &mesh.groups {
        let nodes = mesh.group_nodes(g);
        out.extend(entry(&g.name, &mut nodes.iter().map(|&a| a as usize)));
    }
    Ok(out)
}

/// Per-node arrays of a [`NodalStress`], laid out for the writers.
///
/// Names (in the VTU each prefixed with the `prefix` given to [`StressFields::new`], e.g.
/// `"case1_"`):
///
/// | name | VTU components | gmsh view components |
/// |---|---|---|
/// | `stress` | 6, in VTK's symmetric-tensor order `XX, YY, ZZ, XY, YZ, XZ` | 9, the full tensor row by row |
/// | `von_mises` | 1 | 1 |
/// | `von_mises_max_unaveraged` | 1 | 1 |
/// | `principal_1`, `principal_2`, `principal_3` (descending) | 1 each | 1 each |
/// | `tresca` | 1 | 1 |
///
/// Principal stresses are written as three scalars, not as a 3-vector that viewers would draw
/// as arrows. Nodes without a solid element carry zeros (a model with no solids gets no
/// stress fields). In gmsh the prefix is left out: the load cases are a view's time steps.
#[derive(Clone, Debug)]
pub struct StressFields {
    prefix: String,
    /// 6 per node, VTK symmetric-tensor order `XX, YY, ZZ, XY, YZ, XZ`.
    pub stress_vtk: Vec<f64>,
    /// 9 per node, the full symmetric tensor row-major (`xx, xy, xz, yx, yy, yz, zx, zy, zz`).
    pub stress_tensor9: Vec<f64>,
    /// von Mises of the averaged tensor.
    pub von_mises: Vec<f64>,
    /// Unaveraged maximum von Mises.
    pub von_mises_max_unaveraged: Vec<f64>,
    /// Principal stresses `σ1`, `σ2`, `σ3`, one array each.
    pub principal: [Vec<f64>; 3],
    /// Tresca `σ1 − σ3`.
    pub tresca: Vec<f64>,
}

impl StressFields {
    /// Flattens `ns`; every field name gets `prefix` in front (may be empty).
    pub fn new(ns: &NodalStress, prefix: &str) -> StressFields {
        let n = ns.len();
        let mut stress_vtk = Vec::with_capacity(6 * n);
        let mut stress_tensor9 = Vec::with_capacity(9 * n);
        for s in &ns.stress {
            let [xx, yy, zz, yz, xz, xy] = *s;
            stress_vtk.extend_from_slice(&[xx, yy, zz, xy, yz, xz]);
            stress_tensor9.extend_from_slice(&[xx, xy, xz, xy, yy, yz, xz, yz, zz]);
        }
        StressFields {
            prefix: prefix.to_string(),
            stress_vtk,
            stress_tensor9,
            von_mises: ns.von_mises.clone(),
            von_mises_max_unaveraged: ns.von_mises_max_unaveraged.clone(),
            principal: [0, 1, 2].map(|i| ns.principal.iter().map(|p| p[i]).collect()),
            tresca: ns.tresca.clone(),
        }
    }

    /// The scalar arrays with their names (without prefix).
    fn scalars(&self) -> [(&'static str, &[f64]); 6] {
        [
            ("von_mises", &self.von_mises),
            ("von_mises_max_unaveraged", &self.von_mises_max_unaveraged),
            ("principal_1", &self.principal[0]),
            ("principal_2", &self.principal[1]),
            ("principal_3", &self.principal[2]),
            ("tresca", &self.tresca),
        ]
    }

    /// Point-data arrays for [`crate::io::vtk::write_vtu`] (see the table above).
    pub fn point_fields(&self) -> Vec<PointField<'_>> {
        let mut v = vec![PointField::new(format!("{}stress", self.prefix), 6, &self.stress_vtk)];
        for (name, data) in self.scalars() {
            v.push(PointField::new(format!("{}{name}", self.prefix), 1, data));
        }
        v
    }

    /// Nodal views for [`crate::io::msh_out::write_msh_views`] (see the table above), all at
    /// the given `step` and `time`, named without the prefix: the load cases of a run are the
    /// time steps of one view per field in gmsh, as the displacement's are (a prefixed name
    /// per case made a view whose steps before its case were empty).
    pub fn node_views(&self, step: usize, time: f64) -> Vec<NodeView<'_>> {
        self.node_views_named("", step, time)
    }

    /// [`StressFields::node_views`] with `name` in front of every view's name (the shells'
    /// `shell_top_` and `shell_bottom_` beside the solids' unprefixed views).
    pub fn node_views_named(&self, name: &str, step: usize, time: f64) -> Vec<NodeView<'_>> {
        let mut v = vec![NodeView {
            name: format!("{name}stress"),
            step,
            time,
            n_comp: 9,
            data: &self.stress_tensor9,
        }];
        for (field, data) in self.scalars() {
            v.push(NodeView {
                name: format!("{name}{field}"),
                step,
                time,
                n_comp: 1,
                data,
            });
        }
        v
    }
}
