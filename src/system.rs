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

use crate::assembly::{NodeGraph, assemble, dof_pattern};
use crate::dof::{DofMap, NCOMP};
use crate::linalg::factor::SymbolicFactor;
use crate::linalg::ordering::{Ordering, nested_dissection};
use crate::linalg::sparse::{Pattern, SymMatrix};
use crate::model::Model;
use crate::{Error, Result};
use std::sync::Arc;
use std::time::Instant;

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
}

impl Default for SystemOptions {
    fn default() -> Self {
        SystemOptions {
            ordering: Ordering::Metis,
            max_memory: None,
            mass: true,
        }
    }
}

/// Wall time of building a system, seconds.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct SystemTimings {
    /// Node graph, pattern and the values of K and M.
    pub assemble: f64,
    /// Fill-reducing ordering and symbolic factorisation.
    pub order: f64,
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
    /// Time spent building.
    pub timings: SystemTimings,
}

impl System {
    /// Assemble `model` and analyse its factorisation. `source` names the model in messages
    /// (the mesh file or generator). Fails when every DOF is constrained, or when the
    /// factorisation would not fit in memory ([`SystemOptions::max_memory`]).
    pub fn build(model: Model, opts: &SystemOptions, source: &str) -> Result<System> {
        let t = Instant::now();
        let sets = model.element_sets();
        let graph = NodeGraph::build(model.dofs.n_nodes(), &sets, Some(&model.dofs));
        let pattern = Arc::new(dof_pattern(&graph, &model.dofs));
        let km = assemble(pattern.clone(), &model.dofs, &sets, opts.mass)?;
        drop(sets);
        let t_assemble = t.elapsed().as_secs_f64();
        if model.dofs.n_free == 0 {
            return Err(Error::InvalidInput(format!(
                "{source}: every degree of freedom is fixed or constrained; nothing to solve"
            )));
        }
        let t = Instant::now();
        let symbolic = match opts.ordering {
            Ordering::Metis => {
                let (fwd, inv) = nested_dissection(&graph, &model.dofs)?;
                SymbolicFactor::new(&pattern, Some((&fwd, &inv)))?
            }
            Ordering::Amd => SymbolicFactor::new(&pattern, None)?,
            Ordering::Natural => {
                let id: Vec<usize> = (0..pattern.n).collect();
                SymbolicFactor::new(&pattern, Some((&id, &id)))?
            }
        };
        drop(graph);
        let t_order = t.elapsed().as_secs_f64();
        check_memory(source, &symbolic, &pattern, opts.max_memory)?;
        Ok(System {
            model: Arc::new(model),
            source: source.to_string(),
            pattern,
            k: km.k,
            m: opts.mass.then_some(km.m),
            symbolic: Some(Arc::new(symbolic)),
            ordering: opts.ordering,
            timings: SystemTimings {
                assemble: t_assemble,
                order: t_order,
            },
        })
    }

    /// Assemble K and M of `model` without ordering or analysing a factorisation: for
    /// exporting the matrices or handing them to another solver (SLEPc on a cluster), whose
    /// memory need is not this machine's. [`System::symbolic`] is then an error.
    pub fn assemble_only(model: Model, source: &str) -> Result<System> {
        let t = Instant::now();
        let sets = model.element_sets();
        let graph = NodeGraph::build(model.dofs.n_nodes(), &sets, Some(&model.dofs));
        let pattern = Arc::new(dof_pattern(&graph, &model.dofs));
        drop(graph);
        let km = assemble(pattern.clone(), &model.dofs, &sets, true)?;
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
            ordering: Ordering::Natural,
            timings: SystemTimings {
                assemble: t.elapsed().as_secs_f64(),
                order: 0.0,
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
            Error::InvalidInput(format!(
                "{}: the system was assembled without its mass matrix (statics only)",
                self.source
            ))
        })
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
            Error::InvalidInput(format!(
                "{}: the system was assembled for another solver, without a factorisation analysis",
                self.source
            ))
        })
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

/// Refuse, before factorising, a model whose factor (estimated from the symbolic analysis) plus
/// the matrices would not fit in `limit` bytes (`--max-memory`) or, without a limit, in the memory
/// the system has available — a clear error with the estimate instead of being killed.
pub fn check_memory(source: &str, sym: &SymbolicFactor, pattern: &Pattern, limit: Option<u64>) -> Result<()> {
    // Factor values, K, M, the shifted copy and faer's permuted copy (values + indices).
    let need = sym.factor_bytes() as u64 + 4 * 16 * pattern.nnz() as u64;
    let (lim, what) = match limit {
        Some(l) => (l, "--max-memory is"),
        None => match available_memory() {
            Some(a) => (a, "the system has available"),
            None => return Ok(()),
        },
    };
    if need > lim {
        return Err(Error::InvalidInput(format!(
            "{source}: the factorisation needs about {} (factor {}, {} entries) but {what} {}",
            crate::io::fmt_bytes(need),
            crate::io::fmt_bytes(sym.factor_bytes() as u64),
            sym.nnz_l,
            crate::io::fmt_bytes(lim)
        )));
    }
    Ok(())
}

/// Peak resident set size of this process (bytes), from /proc/self/status.
pub fn peak_memory() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Memory the operating system can still give this process (Linux MemAvailable), bytes.
pub fn available_memory() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
