//! Prestress: the stresses of a static load case, the geometric stiffness `K_σ` they make,
//! and the natural frequencies of the preloaded structure, `(K + K_σ) x = λ M x`.
//!
//! ```text
//! System (K, M, ordering) ──► static solve K u = f ──► stresses at the integration points
//!        ──► K_σ on K's pattern ──► K + K_σ replaces K ──► verified modal solve
//! ```
//!
//! The static solve and the modal solve share the assembly, the ordering and the symbolic
//! factorisation: a prestressed run costs one static factorisation and solve, one evaluation
//! of the stresses and of `K_σ` (an assembly without mass), and the modal run.
//!
//! What carries a geometric stiffness ([`crate::element::geometric`]): solids (the full Cauchy
//! stress), shells (membrane forces on the translations of the mid-surface) and beams (line2:
//! the axial force, bending moments, shear forces and torque of the static state; line3: the
//! axial force). Discrete springs, point masses
//! and rigid couplings carry none: a preloaded spring or a rigid link that rotates under load
//! adds nothing here.
//!
//! The modal verification (residuals, backward errors, Sturm count) is that of every modal run,
//! on `K + K_σ`. A compressive preload beyond the lowest buckling load makes `K + K_σ`
//! indefinite: the lowest eigenvalues become negative, reported as negative frequencies, and a
//! note says the preload exceeds a buckling load.

use crate::analysis::modal::{self, ModalOptions, ModalRun};
use crate::analysis::statics::{self, CaseReport, Load};
use crate::dof::NCOMP;
use crate::element::{ElementSet, geometric, solid};
use crate::linalg::sparse::SymMatrix;
use crate::mesh::{CellKind, Mesh};
use crate::model::{BeamSet, Model, ShellSet, SolidSet};
use crate::system::System;
use crate::{Error, Result};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// One extreme of the preload's stress: the value (Pa) and where.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct StressExtreme {
    /// Stress, Pa (tension positive).
    pub value: f64,
    /// Where: the set (solid kind or shell/beam group) and the element tag.
    pub at: String,
}

/// The stress state of a static case at the integration points of every element that has a
/// geometric stiffness, and its extremes.
pub struct InitialStress {
    /// Per solid set, per cell: the stress at the points of its [`geometric::solid_rule`].
    solids: Vec<Vec<Vec<[f64; 6]>>>,
    /// Per shell set, per cell: membrane forces at [`geometric::shell_points`].
    shells: Vec<Vec<[[f64; 3]; 4]>>,
    /// Per beam set, per cell: stress resultants ([`geometric::beam_resultants`]).
    beams: Vec<Vec<[[f64; 6]; 2]>>,
    /// Largest tensile stress: principal stress of the solids and of the shells' faces, axial
    /// stress `N/A` of the beams.
    pub tension: StressExtreme,
    /// Largest compressive stress (most negative), as [`InitialStress::tension`].
    pub compression: StressExtreme,
}

/// Element displacements of `nodes` (`ndpn` per node) from the full field `u` (NCOMP per node).
fn gather(u: &[f64], nodes: &[u32], ndpn: usize, out: &mut [f64]) {
    for (l, &a) in nodes.iter().enumerate() {
        for c in 0..ndpn {
            out[l * ndpn + c] = u[NCOMP * a as usize + c];
        }
    }
}

fn where_(set: &dyn ElementSet, e: usize) -> String {
    match set.tag(e) {
        Some(t) => format!("{} element {t}", set.group()),
        None => format!("{} #{e}", set.group()),
    }
}

/// Fold a stress into the running extremes.
fn extremes(acc: &mut (StressExtreme, StressExtreme), v: f64, at: impl Fn() -> String) {
    if v > acc.0.value {
        acc.0 = StressExtreme { value: v, at: at() };
    }
    if v < acc.1.value {
        acc.1 = StressExtreme { value: v, at: at() };
    }
}

type Extremes = (StressExtreme, StressExtreme);

fn merge(mut a: Extremes, b: Extremes) -> Extremes {
    if b.0.value > a.0.value {
        a.0 = b.0;
    }
    if b.1.value < a.1.value {
        a.1 = b.1;
    }
    a
}

fn solid_stresses(set: &SolidSet, u: &[f64]) -> Result<(Vec<Vec<[f64; 6]>>, Extremes)> {
    let nn = set.kind.n_nodes();
    let out: Vec<(Vec<[f64; 6]>, Extremes)> = (0..set.len())
        .into_par_iter()
        .map(|e| {
            let mut x = [[0.0; 3]; 27];
            set.coords(e, &mut x[..nn]);
            let rule = geometric::solid_rule(set.kind, solid::integration(set.kind, &x[..nn]))
                .ok_or_else(|| Error::param("kind", format!("{} is not a solid cell kind", set.kind)))?;
            let mut ue = [0.0; 81];
            gather(u, set.nodes(e), 3, &mut ue[..3 * nn]);
            let mut acc = Extremes::default();
            let mut sig = Vec::with_capacity(rule.len());
            for &xi in &rule.points {
                let s = set.stress_at(e, &ue[..3 * nn], xi)?;
                for p in crate::post::stress::principal(&s) {
                    extremes(&mut acc, p, || where_(set, e));
                }
                sig.push(s);
            }
            Ok((sig, acc))
        })
        .collect::<Result<_>>()?;
    Ok(split(out))
}

fn split<T>(v: Vec<(T, Extremes)>) -> (Vec<T>, Extremes) {
    let mut acc = Extremes::default();
    let mut out = Vec::with_capacity(v.len());
    for (t, x) in v {
        acc = merge(acc, x);
        out.push(t);
    }
    (out, acc)
}

fn shell_forces(set: &ShellSet, u: &[f64]) -> Result<(Vec<[[f64; 3]; 4]>, Extremes)> {
    let out: Vec<([[f64; 3]; 4], Extremes)> = (0..set.len())
        .into_par_iter()
        .map(|e| {
            let nodes = set.nodes(e);
            let kind = set.kinds[e];
            let x: Vec<[f64; 3]> = nodes.iter().map(|&a| set.nodes[a as usize]).collect();
            let mut ue = [0.0; 24];
            gather(u, nodes, 6, &mut ue[..6 * nodes.len()]);
            let bad = |det: f64| Error::InvertedElement {
                element: set.tags[e],
                kind: kind.name(),
                det,
                file: None,
            };
            let nf = geometric::shell_membrane_forces(kind, &x, &set.section, &set.material, &ue[..6 * nodes.len()])
                .map_err(bad)?;
            let mut acc = Extremes::default();
            for &(xi, eta, _) in geometric::shell_points(kind) {
                let s = crate::element::shell::stress_at(
                    kind,
                    &x,
                    &set.section,
                    &set.material,
                    &ue[..6 * nodes.len()],
                    [xi, eta, 0.0],
                )
                .map_err(bad)?;
                for face in [s.bottom, s.top] {
                    for p in crate::post::stress::principal(&face) {
                        extremes(&mut acc, p, || where_(set, e));
                    }
                }
            }
            Ok((nf, acc))
        })
        .collect::<Result<_>>()?;
    Ok(split(out))
}

fn beam_forces(set: &BeamSet, u: &[f64]) -> Result<(Vec<[[f64; 6]; 2]>, Extremes)> {
    let ndpn = set.dofs_per_node();
    let out: Vec<([[f64; 6]; 2], Extremes)> = (0..set.len())
        .into_par_iter()
        .map(|e| {
            let nodes = set.nodes(e);
            let x: Vec<[f64; 3]> = nodes.iter().map(|&a| set.nodes[a as usize]).collect();
            let mut ue = [0.0; 21];
            gather(u, nodes, ndpn, &mut ue[..ndpn * nodes.len()]);
            let n = geometric::beam_resultants(
                set.kinds[e],
                &x,
                set.orient[e],
                &set.section,
                &set.material,
                &ue[..ndpn * nodes.len()],
            )
            .map_err(|err| Error::element(set.tags[e], format!("beam '{}': {err}", set.group)))?;
            let mut acc = Extremes::default();
            for f in n {
                extremes(&mut acc, f[0] / set.section.area, || where_(set, e));
            }
            Ok((n, acc))
        })
        .collect::<Result<_>>()?;
    Ok(split(out))
}

impl InitialStress {
    /// The stresses of the displacement field `u` (NCOMP per model node, as a static run's
    /// [`statics::StaticRun::u`]) at the integration points of `model`'s solids, shells and
    /// beams.
    pub fn from_displacements(model: &Model, u: &[f64]) -> Result<InitialStress> {
        if u.len() != NCOMP * model.dofs.n_nodes() {
            return Err(Error::param(
                "u",
                format!(
                    "{} displacement values for {} nodes: {NCOMP} per node expected",
                    u.len(),
                    model.dofs.n_nodes()
                ),
            ));
        }
        let mut acc = Extremes::default();
        let mut solids = Vec::new();
        for s in &model.solids {
            let (v, x) = solid_stresses(s, u)?;
            acc = merge(acc, x);
            solids.push(v);
        }
        let mut shells = Vec::new();
        for s in &model.shells {
            let (v, x) = shell_forces(s, u)?;
            acc = merge(acc, x);
            shells.push(v);
        }
        let mut beams = Vec::new();
        for s in &model.beams {
            let (v, x) = beam_forces(s, u)?;
            acc = merge(acc, x);
            beams.push(v);
        }
        Ok(InitialStress {
            solids,
            shells,
            beams,
            tension: acc.0,
            compression: acc.1,
        })
    }

    /// The geometric stiffness `K_σ` of this stress state, assembled over `sys`'s free DOFs on
    /// its own pattern (that of K), so that `K + K_σ` keeps the ordering and symbolic
    /// factorisation. `sys` must be the system of the model the stresses were computed on.
    pub fn geometric_stiffness(&self, sys: &System) -> Result<SymMatrix> {
        let model = sys.model();
        if self.solids.len() != model.solids.len()
            || self.shells.len() != model.shells.len()
            || self.beams.len() != model.beams.len()
        {
            return Err(Error::param(
                "sys",
                "the stresses were computed on another model than this system's",
            ));
        }
        let mut sets: Vec<Geometric<'_>> = Vec::new();
        for (s, sig) in model.solids.iter().zip(&self.solids) {
            sets.push(Geometric::Solid(s, sig));
        }
        for (s, nf) in model.shells.iter().zip(&self.shells) {
            sets.push(Geometric::Shell(s, nf));
        }
        for (s, n) in model.beams.iter().zip(&self.beams) {
            sets.push(Geometric::Beam(s, n));
        }
        let dyn_sets: Vec<&dyn ElementSet> = sets.iter().map(|s| s as &dyn ElementSet).collect();
        let asm = crate::assembly::assemble(sys.pattern().clone(), &model.dofs, &dyn_sets, false)?;
        Ok(asm.k)
    }
}

/// An element set whose "stiffness" is its geometric stiffness under a stored stress state: it
/// lets [`crate::assembly::assemble`] put `K_σ` on K's pattern with K's constraint handling.
enum Geometric<'a> {
    Solid(&'a SolidSet, &'a [Vec<[f64; 6]>]),
    Shell(&'a ShellSet, &'a [[[f64; 3]; 4]]),
    Beam(&'a BeamSet, &'a [[[f64; 6]; 2]]),
}

impl Geometric<'_> {
    fn inner(&self) -> &dyn ElementSet {
        match self {
            Geometric::Solid(s, _) => *s,
            Geometric::Shell(s, _) => *s,
            Geometric::Beam(s, _) => *s,
        }
    }
}

impl ElementSet for Geometric<'_> {
    fn len(&self) -> usize {
        self.inner().len()
    }
    fn nodes(&self, e: usize) -> &[u32] {
        self.inner().nodes(e)
    }
    fn dofs_per_node(&self) -> usize {
        self.inner().dofs_per_node()
    }
    fn group(&self) -> &str {
        self.inner().group()
    }
    fn tag(&self, e: usize) -> Option<u64> {
        self.inner().tag(e)
    }
    fn cell_kind(&self, e: usize) -> Option<CellKind> {
        self.inner().cell_kind(e)
    }
    /// `ke` gets the geometric stiffness; there is no mass.
    fn matrices(&self, e: usize, ke: &mut [f64], _me: &mut [f64], _want_mass: bool) -> Result<()> {
        match self {
            Geometric::Solid(s, sig) => {
                let nn = s.kind.n_nodes();
                let mut x = [[0.0; 3]; 27];
                s.coords(e, &mut x[..nn]);
                let integ = solid::integration(s.kind, &x[..nn]);
                geometric::solid(s.kind, &x[..nn], integ, &sig[e], ke).map_err(|det| s.inverted(e, det))
            }
            Geometric::Shell(s, nf) => {
                let x: Vec<[f64; 3]> = s.nodes(e).iter().map(|&a| s.nodes[a as usize]).collect();
                let kind = s.kinds[e];
                geometric::shell(kind, &x, &s.section, &nf[e], ke).map_err(|det| Error::InvertedElement {
                    element: s.tags[e],
                    kind: kind.name(),
                    det,
                    file: None,
                })
            }
            Geometric::Beam(s, n) => {
                let x: Vec<[f64; 3]> = s.nodes(e).iter().map(|&a| s.nodes[a as usize]).collect();
                geometric::beam(s.kinds[e], &x, s.orient[e], &s.section, &s.material, &n[e], ke)
                    .map_err(|err| Error::element(s.tags[e], format!("beam '{}': {err}", s.group)))
            }
        }
    }
    fn consistent_mass(&self, _e: usize, me: &mut [f64]) -> Result<()> {
        me.fill(0.0);
        Ok(())
    }
    fn measure(&self, _e: usize) -> Result<f64> {
        Ok(0.0)
    }
    fn density(&self, _e: usize) -> f64 {
        0.0
    }
}

/// A prestressed modal run: the modes of `K + K_σ`, the static case that made the preload and
/// its stress extremes.
pub struct PrestressRun {
    /// The modal run on `K + K_σ` (its report's notes describe the preload).
    pub modal: ModalRun,
    /// The static case's report (reactions, equilibrium, residual).
    pub statics: CaseReport,
    /// Largest tensile stress of the preload.
    pub tension: StressExtreme,
    /// Largest compressive stress of the preload.
    pub compression: StressExtreme,
    /// Seconds spent on the static solve and on the stresses and `K_σ`.
    pub prestress_seconds: f64,
}

/// Natural frequencies of `mesh` preloaded by `loads` (one static case, with the prescribed
/// displacements of `opts.spec`): build the system once, solve the static case, assemble
/// `K_σ` from its stresses and solve `(K + K_σ) x = λ M x` with the verification of every
/// modal run. `read_time` (s) is reported as the read phase.
pub fn run_prestressed_modes(
    mesh: &Mesh,
    source: &str,
    opts: &ModalOptions,
    loads: &[Load],
    read_time: f64,
) -> Result<PrestressRun> {
    let t = Instant::now();
    let model = Model::build(mesh, &opts.spec, source)?;
    let t_model = t.elapsed().as_secs_f64();
    let mut sys = System::build(model, &opts.system_options(), source)?;
    let (pre, case, seconds) = prestress_system(&mut sys, mesh, loads)?;
    let mut modal = modal::solve(&sys, &opts.params())?;
    let tm = &mut modal.report.timings_s;
    tm.read = read_time;
    tm.assemble += t_model;
    tm.total += read_time + t_model + seconds;
    modal.report.notes.push(preload_note(&pre, &case, loads, sys.model()));
    if let Some(first) = modal
        .report
        .modes
        .iter()
        .find(|m| m.eigenvalue < 0.0 && m.kind == "elastic")
    {
        modal.report.notes.push(format!(
            "the preload exceeds a buckling load: K + K_σ has negative eigenvalues (mode {} at {:.4e} rad²/s², \
             reported as a negative frequency); the structure is unstable under this load",
            first.mode, first.eigenvalue
        ));
    }
    Ok(PrestressRun {
        modal,
        statics: case,
        tension: pre.tension,
        compression: pre.compression,
        prestress_seconds: seconds,
    })
}

/// Solve the static case `loads` on `sys`, and replace its K by `K + K_σ` of the resulting
/// stresses: the stresses, the static case's report and the seconds spent.
pub fn prestress_system(sys: &mut System, mesh: &Mesh, loads: &[Load]) -> Result<(InitialStress, CaseReport, f64)> {
    let t = Instant::now();
    let st = statics::solve(sys, mesh, &[loads.to_vec()])?;
    let case = st
        .cases
        .into_iter()
        .next()
        .ok_or_else(|| Error::param("loads", "no static case was solved"))?;
    let pre = InitialStress::from_displacements(sys.model(), &st.u[0])?;
    let kg = pre.geometric_stiffness(sys)?;
    let kt = sys.k().sub_scaled(-1.0, &kg);
    sys.replace_stiffness(kt)?;
    Ok((pre, case, t.elapsed().as_secs_f64()))
}

/// The note a prestressed run reports: the loads, the stress extremes and what carries `K_σ`.
fn preload_note(pre: &InitialStress, case: &CaseReport, loads: &[Load], model: &Model) -> String {
    let mpa = |v: f64| v / 1e6;
    let what = if loads.is_empty() {
        "prescribed displacements".to_string()
    } else {
        format!("{} load(s)", loads.len())
    };
    let mut s = format!(
        "prestressed modes: K + K_σ from a static case ({what}; applied force {:.4e} N, equilibrium error {:.1e}); \
         largest tensile stress {:.3} MPa ({}), largest compressive {:.3} MPa ({})",
        norm3(case.applied.force),
        case.equilibrium_error,
        mpa(pre.tension.value),
        if pre.tension.at.is_empty() {
            "none"
        } else {
            &pre.tension.at
        },
        mpa(pre.compression.value),
        if pre.compression.at.is_empty() {
            "none"
        } else {
            &pre.compression.at
        },
    );
    if !model.beams.is_empty() {
        s.push_str("; beams: axial stress N/A; ");
        s.push_str(&beam_geometric_note(model));
    }
    if !model.discrete.is_empty() || !model.references.is_empty() {
        s.push_str("; springs, point masses and couplings carry no geometric stiffness");
    }
    s
}

/// What the beams' geometric stiffness carries in this model: line2 cells the full resultants
/// of the static state, line3 cells the axial force only (named by group).
pub(crate) fn beam_geometric_note(model: &Model) -> String {
    let line3: Vec<&str> = model
        .beams
        .iter()
        .filter(|b| b.kinds.contains(&crate::mesh::CellKind::Line3))
        .map(|b| b.group.as_str())
        .collect();
    if line3.is_empty() {
        "beam geometric stiffness from the axial force, shear forces, bending moments and torque".to_string()
    } else {
        format!(
            "beam geometric stiffness: line2 cells from the axial force, shears, moments and torque; line3 cells \
             (group(s) {}) from the axial force only (no lateral–torsional or coil buckling there: mesh them with line2)",
            line3.join(", ")
        )
    }
}

fn norm3(v: [f64; 3]) -> f64 {
    // hypot: no under- or overflow of the squares (a force of 1e-200 N read 0).
    v[0].hypot(v[1]).hypot(v[2])
}
