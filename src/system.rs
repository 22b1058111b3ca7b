//! The assembled system: a [`Model`] with its sparsity pattern, K and M, the fill-reducing
//! ordering and the symbolic factorisation, built once and shared by every analysis.
//!
//! ```text
//! Model ──► node graph ──► DOF pattern ──► K, M (one pattern) ──► ordering ──► symbolic LDLᵀ
//! ```
//!
//! Every analysis ([`crate::analysis::modal`], [`crate::analysis::statics`]) takes a `&System`,
//! so a scene with a modal and a static analysis of the same model assembles and orders once.
//! The node graph is dropped once the ordering is computed: it is not needed at the peak.
//!
//! ```
//! use vibrofem::{model::{Model, ModelSpec}, system::{System, SystemOptions}};
//! let mesh = vibrofem::mesh::generate::box_mesh(vibrofem::mesh::CellKind::Hex8, [0.2, 0.1, 0.1], [4, 2, 2]);
//! let model = Model::build(&mesh, &ModelSpec::default(), "box")?;
//! let sys = System::build(model, &SystemOptions::default(), "box")?;
//! assert_eq!(sys.k().n(), 3 * 45); // 5·3·3 nodes, free-free
//! # Ok::<(), vibrofem::Error>(())
//! ```

use crate::assembly::{NodeGraph, assemble, dof_pattern, pattern_nnz};
use crate::dof::{DofMap, NCOMP};
use crate::linalg::coarse::{CoarseModel, Prolongation};
use crate::linalg::factor::SymbolicFactor;
use crate::linalg::ordering::{Ordering, expand_node_order, factor_entries, node_nested_dissection};
use crate::linalg::sparse::{Pattern, SymMatrix};
use crate::model::Model;
use crate::util::fmt::fmt_bytes;
use crate::{Error, Result};
use std::sync::Arc;
use std::time::Instant;

/// The process's memory, at the path where the memory checks ([`check_memory`]) are.
pub use crate::util::memory::{
    MemoryBudget, available_memory, memory_budget, peak_memory, release_free_memory, resident_memory,
};

/// How to build a [`System`].
#[derive(Clone, Debug)]
pub struct SystemOptions {
    /// Fill-reducing ordering of the factorisations.
    pub ordering: Ordering,
    /// Refuse a model whose factorisation would need more than this many bytes; `None`: the
    /// memory the system has available.
    pub max_memory: Option<u64>,
    /// Assemble the mass matrix too (statics alone does not need it).
    pub mass: bool,
    /// Form the Galerkin model on the corner space of a quadratic mesh
    /// ([`System::take_coarse_model`]) once K and M are assembled, while the ordering still
    /// runs (the lowest modes' one-factorisation solve starts from it); needs `mass`.
    pub coarse_model: bool,
}

impl Default for SystemOptions {
    fn default() -> Self {
        SystemOptions {
            ordering: Ordering::Metis,
            max_memory: None,
            mass: true,
            coarse_model: false,
        }
    }
}

/// Wall time of building a system, seconds.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct SystemTimings {
    /// Node graph, pattern and the values of K and M.
    pub assemble: f64,
    /// Fill-reducing ordering and symbolic factorisation (they run alongside the assembly of
    /// K and M, so `assemble + order` can exceed `wall`).
    pub order: f64,
    /// The whole build, wall time.
    pub wall: f64,
}

/// A model with K and M assembled over its free DOFs and the symbolic factorisation ready.
pub struct System {
    model: Arc<Model>,
    source: String,
    pattern: Arc<Pattern>,
    k: SymMatrix,
    m: Option<SymMatrix>,
    /// `None` for a system assembled for another solver ([`System::assemble_only`]).
    symbolic: Option<Arc<SymbolicFactor>>,
    ordering: Ordering,
    /// The corner space of the model, built on first use ([`System::coarse_space`]).
    coarse: std::sync::OnceLock<Option<Prolongation>>,
    /// The Galerkin model on it, when [`SystemOptions::coarse_model`] asked for it and until
    /// taken ([`System::take_coarse_model`]).
    coarse_model: std::sync::Mutex<Option<CoarseModel>>,
    /// K was replaced ([`System::replace_stiffness`]): it may be indefinite.
    k_replaced: bool,
    /// Time spent building.
    pub timings: SystemTimings,
}

impl System {
    /// Assemble `model` and analyse its factorisation. `source` names the model in messages
    /// (the mesh file or generator). Fails when every DOF is constrained, or when the
    /// factorisation would not fit in memory ([`SystemOptions::max_memory`]).
    pub fn build(model: Model, opts: &SystemOptions, source: &str) -> Result<System> {
        Self::build_in(model, opts, source).map_err(|e| e.in_source(source))
    }

    fn build_in(model: Model, opts: &SystemOptions, source: &str) -> Result<System> {
        let t = Instant::now();
        // Size every large buffer before allocating it, so a model too large for the memory is
        // refused with the estimate in seconds rather than killed (or aborted) in assembly.
        let budget = memory_budget(opts.max_memory);
        let sets = model.element_sets();
        let n_nodes = model.dofs.n_nodes();
        let keys = NodeGraph::key_count(n_nodes, &sets, Some(&model.dofs)) as u64;
        check_estimate(source, &budget, 8 * keys, || format!("node graph, {keys} node pairs"))?;
        let graph = NodeGraph::try_build(n_nodes, &sets, Some(&model.dofs))?;
        let nnz = pattern_nnz(&graph, &model.dofs) as u64;
        let mats = if opts.mass { 4 } else { 3 };
        let detail = |factor: u64| {
            move || {
                format!(
                    "factor ≥ {factor} entries, K{} {nnz} entries",
                    if opts.mass { " and M" } else { "" }
                )
            }
        };
        // The factor holds at least the lower triangle of K: a bound before the ordering ...
        let mut factor = (nnz + model.dofs.n_free as u64) / 2;
        check_estimate(source, &budget, 8 * factor + mats * 16 * nnz, detail(factor))?;
        let t_pat = Instant::now();
        let pattern = Arc::new(dof_pattern(&graph, &model.dofs)?);
        let pat_s = t_pat.elapsed().as_secs_f64();
        let t_graph = t.elapsed().as_secs_f64() - pat_s;
        // The coarse model (below) is formed only when the factorisation is unlikely to be
        // refused once the ordering sizes it: when the budget holds 32 times the factor's lower
        // bound (the factor of a 3D quadratic mesh is 10–20 times it: 16 at 119k DOFs). A refusal
        // sends `--solver auto` to the low-memory path, where the coarse model would be time and
        // memory spent for nothing (K and M of the corner mesh, ~1/12 of the model's).
        let coarse_fits = opts.coarse_model
            && opts.mass
            && budget
                .as_ref()
                .is_none_or(|b| 8 * 32 * factor + mats * 16 * nnz <= b.bytes);
        // The fill-reducing ordering and the symbolic factorisation (sequential, from the graph
        // and the pattern) run alongside the assembly of K and M (parallel, from the pattern):
        // neither reads what the other writes. The refined factor estimate is checked once the
        // ordering is known; K and M are within the budget checked above.
        let ((order_result, ordering_time, symbolic_time), (km, km_s)) = rayon::join(
            || {
                let t_nd = Instant::now();
                let node_order = match opts.ordering {
                    Ordering::Metis => match node_nested_dissection(&graph, &model.dofs) {
                        Ok(o) => Some(o),
                        Err(e) => return (Err(e), t_nd.elapsed().as_secs_f64(), 0.0),
                    },
                    Ordering::Amd | Ordering::Natural => None,
                };
                let ordering_time = t_nd.elapsed().as_secs_f64();
                // ... and with a node ordering, its size up to supernode padding, from the
                // elimination tree.
                if let Some(order) = &node_order {
                    // Stop counting once the budget is exceeded: the refusal then says "at least".
                    let cap = budget
                        .as_ref()
                        .map_or(u64::MAX, |b| (b.bytes.saturating_sub(mats * 16 * nnz)) / 8);
                    factor = factor_entries(&graph, &model.dofs, order, cap);
                    if let Err(e) = check_estimate(source, &budget, 8 * factor + mats * 16 * nnz, detail(factor)) {
                        return (Err(e), ordering_time, 0.0);
                    }
                }
                let t_sym = Instant::now();
                let symbolic = match opts.ordering {
                    Ordering::Metis => {
                        let order = node_order.as_deref().unwrap_or(&[]);
                        let (fwd, inv) = expand_node_order(order, &model.dofs);
                        SymbolicFactor::new(&pattern, Some((&fwd, &inv)))
                    }
                    Ordering::Amd => SymbolicFactor::new(&pattern, None),
                    Ordering::Natural => {
                        let id: Vec<usize> = (0..pattern.n).collect();
                        SymbolicFactor::new(&pattern, Some((&id, &id)))
                    }
                };
                (symbolic, ordering_time, t_sym.elapsed().as_secs_f64())
            },
            || {
                let t_km = Instant::now();
                let km = assemble(pattern.clone(), &model.dofs, &sets, opts.mass);
                let km_s = t_km.elapsed().as_secs_f64();
                // The ordering runs longer than the assembly on a quadratic mesh: this thread
                // forms the coarse model meanwhile.
                let coarse = match &km {
                    Ok(km) if coarse_fits => coarse_model(&model, km),
                    _ => None,
                };
                (km.map(|km| (km, coarse)), km_s)
            },
        );
        drop(sets);
        drop(graph);
        let (km, coarse) = km?;
        check_finite(source, &model, &km)?;
        let symbolic = order_result?;
        log::debug!(
            "{source}: graph and estimates {t_graph:.3} s, pattern {pat_s:.3} s; alongside: ordering {ordering_time:.3} s and symbolic analysis {symbolic_time:.3} s, K and M {km_s:.3} s"
        );
        if model.dofs.n_free == 0 {
            return Err(Error::InvalidInput(format!(
                "{source}: every degree of freedom is fixed or constrained; nothing to solve"
            )));
        }
        log::debug!(
            "{source}: factor entries estimated {factor} before assembly, {} from the symbolic analysis",
            symbolic.nnz_l
        );
        check_memory(source, &symbolic, &pattern, opts.max_memory)?;
        release_free_memory();
        let (coarse_space, coarse_model) = match coarse {
            Some((pr, cm)) => (std::sync::OnceLock::from(Some(pr)), Some(cm)),
            None => (std::sync::OnceLock::new(), None),
        };
        Ok(System {
            model: Arc::new(model),
            source: source.to_string(),
            pattern,
            k: km.k,
            m: opts.mass.then_some(km.m),
            symbolic: Some(Arc::new(symbolic)),
            ordering: opts.ordering,
            coarse: coarse_space,
            coarse_model: std::sync::Mutex::new(coarse_model),
            k_replaced: false,
            timings: SystemTimings {
                assemble: t_graph + pat_s + km_s,
                order: ordering_time + symbolic_time,
                wall: t.elapsed().as_secs_f64(),
            },
        })
    }

    /// Assemble K and M of `model` without ordering or analysing a factorisation: for
    /// exporting the matrices or handing them to another solver (SLEPc on a cluster), whose
    /// memory need is not this machine's. [`System::symbolic`] is then an error.
    pub fn assemble_only(model: Model, source: &str) -> Result<System> {
        let t = Instant::now();
        // The graph, K and M must fit here (the factor is another machine's concern).
        let budget = memory_budget(None);
        let sets = model.element_sets();
        let n_nodes = model.dofs.n_nodes();
        let keys = NodeGraph::key_count(n_nodes, &sets, Some(&model.dofs)) as u64;
        check_estimate(source, &budget, 8 * keys, || format!("node graph, {keys} node pairs"))?;
        let graph = NodeGraph::try_build(n_nodes, &sets, Some(&model.dofs))?;
        let nnz = pattern_nnz(&graph, &model.dofs) as u64;
        check_estimate(source, &budget, 2 * 16 * nnz, || format!("K and M, {nnz} entries each"))?;
        let pattern = Arc::new(dof_pattern(&graph, &model.dofs)?);
        drop(graph);
        let km = assemble(pattern.clone(), &model.dofs, &sets, true)?;
        check_finite(source, &model, &km)?;
        drop(sets);
        if model.dofs.n_free == 0 {
            return Err(Error::InvalidInput(format!(
                "{source}: every degree of freedom is fixed or constrained; nothing to solve"
            )));
        }
        Ok(System {
            model: Arc::new(model),
            source: source.to_string(),
            pattern,
            k: km.k,
            m: Some(km.m),
            symbolic: None,
            coarse: Default::default(),
            coarse_model: Default::default(),
            k_replaced: false,
            ordering: Ordering::Natural,
            timings: SystemTimings {
                assemble: t.elapsed().as_secs_f64(),
                order: 0.0,
                wall: t.elapsed().as_secs_f64(),
            },
        })
    }

    /// The model the system was built from.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The model, shared (results that outlive the system keep it for output).
    pub fn model_arc(&self) -> &Arc<Model> {
        &self.model
    }

    /// The DOF numbering (free DOFs ↔ node and component).
    pub fn dofs(&self) -> &DofMap {
        &self.model.dofs
    }

    /// Number of free DOFs (equations).
    pub fn n_free(&self) -> usize {
        self.model.dofs.n_free
    }

    /// What the system was built from (a file or generator), for messages.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Stiffness matrix over the free DOFs (both triangles stored).
    pub fn k(&self) -> &SymMatrix {
        &self.k
    }

    /// Mass matrix over the free DOFs. An error if the system was built without it
    /// ([`SystemOptions::mass`] false).
    pub fn m(&self) -> Result<&SymMatrix> {
        self.m.as_ref().ok_or_else(|| {
            Error::param(
                "SystemOptions::mass",
                format!(
                    "{}: the system was assembled without its mass matrix (statics only)",
                    self.source
                ),
            )
        })
    }

    /// Replace K by `k` on the same pattern (the tangent `K + K_σ` of a prestressed model,
    /// [`crate::analysis::prestress`]); returns the previous K. The ordering and symbolic
    /// factorisation stay valid because the pattern is the same; another pattern is an error.
    pub fn replace_stiffness(&mut self, k: SymMatrix) -> Result<SymMatrix> {
        if !Arc::ptr_eq(&k.pattern, &self.pattern) {
            return Err(Error::InvalidInput(format!(
                "{}: a replacement stiffness must be assembled on the system's own sparsity pattern",
                self.source
            )));
        }
        // A coarse model formed from the previous K is not this K's.
        self.take_coarse_model();
        self.k_replaced = true;
        Ok(std::mem::replace(&mut self.k, k))
    }

    /// Whether K is the one assembled from the model's elements, springs and couplings: positive
    /// semidefinite in exact arithmetic, so that a negative eigenvalue of (K, M) is rounding.
    /// False once it was replaced (a prestressed tangent, a magnet's negative stiffness).
    pub fn k_is_assembled(&self) -> bool {
        !self.k_replaced
    }

    /// True if the mass matrix was assembled.
    pub fn has_mass(&self) -> bool {
        self.m.is_some()
    }

    /// The shared sparsity pattern of K and M.
    pub fn pattern(&self) -> &Arc<Pattern> {
        &self.pattern
    }

    /// The symbolic factorisation (ordering and elimination structure) for K − σM.
    pub fn symbolic(&self) -> Result<&Arc<SymbolicFactor>> {
        self.symbolic.as_ref().ok_or_else(|| {
            Error::param(
                "System",
                format!(
                    "{}: the system was assembled for another solver, without a factorisation analysis",
                    self.source
                ),
            )
        })
    }

    /// The corner space of a quadratic mesh ([`Model::corner_space`]), which the eigen solver
    /// uses to place its shift above the wanted modes; `None` for linear meshes.
    pub fn coarse_space(&self) -> Option<&Prolongation> {
        self.coarse.get_or_init(|| self.model.corner_space()).as_ref()
    }

    /// The Galerkin model on [`System::coarse_space`] formed during the build
    /// ([`SystemOptions::coarse_model`]), handed over once: `None` when it was not asked for,
    /// the mesh is linear, or it was taken already.
    pub fn take_coarse_model(&self) -> Option<CoarseModel> {
        self.coarse_model.lock().ok().and_then(|mut c| c.take())
    }

    /// The ordering used.
    pub fn ordering(&self) -> Ordering {
        self.ordering
    }

    /// Name equation `eq` in the user's terms: the mesh node tag (or the coupled group of a
    /// reference node) and the component, e.g. `node 1234 uz` or `reference node of 'top' rx`.
    pub fn describe_equation(&self, eq: usize) -> String {
        describe_equation(&self.model, eq)
    }
}

/// K and M finite: an entry that overflowed (a Young's modulus of 1e308, coordinates of
/// 1e300 m) is refused with its equation, where it surfaced as a zero pivot or a NaN Jacobian.
fn check_finite(source: &str, model: &Model, km: &crate::assembly::Assembled) -> Result<()> {
    use rayon::prelude::*;
    for (name, mat, what) in [("K", &km.k, "stiffness"), ("M", &km.m, "mass")] {
        // By chunks (a short-circuiting search per entry took 0.15 s for K and M at 119k DOFs,
        // a scan per chunk 0.01 s): the first chunk holding a non-finite entry, then the entry.
        const CHUNK: usize = 1 << 14;
        let first = mat
            .values
            .par_chunks(CHUNK)
            .position_first(|c| !c.iter().fold(true, |ok, v| ok & v.is_finite()))
            .and_then(|c| {
                let c0 = c * CHUNK;
                mat.values[c0..].iter().position(|v| !v.is_finite()).map(|i| c0 + i)
            });
        if let Some(p) = first {
            let col = mat.pattern.col_ptr.partition_point(|&c| c <= p).saturating_sub(1);
            return Err(Error::InvalidInput(format!(
                "{source}: the {what} matrix {name} has a non-finite entry ({}) at {}: the material constants or the \
                 coordinates are beyond double precision (check their units)",
                mat.values[p],
                describe_equation(model, col)
            )));
        }
    }
    Ok(())
}

/// The corner space of `model` and the Galerkin model of the assembled K and M on it; `None`
/// for a linear mesh, or when forming it failed (the eigen solver then forms it itself, and
/// says why if it cannot).
fn coarse_model(model: &Model, km: &crate::assembly::Assembled) -> Option<(Prolongation, CoarseModel)> {
    let t = Instant::now();
    let pr = model.corner_space()?;
    if pr.n_fine != km.k.n() {
        return None;
    }
    let cm = CoarseModel::new(&pr, &km.k, &km.m).ok()?;
    log::debug!(
        "coarse model alongside the ordering: corner space, PᵀKP, PᵀMP and their ordering {:.3} s ({} unknowns)",
        t.elapsed().as_secs_f64(),
        pr.n_coarse
    );
    Some((pr, cm))
}

/// Name equation `eq` of `model` in the user's terms (see [`System::describe_equation`]).
pub fn describe_equation(model: &Model, eq: usize) -> String {
    if eq >= model.dofs.n_free {
        return format!("equation {eq}");
    }
    let (a, c) = model.dofs.node_comp_of(eq);
    let comp = crate::dof::COMPONENT_NAMES.get(c).copied().unwrap_or("?");
    debug_assert!(c < NCOMP);
    if a < model.n_mesh_nodes {
        match model.node_tags.get(a) {
            Some(tag) => format!("node {tag} {comp}"),
            None => format!("node #{a} {comp}"),
        }
    } else if let Some(r) = model.references.iter().find(|r| r.node == a) {
        format!("reference node of '{}' {comp}", r.group)
    } else {
        format!("node #{a} {comp}")
    }
}

/// Refuse before allocating: `bytes` (an estimate, described by `detail`) against the budget.
fn check_estimate(source: &str, budget: &Option<MemoryBudget>, bytes: u64, detail: impl Fn() -> String) -> Result<()> {
    match budget {
        Some(b) if bytes > b.bytes => Err(Error::InvalidInput(format!(
            "{source}: {} {} ({}) but {} {}",
            crate::error::MEMORY_REFUSALS[0],
            fmt_bytes(bytes),
            detail(),
            b.what,
            fmt_bytes(b.bytes)
        ))),
        _ => Ok(()),
    }
}

/// Refuse, before factorising, a model whose factor (estimated from the symbolic analysis) plus
/// the matrices would not fit in `limit` bytes (`--max-memory`) or, without a limit, in the memory
/// the system has available — a clear error with the estimate instead of being killed.
pub fn check_memory(source: &str, sym: &SymbolicFactor, pattern: &Pattern, limit: Option<u64>) -> Result<()> {
    // Factor values and K, M (values and their shared indices); with faer's factorisation also
    // the shifted copy and faer's permuted copy (values + indices).
    let per_entry = if sym.reads_k_and_m() { 32 } else { 64 };
    let need = sym.factor_bytes() as u64 + per_entry * pattern.nnz() as u64;
    let Some(MemoryBudget { bytes: lim, what }) = memory_budget(limit) else {
        return Ok(());
    };
    if need > lim {
        return Err(Error::InvalidInput(format!(
            "{source}: {} {} (factor {}, {} entries) but {what} {}",
            crate::error::MEMORY_REFUSALS[1],
            fmt_bytes(need),
            fmt_bytes(sym.factor_bytes() as u64),
            sym.nnz_l,
            fmt_bytes(lim)
        )));
    }
    Ok(())
}
