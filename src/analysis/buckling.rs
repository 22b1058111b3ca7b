//! Linear buckling: the lowest positive load factors λ of `(K + λ K_σ) φ = 0`, with `K_σ` the
//! geometric stiffness of a static load case ([`crate::analysis::prestress`]), and their shapes.
//!
//! # Method
//! The pencil `(K, −K_σ)` is not definite (`K_σ` is indefinite: tension and compression), so
//! the modal solver's `M`-inner-product Lanczos does not apply as such. With `G = −K_σ` the
//! problem is written `G φ = μ K φ`, `μ = 1/λ`, and solved with `K` — positive definite on a
//! supported model — as the "mass": the operator `Op = K⁻¹G` is self-adjoint in the
//! K inner product, its eigenvalues are the `μ`, and the wanted factors (smallest positive λ)
//! are its **largest** eigenvalues, extreme ones, which a Krylov method finds first. This is
//! the buckling transform of shift-invert Lanczos at shift 0 (Grimes, Lewis and Simon, *A
//! shifted block Lanczos algorithm for solving sparse symmetric generalized eigenproblems*,
//! SIAM J. Matrix Anal. Appl. 15(1), 1994, §2.2), with one factorisation, that of K. The
//! null space of `K_σ` (all DOFs it does not touch) is `μ = 0`, the bottom of the wanted side,
//! and a tensile part gives negative `μ` (factors of the reversed load), which are skipped.
//!
//! The basis is a block Krylov space, kept K-orthonormal (block classical Gram–Schmidt, twice)
//! together with its images `K V` and `G V`; the Rayleigh quotient `T = VᵀGV` gives the Ritz
//! pairs, and by Courant–Fischer the j-th Ritz factor is never below the j-th true one. Two
//! operators grow it, both applied to the best unconverged Ritz vectors as one block solve:
//! 1. **estimates**, `K⁻¹G` with the static solve's factor of K, until the lowest `nev + 1`
//!    Ritz factors move by less than 1e-3 in a step;
//! 2. the **spectral shift** σ placed from them (above the `nev`-th, midway to the next one at
//!    least 2 % further up), then `(K − σG)⁻¹G = (K + σK_σ)⁻¹G`, whose eigenvalues
//!    `1/(λ − σ)` put the factors just below σ at the far end of the spectrum (Grimes, Lewis
//!    and Simon's buckling transform with a shift). Its one factorisation serves the
//!    iteration and the Sturm count: the count at σ, known before the iteration, is how many
//!    factors it must converge. A count below `nev` (a factor the estimates overrated) moves σ
//!    above the factors then found, midway to the next, and factors again (at most
//!    [`MAX_SHIFTS`] shifts); a count above `nev` (estimates that were too high) converges them
//!    all and reports the lowest `nev`.
//!
//! A pair has converged when its backward error
//! `‖Gy − μKy‖ / (‖|G||y|‖ + |μ|‖|K||y|‖)` is at rounding level (1e-12), or below the
//! acceptance 1e-10 once its value has settled (a residual in the K⁻¹ norm, natural for the
//! operator, loses half its digits to cancellation on slender models: not used).
//! When the basis is full it restarts from the best Ritz vectors.
//!
//! # Verification
//! - the residual of each pair relative to ‖Kφ‖ and its backward error
//!   `‖Kφ + λK_σφ‖ / (‖|K||φ|‖ + |λ|‖|K_σ||φ|‖)` ([`crate::linalg::eigen::backward_errors`]);
//! - a Sturm count: by Sylvester's law of inertia the number of negative pivots of an LDLᵀ of
//!   `K + σK_σ` (σ > 0) is the number of load factors in `(0, σ)` when K is positive definite
//!   (`K + σK_σ` is congruent to `I − σ K^{-1/2} G K^{-1/2}`, whose eigenvalues `1 − σμ` are
//!   negative exactly for `0 < λ < σ`). σ is the shift of the iteration; every factor found
//!   below it is counted, and the count must equal them.
//!
//! # Cost
//! One static solve (a factorisation of K, which also proves K positive definite), the stresses
//! and `K_σ` (an assembly without mass), a few block solves with the static factor for the
//! estimates, one factorisation of `K + σK_σ` for both the iteration and the count, all on the
//! same ordering and symbolic factorisation: two numeric factorisations, as a static plus a
//! modal run. Products with K and G are made by blocks, and the backward errors' passes over
//! `|K|` and `|G|` only for pairs whose values have settled.
//!
//! A load without a positive factor (a tensile one) gets an empty list, not an error, and the
//! note "no buckling under this load". The proof is a Sturm count of zero at 1e6 times the
//! smallest |λ| (there `K − σG` is positive definite). When the unshifted estimates find no
//! positive value, that count is taken, and if it is not zero the factors below that point are
//! found with it as the shift. A model that is not supported
//! (K singular) is an error from the static solve, which names the free motions.

use crate::analysis::prestress::{InitialStress, StressExtreme};
use crate::analysis::statics::{self, Load};
use crate::linalg::eigen::backward_errors;
use crate::linalg::factor::{Factor, SymbolicFactor};
use crate::linalg::ordering::Ordering;
use crate::linalg::sparse::SymMatrix;
use crate::linalg::tall;
use crate::mesh::Mesh;
use crate::model::{Model, ModelSpec};
use crate::system::{System, SystemOptions};
use crate::{Error, Result};
use faer::{Accum, Mat, MatRef};
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

/// What a buckling analysis computes.
#[derive(Clone, Debug)]
pub struct BucklingOptions {
    /// The model (supports, couplings, prescribed displacements of the load case).
    pub spec: ModelSpec,
    /// Number of load factors (the lowest positive ones).
    pub modes: usize,
    /// Fill-reducing ordering.
    pub ordering: Ordering,
    /// Refuse to factorise if the factor would need more than this many bytes.
    pub max_memory: Option<u64>,
    /// Limit on the iteration's work (operator applications, vectors).
    pub max_applications: usize,
}

impl Default for BucklingOptions {
    fn default() -> Self {
        BucklingOptions {
            spec: ModelSpec::default(),
            modes: 4,
            ordering: Ordering::Metis,
            max_memory: None,
            max_applications: 20_000,
        }
    }
}

/// One buckling mode of the report.
#[derive(Clone, Debug, Serialize)]
pub struct BucklingRow {
    /// 1-based mode number, ascending load factor.
    pub mode: usize,
    /// Load factor λ: the loads times λ buckle the structure.
    pub load_factor: f64,
    /// ‖Kφ + λK_σφ‖ / ‖Kφ‖.
    pub rel_residual: f64,
    /// ‖Kφ + λK_σφ‖ / (‖|K||φ|‖ + |λ|‖|K_σ||φ|‖): the acceptance test.
    pub backward_error: f64,
}

/// The Sturm count of a buckling run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BucklingSturm {
    /// The check point σ (load-factor units).
    pub point: f64,
    /// Negative pivots of K + σK_σ: the load factors in (0, σ).
    pub count: usize,
    /// Load factors found in (0, σ).
    pub found: usize,
    /// `count == found`.
    pub complete: bool,
}

/// Wall time per phase, seconds.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BucklingTimings {
    /// Reading the mesh.
    pub read: f64,
    /// Model, pattern, K, ordering and symbolic factorisation.
    pub assemble: f64,
    /// The static solve (its factorisation of K included).
    pub statics: f64,
    /// Stresses and K_σ.
    pub geometric: f64,
    /// Factorisation of K + σK_σ (the shifted iteration's and the Sturm count's).
    pub factor: f64,
    /// The iteration (estimates and shifted).
    pub solve: f64,
    /// Residuals.
    pub verify: f64,
    /// Total.
    pub total: f64,
}

/// Everything a buckling run reports (the `--json` document).
#[derive(Clone, Debug, Serialize)]
pub struct BucklingReport {
    /// Mesh file.
    pub mesh: String,
    /// Nodes in the mesh.
    pub nodes: usize,
    /// Free DOFs.
    pub dofs: usize,
    /// The lowest positive load factors, ascending (empty: no buckling under this load).
    pub load_factors: Vec<f64>,
    /// Per-mode rows.
    pub modes: Vec<BucklingRow>,
    /// No positive load factor (proved by the Sturm count at `sturm.point`, see the module doc).
    pub no_buckling: bool,
    /// The Sturm count.
    pub sturm: BucklingSturm,
    /// No factor below the last reported one was missed.
    pub complete: bool,
    /// Every backward error below 1e-10 and the factorisations stable.
    pub accurate: bool,
    /// Largest relative residual.
    pub max_rel_residual: f64,
    /// Largest backward error.
    pub max_backward_error: f64,
    /// Worst probe backward error of the factorisations (stability).
    pub factor_backward_error: f64,
    /// Applied force of the load case, N (its resultant's magnitude).
    pub applied_force: f64,
    /// Equilibrium error of the static case.
    pub static_equilibrium_error: f64,
    /// Largest tensile stress of the load case.
    pub tension: StressExtreme,
    /// Largest compressive stress of the load case.
    pub compression: StressExtreme,
    /// Numeric factorisations: K (the static solve's, reused for the estimates) and K + σK_σ
    /// for the iteration and the Sturm count (none under a load without compression; one more
    /// per new shift when the count shows fewer factors than asked).
    pub factorizations: usize,
    /// Operator applications (vectors).
    pub operator_applications: usize,
    /// Phase timings.
    pub timings_s: BucklingTimings,
    /// Notes.
    pub notes: Vec<String>,
}

/// A buckling run with its shapes.
pub struct BucklingRun {
    /// The report.
    pub report: BucklingReport,
    /// Buckling shapes at the mesh nodes: 3 translations per node (node-major), scaled to a
    /// largest translation of 1.
    pub shapes: Vec<Vec<f64>>,
    /// The shapes over the free DOFs, K-normalised (φᵀKφ = 1).
    pub vectors: Mat<f64>,
    /// The model solved (for the result files: its cells and the vectors' rotations).
    pub model: Arc<Model>,
}

/// The verified solution of the pencil.
pub struct PencilSolution {
    /// Load factors, ascending, positive.
    pub lambda: Vec<f64>,
    /// Vectors (columns), K-orthonormal.
    pub vectors: Mat<f64>,
    /// ‖Kφ + λK_σφ‖/‖Kφ‖.
    pub rel_residual: Vec<f64>,
    /// Backward errors.
    pub backward_error: Vec<f64>,
    /// The Sturm count.
    pub sturm: BucklingSturm,
    /// No compressive part: no positive factor at all.
    pub no_buckling: bool,
    /// Operator applications.
    pub applications: usize,
    /// Factorisations made here (K unless it was given, the Sturm point).
    pub factorizations: usize,
    /// Worst probe backward error of the factorisations.
    pub factor_backward_error: f64,
    /// Seconds: factorisation of K, iteration, verification.
    pub times: [f64; 3],
}

/// Relative size below which a Ritz value μ = 1/λ counts as zero (the null space of K_σ).
const ZERO_MU: f64 = 1e-10;
/// Convergence: backward error of a Ritz pair (or [`VERIFY_TOL`] once its value has settled).
const TOL: f64 = 1e-12;
/// Backward error accepted.
const VERIFY_TOL: f64 = 1e-10;
/// Backward errors are computed exactly (a pass over |K| and |G|) for Ritz values that moved
/// by less than this (relative to the largest) in a step.
const EXACT_GATE: f64 = 1e-8;
/// Estimates for the shift: Ritz values that moved by less than this (relative) in a step.
const ESTIMATE_TOL: f64 = 1e-3;
/// Without a positive estimate, the Sturm count is taken at 1/(this · max|μ|): a point this far
/// out keeps `K − σG` within ~1e6 of K's conditioning.
const NO_FACTOR_BELOW: f64 = 1e-6;
/// Estimates closer than this ratio form a cluster the shift is not placed in.
const CLUSTER: f64 = 1.02;

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

/// A K-orthonormal basis with its images K·V and G·V, and the projected matrix `T = VᵀGV`
/// kept up to date (each append adds its columns' rows and columns, a restart rotates it), so
/// that a Rayleigh–Ritz step does not recompute all of it.
struct Basis<'a> {
    k: &'a SymMatrix,
    g: &'a SymMatrix,
    v: Mat<f64>,
    kv: Mat<f64>,
    gv: Mat<f64>,
    t: Mat<f64>,
    cols: usize,
}

impl Basis<'_> {
    /// Orthogonalise the columns of `w` against the basis and each other in the K inner
    /// product and append the directions that keep more than 1e-7 of their K-norm; returns
    /// how many were added. Block classical Gram–Schmidt, twice: each pass projects out the
    /// basis (with the kept `K V`: no product with K) and orthonormalises the block through the
    /// eigen decomposition of its K-Gram matrix, `K W` coming from one block product with K per
    /// pass (sparse products by blocks read the matrix once for all the columns).
    fn append(&mut self, w: MatRef<'_, f64>) -> usize {
        let m = w.ncols().min(self.v.ncols() - self.cols);
        if m == 0 {
            return 0;
        }
        let (n, c) = (w.nrows(), self.cols);
        let mut x = w.subcols(0, m).to_owned();
        // The K-norms of the columns as given: Σ coef² + ‖projected‖²_K (the basis is
        // K-orthonormal).
        let mut norm0 = vec![0.0f64; m];
        let mut kx = Mat::zeros(n, m);
        for pass in 0..2 {
            if c > 0 {
                let coef = tall::gram(self.kv.as_ref().subcols(0, c), x.as_ref());
                if pass == 0 {
                    for (j, nj) in norm0.iter_mut().enumerate() {
                        *nj = (0..c).map(|i| coef[(i, j)].powi(2)).sum();
                    }
                }
                tall::mul(
                    x.as_mut(),
                    Accum::Add,
                    self.v.as_ref().subcols(0, c),
                    coef.as_ref(),
                    -1.0,
                );
            }
            kx = Mat::zeros(n, x.ncols());
            self.k.mul_block(x.as_ref(), kx.as_mut());
            let h = tall::gram(x.as_ref(), kx.as_ref());
            let scale: Vec<f64> = if pass == 0 {
                (0..x.ncols())
                    .map(|j| {
                        let s2 = norm0[j] + h[(j, j)].max(0.0);
                        if s2 > 0.0 { 1.0 / s2.sqrt() } else { 0.0 }
                    })
                    .collect()
            } else {
                vec![1.0; x.ncols()]
            };
            let q = match orthonormalizer(&h, &scale, if pass == 0 { 1e-14 } else { 0.5 }) {
                Some(q) => q,
                None => return 0,
            };
            x = &x * &q;
            kx = &kx * &q;
        }
        let k = x.ncols();
        let mut gx = Mat::zeros(n, k);
        self.g.mul_block(x.as_ref(), gx.as_mut());
        self.v.as_mut().subcols_mut(c, k).copy_from(&x);
        self.kv.as_mut().subcols_mut(c, k).copy_from(&kx);
        self.gv.as_mut().subcols_mut(c, k).copy_from(&gx);
        // The new rows and columns of T: Vᵀ(G X), the new diagonal block symmetrised.
        let tn = tall::gram(self.v.as_ref().subcols(0, c + k), gx.as_ref());
        for j in 0..k {
            for i in 0..c + k {
                let t = if i >= c {
                    0.5 * (tn[(i, j)] + tn[(c + j, i - c)])
                } else {
                    tn[(i, j)]
                };
                self.t[(i, c + j)] = t;
                self.t[(c + j, i)] = t;
            }
        }
        self.cols += k;
        k
    }

    /// Ritz pairs of the basis, μ descending: values and the coefficient matrix.
    fn ritz(&self) -> Result<(Vec<f64>, Mat<f64>)> {
        let c = self.cols;
        let ts = self.t.as_ref().submatrix(0, 0, c, c).to_owned();
        let (mu, u) = crate::linalg::dense::scaled_self_adjoint_eigen(&ts).map_err(|e| match e {
            Error::Factorization(m) => Error::Factorization(format!("buckling: {m}")),
            other => other,
        })?;
        // Descending.
        let vals: Vec<f64> = mu.into_iter().rev().collect();
        let s = Mat::from_fn(c, c, |i, j| u[(i, c - 1 - j)]);
        Ok((vals, s))
    }

    /// Replace the basis by its first `keep` Ritz vectors (coefficients `s`).
    fn restart(&mut self, s: MatRef<'_, f64>, keep: usize) {
        let c = self.cols;
        let y = s.subrows(0, c).subcols(0, keep);
        for m in [&mut self.v, &mut self.kv, &mut self.gv] {
            tall::combine_columns_in_place(m.as_mut().subcols_mut(0, c), y);
        }
        // T rotated: YᵀTY (diagonal up to rounding), symmetrised.
        let ty = self.t.as_ref().submatrix(0, 0, c, c) * y;
        let r = y.transpose() * &ty;
        for j in 0..keep {
            for i in 0..keep {
                self.t[(i, j)] = 0.5 * (r[(i, j)] + r[(j, i)]);
            }
        }
        self.cols = keep;
    }
}

/// The coefficients `Q` that make `X Q` K-orthonormal, from `h = XᵀKX`: the eigenvectors of
/// `D h D` (`D = diag(scale)`, the columns' K-norms as given brought to 1) whose eigenvalue
/// exceeds `floor` (the square of the fraction of its norm a direction keeps), each times
/// `D λ^{-1/2}`. `None` when no direction is kept.
fn orthonormalizer(h: &Mat<f64>, scale: &[f64], floor: f64) -> Option<Mat<f64>> {
    let m = h.nrows();
    let hs = Mat::from_fn(m, m, |i, j| 0.5 * (h[(i, j)] + h[(j, i)]) * scale[i] * scale[j]);
    let e = hs.self_adjoint_eigen(faer::Side::Lower).ok()?;
    // Descending, the strongest directions first.
    let keep: Vec<usize> = (0..m).rev().filter(|&i| e.S()[i] > floor).collect();
    if keep.is_empty() {
        return None;
    }
    let u = e.U();
    Some(Mat::from_fn(m, keep.len(), |i, j| {
        scale[i] * u[(i, keep[j])] / e.S()[keep[j]].sqrt()
    }))
}

/// The Ritz value `j` moved by at most 1e-10 of the largest |μ| since the previous step.
fn prev_settled(prev: &[f64], vals: &[f64], j: usize, top: f64) -> bool {
    prev.get(j).is_some_and(|&p| (p - vals[j]).abs() <= 1e-10 * top)
}

/// K factored, refused unless positive definite (a supported model).
fn factor_positive_definite(sym: &Arc<SymbolicFactor>, k: &SymMatrix) -> Result<Factor> {
    let fk = Factor::new(sym.clone(), k)?;
    if fk.negative_pivots > 0 || fk.pivot_range.0 <= fk.pivot_range.1 * 1e-13 {
        return Err(Error::Factorization(format!(
            "buckling needs a supported model: K is not positive definite ({} negative pivots, pivot ratio {:.1e})",
            fk.negative_pivots,
            fk.pivot_range.0 / fk.pivot_range.1.max(f64::MIN_POSITIVE)
        )));
    }
    Ok(fk)
}

/// A check point above the `reported` lowest of the `computed` positive factors (ascending):
/// between the last reported factor and the next (if one was computed), else twice the last;
/// at least 1e-6 of the last above it.
fn point_above(computed: &[f64], reported: usize) -> f64 {
    let last = computed[reported - 1];
    let point = match computed.get(reported) {
        Some(&next) => 0.5 * (last + next),
        None => 2.0 * last,
    };
    if point > last * (1.0 + 1e-6) {
        point
    } else {
        last * (1.0 + 1e-6)
    }
}

/// The spectral shift σ from `est`, estimates of the lowest factors (ascending; Ritz values,
/// so upper bounds of the true ones): midway between the `nev`-th estimate (or the first after
/// it) and the next one at least [`CLUSTER`] above it, so that σ keeps about 1 % from every
/// estimate; 1 % above the last estimate if no gap is found; twice the last when fewer than
/// `nev + 1` estimates exist (then they are all the positive factors there are).
fn shift_from_estimates(est: &[f64], nev: usize) -> f64 {
    let last = est[est.len() - 1];
    if est.len() <= nev {
        return 2.0 * last;
    }
    (nev - 1..est.len() - 1)
        .find(|&j| est[j + 1] > CLUSTER * est[j])
        .map(|j| 0.5 * (est[j] + est[j + 1]))
        .unwrap_or(last * (0.5 + 0.5 * CLUSTER))
}

/// The positive factors λ = 1/μ among the first `want` Ritz values (μ descending), ascending.
fn positive_factors(vals: &[f64], cols: usize, want: usize) -> Vec<f64> {
    let top = vals.iter().fold(0.0f64, |a, &m| a.max(m.abs()));
    (0..cols.min(want))
        .filter(|&j| vals[j] > ZERO_MU * top)
        .map(|j| 1.0 / vals[j])
        .collect()
}

/// The Ritz vectors `v[:, ..c] · s[:, ..cols]` (of V, KV or GV).
fn combine(v: &Mat<f64>, s: &Mat<f64>, c: usize, cols: usize) -> Mat<f64> {
    let mut y = Mat::zeros(v.nrows(), cols);
    tall::mul(
        y.as_mut(),
        Accum::Replace,
        v.as_ref().subcols(0, c),
        s.as_ref().subcols(0, cols),
        1.0,
    );
    y
}

/// The backward errors of the Ritz pairs (μ_j, y_j), ‖Gy − μKy‖ / (‖|G||y|‖ + |μ|‖|K||y|‖):
/// free of the cancellation a residual in the K⁻¹ norm suffers on ill-conditioned (slender)
/// models. The products with |G| and |K| (a pass over both matrices) are made only for the
/// pairs that `settled` admits (values that have nearly stopped moving) and that the bound
/// `‖Gy − μKy‖ / (‖Gy‖ + |μ|‖Ky‖)` (never below the backward error) does not already pass;
/// the others get that bound. `y` makes the Ritz vectors of the given pairs (only those
/// products need them).
fn ritz_backward_errors(
    k: &SymMatrix,
    g: &SymMatrix,
    vals: &[f64],
    y: impl Fn(&[usize]) -> Mat<f64>,
    ky: &Mat<f64>,
    gy: &Mat<f64>,
    settled: impl Fn(usize) -> bool,
) -> Vec<f64> {
    let norm = |m: &Mat<f64>, j: usize| m.col(j).iter().map(|v| v * v).sum::<f64>().sqrt();
    let m = ky.ncols();
    let r: Vec<f64> = (0..m)
        .map(|j| {
            let mu = vals[j];
            let (g, k) = (gy.col(j), ky.col(j));
            g.iter()
                .zip(k.iter())
                .map(|(g, k)| (g - mu * k).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let mut eta: Vec<f64> = (0..m)
        .map(|j| r[j] / (norm(gy, j) + vals[j].abs() * norm(ky, j)).max(f64::MIN_POSITIVE))
        .collect();
    let exact: Vec<usize> = (0..m).filter(|&j| eta[j] > TOL && settled(j)).collect();
    if !exact.is_empty() {
        let ys = y(&exact);
        let ag = g.abs_mul_norms(ys.as_ref());
        let ak = k.abs_mul_norms(ys.as_ref());
        for (t, &j) in exact.iter().enumerate() {
            eta[j] = r[j] / (ag[t] + vals[j].abs() * ak[t]).max(f64::MIN_POSITIVE);
        }
    }
    eta
}

/// ‖Kφ − λGφ‖ / ‖Kφ‖ per factor.
fn relative_residuals(k: &SymMatrix, g: &SymMatrix, lambda: &[f64], vectors: &Mat<f64>) -> Vec<f64> {
    let (n, m) = (vectors.nrows(), vectors.ncols());
    let mut kx = Mat::zeros(n, m);
    let mut gx = Mat::zeros(n, m);
    k.mul_block(vectors.as_ref(), kx.as_mut());
    g.mul_block(vectors.as_ref(), gx.as_mut());
    (0..m)
        .map(|j| {
            let (mut r2, mut k2) = (0.0, 0.0);
            for i in 0..n {
                r2 += (kx[(i, j)] - lambda[j] * gx[(i, j)]).powi(2);
                k2 += kx[(i, j)].powi(2);
            }
            (r2 / k2.max(f64::MIN_POSITIVE)).sqrt()
        })
        .collect()
}

/// The answer for a load without a positive factor (no compressive part).
fn no_buckling(
    n: usize,
    applications: usize,
    factorizations: usize,
    factor_err: f64,
    times: [f64; 3],
    point: f64,
) -> PencilSolution {
    PencilSolution {
        lambda: vec![],
        vectors: Mat::zeros(n, 0),
        rel_residual: vec![],
        backward_error: vec![],
        sturm: BucklingSturm {
            point,
            complete: true,
            ..Default::default()
        },
        no_buckling: true,
        applications,
        factorizations,
        factor_backward_error: factor_err,
        times,
    }
}

/// Basis capacity for `want` pairs grown by blocks of `b`.
fn capacity(n: usize, want: usize, b: usize) -> usize {
    (2 * want + 4 * b).max(40).min(n)
}

/// Where an iteration stops.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Goal {
    /// The first `want` Ritz values positive and settled to [`ESTIMATE_TOL`] (or converged).
    Estimates,
    /// The first `want` positive Ritz pairs converged (and the boundary, when fewer are
    /// positive).
    Converged,
}

/// The block Krylov iteration: the K-orthonormal basis, its generator and its work so far.
/// The basis is kept from one operator to the next (a rational Krylov space): the
/// Rayleigh–Ritz step on `(G, K)` does not depend on how its vectors were made.
struct Iteration<'a> {
    basis: Basis<'a>,
    rng: Rng,
    prev: Vec<f64>,
    applications: usize,
    b: usize,
    max_applications: usize,
}

impl<'a> Iteration<'a> {
    /// The iteration for `want` pairs, its basis started with a block of `K⁻¹G` applied to
    /// random vectors (in the range of G: no null-space part); `fk` factors K.
    fn start(k: &'a SymMatrix, g: &'a SymMatrix, fk: &Factor, want: usize, max_applications: usize) -> Self {
        let n = k.n();
        let b = want.clamp(3, 6).max(want / 4).min(32).min(n);
        let mut it = Iteration {
            basis: Basis {
                k,
                g,
                v: Mat::zeros(n, 0),
                kv: Mat::zeros(n, 0),
                gv: Mat::zeros(n, 0),
                t: Mat::zeros(0, 0),
                cols: 0,
            },
            rng: Rng(0x5eed_b0c1_1e00_0001),
            prev: Vec::new(),
            applications: b,
            b,
            max_applications,
        };
        it.reserve(want);
        let w = Mat::from_fn(n, b, |_, _| it.rng.next());
        let mut gw = Mat::zeros(n, b);
        g.mul_block(w.as_ref(), gw.as_mut());
        fk.solve_in_place(gw.as_mut());
        it.basis.append(gw.as_ref());
        it
    }

    /// Room for `want` pairs and the expansion blocks.
    fn reserve(&mut self, want: usize) {
        let n = self.basis.v.nrows();
        let nb = capacity(n, want, self.b);
        if nb > self.basis.v.ncols() {
            for m in [&mut self.basis.v, &mut self.basis.kv, &mut self.basis.gv] {
                m.resize_with(n, nb, |_, _| 0.0);
            }
            self.basis.t.resize_with(nb, nb, |_, _| 0.0);
        }
    }

    /// Iterate with `f`, a factorisation of `K − σG` (σ = 0: K), the operator being
    /// `(K − σG)⁻¹G` applied to the best unconverged Ritz vectors, until `goal` holds for the
    /// first `want` Ritz pairs. Returns the Ritz values μ (descending) and their coefficients.
    fn run(&mut self, f: &Factor, want: usize, goal: Goal) -> Result<(Vec<f64>, Mat<f64>)> {
        self.reserve(want);
        let (k, g, n, b) = (self.basis.k, self.basis.g, self.basis.v.nrows(), self.b);
        let nb = self.basis.v.ncols();
        let keep = (want + b).min(nb / 2).max(1);
        loop {
            let (vals, s) = self.basis.ritz()?;
            let c = self.basis.cols;
            let top = vals.iter().fold(0.0f64, |a, &m| a.max(m.abs()));
            // Ritz vectors to test and expand: the wanted (positive) ones first.
            let n_test = want.min(c);
            let pos = vals.iter().take(n_test).filter(|&&m| m > ZERO_MU * top).count();
            let cand = (pos.max(1) + b).min(c);
            let ky = combine(&self.basis.kv, &s, c, cand);
            let gy = combine(&self.basis.gv, &s, c, cand);
            let prev = &self.prev;
            let y = |cols: &[usize]| {
                let sc = Mat::from_fn(c, cols.len(), |i, t| s[(i, cols[t])]);
                combine(&self.basis.v, &sc, c, cols.len())
            };
            let eta = ritz_backward_errors(k, g, &vals, y, &ky, &gy, |j| {
                prev.get(j).is_some_and(|&p| (p - vals[j]).abs() <= EXACT_GATE * top)
            });
            let converged: Vec<bool> = (0..cand)
                .map(|j| {
                    let still = self
                        .prev
                        .get(j)
                        .is_some_and(|&p: &f64| (p - vals[j]).abs() <= 1e-14 * top);
                    eta[j] <= TOL || (eta[j] <= VERIFY_TOL && still)
                })
                .collect();
            let open: Vec<usize> = (0..pos.min(want).min(cand)).filter(|&j| !converged[j]).collect();
            let worst = open.iter().copied().max_by(|&a, &b| eta[a].total_cmp(&eta[b]));
            log::debug!(
                "buckling: basis {c}, μ {:?}, backward errors {:?}; {} of {} unconverged, worst {:?}",
                &vals[..cand.min(4)],
                &eta[..cand.min(4)],
                open.len(),
                pos.min(want),
                worst.map(|j| (j, vals[j], eta[j]))
            );
            let prev_before = std::mem::replace(&mut self.prev, vals.clone());
            let all_wanted = (0..pos.min(want)).all(|j| converged[j]);
            // Done: the wanted positive ones converged and, when fewer than wanted are positive,
            // the first non-positive one (the top of the null space) converged too.
            // (At the null space of K_σ the backward error of a Ritz pair need not fall: its settled
            // value is what is asked there.)
            let boundary_ok = pos >= want
                || converged.get(pos).copied().unwrap_or(true)
                || prev_settled(&prev_before, &vals, pos, top)
                || c == n;
            if (all_wanted && boundary_ok) || c == n {
                return Ok((vals, s));
            }
            let settled = |j: usize| {
                prev_before
                    .get(j)
                    .is_some_and(|&p| (p - vals[j]).abs() <= ESTIMATE_TOL * vals[j])
            };
            // Fewer positive values than wanted in a basis of twice the request: the positive
            // spectrum is sparse there (a mostly tensile load: a few factors, then values
            // crowding towards μ = 0, which the unshifted operator cannot separate). Their
            // estimates go to the shift; its count and the shifted iteration do the rest.
            // None at all there after twenty applications per wanted pair: the count at a far
            // point decides (`solve_pencil_from`).
            let sparse = pos < want && c >= 2 * want && (pos >= 1 || self.applications >= 20 * want);
            if goal == Goal::Estimates && (pos >= want || sparse) && (0..pos.min(want)).all(settled) {
                return Ok((vals, s));
            }
            if self.applications > self.max_applications {
                return Err(Error::EigenNotConverged(format!(
                    "buckling: {} operator applications, {} of {} load factors converged",
                    self.applications,
                    converged.iter().take(pos.min(want)).filter(|&&x| x).count(),
                    pos.min(want)
                )));
            }
            // Expand with the operator applied to the residuals of the best unconverged Ritz
            // pairs, `(K − σG)⁻¹(Gy − μKy)`: with y in the basis the same space as
            // `(K − σG)⁻¹Gy` (which is `(1 − μσ)⁻¹((K − σG)⁻¹r + μy)`), but without the
            // cancellation: once y is nearly an eigenvector, `(K − σG)⁻¹Gy` is y to all but a
            // fraction of its norm, and that fraction, below what the orthogonalisation keeps,
            // was dropped, so that the iteration went on with random directions.
            let pick: Vec<usize> = (0..cand).filter(|&j| !converged[j]).take(b).collect();
            let mut next = Mat::from_fn(n, pick.len(), |i, j| {
                let p = pick[j];
                gy[(i, p)] - vals[p] * ky[(i, p)]
            });
            f.solve_in_place(next.as_mut());
            self.applications += pick.len();
            if self.basis.cols + next.ncols() > nb {
                self.basis.restart(s.as_ref(), keep.min(c));
            }
            if self.basis.append(next.as_ref()) == 0 && self.basis.cols < nb {
                // The space is exhausted (invariant subspace): random directions carry on.
                let rnd = Mat::from_fn(n, 1, |_, _| self.rng.next());
                if self.basis.append(rnd.as_ref()) == 0 {
                    return Ok((vals, s));
                }
            }
        }
    }
}

/// Factorisations of `K − σG` the iteration may make (the first and, when the count at σ
/// shows fewer factors than asked, new points above).
const MAX_SHIFTS: usize = 3;

/// The lowest `nev` positive load factors of `(K + λK_σ)φ = 0`, verified (module doc). `k`
/// must be positive definite; `kg` is `K_σ` on K's pattern; `sym` the symbolic factorisation
/// of that pattern; `k_factor` a factorisation of `k` already made on `sym` (the static
/// solve's, proved positive definite there; dropped once the estimates are made), or `None`
/// to factor `k` here.
pub fn solve_pencil(
    k: &SymMatrix,
    kg: &SymMatrix,
    sym: &Arc<SymbolicFactor>,
    k_factor: Option<Factor>,
    nev: usize,
    max_applications: usize,
) -> Result<PencilSolution> {
    solve_pencil_from(k, kg, sym, k_factor, nev, max_applications, None)
}

/// [`solve_pencil`], with the first spectral shift given (`first_shift`, load-factor units)
/// instead of placed from the estimates: for tests of the adaptation to a count that differs
/// from the request.
#[doc(hidden)]
pub fn solve_pencil_from(
    k: &SymMatrix,
    kg: &SymMatrix,
    sym: &Arc<SymbolicFactor>,
    k_factor: Option<Factor>,
    nev: usize,
    max_applications: usize,
    first_shift: Option<f64>,
) -> Result<PencilSolution> {
    if nev == 0 {
        return Err(Error::option("--modes", "--modes must be at least 1"));
    }
    let n = k.n();
    // No model has more load factors than equations: a larger request (usize::MAX from Python)
    // is the whole spectrum, not an overflow.
    let nev = nev.min(n);
    // G = −K_σ on the same pattern.
    let mut g = kg.clone();
    g.values.iter_mut().for_each(|a| *a = -*a);
    let t0 = Instant::now();
    let (fk, own_factorizations) = match k_factor {
        Some(f) => (f, 0),
        None => (factor_positive_definite(sym, k)?, 1),
    };
    let mut factor_err = fk.probe_residual;
    let t_factor_k = t0.elapsed().as_secs_f64();
    let mut t_shift = 0.0;
    let t1 = Instant::now();
    if g.values.iter().all(|&x| x == 0.0) {
        return Ok(no_buckling(
            n,
            0,
            own_factorizations,
            factor_err,
            [t_factor_k, 0.0, 0.0],
            0.0,
        ));
    }
    let want = nev + 1; // one more, to place the shift between factors
    let mut it = Iteration::start(k, &g, &fk, want, max_applications);
    // Estimates of the lowest factors with the factor of K (upper bounds: Ritz values).
    let (vals, _) = it.run(&fk, want, Goal::Estimates)?;
    drop(fk);
    let est = positive_factors(&vals, it.basis.cols, want);
    log::debug!("buckling: estimates {est:?} after {} applications", it.applications);
    let mut n_shifted = 0;
    let mut shifted = |sigma: f64| -> Result<Factor> {
        n_shifted += 1;
        let t = Instant::now();
        let f = Factor::new_shifted(sym.clone(), k, Some((&g, sigma)))?;
        t_shift += t.elapsed().as_secs_f64();
        factor_err = factor_err.max(f.probe_residual);
        Ok(f)
    };
    // No positive estimate: the count at a far point, 1/(NO_FACTOR_BELOW · max|μ|), proves that
    // no factor lies below it (there K − σG = K + σ|G| is positive definite when G has no
    // positive part, a stable factorisation), or shows the ones to find (that factor is then
    // the first shifted operator).
    let mut far = None;
    let mut sigma = match first_shift {
        Some(sigma) => sigma,
        None if est.is_empty() => {
            let top = vals.iter().fold(0.0f64, |a, &m| a.max(m.abs()));
            let point = 1.0 / (NO_FACTOR_BELOW * top);
            let f = shifted(point)?;
            log::debug!(
                "buckling: no positive estimate; count {} below {point:e}",
                f.negative_pivots
            );
            if f.negative_pivots == 0 {
                drop(shifted);
                let times = [t_factor_k + t_shift, t1.elapsed().as_secs_f64() - t_shift, 0.0];
                return Ok(no_buckling(
                    n,
                    it.applications,
                    own_factorizations + 1,
                    factor_err,
                    times,
                    point,
                ));
            }
            // Values from the unshifted operator cannot count as settled under the new one.
            it.prev.clear();
            // The factors below the far point lie anywhere in (0, point), and seen from it they
            // all map near −1/σ, unseparated (a 10 × 2 × 1 hex20 bar in tension: 9 below 1.25e13,
            // none found). Sturm counts on a log scale bring the point within 4× of the lowest
            // wanted one (3–4 more factorisations).
            let need = nev.min(f.negative_pivots);
            let (mut lo, mut hi, mut fh) = (point * NO_FACTOR_BELOW, point, f);
            while hi / lo > 4.0 {
                let mid = (lo * hi).sqrt();
                let fm = shifted(mid)?;
                if fm.negative_pivots >= need {
                    (hi, fh) = (mid, fm);
                } else {
                    lo = mid;
                }
            }
            log::debug!("buckling: the lowest positive factors lie below {hi:e} (none below {lo:e})");
            far = Some(fh);
            hi
        }
        None => shift_from_estimates(&est, nev),
    };
    // The shifted iteration: the factor of K − σG serves both the operator and the count.
    let mut shifts = 0;
    let (count, s, computed) = loop {
        let f = match far.take() {
            Some(f) => f,
            None => shifted(sigma)?,
        };
        shifts += 1;
        let count = f.negative_pivots;
        let target = if count >= nev { count } else { want };
        let (vals, s) = it.run(&f, target, Goal::Converged)?;
        let computed = positive_factors(&vals, it.basis.cols, target);
        log::debug!("buckling: σ = {sigma:e}, count {count}, computed {computed:?}");
        // Fewer below σ than asked while more were found above: a new point above them.
        if count >= nev || computed.len() <= count || shifts >= MAX_SHIFTS {
            break (count, s, computed);
        }
        sigma = point_above(&computed, nev.min(computed.len()));
    };
    drop(shifted);
    let t_solve = t1.elapsed().as_secs_f64() - t_shift;
    let t2 = Instant::now();
    let report_n = computed.len().min(nev);
    let lambda: Vec<f64> = computed[..report_n].to_vec();
    let vectors = combine(&it.basis.v, &s, it.basis.cols, report_n);
    let (rel_residual, backward_error, sturm) = verify(k, &g, &lambda, &vectors, sigma, count, &computed);
    Ok(PencilSolution {
        lambda,
        vectors,
        rel_residual,
        backward_error,
        sturm,
        no_buckling: false,
        applications: it.applications,
        factorizations: own_factorizations + n_shifted,
        factor_backward_error: factor_err,
        times: [t_factor_k + t_shift, t_solve, t2.elapsed().as_secs_f64()],
    })
}

/// The reported pairs' relative residuals and backward errors (of K φ − λ G φ = Kφ + λK_σφ),
/// and the Sturm record at `sigma` (`count` negative pivots there) against every positive
/// factor `computed` below it.
fn verify(
    k: &SymMatrix,
    g: &SymMatrix,
    lambda: &[f64],
    vectors: &Mat<f64>,
    sigma: f64,
    count: usize,
    computed: &[f64],
) -> (Vec<f64>, Vec<f64>, BucklingSturm) {
    let backward_error = backward_errors(k, g, lambda, vectors.as_ref());
    let rel_residual = relative_residuals(k, g, lambda, vectors);
    let found = computed.iter().filter(|&&l| l < sigma).count();
    let sturm = BucklingSturm {
        point: sigma,
        count,
        found,
        complete: count == found,
    };
    (rel_residual, backward_error, sturm)
}

/// Linear buckling of `mesh` under `loads` (one static case, with the prescribed displacements
/// of `opts.spec`): build the system once, solve the static case, assemble `K_σ` of its
/// stresses and find the lowest positive load factors. `read_time` (s) is reported as the
/// read phase.
pub fn run_buckling(
    mesh: &Mesh,
    source: &str,
    opts: &BucklingOptions,
    loads: &[Load],
    read_time: f64,
) -> Result<BucklingRun> {
    let t_all = Instant::now();
    let model = Model::build(mesh, &opts.spec, source)?;
    let sys = System::build(
        model,
        &SystemOptions {
            ordering: opts.ordering,
            max_memory: opts.max_memory,
            mass: false,
            ..Default::default()
        },
        source,
    )?;
    let t_asm = t_all.elapsed().as_secs_f64();
    solve(&sys, mesh, loads, opts, read_time, t_asm)
}

/// The stress state K_σ is formed from: that of `c·u` ([`load_scale`]), with the extremes
/// reported as those of `u`. Linear buckling is scale-free (K_σ is linear in u: λ·K_σ(u) =
/// (λ/c)·K_σ(c·u)): a load near the ends of the floating-point range (1e-200 N) is analysed
/// as c times itself and its load factors are scaled back by c, so that K_σ and its shifted
/// factors neither under- nor overflow (1e-200 N ended in "zero pivot").
fn scaled_stress(model: &Model, u: &[f64]) -> Result<(f64, InitialStress)> {
    let c = load_scale(model, u);
    let scaled: Vec<f64> = u.iter().map(|x| c * x).collect();
    let mut pre = InitialStress::from_displacements(model, &scaled)?;
    pre.tension.value /= c;
    pre.compression.value /= c;
    Ok((c, pre))
}

/// The factor c by which a static case's displacements `u` are scaled before K_σ is formed:
/// 1 for ordinary loads (largest |u| within 1e-100…1e100 of the model's size, the results
/// then unchanged to the bit), else what brings the largest |u| to 1e-6 of the size.
fn load_scale(model: &Model, u: &[f64]) -> f64 {
    let umax = u.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let (lo, hi) = crate::mesh::bounding_box(&model.nodes);
    let size = (0..3).map(|d| (hi[d] - lo[d]).powi(2)).sum::<f64>().sqrt();
    let c = 1e-6 * size / umax;
    if (1e-100..=1e100).contains(&(umax / size)) || !(c.is_finite() && c > 0.0) {
        1.0
    } else {
        c
    }
}

/// The static solve's error as buckling reports it: a model free to move needs supports (an
/// overflowing load is a factorisation error too, with its own message).
fn static_error(e: Error) -> Error {
    match e {
        Error::Factorization(m) if m.contains("under-constrained") || m.contains("singular") => {
            Error::Factorization(format!("buckling needs a supported model: {m}"))
        }
        e => e,
    }
}

/// [`run_buckling`] on an assembled system (K only; its stiffness is not changed).
pub fn solve(
    sys: &System,
    mesh: &Mesh,
    loads: &[Load],
    opts: &BucklingOptions,
    read_time: f64,
    t_asm: f64,
) -> Result<BucklingRun> {
    let t = Instant::now();
    let (st, fk) = statics::solve_keeping_factor(sys, mesh, &[loads.to_vec()]).map_err(static_error)?;
    let case = st
        .cases
        .into_iter()
        .next()
        .ok_or_else(|| Error::param("loads", "no static case was solved"))?;
    let t_static = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let (c, pre) = scaled_stress(sys.model(), &st.u[0])?;
    let kg = pre.geometric_stiffness(sys)?;
    let t_geo = t.elapsed().as_secs_f64();
    let n = sys.k().n();
    let dense = if solved_densely(n, opts.modes) {
        solve_pencil_dense(sys.k(), &kg, sys.symbolic()?, opts.modes)?
    } else {
        None
    };
    let dense_note = dense.as_ref().map(|d| {
        let got = d.lambda.len();
        if got < opts.modes {
            format!(
                "{} load factors asked of a {n}-DOF model: solved densely; it has {got} positive ones, all reported",
                opts.modes
            )
        } else {
            format!(
                "{} load factors asked of a {n}-DOF model: solved densely (every load factor at once) rather than by iteration",
                opts.modes
            )
        }
    });
    let mut sol = match dense {
        Some(d) => d,
        None => solve_pencil(
            sys.k(),
            &kg,
            sys.symbolic()?,
            Some(fk),
            opts.modes,
            opts.max_applications,
        )
        .map_err(|e| e.locate(|eq| sys.describe_equation(eq)))?,
    };
    sol.lambda.iter_mut().for_each(|l| *l *= c);
    sol.sturm.point *= c;
    let model = sys.model();
    let shapes = node_shapes(model, &sol.vectors);
    let max_res = sol.rel_residual.iter().fold(0.0f64, |a, &b| a.max(b));
    let max_back = sol.backward_error.iter().fold(0.0f64, |a, &b| a.max(b));
    let accurate = max_back <= VERIFY_TOL && sol.factor_backward_error <= 1e-8;
    let mut notes = model.notes.clone();
    notes.extend(case.notes.iter().cloned());
    let densely = dense_note.is_some();
    notes.extend(dense_note);
    if sol.no_buckling {
        notes.push(if sol.sturm.point > 0.0 {
            format!(
                "no buckling under this load: the Sturm count of K + σK_σ at σ = {} finds no positive load factor below it (σ is 1e6 times the smallest |λ|, a tensile factor)",
                crate::io::fmt_sig(sol.sturm.point, 6)
            )
        } else {
            "no buckling under this load: the geometric stiffness is zero".to_string()
        });
    } else if sol.lambda.len() < opts.modes && !densely {
        // What is proved is the count below the Sturm point; above it, that the iteration found
        // no further positive value of 1/λ (above 1e-10 of the largest |1/λ|).
        notes.push(format!(
            "only {} positive load factor(s) found under this load (the Sturm count at {} confirms none below it was missed; above it the iteration found no further positive 1/λ above 1e-10 of the largest |1/λ|)",
            sol.lambda.len(),
            crate::io::fmt_sig(sol.sturm.point, 6)
        ));
    }
    if !sol.sturm.complete {
        notes.push(format!(
            "Sturm check failed: K + σK_σ at σ = {:.6e} has {} negative pivots, {} load factors found below it",
            sol.sturm.point, sol.sturm.count, sol.sturm.found
        ));
    }
    if !accurate {
        notes.push(format!(
            "accuracy not guaranteed: largest backward error {max_back:.2e} (tolerance {VERIFY_TOL:.0e}), \
             factorisation probe {:.1e}",
            sol.factor_backward_error
        ));
    }
    if !model.beams.is_empty() {
        notes.push(crate::analysis::prestress::beam_geometric_note(model));
    }
    if !model.beams.is_empty() || !model.discrete.is_empty() || !model.references.is_empty() {
        notes.push(
            "geometric stiffness: solids (full stress), shells (membrane forces); springs, \
             point masses and couplings carry none"
                .to_string(),
        );
    }
    let total = t_all_total(read_time, t_asm, t_static, t_geo, &sol);
    let report = BucklingReport {
        mesh: sys.source().to_string(),
        nodes: model.n_mesh_nodes,
        dofs: model.dofs.n_free,
        load_factors: sol.lambda.clone(),
        modes: (0..sol.lambda.len())
            .map(|i| BucklingRow {
                mode: i + 1,
                load_factor: sol.lambda[i],
                rel_residual: sol.rel_residual[i],
                backward_error: sol.backward_error[i],
            })
            .collect(),
        no_buckling: sol.no_buckling,
        complete: sol.sturm.complete,
        sturm: sol.sturm.clone(),
        accurate,
        max_rel_residual: max_res,
        max_backward_error: max_back,
        factor_backward_error: sol.factor_backward_error,
        applied_force: norm3(case.applied.force),
        static_equilibrium_error: case.equilibrium_error,
        tension: pre.tension,
        compression: pre.compression,
        factorizations: 1 + sol.factorizations,
        operator_applications: sol.applications,
        timings_s: BucklingTimings {
            read: read_time,
            assemble: t_asm,
            statics: t_static,
            geometric: t_geo,
            factor: sol.times[0],
            solve: sol.times[1],
            verify: sol.times[2],
            total,
        },
        notes,
    };
    Ok(BucklingRun {
        report,
        shapes,
        vectors: sol.vectors,
        model: sys.model_arc().clone(),
    })
}

/// Models up to this many DOFs are solved densely when a request asks for more than a quarter
/// of their DOFs (a 2000-DOF dense eigen solve takes ~2 s): the iteration, asked for most of a
/// spectrum, converges slowly on its crowded upper end (`--modes 500` on a 720-DOF bar with
/// 488 positive factors: 20 000 operator applications and a failure after ~65 s).
const DENSE_MAX: usize = 2000;

/// Whether a request for `nev` load factors of an `n`-DOF model is solved densely.
fn solved_densely(n: usize, nev: usize) -> bool {
    n <= DENSE_MAX && nev.saturating_mul(4) > n
}

/// The lowest `nev` positive load factors by a dense solve of −K_σφ = μKφ (K positive definite,
/// μ = 1/λ; positive μ above [`ZERO_MU`] of the largest |μ|, as the iteration counts them),
/// verified as [`solve_pencil`]'s: backward errors, and a Sturm count of K − σG at a point above
/// the last reported factor (between it and the next). `None` when there is no positive factor
/// (the iteration's proof of that is used instead).
fn solve_pencil_dense(
    k: &SymMatrix,
    kg: &SymMatrix,
    sym: &Arc<SymbolicFactor>,
    nev: usize,
) -> Result<Option<PencilSolution>> {
    let t0 = Instant::now();
    let mut g = kg.clone();
    g.values.iter_mut().for_each(|a| *a = -*a);
    let (mu, x) = crate::linalg::dense::eigen_all(&g, k, 0.0, true)?;
    let top = mu.iter().fold(0.0f64, |a, &m| a.max(m.abs()));
    // Ascending λ = descending positive μ.
    let order: Vec<usize> = (0..mu.len()).rev().filter(|&i| mu[i] > ZERO_MU * top).collect();
    if order.is_empty() {
        return Ok(None);
    }
    let report_n = order.len().min(nev);
    let lambda: Vec<f64> = order[..report_n].iter().map(|&i| 1.0 / mu[i]).collect();
    let vectors = Mat::from_fn(k.n(), report_n, |r, c| x[(r, order[c])]);
    let t_solve = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    // The point: midway to the next distinct factor above the last reported (a double factor,
    // as a square section has, stays on one side); the count there proves the dense solve
    // found every factor below it, reported or not.
    let all: Vec<f64> = order.iter().map(|&i| 1.0 / mu[i]).collect();
    let last = lambda[report_n - 1];
    let sigma = all
        .iter()
        .find(|&&l| l > last * (1.0 + 1e-6))
        .map_or(last * (1.0 + 1e-3), |&next| 0.5 * (last + next));
    let f = Factor::new_shifted(sym.clone(), k, Some((&g, sigma)))?;
    let t_factor = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let (rel_residual, backward_error, sturm) = verify(k, &g, &lambda, &vectors, sigma, f.negative_pivots, &all);
    Ok(Some(PencilSolution {
        lambda,
        vectors,
        rel_residual,
        backward_error,
        sturm,
        no_buckling: false,
        applications: 0,
        factorizations: 1,
        factor_backward_error: f.probe_residual,
        times: [t_factor, t_solve, t2.elapsed().as_secs_f64()],
    }))
}

fn t_all_total(read: f64, asm: f64, st: f64, geo: f64, sol: &PencilSolution) -> f64 {
    read + asm + st + geo + sol.times.iter().sum::<f64>()
}

/// Shapes at the mesh nodes, 3 translations per node, largest translation 1 (positive).
fn node_shapes(model: &Model, x: &Mat<f64>) -> Vec<Vec<f64>> {
    let n_mesh = model.n_mesh_nodes;
    (0..x.ncols())
        .map(|c| {
            let col: Vec<f64> = x.col(c).iter().copied().collect();
            let mut s = model.dofs.expand(&col, 3);
            s.truncate(3 * n_mesh);
            let (mut big, mut at) = (0.0f64, 0usize);
            for a in 0..n_mesh {
                let m = (s[3 * a].powi(2) + s[3 * a + 1].powi(2) + s[3 * a + 2].powi(2)).sqrt();
                if m > big {
                    big = m;
                    at = a;
                }
            }
            if big > 0.0 {
                let sign = {
                    let v = &s[3 * at..3 * at + 3];
                    let j = (0..3).fold(0, |j, i| if v[i].abs() > v[j].abs() { i } else { j });
                    v[j].signum()
                };
                s.iter_mut().for_each(|e| *e *= sign / big);
            }
            s
        })
        .collect()
}

fn norm3(v: [f64; 3]) -> f64 {
    // hypot: no under- or overflow of the squares (a force of 1e-200 N read 0).
    v[0].hypot(v[1]).hypot(v[2])
}
