//! Sparse LDLᵀ factorisation of symmetric matrices (faer supernodal), with inertia.
//!
//! One [`SymbolicFactor`] (ordering + elimination structure) serves every numeric
//! factorisation on the same pattern: K − σM for the eigen shift and for the Sturm checks.
//! LDLᵀ without pivoting is used for both SPD and indefinite matrices; its count of negative
//! pivots is the inertia that the Sturm-sequence check needs (Sylvester's law of inertia).

use crate::linalg::floor::SolveWork;
use crate::linalg::sparse::{Pattern, SymMatrix};
use crate::linalg::supernodal;
use crate::linalg::trisolve::{self, SolvePlan};
use crate::{Error, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLdltRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::{Conj, MatMut, Par, Side};
use std::sync::{Arc, Mutex};

/// Ordering and elimination structure, computed once per pattern.
pub struct SymbolicFactor {
    sym: SymbolicCholesky<usize>,
    /// Floating-point operations of one numeric factorisation (multiply and add counted
    /// separately: Σ_j c_j² over the columns of L, c_j its entries including the diagonal).
    pub flops: f64,
    /// Entries of L.
    pub nnz_l: usize,
    /// Schedule of the subtree-parallel numeric factorisation ([`supernodal`]), for supernodal
    /// structures on machines that run its kernel; otherwise faer factorises.
    plan: Option<supernodal::Plan>,
    /// The elimination tree's cut for block solves ([`trisolve`]), built on first use.
    solve_plan: std::sync::OnceLock<SolvePlan>,
}

impl SymbolicFactor {
    /// Symbolic analysis of `pattern` with the permutation `fwd` (`fwd[new] = old`).
    pub fn new(pattern: &Pattern, perm: Option<(&[usize], &[usize])>) -> Result<Self> {
        let ord = match perm {
            Some((fwd, inv)) => SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, pattern.n)),
            None => SymmetricOrdering::Amd,
        };
        let structure = pattern.to_faer();
        let sym = factorize_symbolic_cholesky(structure.as_ref(), Side::Upper, ord, CholeskySymbolicParams::default())
            .map_err(|e| Error::Factorization(format!("symbolic analysis: {e:?}")))?;
        let (flops, nnz_l) = count_flops(&sym);
        let plan = match sym.raw() {
            SymbolicCholeskyRaw::Supernodal(sn) if supernodal::available() => Some(supernodal::plan(sn)),
            _ => None,
        };
        let f = SymbolicFactor {
            sym,
            flops,
            nnz_l,
            plan,
            solve_plan: std::sync::OnceLock::new(),
        };
        // Every numeric factorisation of a supernodal structure is packed for the block solves
        // by this plan, which depends on the structure alone: made here, alongside the
        // assembly, rather than between the first factorisation and its solves (0.03 s at
        // 119k DOFs).
        if let SymbolicCholeskyRaw::Supernodal(sn) = f.sym.raw() {
            let _ = f.solve_plan(sn);
        }
        Ok(f)
    }

    /// Whether numeric factorisations of `K − σM` read K and M directly (the subtree-parallel
    /// factorisation) rather than a shifted matrix built for them (faer's).
    pub fn reads_k_and_m(&self) -> bool {
        self.plan.is_some()
    }

    /// The cut of the elimination tree for block solves and the packed layout, made at first
    /// use (`sn` is this structure's supernodal part).
    fn solve_plan(&self, sn: &trisolve::SupernodalSymbolic) -> &SolvePlan {
        self.solve_plan.get_or_init(|| SolvePlan::new(sn))
    }

    /// Bytes the numeric factor's values will take.
    pub fn factor_bytes(&self) -> usize {
        self.sym.len_val() * std::mem::size_of::<f64>()
    }
}

/// Column counts of L from the symbolic structure, and the resulting flop count.
fn count_flops(sym: &SymbolicCholesky<usize>) -> (f64, usize) {
    let mut flops = 0.0f64;
    let mut nnz = 0usize;
    match sym.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let cp = s.col_ptr();
            for j in 0..s.nrows() {
                let c = (cp[j + 1] - cp[j]) as f64;
                flops += c * c;
                nnz += cp[j + 1] - cp[j];
            }
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            for k in 0..s.n_supernodes() {
                let w = s.supernode_end()[k] - s.supernode_begin()[k];
                let p = s.supernode(k).pattern().len();
                for i in 0..w {
                    let c = (w - i + p) as f64;
                    flops += c * c;
                    nnz += w - i + p;
                }
            }
        }
    }
    (flops, nnz)
}

/// A numeric LDLᵀ factorisation.
pub struct Factor {
    sym: Arc<SymbolicFactor>,
    values: Vec<f64>,
    /// Number of negative pivots (eigenvalues of the factored matrix below zero).
    pub negative_pivots: usize,
    /// Smallest and largest pivot magnitude (a ratio near machine precision means the
    /// matrix is numerically singular).
    pub pivot_range: (f64, f64),
    /// Smallest |pivot| relative to the matrix's own diagonal entry in that position: at
    /// rounding level when the matrix is singular, e.g. a shift on an eigenvalue.
    pub min_rel_pivot: f64,
    /// Backward error ‖A y − b‖/‖b‖ of a probe solve (b = A x for a fixed pseudo-random x):
    /// near rounding for a stable factorisation; large after pivot growth (an unpivoted LDLᵀ of
    /// an indefinite matrix can be unstable), when results must not be trusted.
    pub probe_residual: f64,
    /// Bytes of the numeric factorisation's scratch (freed when it returns).
    pub factor_workspace_bytes: usize,
    /// Bytes of the shifted matrix built for the factorisation (0 when it was read from K
    /// and M directly).
    pub shifted_matrix_bytes: usize,
    /// Seconds of the numeric factorisation itself (nothing around it).
    pub numeric_seconds: f64,
    /// Solve workspaces kept between calls (one per concurrent column group).
    scratch: Mutex<Vec<Vec<f64>>>,
    /// The block solves done since the last [`Factor::take_solve_work`].
    solves: Mutex<SolveWork>,
    /// A supernodal factor's values back in faer's layout, made at the first call of faer's
    /// own solve (a reference for tests and benchmarks) and kept for the next.
    unpacked: std::sync::OnceLock<Vec<f64>>,
}

/// Run `f` on worker threads of its own (as many as the current pool has), which end when it
/// returns. The dense kernels of the factorisation keep a packing buffer per thread, sized
/// from the L3 cache (64 MiB reserved here, of which the large updates touch a part) and never
/// freed while the thread lives: on threads that end, it does not stay resident beside the
/// factor and the Lanczos basis (16 MiB less resident after the factorisation of the 119k-DOF
/// plate).
fn on_own_threads<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    match rayon::ThreadPoolBuilder::new()
        .num_threads(rayon::current_num_threads())
        .thread_name(|i| format!("factor-{i}"))
        .build()
    {
        Ok(pool) => pool.install(f),
        // No thread to be had: the current pool then (the buffers stay, the result is the same).
        Err(_) => f(),
    }
}

impl Factor {
    /// Factor `a` (stored symmetric).
    pub fn new(sym: Arc<SymbolicFactor>, a: &SymMatrix) -> Result<Self> {
        Self::new_shifted(sym, a, None)
    }

    /// Factor `K − σM` for `shift = Some((M, σ))` (K alone for `None`). The subtree-parallel
    /// factorisation reads the entries straight from K and M; faer's (simplicial structures,
    /// or machines without the kernel) is given the shifted matrix, built for it.
    pub fn new_shifted(sym: Arc<SymbolicFactor>, k: &SymMatrix, shift: Option<(&SymMatrix, f64)>) -> Result<Self> {
        Self::factorise_into(sym, k, shift, true, None)
    }

    /// faer's own numeric factorisation of `a` (a reference for tests and benchmarks of the
    /// subtree-parallel one, which should give the same values).
    pub fn new_faer(sym: Arc<SymbolicFactor>, a: &SymMatrix) -> Result<Self> {
        Self::factorise_into(sym, a, None, false, None)
    }

    /// [`Factor::new_shifted`] into the zeroed buffer of a [`Prefault`] of the same structure
    /// (its pages made resident ahead, while the machine had a thread to spare).
    pub fn new_shifted_prefaulted(
        sym: Arc<SymbolicFactor>,
        k: &SymMatrix,
        shift: Option<(&SymMatrix, f64)>,
        buffer: Prefault,
    ) -> Result<Self> {
        let values = buffer.finish();
        Self::factorise_into(sym, k, shift, true, values)
    }

    /// Factor into `buffer` (a zeroed buffer of the structure's length and the index from
    /// which its pages are resident) or a fresh allocation; `own`: the subtree-parallel
    /// factorisation where the structure has its plan, else faer's.
    fn factorise_into(
        sym: Arc<SymbolicFactor>,
        k: &SymMatrix,
        shift: Option<(&SymMatrix, f64)>,
        own: bool,
        buffer: Option<(Vec<f64>, usize)>,
    ) -> Result<Self> {
        let t0 = std::time::Instant::now();
        let (buffer, resident_from) = match buffer.filter(|(b, _)| b.len() == sym.sym.len_val()) {
            Some((b, from)) => (Some(b), from),
            None => (None, usize::MAX),
        };
        let mut values = buffer.or_else(|| zeroed(sym.sym.len_val())).ok_or_else(|| {
            Error::Factorization(format!(
                "cannot allocate the factor ({:.1} GiB)",
                sym.factor_bytes() as f64 / (1u64 << 30) as f64
            ))
        })?;
        let perm = sym.sym.perm().map(|p| p.arrays());
        let mut shifted_matrix_bytes = 0;
        let (factor_workspace_bytes, res) = match (&sym.plan, sym.sym.raw()) {
            (Some(plan), SymbolicCholeskyRaw::Supernodal(sn)) if own => {
                let input = supernodal::Input {
                    k,
                    shift,
                    perm,
                    resident_from,
                };
                let ws = supernodal::workspace_bytes(k.n(), plan, rayon::current_num_threads()) + plan.bytes();
                (
                    ws,
                    on_own_threads(|| supernodal::factorize(sn, plan, &input, &mut values)),
                )
            }
            _ => {
                let shifted;
                let a = match shift {
                    Some((m, sigma)) => {
                        shifted = k.sub_scaled(sigma, m);
                        shifted_matrix_bytes = 8 * shifted.values.len();
                        &shifted
                    }
                    None => k,
                };
                let par = Par::rayon(0);
                let req = sym.sym.factorize_numeric_ldlt_scratch::<f64>(par, Default::default());
                let ws = req.unaligned_bytes_required();
                let mut mem = MemBuffer::try_new(req)
                    .map_err(|_| Error::Factorization("cannot allocate factor workspace".into()))?;
                let stack = MemStack::new(&mut mem);
                let structure = a.pattern.to_faer();
                let r = sym
                    .sym
                    .factorize_numeric_ldlt(
                        &mut values,
                        faer::sparse::SparseColMatRef::new(structure.as_ref(), &a.values),
                        Side::Upper,
                        LdltRegularization::default(),
                        par,
                        stack,
                        Default::default(),
                    )
                    .map(|_| ());
                (ws, r)
            }
        };
        res.map_err(|e| {
            // A zero pivot names its column of the permuted matrix: map it back to the
            // equation so the model layer can name the node and component.
            let equation = match e {
                faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index } => {
                    // faer counts the failing pivot from 1.
                    let index = index.saturating_sub(1);
                    Some(perm.map_or(index, |(fwd, _)| fwd.get(index).copied().unwrap_or(index)))
                }
            };
            Error::Singular {
                equation,
                at: None,
                msg: format!("LDLᵀ: zero pivot, the matrix is singular ({e:?})"),
            }
        })?;
        let numeric_seconds = t0.elapsed().as_secs_f64();
        log::info!(
            "factorised K − σM: {} entries in L, {:.3e} flop, {numeric_seconds:.2} s",
            sym.nnz_l,
            sym.flops,
        );
        let Pivots {
            negative_pivots,
            range: (lo, hi),
            min_rel_pivot,
        } = pivots(&sym.sym, &values, k, shift)?;
        // The solves read each diagonal block from the panel's diagonal down: drop the rest
        // (~15 % of faer's layout on a 3D solid) before the iteration allocates its basis.
        if let SymbolicCholeskyRaw::Supernodal(sn) = sym.sym.raw() {
            let t_pack = std::time::Instant::now();
            let before = values.len();
            trisolve::pack(sn, sym.solve_plan(sn), &mut values);
            log::debug!(
                "factor packed for the solves: {} → {} MB in {:.3} s; resident now {} MiB",
                8 * before / 1_000_000,
                8 * values.len() / 1_000_000,
                t_pack.elapsed().as_secs_f64(),
                crate::util::memory::resident_memory().unwrap_or(0) >> 20
            );
        }
        Ok(Factor {
            sym,
            values,
            negative_pivots,
            pivot_range: (lo, hi),
            min_rel_pivot,
            probe_residual: 0.0,
            factor_workspace_bytes,
            shifted_matrix_bytes,
            numeric_seconds,
            scratch: Mutex::new(Vec::new()),
            solves: Mutex::new(SolveWork::default()),
            unpacked: std::sync::OnceLock::new(),
        })
    }

    /// True for a supernodal factor (solved by [`trisolve`]); small or very sparse
    /// factors are simplicial (solved by faer).
    pub fn is_supernodal(&self) -> bool {
        matches!(self.sym.sym.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    /// Bytes of the factor's values as the numeric factorisation held them (faer's layout,
    /// before a supernodal factor is packed).
    pub fn factorisation_bytes(&self) -> usize {
        self.sym.factor_bytes()
    }

    /// Bytes of the factor's values (packed when supernodal).
    pub fn bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<f64>()
    }

    /// How block solves with this factor are split between threads (`None` for a simplicial
    /// factor, solved by faer).
    pub fn solve_layout(&self) -> Option<trisolve::SolveLayout> {
        let SymbolicCholeskyRaw::Supernodal(sn) = self.sym.sym.raw() else {
            return None;
        };
        Some(self.sym.solve_plan(sn).layout)
    }

    /// Bytes of the solve workspaces kept between calls.
    pub fn workspace_bytes(&self) -> usize {
        self.scratch
            .lock()
            .map_or(0, |s| s.iter().map(|w| 8 * w.capacity()).sum())
    }

    /// Solve `A X = B` in place for a block of right-hand sides. Supernodal factors use
    /// [`trisolve`]: column groups of at most [`MAX_GROUP`] one after the other, each solved by
    /// all worker threads with one pass over the factor per direction, workspaces kept with the
    /// factor. Each column's arithmetic is the same whatever group it is solved in and whatever
    /// the thread count, bit for bit. Simplicial (small or very sparse) factors are solved by
    /// faer.
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let k = rhs.ncols();
        if k == 0 {
            return;
        }
        let t = std::time::Instant::now();
        let SymbolicCholeskyRaw::Supernodal(_) = self.sym.sym.raw() else {
            self.solve_faer(rhs);
            return self.count_solves(1, k, t);
        };
        let per = k.div_ceil(k.div_ceil(MAX_GROUP));
        let mut rhs = rhs;
        let mut c0 = 0;
        while c0 < k {
            let cols = per.min(k - c0);
            self.solve_group(rhs.as_mut().subcols_mut(c0, cols));
            c0 += cols;
        }
        self.count_solves(k.div_ceil(per), k, t);
    }

    /// Counts a solve of `columns` right-hand sides in `passes` passes over the factor (each
    /// reads every value once forward and once backward), started at `t`.
    fn count_solves(&self, passes: usize, columns: usize, t: std::time::Instant) {
        if let Ok(mut w) = self.solves.lock() {
            w.add(&SolveWork {
                passes,
                columns,
                bytes: (2 * passes * self.bytes()) as f64,
                seconds: t.elapsed().as_secs_f64(),
            });
        }
    }

    /// The block solves done with this factor since the last call (the counts restart).
    pub fn take_solve_work(&self) -> SolveWork {
        self.solves
            .lock()
            .map(|mut w| std::mem::take(&mut *w))
            .unwrap_or_default()
    }

    /// Read bandwidth over this factor's values (GB/s) and the seconds its measurement took
    /// ([`crate::linalg::floor::read_rate`]).
    pub fn read_rate(&self) -> (f64, f64) {
        crate::linalg::floor::read_rate(&self.values)
    }

    /// faer's own sequential supernodal solve (a reference for tests and benchmarks: it rounds
    /// differently from [`Factor::solve_in_place`]). A supernodal factor keeps a copy of its
    /// values in faer's layout from the first call on.
    pub fn solve_in_place_faer(&self, rhs: MatMut<'_, f64>) {
        if rhs.ncols() > 0 {
            self.solve_faer(rhs);
        }
    }

    /// faer's solve (simplicial factors; a supernodal one is unpacked into faer's layout first).
    fn solve_faer(&self, rhs: MatMut<'_, f64>) {
        let par = Par::Seq;
        let req = self.sym.sym.solve_in_place_scratch::<f64>(rhs.ncols(), par);
        let mut mem = MemBuffer::new(req);
        let stack = MemStack::new(&mut mem);
        let values = match self.sym.sym.raw() {
            SymbolicCholeskyRaw::Supernodal(sn) => self
                .unpacked
                .get_or_init(|| trisolve::unpack(sn, self.sym.solve_plan(sn), &self.values)),
            SymbolicCholeskyRaw::Simplicial(_) => &self.values,
        };
        LdltRef::new(&self.sym.sym, values).solve_in_place_with_conj(Conj::No, rhs, par, stack);
    }

    /// One group of at most [`MAX_GROUP`] columns: permuted into a row-major workspace (kept
    /// for the next call), solved, permuted back.
    fn solve_group(&self, mut rhs: MatMut<'_, f64>) {
        let SymbolicCholeskyRaw::Supernodal(sn) = self.sym.sym.raw() else {
            return self.solve_faer(rhs);
        };
        let (n, k) = (rhs.nrows(), rhs.ncols());
        let need = n * k;
        let pooled = self.scratch.lock().ok().and_then(|mut pool| {
            let i = pool.iter().position(|w| w.len() >= need)?;
            Some(pool.swap_remove(i))
        });
        let mut x = pooled.unwrap_or_else(|| vec![0.0; need]);
        let plan = self.sym.solve_plan(sn);
        let perm = self.sym.sym.perm().map(|p| p.arrays());
        for c in 0..k {
            let col = rhs.as_ref().col(c);
            for i in 0..n {
                let src = perm.map_or(i, |(fwd, _)| fwd[i]);
                x[i * k + c] = col[src];
            }
        }
        macro_rules! go {
            ($($kk:literal)*) => {
                match k {
                    $($kk => trisolve::solve::<$kk>(sn, plan, &self.values, x[..need].as_chunks_mut::<$kk>().0),)*
                    _ => unreachable!("column groups hold at most {MAX_GROUP} columns"),
                }
            };
        }
        go!(1 2 3 4 5 6 7 8 9 10 11 12);
        for c in 0..k {
            let mut col = rhs.as_mut().col_mut(c);
            for i in 0..n {
                let src = perm.map_or(i, |(_, inv)| inv[i]);
                col[i] = x[src * k + c];
            }
        }
        if let Ok(mut pool) = self.scratch.lock() {
            pool.push(x);
        }
    }

    /// Measure [`Factor::probe_residual`] against the matrix that was factorised: `K − σM` for
    /// `shift = Some((M, σ))`, K alone for `None`.
    pub fn probe_shifted(&mut self, k: &SymMatrix, shift: Option<(&SymMatrix, f64)>) {
        let b = Self::probe_rhs(k, shift);
        let mut y = faer::Mat::from_fn(b.len(), 1, |i, _| b[i]);
        self.solve_in_place(y.as_mut());
        self.probe_residual = Self::probe_error(k, shift, &b, y.col(0).try_as_col_major().unwrap().as_slice());
    }

    /// The probe's right-hand side b = A x, x a fixed pseudo-random vector, A = K − σM (K for
    /// `shift = None`): a caller may solve it along with other columns and pass the solution to
    /// [`Factor::probe_error`] (what [`Factor::probe_shifted`] does with a solve of its own).
    pub fn probe_rhs(k: &SymMatrix, shift: Option<(&SymMatrix, f64)>) -> Vec<f64> {
        let n = k.n();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let x: Vec<f64> = (0..n)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        Self::shifted_product(k, shift, &x)
    }

    /// The probe's backward error ‖A y − b‖/‖b‖ for the computed solution `y` of A y = b.
    pub fn probe_error(k: &SymMatrix, shift: Option<(&SymMatrix, f64)>, b: &[f64], y: &[f64]) -> f64 {
        let ay = Self::shifted_product(k, shift, y);
        let num: f64 = ay.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum::<f64>().sqrt();
        let den: f64 = b.iter().map(|q| q * q).sum::<f64>().sqrt();
        if den > 0.0 { num / den } else { 0.0 }
    }

    /// (K − σM) x, or K x without a shift.
    fn shifted_product(k: &SymMatrix, shift: Option<(&SymMatrix, f64)>, x: &[f64]) -> Vec<f64> {
        let mut y = k.mul_vec(x);
        if let Some((m, sigma)) = shift {
            for (a, b) in y.iter_mut().zip(m.mul_vec(x)) {
                *a -= sigma * b;
            }
        }
        y
    }

    /// The factor's values (faer's simplicial layout, or the packed supernodal one of
    /// [`trisolve`]), for comparisons in tests.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The symbolic part.
    pub fn symbolic(&self) -> &Arc<SymbolicFactor> {
        &self.sym
    }
}

/// Most right-hand sides solved together (one pass over the factor per direction): the 19–21
/// columns of a refinement make two groups.
const MAX_GROUP: usize = 12;

/// A factor's zeroed buffer whose pages a low-priority thread makes resident ahead of the
/// factorisation, from the end (the top separators, factored one at a time) towards the
/// front, until [`Prefault::finish`]. Every page reads zero whether or not it was reached.
///
/// A page's first write costs the system its zeroing and mapping (~0.45 ms per MB on this
/// 2-core box): the 716 MB of the 119k-DOF plate's factor took 0.32 thread-seconds inside the
/// factorisation, 0.075 s of it in the top separators, cleared one at a time. Started before
/// the coarse estimate, whose solves leave a core partly idle, the thread makes all of it
/// resident in time (factorisation 2.24 → 2.09 s with the coarse estimate, medians of five).
pub struct Prefault {
    values: Option<Vec<f64>>,
    stop: Arc<std::sync::atomic::AtomicBool>,
    worker: Option<std::thread::JoinHandle<usize>>,
    /// Pages made resident, once the thread is joined.
    done: usize,
}

impl Prefault {
    /// Start on a buffer for `sym`'s factor. `None` for a factor not factored by
    /// [`supernodal`], or when the system has less than twice the factor's bytes available
    /// (the buffer is resident before the coarse model is freed; an allocation that fails
    /// later is reported by the factorisation itself).
    pub fn start(sym: &SymbolicFactor) -> Option<Prefault> {
        if !sym.reads_k_and_m() {
            return None;
        }
        let room = crate::util::memory::memory_budget(None).map_or(0, |b| b.bytes);
        if room < 2 * sym.factor_bytes() as u64 {
            return None;
        }
        Self::start_limited(sym, usize::MAX)
    }

    /// [`Prefault::start`] without its checks, making at most `bytes` resident (whole pages,
    /// from the end). `None` when the buffer cannot be allocated.
    pub fn start_limited(sym: &SymbolicFactor, bytes: usize) -> Option<Prefault> {
        let len = sym.sym.len_val();
        let mut values = zeroed(len)?;
        let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let (ptr, flag) = (values.as_mut_ptr() as usize, stop.clone());
        // Entry `len − 1 − 512·i` for i = 0, 1, …: one in each 4 KiB page from the last down.
        let pages = len.div_ceil(512).min(bytes / 4096);
        let worker = std::thread::Builder::new()
            .name("prefault".into())
            .spawn(move || {
                crate::util::memory::lower_thread_priority();
                let mut done = 0;
                while done < pages && !flag.load(std::sync::atomic::Ordering::Relaxed) {
                    for _ in 0..64.min(pages - done) {
                        // SAFETY: `len − 1 − 512·done ≥ 0` inside the buffer, which no other
                        // thread touches until this one is joined; zero over zero.
                        unsafe { std::ptr::write_volatile((ptr as *mut f64).add(len - 1 - 512 * done), 0.0) };
                        done += 1;
                    }
                }
                done
            })
            .ok();
        Some(Prefault {
            values: Some(values),
            stop,
            worker,
            done: 0,
        })
    }

    /// Wait until the thread has made its share resident.
    pub fn wait(mut self) -> Prefault {
        self.join(false);
        self
    }

    /// Stop the thread and hand over the buffer with the index from which its pages are
    /// resident (`len` when none is).
    pub fn finish(mut self) -> Option<(Vec<f64>, usize)> {
        self.join(true);
        let values = self.values.take()?;
        let from = match self.done {
            0 => values.len(),
            d => values.len() + 511 - 512 * d,
        };
        Some((values, from))
    }

    fn join(&mut self, stop: bool) {
        self.stop.store(stop, std::sync::atomic::Ordering::Relaxed);
        if let Some(w) = self.worker.take() {
            self.done = w.join().unwrap_or(0);
            log::debug!("prefault: {} MiB of the factor made resident ahead", self.done >> 8);
        }
    }
}

impl Drop for Prefault {
    fn drop(&mut self) {
        self.join(true);
    }
}

/// A zeroed vector of `len` values, or `None` when it cannot be allocated. The allocator's
/// zeroed memory is used, so a large factor's pages are zero-filled by the system when first
/// written (in parallel, by the workers that factor them) rather than by one pass here.
fn zeroed(len: usize) -> Option<Vec<f64>> {
    if len == 0 {
        return Some(Vec::new());
    }
    let layout = std::alloc::Layout::array::<f64>(len).ok()?;
    // SAFETY: the layout has a non-zero size; the pointer, if not null, is a fresh allocation
    // of `len` zeroed f64 (all-zero bits are 0.0) with the global allocator and f64's layout,
    // which is what `Vec::from_raw_parts` requires.
    unsafe {
        let p = std::alloc::alloc_zeroed(layout) as *mut f64;
        if p.is_null() {
            return None;
        }
        Some(Vec::from_raw_parts(p, len, len))
    }
}

/// What the pivots tell of a factorisation.
struct Pivots {
    negative_pivots: usize,
    /// Smallest and largest |pivot|.
    range: (f64, f64),
    /// Smallest |pivot| relative to its diagonal entry of the matrix factored.
    min_rel_pivot: f64,
}

/// The pivots of a factor of `K − σM`; an error naming the equation of a zero or non-finite one.
fn pivots(
    sym: &SymbolicCholesky<usize>,
    values: &[f64],
    k: &SymMatrix,
    shift: Option<(&SymMatrix, f64)>,
) -> Result<Pivots> {
    let d = diagonal(sym, values);
    let mut adiag = k.diagonal();
    if let Some((m, sigma)) = shift {
        for (a, b) in adiag.iter_mut().zip(m.diagonal()) {
            *a -= sigma * b;
        }
    }
    let min_rel_pivot = match sym.perm() {
        Some(perm) => {
            let (fwd, _) = perm.arrays();
            d.iter()
                .enumerate()
                .map(|(i, x)| x.abs() / adiag[fwd[i]].abs().max(f64::MIN_POSITIVE))
                .fold(f64::INFINITY, f64::min)
        }
        None => d
            .iter()
            .zip(&adiag)
            .map(|(x, a)| x.abs() / a.abs().max(f64::MIN_POSITIVE))
            .fold(f64::INFINITY, f64::min),
    };
    let negative_pivots = d.iter().filter(|&&x| x < 0.0).count();
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for &x in &d {
        lo = lo.min(x.abs());
        hi = hi.max(x.abs());
    }
    if let Some(i) = d.iter().position(|x| !x.is_finite() || *x == 0.0) {
        // Pivot i of the permuted matrix: name the equation it belongs to.
        let equation = match sym.perm() {
            Some(p) => p.arrays().0.get(i).copied().unwrap_or(i),
            None => i,
        };
        return Err(Error::Singular {
            equation: Some(equation),
            at: None,
            msg: format!(
                "{} pivot (singular matrix at this shift)",
                if d[i] == 0.0 { "zero" } else { "non-finite" }
            ),
        });
    }
    Ok(Pivots {
        negative_pivots,
        range: (lo, hi),
        min_rel_pivot,
    })
}

/// The pivots D of an LDLᵀ factor (in elimination order).
fn diagonal(sym: &SymbolicCholesky<usize>, values: &[f64]) -> Vec<f64> {
    match sym.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            // Each column of L stores its diagonal (the pivot) first.
            let cp = s.col_ptr();
            (0..s.nrows()).map(|j| values[cp[j]]).collect()
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let l = SupernodalLdltRef::new(s, values);
            let mut d = Vec::with_capacity(s.nrows());
            for k in 0..s.n_supernodes() {
                let m = l.supernode(k).val();
                for i in 0..m.ncols() {
                    d.push(m[(i, i)]);
                }
            }
            d
        }
    }
}
