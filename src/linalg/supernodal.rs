//! Numeric supernodal LDLᵀ on faer's symbolic structure, parallel over independent subtrees
//! of the elimination tree.
//!
//! The arithmetic of every supernode is faer's left-looking supernodal LDLᵀ (the same update
//! kernel, `private_gemm_x86`'s gather–scatter product, in the same order of descendants, the
//! same dense LDLᵀ and triangular solve), and the values land in faer's layout, so the factor
//! is solved by [`super::factor`]'s supernodal solve and reads the same pivots. What differs is
//! the schedule: faer walks the supernodes one after another and is parallel only inside the
//! dense kernels, which on a mesh's many medium supernodes leaves most threads idle. Here the
//! elimination tree is cut into independent subtrees and the mid-level separators between
//! them, run as tasks by whichever thread is free (a separator once its children are
//! complete), each with sequential kernels; only the supernodes above them (the top
//! separators, few and large) run one after another with parallel kernels. A supernode's
//! result does not depend on which thread computes it or when, so the factor is the same bit
//! for bit on any thread count.
//!
//! The matrix is read straight from K and M (`K − σM` entry by entry, in elimination order):
//! neither the shifted matrix nor its permuted copy is built.

use crate::linalg::sparse::SymMatrix;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{
    LdltError, LdltRegularization, cholesky_in_place, cholesky_in_place_scratch,
};
use faer::{MatMut, Par};

type Symbolic = faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize>;

/// The part of the schedule that depends on the structure only (computed once per pattern).
pub struct Plan {
    /// Descendants whose columns update each supernode, ascending:
    /// `updaters[upd_ptr[s]..upd_ptr[s + 1]]`.
    upd_ptr: Vec<usize>,
    updaters: Vec<u32>,
    /// Children of each supernode in the supernodal elimination tree:
    /// `children[child_ptr[s]..child_ptr[s + 1]]`; the roots are listed in `roots`.
    child_ptr: Vec<usize>,
    children: Vec<u32>,
    roots: Vec<u32>,
    /// Flops of each supernode's own factorisation and updates, and of its whole subtree.
    subtree_flops: Vec<f64>,
    /// Widest supernode (for the dense factorisation's scratch).
    max_width: usize,
    /// Longest index list of one update (rows of a descendant at or below a supernode).
    max_rows: usize,
}

impl Plan {
    /// Bytes of the plan's own arrays.
    pub fn bytes(&self) -> usize {
        8 * (self.upd_ptr.len() + self.child_ptr.len() + self.subtree_flops.len())
            + 4 * (self.updaters.len() + self.children.len() + self.roots.len())
    }
}

/// Build the plan of a supernodal structure.
pub fn plan(sn: &Symbolic) -> Plan {
    let ns = sn.n_supernodes();
    let n = sn.nrows();
    let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
    let mut of_col = vec![0u32; n];
    for s in 0..ns {
        for c in &mut of_col[begin[s]..end[s]] {
            *c = s as u32;
        }
    }
    // Pairs (target, descendant): one per supernode that a descendant's pattern reaches.
    let mut count = vec![0usize; ns + 1];
    let mut parent = vec![u32::MAX; ns];
    let mut own_flops = vec![0.0f64; ns];
    let mut max_rows = 0;
    for d in 0..ns {
        let pat = sn.supernode(d).pattern();
        max_rows = max_rows.max(pat.len());
        let w = (end[d] - begin[d]) as f64;
        let p = pat.len() as f64;
        // Dense LDLᵀ of the diagonal block, the triangular solve below it, and the updates
        // this supernode sends to its ancestors (counted at the sender: they read its columns).
        own_flops[d] = w * w * w / 3.0 + p * w * w + p * p * w;
        if let Some(&r) = pat.first() {
            parent[d] = of_col[r];
        }
        let mut last = u32::MAX;
        for &r in pat {
            let t = of_col[r];
            if t != last {
                count[t as usize + 1] += 1;
                last = t;
            }
        }
    }
    for s in 0..ns {
        count[s + 1] += count[s];
    }
    let upd_ptr = count.clone();
    let mut fill = count;
    let mut updaters = vec![0u32; upd_ptr[ns]];
    for d in 0..ns {
        let mut last = u32::MAX;
        for &r in sn.supernode(d).pattern() {
            let t = of_col[r];
            if t != last {
                updaters[fill[t as usize]] = d as u32;
                fill[t as usize] += 1;
                last = t;
            }
        }
    }
    // Children lists (ascending) and subtree weights; parents come after their children.
    let mut child_ptr = vec![0usize; ns + 1];
    let mut roots = Vec::new();
    for d in 0..ns {
        match parent[d] {
            u32::MAX => roots.push(d as u32),
            p => child_ptr[p as usize + 1] += 1,
        }
    }
    for s in 0..ns {
        child_ptr[s + 1] += child_ptr[s];
    }
    let mut fill = child_ptr.clone();
    let mut children = vec![0u32; child_ptr[ns]];
    let mut subtree_flops = own_flops;
    for d in 0..ns {
        if parent[d] != u32::MAX {
            let p = parent[d];
            debug_assert!((p as usize) > d, "a supernode's parent comes after it");
            children[fill[p as usize]] = d as u32;
            fill[p as usize] += 1;
            let f = subtree_flops[d];
            subtree_flops[p as usize] += f;
        }
    }
    let max_width = (0..ns).map(|s| end[s] - begin[s]).max().unwrap_or(0);
    Plan {
        upd_ptr,
        updaters,
        child_ptr,
        children,
        roots,
        subtree_flops,
        max_width,
        max_rows,
    }
}

/// The subtrees below the top separators are cut down to 1/(`SPLIT` · threads) of the flops.
const SPLIT: usize = 32;

/// Whether this machine runs the update kernel (x86-64 with AVX2 and FMA, or AVX-512).
pub fn available() -> bool {
    instr_set().is_some()
}

#[cfg(target_arch = "x86_64")]
fn instr_set() -> Option<private_gemm_x86::InstrSet> {
    if std::arch::is_x86_feature_detected!("avx512f") {
        Some(private_gemm_x86::InstrSet::Avx512)
    } else if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        Some(private_gemm_x86::InstrSet::Avx256)
    } else {
        None
    }
}

#[cfg(not(target_arch = "x86_64"))]
fn instr_set() -> Option<()> {
    None
}

/// The matrix to factor: `K − σM` read from K and (optionally) M on their shared pattern,
/// permuted by `perm` (`fwd[new] = old`, `inv[old] = new`).
pub struct Input<'a> {
    /// K (or the matrix itself), both triangles stored.
    pub k: &'a SymMatrix,
    /// M and σ; M on K's pattern or a subset of it.
    pub shift: Option<(&'a SymMatrix, f64)>,
    /// The elimination order.
    pub perm: Option<(&'a [usize], &'a [usize])>,
    /// `values[resident_from..]` are resident already (written by a [`super::factor::Prefault`]):
    /// their supernodes are not cleared first.
    pub resident_from: usize,
}

/// The values array shared by the workers: each supernode's block is written by exactly one
/// task, and read only by its ancestors' tasks, which start after it is complete.
#[derive(Clone, Copy)]
struct Shared(*mut f64, usize);
// SAFETY: see the type's description; the schedule guarantees disjoint writes and
// reads-after-completion (each task runs after its whole subtree).
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

/// Per-worker scratch: the global-to-local row map (all "none" between supernodes) and the
/// index lists of one update.
struct Work {
    g2l: Vec<usize>,
    rows: Vec<usize>,
    cols: Vec<usize>,
    mem: MemBuffer,
}

const NONE: usize = usize::MAX;

impl Work {
    fn new(n: usize, plan: &Plan) -> Work {
        Work {
            g2l: vec![NONE; n],
            rows: Vec::with_capacity(plan.max_rows),
            cols: Vec::with_capacity(plan.max_rows),
            mem: MemBuffer::new(cholesky_in_place_scratch::<f64>(
                plan.max_width,
                Par::Seq,
                Default::default(),
            )),
        }
    }
    /// Bytes of one worker's scratch.
    fn bytes(n: usize, plan: &Plan) -> usize {
        8 * (n + 2 * plan.max_rows + plan.max_width) + 4096
    }
}

/// Bytes of the scratch a factorisation with `threads` workers allocates.
pub fn workspace_bytes(n: usize, plan: &Plan, threads: usize) -> usize {
    threads.max(1) * Work::bytes(n, plan)
}

/// Factor into `values` (length `sn.len_val()`, faer's supernodal LDLᵀ layout, all zero on
/// entry: the caller's fresh zeroed allocation, whose pages need not be resident). A zero pivot
/// is returned as faer reports it (counted from 1, in elimination order).
pub fn factorize(sn: &Symbolic, plan: &Plan, input: &Input<'_>, values: &mut [f64]) -> Result<(), LdltError> {
    assert_eq!(values.len(), sn.len_val());
    let ns = sn.n_supernodes();
    let n = sn.nrows();
    let threads = rayon::current_num_threads().max(1);
    let shared = Shared(values.as_mut_ptr(), values.len());
    if threads == 1 || ns < 2 {
        let mut w = Work::new(n, plan);
        for s in 0..ns {
            node(sn, plan, input, shared, s, &mut w, Par::Seq)?;
        }
        return Ok(());
    }
    // Cut the tree: split the heaviest subtree into its children until none is heavier than
    // a share of the total that keeps every thread busy to the end; the split nodes form the
    // top, run afterwards one by one with parallel kernels. The share, 1/(3·threads) of the
    // flops: the mid-level separators stay in the subtrees, where sequential kernels run them
    // side by side, rather than one at a time with parallel kernels that split their many
    // small updates. Measured on the tet10 plates, 2 threads (factorisation, s): 0.09 → 0.086
    // at 20k DOFs, 0.57 → 0.56 at 65k, 1.77 → 1.71 at 119k, 10.3 → 9.7 at 274k, against
    // 1/(6·threads).
    let total: f64 = plan.roots.iter().map(|&r| plan.subtree_flops[r as usize]).sum();
    let limit = total / (3 * threads) as f64;
    let tq = std::time::Instant::now();
    let mut heap: std::collections::BinaryHeap<(u64, u32)> = plan
        .roots
        .iter()
        .map(|&r| (plan.subtree_flops[r as usize] as u64, r))
        .collect();
    let mut top: Vec<usize> = split_heaviest(plan, &mut heap, limit)
        .into_iter()
        .map(|s| s as usize)
        .collect();
    // The subtrees are split further, down to a share of the flops that leaves the last tasks
    // small: the supernodes split off here (the mid-level separators) run alone with
    // sequential kernels once their children are complete, on whichever worker is free. With
    // whole subtrees of ~1/6 of the flops, a worker slowed for a while (a core the host took)
    // left the other idle at the end for up to the length of one subtree (0.25–0.3 s of the
    // 119k-DOF factorisation's 1.5 s of subtrees).
    let fine = total / (SPLIT * threads) as f64;
    let mid = split_heaviest(plan, &mut heap, fine);
    // Tasks: the subtrees (whole) and the mid-level supernodes (alone); each waits for its
    // children in the tree. Priority: the flops from the task up through its mid-level
    // ancestors (the longest chain first, then the heaviest subtree).
    let subtrees: Vec<u32> = heap.into_vec().into_iter().map(|(_, r)| r).collect();
    let tasks: Vec<u32> = subtrees.iter().chain(&mid).copied().collect();
    let mut task_of = vec![u32::MAX; ns];
    for (t, &s) in tasks.iter().enumerate() {
        task_of[s as usize] = t as u32;
    }
    let mut parent: Vec<Option<usize>> = vec![None; tasks.len()];
    for (t, &m) in tasks.iter().enumerate().skip(subtrees.len()) {
        let m = m as usize;
        for &c in &plan.children[plan.child_ptr[m]..plan.child_ptr[m + 1]] {
            parent[task_of[c as usize] as usize] = Some(t);
        }
    }
    let own = |t: usize| {
        let s = tasks[t] as usize;
        if t < subtrees.len() {
            plan.subtree_flops[s]
        } else {
            let below: f64 = plan.children[plan.child_ptr[s]..plan.child_ptr[s + 1]]
                .iter()
                .map(|&c| plan.subtree_flops[c as usize])
                .sum();
            plan.subtree_flops[s] - below
        }
    };
    let priority: Vec<u64> = (0..tasks.len())
        .map(|t| {
            let mut chain = own(t);
            let mut a = parent[t];
            while let Some(p) = a {
                chain += own(p);
                a = parent[p];
            }
            chain as u64
        })
        .collect();
    let pool = std::sync::Mutex::new(Vec::<Work>::new());
    let take = || {
        pool.lock()
            .ok()
            .and_then(|mut p| p.pop())
            .unwrap_or_else(|| Work::new(n, plan))
    };
    crate::util::queue::forest(&parent, &priority, |t| {
        let mut w = take();
        let root = tasks[t];
        let r = if t < subtrees.len() {
            // The subtree's supernodes, ascending (children before parents).
            let mut nodes = Vec::new();
            let mut stack = vec![root];
            while let Some(s) = stack.pop() {
                nodes.push(s);
                let s = s as usize;
                stack.extend_from_slice(&plan.children[plan.child_ptr[s]..plan.child_ptr[s + 1]]);
            }
            nodes.sort_unstable();
            nodes
                .iter()
                .try_for_each(|&s| node(sn, plan, input, shared, s as usize, &mut w, Par::Seq))
        } else {
            node(sn, plan, input, shared, root as usize, &mut w, Par::Seq)
        };
        if let Ok(mut p) = pool.lock() {
            p.push(w);
        }
        r
    })?;
    let t_sub = tq.elapsed().as_secs_f64();
    let ntop = top.len();
    top.sort_unstable();
    let mut w = take();
    for s in top {
        node(sn, plan, input, shared, s, &mut w, Par::rayon(0))?;
    }
    log::debug!(
        "subtrees {t_sub:.3} s ({} whole, {} mid-level supernodes), {ntop} top nodes {:.3} s",
        subtrees.len(),
        mid.len(),
        tq.elapsed().as_secs_f64() - t_sub
    );
    Ok(())
}

/// Split the heaviest subtree of `heap` (flops, root) into its children until none is heavier
/// than `limit`; the roots split, in the order split.
fn split_heaviest(plan: &Plan, heap: &mut std::collections::BinaryHeap<(u64, u32)>, limit: f64) -> Vec<u32> {
    let mut split = Vec::new();
    while let Some(&(w, s)) = heap.peek() {
        if (w as f64) <= limit {
            break;
        }
        heap.pop();
        split.push(s);
        let s = s as usize;
        for &c in &plan.children[plan.child_ptr[s]..plan.child_ptr[s + 1]] {
            heap.push((plan.subtree_flops[c as usize] as u64, c));
        }
    }
    split
}

/// Factor supernode `s`: gather its columns of the matrix, subtract the updates of its
/// descendants (all complete), factor the diagonal block and solve for the rows below.
fn node(
    sn: &Symbolic,
    plan: &Plan,
    input: &Input<'_>,
    shared: Shared,
    s: usize,
    w: &mut Work,
    par: Par,
) -> Result<(), LdltError> {
    let cp = sn.col_ptr_for_val();
    let (s_start, s_end) = (sn.supernode_begin()[s], sn.supernode_end()[s]);
    let s_pattern = sn.supernode(s).pattern();
    let s_ncols = s_end - s_start;
    let s_nrows = s_ncols + s_pattern.len();
    debug_assert!(cp[s + 1] <= shared.1);
    // SAFETY: supernode s's block is written by this task only (see `Shared`).
    let ls_vals = unsafe { std::slice::from_raw_parts_mut(shared.0.add(cp[s]), cp[s + 1] - cp[s]) };
    // The block is zero already, but a page of it never written is the shared zero page: the
    // first `+=` below would read it there and fault again to write, flushing the other
    // threads' TLBs (4× the system time of the 119k-DOF factorisation). Written once here, the
    // pages are the block's own (the part a prefault made resident needs nothing).
    let clear = input.resident_from.saturating_sub(cp[s]).min(ls_vals.len());
    ls_vals[..clear].fill(0.0);
    for (i, &row) in s_pattern.iter().enumerate() {
        w.g2l[row] = i + s_ncols;
    }
    // The matrix's columns, lower part in elimination order: K, then −σM from M's own pattern
    // (a subset of K's: each of its rows is one of K's). `c·a` with c = 1 is `a` exactly, and
    // adding (−σ)·m is subtracting σ·m: the same bits as one pass over K − σM.
    for j in s_start..s_end {
        let jl = j - s_start;
        let c_old = input.perm.map_or(j, |(fwd, _)| fwd[j]);
        let terms = std::iter::once((input.k, 1.0)).chain(input.shift.map(|(m, sigma)| (m, -sigma)));
        for (a, c) in terms {
            let pat = &a.pattern;
            for pos in pat.col_ptr[c_old]..pat.col_ptr[c_old + 1] {
                let i = input
                    .perm
                    .map_or(pat.row_idx[pos] as usize, |(_, inv)| inv[pat.row_idx[pos] as usize]);
                if i < j {
                    continue;
                }
                let il = if i < s_end { i - s_start } else { w.g2l[i] };
                ls_vals[il + jl * s_nrows] += c * a.values[pos];
            }
        }
    }
    // Updates from the descendants, in ascending order (faer's). (Splitting a top supernode's
    // updates by column ranges across threads was measured slower than parallel kernels: every
    // range packs each descendant's block again.)
    for &d in &plan.updaters[plan.upd_ptr[s]..plan.upd_ptr[s + 1]] {
        let d = d as usize;
        let (ld, d_nrows, d_ncols, d_pattern) = block(sn, shared, d);
        let p0 = d_pattern.partition_point(|&r| r < s_start);
        let mid = d_pattern[p0..].partition_point(|&r| r < s_end);
        w.rows.clear();
        w.cols.clear();
        for (i, &r) in d_pattern[p0..].iter().enumerate() {
            w.rows.push(if i < mid { r - s_start } else { w.g2l[r] });
        }
        for &r in &d_pattern[p0..p0 + mid] {
            w.cols.push(r - s_start);
        }
        update(
            ls_vals, s_nrows, s_ncols, ld, d_nrows, d_ncols, p0, mid, &w.rows, &w.cols, par,
        );
    }
    // The row map is not needed past the updates: leave it all "none" for the next supernode.
    for &row in s_pattern {
        w.g2l[row] = NONE;
    }
    // Dense LDLᵀ of the diagonal block; L below it.
    let ls = MatMut::from_column_major_slice_mut(ls_vals, s_nrows, s_ncols);
    let (mut top, mut bot) = ls.split_at_row_mut(s_ncols);
    let stack = MemStack::new(&mut w.mem);
    let res = cholesky_in_place(
        top.as_mut(),
        LdltRegularization::default(),
        par,
        stack,
        Default::default(),
    );
    if let Err(LdltError::ZeroPivot { index }) = res {
        return Err(LdltError::ZeroPivot { index: index + s_start });
    }
    for j in 0..s_ncols {
        for i in 0..j {
            top[(i, j)] = 0.0;
        }
    }
    faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(
        top.as_ref(),
        bot.as_mut().transpose_mut(),
        par,
    );
    for j in 0..s_ncols {
        let d = top[(j, j)].recip();
        for i in 0..s_pattern.len() {
            bot[(i, j)] *= d;
        }
    }
    Ok(())
}

/// A complete descendant's block: values, rows, columns, off-diagonal pattern.
fn block(sn: &Symbolic, shared: Shared, d: usize) -> (&[f64], usize, usize, &[usize]) {
    let cp = sn.col_ptr_for_val();
    let d_pattern = sn.supernode(d).pattern();
    let d_ncols = sn.supernode_end()[d] - sn.supernode_begin()[d];
    // SAFETY: only called for descendants of the supernode being factored, all complete
    // before its task started; only read.
    let ld = unsafe { std::slice::from_raw_parts(shared.0.add(cp[d]) as *const f64, cp[d + 1] - cp[d]) };
    (ld, d_ncols + d_pattern.len(), d_ncols, d_pattern)
}

/// `Ls[rows, cols] −= L_d[p0.., :] · D_d · L_d[p0..p0+mid, :]ᵀ` on the lower triangle (faer's
/// supernodal update, through the same kernel).
#[allow(clippy::too_many_arguments)]
fn update(
    ls: &mut [f64],
    s_nrows: usize,
    s_ncols: usize,
    ld: &[f64],
    d_nrows: usize,
    d_ncols: usize,
    p0: usize,
    mid: usize,
    rows: &[usize],
    cols: &[usize],
    par: Par,
) {
    let nrows = rows.len();
    if nrows == 0 || mid == 0 || d_ncols == 0 {
        return;
    }
    debug_assert!(ls.len() >= s_nrows * s_ncols && ld.len() >= d_nrows * d_ncols);
    let par = if (nrows * mid).saturating_mul(d_ncols) > 32 * 32 * 32 {
        par
    } else {
        Par::Seq
    };
    #[cfg(target_arch = "x86_64")]
    if let Some(instr) = instr_set() {
        use private_gemm_x86 as pg;
        let a = ld[d_ncols + p0..].as_ptr(); // rows d_ncols+p0.., column-major, stride d_nrows
        let minus_one = -1.0f64;
        // SAFETY: every index is inside the blocks (checked by construction: rows index the
        // supernode's rows, cols its columns, and the operands are views of d's block); the
        // kernel reads A (nrows × d_ncols), B = L_d[mid rows]ᵀ (d_ncols × mid) and the
        // diagonal, and adds into Ls at (rows[i], cols[j]) for rows[i] ≥ cols[j].
        unsafe {
            pg::gemm(
                pg::DType::F64,
                pg::IType::U64,
                instr,
                nrows,
                mid,
                d_ncols,
                ls.as_mut_ptr() as *mut (),
                1,
                s_nrows as isize,
                rows.as_ptr() as *const (),
                cols.as_ptr() as *const (),
                pg::DstKind::Lower,
                pg::Accum::Add,
                a as *const (),
                1,
                d_nrows as isize,
                false,
                ld.as_ptr() as *const (),
                (d_nrows + 1) as isize,
                a as *const (),
                d_nrows as isize,
                1,
                false,
                &raw const minus_one as *const (),
                par.degree(),
            );
        }
        return;
    }
    // Portable path (not reached: `available()` gates this module).
    let a = |i: usize, k: usize| ld[d_ncols + p0 + i + k * d_nrows];
    for (jj, &cj) in cols.iter().enumerate() {
        for (ii, &ri) in rows.iter().enumerate() {
            if ri < cj {
                continue;
            }
            let mut acc = 0.0;
            for k in 0..d_ncols {
                acc += a(ii, k) * ld[k * d_nrows + k] * a(jj, k);
            }
            ls[ri + cj * s_nrows] -= acc;
        }
    }
}
