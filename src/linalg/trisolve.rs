//! Block triangular solves with a supernodal LDLᵀ factor, parallel without reading L twice.
//!
//! The elimination tree is cut once per structure ([`SolvePlan`], independent of the thread
//! count) into subtrees of at most a sixteenth of the factor's entries each and the supernodes
//! above them (the top). Forward (L y = b): the subtrees run at once, each writing its own rows
//! and summing what it sends to rows of the top into a buffer of its own (the root's pattern:
//! every row outside a subtree that the subtree touches is in it); the buffers are subtracted
//! in subtree order; then the top supernodes one by one, each off-diagonal product split by rows
//! between two tasks. Backward (D Lᵀ x = y): the top supernodes last first, each off-diagonal
//! product split by columns, then the subtrees at once. Every value of L is read once per
//! direction whatever the thread count, so a block of right-hand sides solved by two threads
//! reads the factor half as often as two column groups did.
//!
//! Bits: every entry's arithmetic is a fixed sequence set by the structure and the plan — the
//! split of a product between tasks never changes an entry's sequence, and the buffers are used
//! on one thread too — so results do not depend on the thread count, and a column solved alone
//! equals the same column solved in a block.
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use rayon::prelude::*;

pub(crate) type SupernodalSymbolic = SymbolicSupernodalCholesky<usize>;

/// Subtrees per factor: a quarter of the entries at most each. More of the factor in the
/// subtrees, solved at once without waiting for each other, and less in the top supernodes,
/// whose products tasks share one supernode at a time: on two threads, 6 right-hand sides at
/// 119k DOFs (tet10 plate) take 0.094–0.105 s a solve against 0.116–0.119 s with a sixteenth
/// (the cut before), and a quarter is as fast as a half, a third or a fifth. (With more than
/// four threads the subtrees alone would not keep every thread busy: not measured here.)
const SUBTREE_SHARE: usize = 4;

/// Off-diagonal blocks of fewer entries are not split between tasks.
const SPLIT_MIN: usize = 1 << 14;

/// What the cut of a factor's elimination tree for block solves looks like ([`SolvePlan`]).
#[derive(Clone, Copy, Debug)]
pub struct SolveLayout {
    /// Subtrees solved at once.
    pub subtrees: usize,
    /// Supernodes above them, solved one by one.
    pub top: usize,
    /// Widest top supernode (columns; solved as panels of at most 64).
    pub widest_top: usize,
    /// Panels of top supernodes whose products are split between two tasks.
    pub split_panels: usize,
}

/// The cut of the supernodal elimination tree used by every solve with factors of one
/// structure.
pub(crate) struct SolvePlan {
    /// Supernodes of each subtree, ascending (children before parents, the root last).
    subtrees: Vec<Vec<u32>>,
    /// Supernodes above the subtrees, ascending.
    top: Vec<u32>,
    /// Largest off-diagonal pattern.
    max_p: usize,
    /// Widest supernode.
    max_w: usize,
    /// Its summary.
    pub layout: SolveLayout,
    /// Where each supernode's values start in the packed layout ([`pack`]).
    offsets: Vec<usize>,
}

impl SolvePlan {
    pub(crate) fn new(sn: &SupernodalSymbolic) -> SolvePlan {
        let ns = sn.n_supernodes();
        let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
        let mut of_col = vec![0u32; sn.nrows()];
        for s in 0..ns {
            of_col[begin[s]..end[s]].fill(s as u32);
        }
        let entries = |s: usize| {
            let w = end[s] - begin[s];
            w * (w + sn.supernode(s).pattern().len())
        };
        // Parent: the supernode of the first off-diagonal row; children lists; subtree sizes.
        let mut weight: Vec<usize> = (0..ns).map(entries).collect();
        let mut children: Vec<Vec<u32>> = vec![Vec::new(); ns];
        let mut roots = Vec::new();
        for s in 0..ns {
            match sn.supernode(s).pattern().first() {
                Some(&r) => {
                    let p = of_col[r] as usize;
                    children[p].push(s as u32);
                    weight[p] += weight[s];
                }
                None => roots.push(s as u32),
            }
        }
        let total: usize = roots.iter().map(|&r| weight[r as usize]).sum();
        let limit = total / SUBTREE_SHARE;
        // Split the heaviest subtree into its children until none is above the limit.
        let mut heap: std::collections::BinaryHeap<(usize, u32)> =
            roots.iter().map(|&r| (weight[r as usize], r)).collect();
        let mut top = Vec::new();
        while let Some(&(w, s)) = heap.peek() {
            if w <= limit {
                break;
            }
            heap.pop();
            top.push(s);
            for &c in &children[s as usize] {
                heap.push((weight[c as usize], c));
            }
        }
        // Heaviest first, so that the last to finish are small.
        let mut cut = heap.into_vec();
        cut.sort_by(|a, b| b.cmp(a));
        let subtrees = cut
            .iter()
            .map(|&(_, root)| {
                let mut nodes = Vec::new();
                let mut stack = vec![root];
                while let Some(s) = stack.pop() {
                    nodes.push(s);
                    stack.extend_from_slice(&children[s as usize]);
                }
                nodes.sort_unstable();
                nodes
            })
            .collect();
        top.sort_unstable();
        let top_entries: usize = top.iter().map(|&s| entries(s as usize)).sum();
        let triangles: usize = (0..ns).map(|s| (end[s] - begin[s]) * (end[s] - begin[s] + 1) / 2).sum();
        log::debug!(
            "solve plan: {} subtrees, {} top supernodes with {:.1} % of the entries; diagonal triangles {:.1} %",
            cut.len(),
            top.len(),
            100.0 * top_entries as f64 / total.max(1) as f64,
            100.0 * triangles as f64 / total.max(1) as f64
        );
        let panel_sizes = |s: usize| {
            let (w, p) = (end[s] - begin[s], sn.supernode(s).pattern().len());
            (0..w.div_ceil(PANEL))
                .map(move |k| (PANEL.min(w - k * PANEL), w - k * PANEL - PANEL.min(w - k * PANEL) + p))
        };
        let layout = SolveLayout {
            subtrees: cut.len(),
            top: top.len(),
            widest_top: top
                .iter()
                .map(|&s| end[s as usize] - begin[s as usize])
                .max()
                .unwrap_or(0),
            split_panels: top
                .iter()
                .flat_map(|&s| panel_sizes(s as usize))
                .filter(|&(w, q)| w * q >= SPLIT_MIN)
                .count(),
        };
        SolvePlan {
            layout,
            subtrees,
            top,
            max_p: (0..ns).map(|s| sn.supernode(s).pattern().len()).max().unwrap_or(0),
            max_w: (0..ns).map(|s| end[s] - begin[s]).max().unwrap_or(0),
            offsets: packed_offsets(sn),
        }
    }
}

/// Rows of the solution block, shared by the tasks of a solve. Each task writes only rows it
/// owns (its subtree's columns, or its columns of a top supernode) and reads rows no other task
/// writes at the same time (its own, or the top's, final before the subtrees read them).
#[derive(Clone, Copy)]
struct Rows<const K: usize> {
    ptr: *mut [f64; K],
    len: usize,
}

// SAFETY: the tasks that share a `Rows` access disjoint rows mutably (see the type's comment);
// the pointer is valid for the whole solve (it borrows the caller's block).
unsafe impl<const K: usize> Send for Rows<K> {}
unsafe impl<const K: usize> Sync for Rows<K> {}

impl<const K: usize> Rows<K> {
    /// A view of `x` for the tasks of one parallel phase. A fresh view per phase: `x` itself is
    /// used between the phases, which a view taken before would not survive.
    fn of(x: &mut [[f64; K]]) -> Self {
        Rows {
            ptr: x.as_mut_ptr(),
            len: x.len(),
        }
    }

    /// Rows `a..b`, mutably.
    ///
    /// # Safety
    /// No other task accesses rows `a..b` while the slice lives.
    #[allow(clippy::mut_from_ref)]
    unsafe fn slice(&self, a: usize, b: usize) -> &mut [[f64; K]] {
        assert!(a <= b && b <= self.len);
        // SAFETY: in bounds (checked); exclusive by the caller's contract.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(a), b - a) }
    }

    /// Row `i`, mutably.
    ///
    /// # Safety
    /// As [`Rows::slice`] for the one row.
    #[allow(clippy::mut_from_ref)]
    unsafe fn row(&self, i: usize) -> &mut [f64; K] {
        assert!(i < self.len);
        // SAFETY: in bounds (checked); exclusive by the caller's contract.
        unsafe { &mut *self.ptr.add(i) }
    }
}

/// Supernode columns per panel: a wide supernode is solved as panels of at most this many
/// columns, each a triangle of its own and a product with every row below it (the rest of the
/// diagonal block, then the pattern), so that nearly all the work is in products that two
/// tasks can share.
const PANEL: usize = 64;

/// A panel of a supernode in the packed layout ([`pack`]): columns `f..f + w` of the factor
/// (rows of the solution block); its values start at `ls[0]` (the panel's first column, from its
/// diagonal down), columns `nr` apart. Below the panel's triangle: `below` rows of the
/// supernode's diagonal block (`f + w..f + w + below`), then the pattern.
struct Node<'a> {
    f: usize,
    w: usize,
    nr: usize,
    below: usize,
    pat: &'a [usize],
    ls: &'a [f64],
}

impl Node<'_> {
    /// Rows below the panel.
    fn q(&self) -> usize {
        self.below + self.pat.len()
    }

    /// Row of the solution block of the `idx`-th row below the panel.
    fn row(&self, idx: usize) -> usize {
        if idx < self.below {
            self.f + self.w + idx
        } else {
            self.pat[idx - self.below]
        }
    }
}

/// The panels of supernode `s`, first to last, in the packed layout ([`pack`]).
fn panels<'a>(
    sn: &'a SupernodalSymbolic,
    plan: &SolvePlan,
    values: &'a [f64],
    s: usize,
) -> impl DoubleEndedIterator<Item = Node<'a>> {
    let (f, w) = (sn.supernode_begin()[s], sn.supernode_end()[s] - sn.supernode_begin()[s]);
    let pat = sn.supernode(s).pattern();
    let nr = w + pat.len();
    let ls = &values[plan.offsets[s]..plan.offsets[s + 1]];
    (0..w.div_ceil(PANEL)).map(move |k| {
        let c0 = k * PANEL;
        let pw = PANEL.min(w - c0);
        let at = packed_start(nr, k);
        Node {
            f: f + c0,
            w: pw,
            nr: nr - c0,
            below: w - c0 - pw,
            pat,
            ls: &ls[at..],
        }
    })
}

/// Values per supernode in the packed layout, cumulated (`offsets[s]..offsets[s + 1]` holds
/// supernode `s`): each panel of at most [`PANEL`] columns keeps, of every column, the rows from
/// the panel's own diagonal down (faer's layout keeps the whole square diagonal block, whose
/// upper triangle the solves never read).
fn packed_offsets(sn: &SupernodalSymbolic) -> Vec<usize> {
    let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
    let mut offsets = Vec::with_capacity(sn.n_supernodes() + 1);
    offsets.push(0);
    let mut total = 0;
    for s in 0..sn.n_supernodes() {
        let w = end[s] - begin[s];
        let nr = w + sn.supernode(s).pattern().len();
        total += (0..w).map(|j| nr - j / PANEL * PANEL).sum::<usize>();
        offsets.push(total);
    }
    offsets
}

/// Every column's kept rows, supernode by supernode in order: `f(faer, packed, len)` with where
/// they start in faer's layout and in the packed one, and how many there are.
fn packed_columns(sn: &SupernodalSymbolic, plan: &SolvePlan, mut f: impl FnMut(usize, usize, usize)) {
    let cp = sn.col_ptr_for_val();
    let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
    for s in 0..sn.n_supernodes() {
        let w = end[s] - begin[s];
        let nr = w + sn.supernode(s).pattern().len();
        for j in 0..w {
            let (k, c0) = (j / PANEL, j / PANEL * PANEL);
            f(
                cp[s] + j * nr + c0,
                plan.offsets[s] + packed_start(nr, k) + (j - c0) * (nr - c0),
                nr - c0,
            );
        }
    }
}

/// Where panel `k` of a supernode of `nr` rows starts in the packed layout: after `k` full
/// panels, the i-th of `PANEL` columns of `nr − i·PANEL` values.
fn packed_start(nr: usize, k: usize) -> usize {
    PANEL * (k * nr - PANEL * k * k.saturating_sub(1) / 2)
}

/// Rewrite a supernodal factor from faer's layout into the packed one, in place, and give the
/// freed tail back: every value moves towards the front (a column's packed position is never
/// after its position in faer's layout), so one forward pass of overlapping copies suffices.
pub(crate) fn pack(sn: &SupernodalSymbolic, plan: &SolvePlan, values: &mut Vec<f64>) {
    packed_columns(sn, plan, |src, dst, len| values.copy_within(src..src + len, dst));
    values.truncate(plan.offsets[sn.n_supernodes()]);
    values.shrink_to_fit();
}

/// faer's layout of a packed factor (the upper triangles of the diagonal blocks, which no solve
/// reads, zero): for faer's own solve, a reference.
pub(crate) fn unpack(sn: &SupernodalSymbolic, plan: &SolvePlan, packed: &[f64]) -> Vec<f64> {
    let mut values = vec![0.0; sn.col_ptr_for_val()[sn.n_supernodes()]];
    packed_columns(sn, plan, |dst, src, len| {
        values[dst..dst + len].copy_from_slice(&packed[src..src + len])
    });
    values
}

/// Entry (i, c) of a product buffer of `len` rows (one column per right-hand side).
#[inline(always)]
fn at(len: usize, i: usize, c: usize) -> usize {
    c * len + i
}

/// Solve L D Lᵀ x = b in place for `K` right-hand sides stored row by row (`x[i]` holds row i
/// of the block, in the factor's elimination order), on the threads of the current pool.
pub(crate) fn solve<const K: usize>(sn: &SupernodalSymbolic, plan: &SolvePlan, values: &[f64], x: &mut [[f64; K]]) {
    assert_eq!(x.len(), sn.nrows());
    let kern = Kernels::<K>::new();
    let rows = Rows::of(x);
    let end = sn.supernode_end();
    let buf_len = K * (plan.max_p + plan.max_w);
    // Forward, subtrees: each returns what it sends to the top, by position in its root's pattern.
    let sent: Vec<Vec<[f64; K]>> = plan
        .subtrees
        .par_iter()
        .with_max_len(1)
        .map(|nodes| {
            let root = *nodes.last().expect("a subtree has a root") as usize;
            let root_pat = sn.supernode(root).pattern();
            let inside_end = end[root];
            let mut out = vec![[0.0f64; K]; root_pat.len()];
            let mut tmp = vec![0.0f64; buf_len];
            for &s in nodes {
                for nd in panels(sn, plan, values, s as usize) {
                    let q = nd.q();
                    // SAFETY: the subtree's own rows; no other task touches them.
                    let xs = unsafe { rows.slice(nd.f, nd.f + nd.w) };
                    kern.forward_diag(&nd, xs);
                    let tmp = &mut tmp[..K * q];
                    kern.forward_off(&nd, 0, q, xs, tmp);
                    // Rows inside the subtree (below its root's end) come first; the rest are
                    // in the root's pattern, in the same order.
                    let mut k = usize::MAX;
                    for idx in 0..q {
                        let r = nd.row(idx);
                        if r < inside_end {
                            // SAFETY: a row of this subtree, outside the panel.
                            let xr = unsafe { rows.row(r) };
                            for c in 0..K {
                                xr[c] -= tmp[at(q, idx, c)];
                            }
                        } else {
                            if k == usize::MAX {
                                k = root_pat.partition_point(|&x| x < r);
                            }
                            while root_pat[k] != r {
                                k += 1;
                            }
                            for c in 0..K {
                                out[k][c] += tmp[at(q, idx, c)];
                            }
                        }
                    }
                }
            }
            out
        })
        .collect();
    for (nodes, out) in plan.subtrees.iter().zip(&sent) {
        let root = *nodes.last().expect("a subtree has a root") as usize;
        for (&r, o) in sn.supernode(root).pattern().iter().zip(out) {
            for c in 0..K {
                x[r][c] -= o[c];
            }
        }
    }
    drop(sent);
    // Forward, top: each panel's product split by rows between two tasks.
    let mut tmp = vec![0.0f64; buf_len];
    for &s in &plan.top {
        for nd in panels(sn, plan, values, s as usize) {
            let q = nd.q();
            let (xs, _) = x[nd.f..].split_at_mut(nd.w);
            kern.forward_diag(&nd, xs);
            let xs = &x[nd.f..nd.f + nd.w];
            let tmp = &mut tmp[..K * q];
            let h = if q * nd.w >= SPLIT_MIN { (q / 2) & !3 } else { q };
            let (ta, tb) = tmp.split_at_mut(K * h);
            rayon::join(
                || kern.forward_off(&nd, 0, h, xs, ta),
                || kern.forward_off(&nd, h, q - h, xs, tb),
            );
            let (ta, tb) = tmp.split_at(K * h);
            for idx in 0..q {
                let r = nd.row(idx);
                for c in 0..K {
                    x[r][c] -= if idx < h {
                        ta[at(h, idx, c)]
                    } else {
                        tb[at(q - h, idx - h, c)]
                    };
                }
            }
        }
    }
    // Backward, top, last panel first: each product split by columns.
    let mut g = vec![0.0f64; buf_len];
    for &s in plan.top.iter().rev() {
        for nd in panels(sn, plan, values, s as usize).rev() {
            let q = nd.q();
            scale_by_pivots(&nd, &mut x[nd.f..nd.f + nd.w]);
            let g = &mut g[..K * q];
            for idx in 0..q {
                let r = nd.row(idx);
                for c in 0..K {
                    g[c * q + idx] = x[r][c];
                }
            }
            let g = &g[..];
            let xs = &mut x[nd.f..nd.f + nd.w];
            let h = if q * nd.w >= SPLIT_MIN { nd.w / 2 } else { nd.w };
            let (xa, xb) = xs.split_at_mut(h);
            rayon::join(|| kern.backward_off(&nd, 0, xa, g), || kern.backward_off(&nd, h, xb, g));
            kern.backward_diag(&nd, xs);
        }
    }
    // Backward, subtrees.
    let rows = Rows::of(x);
    plan.subtrees.par_iter().with_max_len(1).for_each(|nodes| {
        let mut g = vec![0.0f64; buf_len];
        for &s in nodes.iter().rev() {
            for nd in panels(sn, plan, values, s as usize).rev() {
                let q = nd.q();
                // SAFETY: the subtree's own rows; the rows below read next are its ancestors'
                // or later panels' (done), or the top's (final).
                let xs = unsafe { rows.slice(nd.f, nd.f + nd.w) };
                scale_by_pivots(&nd, xs);
                let g = &mut g[..K * q];
                for idx in 0..q {
                    // SAFETY: a row outside the panel, not written while the subtree runs.
                    let xr = unsafe { *rows.row(nd.row(idx)) };
                    for c in 0..K {
                        g[c * q + idx] = xr[c];
                    }
                }
                kern.backward_off(&nd, 0, xs, g);
                kern.backward_diag(&nd, xs);
            }
        }
    });
}

/// D z = y on the rows of one panel.
fn scale_by_pivots<const K: usize>(nd: &Node<'_>, xs: &mut [[f64; K]]) {
    for (j, xj) in xs.iter_mut().enumerate() {
        let dinv = nd.ls[j * nd.nr + j].recip();
        for v in xj.iter_mut() {
            *v *= dinv;
        }
    }
}

/// The per-supernode kernels, compiled for AVX2 with fused multiply–adds when the machine has
/// them (the off-diagonal ones for AVX-512VL too, preferred where present).
struct Kernels<const K: usize> {
    fma: bool,
    /// AVX-512VL as well: the off-diagonal kernels with thirty-two vector registers.
    avx512: bool,
}

impl<const K: usize> Kernels<K> {
    fn new() -> Self {
        #[cfg(target_arch = "x86_64")]
        let fma = std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma");
        #[cfg(not(target_arch = "x86_64"))]
        let fma = false;
        #[cfg(target_arch = "x86_64")]
        let avx512 = fma && std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512vl");
        #[cfg(not(target_arch = "x86_64"))]
        let avx512 = false;
        Kernels { fma, avx512 }
    }

    /// The diagonal block's forward substitution on the supernode's rows `xs`.
    fn forward_diag(&self, nd: &Node<'_>, xs: &mut [[f64; K]]) {
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: the CPU has the features the function is compiled for.
            return unsafe { fma_diag::forward_diag::<K>(nd, xs) };
        }
        forward_diag::<K, false>(nd, xs)
    }

    /// `tmp[c·len + i] = Σ_t L_off[lo + i, t]·xs[t][c]` for off-diagonal rows `lo..lo + len`.
    fn forward_off(&self, nd: &Node<'_>, lo: usize, len: usize, xs: &[[f64; K]], tmp: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if self.avx512 {
            // SAFETY: the CPU has the features the function is compiled for.
            return unsafe { avx512::forward_off::<K>(nd, lo, len, xs, tmp) };
        }
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: as above.
            return unsafe { fma::forward_off::<K>(nd, lo, len, xs, tmp) };
        }
        forward_off::<K, false>(nd, lo, len, xs, tmp)
    }

    /// `xs[t][c] −= L_off[:, j0 + t]ᵀ·g[c]` for the columns `j0..j0 + xs.len()`.
    fn backward_off(&self, nd: &Node<'_>, j0: usize, xs: &mut [[f64; K]], g: &[f64]) {
        #[cfg(target_arch = "x86_64")]
        if self.avx512 {
            // SAFETY: the CPU has the features the function is compiled for.
            return unsafe { avx512::backward_off::<K>(nd, j0, xs, g) };
        }
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: as above.
            return unsafe { fma::backward_off::<K>(nd, j0, xs, g) };
        }
        backward_off::<K, false>(nd, j0, xs, g)
    }

    /// The diagonal block's backward substitution on the supernode's rows `xs`.
    fn backward_diag(&self, nd: &Node<'_>, xs: &mut [[f64; K]]) {
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: the CPU has the features the function is compiled for.
            return unsafe { fma_diag::backward_diag::<K>(nd, xs) };
        }
        backward_diag::<K, false>(nd, xs)
    }
}

/// The off-diagonal kernels in explicit four-lane vector code (the same arithmetic as
/// [`forward_off`] and [`backward_off`] with `F`: each lane a fused multiply–add chain over the
/// columns, the backward lanes summed as (l0 + l1) + (l2 + l3), the remaining rows in order),
/// compiled twice: for AVX2 with FMA (sixteen vector registers) and for AVX-512VL (the same
/// four-lane vectors, thirty-two registers). The number of columns of L per pass over a chunk of
/// right-hand sides (`J` of the tables) keeps the accumulators, the right-hand sides' vectors
/// and one vector of L within the registers: with AVX2 for a six-column chunk two columns
/// forward (the x values broadcast from memory), one backward (six accumulators, six vectors of
/// g, one of L); with AVX-512VL four columns each way (24 accumulators or broadcasts, six
/// vectors, one of L).
macro_rules! vector_kernels {
    ($name:ident, $feat:literal, forward: [$f1:literal, $f2:literal, $f3:literal, $f4:literal, $f5:literal, $f6:literal],
     backward: [$b1:literal, $b2:literal, $b3:literal, $b4:literal, $b5:literal, $b6:literal]) => {
        #[cfg(target_arch = "x86_64")]
        mod $name {
            use super::{Node, cols};
            use std::arch::x86_64::*;

            #[target_feature(enable = $feat)]
            pub(super) unsafe fn forward_off<const K: usize>(
                nd: &Node<'_>,
                lo: usize,
                len: usize,
                xs: &[[f64; K]],
                tmp: &mut [f64],
            ) {
                let start = nd.w + lo;
                tmp[..K * len].fill(0.0);
                let mut c0 = 0;
                while c0 + 6 <= K {
                    forward_chunk::<K, 6, $f6>(nd, start, len, xs, tmp, c0);
                    c0 += 6;
                }
                match K - c0 {
                    0 => {}
                    1 => forward_chunk::<K, 1, $f1>(nd, start, len, xs, tmp, c0),
                    2 => forward_chunk::<K, 2, $f2>(nd, start, len, xs, tmp, c0),
                    3 => forward_chunk::<K, 3, $f3>(nd, start, len, xs, tmp, c0),
                    4 => forward_chunk::<K, 4, $f4>(nd, start, len, xs, tmp, c0),
                    _ => forward_chunk::<K, 5, $f5>(nd, start, len, xs, tmp, c0),
                }
            }

            #[target_feature(enable = $feat)]
            #[inline]
            fn forward_chunk<const K: usize, const KC: usize, const J: usize>(
                nd: &Node<'_>,
                start: usize,
                len: usize,
                xs: &[[f64; K]],
                tmp: &mut [f64],
                c0: usize,
            ) {
                let (w, nr) = (nd.w, nd.nr);
                let mut j0 = 0;
                while j0 + J <= w {
                    let l = cols::<J>(nd.ls, nr, start, len, j0);
                    forward_cols::<K, KC, J>(l, &xs[j0..j0 + J], tmp, len, c0);
                    j0 += J;
                }
                while j0 < w {
                    let l = cols::<1>(nd.ls, nr, start, len, j0);
                    forward_cols::<K, KC, 1>(l, &xs[j0..j0 + 1], tmp, len, c0);
                    j0 += 1;
                }
            }

            /// `tmp[c·p + i] += Σ_t col[t][i]·xs[t][c]` for `c` in `c0..c0 + KC`.
            #[target_feature(enable = $feat)]
            #[inline]
            fn forward_cols<const K: usize, const KC: usize, const J: usize>(
                cols: [&[f64]; J],
                xs: &[[f64; K]],
                tmp: &mut [f64],
                p: usize,
                c0: usize,
            ) {
                let tmp = &mut tmp[c0 * p..(c0 + KC) * p];
                let p4 = p - p % 4;
                for t in 0..J {
                    assert!(cols[t].len() >= p);
                }
                let mut xb = [[_mm256_setzero_pd(); KC]; J];
                for t in 0..J {
                    for c in 0..KC {
                        xb[t][c] = _mm256_set1_pd(xs[t][c0 + c]);
                    }
                }
                let tp = tmp.as_mut_ptr();
                let mut i = 0;
                while i < p4 {
                    let mut acc = [_mm256_setzero_pd(); KC];
                    // SAFETY: rows i..i + 4 ≤ p of every column of L and of tmp's KC columns.
                    unsafe {
                        for c in 0..KC {
                            acc[c] = _mm256_loadu_pd(tp.add(c * p + i));
                        }
                        for t in 0..J {
                            let a = _mm256_loadu_pd(cols[t].as_ptr().add(i));
                            for c in 0..KC {
                                acc[c] = _mm256_fmadd_pd(a, xb[t][c], acc[c]);
                            }
                        }
                        for c in 0..KC {
                            _mm256_storeu_pd(tp.add(c * p + i), acc[c]);
                        }
                    }
                    i += 4;
                }
                for i in p4..p {
                    for t in 0..J {
                        let a = cols[t][i];
                        for c in 0..KC {
                            tmp[c * p + i] = a.mul_add(xs[t][c0 + c], tmp[c * p + i]);
                        }
                    }
                }
            }

            #[target_feature(enable = $feat)]
            pub(super) unsafe fn backward_off<const K: usize>(
                nd: &Node<'_>,
                j0: usize,
                xs: &mut [[f64; K]],
                g: &[f64],
            ) {
                let mut c0 = 0;
                while c0 + 6 <= K {
                    backward_chunk::<K, 6, $b6>(nd, j0, xs, g, c0);
                    c0 += 6;
                }
                match K - c0 {
                    0 => {}
                    1 => backward_chunk::<K, 1, $b1>(nd, j0, xs, g, c0),
                    2 => backward_chunk::<K, 2, $b2>(nd, j0, xs, g, c0),
                    3 => backward_chunk::<K, 3, $b3>(nd, j0, xs, g, c0),
                    4 => backward_chunk::<K, 4, $b4>(nd, j0, xs, g, c0),
                    _ => backward_chunk::<K, 5, $b5>(nd, j0, xs, g, c0),
                }
            }

            #[target_feature(enable = $feat)]
            #[inline]
            fn backward_chunk<const K: usize, const KC: usize, const J: usize>(
                nd: &Node<'_>,
                j0: usize,
                xs: &mut [[f64; K]],
                g: &[f64],
                c0: usize,
            ) {
                let (q, nr, start) = (nd.q(), nd.nr, nd.w);
                let n = xs.len();
                let mut j = 0;
                while j + J <= n {
                    let l = cols::<J>(nd.ls, nr, start, q, j0 + j);
                    backward_cols::<K, KC, J>(l, &mut xs[j..j + J], g, q, c0);
                    j += J;
                }
                while j < n {
                    let l = cols::<1>(nd.ls, nr, start, q, j0 + j);
                    backward_cols::<K, KC, 1>(l, &mut xs[j..j + 1], g, q, c0);
                    j += 1;
                }
            }

            /// `xs[t][c] −= col[t]ᵀ·g[c]` for `c` in `c0..c0 + KC`.
            #[target_feature(enable = $feat)]
            #[inline]
            fn backward_cols<const K: usize, const KC: usize, const J: usize>(
                cols: [&[f64]; J],
                xs: &mut [[f64; K]],
                g: &[f64],
                p: usize,
                c0: usize,
            ) {
                let g = &g[c0 * p..(c0 + KC) * p];
                let p4 = p - p % 4;
                for t in 0..J {
                    assert!(cols[t].len() >= p);
                }
                let gp = g.as_ptr();
                let mut acc = [[_mm256_setzero_pd(); KC]; J];
                let mut i = 0;
                while i < p4 {
                    let mut gv = [_mm256_setzero_pd(); KC];
                    // SAFETY: rows i..i + 4 ≤ p of every column of L and of g's KC columns.
                    unsafe {
                        for c in 0..KC {
                            gv[c] = _mm256_loadu_pd(gp.add(c * p + i));
                        }
                        for t in 0..J {
                            let a = _mm256_loadu_pd(cols[t].as_ptr().add(i));
                            for c in 0..KC {
                                acc[t][c] = _mm256_fmadd_pd(a, gv[c], acc[t][c]);
                            }
                        }
                    }
                    i += 4;
                }
                for t in 0..J {
                    for c in 0..KC {
                        let mut v = [0.0f64; 4];
                        // SAFETY: four lanes into a four-element array.
                        unsafe { _mm256_storeu_pd(v.as_mut_ptr(), acc[t][c]) };
                        let mut sum = (v[0] + v[1]) + (v[2] + v[3]);
                        for i in p4..p {
                            sum = cols[t][i].mul_add(g[c * p + i], sum);
                        }
                        xs[t][c0 + c] -= sum;
                    }
                }
            }
        }
    };
}

vector_kernels!(fma, "avx2,fma", forward: [8, 6, 4, 3, 2, 2], backward: [8, 6, 4, 2, 2, 1]);
vector_kernels!(avx512, "avx2,fma,avx512f,avx512vl", forward: [8, 12, 8, 6, 5, 4], backward: [8, 12, 8, 6, 5, 4]);

#[cfg(target_arch = "x86_64")]
mod fma_diag {
    use super::Node;

    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn forward_diag<const K: usize>(nd: &Node<'_>, xs: &mut [[f64; K]]) {
        super::forward_diag::<K, true>(nd, xs)
    }

    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn backward_diag<const K: usize>(nd: &Node<'_>, xs: &mut [[f64; K]]) {
        super::backward_diag::<K, true>(nd, xs)
    }
}

/// `a·b + c`, fused when `F`.
#[inline(always)]
fn madd<const F: bool>(a: f64, b: f64, c: f64) -> f64 {
    if F { a.mul_add(b, c) } else { a * b + c }
}

/// Forward substitution with the unit lower triangle of the panel: `x_i −= L_ij·x_j` for the
/// columns `j < i` in order, each a multiply–add on `x_i` (the column-by-column arithmetic,
/// bit for bit). The rows go four at a time, one per vector lane, their sums over the columns
/// before them kept in registers (no store per column); the four rows' own triangle last.
#[inline(always)]
fn forward_diag<const K: usize, const F: bool>(nd: &Node<'_>, xs: &mut [[f64; K]]) {
    let (w, nr) = (nd.w, nd.nr);
    let w4 = w - w % 4;
    let mut i0 = 0;
    while i0 < w4 {
        let mut acc = [[0.0f64; 4]; K];
        for r in 0..4 {
            for c in 0..K {
                acc[c][r] = xs[i0 + r][c];
            }
        }
        for (j, xj) in xs[..i0].iter().enumerate() {
            let a: &[f64; 4] = nd.ls[j * nr + i0..j * nr + i0 + 4].try_into().expect("four rows");
            for c in 0..K {
                for r in 0..4 {
                    acc[c][r] = madd::<F>(-a[r], xj[c], acc[c][r]);
                }
            }
        }
        for r in 1..4 {
            for t in 0..r {
                let a = nd.ls[(i0 + t) * nr + i0 + r];
                for c in 0..K {
                    acc[c][r] = madd::<F>(-a, acc[c][t], acc[c][r]);
                }
            }
        }
        for r in 0..4 {
            for c in 0..K {
                xs[i0 + r][c] = acc[c][r];
            }
        }
        i0 += 4;
    }
    for i in w4..w {
        let mut xi = xs[i];
        for (j, xj) in xs[..i].iter().enumerate() {
            let a = nd.ls[j * nr + i];
            for c in 0..K {
                xi[c] = madd::<F>(-a, xj[c], xi[c]);
            }
        }
        xs[i] = xi;
    }
}

/// Backward substitution with the transposed unit triangle of the panel, last column first.
#[inline(always)]
fn backward_diag<const K: usize, const F: bool>(nd: &Node<'_>, xs: &mut [[f64; K]]) {
    let (w, nr) = (nd.w, nd.nr);
    for j in (0..w).rev() {
        let col = &nd.ls[j * nr..j * nr + w];
        let mut acc = [0.0f64; K];
        for (xi, &a) in xs[j + 1..w].iter().zip(&col[j + 1..w]) {
            for c in 0..K {
                acc[c] = madd::<F>(a, xi[c], acc[c]);
            }
        }
        for c in 0..K {
            xs[j][c] -= acc[c];
        }
    }
}

/// Rows `start..start + len` of panel columns `j0..j0 + J` (`nr` apart).
#[inline(always)]
fn cols<const J: usize>(ls: &[f64], nr: usize, start: usize, len: usize, j0: usize) -> [&[f64]; J] {
    std::array::from_fn(|t| &ls[(j0 + t) * nr + start..(j0 + t) * nr + start + len])
}

/// [`Kernels::forward_off`]: the right-hand sides in chunks of at most six, each chunk `J`
/// columns at a time over four rows (one lane per row), all the chunk's right-hand sides per
/// vector. Each entry is a sum over the columns in order from zero, multiply–adds.
#[inline(always)]
fn forward_off<const K: usize, const F: bool>(nd: &Node<'_>, lo: usize, len: usize, xs: &[[f64; K]], tmp: &mut [f64]) {
    let start = nd.w + lo;
    tmp[..K * len].fill(0.0);
    let mut c0 = 0;
    while c0 + 6 <= K {
        forward_chunk::<K, 6, 2, F>(nd, start, len, xs, tmp, c0);
        c0 += 6;
    }
    match K - c0 {
        0 => {}
        1 => forward_chunk::<K, 1, 8, F>(nd, start, len, xs, tmp, c0),
        2 => forward_chunk::<K, 2, 6, F>(nd, start, len, xs, tmp, c0),
        3 => forward_chunk::<K, 3, 4, F>(nd, start, len, xs, tmp, c0),
        4 => forward_chunk::<K, 4, 3, F>(nd, start, len, xs, tmp, c0),
        _ => forward_chunk::<K, 5, 2, F>(nd, start, len, xs, tmp, c0),
    }
}

/// [`forward_off`] for right-hand sides `c0..c0 + KC`, `J` columns at a time (the chunk's
/// accumulators, one vector of L and the J·KC values of x within the registers, or close).
#[inline(always)]
fn forward_chunk<const K: usize, const KC: usize, const J: usize, const F: bool>(
    nd: &Node<'_>,
    start: usize,
    len: usize,
    xs: &[[f64; K]],
    tmp: &mut [f64],
    c0: usize,
) {
    let (w, nr) = (nd.w, nd.nr);
    let mut j0 = 0;
    while j0 + J <= w {
        forward_cols::<K, KC, J, F>(cols::<J>(nd.ls, nr, start, len, j0), &xs[j0..j0 + J], tmp, len, c0);
        j0 += J;
    }
    while j0 < w {
        forward_cols::<K, KC, 1, F>(cols::<1>(nd.ls, nr, start, len, j0), &xs[j0..j0 + 1], tmp, len, c0);
        j0 += 1;
    }
}

/// `tmp[c·p + i] += Σ_t col[t][i]·xs[t][c]` for `c` in `c0..c0 + KC`, four rows at a time.
#[inline(always)]
fn forward_cols<const K: usize, const KC: usize, const J: usize, const F: bool>(
    cols: [&[f64]; J],
    xs: &[[f64; K]],
    tmp: &mut [f64],
    p: usize,
    c0: usize,
) {
    let xs: [[f64; KC]; J] = std::array::from_fn(|t| std::array::from_fn(|c| xs[t][c0 + c]));
    let tmp = &mut tmp[c0 * p..(c0 + KC) * p];
    let p4 = p - p % 4;
    let mut i = 0;
    while i < p4 {
        let mut acc = [[0.0f64; 4]; KC];
        for c in 0..KC {
            acc[c].copy_from_slice(&tmp[c * p + i..c * p + i + 4]);
        }
        for t in 0..J {
            let a: &[f64; 4] = cols[t][i..i + 4].try_into().expect("four rows");
            for c in 0..KC {
                for r in 0..4 {
                    acc[c][r] = madd::<F>(a[r], xs[t][c], acc[c][r]);
                }
            }
        }
        for c in 0..KC {
            tmp[c * p + i..c * p + i + 4].copy_from_slice(&acc[c]);
        }
        i += 4;
    }
    for i in p4..p {
        for t in 0..J {
            let a = cols[t][i];
            for c in 0..KC {
                tmp[c * p + i] = madd::<F>(a, xs[t][c], tmp[c * p + i]);
            }
        }
    }
}

/// [`Kernels::backward_off`]: the right-hand sides in chunks of at most six (a chunk's
/// J·KC four-lane accumulators, its KC vectors of the gathered rows and one of L fill the
/// sixteen vector registers of AVX2), `J` columns at a time.
#[inline(always)]
fn backward_off<const K: usize, const F: bool>(nd: &Node<'_>, j0: usize, xs: &mut [[f64; K]], g: &[f64]) {
    let mut c0 = 0;
    while c0 + 6 <= K {
        backward_chunk::<K, 6, 1, F>(nd, j0, xs, g, c0);
        c0 += 6;
    }
    match K - c0 {
        0 => {}
        1 => backward_chunk::<K, 1, 8, F>(nd, j0, xs, g, c0),
        2 => backward_chunk::<K, 2, 6, F>(nd, j0, xs, g, c0),
        3 => backward_chunk::<K, 3, 4, F>(nd, j0, xs, g, c0),
        4 => backward_chunk::<K, 4, 2, F>(nd, j0, xs, g, c0),
        _ => backward_chunk::<K, 5, 2, F>(nd, j0, xs, g, c0),
    }
}

/// [`backward_off`] for right-hand sides `c0..c0 + KC`.
#[inline(always)]
fn backward_chunk<const K: usize, const KC: usize, const J: usize, const F: bool>(
    nd: &Node<'_>,
    j0: usize,
    xs: &mut [[f64; K]],
    g: &[f64],
    c0: usize,
) {
    let (q, nr, start) = (nd.q(), nd.nr, nd.w);
    let n = xs.len();
    let mut j = 0;
    while j + J <= n {
        backward_cols::<K, KC, J, F>(cols::<J>(nd.ls, nr, start, q, j0 + j), &mut xs[j..j + J], g, q, c0);
        j += J;
    }
    while j < n {
        backward_cols::<K, KC, 1, F>(cols::<1>(nd.ls, nr, start, q, j0 + j), &mut xs[j..j + 1], g, q, c0);
        j += 1;
    }
}

/// `xs[t][c] −= col[t]ᵀ·g[c]` for `c` in `c0..c0 + KC`: four lanes over the rows, summed as
/// (l0 + l1) + (l2 + l3), then the remaining rows in order.
#[inline(always)]
fn backward_cols<const K: usize, const KC: usize, const J: usize, const F: bool>(
    cols: [&[f64]; J],
    xs: &mut [[f64; K]],
    g: &[f64],
    p: usize,
    c0: usize,
) {
    let g = &g[c0 * p..(c0 + KC) * p];
    let p4 = p - p % 4;
    let mut acc = [[[0.0f64; 4]; KC]; J];
    let mut i = 0;
    while i < p4 {
        let mut gv = [[0.0f64; 4]; KC];
        for c in 0..KC {
            gv[c].copy_from_slice(&g[c * p + i..c * p + i + 4]);
        }
        for t in 0..J {
            let a: &[f64; 4] = cols[t][i..i + 4].try_into().expect("four rows");
            for c in 0..KC {
                for r in 0..4 {
                    acc[t][c][r] = madd::<F>(a[r], gv[c][r], acc[t][c][r]);
                }
            }
        }
        i += 4;
    }
    for t in 0..J {
        for c in 0..KC {
            let v = &acc[t][c];
            let mut sum = (v[0] + v[1]) + (v[2] + v[3]);
            for i in p4..p {
                sum = madd::<F>(cols[t][i], g[c * p + i], sum);
            }
            xs[t][c0 + c] -= sum;
        }
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;

    /// Pseudo-random numbers in [−0.5, 0.5) (xorshift64) from `state`.
    fn uniform(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// The diagonal forward substitution, four rows at a time, is the column-by-column one bit
    /// for bit (fused and not, and compiled for AVX2), for panel widths with and without rows
    /// over a multiple of four.
    #[test]
    fn forward_diag_equals_the_column_by_column_substitution() {
        // The definition: x_i −= L_ij·x_j column by column, each a multiply–add on x_i.
        fn by_columns<const K: usize, const F: bool>(nd: &Node<'_>, xs: &mut [[f64; K]]) {
            for j in 0..nd.w {
                let xj = xs[j];
                for i in j + 1..nd.w {
                    let a = nd.ls[j * nd.nr + i];
                    for c in 0..K {
                        xs[i][c] = madd::<F>(-a, xj[c], xs[i][c]);
                    }
                }
            }
        }
        fn check<const K: usize>(next: &mut dyn FnMut() -> f64) {
            for w in [1usize, 2, 3, 4, 5, 7, 8, 9, 13, 64] {
                let nr = w + 5;
                let ls: Vec<f64> = (0..w * nr).map(|_| next()).collect();
                let nd = Node {
                    f: 0,
                    w,
                    nr,
                    below: 5,
                    pat: &[],
                    ls: &ls,
                };
                let xs: Vec<[f64; K]> = (0..w).map(|_| std::array::from_fn(|_| next())).collect();
                let same = |a: &[[f64; K]], b: &[[f64; K]]| {
                    a.iter()
                        .flatten()
                        .zip(b.iter().flatten())
                        .all(|(p, q)| p.to_bits() == q.to_bits())
                };
                let (mut x1, mut x2) = (xs.clone(), xs.clone());
                by_columns::<K, true>(&nd, &mut x1);
                forward_diag::<K, true>(&nd, &mut x2);
                assert!(same(&x1, &x2), "fused, K = {K}, w = {w}");
                let (mut x1, mut x2) = (xs.clone(), xs.clone());
                by_columns::<K, false>(&nd, &mut x1);
                forward_diag::<K, false>(&nd, &mut x2);
                assert!(same(&x1, &x2), "unfused, K = {K}, w = {w}");
                #[cfg(target_arch = "x86_64")]
                if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
                    let mut x3 = xs.clone();
                    // SAFETY: the CPU has the features (checked).
                    unsafe { fma_diag::forward_diag::<K>(&nd, &mut x3) };
                    let mut x1 = xs.clone();
                    by_columns::<K, true>(&nd, &mut x1);
                    assert!(same(&x1, &x3), "AVX2, K = {K}, w = {w}");
                }
            }
        }
        let mut next = uniform(0x9e37_79b9_7f4a_7c15);
        check::<1>(&mut next);
        check::<2>(&mut next);
        check::<4>(&mut next);
        check::<5>(&mut next);
        check::<8>(&mut next);
        check::<12>(&mut next);
    }

    /// The AVX2 kernels, and the AVX-512VL ones where the machine has them, compute the scalar
    /// fused definition ([`forward_off`] and [`backward_off`] with `F`) bit for bit, for every
    /// chunk width (1–13 right-hand sides: the six-column chunks and each remainder), panel
    /// widths that leave columns over, and row counts that leave rows outside the four-row
    /// vectors.
    #[test]
    fn vector_kernels_equal_the_scalar_definition() {
        if !(std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")) {
            return;
        }
        let mut next = uniform(0x2545_f491_4f6c_dd1d);
        fn check<const K: usize>(next: &mut dyn FnMut() -> f64) {
            for (w, below) in [(1usize, 3usize), (5, 17), (7, 30), (64, 9)] {
                let nr = w + below;
                let ls: Vec<f64> = (0..w * nr).map(|_| next()).collect();
                let nd = Node {
                    f: 0,
                    w,
                    nr,
                    below,
                    pat: &[],
                    ls: &ls,
                };
                let xs: Vec<[f64; K]> = (0..w).map(|_| std::array::from_fn(|_| next())).collect();
                let len = below;
                let mut t1 = vec![0.0; K * len];
                forward_off::<K, true>(&nd, 0, len, &xs, &mut t1);
                let g: Vec<f64> = (0..K * nd.q()).map(|_| next()).collect();
                let mut x1 = xs.clone();
                backward_off::<K, true>(&nd, 0, &mut x1, &g);
                type Fwd<const K: usize> = unsafe fn(&Node<'_>, usize, usize, &[[f64; K]], &mut [f64]);
                type Bwd<const K: usize> = unsafe fn(&Node<'_>, usize, &mut [[f64; K]], &[f64]);
                let mut variants: Vec<(&str, Fwd<K>, Bwd<K>)> =
                    vec![("AVX2", fma::forward_off::<K>, fma::backward_off::<K>)];
                if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512vl") {
                    variants.push(("AVX-512VL", avx512::forward_off::<K>, avx512::backward_off::<K>));
                }
                for (name, fwd, bwd) in variants {
                    let mut t2 = vec![0.0; K * len];
                    // SAFETY: the CPU has the variant's features (checked above).
                    unsafe { fwd(&nd, 0, len, &xs, &mut t2) };
                    assert!(
                        t1.iter().zip(&t2).all(|(a, b)| a.to_bits() == b.to_bits()),
                        "{name} forward, K = {K}, w = {w}"
                    );
                    let mut x2 = xs.clone();
                    // SAFETY: as above.
                    unsafe { bwd(&nd, 0, &mut x2, &g) };
                    assert!(
                        x1.iter()
                            .flatten()
                            .zip(x2.iter().flatten())
                            .all(|(a, b)| a.to_bits() == b.to_bits()),
                        "{name} backward, K = {K}, w = {w}"
                    );
                }
            }
        }
        check::<1>(&mut next);
        check::<2>(&mut next);
        check::<3>(&mut next);
        check::<4>(&mut next);
        check::<5>(&mut next);
        check::<6>(&mut next);
        check::<7>(&mut next);
        check::<11>(&mut next);
        check::<13>(&mut next);
    }
}
