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

/// Union–find over the equations `0..n`: the connected parts of a symmetric pattern, plus any
/// further unions (the DOFs of one node).
pub struct Parts {
    parent: Vec<usize>,
}

impl Parts {
    /// The parts of the structurally symmetric pattern `p` (both triangles stored, as a
    /// [`super::sparse::SymMatrix`]'s are: each coupling is taken once, from its entry above the
    /// diagonal; half the work of taking both).
    pub fn of_pattern(p: &super::sparse::Pattern) -> Parts {
        let mut parts = Parts {
            parent: (0..p.n).collect(),
        };
        for j in 0..p.n {
            for &i in &p.row_idx[p.col_ptr[j]..p.col_ptr[j + 1]] {
                if (i as usize) < j {
                    parts.join(i as usize, j);
                }
            }
        }
        parts
    }

    /// The representative of `i`'s part (path halving).
    pub fn find(&mut self, mut i: usize) -> usize {
        let p = &mut self.parent;
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }

    /// Put `a` and `b` in one part (its representative the smaller of the two).
    pub fn join(&mut self, a: usize, b: usize) {
        let (x, y) = (self.find(a), self.find(b));
        if x != y {
            self.parent[x.max(y)] = x.min(y);
        }
    }

    /// Each equation's part, the parts numbered in order of their first equation, and their
    /// number.
    pub fn labels(&mut self) -> (Vec<usize>, usize) {
        let n = self.parent.len();
        let mut label_of_root = vec![usize::MAX; n];
        let mut label = vec![0usize; n];
        let mut count = 0;
        for e in 0..n {
            let r = self.find(e);
            if label_of_root[r] == usize::MAX {
                label_of_root[r] = count;
                count += 1;
            }
            label[e] = label_of_root[r];
        }
        (label, count)
    }
}
