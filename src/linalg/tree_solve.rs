//! Triangular solves with a supernodal LDLᵀ factor, parallel over the elimination tree.
//!
//! Supernodes of disjoint subtrees touch disjoint rows of the solution except their common
//! ancestors' rows. The forward solve (L y = b) runs big subtrees as parallel tasks; a task
//! subtracts its updates of rows outside its subtree into a private buffer (those rows are
//! exactly the off-diagonal pattern of the subtree's root), and the buffers are merged in a
//! fixed order when the tasks join. The backward solve (Lᵀ x = z) reads only ancestor rows,
//! final by then, so its subtrees need nothing private. Which subtrees become tasks depends
//! on the tree alone, never on the thread count: the result is the same bits on any number
//! of threads, and each column's arithmetic is independent of the other columns of the block.

use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;

type Sn = SymbolicSupernodalCholesky<usize>;

/// A split of the supernodal elimination tree (in postorder: every subtree is a contiguous
/// range of supernodes ending at its root) into disjoint subtrees solved as parallel tasks and
/// the "top" supernodes above them, solved in order.
pub(crate) struct SolveTree {
    /// Task subtrees: (first supernode, root).
    tasks: Vec<(usize, usize)>,
    /// Supernodes in no task, ascending.
    top: Vec<usize>,
}

/// Subtrees holding more than this share of the factor's entries are split further.
const TASK_SHARE: u64 = 16;

impl SolveTree {
    /// The split for `sn`, or `None` when its supernodes are not in postorder (then the solve
    /// runs sequentially).
    pub(crate) fn new(sn: &Sn) -> Option<SolveTree> {
        let ns = sn.n_supernodes();
        let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
        let mut snode_of = vec![0usize; sn.nrows()];
        for s in 0..ns {
            for r in begin[s]..end[s] {
                snode_of[r] = s;
            }
        }
        let mut children = vec![Vec::new(); ns];
        let mut roots = Vec::new();
        let mut work = vec![0u64; ns];
        let mut first: Vec<usize> = (0..ns).collect();
        let mut count = vec![1usize; ns];
        for s in 0..ns {
            let pat = sn.supernode(s).pattern();
            let w = (end[s] - begin[s]) as u64;
            work[s] += w * (w + pat.len() as u64);
            match pat.first() {
                Some(&r) => {
                    let p = snode_of[r];
                    if p <= s {
                        return None;
                    }
                    children[p].push(s);
                    work[p] += work[s];
                    first[p] = first[p].min(first[s]);
                    count[p] += count[s];
                }
                None => roots.push(s),
            }
        }
        // Postorder: subtree s is exactly first[s]..=s.
        if (0..ns).any(|s| s + 1 - first[s] != count[s]) {
            return None;
        }
        // A child's pattern beyond its parent's columns lies in the parent's pattern (so a
        // task's updates outside its subtree land in its root's pattern).
        for s in 0..ns {
            let pat = sn.supernode(s).pattern();
            let Some(&r0) = pat.first() else { continue };
            let p = snode_of[r0];
            let ppat = sn.supernode(p).pattern();
            let mut k = 0;
            for &r in pat.iter().filter(|&&r| r >= end[p]) {
                while k < ppat.len() && ppat[k] < r {
                    k += 1;
                }
                if k == ppat.len() || ppat[k] != r {
                    return None;
                }
            }
        }
        let total: u64 = roots.iter().map(|&r| work[r]).sum();
        let limit = (total / TASK_SHARE).max(1);
        // Split the biggest subtree until none is above the limit (the tree alone decides).
        let mut heap: std::collections::BinaryHeap<(u64, std::cmp::Reverse<usize>)> =
            roots.iter().map(|&r| (work[r], std::cmp::Reverse(r))).collect();
        let mut top = Vec::new();
        while let Some(&(w, std::cmp::Reverse(s))) = heap.peek() {
            if w <= limit {
                break;
            }
            heap.pop();
            top.push(s);
            for &c in &children[s] {
                heap.push((work[c], std::cmp::Reverse(c)));
            }
        }
        let mut tasks: Vec<(usize, usize)> = heap
            .into_iter()
            .map(|(_, std::cmp::Reverse(s))| (first[s], s))
            .collect();
        tasks.sort_unstable();
        top.sort_unstable();
        Some(SolveTree { tasks, top })
    }
}

/// The solution block shared by the tasks: each writes only rows it owns (see the module
/// documentation).
#[derive(Clone, Copy)]
struct Shared<const K: usize>(*mut [f64; K]);
// SAFETY: tasks write disjoint rows and read rows that no running task writes.
unsafe impl<const K: usize> Send for Shared<K> {}
unsafe impl<const K: usize> Sync for Shared<K> {}

impl<const K: usize> Shared<K> {
    /// Row `r`. SAFETY (callers): r < n, and no other task writes row r meanwhile.
    #[inline(always)]
    unsafe fn get(self, r: usize) -> [f64; K] {
        unsafe { *self.0.add(r) }
    }
    /// Row `r` to write. SAFETY (callers): r < n, and the calling task owns row r.
    #[inline(always)]
    #[allow(clippy::mut_from_ref)]
    unsafe fn at<'a>(self, r: usize) -> &'a mut [f64; K] {
        unsafe { &mut *self.0.add(r) }
    }
}

/// Solve L D Lᵀ x = b in place for `K` right-hand sides stored row by row (`x[i]` is row i of
/// the block, in the factor's elimination order).
pub(crate) fn solve<const K: usize, const F: bool>(sn: &Sn, values: &[f64], tree: &SolveTree, x: &mut [[f64; K]]) {
    use rayon::prelude::*;
    let xs = Shared(x.as_mut_ptr());
    let end = sn.supernode_end();
    // Forward: the tasks in parallel, each keeping its updates of rows above it apart ...
    let deltas: Vec<(Vec<usize>, Vec<[f64; K]>)> = tree
        .tasks
        .par_iter()
        .map(|&(first, root)| {
            let rows = sn.supernode(root).pattern();
            let mut vals = vec![[0.0; K]; rows.len()];
            let mut buf = Vec::new();
            for s in first..=root {
                // SAFETY: rows below end[root] are this task's subtree; the others go to vals.
                unsafe { forward_supernode::<K, F>(sn, values, xs, s, end[root], rows, &mut vals, &mut buf) };
            }
            (rows.to_vec(), vals)
        })
        .collect();
    // ... merged in task order, then the supernodes above the tasks, in order.
    for (rows, vals) in &deltas {
        for (&r, v) in rows.iter().zip(vals) {
            let xr = &mut x[r];
            for c in 0..K {
                xr[c] -= v[c];
            }
        }
    }
    let xs = Shared(x.as_mut_ptr());
    let mut buf = Vec::new();
    for &s in &tree.top {
        // SAFETY: nothing runs in parallel here.
        unsafe { forward_supernode::<K, F>(sn, values, xs, s, usize::MAX, &[], &mut [], &mut buf) };
    }
    // Diagonal.
    let (begin, cp) = (sn.supernode_begin(), sn.col_ptr_for_val());
    for s in 0..sn.n_supernodes() {
        let (f, l) = (begin[s], end[s]);
        let nr = l - f + sn.supernode(s).pattern().len();
        let ls = &values[cp[s]..cp[s + 1]];
        for j in 0..l - f {
            let dinv = ls[j * nr + j].recip();
            for v in x[f + j].iter_mut() {
                *v *= dinv;
            }
        }
    }
    // Backward: the top supernodes from the last, then the tasks in parallel (each reads only
    // rows above its own, final by then).
    let xs = Shared(x.as_mut_ptr());
    let mut buf = Vec::new();
    for &s in tree.top.iter().rev() {
        // SAFETY: nothing runs in parallel here.
        unsafe { backward_supernode::<K, F>(sn, values, xs, s, &mut buf) };
    }
    tree.tasks.par_iter().for_each(|&(first, root)| {
        let mut buf = Vec::new();
        for s in (first..=root).rev() {
            // SAFETY: a task writes only its own rows and reads rows above it.
            unsafe { backward_supernode::<K, F>(sn, values, xs, s, &mut buf) };
        }
    });
}

/// Forward step of supernode `s`: its own rows, then the update of its pattern rows; rows at
/// or above `hi` are added to `out_vals` at their place in `out_rows` instead of x.
///
/// SAFETY: the caller owns the rows of `s` and every pattern row below `hi`.
#[allow(clippy::too_many_arguments)]
unsafe fn forward_supernode<const K: usize, const F: bool>(
    sn: &Sn,
    values: &[f64],
    xs: Shared<K>,
    s: usize,
    hi: usize,
    out_rows: &[usize],
    out_vals: &mut [[f64; K]],
    buf: &mut Vec<f64>,
) {
    let (f, l) = (sn.supernode_begin()[s], sn.supernode_end()[s]);
    let w = l - f;
    let pat = sn.supernode(s).pattern();
    let p = pat.len();
    let nr = w + p;
    let cp = sn.col_ptr_for_val();
    let ls = &values[cp[s]..cp[s + 1]];
    buf.clear();
    buf.resize(K * p, 0.0);
    let tmp = &mut buf[..];
    for j in 0..w {
        let col = &ls[j * nr..(j + 1) * nr];
        let xj = unsafe { xs.get(f + j) };
        for (i, &a) in col[j + 1..w].iter().enumerate() {
            let xi = unsafe { xs.at(f + j + 1 + i) };
            for c in 0..K {
                xi[c] = madd::<F>(-a, xj[c], xi[c]);
            }
        }
        let bot = &col[w..];
        for c in 0..K {
            let v = xj[c];
            if v != 0.0 {
                axpy::<F>(&mut tmp[c * p..(c + 1) * p], bot, v);
            }
        }
    }
    // Pattern rows are ascending: those below `hi` first, then the task's outside rows, which
    // are a subset of `out_rows` (also ascending): one merge walk.
    let split = pat.partition_point(|&r| r < hi);
    for (idx, &r) in pat[..split].iter().enumerate() {
        let xr = unsafe { xs.at(r) };
        for c in 0..K {
            xr[c] -= tmp[c * p + idx];
        }
    }
    let mut k = 0;
    for (idx, &r) in pat.iter().enumerate().skip(split) {
        while out_rows[k] < r {
            k += 1;
        }
        debug_assert_eq!(out_rows[k], r);
        for c in 0..K {
            out_vals[k][c] += tmp[c * p + idx];
        }
    }
}

/// Backward step of supernode `s`.
///
/// SAFETY: the caller owns the rows of `s`; its pattern rows are final.
unsafe fn backward_supernode<const K: usize, const F: bool>(
    sn: &Sn,
    values: &[f64],
    xs: Shared<K>,
    s: usize,
    buf: &mut Vec<f64>,
) {
    let (f, l) = (sn.supernode_begin()[s], sn.supernode_end()[s]);
    let w = l - f;
    let pat = sn.supernode(s).pattern();
    let p = pat.len();
    let nr = w + p;
    let cp = sn.col_ptr_for_val();
    let ls = &values[cp[s]..cp[s + 1]];
    buf.clear();
    buf.resize(K * p, 0.0);
    let g = &mut buf[..];
    for (idx, &r) in pat.iter().enumerate() {
        let xr = unsafe { xs.get(r) };
        for c in 0..K {
            g[c * p + idx] = xr[c];
        }
    }
    for j in (0..w).rev() {
        let col = &ls[j * nr..(j + 1) * nr];
        let mut acc = [0.0f64; K];
        for (i, &a) in col[j + 1..w].iter().enumerate() {
            let xi = unsafe { xs.get(f + j + 1 + i) };
            for c in 0..K {
                acc[c] = madd::<F>(a, xi[c], acc[c]);
            }
        }
        let bot = &col[w..];
        for c in 0..K {
            acc[c] += dot::<F>(bot, &g[c * p..(c + 1) * p]);
        }
        let xj = unsafe { xs.at(f + j) };
        for c in 0..K {
            xj[c] -= acc[c];
        }
    }
}

/// `a·b + c`, fused when `F`.
#[inline(always)]
pub(crate) fn madd<const F: bool>(a: f64, b: f64, c: f64) -> f64 {
    if F { a.mul_add(b, c) } else { a * b + c }
}

/// `y += a·x`.
#[inline(always)]
pub(crate) fn axpy<const F: bool>(y: &mut [f64], x: &[f64], a: f64) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi = madd::<F>(a, *xi, *yi);
    }
}

/// `x·y` with eight partial sums (in a fixed order).
#[inline(always)]
pub(crate) fn dot<const F: bool>(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().min(y.len());
    let (x8, xr) = x[..n].split_at(n - n % 8);
    let (y8, yr) = y[..n].split_at(n - n % 8);
    let mut s = [0.0f64; 8];
    for (a, b) in x8.chunks_exact(8).zip(y8.chunks_exact(8)) {
        for l in 0..8 {
            s[l] = madd::<F>(a[l], b[l], s[l]);
        }
    }
    let mut t = ((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]));
    for (a, b) in xr.iter().zip(yr) {
        t = madd::<F>(*a, *b, t);
    }
    t
}
