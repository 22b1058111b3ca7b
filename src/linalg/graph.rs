//! The node adjacency graph in CSR form: what the fill-reducing ordering ([`super::ordering`])
//! and the DOF pattern of the assembly read. How element sets make one (two nodes are adjacent
//! when they share an element) is [`crate::assembly`]'s `NodeGraph::build`.

use rayon::prelude::*;

/// Node adjacency graph in CSR form (each node is adjacent to itself).
#[derive(Clone, Debug)]
pub struct NodeGraph {
    /// Offsets, length `n_nodes + 1`.
    pub ptr: Vec<usize>,
    /// Adjacent nodes, sorted per node.
    pub adj: Vec<u32>,
}

impl NodeGraph {
    /// Sort and deduplicate node-pair keys (`(a << 32) | b`) in place; the number of distinct keys.
    pub(crate) fn sort_keys(keys: &mut Vec<u64>) -> usize {
        keys.par_sort_unstable();
        keys.dedup();
        keys.len()
    }

    /// The graph of sorted, distinct node-pair keys over `n_nodes` nodes; `adj` (reserved by the
    /// caller, so that an allocation failure is its to report) receives the adjacency.
    pub(crate) fn from_keys(keys: &[u64], n_nodes: usize, adj: &mut Vec<u32>) -> NodeGraph {
        let mut ptr = vec![0usize; n_nodes + 1];
        for &k in keys {
            ptr[(k >> 32) as usize + 1] += 1;
        }
        for a in 0..n_nodes {
            ptr[a + 1] += ptr[a];
        }
        adj.extend(keys.iter().map(|&k| (k & 0xffff_ffff) as u32));
        NodeGraph {
            ptr,
            adj: std::mem::take(adj),
        }
    }

    /// Neighbours of node `a` (including `a`).
    pub fn neighbours(&self, a: usize) -> &[u32] {
        &self.adj[self.ptr[a]..self.ptr[a + 1]]
    }
}
