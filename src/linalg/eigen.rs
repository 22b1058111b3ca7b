//! Generalised symmetric eigenproblem K x = λ M x: shift-invert block Lanczos, verified.
//!
//! # Method
//! One sparse LDLᵀ factorisation of A = K − σM. The operator Op = A⁻¹M is self-adjoint in the
//! M inner product, and its eigenvalues θ = 1/(λ − σ) are largest in magnitude for the λ
//! nearest σ. A block Krylov basis V (block size `b`, default 6) is kept M-orthonormal by full
//! reorthogonalisation (classical Gram–Schmidt, twice), the projected matrix T = VᵀM·Op·V is
//! built from the orthogonalisation coefficients, and Ritz pairs come from its dense
//! eigen-decomposition. When the basis is full it is restarted thick: the best Ritz vectors
//! are kept and the last block carries on. Block Lanczos finds every copy of an eigenvalue
//! of multiplicity up to `b` (single-vector Lanczos misses copies in exact arithmetic).
//!
//! # Verification (every run)
//! - backward error of every mode, η = ‖Kx − λMx‖ / (‖|K||x|‖ + |λ|‖|M||x|‖): the residual
//!   measured against the size of the rounding that forming Kx − λMx alone can produce. It is
//!   the acceptance test ([`EigenParams::verify_tol`]); unlike ‖Kx − λMx‖ / ‖Kx‖ (also
//!   reported) it does not grow with the conditioning (slender and thin parts, where Kx is a
//!   small difference of large terms) nor blow up for rigid-body modes (Kx ≈ 0);
//! - M-orthonormality max |XᵀMX − I|;
//! - Sturm-sequence counts: the number of negative pivots of an LDLᵀ of K − σ_c M is the
//!   number of eigenvalues below σ_c. A count at a point just above the highest reported
//!   eigenvalue (and, for a shift inside the spectrum, just below the lowest) must equal the
//!   number of modes found in between. If it does not, iteration resumes for more modes; a
//!   mismatch that persists is an error.
//!
//! # Shift
//! The default shift is negative, σ = −10⁻⁷·median(K_ii/M_ii): A is then positive definite even
//! for free–free models (six rigid-body modes, K singular), and the lowest modes are sought.
//! A user shift finds the modes nearest to it.

use super::coarse::{CoarseModel, Prolongation};
use super::factor::{Factor, Prefault, SymbolicFactor};
use super::floor::SolveWork;
use super::tall;
use crate::linalg::sparse::SymMatrix;
use crate::{Error, Result};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use std::sync::Arc;
use std::time::Instant;

/// Which modes to compute.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// The `n` eigenvalues nearest the shift (the lowest `n` with the default shift).
    Nearest(usize),
    /// All eigenvalues λ in `[lo, hi]`.
    Band(f64, f64),
}

/// Knobs of the eigen solver.
#[derive(Clone, Debug)]
pub struct EigenParams {
    /// What to compute.
    pub target: Target,
    /// Shift σ (λ units, rad²/s²); `None` for the default negative shift.
    pub shift: Option<f64>,
    /// Block size (≥ the largest multiplicity expected; 6 covers rigid-body modes).
    pub block: usize,
    /// Convergence tolerance on the Ritz residual, relative to |θ|.
    pub tol: f64,
    /// Maximum number of operator applications (vectors) before giving up.
    pub max_applications: usize,
    /// Seed of the start block.
    pub seed: u64,
    /// Backward error η = ‖Kx − λMx‖ / (‖|K||x|‖ + |λ|‖|M||x|‖) above which a mode fails
    /// verification.
    pub verify_tol: f64,
    /// Models with at most this many free DOFs are solved densely (all modes, exact).
    pub dense_below: usize,
    /// Candidates for K's null space (the rigid-body motions from the node coordinates): the
    /// one-factorisation solve deflates those that are null vectors to rounding
    /// ([`null_vectors`]) rather than iterating for them.
    pub null_candidates: Option<NullCandidates>,
    /// Raised when the iteration with the last factorisation starts (its factor complete and
    /// resident): work waiting on it ([`Signal::wait`]) then runs beside the iteration, which
    /// leaves part of the cores idle, without slowing the factorisation.
    pub iterating: Option<Signal>,
}

/// A one-shot signal between the solver and work waiting to run beside it: raised ("go") or
/// called off, whichever comes first.
#[derive(Clone, Default)]
pub struct Signal(Arc<(std::sync::Mutex<Option<bool>>, std::sync::Condvar)>);

impl Signal {
    /// Raise it (`true`) or call it off (`false`); the first call decides.
    pub fn set(&self, go: bool) {
        let (state, cv) = &*self.0;
        let mut s = state.lock().unwrap_or_else(|p| p.into_inner());
        if s.is_none() {
            *s = Some(go);
            cv.notify_all();
        }
    }
    /// A guard that calls it off when dropped, on return or unwinding alike: work waiting on
    /// the signal never outlives the solve that was to raise it.
    pub fn off_on_drop(&self) -> impl Drop + '_ {
        struct Off<'a>(&'a Signal);
        impl Drop for Off<'_> {
            fn drop(&mut self) {
                self.0.set(false);
            }
        }
        Off(self)
    }
    /// Wait until it is raised (`true`) or called off (`false`).
    pub fn wait(&self) -> bool {
        let (state, cv) = &*self.0;
        let mut s = state.lock().unwrap_or_else(|p| p.into_inner());
        loop {
            if let Some(go) = *s {
                return go;
            }
            s = cv.wait(s).unwrap_or_else(|p| p.into_inner());
        }
    }
}

impl std::fmt::Debug for Signal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Signal")
    }
}

/// Vectors over the free DOFs offered as candidates for K's null space, typically the six
/// rigid-body motions ([`crate::post::modal::rigid_vectors`]). The solver keeps only those that
/// K maps to zero to rounding, so wrong or partly constrained candidates cost nothing but a
/// product.
#[derive(Clone)]
pub struct NullCandidates(pub Arc<Mat<f64>>);

impl std::fmt::Debug for NullCandidates {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "NullCandidates({} × {})", self.0.nrows(), self.0.ncols())
    }
}

impl Default for EigenParams {
    fn default() -> Self {
        EigenParams {
            target: Target::Nearest(12),
            shift: None,
            block: 6,
            tol: 1e-10,
            max_applications: 20_000,
            seed: 0x5eed_cafe_f00d_0001,
            verify_tol: 1e-10,
            dense_below: 300,
            null_candidates: None,
            iterating: None,
        }
    }
}

/// The result of the Sturm-sequence check.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SturmCheck {
    /// Lower check point (λ units) and the count of eigenvalues below it.
    pub lower: (f64, usize),
    /// Upper check point and the count of eigenvalues below it.
    pub upper: (f64, usize),
    /// Modes expected between the points (`upper.1 − lower.1`).
    pub expected: usize,
    /// Modes found between them.
    pub found: usize,
    /// `expected == found`.
    pub complete: bool,
}

/// Eigen solution with its verification.
pub struct EigenSolution {
    /// Eigenvalues λ = ω², ascending.
    pub lambda: Vec<f64>,
    /// Eigenvectors (columns), M-orthonormal: XᵀMX = I.
    pub vectors: Mat<f64>,
    /// Relative residual of each mode.
    pub rel_residual: Vec<f64>,
    /// Backward error of each mode (see [`backward_errors`]): the acceptance test.
    pub backward_error: Vec<f64>,
    /// Notes for the user (request capped, dense solve chosen, ...).
    pub notes: Vec<String>,
    /// max |XᵀMX − I|.
    pub m_orthonormality: f64,
    /// The completeness check.
    pub sturm: SturmCheck,
    /// The shift used.
    pub shift: f64,
    /// Operator applications (vectors solved for).
    pub applications: usize,
    /// Factorisations done (shift and Sturm points).
    pub factorizations: usize,
    /// Seconds spent factorising, iterating and verifying.
    pub time_factor: f64,
    /// Seconds in the Lanczos iteration.
    pub time_iterate: f64,
    /// Seconds in verification (residuals, orthonormality, Sturm factorisations).
    pub time_verify: f64,
    /// Worst probe backward error of the factorisations used (see [`Factor::probe_residual`]).
    pub factor_backward_error: f64,
    /// The large allocations of the solve.
    pub memory: EigenMemory,
}

/// Bytes of the large allocations of an eigen solve (the largest of each kind held at once).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct EigenMemory {
    /// Values of one LDLᵀ factor as the factorisation holds them (faer's layout; never two at
    /// once).
    pub factor: u64,
    /// The same factor packed for the solves, as the iteration holds it.
    pub factor_packed: u64,
    /// K − σM, the matrix being factorised (dropped once factorised).
    pub shifted_matrix: u64,
    /// Scratch of the numeric factorisation (freed when it returns).
    pub factor_workspace: u64,
    /// Solve workspaces kept with the factor.
    pub solve_workspace: u64,
    /// Lanczos basis V, the next block's M-image and the projected matrix.
    pub lanczos_basis: u64,
    /// Seconds of the numeric factorisations, summed (every factorisation passes through
    /// [`EigenMemory::add_factor`], so its time is gathered here too).
    #[serde(skip)]
    pub numeric_seconds: f64,
    /// Numeric factorisations counted in `numeric_seconds`.
    #[serde(skip)]
    pub numeric_count: usize,
    /// The block solves with the factorisations of the solve (gathered from each factor
    /// before it is dropped; a coarse estimate's are its own).
    #[serde(skip)]
    pub solves: SolveWork,
    /// Read bandwidth over the iteration's factor (GB/s) and the seconds its measurement
    /// took ([`Factor::read_rate`]), measured once, when that factor's solves are gathered.
    #[serde(skip)]
    pub read_rate: (f64, f64),
    /// The Lanczos iteration's parts, seconds: block solves, M products, orthogonalisation,
    /// normalisation, Rayleigh–Ritz and restarts.
    #[serde(skip)]
    pub iteration: [f64; 5],
}

impl EigenMemory {
    fn add_factor(&mut self, f: &Factor) {
        self.factor = self.factor.max(f.factorisation_bytes() as u64);
        self.factor_packed = self.factor_packed.max(f.bytes() as u64);
        self.shifted_matrix = self.shifted_matrix.max(f.shifted_matrix_bytes as u64);
        self.factor_workspace = self.factor_workspace.max(f.factor_workspace_bytes as u64);
        self.solve_workspace = self.solve_workspace.max(f.workspace_bytes() as u64);
        self.numeric_seconds += f.numeric_seconds;
        self.numeric_count += 1;
        self.solves.add(&f.take_solve_work());
    }

    /// Gathers the block solves done with `f` so far; the first time, measures the read
    /// bandwidth over it (for the floor report: its solves read it).
    fn add_solves(&mut self, f: &Factor) {
        self.solves.add(&f.take_solve_work());
        if self.read_rate.0 == 0.0 {
            self.read_rate = f.read_rate();
        }
    }

    /// Gathers (and zeroes) the time of a Lanczos iteration's parts.
    fn add_iteration(&mut self, times: &mut [f64; 5]) {
        for (a, t) in self.iteration.iter_mut().zip(times.iter_mut()) {
            *a += std::mem::take(t);
        }
    }
}

/// Largest model solved densely when a request asks for a sixth of its modes or more. Measured
/// (2-core box): the dense solve takes ~18 s at 3795 DOFs and ~60 s at 5562, 1.1 and ~2.5 GB;
/// Lanczos for 900 of 3795 modes 53 s, for 1000 of 5562 79 s, for 200 of 5562 6.6 s, and for
/// all 5562 past ten minutes (a basis as large as the model, reorthogonalised every step).
const DENSE_MAX: usize = 6000;
/// Orthonormalisation passes of a block at most: the first, one after random replacements,
/// and room for replacements that are themselves deficient. With three, a block whose
/// replacements were deficient again in the last pass left un-normalised (M-norm² ~1e8), and
/// the iteration ended in NaN: the start block Op·random of a clamped cantilever with a tip
/// mass 6e9 times its own is of rank 3 (the tip's translations).
const NORMALISE_PASSES: usize = 5;
/// Smallest ratio of the extreme eigenvalues of a new block's M-Gram matrix for which the block
/// is normalised without another orthogonalisation pass against the basis.
const WELL_CONDITIONED: f64 = 1e-4;
/// Smallest ratio of a new block's least M-norm² after orthogonalisation to its largest before
/// it for which the block's M-image is updated along rather than recomputed.
const IMAGE_KEPT: f64 = 1e-6;
/// Smallest block once K's null vectors are deflated ([`null_vectors`]): the block need no
/// longer cover them, and 4 covers the repeated roots of symmetric bodies (a cube's are triple).
/// Against 6 at 119k DOFs, 18 modes: 64 operator applications instead of 84, the iteration
/// 2.25 → 2.06 s; at 20k 0.26 → 0.23 s; at 66k and 273k within ±0.02 s.
const BLOCK_DEFLATED: usize = 4;
/// Largest block size chosen automatically for models of several unconnected parts.
const MAX_AUTO_BLOCK: usize = 60;

/// Number of connected parts (of at least `min_size` equations) of the graph of `k`.
fn components(k: &SymMatrix, min_size: usize) -> usize {
    let (label, count) = crate::linalg::graph::Parts::of_pattern(&k.pattern).labels();
    let mut size = vec![0usize; count];
    for l in label {
        size[l] += 1;
    }
    size.iter().filter(|&&s| s >= min_size).count()
}

/// Backward error of each eigenpair, η = ‖Kx − λMx‖ / (‖|K||x|‖ + |λ|‖|M||x|‖): the residual
/// relative to what rounding in forming it can produce (|K| is K with its entries' magnitudes).
/// About machine precision for an exact pair; a perturbation δ of the vector raises it to
/// about ‖δ‖/‖x‖ (its stiff components dominate), so it stays a real check. Unlike the
/// relative residual ‖Kx − λMx‖/‖Kx‖ it needs no special case for λ ≈ 0 and does not grow
/// with the conditioning of slender or thin parts (where Kx is a small difference of large
/// terms).
pub fn backward_errors(k: &SymMatrix, m: &SymMatrix, lambda: &[f64], x: MatRef<'_, f64>) -> Vec<f64> {
    let pn = products_and_norms(k, m, x);
    backward_errors_of(lambda, &pn)
}

/// K·X and M·X with the norms ‖|K|·|x_c|‖ and ‖|M|·|x_c|‖ of the backward errors, one pass
/// over each matrix.
struct ProductsAndNorms {
    kx: Mat<f64>,
    mx: Mat<f64>,
    ak: Vec<f64>,
    am: Vec<f64>,
}

fn products_and_norms(k: &SymMatrix, m: &SymMatrix, x: MatRef<'_, f64>) -> ProductsAndNorms {
    let (n, nc) = (x.nrows(), x.ncols());
    let mut kx = Mat::zeros(n, nc);
    let mut mx = Mat::zeros(n, nc);
    let ak = k.mul_block_abs_norms(x, kx.as_mut());
    let am = m.mul_block_abs_norms(x, mx.as_mut());
    ProductsAndNorms { kx, mx, ak, am }
}

/// K·X and M·X.
fn products(k: &SymMatrix, m: &SymMatrix, x: MatRef<'_, f64>) -> (Mat<f64>, Mat<f64>) {
    let (n, nc) = (x.nrows(), x.ncols());
    let mut kx = Mat::zeros(n, nc);
    let mut mx = Mat::zeros(n, nc);
    k.mul_block(x, kx.as_mut());
    m.mul_block(x, mx.as_mut());
    (kx, mx)
}

/// [`verify`] and [`backward_errors`] of the same pairs, with K·X and M·X formed once:
/// (relative residuals, M-orthonormality, backward errors).
pub fn verify_with_backward_errors(
    k: &SymMatrix,
    m: &SymMatrix,
    lambda: &[f64],
    x: MatRef<'_, f64>,
    sigma: f64,
) -> (Vec<f64>, f64, Vec<f64>) {
    let pn = products_and_norms(k, m, x);
    let (res, orth) = verify_of(lambda, x, &pn.kx, &pn.mx, sigma);
    (res, orth, backward_errors_of(lambda, &pn))
}

/// [`backward_errors`] from K·X, M·X and their norms.
fn backward_errors_of(lambda: &[f64], pn: &ProductsAndNorms) -> Vec<f64> {
    let ProductsAndNorms { kx, mx, ak, am } = pn;
    let nc = kx.ncols();
    use rayon::prelude::*;
    (0..nc)
        .into_par_iter()
        .map(|c| {
            let r = kx
                .col(c)
                .iter()
                .zip(mx.col(c).iter())
                .map(|(a, b)| {
                    let r = a - lambda[c] * b;
                    r * r
                })
                .sum::<f64>()
                .sqrt();
            let denom = ak[c] + lambda[c].abs() * am[c];
            if denom > 0.0 { r / denom } else { r }
        })
        .collect()
}

/// Backward error at or below which a candidate null vector is deflated: the rounding level
/// (an exact rigid-body motion of a free model gives ~1e-16), two orders below the acceptance
/// bar, so that a deflated pair is as accurate as any the iteration returns.
const NULL_KEPT: f64 = 1e-12;

/// The null vectors of K among the candidates `cand` (columns: three translations, then
/// rotations, as [`crate::post::modal::rigid_vectors`] gives them), M-orthonormal, and their
/// M-images: (Z, MZ). A candidate is kept when its backward error as an eigenvector at λ = 0
/// ([`backward_errors`]) is at most [`NULL_KEPT`]: a clamped model keeps none (`None`), one on
/// rollers the motions they allow; a null combination of several rejected candidates is left
/// to the iteration. The kept translations are M-orthonormalised first; the kept rotations,
/// M-orthogonalised against them (which moves their axes through the centre of mass), are
/// turned to the principal axes of inertia, least inertia first. Their eigenvalue is 0: their
/// Rayleigh quotients are rounding (~1e-6 rad²/s² on a 119k-DOF plate), and reporting 0
/// keeps them in the order built here.
fn null_vectors(k: &SymMatrix, m: &SymMatrix, cand: MatRef<'_, f64>) -> Option<Null> {
    let (n, c) = (cand.nrows(), cand.ncols());
    if n != k.n() || c == 0 {
        return None;
    }
    let pn = products_and_norms(k, m, cand);
    let eta = backward_errors_of(&vec![0.0; c], &pn);
    let kept: Vec<usize> = (0..c).filter(|&j| eta[j] <= NULL_KEPT && pn.am[j] > 0.0).collect();
    log::debug!(
        "null vectors: {} of {c} candidates kept (backward errors at λ = 0: {})",
        kept.len(),
        eta.iter().map(|e| format!("{e:.1e}")).collect::<Vec<_>>().join(" ")
    );
    if kept.is_empty() {
        return None;
    }
    let cand = Mat::from_fn(n, kept.len(), |i, j| cand[(i, kept[j])]);
    let mc = Mat::from_fn(n, kept.len(), |i, j| pn.mx[(i, kept[j])]);
    let c = kept.len();
    let g = tall::gram(cand.as_ref(), mc.as_ref());
    let g = nalgebra::DMatrix::from_fn(c, c, |i, j| 0.5 * (g[(i, j)] + g[(j, i)]));
    let ip = |a: &nalgebra::DVector<f64>, b: &nalgebra::DVector<f64>| a.dot(&(&g * b));
    let unit = |j: usize| nalgebra::DVector::from_fn(c, |i, _| if i == j { 1.0 } else { 0.0 });
    let project = |v: &mut nalgebra::DVector<f64>, t: &[nalgebra::DVector<f64>]| {
        for _ in 0..2 {
            for q in t {
                let a = ip(q, v);
                v.axpy(-a, q, 1.0);
            }
        }
    };
    // Coefficients of the M-orthonormal combinations, in the kept candidates' coordinates.
    let mut t: Vec<nalgebra::DVector<f64>> = Vec::new();
    let ntr = kept.iter().filter(|&&j| j < 3).count();
    for j in 0..ntr {
        let mut v = unit(j);
        project(&mut v, &t);
        let s = ip(&v, &v);
        if s > 1e-10 * g[(j, j)] {
            t.push(v / s.sqrt());
        }
    }
    let rest: Vec<nalgebra::DVector<f64>> = (ntr..c)
        .map(|j| {
            let mut v = unit(j);
            project(&mut v, &t);
            v
        })
        .collect();
    if !rest.is_empty() {
        let q = rest.len();
        let gr = nalgebra::DMatrix::from_fn(q, q, |i, j| ip(&rest[i], &rest[j]));
        let scale = (ntr..c).map(|j| g[(j, j)]).fold(0.0f64, f64::max);
        let e = gr.symmetric_eigen();
        let mut order: Vec<usize> = (0..q).collect();
        order.sort_by(|&a, &b| e.eigenvalues[a].total_cmp(&e.eigenvalues[b]));
        for &kk in &order {
            let s = e.eigenvalues[kk];
            if !(s > 1e-10 * scale) {
                continue;
            }
            let mut v = nalgebra::DVector::zeros(c);
            for (i, r) in rest.iter().enumerate() {
                v.axpy(e.eigenvectors[(i, kk)], r, 1.0);
            }
            // A fixed sign: the largest rotation component positive.
            let big = (ntr..c).max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs())).unwrap_or(0);
            let sign = if v[big] < 0.0 { -1.0 } else { 1.0 };
            t.push(v * (sign / s.sqrt()));
        }
    }
    // Z = C·T and MZ = (MC)·T: combinations of null vectors are null vectors.
    let tm = Mat::from_fn(c, t.len(), |i, j| t[j][i]);
    let mut z = Mat::zeros(n, t.len());
    tall::mul(z.as_mut(), Accum::Replace, cand.as_ref(), tm.as_ref(), 1.0);
    let mut mz = Mat::zeros(n, t.len());
    tall::mul(mz.as_mut(), Accum::Replace, mc.as_ref(), tm.as_ref(), 1.0);
    Some((Arc::new(z), Arc::new(mz)))
}

/// Default shift: a small negative fraction of the typical diagonal ratio K_ii/M_ii (which
/// is of the order of the largest eigenvalue), so that A = K − σM is positive definite and
/// well enough conditioned even when K is singular.
pub fn default_shift(k: &SymMatrix, m: &SymMatrix) -> f64 {
    let dk = k.diagonal();
    let dm = m.diagonal();
    let mut r: Vec<f64> = dk
        .iter()
        .zip(&dm)
        .filter(|(a, b)| **b > 0.0 && **a > 0.0)
        .map(|(a, b)| a / b)
        .collect();
    if r.is_empty() {
        return -1.0;
    }
    let mid = r.len() / 2;
    let (_, med, _) = r.select_nth_unstable_by(mid, f64::total_cmp);
    -1e-7 * *med
}

/// Small deterministic generator for start vectors (xorshift64*).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        (v >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// Solve K x = λ M x for the requested modes, verified. `sym` is the symbolic factorisation of
/// the shared pattern (ordering included), reused for every numeric factorisation.
pub fn solve(k: &SymMatrix, m: &SymMatrix, sym: &Arc<SymbolicFactor>, p: &EigenParams) -> Result<EigenSolution> {
    solve_inner(k, m, sym, p, None, true)
}

/// [`solve`], with a coarse subspace of the DOFs ([`Prolongation`], e.g. the corner space of a
/// quadratic mesh) for the lowest modes: the Galerkin model on it bounds the wanted
/// eigenvalues from above, which places one shift U just above them. The inertia of K − UM
/// counts every eigenvalue below U, and Lanczos on that same factorisation finds them all: a
/// complete, verified solve with one factorisation instead of two (shift and upper Sturm
/// point). When the count falls outside what the estimate promised, the solve goes on as
/// [`solve`] does (said in `-v`).
pub fn solve_with(
    k: &SymMatrix,
    m: &SymMatrix,
    sym: &Arc<SymbolicFactor>,
    p: &EigenParams,
    coarse: Option<&Prolongation>,
) -> Result<EigenSolution> {
    solve_with_prepared(k, m, sym, p, coarse, None)
}

/// [`solve_with`], with the Galerkin model on `coarse` already formed (by
/// [`crate::system::System::build`], alongside the ordering): the same solve, without forming
/// it here. `prepared` must be the Galerkin model of this K and M on `coarse`; it is freed
/// before the model's factorisation.
pub fn solve_with_prepared(
    k: &SymMatrix,
    m: &SymMatrix,
    sym: &Arc<SymbolicFactor>,
    p: &EigenParams,
    coarse: Option<&Prolongation>,
    prepared: Option<CoarseModel>,
) -> Result<EigenSolution> {
    solve_inner(k, m, sym, p, coarse.map(|pr| (pr, prepared)), true)
}

/// The solver. Without `check`, the Sturm count, the refinement step and the verification are
/// skipped (the coarse estimate of [`solve_with`] needs eigenvalue estimates and start vectors,
/// not their proof): its `sturm` is then not a check, and its residuals, backward errors and
/// M-orthonormality are NaN (not computed).
///
/// The steps: the request checked and the block size fitted to it ([`adjusted_params`]); the
/// shift placed ([`first_shift`]); for the lowest modes with a coarse space, the
/// one-factorisation solve ([`solve_below_bound`]); otherwise the factorisation at the shift,
/// moved nearer the wanted modes when the default shift is far below them
/// ([`factor_at_shift`]); a band's upper Sturm count ([`wanted_count`]); then rounds of Lanczos
/// (or a dense solve), refinement, Sturm check and, when a mode was missed, more iteration
/// ([`Rounds::run`]).
fn solve_inner(
    k: &SymMatrix,
    m: &SymMatrix,
    sym: &Arc<SymbolicFactor>,
    p: &EigenParams,
    coarse: Option<(&Prolongation, Option<CoarseModel>)>,
    check: bool,
) -> Result<EigenSolution> {
    let n = k.n();
    if n == 0 {
        return Err(Error::InvalidInput("the model has no free degree of freedom".into()));
    }
    // K − σM is factorised on K's pattern: M's entries must be among K's.
    if m.n() != n || !k.pattern.contains(&m.pattern) {
        return Err(Error::InvalidInput(format!(
            "M ({} equations) must have K's sparsity pattern ({n} equations) or a subset of it",
            m.n()
        )));
    }
    let t0 = Instant::now();
    let (mut pl, mut notes) = adjusted_params(k, p);
    if let Target::Nearest(nm) = pl.target {
        iteration_fits(n, nm.min(n), &pl, false)?;
    }
    // The one-factorisation solve (with a coarse model, for the lowest modes, to be proved);
    // its factor's pages made resident during the set-up and the coarse estimate ([`Prefault`]).
    let lowest = lowest_by_lanczos(n, &pl);
    let below_bound = coarse.is_some() && check && lowest.is_some();
    let mut prefault = if below_bound { Prefault::start(sym) } else { None };
    let (sigma, band) = first_shift(k, m, &pl)?;
    let p = &pl;
    // For the lowest modes by Lanczos, K's null vectors among the candidates (the rigid-body
    // motions of a free model) are exact eigenpairs at λ = 0: deflated, the iteration looks
    // only for the others.
    let null = match (lowest, &p.null_candidates) {
        (Some(nm), Some(c)) => null_vectors(k, m, (*c.0).as_ref()).filter(|(z, _)| z.ncols() < nm),
        _ => None,
    };
    if let Some((z, _)) = &null {
        // The block was sized to cover the cluster at λ = 0 (six rigid-body modes per free
        // part); the deflated vectors leave it smaller.
        let b = pl.block.saturating_sub(z.ncols()).max(BLOCK_DEFLATED).min(pl.block);
        let level = if check { log::Level::Info } else { log::Level::Debug };
        log::log!(
            level,
            "{} null vectors of K (rigid-body motions) deflated: the iteration seeks the other modes, block {b}",
            z.ncols()
        );
        pl.block = b;
    }
    let p = &pl;
    let pb = Problem {
        k,
        m,
        sym,
        p,
        check,
        null: null.as_ref(),
    };
    let mut tally = Tally::default();
    if let (Some((pr, prepared)), Some(nm), true) = (coarse, lowest, below_bound) {
        let est = Estimate {
            t0,
            factorizations: &mut tally.factorizations,
            memory: &mut tally.memory,
        };
        let pre = prefault.take();
        if let Some(sol) = solve_below_bound(k, m, sym, p, (pr, prepared), nm, est, &notes, null.as_ref(), pre)? {
            return Ok(sol);
        }
        // A prepared coarse model not used is dropped here, before the factorisation.
    }
    // So is a prefaulted buffer not used (the factorisation below allocates its own).
    drop(prefault);
    let shift = factor_at_shift(&pb, sigma, &mut tally)?;
    let sigma = shift.sigma;
    let mut rounds = Rounds {
        pb: &pb,
        sigma,
        band,
        dense: false,
        tally,
        backward: shift.backward,
        notes: vec![],
        time_factor: t0.elapsed().as_secs_f64() - shift.time_probe,
        time_iterate: shift.time_probe,
        time_verify: 0.0,
        lower_count_at_shift: shift.fa.negative_pivots,
        upper_known: None,
        null: None,
    };
    let want = rounds.wanted_count()?;
    if want == 0 {
        rounds.notes = notes;
        return Ok(rounds.nothing_wanted());
    }
    let ti = Instant::now();
    let dense = solved_densely(n, want, p);
    if dense && n > p.dense_below {
        notes.push(format!(
            "{want} modes of {n} degrees of freedom: solved densely (all eigenpairs) rather than by Lanczos"
        ));
    }
    rounds.dense = dense;
    rounds.notes = notes;
    // Dense solves and bands deflate nothing (no null vectors were sought for them).
    rounds.null = if dense { None } else { pb.null };
    let lz = match shift.lz {
        Some(lz) if !dense => lz,
        _ => {
            let mut lz = Lanczos::new(
                n,
                if dense { 1 } else { want - null_count(rounds.null) },
                p,
                if band.is_some() { Side::Above } else { Side::Both },
            );
            lz.deflate = rounds.null.cloned();
            lz
        }
    };
    rounds.run(lz, shift.fa, want, shift.early, ti)
}

/// The count `nm` of a request for the `nm` lowest modes (no shift) that Lanczos solves: not
/// the whole spectrum, not a small model or a large share of the spectrum (solved densely).
fn lowest_by_lanczos(n: usize, p: &EigenParams) -> Option<usize> {
    match (p.target, p.shift) {
        (Target::Nearest(nm), None) if n > p.dense_below && nm < n && !big_request(n, nm) => Some(nm),
        _ => None,
    }
}

/// Refuse, before any work, a request for `want` modes of an `n`-equation model whose dense
/// matrices or Lanczos basis (three vectors of the model's size per mode, and their M-images)
/// would not fit in the memory this process can use: the allocation would abort the run.
/// `band`: the modes are a band's (the advice differs).
fn iteration_fits(n: usize, want: usize, p: &EigenParams, band: bool) -> Result<()> {
    let n64 = n as u64;
    let (bytes, what) = if solved_densely(n, want, p) {
        // The dense solve holds about ten n × n matrices (K, M, their factors and reductions,
        // the eigenvectors).
        (10 * n64 * n64 * 8, "the dense solve's matrices")
    } else {
        let b = p.block.max(1).min(n);
        let m = (basis_columns(n, want, b) + b) as u64;
        (
            (2 * n64 * m + m * m) * 8,
            "the Lanczos basis (three vectors of the model's size per mode, and their M-images)",
        )
    };
    match crate::util::memory::available_memory() {
        Some(avail) if bytes > avail => Err(Error::InvalidInput(format!(
            "{want} modes{} of this model of {n} degrees of freedom: {what} would take {}, more than the {} this process can use; {}",
            if band { " in the band" } else { "" },
            crate::util::fmt::fmt_bytes(bytes),
            crate::util::fmt::fmt_bytes(avail),
            if band {
                "ask for a narrower band, or split it into several (--band F_LO F_HI)"
            } else {
                "ask for fewer modes, or for the range in several frequency bands (--band F_LO F_HI)"
            }
        ))),
        _ => Ok(()),
    }
}

/// Whether `want` modes of an `n`-equation model are solved densely (a tiny model, or a large
/// share of the spectrum) rather than by Lanczos.
fn solved_densely(n: usize, want: usize, p: &EigenParams) -> bool {
    n <= p.dense_below || big_request(n, want)
}

/// Requests for a large share of the spectrum are solved densely when that is affordable
/// (Lanczos would build a basis of about the model's size anyway, much more slowly).
fn big_request(n: usize, want: usize) -> bool {
    6 * want >= n && n <= DENSE_MAX
}

/// The parameters fitted to the model of `n = k.n()` equations, with notes: a request above
/// `n` computes all `n` modes; the block is capped to the wanted count plus a six-fold cluster
/// (a wider one buys nothing) and raised to cover the rigid-body modes of unconnected parts.
fn adjusted_params(k: &SymMatrix, p: &EigenParams) -> (EigenParams, Vec<String>) {
    let n = k.n();
    let mut notes = Vec::new();
    let mut p = p.clone();
    if let Target::Nearest(nm) = p.target {
        if nm > n {
            notes.push(format!(
                "{nm} modes asked for, but the model has {n} degrees of freedom: computing all {n}"
            ));
        }
    }
    // A block wider than the wanted count plus a six-fold cluster buys nothing.
    let block_cap = match p.target {
        Target::Nearest(nm) => (nm.min(n) + 6).min(n),
        Target::Band(..) => n,
    }
    .max(1);
    if p.block > block_cap {
        notes.push(format!("block size {} capped to {block_cap}", p.block));
        p.block = block_cap;
    }
    // Separate bodies: each free one has up to six rigid-body modes at λ = 0, one cluster
    // that the block must cover (block Lanczos finds at most `block` copies of an eigenvalue).
    let parts = components(k, 6);
    if parts > 1 && p.block < 6 * parts {
        let b = (6 * parts).min(MAX_AUTO_BLOCK).min(block_cap.max(6)).min(n);
        if b > p.block {
            notes.push(format!(
                "the model has {parts} unconnected parts: Lanczos block size raised from {} to {b} to cover their rigid-body modes",
                p.block
            ));
            p.block = b;
        }
    }
    (p, notes)
}

/// The first shift σ, and the band asked for: the user's shift, or for a band just below its
/// lower end (the factor's inertia is then the lower Sturm count), or the default shift.
fn first_shift(k: &SymMatrix, m: &SymMatrix, p: &EigenParams) -> Result<(f64, Option<(f64, f64)>)> {
    let (s, band) = match p.target {
        Target::Band(lo, hi) => {
            if !(lo < hi) || !lo.is_finite() || !hi.is_finite() {
                return Err(Error::param("band", format!("empty band [{lo}, {hi}]")));
            }
            // Factor just below the band's lower end; its inertia is the lower Sturm count.
            let s = p.shift.unwrap_or(if lo <= 0.0 {
                default_shift(k, m).min(lo - lo.abs() * 1e-9 - 1e-9)
            } else {
                lo * (1.0 - 1e-9)
            });
            (s, Some((lo, hi)))
        }
        Target::Nearest(_) => (p.shift.unwrap_or_else(|| default_shift(k, m)), None),
    };
    if !s.is_finite() {
        // Finite K and M whose typical ratio K_ii/M_ii overflows: refused here, where it would
        // surface as a zero pivot.
        return Err(Error::InvalidInput(format!(
            "the stiffness-to-mass ratio K_ii/M_ii of the model overflows double precision (shift {s}): check the \
             units of the material constants and the coordinates"
        )));
    }
    Ok((s, band))
}

/// The matrices and the (fitted) parameters of a solve: what every step reads.
struct Problem<'a> {
    k: &'a SymMatrix,
    m: &'a SymMatrix,
    sym: &'a Arc<SymbolicFactor>,
    p: &'a EigenParams,
    /// Prove the result (Sturm counts, refinement, verification): see [`solve_inner`].
    check: bool,
    /// K's null vectors and their M-images, deflated ([`null_vectors`]; lowest modes only).
    null: Option<&'a Null>,
}

/// Deflated null vectors of K and their M-images, (Z, MZ) ([`null_vectors`]); Z shared with the
/// Lanczos runs that deflate it.
type Null = (Arc<Mat<f64>>, Arc<Mat<f64>>);

/// The number of deflated vectors.
fn null_count(null: Option<&Null>) -> usize {
    null.map_or(0, |(z, _)| z.ncols())
}

/// Rayleigh–Ritz on the span of `y` with the deflated null vectors taken out of it (A⁻¹M keeps
/// their complement only up to rounding: taken out, the pairs stay M-orthogonal to them to
/// ~1e-15 rather than ~1e-13), then the null vectors put back in front at λ = 0
/// ([`with_null`]): the refinement of the pairs an iteration that deflates them returned.
fn ritz_deflated(k: &SymMatrix, m: &SymMatrix, null: Option<&Null>, mut y: Mat<f64>) -> Result<(Vec<f64>, Mat<f64>)> {
    if let Some((z, mz)) = null {
        project_out(z, mz, y.as_mut());
    }
    let (l, x) = rayleigh_ritz(k, m, y)?;
    Ok(with_null(null, l, x))
}

/// The deflated pairs (at λ = 0) before the pairs (λ, X) of an iteration.
fn with_null(null: Option<&Null>, l: Vec<f64>, x: Mat<f64>) -> (Vec<f64>, Mat<f64>) {
    let Some((z, _)) = null else { return (l, x) };
    let mut lambda = vec![0.0; z.ncols()];
    lambda.extend_from_slice(&l);
    let mut xs = Mat::zeros(x.nrows(), z.ncols() + x.ncols());
    xs.get_mut(.., 0..z.ncols()).copy_from(&**z);
    xs.get_mut(.., z.ncols()..).copy_from(&x);
    (lambda, xs)
}

/// How far outside the null space a computed pair may lie and still be taken for a null pair:
/// 1 − ‖ZᵀMx‖² ≤ 1e-2 (the pair is at least 99 % rigid-body motion by M-norm). An elastic
/// eigenvector is M-orthogonal to the null space (its share there is its error, squared), so no
/// elastic pair comes near; a rigid-body pair of an ill-conditioned model solved without
/// deflation (a 0.1 mm wide shell strip: eigenvalue noise ~1e-16 λ_max, ±0.07 Hz, near its
/// first elastic mode at 1.5 Hz) lay up to 1.8e-4 of its M-norm outside the null space, far
/// above the 1e-10 an earlier bar asked, and was left as six 'elastic' modes at ±0.07 Hz.
const NULL_SHARE_TOL: f64 = 1e-2;

/// The leading pairs of a solution that lie in K's null space (the rigid-body motions of a free
/// model) replaced by the M-orthonormal null vectors a deflating solve reports there
/// ([`null_vectors`]: translations first, then rotations about the principal axes of inertia,
/// least inertia first) at λ = 0. A solve that iterated for them (every wanted mode is rigid,
/// or another engine found them) returns arbitrary combinations of the motions whose Rayleigh
/// quotients are rounding (±1e-4 rad²/s² on a steel bar, printed as −0.003 Hz, with a residual
/// relative to that |λ| of order 1); any M-orthonormal basis of the null space is as valid a set
/// of eigenvectors, and this one is the same whichever path solved. The pairs replaced are the
/// leading M-orthonormal ones inside span(Z) (‖x − Z ZᵀMx‖²_M = 1 − ‖ZᵀMx‖² ≤ [`NULL_SHARE_TOL`]), at most
/// as many as Z has columns; the pairs after them are orthogonal to the null space already
/// (eigenvectors of other eigenvalues). Nothing is done (and no product formed) when the first
/// eigenvalue is exactly 0 (a deflating solve's) or above 1e-6 of the typical K_ii/M_ii (no
/// null pair); every eigenvalue exactly 0 (K = 0) is replaced. `true` when pairs were
/// replaced (the caller then verifies them again).
pub fn canonical_null_pairs(
    k: &SymMatrix,
    m: &SymMatrix,
    cand: &NullCandidates,
    lambda: &mut [f64],
    vectors: &mut Mat<f64>,
) -> bool {
    let Some(&l0) = lambda.first() else {
        return false;
    };
    // Every λ exactly 0 is a K = 0 model's (a whole free body coupled to one reference node):
    // any engine returns its null space in an arbitrary basis, made canonical too.
    let deflated = l0 == 0.0 && lambda.iter().any(|&l| l != 0.0);
    if deflated || vectors.ncols() != lambda.len() || l0.abs() > 1e-6 * default_shift(k, m).abs() {
        return false;
    }
    let Some((z, mz)) = null_vectors(k, m, (*cand.0).as_ref()) else {
        return false;
    };
    if z.nrows() != vectors.nrows() {
        return false;
    }
    let c = z.ncols();
    let a = tall::gram((*mz).as_ref(), vectors.get(.., 0..c.min(lambda.len())));
    let outside: Vec<f64> = (0..a.ncols())
        .map(|j| (1.0 - (0..c).map(|i| a[(i, j)] * a[(i, j)]).sum::<f64>()).abs())
        .take_while(|&o| o <= NULL_SHARE_TOL)
        .collect();
    let r = outside.len();
    if r == 0 {
        return false;
    }
    let worst = outside.iter().copied().fold(0.0, f64::max);
    log::debug!("{r} pairs replaced by null vectors (largest share outside the null space {worst:.1e})");
    vectors.get_mut(.., 0..r).copy_from(z.get(.., 0..r));
    lambda[..r].fill(0.0);
    // The pairs after them carry the null space to the iteration's accuracy only (1.3e-8 on a
    // free shell of h/a = 1e-4, against the M-orthonormality bar of 1e-8): its components taken
    // out, as a deflating solve takes them out, and the pairs M-normalised again.
    let nc = lambda.len();
    if r < nc {
        let mut rest = vectors.get_mut(.., r..nc);
        project_out(&z, &mz, rest.as_mut());
        // Pairs mixed with the null space beyond rounding (the replaced ones were more than
        // 1e-10 outside it): a Rayleigh–Ritz step on what is left makes them M-orthonormal
        // again, with the best eigenvalues their span holds.
        // (Only when the span keeps every column: Rayleigh–Ritz drops a dependent one.)
        if worst > 1e-10
            && let Ok((l, x)) = rayleigh_ritz(k, m, rest.to_owned())
            && l.len() == nc - r
        {
            lambda[r..].copy_from_slice(&l);
            vectors.get_mut(.., r..nc).copy_from(&x);
            return true;
        }
        let mut mr = Mat::zeros(rest.nrows(), nc - r);
        m.mul_block(rest.as_ref(), mr.as_mut());
        for (j, s) in tall::col_dots(rest.as_ref(), mr.as_ref()).into_iter().enumerate() {
            if s > 0.0 {
                let f = s.sqrt().recip();
                rest.as_mut().col_mut(j).iter_mut().for_each(|v| *v *= f);
            }
        }
    }
    true
}

/// Y − Z(MZ)ᵀY: Y's components along the M-orthonormal null vectors Z taken out.
fn project_out(z: &Mat<f64>, mz: &Mat<f64>, mut y: MatMut<'_, f64>) {
    let c = tall::gram(mz.as_ref(), y.as_ref());
    tall::mul(y.as_mut(), Accum::Add, z.as_ref(), c.as_ref(), -1.0);
}

/// What a solve counts as it goes.
#[derive(Default)]
struct Tally {
    /// Factorisations done.
    factorizations: usize,
    /// Large allocations.
    memory: EigenMemory,
    /// Operator applications.
    applications: usize,
}

/// The factorisation at the shift, with what probing the spectrum from it left.
struct ShiftFactor {
    fa: Factor,
    /// The shift, as moved off an eigenvalue or nearer the wanted modes.
    sigma: f64,
    /// Probe backward error of `fa`.
    backward: f64,
    /// Lanczos started while probing the spectrum (kept when the shift stays).
    lz: Option<Lanczos>,
    /// Its result, if it already converged.
    early: Option<(Vec<f64>, Mat<f64>)>,
    /// Seconds of those Lanczos steps (iteration, not factorisation).
    time_probe: f64,
}

/// Factorise K − σM at the shift; for the default shift and a Lanczos solve, probe the low
/// spectrum and move the shift nearer the wanted modes while it is far below them
/// ([`probe_spectrum`]).
fn factor_at_shift(pb: &Problem<'_>, sigma: f64, tally: &mut Tally) -> Result<ShiftFactor> {
    let (k, m, sym, p) = (pb.k, pb.m, pb.sym, pb.p);
    let n = k.n();
    let (fa, sigma) = factor_at_checked(
        k,
        m,
        sym,
        sigma,
        &mut tally.factorizations,
        p.shift.is_some(),
        true,
        None,
    )?;
    tally.memory.add_factor(&fa);
    if let (None, Target::Nearest(nm)) = (p.shift, p.target) {
        if n > p.dense_below && !big_request(n, nm.min(n)) {
            return probe_spectrum(pb, nm, fa, sigma, tally);
        }
    }
    Ok(ShiftFactor {
        backward: fa.probe_residual,
        fa,
        sigma,
        lz: None,
        early: None,
        time_probe: 0.0,
    })
}

/// The diagonal heuristic can put the default shift far below the wanted modes (thin shells:
/// rotational stiffness ∝ 1/t²; huge stiffness contrasts). Then every θ = 1/(λ − σ) is nearly
/// the same and Lanczos crawls. Estimate the low spectrum from the Ritz values of the first few
/// Lanczos steps and move the shift closer while it is too far; when it stays, the iteration
/// simply continues (no solve is spent on the estimate alone).
fn probe_spectrum(pb: &Problem<'_>, nm: usize, fa: Factor, sigma: f64, tally: &mut Tally) -> Result<ShiftFactor> {
    let (k, m, sym, p) = (pb.k, pb.m, pb.sym, pb.p);
    let n = k.n();
    let (mut fa, mut sigma) = (fa, sigma);
    let mut backward = fa.probe_residual;
    let mut probe_lz = None;
    let mut early = None;
    let mut time_probe = 0.0;
    let nz = null_count(pb.null);
    for _ in 0..6 {
        // Estimates past the block: several free parts put more than six rigid-body modes
        // first, and the first elastic scale must be among the estimates.
        let nb = (nm + 6).min(12.max(p.block + 6)).min(n);
        let mut lz = Lanczos::new(n, nm.min(n) - nz, p, Side::Both);
        lz.deflate = pb.null.cloned();
        lz.pause_after = Some(nb.div_ceil(lz.b).max(3));
        let tp = Instant::now();
        early = lz.run(p, &fa, m, sigma, &mut tally.applications)?;
        time_probe += tp.elapsed().as_secs_f64();
        let mut est: Vec<f64> = lz
            .last_theta
            .iter()
            .filter(|t| **t > 0.0)
            .map(|t| sigma + 1.0 / t)
            .collect();
        est.sort_by(f64::total_cmp);
        est.truncate(nb);
        probe_lz = Some(lz);
        if early.is_some() {
            break;
        }
        let Some(&last) = est.last() else { break };
        // The deflated null vectors are not among the estimates.
        let mut lam_est = est[(nm - nz).clamp(1, est.len()) - 1];
        if lam_est < 1e-6 * last {
            lam_est = last; // the wanted ones are rigid-body modes: use the first elastic scale
        }
        if !(lam_est > 0.0) || sigma.abs() <= 10.0 * lam_est {
            break;
        }
        // Near the wanted modes but not closer than their scale: the θ spread is then about
        // 2, and K − σM stays as well conditioned as the problem allows.
        let s_new = -lam_est;
        log::info!(
            "default shift {sigma:.3e} is far below the wanted modes (~{lam_est:.3e}): moving it to {s_new:.3e} (another factorisation)"
        );
        probe_lz = None;
        tally.memory.add_solves(&fa);
        drop(fa);
        (fa, sigma) = factor_at(k, m, sym, s_new, &mut tally.factorizations)?;
        tally.memory.add_factor(&fa);
        backward = fa.probe_residual;
    }
    Ok(ShiftFactor {
        fa,
        sigma,
        backward,
        lz: probe_lz,
        early,
        time_probe,
    })
}

/// The two-factorisation solve from a shift: rounds of iteration and Sturm check.
struct Rounds<'a> {
    pb: &'a Problem<'a>,
    sigma: f64,
    band: Option<(f64, f64)>,
    /// All eigenpairs by a dense solve rather than Lanczos.
    dense: bool,
    tally: Tally,
    /// Worst probe backward error of the factorisations used.
    backward: f64,
    notes: Vec<String>,
    time_factor: f64,
    time_iterate: f64,
    time_verify: f64,
    /// Eigenvalues below the shift (the shift factor's inertia).
    lower_count_at_shift: usize,
    /// The Sturm count at the band's upper end, kept for the final check: (point asked for,
    /// point used, count).
    upper_known: Option<(f64, f64, usize)>,
    /// Null vectors deflated (put before the pairs of each iteration; `None` once a second
    /// round locks them in its basis with the other pairs found).
    null: Option<&'a Null>,
}

impl Rounds<'_> {
    /// How many modes to iterate for: the request, or for a band the Sturm count of its upper
    /// end (a factorisation) less the eigenvalues below the shift.
    fn wanted_count(&mut self) -> Result<usize> {
        let Problem { k, m, sym, p, .. } = *self.pb;
        Ok(match p.target {
            Target::Nearest(nm) => nm.min(k.n()),
            Target::Band(_, hi) => {
                let tv = Instant::now();
                log::info!("factorisation at the band's upper end {hi:.6e} for its Sturm count");
                let (fh, s_hi) = factor_at(k, m, sym, hi, &mut self.tally.factorizations)?;
                self.tally.memory.add_factor(&fh);
                self.backward = self.backward.max(fh.probe_residual);
                self.time_verify += tv.elapsed().as_secs_f64();
                self.upper_known = Some((hi, s_hi, fh.negative_pivots));
                let want = fh.negative_pivots.saturating_sub(self.lower_count_at_shift);
                iteration_fits(k.n(), want, p, true)?;
                want
            }
        })
    }

    /// The solution when no mode is wanted (an empty band).
    fn nothing_wanted(self) -> EigenSolution {
        let count = self.lower_count_at_shift;
        let sturm = SturmCheck {
            lower: (self.sigma, count),
            upper: (self.sigma, count),
            expected: 0,
            found: 0,
            complete: true,
        };
        let vectors = Mat::zeros(self.pb.k.n(), 0);
        self.solution(vec![], vectors, (vec![], 0.0, vec![]), sturm)
    }

    /// The solution with its pairs, their verification (relative residuals, M-orthonormality,
    /// backward errors) and the Sturm check.
    fn solution(
        self,
        lambda: Vec<f64>,
        vectors: Mat<f64>,
        verified: (Vec<f64>, f64, Vec<f64>),
        sturm: SturmCheck,
    ) -> EigenSolution {
        let (rel_residual, m_orthonormality, backward_error) = verified;
        EigenSolution {
            lambda,
            vectors,
            rel_residual,
            backward_error,
            notes: self.notes,
            m_orthonormality,
            sturm,
            shift: self.sigma,
            applications: self.tally.applications,
            factorizations: self.tally.factorizations,
            time_factor: self.time_factor,
            time_iterate: self.time_iterate,
            time_verify: self.time_verify,
            factor_backward_error: self.backward,
            memory: self.tally.memory,
        }
    }

    /// Iterate, refine, check; when the Sturm check shows a mode missed, iterate again for
    /// more modes with the pairs found locked (at most four rounds). `early` is a result the
    /// shift's probe already converged to; `ti` started the iteration.
    fn run(
        mut self,
        mut lz: Lanczos,
        fa: Factor,
        mut want: usize,
        mut early: Option<(Vec<f64>, Mat<f64>)>,
        ti: Instant,
    ) -> Result<EigenSolution> {
        let Problem { k, m, sym, p, .. } = *self.pb;
        let n = k.n();
        let mut attempt = 0;
        // The shift factor is dropped before each Sturm factorisation, so that two factors
        // never coexist in memory; it is rebuilt only if the check asks for more iteration.
        let mut fa = Some(fa);
        loop {
            attempt += 1;
            let ti_round = Instant::now();
            if fa.is_none() {
                log::info!("factorising K − σM at the shift again to iterate for more modes");
                fa = Some(
                    factor_at_checked(
                        k,
                        m,
                        sym,
                        self.sigma,
                        &mut self.tally.factorizations,
                        p.shift.is_some(),
                        true,
                        None,
                    )?
                    .0,
                );
            }
            let f = fa
                .as_ref()
                .ok_or_else(|| Error::Factorization("lost the shift factor".into()))?;
            if !self.dense {
                lz.set_want(want - null_count(self.null));
            }
            let (lambda, x) = self.iterate_once(&mut lz, f, early.take())?;
            self.time_iterate += if attempt == 1 {
                ti.elapsed().as_secs_f64()
            } else {
                ti_round.elapsed().as_secs_f64()
            };
            // Verify: Sturm counts around the modes found.
            let tv = Instant::now();
            if let Some(f) = &fa {
                self.tally.memory.add_solves(f);
            }
            fa = None;
            let found = self.found(&lambda);
            let (upper_pt, lower_pt) = check_points(&found, p, self.band, self.sigma, &lz);
            // The basis is not needed for the check: free it before the Sturm factorisations
            // (the rare second round, when a mode was missed, starts a new iteration).
            if !self.dense {
                lz.release();
            }
            let sturm = self.sturm_counts(&found, lower_pt, upper_pt)?;
            self.time_verify += tv.elapsed().as_secs_f64();
            if sturm.expected > sturm.found && attempt < 4 && self.band.is_none() && !self.dense {
                // A mode was missed (or sits just above the last one found): iterate for more
                // modes, with the pairs found locked at the start of a new basis (the old one
                // was freed for the Sturm factorisation).
                want = (want + (sturm.expected - sturm.found) + p.block.min(4)).min(n);
                log::info!("iterating again for {want} modes, the {} found locked", lambda.len());
                // The deflated vectors are among the pairs found: locked with them from here.
                self.null = None;
                lz.deflate = None;
                lz.set_want(want.max(lambda.len()));
                lz.restart_from(&lambda, x.as_ref(), m, self.sigma);
                continue;
            }
            return Ok(self.finish(&lambda, &x, &found, sturm));
        }
    }

    /// One round's pairs: a dense solve, or Lanczos (from `early` if the probe converged)
    /// followed by one refinement step when the result is to be proved.
    fn iterate_once(
        &mut self,
        lz: &mut Lanczos,
        f: &Factor,
        early: Option<(Vec<f64>, Mat<f64>)>,
    ) -> Result<(Vec<f64>, Mat<f64>)> {
        let Problem { k, m, p, check, .. } = *self.pb;
        let sigma = self.sigma;
        if self.dense {
            // Most of the spectrum: reduce through M, which keeps the upper modes accurate.
            let (l, x) = super::dense::eigen_all(k, m, sigma, true)?;
            lz.last_theta = l.iter().map(|l| 1.0 / (l - sigma)).collect();
            return Ok((l, x));
        }
        let res = match early {
            Some(r) => Some(r),
            None => lz.run(p, f, m, sigma, &mut self.tally.applications)?,
        };
        let (l, x) = res.ok_or_else(|| Error::EigenNotConverged("the iteration paused unexpectedly".into()))?;
        let memory = &mut self.tally.memory;
        memory.add_iteration(&mut lz.times);
        memory.lanczos_basis = memory.lanczos_basis.max(lz.peak_bytes());
        memory.solve_workspace = memory.solve_workspace.max(f.workspace_bytes() as u64);
        // The basis is not needed past this point (a second round starts a new one from the
        // pairs found): free it before the refinement's blocks are allocated.
        lz.release();
        log::info!(
            "Lanczos: {} pairs converged after {} operator applications",
            l.len(),
            self.tally.applications
        );
        // One step of inverse iteration and a Rayleigh–Ritz on the result: damps the
        // high-frequency rounding the Krylov vectors carry (which K amplifies in the residual)
        // at the cost of one block solve.
        let null = self.null;
        if check {
            self.tally.applications += x.ncols();
            let y = inverse_images(m, f, x.as_ref());
            drop(x);
            ritz_deflated(k, m, null, y)
        } else {
            Ok(with_null(null, l, x))
        }
    }

    /// The pairs found as (λ, index), ascending; for a band, those in it.
    fn found(&self, lambda: &[f64]) -> Vec<(f64, usize)> {
        let mut found: Vec<(f64, usize)> = lambda.iter().copied().enumerate().map(|(i, l)| (l, i)).collect();
        found.sort_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((lo, hi)) = self.band {
            // A band from 0 (or below) includes the rigid-body modes, whose computed λ rounds
            // to either side of 0: keep everything above the lower Sturm point (the shift),
            // which is what the count includes.
            let sigma = self.sigma;
            found.retain(|(l, _)| (*l >= lo || (lo <= 0.0 && *l > sigma)) && *l <= hi);
        }
        found
    }

    /// The Sturm counts at the check points (a factorisation at each, unless the count is
    /// known: the shift's, a band's upper end's, or none asked for) and the pairs found between.
    fn sturm_counts(&mut self, found: &[(f64, usize)], lower_pt: f64, upper_pt: f64) -> Result<SturmCheck> {
        let Problem { k, m, sym, check, .. } = *self.pb;
        let lower_count = if lower_pt == self.sigma || !check {
            self.lower_count_at_shift
        } else {
            log::info!("factorisation at {lower_pt:.6e} for the lower Sturm count");
            let (fl, _) = factor_at(k, m, sym, lower_pt, &mut self.tally.factorizations)?;
            self.tally.memory.add_factor(&fl);
            self.backward = self.backward.max(fl.probe_residual);
            fl.negative_pivots
        };
        let (upper_pt, upper_count) = match self.upper_known {
            Some((asked, used, count)) if asked == upper_pt => (used, count),
            // No proof asked for: the count is taken as what was found.
            _ if !check => (
                upper_pt,
                lower_count + found.iter().filter(|(l, _)| *l > lower_pt && *l < upper_pt).count(),
            ),
            _ => {
                log::info!("factorisation at {upper_pt:.6e} for the upper Sturm count");
                let (fu, used) = factor_at(k, m, sym, upper_pt, &mut self.tally.factorizations)?;
                self.tally.memory.add_factor(&fu);
                self.backward = self.backward.max(fu.probe_residual);
                (used, fu.negative_pivots)
            }
        };
        let n_between = found.iter().filter(|(l, _)| *l > lower_pt && *l < upper_pt).count();
        let expected = upper_count.saturating_sub(lower_count);
        if check {
            log::info!(
                "Sturm check: {expected} eigenvalues in ({lower_pt:.6e}, {upper_pt:.6e}) rad²/s², {n_between} found"
            );
        }
        // The lowest modes asked for (the default shift): an eigenvalue below the lower point
        // is a lower mode not found (a preload past buckling has them far below the shift).
        let lowest = self.band.is_none() && self.pb.p.shift.is_none();
        Ok(SturmCheck {
            lower: (lower_pt, lower_count),
            upper: (upper_pt, upper_count),
            expected,
            found: n_between,
            complete: expected == n_between && !(check && lowest && lower_count > 0),
        })
    }

    /// The requested pairs (the nearest the shift, or a band's) in ascending order, verified.
    fn finish(mut self, lambda: &[f64], x: &Mat<f64>, found: &[(f64, usize)], sturm: SturmCheck) -> EigenSolution {
        let Problem { k, m, p, check, .. } = *self.pb;
        let sigma = self.sigma;
        // Keep the requested count (lowest / nearest) in ascending order.
        let keep: Vec<usize> = match p.target {
            Target::Nearest(nm) => {
                let mut by_dist: Vec<(f64, usize)> = found.iter().map(|&(l, i)| ((l - sigma).abs(), i)).collect();
                by_dist.sort_by(|a, b| a.0.total_cmp(&b.0));
                let mut idx: Vec<usize> = by_dist.iter().take(nm).map(|x| x.1).collect();
                idx.sort_by(|&a, &b| lambda[a].total_cmp(&lambda[b]));
                idx
            }
            Target::Band(..) => found.iter().map(|x| x.1).collect(),
        };
        let tv = Instant::now();
        let (lam, vectors) = select(lambda, x, &keep);
        let verified = if check {
            verify_with_backward_errors(k, m, &lam, vectors.as_ref(), sigma)
        } else {
            (vec![f64::NAN; lam.len()], f64::NAN, vec![f64::NAN; lam.len()])
        };
        self.time_verify += tv.elapsed().as_secs_f64();
        self.solution(lam, vectors, verified, sturm)
    }
}

/// The pairs `keep` of (λ, X), in that order.
fn select(lambda: &[f64], x: &Mat<f64>, keep: &[usize]) -> (Vec<f64>, Mat<f64>) {
    let mut vectors = Mat::zeros(x.nrows(), keep.len());
    for (c, &i) in keep.iter().enumerate() {
        vectors.col_mut(c).copy_from(x.col(i));
    }
    (keep.iter().map(|&i| lambda[i]).collect(), vectors)
}

/// Two eigenvalues found closer than this, relative to the spectrum's scale, are taken for
/// copies of one repeated root: a Sturm point is never placed between them.
const SAME_ROOT: f64 = 2e-9;

/// Positions in `found` (ascending) of the lowest and the highest pair kept for the request:
/// the `nm` nearest the shift (ties in the order found), or all of a band's.
fn kept_span(found: &[(f64, usize)], target: Target, sigma: f64) -> (usize, usize) {
    let last = found.len().saturating_sub(1);
    match target {
        Target::Band(..) => (0, last),
        Target::Nearest(nm) => {
            let mut by_dist: Vec<(f64, usize)> = found
                .iter()
                .enumerate()
                .map(|(i, f)| ((f.0 - sigma).abs(), i))
                .collect();
            by_dist.sort_by(|a, b| a.0.total_cmp(&b.0));
            let kept = by_dist.iter().take(nm.max(1)).map(|x| x.1);
            (kept.clone().min().unwrap_or(0), kept.max().unwrap_or(last))
        }
    }
}

/// The Sturm check points (upper, lower) around the pairs `found` (ascending). A request that
/// ends inside a multiplet is extended to the whole multiplet: the upper point lies in the first
/// clear gap of `found` above the highest kept pair (halfway across it: it cannot pass an
/// eigenvalue that is simply the next one, nor split a repeated root), and for a user shift the
/// lower point in the first clear gap below the lowest kept pair. When `found` has no such gap
/// above, the upper point is just above the highest mode found, a small relative step, or half
/// the way to the next Ritz estimate if that is closer (Ritz estimates of unconverged values lie
/// above the true ones, so a far point could pass an eigenvalue that is simply the next one,
/// costing an extra round of iteration); below, the shift itself when nothing kept lies under
/// it (its count is known), else just below the lowest mode found. A band's upper point is its
/// upper end.
fn check_points(
    found: &[(f64, usize)],
    p: &EigenParams,
    band: Option<(f64, f64)>,
    sigma: f64,
    lz: &Lanczos,
) -> (f64, f64) {
    let lam_min = found.first().map_or(sigma, |f| f.0);
    let lam_max = found.last().map_or(sigma, |f| f.0);
    let scale = lam_max.abs().max(sigma.abs());
    let gap_below = |e: usize| found[e].0 - found[e - 1].0 > SAME_ROOT * scale;
    let (lo, hi) = kept_span(found, p.target, sigma);
    let upper_pt = match band {
        Some((_, b_hi)) => b_hi,
        None => match (hi + 1..found.len()).find(|&e| gap_below(e)) {
            Some(e) => 0.5 * (found[e - 1].0 + found[e].0),
            None => {
                let mut step = 1e-4 * scale;
                if let Some(nx) = lz.next_estimate_above(lam_max, sigma) {
                    step = step.min(0.5 * (nx - lam_max));
                }
                // Not closer than 1e-6 of the scale (as the lower point below): the found λ is
                // only as exact as its residual allows (a relative residual up to 1e-6 passes
                // without a note). Nor closer than twice the refinement's move of the highest
                // pair: on ill-conditioned models (a 1 mm free sheet, relative residuals ~1e-4)
                // it moved by 7e-5 relative, and a point at 1e-6 fell below the true eigenvalue.
                let moved = lz.returned_max(sigma).map_or(0.0, |r| (r - lam_max).abs());
                lam_max + step.max(1e-6 * scale).max(2.0 * moved)
            }
        },
    };
    // The first pair of the lowest kept multiplet (the default shift keeps the lowest: 0).
    let first = if band.is_none() && p.shift.is_some() {
        (1..=lo.min(found.len().saturating_sub(1)))
            .rev()
            .find(|&s| gap_below(s))
            .unwrap_or(0)
    } else {
        0
    };
    let lower_pt = match found.get(first) {
        Some(f) if f.0 >= sigma && (first == 0 || found[first - 1].0 < sigma) => sigma,
        Some(f) if first > 0 => 0.5 * (found[first - 1].0 + f.0),
        _ if lam_min >= sigma => sigma,
        _ => lam_min - (lam_min.abs().max(sigma.abs()) * 1e-6),
    };
    (upper_pt, lower_pt)
}

/// Largest relative residual the one-factorisation solve returns; above it (singular mass
/// matrices, stiffness contrasts, where the shift above the modes purifies less) the solve is
/// done again from the default shift, whose residuals are those of the verified reference path.
/// The relative residual ‖Kx − λMx‖/‖Kx‖ of a low mode has a rounding floor of about
/// ε·‖K‖/λ·(U/gap): 1.5e-9 on the first elastic mode of the 66k-DOF plate, where the backward
/// error is 4e-15 and the frequencies agree with the reference path to 1e-13. The bar sits
/// above that floor and at the tests' own bar for a verified mode.
const RESIDUAL_FALLBACK: f64 = 1e-8;

/// What [`solve_below_bound`] shares with the solve that called it.
struct Estimate<'a> {
    /// Start of the solve.
    t0: Instant,
    /// Factorisations done so far.
    factorizations: &'a mut usize,
    /// Large allocations so far.
    memory: &'a mut EigenMemory,
}

/// The one-factorisation solve of [`solve_with`] for the `nm` lowest modes: Galerkin model on
/// `pr`, its eigenvalues λ̃ᵢ ≥ λᵢ, one shift U just above λ̃_nm, Lanczos on K − UM for every
/// eigenvalue below U (θ = 1/(λ − U) < 0), whose number is the factor's inertia. `Ok(None)`
/// when the estimate cannot be used (the caller then solves from its default shift).
///
/// The steps: the coarse estimate ([`coarse_estimate`]); U placed from its bounds
/// ([`bound_shift`]); the factorisation at U and its count; Lanczos below U from the
/// prolongated coarse modes with a first refinement step ([`BelowBound::lanczos`]); further
/// refinement and verification ([`BelowBound::purify`]); more iteration while pairs below U are
/// missing.
#[allow(clippy::too_many_arguments)]
fn solve_below_bound(
    k: &SymMatrix,
    m: &SymMatrix,
    sym: &Arc<SymbolicFactor>,
    p: &EigenParams,
    (pr, prepared): (&Prolongation, Option<CoarseModel>),
    nm: usize,
    est: Estimate<'_>,
    notes: &[String],
    null: Option<&Null>,
    prefault: Option<Prefault>,
) -> Result<Option<EigenSolution>> {
    let n = k.n();
    if pr.n_fine != n || pr.n_coarse <= nm {
        return Ok(None);
    }
    let tc = Instant::now();
    let Some((lc, start)) = coarse_estimate(k, m, p, (pr, prepared), nm, tc)? else {
        return Ok(None);
    };
    // The coarse model's matrices and factor are freed: give the memory back before the
    // model's factor is allocated.
    crate::util::memory::release_free_memory();
    // The next bound positive, or above a negative wanted one (a preload past buckling).
    if lc.len() <= nm || !(lc[nm] > 0.0 || (lc[nm - 1] < 0.0 && lc[nm] > lc[nm - 1])) {
        return Ok(None);
    }
    let zero = default_shift(k, m).abs();
    let Some(u) = bound_shift(&lc, nm, zero) else {
        return Ok(None);
    };
    log::info!(
        "coarse estimate ({} DOFs, {:.2} s): mode {nm} at most {:.6e} rad²/s², the next at most {:.6e}; one factorisation at U = {u:.6e}",
        pr.n_coarse,
        tc.elapsed().as_secs_f64(),
        lc[nm - 1],
        lc[nm]
    );
    // Its probe is solved with the first refinement step's block ([`inverse_images_probed`]).
    let (fa, u) = factor_at_checked(k, m, sym, u, est.factorizations, false, false, prefault)?;
    est.memory.add_factor(&fa);
    let count = fa.negative_pivots;
    if count < nm || count > 2 * nm + 12 {
        log::info!(
            "{count} eigenvalues below U (the {nm} lowest wanted): solving from the default shift instead (another factorisation)"
        );
        return Ok(None);
    }
    let time_factor = est.t0.elapsed().as_secs_f64();
    if let Some(s) = &p.iterating {
        s.set(true);
    }
    let ti = Instant::now();
    // The deflated null vectors (nz < nm ≤ count) are among the eigenvalues below U.
    let nz = null_count(null);
    let mut lz = Lanczos::new(n, count - nz, p, Side::Below);
    lz.keep_image = true;
    lz.start = Some(prolongated(pr, &start));
    lz.deflate = null.cloned();
    let mut bb = BelowBound {
        null,
        k,
        m,
        p,
        fa: &fa,
        u,
        zero,
        count,
        nm,
        applications: 0,
        memory: est.memory,
        probe: None,
    };
    let done = bb.iterate(&mut lz, nz)?;
    let time_iterate = ti.elapsed().as_secs_f64() - done.tv.elapsed().as_secs_f64();
    log::info!(
        "Sturm check: {count} eigenvalues below {u:.6e} rad²/s², {} found ({} refinement step{})",
        done.found,
        done.steps,
        if done.steps == 1 { "" } else { "s" }
    );
    let factor_backward_error = bb.probe();
    bb.memory.add_solves(&fa);
    // The deflated vectors, unless a second round locked them in its basis as ordinary pairs.
    let null = bb.null.and(null);
    let BelowBound {
        memory,
        mut applications,
        ..
    } = bb;
    let (mut done, mut time_factor) = (done, time_factor);
    if done.worst > RESIDUAL_FALLBACK {
        // Refinement at U stalled: once more from below the spectrum, the factor at U freed
        // first (the peak stays one factor); if that fails too, the default-shift solve.
        drop(fa);
        let counts = (&mut *est.factorizations, &mut *memory);
        let Some((d, seconds)) = refine_below_spectrum((k, m, sym), null, &done, u, counts, &mut applications)? else {
            return Ok(None);
        };
        (done, time_factor) = (d, time_factor + seconds);
    } else {
        // The factor is not needed any more: freed while the caller post-processes.
        crate::util::memory::drop_in_background(fa);
    }
    let (rel_residual, m_orthonormality, backward_error) = done.verified;
    Ok(Some(EigenSolution {
        lambda: done.lambda,
        vectors: done.vectors,
        rel_residual,
        backward_error,
        notes: notes.to_vec(),
        m_orthonormality,
        // Below −∞ there is nothing: the count at U alone is the whole check.
        sturm: SturmCheck {
            lower: (f64::NEG_INFINITY, 0),
            upper: (u, count),
            expected: count,
            found: done.found,
            complete: done.found == count,
        },
        shift: u,
        applications,
        factorizations: *est.factorizations,
        time_factor,
        time_iterate,
        time_verify: done.tv.elapsed().as_secs_f64(),
        factor_backward_error,
        memory: *memory,
    }))
}

/// One refinement step of the pairs `done` of a one-factorisation solve with a factorisation
/// below the spectrum (at the default shift), for when refinement at U stalled above
/// [`RESIDUAL_FALLBACK`]. Inverse iteration at U damps the modes far above U, but it amplifies
/// those between U and 2U against the lowest modes (on a clamped 66k-DOF plate, mode 1's
/// relative residual went 1.3e-7, 5.2e-7, 3.0e-5 in three steps); a shift below the spectrum
/// damps every higher mode against each. The deflated null vectors are kept as they are.
/// Returns the verified pairs and the factorisation's seconds; `None` when the largest
/// relative residual is still above the bar or a pair is no longer below U.
fn refine_below_spectrum(
    (k, m, sym): (&SymMatrix, &SymMatrix, &Arc<SymbolicFactor>),
    null: Option<&Null>,
    done: &Purification,
    u: f64,
    (count, memory): (&mut usize, &mut EigenMemory),
    applications: &mut usize,
) -> Result<Option<(Purification, f64)>> {
    let nz = null_count(null);
    let sigma = default_shift(k, m);
    // Its probe rides along the step's block solve (warned about there, as for the one at U).
    let (fb, sigma) = factor_at_checked(k, m, sym, sigma, count, false, false, None)?;
    memory.add_factor(&fb);
    let x = done.vectors.get(.., nz..);
    *applications += x.ncols();
    let (y, _) = inverse_images_probed(k, m, &fb, sigma, x);
    memory.add_solves(&fb);
    let seconds = fb.numeric_seconds;
    drop(fb);
    let (lambda, vectors) = ritz_deflated(k, m, null, y)?;
    let tv = Instant::now();
    let verified = verify_with_backward_errors(k, m, &lambda, vectors.as_ref(), u);
    let worst = verified.0.iter().fold(0.0f64, |a, &r| a.max(r));
    log::info!(
        "refinement at U stalled at a relative residual of {:.1e}: one step from σ = {sigma:.3e} below the spectrum gives {worst:.1e}",
        done.worst
    );
    if !(worst <= RESIDUAL_FALLBACK) || lambda.len() != done.lambda.len() || lambda.iter().any(|&l| l >= u) {
        log::info!(
            "one-factorisation solve: largest relative residual {worst:.1e} (above {RESIDUAL_FALLBACK:.0e}): solving again from the default shift"
        );
        return Ok(None);
    }
    let refined = Purification {
        lambda,
        vectors,
        verified,
        found: done.found,
        steps: done.steps + 1,
        worst,
        tv,
    };
    Ok(Some((refined, seconds)))
}

/// The coarse model on `pr` (PᵀKP, PᵀMP) and its `nm + 1` lowest eigenpairs, unproved:
/// (λ̃ ascending, vectors in the same order); `None` when its solve failed. The coarse model
/// lives only here: its matrices and factor are freed before the model's factorisation (at 1M
/// DOFs they would be ~0.5 GB at the peak). `tc` started the estimate.
fn coarse_estimate(
    k: &SymMatrix,
    m: &SymMatrix,
    p: &EigenParams,
    (pr, prepared): (&Prolongation, Option<CoarseModel>),
    nm: usize,
    tc: Instant,
) -> Result<Option<(Vec<f64>, Mat<f64>)>> {
    let cm = match prepared {
        Some(cm) if cm.k.n() == pr.n_coarse => {
            log::debug!(
                "coarse model: formed alongside the ordering, {} entries in L",
                cm.symbolic.nnz_l
            );
            cm
        }
        _ => {
            let cm = CoarseModel::new(pr, k, m)?;
            log::debug!(
                "coarse model: PᵀKP, PᵀMP and ordering {:.3} s, {} entries in L",
                tc.elapsed().as_secs_f64(),
                cm.symbolic.nnz_l
            );
            cm
        }
    };
    let CoarseModel {
        k: kc,
        m: mc,
        symbolic: symc,
    } = cm;
    // Ritz values converged to 1e-6 are within ~1e-12 of the coarse eigenvalues (the error of
    // a Ritz value is of the order of its residual squared): ample for placing a shift.
    // The model's null-space candidates at the corners are the coarse model's (exact for
    // rigid motions, which the corner space holds on straight cells; verified there anyway).
    // An estimate that does not converge quickly is abandoned for the default-shift solve:
    // the 18 modes of the 119k-DOF plate take 60 applications, a cantilever with a tip mass
    // 6e8 times its own (1059 coarse unknowns) stalled for 20 000 (5.4 s) before.
    let pc = EigenParams {
        target: Target::Nearest(nm + 1),
        tol: 1e-6,
        max_applications: (COARSE_APPLICATIONS_PER_MODE * (nm + 1) + 200).min(p.max_applications),
        null_candidates: p
            .null_candidates
            .as_ref()
            .and_then(|c| pr.inject((*c.0).as_ref()))
            .map(|z| NullCandidates(Arc::new(z))),
        ..p.clone()
    };
    let coarse = match solve_inner(&kc, &mc, &symc, &pc, None, false) {
        Ok(c) => c,
        Err(e) => {
            log::info!("coarse estimate failed ({e}): solving from the default shift");
            return Ok(None);
        }
    };
    log::debug!(
        "coarse solve: factor {:.3} s, iterate {:.3} s, verify {:.3} s, {} applications",
        coarse.time_factor,
        coarse.time_iterate,
        coarse.time_verify,
        coarse.applications
    );
    // Ascending, as every solve returns them, with the vectors in the same order.
    Ok(Some((coarse.lambda, coarse.vectors)))
}

/// Operator applications per wanted mode (plus 200) after which the coarse estimate gives up.
const COARSE_APPLICATIONS_PER_MODE: usize = 30;

/// The shift U from the coarse bounds `lc` (ascending, more than `nm`): just above the bound of
/// the last wanted eigenvalue, so that every wanted one lies below, and few others (the coarse
/// gap to the next is no promise for the model's). When the wanted ones are rigid-body modes
/// (the bound at the rounding level of λ = 0, at most `zero`, the default shift's magnitude),
/// halfway to the first elastic bound; when the next is one too, `None`: the estimate places
/// nothing (rigid-body modes only: the default solve).
fn bound_shift(lc: &[f64], nm: usize, zero: f64) -> Option<f64> {
    let (a, b) = (lc[nm - 1], lc[nm]);
    if a < -zero && b > a {
        // A clearly negative bound: a preload past buckling (K + K_σ indefinite). The lowest
        // modes are the most negative ones, and the fine model has more negative eigenvalues
        // than the coarse one shows: U just above the bound (which the nm-th eigenvalue lies
        // below) rather than halfway to the next, which would take in all of them.
        return Some(a + (0.5 * (b - a)).min(0.02 * -a));
    }
    if a <= zero {
        if b <= zero {
            return None;
        }
        Some(0.5 * b)
    } else {
        Some(a + (0.5 * (b - a)).min(0.02 * a).max(1e-4 * a))
    }
}

/// The coarse modes `cv`, prolongated: a start block with large components in the wanted modes
/// (66 instead of 90 operator applications for 12 modes of a 119k-DOF tet10 plate); its random
/// part keeps every other mode reachable, and the count at U proves that none was missed.
fn prolongated(pr: &Prolongation, cv: &Mat<f64>) -> Mat<f64> {
    let mut st = Mat::zeros(pr.n_fine, cv.ncols());
    for j in 0..cv.ncols() {
        let xc: Vec<f64> = (0..cv.nrows()).map(|i| cv[(i, j)]).collect();
        for (i, v) in pr.apply(&xc).into_iter().enumerate() {
            st[(i, j)] = v;
        }
    }
    st
}

/// The iteration of [`solve_below_bound`] on the factorisation at U.
struct BelowBound<'a, 'm> {
    /// Deflated null vectors of K and their M-images ([`null_vectors`]), put before the pairs
    /// of each Lanczos run (at λ = 0); `None` once a second round locks them in its basis.
    null: Option<&'a Null>,
    k: &'a SymMatrix,
    m: &'a SymMatrix,
    p: &'a EigenParams,
    /// The factorisation of K − UM.
    fa: &'a Factor,
    u: f64,
    /// The rounding level of λ = 0 (the default shift's magnitude).
    zero: f64,
    /// Eigenvalues below U (the factor's inertia).
    count: usize,
    /// Modes wanted.
    nm: usize,
    applications: usize,
    memory: &'m mut EigenMemory,
    /// Probe backward error of `fa` ([`Factor::probe_residual`]), once a solve has carried it.
    probe: Option<f64>,
}

/// The largest relative residual of verified pairs, or, when a pair's backward error is above
/// the acceptance bar `verify_tol`, that error scaled to [`RESIDUAL_FALLBACK`] (above the bar:
/// refine again). Relative residuals measure a mode of λ ≈ 0 against the spectrum's scale, so
/// alone they pass the modes of a large point mass on a support (λ ~ 1e-4 rad²/s²) whose
/// backward errors are above the bar.
fn worst_of(verified: &(Vec<f64>, f64, Vec<f64>), verify_tol: f64) -> f64 {
    let res = verified.0.iter().fold(0.0f64, |a, &r| a.max(r));
    let bwd = verified.2.iter().fold(0.0f64, |a, &r| a.max(r));
    res.max(bwd * (RESIDUAL_FALLBACK / verify_tol))
}

/// A verified result of [`BelowBound::purify`].
struct Purification {
    /// The `nm` lowest pairs.
    lambda: Vec<f64>,
    vectors: Mat<f64>,
    /// Their relative residuals, M-orthonormality and backward errors.
    verified: (Vec<f64>, f64, Vec<f64>),
    /// Pairs found below U.
    found: usize,
    /// Refinement steps taken.
    steps: usize,
    /// Largest relative residual.
    worst: f64,
    /// Start of the last verification.
    tv: Instant,
}

/// What [`BelowBound::purify`] made of the pairs of one Lanczos run.
enum Purified {
    /// Fewer pairs below U than its count (`below` of them): iterate on from these.
    Short {
        lambda: Vec<f64>,
        x: Mat<f64>,
        below: usize,
    },
    /// Every pair below U found (or no round left), verified.
    Done(Purification),
}

impl BelowBound<'_, '_> {
    /// Lanczos rounds below U, each purified, until every one of the `count` pairs below U is
    /// found (or the rounds are spent): a round short of pairs iterates on with the pairs
    /// found locked at the start of a new basis. `nz`: null vectors deflated.
    fn iterate(&mut self, lz: &mut Lanczos, nz: usize) -> Result<Purification> {
        let (n, count, p, m, u) = (self.k.n(), self.count, self.p, self.m, self.u);
        let mut want = count - nz;
        let mut attempt = 0;
        loop {
            attempt += 1;
            lz.set_want(want);
            let (lambda, x) = self.lanczos(lz)?;
            match self.purify(lambda, x, attempt)? {
                Purified::Short { lambda, x, below } => {
                    // A cluster wider than the block, or a pair that had not converged: iterate
                    // on, with the pairs found locked at the start of a new basis.
                    want = (want + (count - below) + p.block.min(4)).min(n);
                    // The deflated pairs are among those found: from here on they are locked
                    // in the basis like the others.
                    if self.null.take().is_some() {
                        lz.deflate = None;
                        want = (want + nz).min(n);
                    }
                    log::info!(
                        "{below} of the {count} eigenvalues below U found: iterating for more, the pairs found locked"
                    );
                    lz.set_want(want.max(lambda.len()));
                    lz.restart_from(&lambda, x.as_ref(), m, u);
                }
                Purified::Done(d) => return Ok(d),
            }
        }
    }

    /// A⁻¹MX, the first time with the factor's probe solved along ([`inverse_images_probed`]).
    fn images(&mut self, x: MatRef<'_, f64>) -> Mat<f64> {
        if self.probe.is_some() {
            return inverse_images(self.m, self.fa, x);
        }
        let (y, probe) = inverse_images_probed(self.k, self.m, self.fa, self.u, x);
        self.probe = Some(probe);
        y
    }

    /// The factor's probe backward error, solved on its own if no block carried it.
    fn probe(&mut self) -> f64 {
        if self.probe.is_none() {
            let _ = self.images(Mat::zeros(self.k.n(), 0).as_ref());
        }
        self.probe.unwrap_or(f64::NAN)
    }

    /// A Lanczos run for the pairs below U, then a first refinement step: inverse iteration
    /// with Rayleigh–Ritz at U.
    fn lanczos(&mut self, lz: &mut Lanczos) -> Result<(Vec<f64>, Mat<f64>)> {
        let (k, m, p, fa) = (self.k, self.m, self.p, self.fa);
        let (l, x) = lz
            .run(p, fa, m, self.u, &mut self.applications)?
            .ok_or_else(|| Error::EigenNotConverged("the iteration paused unexpectedly".into()))?;
        self.memory.add_iteration(&mut lz.times);
        self.memory.lanczos_basis = self.memory.lanczos_basis.max(lz.peak_bytes());
        self.memory.solve_workspace = self.memory.solve_workspace.max(fa.workspace_bytes() as u64);
        log::debug!(
            "Lanczos done: resident {} MiB, peak so far {} MiB",
            crate::util::memory::resident_memory().unwrap_or(0) >> 20,
            crate::util::memory::peak_memory().unwrap_or(0) >> 20
        );
        lz.release();
        // The iteration's freed blocks stay in the allocator's heaps (~40 MiB at 119k DOFs):
        // give them back before the refinement allocates its own.
        crate::util::memory::release_free_memory();
        log::info!(
            "Lanczos: {} pairs below U converged after {} operator applications",
            l.len(),
            self.applications
        );
        // Inverse iteration with Rayleigh–Ritz at U purifies the modes. With the shift above
        // them, one step damps a high-frequency error component at λ_h only by
        // |λ − U|/|λ_h − U| (against |λ − σ|/|λ_h − σ| from a shift below them): a second step
        // is taken when the first leaves a residual above RESIDUAL_FALLBACK (one step gave
        // at most 1.5e-9 on the 20k–119k-DOF plates, and a second 4× less where it was above
        // the rounding floor: not worth its solve). The first step solves only for the lowest
        // elastic modes and takes the other images from the Lanczos relation (see
        // [`image_with_solves`]: 6 solved columns instead of 19 for 18 modes of the plates);
        // the further steps, when needed, solve for every column.
        let y = match lz.image.take() {
            Some(y) if y.ncols() == x.ncols() && y.ncols() == l.len() => {
                let solved = lowest_elastic(&l, self.zero, p.block.max(1));
                self.applications += solved.len();
                image_with_solves(&x, y, &solved, |xs| self.images(xs))
            }
            _ => {
                self.applications += x.ncols();
                self.images(x.as_ref())
            }
        };
        // The Lanczos vectors are spent: free them before the Rayleigh–Ritz step allocates.
        drop(x);
        ritz_deflated(k, m, self.null, y)
    }

    /// The pairs below U, verified, refined again (up to three steps in all) while their
    /// largest relative residual is above [`RESIDUAL_FALLBACK`]; `Short` when fewer than the
    /// count are below U and `attempt` (the Lanczos round) leaves room for another round.
    fn purify(&mut self, lambda: Vec<f64>, x: Mat<f64>, attempt: usize) -> Result<Purified> {
        let (k, m, u) = (self.k, self.m, self.u);
        let (mut lambda, mut x) = (lambda, x);
        let mut steps = 1;
        // The best step so far: a step that raised the largest residual is undone (refinement
        // at U can amplify the modes between U and 2U, see [`refine_below_spectrum`]).
        let mut best: Option<Purification> = None;
        loop {
            let mut below: Vec<usize> = (0..lambda.len()).filter(|&i| lambda[i] < u).collect();
            below.sort_by(|&i, &j| lambda[i].total_cmp(&lambda[j]));
            if below.len() < self.count && attempt < 4 {
                return Ok(Purified::Short {
                    lambda,
                    x,
                    below: below.len(),
                });
            }
            let tv = Instant::now();
            let (lam, vectors) = select(&lambda, &x, &below[..self.nm.min(below.len())]);
            let verified = verify_with_backward_errors(k, m, &lam, vectors.as_ref(), u);
            let worst = worst_of(&verified, self.p.verify_tol);
            let this = Purification {
                lambda: lam,
                vectors,
                verified,
                found: below.len(),
                steps,
                worst,
                tv,
            };
            if let Some(b) = best.take_if(|b| b.worst < worst) {
                log::debug!("refinement step {steps} raised the largest relative residual to {worst:.1e}: undone");
                return Ok(Purified::Done(b));
            }
            if worst > RESIDUAL_FALLBACK && steps < 3 {
                log::debug!("after {steps} refinement step(s): largest relative residual {worst:.1e}, refining again");
                self.applications += x.ncols();
                (lambda, x) = refine(k, m, self.fa, &x)?;
                steps += 1;
                best = Some(this);
                continue;
            }
            return Ok(Purified::Done(this));
        }
    }
}

/// A warning when a factorisation's probe backward error ([`Factor::probe_residual`]) is above
/// 1e-8: pivot growth, results not to be trusted (the run's accuracy verdict says so too).
fn warn_probe(sigma: f64, probe: f64) {
    if probe > 1e-8 {
        log::warn!("factorisation of K − σM at σ = {sigma:.6e}: probe backward error {probe:.1e}");
    }
}

/// Y = A⁻¹MX with the probe of A's factor ([`Factor::probe_rhs`]) solved as one more column
/// of the same block solve rather than as a solve of its own (a pass over the factor, ~0.06 s at
/// 119k DOFs): (Y, probe backward error).
fn inverse_images_probed(k: &SymMatrix, m: &SymMatrix, fa: &Factor, sigma: f64, x: MatRef<'_, f64>) -> (Mat<f64>, f64) {
    let (n, c) = (x.nrows(), x.ncols());
    let shift = Some((m, sigma));
    let b = Factor::probe_rhs(k, shift);
    let mut y = Mat::zeros(n, c + 1);
    m.mul_block(x, y.get_mut(.., 0..c));
    for (i, v) in b.iter().enumerate() {
        y[(i, c)] = *v;
    }
    fa.solve_in_place(y.as_mut());
    let yb: Vec<f64> = (0..n).map(|i| y[(i, c)]).collect();
    let probe = Factor::probe_error(k, shift, &b, &yb);
    warn_probe(sigma, probe);
    (y.get(.., 0..c).to_owned(), probe)
}

/// Factor K − σM; if σ sits exactly on an eigenvalue (zero pivot), nudge it.
fn factor_at(
    k: &SymMatrix,
    m: &SymMatrix,
    sym: &Arc<SymbolicFactor>,
    sigma: f64,
    count: &mut usize,
) -> Result<(Factor, f64)> {
    factor_at_checked(k, m, sym, sigma, count, false, true, None)
}

/// [`factor_at`]; with `strict`, a pivot below 1e-8 of its own diagonal entry
/// (σ on an eigenvalue) also moves the shift. Only a user's operator shift is checked so:
/// Sturm points need only the count, and small shifts next to rigid-body modes are
/// legitimately ill-conditioned (their pivots are small without being wrong). Without `probe`,
/// the factor's probe is left to the caller (who solves it along with a block of its own:
/// [`inverse_images_probed`]). The first attempt factors into `buffer` when given (a
/// [`Prefault`] for this structure).
#[allow(clippy::too_many_arguments)]
fn factor_at_checked(
    k: &SymMatrix,
    m: &SymMatrix,
    sym: &Arc<SymbolicFactor>,
    sigma: f64,
    count: &mut usize,
    strict: bool,
    probe: bool,
    mut buffer: Option<Prefault>,
) -> Result<(Factor, f64)> {
    let mut s = sigma;
    let mut last_err = None;
    // Moves of 1e-7 … 1e-2 relative: a shift given on an eigenvalue (to ten digits) still
    // failed the strict test at 1e-4 and passes at ~1e-3; the shift only orders the modes.
    for i in 0..6 {
        *count += 1;
        let f = match buffer.take() {
            Some(b) => Factor::new_shifted_prefaulted(sym.clone(), k, Some((m, s)), b),
            None => Factor::new_shifted(sym.clone(), k, Some((m, s))),
        };
        match f {
            Ok(mut f) if !strict || f.min_rel_pivot > 1e-8 => {
                if probe {
                    f.probe_shifted(k, Some((m, s)));
                    warn_probe(s, f.probe_residual);
                }
                return Ok((f, s));
            }
            Ok(_) => {
                last_err = Some(Error::Factorization(format!(
                    "K − σM numerically singular at σ = {s:.6e} rad²/s² ({} Hz)",
                    crate::io::fmt_sig(crate::post::modal::hz(s), 8)
                )))
            }
            Err(e) => last_err = Some(e),
        }
        // Move off the eigenvalue by a relative amount that grows each try. Near 0 (a free
        // body's rigid-body modes) "relative" means relative to the spectrum's scale, the
        // magnitude of the default shift: a step relative to σ itself would be nothing.
        let floor = default_shift(k, m).abs();
        if s.abs() < floor {
            s += floor * 10f64.powi(i) * if s >= 0.0 { 1.0 } else { -1.0 };
            continue;
        }
        let scale = s.abs().max(1e-300);
        s += scale * 1e-7 * 10f64.powi(i) * if s >= 0.0 { 1.0 } else { -1.0 };
    }
    Err(last_err.unwrap_or_else(|| Error::Factorization("factorisation failed".into())))
}

/// Rayleigh–Ritz refinement of approximate eigenvectors X: Y = A⁻¹MX, then the k×k pencil
/// (YᵀKY, YᵀMY) gives eigenvalues and M-orthonormal vectors in span(Y), ascending.
fn refine(k: &SymMatrix, m: &SymMatrix, fa: &Factor, x: &Mat<f64>) -> Result<(Vec<f64>, Mat<f64>)> {
    rayleigh_ritz(k, m, inverse_images(m, fa, x.as_ref()))
}

/// Y = A⁻¹MX, one block solve.
fn inverse_images(m: &SymMatrix, fa: &Factor, x: MatRef<'_, f64>) -> Mat<f64> {
    let mut y = Mat::zeros(x.nrows(), x.ncols());
    m.mul_block(x, y.as_mut());
    fa.solve_in_place(y.as_mut());
    y
}

/// Indices of the (at most) `count` lowest eigenvalues above `zero` (the elastic ones).
fn lowest_elastic(lambda: &[f64], zero: f64, count: usize) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..lambda.len()).filter(|&i| lambda[i] > zero).collect();
    idx.sort_by(|&i, &j| lambda[i].total_cmp(&lambda[j]));
    idx.truncate(count);
    idx
}

/// Op·X = A⁻¹MX for a refinement step: `image` (from the Lanczos relation, no solve) with the
/// columns `solved` replaced by true solves. The relation carries the rounding of X itself,
/// which K amplifies by λ_max/λ in the relative residual ‖Kx − λMx‖/‖Kx‖, so the low elastic
/// modes get the solve, which damps it (6.4e-9 → 1.1e-9 on mode 7 of the 119k-DOF plate; the
/// higher modes 1e-10–7e-10, the backward errors ≤ 5e-14 either way).
fn image_with_solves(
    x: &Mat<f64>,
    mut image: Mat<f64>,
    solved: &[usize],
    images: impl FnOnce(MatRef<'_, f64>) -> Mat<f64>,
) -> Mat<f64> {
    if solved.is_empty() {
        return image;
    }
    let xs = Mat::from_fn(x.nrows(), solved.len(), |i, j| x[(i, solved[j])]);
    let ys = images(xs.as_ref());
    for (j, &c) in solved.iter().enumerate() {
        image.col_mut(c).copy_from(ys.col(j));
    }
    image
}

/// The Rayleigh–Ritz step of [`refine`] on Y = A⁻¹MX however it was formed: eigenvalues and
/// M-orthonormal vectors of the pencil (K, M) in span(Y), ascending.
fn rayleigh_ritz(k: &SymMatrix, m: &SymMatrix, y: Mat<f64>) -> Result<(Vec<f64>, Mat<f64>)> {
    let (n, c) = (y.nrows(), y.ncols());
    // One product at a time (each Gram matrix is all that is kept of it).
    let gram_of = |a: &SymMatrix| {
        let mut ay = Mat::zeros(n, c);
        a.mul_block(y.as_ref(), ay.as_mut());
        tall::gram(y.as_ref(), ay.as_ref())
    };
    let kh = gram_of(k);
    let mh = gram_of(m);
    // Columns scaled to unit M-norm first (they differ by the ratios of θ).
    let sc: Vec<f64> = (0..c)
        .map(|i| 1.0 / mh[(i, i)].abs().sqrt().max(f64::MIN_POSITIVE))
        .collect();
    let kd = nalgebra::DMatrix::from_fn(c, c, |i, j| 0.5 * (kh[(i, j)] + kh[(j, i)]) * sc[i] * sc[j]);
    let md = nalgebra::DMatrix::from_fn(c, c, |i, j| 0.5 * (mh[(i, j)] + mh[(j, i)]) * sc[i] * sc[j]);
    // M-orthonormal basis of span(Y) from the eigen-decomposition of its Gram matrix, dropping
    // directions that are numerically dependent (two Ritz vectors of one eigenvector would
    // otherwise give a spurious extra eigenvalue).
    let ge = md.symmetric_eigen();
    let gmax = ge.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
    let keep: Vec<usize> = (0..c).filter(|&i| ge.eigenvalues[i] > 1e-10 * gmax).collect();
    if keep.is_empty() {
        return Err(Error::Verification("refined Ritz vectors are not M-independent".into()));
    }
    let q = nalgebra::DMatrix::from_fn(c, keep.len(), |i, j| {
        ge.eigenvectors[(i, keep[j])] / ge.eigenvalues[keep[j]].sqrt()
    });
    let cmat = q.transpose() * &kd * &q;
    let cmat = (&cmat + cmat.transpose()) * 0.5;
    let eig = cmat.symmetric_eigen();
    let r = keep.len();
    let mut order: Vec<usize> = (0..r).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    // Z = Q U, columns in ascending order; then X = Y Z is M-orthonormal.
    let z = &q * &eig.eigenvectors;
    let zf = Mat::from_fn(c, r, |i, j| z[(i, order[j])] * sc[i]);
    let mut xn = Mat::zeros(n, r);
    tall::mul(xn.as_mut(), Accum::Replace, y.as_ref(), zf.as_ref(), 1.0);
    Ok((order.iter().map(|&j| eig.eigenvalues[j]).collect(), xn))
}

/// Residuals and M-orthonormality of computed modes.
pub fn verify(k: &SymMatrix, m: &SymMatrix, lambda: &[f64], x: MatRef<'_, f64>, sigma: f64) -> (Vec<f64>, f64) {
    let (kx, mx) = products(k, m, x);
    verify_of(lambda, x, &kx, &mx, sigma)
}

/// [`verify`] from K·X and M·X.
fn verify_of(lambda: &[f64], x: MatRef<'_, f64>, kx: &Mat<f64>, mx: &Mat<f64>, sigma: f64) -> (Vec<f64>, f64) {
    let (n, nc) = (x.nrows(), x.ncols());
    // Scale of the spectrum found (a far shift must not make elastic modes look rigid).
    let lam_ref = lambda.iter().fold(1e-3 * sigma.abs(), |a, l| a.max(l.abs()));
    let mut res = Vec::with_capacity(nc);
    for c in 0..nc {
        let (mut r2, mut k2, mut m2) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let r = kx[(i, c)] - lambda[c] * mx[(i, c)];
            r2 += r * r;
            k2 += kx[(i, c)] * kx[(i, c)];
            m2 += mx[(i, c)] * mx[(i, c)];
        }
        // Rigid-body modes (λ ≈ 0) have Kx ≈ 0: normalise by a representative stiffness
        // scale instead, so the number still measures accuracy.
        let denom = if lambda[c].abs() < 1e-6 * lam_ref {
            lam_ref * m2.sqrt()
        } else {
            k2.sqrt().max(lambda[c].abs() * m2.sqrt())
        };
        res.push(if denom > 0.0 { r2.sqrt() / denom } else { r2.sqrt() });
    }
    let g = tall::gram(x, mx.as_ref());
    let mut err = 0.0f64;
    for i in 0..nc {
        for j in 0..nc {
            let e = g[(i, j)] - if i == j { 1.0 } else { 0.0 };
            // NaN-propagating: vectors holding a NaN are not M-orthonormal.
            err = if err.is_nan() || e.is_nan() {
                f64::NAN
            } else {
                err.max(e.abs())
            };
        }
    }
    (res, err)
}

/// Block Lanczos state.
/// Basis columns kept per wanted pair before a thick restart (plus four blocks). Three rather
/// than two: 10–13 % fewer operator applications for 18 modes of the 20k–119k-DOF plates; the
/// basis is freed before the Sturm factorisation, so it does not raise the memory peak.
const BASIS_PER_WANTED: usize = 3;

/// Basis columns before a thick restart for `want` pairs in blocks of `b` on `n` equations
/// (at least one block).
fn basis_columns(n: usize, want: usize, b: usize) -> usize {
    (want * BASIS_PER_WANTED + 4 * b).max(want + 6 * b).min(n).max(b.min(n))
}

/// Projections from this size on are diagonalised by faer's blocked solver (scaled), smaller
/// ones by nalgebra's.
const RITZ_BLOCKED_FROM: usize = 200;

/// Work of a Rayleigh–Ritz step on a c-column basis, in the units of [`Lanczos::step_work`]
/// (flops of the block steps), per c³. The dense eigensolver does ~9c³ flops at a rate ~1–5×
/// below that of the steps' streaming kernels; 10 errs towards testing often. With the 18 modes
/// of a 119k-DOF plate (c ≤ 60) a step's work is ~500× a Rayleigh–Ritz step's: one after
/// every step, as before. With 200 modes of a 5.6k-DOF plate (c ~ 900) one every ~10 steps.
const RITZ_WORK_PER_CUBE: f64 = 10.0;

/// The side of the shift whose eigenvalues a Lanczos run wants.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Side {
    /// The nearest, on either side (largest |θ|).
    Both,
    /// Above σ only (θ > 0, largest first): band searches from the band's lower end.
    Above,
    /// Below σ only (θ < 0, most negative first): every eigenvalue under a shift placed above
    /// the wanted ones.
    Below,
}

impl Side {
    fn wants(self, theta: f64) -> bool {
        match self {
            Side::Both => true,
            Side::Above => theta > 0.0,
            Side::Below => theta < 0.0,
        }
    }
}

struct Lanczos {
    n: usize,
    b: usize,
    /// Number of wanted eigenpairs.
    want: usize,
    /// Maximum basis size before a restart.
    m_max: usize,
    /// Basis (columns `0..cur` in use, plus the next block at `cur..cur + b`).
    v: Mat<f64>,
    /// M-images of the basis columns (the next block's included). With them the coefficients
    /// against the basis are (MV)ᵀw, formed from w itself: the Gram–Schmidt passes need no M
    /// product of their own, one per block step instead of three, for an allocation the size
    /// of the basis.
    mv: Mat<f64>,
    /// Two blocks of the same size kept for the next step's solve and M-image (no allocation
    /// per step: the freed blocks would stay in the allocator's heap, fragmented, and add to
    /// the peak).
    spare: [Mat<f64>; 2],
    /// Projected matrix (full storage, symmetrised at use).
    t: Mat<f64>,
    /// Columns whose operator image is in `t`.
    cur: usize,
    rng: Rng,
    /// Which Ritz values θ = 1/(λ − σ) are wanted.
    side: Side,
    /// Last Ritz values θ, for estimates of the next eigenvalue.
    last_theta: Vec<f64>,
    /// The Ritz values θ of the pairs last returned (among `last_theta`).
    returned_theta: Vec<f64>,
    /// The start block has been built.
    started: bool,
    /// Return (`Ok(None)`) after this many more block steps, to look at the Ritz values.
    pause_after: Option<usize>,
    /// Approximations of the wanted modes to start from (columns summed into the start
    /// block, with a random part so that no eigenvector is missing from it).
    start: Option<Mat<f64>>,
    /// Wall time of the iteration's parts, seconds: solves, M products, orthogonalisation
    /// against the basis, block normalisation, Rayleigh–Ritz (and restarts).
    times: [f64; 5],
    /// Largest [`Lanczos::bytes`] seen, recorded before the basis is freed.
    peak_bytes: std::cell::Cell<u64>,
    /// Block steps and Rayleigh–Ritz steps taken (they differ with a large basis:
    /// [`RITZ_WORK_PER_CUBE`]).
    steps: (usize, usize),
    /// Form [`Lanczos::image`] when the iteration converges.
    keep_image: bool,
    /// Op·X of the Ritz vectors X last returned, from the Lanczos relation
    /// Op·V = V·T + W·R·E_lastᵀ: X·Θ + W·R·(last block rows of the Ritz coefficients).
    image: Option<Mat<f64>>,
    /// M-orthonormal invariant vectors kept out of the basis (K's null vectors, see
    /// [`null_vectors`]): every new block is M-orthogonalised against them too, so the
    /// iteration works in their complement and never returns them.
    deflate: Option<Null>,
}

impl Lanczos {
    fn new(n: usize, want: usize, p: &EigenParams, side: Side) -> Self {
        let b = p.block.max(1).min(n);
        let m_max = basis_columns(n, want, b);
        // The basis is the largest allocation of the iteration (83 MB at 119k DOFs).
        Lanczos {
            n,
            b,
            want,
            m_max,
            v: Mat::zeros(n, m_max + b),
            mv: Mat::zeros(n, m_max + b),
            spare: [Mat::zeros(0, 0), Mat::zeros(0, 0)],
            t: Mat::zeros(m_max + b, m_max + b),
            cur: 0,
            rng: Rng(p.seed | 1),
            side,
            last_theta: Vec::new(),
            returned_theta: Vec::new(),
            started: false,
            pause_after: None,
            start: None,
            times: [0.0; 5],
            peak_bytes: std::cell::Cell::new(0),
            steps: (0, 0),
            keep_image: false,
            image: None,
            deflate: None,
        }
    }

    /// Bytes of the basis, its M-images, the spare blocks and the projected matrix held now.
    fn bytes(&self) -> u64 {
        8 * (self.v.nrows() * self.v.ncols()
            + self.mv.nrows() * self.mv.ncols()
            + self.spare.iter().map(|s| s.nrows() * s.ncols()).sum::<usize>()
            + self.t.nrows() * self.t.ncols()) as u64
    }

    /// The most [`Lanczos::bytes`] held so far (a converged run frees them as it hands back
    /// its Ritz vectors).
    fn peak_bytes(&self) -> u64 {
        self.peak_bytes.get().max(self.bytes())
    }

    /// Apply Op = A⁻¹M to a block: W = A⁻¹ (M X).
    fn apply(fa: &Factor, m: &SymMatrix, x: MatRef<'_, f64>, apps: &mut usize) -> Mat<f64> {
        let mut w = Mat::zeros(x.nrows(), x.ncols());
        m.mul_block(x, w.as_mut());
        fa.solve_in_place(w.as_mut());
        *apps += x.ncols();
        w
    }

    /// M-orthogonalise `w` against basis columns `0..upto` and the deflated vectors, twice
    /// (classical Gram–Schmidt with the coefficients (MV)ᵀw from the stored M-images, so that
    /// the second pass sees the rounding the first left in w itself). Returns the coefficients
    /// against the basis, summed over the passes, and each column's M-norm² removed (Σ of the
    /// squared coefficients, deflated vectors included: by Pythagoras, the M-norm² before is
    /// that plus the M-norm² after). The caller forms the M-image of the result.
    fn orthogonalise(&self, w: &mut Mat<f64>, upto: usize) -> (Mat<f64>, Vec<f64>) {
        let bw = w.ncols();
        let mut coef = Mat::zeros(upto, bw);
        let mut removed = vec![0.0; bw];
        let z = self.deflate.as_ref().filter(|(z, _)| z.ncols() > 0);
        let mut zcoef = z.map(|(z, _)| Mat::<f64>::zeros(z.ncols(), bw));
        for _ in 0..2 {
            if upto > 0 {
                let c = tall::gram(self.mv.get(.., 0..upto), w.as_ref());
                tall::mul(w.as_mut(), Accum::Add, self.v.get(.., 0..upto), c.as_ref(), -1.0);
                coef += &c;
            }
            if let (Some((z, mz)), Some(zc)) = (z, zcoef.as_mut()) {
                let c = tall::gram((**mz).as_ref(), w.as_ref());
                tall::mul(w.as_mut(), Accum::Add, (**z).as_ref(), c.as_ref(), -1.0);
                *zc += &c;
            }
        }
        let squares = |c: &Mat<f64>, j: usize| (0..c.nrows()).map(|i| c[(i, j)] * c[(i, j)]).sum::<f64>();
        for (j, r) in removed.iter_mut().enumerate() {
            *r = squares(&coef, j) + zcoef.as_ref().map_or(0.0, |zc| squares(zc, j));
        }
        (coef, removed)
    }

    /// M-orthonormalise `w` (already orthogonal to the basis columns `0..upto`; `mw` is its
    /// M-image) in place. Returns R with W_old = W_new·R; `mw` is recomputed fresh at the end.
    /// Directions whose M-norm² fell below 1e-20 of `scale2` (the largest M-norm² before
    /// orthogonalisation) carry no new information: they are replaced by random vectors
    /// orthogonal to everything, and their rows of R are zero.
    fn normalise(&mut self, w: &mut Mat<f64>, mw: &mut Mat<f64>, m: &SymMatrix, upto: usize, scale2: f64) -> Mat<f64> {
        let bw = w.ncols();
        let mut r_total = Mat::<f64>::identity(bw, bw);
        let mut fresh = true;
        let mut settled = false;
        for pass in 0..NORMALISE_PASSES {
            let g = tall::gram(w.as_ref(), mw.as_ref());
            let gs = nalgebra::DMatrix::from_fn(bw, bw, |i, j| 0.5 * (g[(i, j)] + g[(j, i)]));
            let eig = nalgebra::SymmetricEigen::new(gs);
            let smax = eig.eigenvalues.iter().fold(0.0f64, |a, &s| a.max(s));
            let smin = eig.eigenvalues.iter().fold(f64::INFINITY, |a, &s| a.min(s));
            let floor = if pass == 0 && scale2 > 0.0 {
                scale2 * 1e-20
            } else {
                smax * 1e-20
            };
            let mut deficient = Vec::new();
            let mut u = Mat::zeros(bw, bw);
            let mut r = Mat::zeros(bw, bw);
            for k in 0..bw {
                let s = eig.eigenvalues[k];
                if s > floor && s > 0.0 {
                    let sq = s.sqrt();
                    for i in 0..bw {
                        u[(i, k)] = eig.eigenvectors[(i, k)] / sq;
                        r[(k, i)] = eig.eigenvectors[(i, k)] * sq;
                    }
                } else {
                    deficient.push(k);
                }
            }
            // W·U and (MW)·U in place (U is square).
            tall::combine_columns_in_place(w.as_mut(), u.as_ref());
            tall::combine_columns_in_place(mw.as_mut(), u.as_ref());
            r_total = &r * &r_total;
            if !deficient.is_empty() {
                // Entries scaled by 1/√M_ii: every equation weighs alike in the M-norm, so a
                // replacement is not all in the few equations of a heavy point mass (which the
                // basis holds already; 1e30 kg on a cantilever left nothing after
                // orthogonalisation, pass after pass). Massless equations take the mean mass.
                let d = m.diagonal();
                let mean = d.iter().map(|x| x.abs()).sum::<f64>() / d.len().max(1) as f64;
                let scale: Vec<f64> = d
                    .iter()
                    .map(|&mi| match (mi > 0.0, mean > 0.0) {
                        (true, _) => 1.0 / mi.sqrt(),
                        (false, true) => 1.0 / mean.sqrt(),
                        (false, false) => 1.0,
                    })
                    .collect();
                for &k in &deficient {
                    for (i, &si) in scale.iter().enumerate().take(self.n) {
                        w[(i, k)] = self.rng.next() * si;
                    }
                }
                m.mul_block(w.as_ref(), mw.as_mut());
            } else if pass >= 1 || smin >= WELL_CONDITIONED * smax {
                // The block was orthogonal to the basis to rounding (two Gram–Schmidt passes);
                // scaling a well-conditioned block amplifies that rounding by at most
                // √(smax/smin) ≤ 100, so another pass against the basis buys nothing.
                // Its M-image, scaled along, carries the rounding of the unscaled terms
                // amplified by at most √(scale2/smin): below 1e3, it is accurate to ~1e-13 and
                // is kept rather than recomputed.
                fresh = !(pass == 0 && scale2 > 0.0 && smin >= IMAGE_KEPT * scale2);
                settled = true;
                break;
            }
            // Second pass: clean rounding (and orthogonalise random replacements).
            let _ = self.orthogonalise(w, upto);
            m.mul_block(w.as_ref(), mw.as_mut());
        }
        // Replacements still deficient after every pass: the space is exhausted (the basis
        // spans all n equations, which the caller detects), or something is wrong.
        if !settled && upto + bw <= self.n {
            log::debug!("Lanczos: a block was not M-orthonormal after {NORMALISE_PASSES} passes");
        }
        // A fresh M-image: the algebraic updates above lose accuracy when a block is nearly
        // in the span of the basis (its scaling amplifies their rounding).
        if fresh {
            m.mul_block(w.as_ref(), mw.as_mut());
        }
        r_total
    }

    /// Ritz values θ and vectors Y of the current projected matrix (size `cur`), sorted by
    /// decreasing "wantedness" (|θ|, or θ for positive-only targets).
    fn ritz(&self) -> (Vec<f64>, Mat<f64>) {
        let c = self.cur;
        let sym = |i: usize, j: usize| 0.5 * (self.t[(i, j)] + self.t[(j, i)]);
        // Small projections by nalgebra's unblocked solver (faster below ~200 and what every
        // small run has always used); larger ones by faer's blocked one, 2–7× faster at
        // 300–1500 (many modes: a basis of three columns per mode).
        let blocked = (c >= RITZ_BLOCKED_FROM)
            .then(|| crate::linalg::dense::scaled_self_adjoint_eigen(&Mat::from_fn(c, c, sym)).ok())
            .flatten();
        let (vals, vecs) = blocked.unwrap_or_else(|| {
            let eig = nalgebra::SymmetricEigen::new(nalgebra::DMatrix::from_fn(c, c, sym));
            let vals = eig.eigenvalues.iter().copied().collect();
            (vals, Mat::from_fn(c, c, |i, j| eig.eigenvectors[(i, j)]))
        });
        let mut order: Vec<usize> = (0..c).collect();
        let key = |th: f64| match self.side {
            Side::Both => th.abs(),
            Side::Above => th,
            Side::Below => -th,
        };
        order.sort_by(|&a, &b| key(vals[b]).total_cmp(&key(vals[a])));
        let theta: Vec<f64> = order.iter().map(|&k| vals[k]).collect();
        let y = Mat::from_fn(c, c, |i, j| vecs[(i, order[j])]);
        (theta, y)
    }

    /// Estimated floating-point work of one block step with `cur` basis columns: the block
    /// solve (forward and backward through L), two Gram–Schmidt passes against the basis, the
    /// M product.
    fn step_work(&self, fa: &Factor, m: &SymMatrix) -> f64 {
        let (n, b, c) = (self.n as f64, self.b as f64, self.cur as f64);
        4.0 * fa.symbolic().nnz_l as f64 * b + 8.0 * n * c * b + 2.0 * m.pattern.nnz() as f64 * b
    }

    /// Run until the wanted Ritz pairs converge. Returns (λ, X) of the converged pairs, or
    /// `None` when [`Lanczos::pause_after`] block steps were done first.
    fn run(
        &mut self,
        p: &EigenParams,
        fa: &Factor,
        m: &SymMatrix,
        sigma: f64,
        apps: &mut usize,
    ) -> Result<Option<(Vec<f64>, Mat<f64>)>> {
        let n = self.n;
        let b = self.b;
        if self.started {
            return self.iterate(p, fa, m, sigma, apps);
        }
        self.started = true;
        // Start block: Op applied to random vectors (removes components in the null space
        // of M, which matters for massless DOFs), then M-orthonormalised.
        let mut x0 = Mat::zeros(n, b);
        for j in 0..b {
            for i in 0..n {
                x0[(i, j)] = self.rng.next();
            }
        }
        if let Some(st) = self.start.take() {
            // Each start column: a sum of approximate modes (every b-th), plus a random part
            // of a hundredth of its size.
            for j in 0..b {
                let mut col = vec![0.0; n];
                for c in (j..st.ncols()).step_by(b) {
                    for (i, v) in col.iter_mut().enumerate() {
                        *v += st[(i, c)];
                    }
                }
                let amax = col.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                if amax > 0.0 {
                    for (i, v) in col.iter().enumerate() {
                        x0[(i, j)] = v + 0.01 * amax * x0[(i, j)];
                    }
                }
            }
        }
        let w = Self::apply(fa, m, x0.as_ref(), apps);
        // Out of the deflated vectors' span (a no-op without them).
        let deflated = self.deflate.is_some();
        self.place_block(w, m, 0, deflated);
        // `cur` columns have images in T; the block at cur..cur+b is the next to apply.
        self.cur = 0;
        self.iterate(p, fa, m, sigma, apps)
    }

    /// Free the basis and the projected matrix (before a Sturm factorisation, so that they do
    /// not add to its memory peak). A later [`Lanczos::run`] starts a new iteration.
    fn release(&mut self) {
        self.peak_bytes.set(self.peak_bytes());
        self.v = Mat::zeros(0, 0);
        self.mv = Mat::zeros(0, 0);
        self.spare = [Mat::zeros(0, 0), Mat::zeros(0, 0)];
        self.t = Mat::zeros(0, 0);
        self.m_max = 0;
        self.cur = 0;
        self.started = false;
        self.pause_after = None;
    }

    /// Start a released iteration from converged pairs (λ, X), X M-orthonormal: they become the
    /// first columns of the basis, locked (their block of T is diag θ, coupled to nothing), and
    /// a random block M-orthogonal to them carries the search on. Without room for them and a
    /// block, or for a small problem, it simply starts anew.
    fn restart_from(&mut self, lambda: &[f64], x: MatRef<'_, f64>, m: &SymMatrix, sigma: f64) {
        let (n, b, c) = (self.n, self.b, x.ncols());
        if self.started || c + 2 * b > self.m_max || c + b >= n {
            return;
        }
        self.v.get_mut(.., 0..c).copy_from(x);
        m.mul_block(x, self.mv.get_mut(.., 0..c));
        self.t.fill(0.0);
        for (k, &l) in lambda.iter().enumerate().take(c) {
            self.t[(k, k)] = 1.0 / (l - sigma);
        }
        let w = Mat::from_fn(n, b, |_, _| self.rng.next());
        self.place_block(w, m, c, true);
        self.cur = c;
        self.started = true;
    }

    /// A start block `w`: M-orthonormalised against the basis columns `0..at` and the deflated
    /// vectors, then put at `at..at + b` with its M-image. `scaled`: the normalisation judges
    /// deficient directions against the block's M-norm² before the orthogonalisation (else
    /// against its own largest).
    fn place_block(&mut self, mut w: Mat<f64>, m: &SymMatrix, at: usize, scaled: bool) {
        let b = w.ncols();
        let (_, removed) = self.orthogonalise(&mut w, at);
        let mut mw = Mat::zeros(w.nrows(), b);
        m.mul_block(w.as_ref(), mw.as_mut());
        let scale2 = if scaled { norm2_before(&w, &mw, &removed) } else { 0.0 };
        let _ = self.normalise(&mut w, &mut mw, m, at, scale2);
        self.v.get_mut(.., at..at + b).copy_from(&w);
        self.mv.get_mut(.., at..at + b).copy_from(&mw);
    }

    /// Grow the wanted count (and the basis capacity), keeping the current state.
    fn set_want(&mut self, want: usize) {
        if want <= self.want && self.started {
            return;
        }
        self.want = want.max(self.want);
        let b = self.b;
        // The basis must also hold the current columns plus the next block (a resumed run may
        // end with a full basis).
        let m_max = basis_columns(self.n, self.want, b).max(self.cur + b).min(self.n);
        if m_max > self.m_max {
            let cols = m_max + b;
            let mut v = Mat::zeros(self.n, cols);
            let mut mv = Mat::zeros(self.n, cols);
            let mut t = Mat::zeros(cols, cols);
            let old = self.v.ncols();
            if old > 0 {
                v.get_mut(.., 0..old).copy_from(&self.v);
                mv.get_mut(.., 0..old).copy_from(&self.mv);
                t.get_mut(0..old, 0..old).copy_from(&self.t);
            }
            self.v = v;
            self.mv = mv;
            self.t = t;
            self.m_max = m_max;
        }
    }

    /// The iteration proper, from the current state: block steps, each followed by a
    /// Rayleigh–Ritz step and its residual estimates, until the wanted pairs converge
    /// ([`Lanczos::converged_pairs`]), with a thick restart whenever the basis is full.
    fn iterate(
        &mut self,
        p: &EigenParams,
        fa: &Factor,
        m: &SymMatrix,
        sigma: f64,
        apps: &mut usize,
    ) -> Result<Option<(Vec<f64>, Mat<f64>)>> {
        let n = self.n;
        // Block steps' work since the last Rayleigh–Ritz step (see [`RITZ_WORK_PER_CUBE`]).
        let mut since = 0.0;
        // Progress of a long iteration (many modes), on the log every ten seconds.
        let mut noted = Instant::now();
        loop {
            let blk = self.cur;
            let mut lap = Lap(Instant::now());
            since += self.step_work(fa, m);
            let r = self.block_step(fa, m, apps, &mut lap)?;
            self.steps.0 += 1;
            let nb = self.cur;
            let c = self.cur;
            // The Rayleigh–Ritz step costs O(c³): with a large basis (many modes) it is taken
            // once the steps since the last one have done as much work, so that it is at most
            // about half of the iteration. It is always taken when the basis is full (the
            // restart needs it), when the iteration pauses or has exhausted the space, and past
            // the application limit.
            let pausing = self.pause_after.is_some_and(|left| left <= 1);
            let must = self.cur + self.b > self.m_max || pausing || c >= n || *apps > p.max_applications;
            if !must && since < RITZ_WORK_PER_CUBE * (c as f64).powi(3) {
                if let Some(left) = self.pause_after {
                    self.pause_after = Some(left - 1);
                }
                lap.lap(&mut self.times, 4);
                continue;
            }
            since = 0.0;
            self.steps.1 += 1;
            // Rayleigh–Ritz and residual estimates ‖R·E_lastᵀ·y‖.
            let (theta, y) = self.ritz();
            self.last_theta = theta.clone();
            let nw = self.want.min(c);
            let resid = residual_estimates(&r, &y, blk, c);
            let converged = |k: usize| resid[k] <= p.tol * theta[k].abs().max(f64::MIN_POSITIVE);
            let all_wanted = c >= self.want && (0..nw).all(|k| converged(k) && self.side.wants(theta[k]));
            if noted.elapsed().as_secs_f64() >= 10.0 {
                noted = Instant::now();
                let nconv = (0..nw).filter(|&k| converged(k)).count();
                log::info!(
                    "Lanczos: {} operator applications, basis {c} columns, {nconv} of {} wanted pairs converged",
                    *apps,
                    self.want
                );
            }
            // Everything there is to find has been found (tiny problems).
            let exhausted = c >= n;
            let ritz = RitzStep {
                theta: &theta,
                y: &y,
                r: &r,
                blk,
                nb,
            };
            if all_wanted || exhausted {
                // Take every converged pair (wanted ones first) so that clusters straddling
                // the cut are complete.
                let mut take: Vec<usize> = (0..c).filter(|&k| converged(k) || (exhausted && k < nw)).collect();
                take.retain(|&k| self.side.wants(theta[k]));
                return Ok(Some(self.converged_pairs(&ritz, &take, sigma, &mut lap)));
            }
            if *apps > p.max_applications {
                let nconv = (0..nw).filter(|&k| converged(k)).count();
                return Err(Error::EigenNotConverged(format!(
                    "{nconv} of {} wanted modes converged after {} operator applications (tolerance {:.1e})",
                    self.want, *apps, p.tol
                )));
            }
            if self.cur + self.b > self.m_max {
                self.thick_restart(&ritz);
            }
            lap.lap(&mut self.times, 4);
            if let Some(left) = self.pause_after {
                if left <= 1 {
                    self.pause_after = None;
                    return Ok(None);
                }
                self.pause_after = Some(left - 1);
            }
        }
    }

    /// One block step: Op applied to the next block, M-orthogonalised against the basis (its
    /// coefficients are the block's column of T) and M-orthonormalised; the new block goes
    /// after the basis. Returns R, T's subdiagonal block (W_old = W_new·R).
    fn block_step(&mut self, fa: &Factor, m: &SymMatrix, apps: &mut usize, lap: &mut Lap) -> Result<Mat<f64>> {
        let (n, b, blk) = (self.n, self.b, self.cur);
        // Op V_blk = A⁻¹ (M V_blk), and M V_blk is already stored.
        let [mut w, mut mw] = std::mem::replace(&mut self.spare, [Mat::zeros(0, 0), Mat::zeros(0, 0)]);
        for a in [&mut w, &mut mw] {
            if a.nrows() != n || a.ncols() != b {
                *a = Mat::zeros(n, b);
            }
        }
        w.copy_from(self.mv.get(.., blk..blk + b));
        fa.solve_in_place(w.as_mut());
        *apps += b;
        lap.lap(&mut self.times, 0);
        let (coef, removed) = self.orthogonalise(&mut w, blk + b);
        // Column block `blk` of T: rows 0..blk+b.
        self.t.get_mut(0..blk + b, blk..blk + b).copy_from(&coef);
        lap.lap(&mut self.times, 2);
        m.mul_block(w.as_ref(), mw.as_mut());
        lap.lap(&mut self.times, 1);
        let scale2 = norm2_before(&w, &mw, &removed);
        let r = self.normalise(&mut w, &mut mw, m, blk + b, scale2);
        lap.lap(&mut self.times, 3);
        self.cur = blk + b;
        // The new block goes after the basis; R is T's subdiagonal block.
        let nb = self.cur;
        if nb + b > self.v.ncols() {
            return Err(Error::EigenNotConverged("internal basis overflow".into()));
        }
        self.v.get_mut(.., nb..nb + b).copy_from(&w);
        self.mv.get_mut(.., nb..nb + b).copy_from(&mw);
        self.spare = [w, mw];
        self.t.get_mut(nb..nb + b, blk..blk + b).copy_from(&r);
        self.t.get_mut(blk..blk + b, nb..nb + b).copy_from(r.transpose());
        Ok(r)
    }

    /// The converged pairs `take` of a Ritz step, (λ, X), with the Ritz vectors formed in place
    /// of the basis (it is spent: every caller releases it next), and their image
    /// [`Lanczos::image`] when it is kept.
    fn converged_pairs(
        &mut self,
        ritz: &RitzStep<'_>,
        take: &[usize],
        sigma: f64,
        lap: &mut Lap,
    ) -> (Vec<f64>, Mat<f64>) {
        let (n, b) = (self.n, self.b);
        let (c, blk, nb) = (self.cur, ritz.blk, ritz.nb);
        let mut lam = Vec::with_capacity(take.len());
        let yk = Mat::from_fn(c, take.len(), |i, j| ritz.y[(i, take[j])]);
        // The Ritz vectors in place of the basis: it is spent (every caller releases it next).
        tall::combine_columns_in_place(self.v.as_mut(), yk.as_ref());
        self.peak_bytes.set(self.peak_bytes());
        let x = self.v.get(.., 0..take.len()).to_owned();
        // Op·X = X·Θ + W·R·Y_last, with the next block W still after the basis columns (the
        // in-place combination wrote only the first ones). W is copied out and the basis freed
        // before the image is formed: it is not at the memory peak.
        let next = self.keep_image.then(|| self.v.get(.., nb..nb + b).to_owned());
        self.release();
        let image = next.map(|next| {
            let mut rs = Mat::zeros(b, take.len());
            matmul(
                rs.as_mut(),
                Accum::Replace,
                ritz.r.as_ref(),
                yk.get(blk..blk + b, ..),
                1.0,
                Par::Seq,
            );
            let mut image = Mat::zeros(n, take.len());
            tall::mul(image.as_mut(), Accum::Replace, next.as_ref(), rs.as_ref(), 1.0);
            let th: Vec<f64> = take.iter().map(|&k| ritz.theta[k]).collect();
            tall::add_scaled_columns(image.as_mut(), x.as_ref(), &th);
            image
        });
        self.image = image;
        for &k in take {
            lam.push(sigma + 1.0 / ritz.theta[k]);
        }
        self.returned_theta = take.iter().map(|&k| ritz.theta[k]).collect();
        lap.lap(&mut self.times, 4);
        let t = self.times;
        log::debug!(
            "Lanczos: solves {:.3} s, M products {:.3} s, orthogonalisation {:.3} s, normalisation {:.3} s, Rayleigh–Ritz and restarts {:.3} s",
            t[0],
            t[1],
            t[2],
            t[3],
            t[4]
        );
        (lam, x)
    }

    /// Thick restart: keep the best Ritz vectors, continue from the last block.
    fn thick_restart(&mut self, ritz: &RitzStep<'_>) {
        let (b, c, blk, nb) = (self.b, self.cur, ritz.blk, ritz.nb);
        let keep = (self.want + b).min(c.saturating_sub(b)).max(1);
        let yk = ritz.y.get(.., 0..keep).to_owned();
        // R·E_lastᵀ·Y: coupling of the kept Ritz vectors to the next block.
        let mut coup = Mat::zeros(b, keep);
        matmul(
            coup.as_mut(),
            Accum::Replace,
            ritz.r.as_ref(),
            yk.get(blk..blk + b, ..),
            1.0,
            Par::Seq,
        );
        // In place (no copies of the basis at the memory peak): the Ritz vectors into the first
        // columns, then the next block after them (keep + b ≤ c = nb). The next block's
        // M-image moves along with it.
        for a in [&mut self.v, &mut self.mv] {
            tall::combine_columns_in_place(a.as_mut(), yk.as_ref());
            let (head, tail) = a.as_mut().split_at_col_mut(nb);
            head.get_mut(.., keep..keep + b).copy_from(tail.get(.., 0..b));
        }
        self.t.fill(0.0);
        for k in 0..keep {
            self.t[(k, k)] = ritz.theta[k];
        }
        self.t.get_mut(keep..keep + b, 0..keep).copy_from(&coup);
        self.t.get_mut(0..keep, keep..keep + b).copy_from(coup.transpose());
        self.cur = keep;
    }

    /// Smallest eigenvalue estimate above `lam` among the last Ritz values, those of the pairs
    /// returned excepted (a returned pair's Ritz value can lie just above its refined value and
    /// pass for the next eigenvalue).
    fn next_estimate_above(&self, lam: f64, sigma: f64) -> Option<f64> {
        self.last_theta
            .iter()
            .filter(|t| t.abs() > 0.0 && !self.returned_theta.contains(t))
            .map(|t| sigma + 1.0 / t)
            .filter(|&l| l > lam * (1.0 + 1e-9) + 1e-300)
            .min_by(f64::total_cmp)
    }

    /// The largest eigenvalue estimate of the pairs last returned (before refinement).
    fn returned_max(&self, sigma: f64) -> Option<f64> {
        self.returned_theta
            .iter()
            .filter(|t| t.abs() > 0.0)
            .map(|t| sigma + 1.0 / t)
            .max_by(f64::total_cmp)
    }
}

/// The largest M-norm² of the columns of a block before [`Lanczos::orthogonalise`] took
/// `removed` out of them: `w` and `mw` are the block after it and its M-image.
fn norm2_before(w: &Mat<f64>, mw: &Mat<f64>, removed: &[f64]) -> f64 {
    tall::col_dots(w.as_ref(), mw.as_ref())
        .into_iter()
        .zip(removed)
        .map(|(a, r)| a + r)
        .fold(0.0, f64::max)
}

/// One Rayleigh–Ritz step of [`Lanczos::iterate`]: Ritz values θ and vectors Y of T (wanted
/// first), R (T's last subdiagonal block), and where the last block (`blk`) and the next one
/// (`nb`) start in the basis.
struct RitzStep<'a> {
    theta: &'a [f64],
    y: &'a Mat<f64>,
    r: &'a Mat<f64>,
    blk: usize,
    nb: usize,
}

/// Times the phases of the iteration: each lap adds the time since the last one to a phase.
struct Lap(Instant);

impl Lap {
    fn lap(&mut self, times: &mut [f64; 5], k: usize) {
        let now = Instant::now();
        times[k] += (now - self.0).as_secs_f64();
        self.0 = now;
    }
}

/// Residual estimates ‖R·E_lastᵀ·y_k‖ of the Ritz vectors y_k, k < `c`, whose last block of
/// rows starts at `blk`.
fn residual_estimates(r: &Mat<f64>, y: &Mat<f64>, blk: usize, c: usize) -> Vec<f64> {
    let b = r.nrows();
    let mut resid = vec![0.0; c];
    for k in 0..c {
        let mut s2 = 0.0;
        for i in 0..b {
            let mut s = 0.0;
            for j in 0..b {
                s += r[(i, j)] * y[(blk + j, k)];
            }
            s2 += s * s;
        }
        resid[k] = s2.sqrt();
    }
    resid
}

/// Convenience for tests: a view of column `j` as a slice-backed vector.
pub fn column(x: &Mat<f64>, j: usize) -> Vec<f64> {
    (0..x.nrows()).map(|i| x[(i, j)]).collect()
}

#[allow(dead_code)]
fn _assert_send(_: MatMut<'_, f64>) {}

#[cfg(test)]
mod tests {
    use super::*;

    /// K and M (on K's pattern) of a fixed–free chain of `n` unit masses and unit springs.
    /// Eigenvalue `j` (from 1) of [`fixed_free_chain`]: λ_j = 4 sin²((2j − 1)π/(4n + 2)).
    fn chain_eigenvalue(n: usize, j: usize) -> f64 {
        let s = ((2 * j - 1) as f64 * std::f64::consts::PI / (4 * n + 2) as f64).sin();
        4.0 * s * s
    }

    /// [`fixed_free_chain`] with K − σM factorised at σ = −λ₁/2.
    fn factored_chain(n: usize) -> (SymMatrix, SymMatrix, Factor, f64) {
        let (k, m) = fixed_free_chain(n);
        let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
        let sigma = -0.5 * chain_eigenvalue(n, 1);
        let fa = factor_at(&k, &m, &sym, sigma, &mut 0).unwrap().0;
        (k, m, fa, sigma)
    }

    fn fixed_free_chain(n: usize) -> (SymMatrix, SymMatrix) {
        let mut kt = Vec::new();
        let mut mt = Vec::new();
        for i in 0..n {
            kt.push((i, i, if i + 1 < n { 2.0 } else { 1.0 }));
            if i + 1 < n {
                kt.push((i, i + 1, -1.0));
            }
            mt.push((i, i, 1.0));
        }
        let k = SymMatrix::from_triplets(n, &kt);
        let m = SymMatrix::from_triplets(n, &mt).on_pattern(k.pattern.clone());
        (k, m)
    }

    /// The signal between the solver and the work waiting on it: the first call decides, a
    /// waiter wakes to it, and the guard calls it off on unwinding as on return.
    #[test]
    fn signal_first_call_decides_and_the_guard_calls_it_off() {
        let s = Signal::default();
        let waiter = {
            let s = s.clone();
            std::thread::spawn(move || s.wait())
        };
        s.set(true);
        s.set(false);
        assert!(waiter.join().unwrap());
        assert!(s.wait());
        let off = Signal::default();
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let _g = off.off_on_drop();
            panic!("a solve that fails");
        }));
        assert!(r.is_err());
        assert!(!off.wait());
        let raised = Signal::default();
        {
            let _g = raised.off_on_drop();
            raised.set(true);
        }
        assert!(raised.wait());
    }

    /// Refinement at U, above the wanted modes, amplifies a mode between U and 2U in the lowest
    /// mode's vector (by |λ₁ − U|/|λ₇ − U| ≈ 6 a step here), and the refinement undoes such a
    /// step; one step from below the spectrum ([`refine_below_spectrum`]) damps it by λ₁/λ₇.
    /// Fixed–free chain of 200 unit masses and springs, whose modes are known in closed form:
    /// x_j(i) = sin((2j − 1)π(i + 1)/(2n + 1)), λ_j = 4 sin²((2j − 1)π/(4n + 2)).
    #[test]
    fn refinement_below_the_spectrum_removes_what_refinement_at_u_amplifies() {
        let n = 200;
        let (k, m) = fixed_free_chain(n);
        let angle = |j: usize| (2 * j - 1) as f64 * std::f64::consts::PI / (2 * n + 1) as f64;
        let exact = |j: usize| 4.0 * (0.5 * angle(j)).sin().powi(2);
        let mode = |j: usize, i: usize| (angle(j) * (i + 1) as f64).sin();
        let nm = 6;
        let u = 0.5 * (exact(6) + exact(7));
        // The six lowest modes, the first with 1e-9 of mode 7 (λ₇ − U < U − λ₁): a relative
        // residual of ~1e-7, as the clamped 66k-DOF plate's mode 1 had after Lanczos.
        let x = Mat::from_fn(n, nm, |i, j| {
            mode(j + 1, i) + if j == 0 { 1e-9 * mode(7, i) } else { 0.0 }
        });
        let sym = Arc::new(SymbolicFactor::new(&k.pattern, None).unwrap());
        let verified = |l: &[f64], x: &Mat<f64>| verify_with_backward_errors(&k, &m, l, x.as_ref(), u);
        let worst = |v: &(Vec<f64>, f64, Vec<f64>)| v.0.iter().fold(0.0f64, |a, &r| a.max(r));
        let (l0, x0) = rayleigh_ritz(&k, &m, x).unwrap();
        let v0 = verified(&l0, &x0);
        let r0 = worst(&v0);
        assert!(r0 > RESIDUAL_FALLBACK, "the start is above the bar: {r0:.1e}");
        let fa = factor_at(&k, &m, &sym, u, &mut 0).unwrap().0;
        let (l1, x1) = refine(&k, &m, &fa, &x0).unwrap();
        let r1 = worst(&verified(&l1, &x1));
        assert!(r1 > 3.0 * r0, "refinement at U: {r0:.1e} → {r1:.1e}");
        // The one-factorisation solve's refinement ([`BelowBound::purify`]) takes that step,
        // sees the largest residual rise and undoes it: it hands back the start's pairs, as
        // verified, one step counted and the step's solves among the applications.
        let p = EigenParams::default();
        let mut mem = EigenMemory::default();
        let mut bb = BelowBound {
            null: None,
            k: &k,
            m: &m,
            p: &p,
            fa: &fa,
            u,
            zero: default_shift(&k, &m).abs(),
            count: nm,
            nm,
            applications: 0,
            memory: &mut mem,
            probe: None,
        };
        let Purified::Done(undone) = bb.purify(l0.clone(), x0.clone(), 1).unwrap() else {
            panic!("every pair below U is there")
        };
        assert_eq!((undone.steps, undone.worst, undone.found), (1, r0, nm));
        assert_eq!(undone.lambda, l0);
        assert_eq!(bb.applications, nm);
        drop(fa);
        let done = Purification {
            lambda: l0,
            vectors: x0,
            verified: v0,
            found: nm,
            steps: 1,
            worst: r0,
            tv: Instant::now(),
        };
        let (mut count, mut memory, mut apps) = (0, EigenMemory::default(), 0);
        let (d, _) = refine_below_spectrum((&k, &m, &sym), None, &done, u, (&mut count, &mut memory), &mut apps)
            .unwrap()
            .expect("below the bar after one step from below the spectrum");
        // Damped by λ₁/λ₇ ≈ 6e-3: the bar, and 50 times below the start.
        assert!(
            d.worst <= RESIDUAL_FALLBACK && d.worst < r0 / 50.0,
            "{r0:.1e} → {:.1e}",
            d.worst
        );
        assert_eq!((count, apps, d.steps), (1, nm, 2));
        for (j, l) in d.lambda.iter().enumerate() {
            // Rayleigh quotients of vectors accurate to ~1e-9: eigenvalues to ~1e-18, rounding
            // to ~1e-15; 1e-12 leaves room.
            assert!(
                (l - exact(j + 1)).abs() <= 1e-12 * exact(j + 1),
                "mode {}: {l} vs {}",
                j + 1,
                exact(j + 1)
            );
        }
    }

    #[test]
    fn a_request_whose_basis_cannot_fit_is_refused_before_any_work() {
        // 100 000 modes of a million equations: a basis of 300 000 vectors of 8 MB and their
        // M-images, ~4.8 TB, more than any machine this runs on; 18 modes need ~1.3 GB.
        let p = EigenParams::default();
        let e = iteration_fits(1_000_000, 100_000, &p, false).unwrap_err().to_string();
        assert!(
            e.contains("100000 modes") && e.contains("1000000 degrees of freedom") && e.contains("--band"),
            "{e}"
        );
        assert!(
            !Error::InvalidInput(e).is_memory_refusal(),
            "not a refusal the low-memory path answers"
        );
        let e = iteration_fits(1_000_000, 100_000, &p, true).unwrap_err().to_string();
        assert!(e.contains("in the band") && e.contains("narrower band"), "{e}");
        assert!(iteration_fits(20_000, 18, &p, false).is_ok());
    }

    #[test]
    fn many_modes_take_fewer_rayleigh_ritz_steps_and_stay_exact() {
        // 220 modes of a fixed–free chain of 2000 masses (λ_j = 4 sin²((2j − 1)π/(4n + 2))):
        // a basis of up to ~680 columns, whose Rayleigh–Ritz step (O(c³), by the blocked dense
        // solver from 200 columns on) is taken only once the block steps since the last one
        // have done as much work. The pairs must be those of the closed form all the same.
        let n = 2000;
        let want = 220;
        let (_, m, fa, sigma) = factored_chain(n);
        let exact = |j: usize| chain_eigenvalue(n, j);
        let p = EigenParams {
            target: Target::Nearest(want),
            ..Default::default()
        };
        let mut lz = Lanczos::new(n, want, &p, Side::Above);
        let mut apps = 0;
        let (mut l, x) = lz.run(&p, &fa, &m, sigma, &mut apps).unwrap().unwrap();
        let (blocks, ritz) = lz.steps;
        assert!(ritz < blocks, "{ritz} Rayleigh–Ritz steps for {blocks} block steps");
        assert!(l.len() >= want && x.ncols() == l.len());
        l.sort_by(f64::total_cmp);
        for (j, l) in l.iter().take(want).enumerate() {
            // Rounding alone moves an eigenvalue of this K (‖K‖ = 4) by ~ε‖K‖ ≈ 1e-15, which
            // is 2e-9 of λ₁ ≈ 6e-7; the Ritz tolerance (1e-10 relative on θ) adds less. 1e-8.
            assert!(
                (l - exact(j + 1)).abs() <= 1e-8 * exact(j + 1),
                "mode {j}: {l} vs {}",
                exact(j + 1)
            );
        }
    }

    /// A released Lanczos (its basis freed for a Sturm factorisation), restarted with the pairs
    /// it found locked, iterates on for more modes and finds them: the path taken when the
    /// Sturm check says a mode was missed.
    #[test]
    fn released_lanczos_runs_again_for_more_modes() {
        // A fixed–free chain of 200 unit masses and springs: λ_j = 4 sin²((2j − 1)π/(4n + 2)).
        let n = 200;
        let (k, m, fa, sigma) = factored_chain(n);
        let exact = |j: usize| chain_eigenvalue(n, j);
        let p = EigenParams {
            target: Target::Nearest(4),
            block: 2,
            ..Default::default()
        };
        let mut lz = Lanczos::new(n, 4, &p, Side::Both);
        let mut apps = 0;
        let (l1, x1) = lz.run(&p, &fa, &m, sigma, &mut apps).unwrap().unwrap();
        assert!(l1.len() >= 4);
        lz.release();
        assert_eq!(lz.bytes(), 0);
        lz.set_want(7);
        // The pairs found are locked at the start of the new basis.
        let (l1, x1) = refine(&k, &m, &fa, &x1).unwrap();
        lz.restart_from(&l1, x1.as_ref(), &m, sigma);
        assert!(lz.started && lz.cur == l1.len());
        let (mut l2, x2) = lz.run(&p, &fa, &m, sigma, &mut apps).unwrap().unwrap();
        assert!(l2.len() >= 7 && x2.ncols() == l2.len());
        l2.sort_by(f64::total_cmp);
        for (j, l) in l2.iter().take(7).enumerate() {
            // Ritz tolerance 1e-10 on θ: eigenvalues to ~1e-12 relative, 1e-10 leaves room.
            assert!(
                (l - exact(j + 1)).abs() <= 1e-10 * exact(j + 1),
                "mode {j}: {l} vs {}",
                exact(j + 1)
            );
        }
    }
}
