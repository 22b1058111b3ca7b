//! Mass properties per physical group: mass, centre of mass and inertia tensor.
//!
//! The two-mass model of the machine (scene S8) takes its masses from such a report, and a
//! designer checks where the centre of mass of the oscillating parts lies relative to the
//! drive line.
//!
//! # Method
//!
//! Everything comes from the **consistent element mass matrices** (whatever lumping the model
//! uses for its modal analysis: HRZ lumping keeps the mass but not the second moments). For one
//! element with mass matrix `M` and the matrix `R` of its six rigid-body motions about a point
//! `p` (node `a` at `y_a = x_a − p` gets `u = u₀ + θ × y_a`, rotations `θ`, warping `0`),
//!
//! ```text
//!            | m I      −[s]× |     m  = mass,
//! Rᵀ M R  =  |                |     s  = first moment about p (m (c − p)),
//!            | [s]×      J_p  |     J_p = inertia tensor about p.
//! ```
//!
//! With translational mass `M_ab` alone this is `m = Σ M_ab`, `s = Σ M_ab y_b`,
//! `J_p = Σ M_ab ([y_a]×ᵀ [y_b]×)`, i.e. the second moment `Σ M_ab y_a y_bᵀ`: **exact** for
//! isoparametric solids (`x = Σ N_a x_a`, and the mass quadrature is exact on straight-sided
//! cells). The rotational entries of shells and beams add their rotary inertia:
//!
//! - **Shells**: the consistent mass carries `ρ t³/12` per unit area on all three rotations;
//!   the through-thickness inertia of a flat plate is `ρ t³/12 ∫ (I − n nᵀ) dA`, so the
//!   drilling part `ρ t³/12 A n nᵀ` (which has no physical counterpart) is removed element by
//!   element. The result is exact for flat elements, offsets included (the offset's rigid links
//!   carry the mass to the mid-surface). Warped quads use their projected (mean-plane) element,
//!   as the mass matrix does. Where webs and plates of a mid-surface model overlap (junction
//!   strips counted twice), the model's mass is what is reported, not the real part's.
//! - **Beams**: the consistent mass carries `ρ Ip` on the twist and `ρ Iy`, `ρ Iz` on the
//!   bending rotations, which is exactly the section's inertia `ρ diag(Iy + Iz, Iy, Iz)` per
//!   unit length in local axes: straight `Line2` and `Line3` beams are exact; curved `Line3`
//!   beams are integrated like their mass matrix. The warping DOF does not move in a rigid
//!   motion and adds nothing.
//! - **Point masses** (6-DOF, with inertia) and masses spread over a group's nodes enter the
//!   model total and a `"(point masses)"` entry with their own matrices.
//!
//! Per-element moments are shifted to a reference point of each group (an element's
//! reference point is the mean of its nodes) with exact parallel-axis algebra, so summing many
//! elements far from the origin loses no accuracy.

// Index loops over the three axes read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

use crate::Result;
use crate::element::ElementSet;
use crate::mesh::{CellKind, Mesh};
use crate::model::Model;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashMap;

/// Name of the whole-model entry of [`group_mass_properties`].
pub const MODEL_ENTRY: &str = "(model)";

/// Name of the entry of the point masses (discrete masses), when the model has any.
pub const POINT_MASS_ENTRY: &str = "(point masses)";

/// Mass properties of a group of elements.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MassProps {
    /// Physical group name, [`MODEL_ENTRY`] or [`POINT_MASS_ENTRY`].
    pub group: String,
    /// Mass, kg.
    pub mass: f64,
    /// Centre of mass, m (the mean of the group's element reference points when the mass is
    /// zero).
    pub centre: [f64; 3],
    /// Inertia tensor about the centre of mass, kg·m², in global axes:
    /// `[[Ixx, −Pxy, −Pxz], …]` with the products of inertia `P` entering with a minus sign
    /// (`I = ∫ ρ (|r|² 1 − r rᵀ) dV`).
    pub inertia: [[f64; 3]; 3],
}

impl MassProps {
    /// Principal moments of inertia about the centre of mass, ascending, kg·m².
    ///
    /// ```
    /// use vibrofem::post::mass::MassProps;
    /// let p = MassProps { group: "g".into(), mass: 1.0, centre: [0.0; 3],
    ///     inertia: [[2.0, -1.0, 0.0], [-1.0, 2.0, 0.0], [0.0, 0.0, 5.0]] };
    /// let e = p.principal_moments();
    /// assert!((e[0] - 1.0).abs() < 1e-12 && (e[1] - 3.0).abs() < 1e-12 && (e[2] - 5.0).abs() < 1e-12);
    /// ```
    pub fn principal_moments(&self) -> [f64; 3] {
        let m = nalgebra::Matrix3::from_fn(|i, j| self.inertia[i][j]);
        let mut e: Vec<f64> = m.symmetric_eigenvalues().iter().copied().collect();
        e.sort_by(f64::total_cmp);
        [e[0], e[1], e[2]]
    }
}

/// Mass, first moment and second-moment tensor `Σ m y yᵀ` about a reference point.
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    /// Reference point.
    p: [f64; 3],
    m: f64,
    s: [f64; 3],
    ss: [[f64; 3]; 3],
}

impl Moments {
    /// Add `o` (about its own point) to `self` (about `self.p`): exact parallel-axis shift.
    fn add(&mut self, o: &Moments) {
        let d = [o.p[0] - self.p[0], o.p[1] - self.p[1], o.p[2] - self.p[2]];
        self.m += o.m;
        for i in 0..3 {
            self.s[i] += o.s[i] + o.m * d[i];
            for j in 0..3 {
                self.ss[i][j] += o.ss[i][j] + o.s[i] * d[j] + d[i] * o.s[j] + o.m * d[i] * d[j];
            }
        }
    }

    /// The properties about the centre of mass.
    fn finish(&self, group: &str) -> MassProps {
        if self.m <= 0.0 {
            return MassProps {
                group: group.to_string(),
                mass: self.m,
                centre: self.p,
                inertia: [[0.0; 3]; 3],
            };
        }
        let dc = [self.s[0] / self.m, self.s[1] / self.m, self.s[2] / self.m];
        let mut sc = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                sc[i][j] = 0.5 * (self.ss[i][j] + self.ss[j][i]) - self.m * dc[i] * dc[j];
            }
        }
        let tr = sc[0][0] + sc[1][1] + sc[2][2];
        let mut inertia = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                inertia[i][j] = if i == j { tr } else { 0.0 } - sc[i][j];
            }
        }
        MassProps {
            group: group.to_string(),
            mass: self.m,
            centre: [self.p[0] + dc[0], self.p[1] + dc[1], self.p[2] + dc[2]],
            inertia,
        }
    }
}

/// Rigid-body moments of one element mass matrix `me` (`(n·d)²`, node-major, `d` components
/// per node: 3 translations, then 3 rotations if `d ≥ 6`, then components that a rigid motion
/// does not move) with nodes at `x`, about the mean of the nodes. `drill`: a shell's drilling
/// inertia `(ρ t³/12 A, n)` to remove.
fn element_moments(x: &[[f64; 3]], d: usize, me: &[f64], drill: Option<(f64, [f64; 3])>) -> Moments {
    let n = x.len();
    let nd = n * d;
    debug_assert_eq!(me.len(), nd * nd);
    let mut p = [0.0; 3];
    for xa in x {
        for k in 0..3 {
            p[k] += xa[k] / n as f64;
        }
    }
    // R (nd × 6): rigid motions about p.
    let mut r = vec![[0.0f64; 6]; nd];
    for (a, xa) in x.iter().enumerate() {
        let y = [xa[0] - p[0], xa[1] - p[1], xa[2] - p[2]];
        // u = u0 + θ × y = u0 − [y]× θ.
        let yx = [[0.0, -y[2], y[1]], [y[2], 0.0, -y[0]], [-y[1], y[0], 0.0]];
        for c in 0..3 {
            r[a * d + c][c] = 1.0;
            for k in 0..3 {
                r[a * d + c][3 + k] = -yx[c][k];
            }
        }
        if d >= 6 {
            for c in 3..6 {
                r[a * d + c][c] = 1.0;
            }
        }
    }
    let mut mr = vec![[0.0f64; 6]; nd];
    for i in 0..nd {
        let row = &me[i * nd..(i + 1) * nd];
        for (j, &v) in row.iter().enumerate() {
            if v != 0.0 {
                for k in 0..6 {
                    mr[i][k] += v * r[j][k];
                }
            }
        }
    }
    let mut rb = [[0.0f64; 6]; 6];
    for i in 0..nd {
        for k in 0..6 {
            if r[i][k] != 0.0 {
                for l in 0..6 {
                    rb[k][l] += r[i][k] * mr[i][l];
                }
            }
        }
    }
    let m = (rb[0][0] + rb[1][1] + rb[2][2]) / 3.0;
    // Rᵀ M R (translation, rotation) block = −[s]×.
    let s = [
        0.5 * (rb[1][5] - rb[2][4]),
        0.5 * (rb[2][3] - rb[0][5]),
        0.5 * (rb[0][4] - rb[1][3]),
    ];
    let mut j = [[0.0; 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            j[a][b] = 0.5 * (rb[3 + a][3 + b] + rb[3 + b][3 + a]);
        }
    }
    if let Some((c, nv)) = drill {
        for a in 0..3 {
            for b in 0..3 {
                j[a][b] -= c * nv[a] * nv[b];
            }
        }
    }
    // Second-moment tensor from the inertia tensor: S = tr(J)/2 · 1 − J.
    let half_tr = 0.5 * (j[0][0] + j[1][1] + j[2][2]);
    let mut ss = [[0.0; 3]; 3];
    for a in 0..3 {
        for b in 0..3 {
            ss[a][b] = if a == b { half_tr } else { 0.0 } - j[a][b];
        }
    }
    Moments { p, m, s, ss }
}

/// A model element: the index of its set in the list of continuum sets and the element index
/// in the set.
type ElementRef = (usize, usize);

fn coords(model: &Model, nodes: &[u32], buf: &mut [[f64; 3]; 27]) -> usize {
    for (o, &a) in buf.iter_mut().zip(nodes) {
        *o = model.nodes[a as usize];
    }
    nodes.len()
}

/// Rigid-body moments of element `e` of `set`, from its consistent mass matrix less its
/// spurious rotary inertia ([`ElementSet::spurious_inertia`]).
fn moments_of(model: &Model, set: &dyn ElementSet, e: usize) -> Result<Moments> {
    let mut buf = [[0.0; 3]; 27];
    let n = coords(model, set.nodes(e), &mut buf);
    let d = set.dofs_per_node();
    let nd = d * n;
    let mut me = vec![0.0; nd * nd];
    set.consistent_mass(e, &mut me)?;
    let drill = set.spurious_inertia(e)?;
    Ok(element_moments(&buf[..n], d, &me, drill))
}

/// Mass properties of every physical group of `mesh` that contains solid, shell or beam
/// cells of `model` (in the mesh's group order; only the group's cells that are elements of
/// the model count), then [`POINT_MASS_ENTRY`] if the model has point masses, then the whole
/// model, [`MODEL_ENTRY`] (every element once, point masses included).
///
/// `model` must have been built from `mesh` ([`Model::build`]). Computed from consistent
/// element mass matrices; see the module documentation for what is exact.
///
/// ```
/// use vibrofem::{mesh::{generate::box_mesh, CellKind}, model::{Model, ModelSpec}};
/// use vibrofem::post::mass::group_mass_properties;
/// let mesh = box_mesh(CellKind::Hex8, [0.3, 0.2, 0.1], [3, 2, 1]);
/// let model = Model::build(&mesh, &ModelSpec::default(), "box").unwrap();
/// let props = group_mass_properties(&model, &mesh).unwrap();
/// let total = props.iter().find(|p| p.group == "(model)").unwrap();
/// let m = 7850.0 * 0.3 * 0.2 * 0.1;
/// assert!((total.mass / m - 1.0).abs() < 1e-12);
/// assert!((total.inertia[0][0] / (m * (0.2f64.powi(2) + 0.1f64.powi(2)) / 12.0) - 1.0).abs() < 1e-12);
/// ```
pub fn group_mass_properties(model: &Model, mesh: &Mesh) -> Result<Vec<MassProps>> {
    // The continuum sets (solids, shells, beams, in this order), whose elements are mesh cells
    // and belong to groups.
    let sets: Vec<&dyn ElementSet> = (model.solids.iter().map(|s| s as &dyn ElementSet))
        .chain(model.shells.iter().map(|s| s as &dyn ElementSet))
        .chain(model.beams.iter().map(|s| s as &dyn ElementSet))
        .collect();
    // Element moments, set by set (in parallel; stored per element, summed sequentially).
    let continuum: Vec<Vec<Moments>> = sets
        .iter()
        .map(|&s| {
            (0..s.len())
                .into_par_iter()
                .map(|e| moments_of(model, s, e))
                .collect::<Result<Vec<_>>>()
        })
        .collect::<Result<_>>()?;
    let discrete: Vec<Moments> = model
        .discrete
        .iter()
        .flat_map(|d| (0..d.len()).map(move |e| moments_of(model, d, e)))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .filter(|m| m.m != 0.0 || m.ss.iter().flatten().any(|&v| v != 0.0))
        .collect();

    // Mesh cell (kind, tag) → model elements with the same nodes.
    let mut index: HashMap<(CellKind, u64), Vec<ElementRef>> = HashMap::new();
    for (si, s) in sets.iter().enumerate() {
        for e in 0..s.len() {
            if let (Some(kind), Some(tag)) = (s.cell_kind(e), s.tag(e)) {
                index.entry((kind, tag)).or_default().push((si, e));
            }
        }
    }
    let sum = |items: &mut dyn Iterator<Item = &Moments>| -> Option<Moments> {
        let items: Vec<&Moments> = items.collect();
        if items.is_empty() {
            return None;
        }
        let mut p = [0.0; 3];
        for m in &items {
            for k in 0..3 {
                p[k] += m.p[k] / items.len() as f64;
            }
        }
        let mut acc = Moments {
            p,
            ..Default::default()
        };
        for m in items {
            acc.add(m);
        }
        Some(acc)
    };

    let mut out = Vec::new();
    for g in &mesh.groups {
        let mut members: Vec<ElementRef> = Vec::new();
        for c in &g.cells {
            let block = &mesh.blocks[c.block as usize];
            let i = c.index as usize;
            let Some(found) = index.get(&(block.kind, block.tags[i])) else {
                continue;
            };
            let cell = block.cell(i);
            members.extend(found.iter().copied().filter(|&(si, e)| sets[si].nodes(e) == cell));
        }
        if members.is_empty() {
            continue;
        }
        members.sort_unstable();
        members.dedup();
        if let Some(acc) = sum(&mut members.iter().map(|&(si, e)| &continuum[si][e])) {
            out.push(acc.finish(&g.name));
        }
    }
    if let Some(acc) = sum(&mut discrete.iter()) {
        out.push(acc.finish(POINT_MASS_ENTRY));
    }
    let mut all = continuum.iter().flatten().chain(discrete.iter());
    if let Some(acc) = sum(&mut all) {
        out.push(acc.finish(MODEL_ENTRY));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_mass_moments_and_shift() {
        // A 2 kg point mass (3 DOF) at y = (1, 2, 3) from the element's reference point.
        let x = [[1.0, 2.0, 3.0]];
        let me = [2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.0];
        let m = element_moments(&x, 3, &me, None);
        assert_eq!(m.p, [1.0, 2.0, 3.0]);
        assert!(m.m == 2.0 && m.s.iter().all(|v| v.abs() < 1e-15));
        let mut acc = Moments::default();
        acc.add(&m);
        let mut acc2 = acc;
        acc2.add(&Moments {
            p: [-1.0, 2.0, 3.0],
            m: 2.0,
            ..Default::default()
        });
        let p = acc2.finish("two");
        assert!((p.centre[0]).abs() < 1e-15 && (p.centre[1] - 2.0).abs() < 1e-15);
        // Two 2 kg masses at x = ±1: Iyy = Izz = 4, Ixx = 0.
        assert!((p.inertia[1][1] - 4.0).abs() < 1e-14 && (p.inertia[2][2] - 4.0).abs() < 1e-14);
        assert!(p.inertia[0][0].abs() < 1e-14);
    }
}
