//! Global assembly of K and M on one sparsity pattern.
//!
//! The pattern is built once from the node graph (two nodes are adjacent when they share an
//! element) and the DOF map. Element matrices are computed in parallel (rayon) in chunks,
//! and scattered into the global values serially in element order, so the sums never
//! depend on thread scheduling: results are bit-identical for any thread count. The element
//! matrices of a chunk go to one buffer reused for every chunk: nothing is allocated per
//! element.

use crate::Result;
use crate::dof::DofMap;
use crate::linalg::sparse::{Pattern, SymMatrix};
use rayon::prelude::*;
use std::sync::Arc;

pub use crate::element::ElementSet;
pub use crate::linalg::graph::NodeGraph;

/// How element sets make a [`NodeGraph`]: two nodes are adjacent when they share an element
/// (the graph itself, and what the ordering reads of it, is [`crate::linalg::graph`]).
impl NodeGraph {
    /// Build the graph of nodes sharing an element, over all element sets. Through
    /// constraints, an element also couples the nodes its nodes depend on (`dofs.deps`, e.g.
    /// the reference node of a rigid coupling).
    pub fn build(n_nodes: usize, sets: &[&dyn ElementSet], dofs: Option<&DofMap>) -> NodeGraph {
        let mut keys = Vec::with_capacity(Self::key_count(n_nodes, sets, dofs));
        Self::fill_keys(&mut keys, n_nodes, sets, dofs);
        let adj_len = NodeGraph::sort_keys(&mut keys);
        let mut adj = Vec::with_capacity(adj_len);
        NodeGraph::from_keys(&keys, n_nodes, &mut adj)
    }

    /// As [`NodeGraph::build`], but an allocation failure is an error naming the memory the
    /// graph needed (8 bytes per node pair of each element, before duplicates are removed)
    /// instead of an abort.
    pub fn try_build(n_nodes: usize, sets: &[&dyn ElementSet], dofs: Option<&DofMap>) -> Result<NodeGraph> {
        let count = Self::key_count(n_nodes, sets, dofs);
        let mut keys: Vec<u64> = Vec::new();
        keys.try_reserve_exact(count)
            .map_err(|_| crate::Error::out_of_memory("the node graph", 8 * count as u64))?;
        Self::fill_keys(&mut keys, n_nodes, sets, dofs);
        let adj_len = NodeGraph::sort_keys(&mut keys);
        let mut adj = Vec::new();
        adj.try_reserve_exact(adj_len)
            .map_err(|_| crate::Error::out_of_memory("the node graph", 4 * adj_len as u64))?;
        Ok(NodeGraph::from_keys(&keys, n_nodes, &mut adj))
    }

    /// Node-pair keys [`NodeGraph::build`] sorts (with repeats): its working memory, 8 bytes each.
    pub fn key_count(n_nodes: usize, sets: &[&dyn ElementSet], dofs: Option<&DofMap>) -> usize {
        let mut count = n_nodes;
        for s in sets {
            for e in 0..s.len() {
                let mut k = s.nodes(e).len();
                if let Some(d) = dofs {
                    k += s.nodes(e).iter().map(|&a| d.deps[a as usize].len()).sum::<usize>();
                }
                count += k * k;
            }
        }
        if let Some(d) = dofs {
            count += d
                .deps
                .iter()
                .map(|deps| 2 * deps.len() + deps.len() * deps.len())
                .sum::<usize>();
        }
        count
    }

    /// One packed (a, b) key per ordered node pair of each element, every node with itself,
    /// and a constrained node with what it depends on.
    fn fill_keys(keys: &mut Vec<u64>, n_nodes: usize, sets: &[&dyn ElementSet], dofs: Option<&DofMap>) {
        let mut nodes: Vec<u32> = Vec::new();
        for s in sets {
            for e in 0..s.len() {
                nodes.clear();
                nodes.extend_from_slice(s.nodes(e));
                if let Some(d) = dofs {
                    for &a in s.nodes(e) {
                        nodes.extend_from_slice(&d.deps[a as usize]);
                    }
                }
                for &a in &nodes {
                    keys.extend(nodes.iter().map(|&b| ((a as u64) << 32) | b as u64));
                }
            }
        }
        keys.extend((0..n_nodes as u64).map(|a| (a << 32) | a));
        if let Some(d) = dofs {
            for (a, deps) in d.deps.iter().enumerate() {
                for &b in deps {
                    keys.push(((a as u64) << 32) | b as u64);
                    keys.push(((b as u64) << 32) | a as u64);
                    for &c in deps {
                        keys.push(((b as u64) << 32) | c as u64);
                    }
                }
            }
        }
    }
}

/// Entries of the DOF pattern [`dof_pattern`] builds (both triangles), without building it.
pub fn pattern_nnz(graph: &NodeGraph, dofs: &DofMap) -> usize {
    (0..dofs.n_nodes())
        .into_par_iter()
        .map(|b| {
            let ncol = dofs.first[b + 1] - dofs.first[b];
            ncol * graph
                .neighbours(b)
                .iter()
                .map(|&a| dofs.first[a as usize + 1] - dofs.first[a as usize])
                .sum::<usize>()
        })
        .sum()
}

/// Build the full (both triangles) DOF pattern from the node graph and DOF map. An allocation
/// failure is an error ([`crate::Error::out_of_memory`]), not an abort.
pub fn dof_pattern(graph: &NodeGraph, dofs: &DofMap) -> Result<Pattern> {
    let n_nodes = dofs.n_nodes();
    // Column counts first, then fill: each column of node b lists the free DOFs of all
    // neighbours a in node order, which is equation order.
    let counts: Vec<usize> = (0..n_nodes)
        .into_par_iter()
        .map(|b| {
            graph
                .neighbours(b)
                .iter()
                .map(|&a| dofs.first[a as usize + 1] - dofs.first[a as usize])
                .sum()
        })
        .collect();
    let n = dofs.n_free;
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0usize);
    for b in 0..n_nodes {
        for _ in dofs.first[b]..dofs.first[b + 1] {
            let last = *col_ptr.last().unwrap_or(&0);
            col_ptr.push(last + counts[b]);
        }
    }
    let nnz = *col_ptr.last().unwrap_or(&0);
    if u32::try_from(n).is_err() {
        return Err(crate::Error::InvalidInput(format!(
            "{n} equations: more than the 2³² − 1 that the sparse structure indexes"
        )));
    }
    let mut row_idx: Vec<u32> = Vec::new();
    row_idx
        .try_reserve_exact(nnz)
        .map_err(|_| crate::Error::out_of_memory("the sparsity pattern", 4 * nnz as u64))?;
    row_idx.resize(nnz, 0);
    // Fill per node in parallel: the columns of node b are a contiguous slice of row_idx.
    let mut slices: Vec<&mut [u32]> = Vec::with_capacity(n_nodes);
    let mut rest = row_idx.as_mut_slice();
    for b in 0..n_nodes {
        let len = counts[b] * (dofs.first[b + 1] - dofs.first[b]);
        let (head, tail) = rest.split_at_mut(len);
        slices.push(head);
        rest = tail;
    }
    slices.into_par_iter().enumerate().for_each(|(b, out)| {
        let ncol = dofs.first[b + 1] - dofs.first[b];
        if ncol == 0 {
            return;
        }
        let len = counts[b];
        for c in 0..ncol {
            let mut k = c * len;
            for &a in graph.neighbours(b) {
                for e in dofs.first[a as usize]..dofs.first[a as usize + 1] {
                    // Below n, checked above.
                    out[k] = e as u32;
                    k += 1;
                }
            }
        }
    });
    Ok(Pattern { n, col_ptr, row_idx })
}

/// Assembled stiffness and mass on one shared pattern.
pub struct Assembled {
    /// Stiffness.
    pub k: SymMatrix,
    /// Mass (no values if not requested).
    pub m: SymMatrix,
}

/// Assemble K (and M) of all element sets on `pattern`.
///
/// The columns are split into one range per worker; each range computes the matrices of the
/// elements reaching it and adds their entries in its columns, in a fixed element order (see
/// the body). Fixed DOFs are skipped (eliminated).
pub fn assemble(pattern: Arc<Pattern>, dofs: &DofMap, sets: &[&dyn ElementSet], want_mass: bool) -> Result<Assembled> {
    let mut k = SymMatrix::try_zeros(pattern.clone(), "the stiffness matrix")?;
    // Without mass, M keeps the pattern but no values (nothing is scattered into it).
    let mut m = if want_mass {
        SymMatrix::try_zeros(pattern.clone(), "the mass matrix")?
    } else {
        SymMatrix {
            pattern: pattern.clone(),
            values: Vec::new(),
        }
    };
    // Column ranges of about equal numbers of entries, one per worker thread.
    let ranges = rayon::current_num_threads().clamp(1, 64).min(pattern.n.max(1));
    let bounds: Vec<usize> = (0..=ranges)
        .map(|r| {
            if r == ranges {
                pattern.n
            } else {
                let target = pattern.nnz() * r / ranges;
                pattern.col_ptr.partition_point(|&p| p < target).min(pattern.n)
            }
        })
        .collect();
    // Elements in the order of their lowest node: consecutive elements then share columns of
    // K and M, which stay in cache while they are added to.
    let orders: Vec<Vec<u32>> = sets
        .iter()
        .map(|set| {
            let mut order: Vec<u32> = (0..set.len() as u32).collect();
            order.sort_by_key(|&e| set.nodes(e as usize).iter().copied().min().unwrap_or(0));
            order
        })
        .collect();
    // Each column range (one per worker) computes the matrices of the elements that reach
    // its columns and adds their entries in those columns, in the order above. Every entry's
    // sum is so formed in the same element order whatever the number of ranges: bit for bit
    // the serial result. Elements across a range boundary are computed by each range they
    // reach (a small share), nothing is allocated per element, no element matrix is stored.
    let kparts = split_by_columns(&mut k.values, &pattern, &bounds);
    let mparts = if want_mass {
        split_by_columns(&mut m.values, &pattern, &bounds)
    } else {
        (0..ranges).map(|_| &mut [][..]).collect()
    };
    kparts
        .into_par_iter()
        .zip(mparts)
        .enumerate()
        .try_for_each(|(r, (kv, mv))| -> Result<()> {
            let cols = bounds[r]..bounds[r + 1];
            let (mut ke, mut me) = (Vec::<f64>::new(), Vec::<f64>::new());
            // Magnitudes of the terms added through constraints, by position in `kv`.
            let mut added = Cancellation::default();
            for (set, order) in sets.iter().zip(&orders) {
                let ndpn = set.dofs_per_node();
                for &e in order {
                    let e = e as usize;
                    let nodes = set.nodes(e);
                    let special = nodes.iter().any(|&a| dofs.special[a as usize]);
                    // A constrained node's entries go to its masters' columns, anywhere.
                    let reaches = special
                        || nodes.iter().any(|&a| {
                            let a = a as usize;
                            dofs.first[a] < cols.end && dofs.first[a + 1] > cols.start
                        });
                    if !reaches {
                        continue;
                    }
                    let nd = ndpn * nodes.len();
                    ke.clear();
                    ke.resize(nd * nd, 0.0);
                    me.clear();
                    me.resize(if want_mass { nd * nd } else { 0 }, 0.0);
                    set.matrices(e, &mut ke, &mut me, want_mass)?;
                    if special {
                        scatter_general(&pattern, dofs, nodes, ndpn, &ke, cols.clone(), kv, Some(&mut added));
                        if want_mass {
                            scatter_general(&pattern, dofs, nodes, ndpn, &me, cols.clone(), mv, None);
                        }
                    } else if want_mass {
                        scatter(
                            &pattern,
                            dofs,
                            nodes,
                            ndpn,
                            [&ke, &me],
                            cols.clone(),
                            [&mut *kv, &mut *mv],
                        );
                    } else {
                        scatter(&pattern, dofs, nodes, ndpn, [&ke], cols.clone(), [&mut *kv]);
                    }
                }
            }
            added.clean(kv);
            Ok(())
        })?;
    // M keeps only its nonzeros, on a pattern of its own within K's (a third of the values of a
    // solid's; see [`SymMatrix::without_zeros`]).
    let m = if want_mass { m.without_zeros() } else { m };
    Ok(Assembled { k, m })
}

/// The values of each column range `bounds[r]..bounds[r + 1]`, as disjoint slices.
fn split_by_columns<'a>(values: &'a mut [f64], pattern: &Pattern, bounds: &[usize]) -> Vec<&'a mut [f64]> {
    let mut out = Vec::with_capacity(bounds.len().saturating_sub(1));
    let mut rest = values;
    for w in bounds.windows(2) {
        let len = pattern.col_ptr[w[1]] - pattern.col_ptr[w[0]];
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(len);
        out.push(head);
        rest = tail;
    }
    out
}

/// Relative size below which a stiffness entry formed through constraints is cancellation
/// noise: its terms' magnitudes summed, times this, exceed what is left of it. The terms of a
/// rigid motion's stiffness cancel exactly in exact arithmetic (a whole free body coupled to one
/// reference node has K̂ = TᵀKT = 0); in floating point they leave ~1e-16 of the terms per
/// addition, which without this would be a spurious stiffness of random sign (eigenvalues of
/// ±1e-6 rad²/s² that no scale tells from real ones). An entry really that small relative to
/// its terms carries no more than their rounding.
const CANCELLED: f64 = 1e-12;

/// Σ|terms| of the slave–slave terms [`scatter_general`] added (by position within a column
/// range's values), for [`Cancellation::clean`].
#[derive(Default)]
struct Cancellation(std::collections::HashMap<usize, f64, std::hash::BuildHasherDefault<PositionHasher>>);

/// A multiplicative hash of a position (SipHash, the default, doubled the assembly time of a
/// coupled model).
#[derive(Default)]
struct PositionHasher(u64);

impl std::hash::Hasher for PositionHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }
    fn write_usize(&mut self, n: usize) {
        self.0 = (n as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

impl Cancellation {
    /// Entries whose value is cancellation noise ([`CANCELLED`]) set to zero.
    fn clean(&self, vals: &mut [f64]) {
        for (&p, &a) in &self.0 {
            if vals[p].abs() <= CANCELLED * a {
                vals[p] = 0.0;
            }
        }
    }
}

/// Add one element matrix through the constraint transformation: K̂ += Tₑᵀ Kₑ Tₑ, where row i
/// of Tₑ expands local DOF i into equations (slaves into their masters).
/// Only the columns in `cols` are written; `vals` holds their values (from the first of them);
/// `added`, when given, the magnitudes of the terms added.
#[allow(clippy::too_many_arguments)]
fn scatter_general(
    pattern: &Pattern,
    dofs: &DofMap,
    nodes: &[u32],
    ndpn: usize,
    me: &[f64],
    cols: std::ops::Range<usize>,
    vals: &mut [f64],
    mut added: Option<&mut Cancellation>,
) {
    let off = pattern.col_ptr[cols.start];
    let nd = ndpn * nodes.len();
    let exps = dofs.local_expansions(nodes, ndpn);
    // Only a slave–slave term can cancel (a rigid motion's energy, summed into the masters'
    // entries): their magnitudes are kept, the other terms' are not needed.
    let slave: Vec<bool> = match added {
        Some(_) => (0..nd)
            .map(|i| dofs.slave[nodes[i / ndpn] as usize] & (1 << (i % ndpn)) != 0)
            .collect(),
        None => Vec::new(),
    };
    for j in 0..nd {
        for &(ej, cj) in &exps[j].terms {
            if !cols.contains(&ej) {
                continue;
            }
            for i in 0..nd {
                let v = me[i * nd + j];
                if v == 0.0 {
                    continue;
                }
                let track = !slave.is_empty() && slave[i] && slave[j];
                for &(ei, ci) in &exps[i].terms {
                    if let Some(pos) = pattern.position(ei, ej) {
                        let t = ci * cj * v;
                        vals[pos - off] += t;
                        if let Some(a) = added.as_deref_mut().filter(|_| track) {
                            *a.0.entry(pos - off).or_insert(0.0) += t.abs();
                        }
                    } else {
                        debug_assert!(false, "pattern misses ({ei}, {ej})");
                    }
                }
            }
        }
    }
}

/// Most nodes an element may have for [`scatter`]'s stack tables (larger elements take
/// [`scatter_general`]).
const SCATTER_MAX_NODES: usize = 32;

/// Add `T` element matrices of one element (K, or K and M) into their global values.
///
/// Every column of a node b lists the same rows (the free DOFs of b's neighbours, in
/// equation order; [`dof_pattern`]), and a node's equations are consecutive in component
/// order. So one binary search per node pair (a, b) places node a's rows in all of b's
/// columns, for every matrix at once, and the free components of each node are looked up once
/// per element. Only the columns in `cols` are written; `vals[t]` holds matrix t's values in
/// them (from the first of them).
fn scatter<const T: usize>(
    pattern: &Pattern,
    dofs: &DofMap,
    nodes: &[u32],
    ndpn: usize,
    mats: [&[f64]; T],
    cols: std::ops::Range<usize>,
    vals: [&mut [f64]; T],
) {
    if nodes.len() > SCATTER_MAX_NODES {
        for (me, v) in mats.into_iter().zip(vals) {
            scatter_general(pattern, dofs, nodes, ndpn, me, cols.clone(), v, None);
        }
        return;
    }
    let off = pattern.col_ptr[cols.start];
    let nd = ndpn * nodes.len();
    // Per element node: its free components below `ndpn` as (offset among the node's
    // equations, component).
    let mut free = [[(0u8, 0u8); crate::dof::NCOMP]; SCATTER_MAX_NODES];
    let mut nfree = [0u8; SCATTER_MAX_NODES];
    for (l, &a) in nodes.iter().enumerate() {
        let a = a as usize;
        let (mut k, mut r) = (0usize, 0u8);
        for c in 0..crate::dof::NCOMP {
            if dofs.eq_of(a, c).is_some() {
                if c < ndpn {
                    free[l][k] = (r, c as u8);
                    k += 1;
                }
                r += 1;
            }
        }
        nfree[l] = k as u8;
    }
    for (lb, &b) in nodes.iter().enumerate() {
        let b = b as usize;
        let (fb, eb) = (dofs.first[b], dofs.first[b + 1]);
        if fb == eb || eb <= cols.start || fb >= cols.end {
            continue;
        }
        let s = pattern.col_ptr[fb];
        let len = pattern.col_ptr[fb + 1] - s;
        let rows = &pattern.row_idx[s..s + len];
        for (la, &a) in nodes.iter().enumerate() {
            let f0 = dofs.first[a as usize];
            if nfree[la] == 0 {
                continue;
            }
            let Ok(k0) = rows.binary_search(&(f0 as u32)) else {
                continue;
            };
            for &(jb, cb) in &free[lb][..nfree[lb] as usize] {
                let col = fb + jb as usize;
                if !cols.contains(&col) {
                    continue;
                }
                let base = s + jb as usize * len + k0;
                let mcol = lb * ndpn + cb as usize;
                for &(ra, ca) in &free[la][..nfree[la] as usize] {
                    let pos = base + ra as usize;
                    debug_assert_eq!(pattern.row_idx[pos] as usize, f0 + ra as usize);
                    let idx = (la * ndpn + ca as usize) * nd + mcol;
                    for t in 0..T {
                        vals[t][pos - off] += mats[t][idx];
                    }
                }
            }
        }
    }
}
