//! A reduced (Ritz) basis for the 3D machine's repeated runs: the envelope's points differ from
//! its nominal design only in what enters K at the attachment points (the leaves' thickness,
//! E and clamping, the magnets' stiffness) and in what enters the forced response alone
//! (damping, mains). Per machine base (geometry and load case) one basis V is built at a
//! reference stiffness K0 (the load case's nominal leaves and magnets):
//!
//! - the reference machine's lowest modes Φ (up to at least [`REFERENCE_RANGE`] × the response
//!   range),
//! - S1 = K0⁻¹B: the static responses to unit loads on the attachment DOFs (the leaves' table
//!   ends, the magnets' armature ends and the reactive mass's centre: 17 nodes × 6) and to the
//!   magnets' force pattern,
//! - S2 = K0⁻¹M S1: one more Krylov block,
//!
//! made M-orthonormal (near-dependent columns dropped), with VᵀK_baseV (K_base: the machine
//! without leaves and magnets) and V's rows on the attachment DOFs stored. A run at another
//! stiffness K(p) = K_base + ΔK(p) (ΔK(p) nonzero on the attachment DOFs only) then costs
//! K_r = VᵀK_baseV + Rᵀ ΔK R, a dense symmetric eigenproblem of the basis's size, and one
//! sparse product per mode for its check.
//!
//! # Why the basis holds the modes and the static solve
//! An eigenpair (λ, x) of K(p) satisfies (K0 − λM)x = −(ΔK(p) − ΔK0)x = B y for some y (the
//! difference acts on the attachment DOFs only): x = (K0 − λM)⁻¹B y, or, if that difference
//! is zero on x, x is a mode of K0. Expanding (K0 − λM)⁻¹ over K0's modes, the ones in Φ are in
//! the basis, and the rest is K0⁻¹ + λ K0⁻¹MK0⁻¹ + O((λ/λ_c)²) restricted to them (λ_c the
//! first mode of K0 not in Φ): S1 and S2 carry the first two terms. A mode of K(p) below the
//! response range therefore lies in the basis up to a term of relative size (λ/λ_c)², small
//! when Φ reaches well above the range. The static solve is exact in the basis: K(p)u = f
//! gives u = K0⁻¹f − K0⁻¹(ΔK(p) − ΔK0)u, both in span(S1) when f is a magnet force pattern.
//!
//! A reduced run is **verified by residuals, not by a Sturm count**: every mode it uses (those
//! up to the response range) must have a backward error η = ‖Kx − λMx‖ / (‖|K||x|‖ +
//! |λ|‖|M||x|‖) (the measure of the full eigen solver, [`crate::linalg::eigen::backward_errors`])
//! at or below the bar `envelope.reduced_tol`, or the run is made on the full model. Ritz values
//! are upper bounds of the eigenvalues of the same index (Rayleigh–Ritz), so a mode the basis
//! missed would shift the indices rather than hide between verified ones; the argument above
//! is why none is missed.

use crate::Result;
use crate::analysis::modal::{ModalReport, ModalRun};
use crate::linalg::factor::{Factor, SymbolicFactor};
use crate::linalg::sparse::SymMatrix;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par, c64};
use nalgebra::DMatrix;
use serde::Serialize;
use std::cell::RefCell;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// The reference run's modes reach at least this multiple of the response range.
pub const REFERENCE_RANGE: f64 = 2.0;

/// Default bar on a reduced run's backward errors (`envelope.reduced_tol`).
pub const DEFAULT_TOL: f64 = 1e-7;

/// Blocks of static responses in the basis: K0⁻¹B and K0⁻¹MK0⁻¹B (a third changed the backward
/// errors by nothing measurable on the coarse test machine: 6.9e-9 against 7.6e-9).
const KRYLOV_BLOCKS: usize = 2;

/// Part of a column's M-norm below which what is left after orthogonalisation counts as
/// dependent and is dropped.
const DROP: f64 = 1e-10;

/// A Ritz basis of one machine base at its reference stiffness.
pub struct Basis {
    /// n × c, M-orthonormal.
    v: Mat<f64>,
    /// VᵀK_baseV (c × c).
    kb: DMatrix<f64>,
    /// The attachment equations (free DOFs where the leaves and magnets enter K).
    att: Vec<usize>,
    /// V's rows on `att` (na × c).
    rows: DMatrix<f64>,
    /// The reference run's report (the machine's mass; no rigid-body modes).
    report: ModalReport,
}

/// M·X for a block X.
fn mul(a: &SymMatrix, x: &Mat<f64>) -> Mat<f64> {
    let mut y = Mat::zeros(x.nrows(), x.ncols());
    a.mul_block(x.as_ref(), y.as_mut());
    y
}

/// XᵀY as a nalgebra matrix.
fn gram(x: &Mat<f64>, y: &Mat<f64>) -> DMatrix<f64> {
    let mut g = Mat::zeros(x.ncols(), y.ncols());
    matmul(
        g.as_mut(),
        Accum::Replace,
        x.transpose(),
        y.as_ref(),
        1.0,
        Par::rayon(0),
    );
    DMatrix::from_fn(x.ncols(), y.ncols(), |i, j| g[(i, j)])
}

/// X·T for a nalgebra T.
fn times(x: &Mat<f64>, t: &DMatrix<f64>) -> Mat<f64> {
    let tf = Mat::from_fn(t.nrows(), t.ncols(), |i, j| t[(i, j)]);
    let mut y = Mat::zeros(x.nrows(), t.ncols());
    matmul(y.as_mut(), Accum::Replace, x.as_ref(), tf.as_ref(), 1.0, Par::rayon(0));
    y
}

fn symmetrise(a: &mut DMatrix<f64>) {
    let n = a.nrows();
    for i in 0..n {
        for j in 0..i {
            let v = 0.5 * (a[(i, j)] + a[(j, i)]);
            a[(i, j)] = v;
            a[(j, i)] = v;
        }
    }
}

/// Columns orthogonalised together against the basis so far (after the modes).
const GS_BLOCK: usize = 64;

/// An M-orthonormal basis of the span of `cols` (the first `n_modes` of them modes): each
/// column made M-orthogonal to the basis so far by classical Gram–Schmidt twice (which keeps
/// orthogonality to rounding without squaring the columns' conditioning, as a Gram matrix
/// would), and dropped when what is left is below [`DROP`] of its M-norm after the modes. The
/// modes go column by column; the other columns in blocks of [`GS_BLOCK`]: a block is projected
/// against the basis so far with matrix products (twice), then its columns against the block's
/// columns kept before them, one by one. In exact arithmetic this is the column-by-column
/// process; it needs one product with M per column instead of five.
fn m_orthonormal(m: &SymMatrix, cols: &[Vec<f64>], n_modes: usize) -> Mat<f64> {
    let n = m.n();
    let mut q = Mat::<f64>::zeros(n, cols.len());
    let mut mq = Mat::<f64>::zeros(n, cols.len());
    let mut k = 0;
    let n_modes = n_modes.min(cols.len());
    let mut start = 0;
    while start < cols.len() {
        let end = if start < n_modes {
            n_modes
        } else {
            (start + GS_BLOCK).min(cols.len())
        };
        let mut w = Mat::from_fn(n, end - start, |i, j| cols[start + j][i]);
        let norms = |w: &Mat<f64>| -> Vec<f64> {
            let mw = mul(m, w);
            (0..w.ncols())
                .map(|j| (0..n).map(|i| w[(i, j)] * mw[(i, j)]).sum::<f64>().max(0.0).sqrt())
                .collect()
        };
        // The part of the basis so far the columns' norms are measured after: the modes.
        let k_modes = n_modes.min(k);
        // Measured after the projection on the modes when they are all in, else as given.
        let after_modes = k_modes > 0 && k >= n_modes;
        let mut norm0 = if after_modes { vec![] } else { norms(&w) };
        for (lo, hi) in [(0, k_modes), (k_modes, k)] {
            if hi > lo {
                for _ in 0..2 {
                    let (qs, mqs) = (q.as_ref().subcols(lo, hi - lo), mq.as_ref().subcols(lo, hi - lo));
                    let mut h = Mat::zeros(hi - lo, w.ncols());
                    matmul(
                        h.as_mut(),
                        Accum::Replace,
                        mqs.transpose(),
                        w.as_ref(),
                        1.0,
                        Par::rayon(0),
                    );
                    matmul(w.as_mut(), Accum::Add, qs, h.as_ref(), -1.0, Par::rayon(0));
                }
            }
            if lo == 0 && after_modes {
                norm0 = norms(&w);
            }
        }
        let k_block = k;
        for (j, &nrm0) in norm0.iter().enumerate() {
            let mut v = w.as_ref().subcols(j, 1).to_owned();
            if k > k_block {
                for _ in 0..2 {
                    let (qs, mqs) = (
                        q.as_ref().subcols(k_block, k - k_block),
                        mq.as_ref().subcols(k_block, k - k_block),
                    );
                    let mut h = Mat::zeros(k - k_block, 1);
                    matmul(h.as_mut(), Accum::Replace, mqs.transpose(), v.as_ref(), 1.0, Par::Seq);
                    matmul(v.as_mut(), Accum::Add, qs, h.as_ref(), -1.0, Par::Seq);
                }
            }
            let mv = mul(m, &v);
            let norm = (0..n).map(|i| v[(i, 0)] * mv[(i, 0)]).sum::<f64>().max(0.0).sqrt();
            if !(nrm0 > 0.0) || norm <= DROP * nrm0 {
                continue;
            }
            for i in 0..n {
                q[(i, k)] = v[(i, 0)] / norm;
                mq[(i, k)] = mv[(i, 0)] / norm;
            }
            k += 1;
        }
        start = end;
    }
    q.subcols(0, k).to_owned()
}

impl Basis {
    /// The basis of the module's documentation: `modes` of the reference stiffness `k0`, whose
    /// part without leaves and magnets is `k_base`; `att` the attachment equations, `loads` the
    /// force patterns (free-DOF vectors) whose static responses must be exact.
    pub fn build(
        k_base: &SymMatrix,
        k0: &SymMatrix,
        m: &SymMatrix,
        sym: Arc<SymbolicFactor>,
        modes: &ModalRun,
        att: Vec<usize>,
        loads: &[Vec<f64>],
    ) -> Result<Basis> {
        let n = k0.n();
        let fac = Factor::new(sym, k0)?;
        let nb = att.len() + loads.len();
        let mut s1 = Mat::from_fn(n, nb, |i, j| match j < att.len() {
            true => f64::from(u8::from(att[j] == i)),
            false => loads[j - att.len()][i],
        });
        fac.solve_in_place(s1.as_mut());
        let mut blocks = vec![s1];
        for _ in 1..KRYLOV_BLOCKS {
            let mut s2 = mul(m, blocks.last().unwrap());
            fac.solve_in_place(s2.as_mut());
            blocks.push(s2);
        }
        let mut cols: Vec<Vec<f64>> = (0..modes.vectors.ncols())
            .map(|j| modes.vectors.col(j).iter().copied().collect())
            .collect();
        for blk in &blocks {
            cols.extend((0..nb).map(|j| blk.col(j).iter().copied().collect::<Vec<f64>>()));
        }
        let v = m_orthonormal(m, &cols, modes.vectors.ncols());
        let mut kb = gram(&v, &mul(k_base, &v));
        symmetrise(&mut kb);
        let rows = DMatrix::from_fn(att.len(), v.ncols(), |a, j| v[(att[a], j)]);
        Ok(Basis {
            v,
            kb,
            att,
            rows,
            report: modes.report.clone(),
        })
    }

    /// Columns of the basis.
    pub fn columns(&self) -> usize {
        self.v.ncols()
    }
}

/// A machine run in a basis: its Ritz pairs as a modal run, and the static solve.
pub struct ReducedRun {
    /// The Ritz pairs (the lowest `want`) as a modal run (M-orthonormal vectors).
    pub run: ModalRun,
    /// The static solve in the basis.
    pub statics: Statics,
    /// Largest backward error of the modes used.
    pub backward: f64,
}

/// The static solve K(p)⁻¹f of a reduced run (exact in the basis for the magnets' forces).
pub struct Statics {
    basis: Arc<Basis>,
    /// Eigenvectors and eigenvalues of K_r (all of them).
    z: DMatrix<f64>,
    lam: Vec<f64>,
}

impl Statics {
    /// K(p)⁻¹f in the basis: V K_r⁻¹ Vᵀ f (real and imaginary parts).
    pub fn static_solve(&self, f: &[c64]) -> Vec<c64> {
        let v = &self.basis.v;
        let (n, c) = (v.nrows(), v.ncols());
        let mut out = vec![c64::new(0.0, 0.0); n];
        for part in 0..2 {
            let g: Vec<f64> = (0..c)
                .map(|j| {
                    (0..n)
                        .map(|i| v[(i, j)] * if part == 0 { f[i].re } else { f[i].im })
                        .sum()
                })
                .collect();
            // h = Z Λ⁻¹ Zᵀ g.
            let y: Vec<f64> = (0..c)
                .map(|k| (0..c).map(|j| self.z[(j, k)] * g[j]).sum::<f64>() / self.lam[k])
                .collect();
            let h: Vec<f64> = (0..c).map(|j| (0..c).map(|k| self.z[(j, k)] * y[k]).sum()).collect();
            for (i, o) in out.iter_mut().enumerate() {
                let s: f64 = (0..c).map(|j| v[(i, j)] * h[j]).sum();
                if part == 0 {
                    o.re = s;
                } else {
                    o.im = s;
                }
            }
        }
        out
    }
}

/// The run at stiffness `k` (= `k_base` plus the leaves and magnets) in `basis`: the lowest
/// `want` Ritz pairs, the modes up to `lambda_used` (rad²/s²) checked against `tol` (their
/// backward errors in the full model). `Ok(Err(η))`: a used mode's backward error η is above
/// the bar (or the reduced K is not positive definite: η = ∞).
pub fn run_in(
    basis: &Arc<Basis>,
    k: &SymMatrix,
    k_base: &SymMatrix,
    m: &SymMatrix,
    want: usize,
    lambda_used: f64,
    tol: f64,
) -> Result<std::result::Result<ReducedRun, f64>> {
    let b = &**basis;
    let na = b.att.len();
    let mut dk = DMatrix::<f64>::zeros(na, na);
    for (r, &er) in b.att.iter().enumerate() {
        for (c, &ec) in b.att.iter().enumerate() {
            if let Some(pos) = k.pattern.position(er, ec) {
                dk[(r, c)] = k.values[pos] - k_base.values[pos];
            }
        }
    }
    let mut kr = &b.kb + b.rows.transpose() * &dk * &b.rows;
    symmetrise(&mut kr);
    let eg = kr.symmetric_eigen();
    let c = eg.eigenvalues.len();
    let mut order: Vec<usize> = (0..c).collect();
    order.sort_by(|&i, &j| eg.eigenvalues[i].total_cmp(&eg.eigenvalues[j]));
    let lam: Vec<f64> = order.iter().map(|&i| eg.eigenvalues[i]).collect();
    if lam.first().is_none_or(|&l| !(l > 0.0)) {
        return Ok(Err(f64::INFINITY));
    }
    let z = DMatrix::from_fn(c, c, |i, k| eg.eigenvectors[(i, order[k])]);
    let want = want.min(c);
    let zw = z.columns(0, want).into_owned();
    let x = times(&b.v, &zw);
    let n_use = lam[..want]
        .iter()
        .position(|&l| l > lambda_used)
        .map_or(want, |k| k.max(1));
    let eta = crate::linalg::eigen::backward_errors(k, m, &lam[..n_use], x.as_ref().subcols(0, n_use));
    let worst = eta.iter().copied().fold(0.0, f64::max);
    if !(worst <= tol) {
        return Ok(Err(worst));
    }
    let run = ModalRun {
        report: b.report.clone(),
        shapes: vec![],
        lambda: lam[..want].to_vec(),
        vectors: x,
        model: None,
    };
    Ok(Ok(ReducedRun {
        run,
        statics: Statics {
            basis: basis.clone(),
            z,
            lam,
        },
        backward: worst,
    }))
}

/// What the reduced runs of one plan did.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Stats {
    /// Machine runs made in a basis.
    pub reduced_runs: usize,
    /// Machine runs made on the full model (reduction off, no basis for the geometry, or a
    /// fallback).
    pub full_runs: usize,
    /// Of the full runs, those whose reduced run was over the bar.
    pub fallbacks: usize,
    /// Largest backward error of an accepted reduced run's modes.
    pub max_backward_error: f64,
}

/// The bases of one envelope and its counts: set on the threads that run its points
/// ([`within`]); the 3D machine's runs under it look their base up here.
pub struct Plan {
    /// Reduced runs allowed (`envelope.reduced`).
    pub enabled: bool,
    /// Bar on the backward errors (`envelope.reduced_tol`).
    pub tol: f64,
    bases: Mutex<HashMap<String, Arc<Basis>>>,
    stats: Mutex<Stats>,
}

impl Plan {
    /// A plan with no bases yet.
    pub fn new(enabled: bool, tol: f64) -> Plan {
        Plan {
            enabled,
            tol,
            bases: Mutex::new(HashMap::new()),
            stats: Mutex::new(Stats::default()),
        }
    }

    /// Whether a basis for `key` is there.
    pub fn has(&self, key: &str) -> bool {
        self.bases.lock().unwrap_or_else(|e| e.into_inner()).contains_key(key)
    }

    /// Keep `basis` for the machine base `key`.
    pub fn insert(&self, key: String, basis: Basis) {
        self.bases
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .insert(key, Arc::new(basis));
    }

    /// The basis for `key`, if any (and reduction is on).
    pub fn basis(&self, key: &str) -> Option<Arc<Basis>> {
        if !self.enabled {
            return None;
        }
        self.bases.lock().unwrap_or_else(|e| e.into_inner()).get(key).cloned()
    }

    /// Count a run: `Some(η)` reduced with backward error η, `None` full (`fallback`: a reduced
    /// run was over the bar).
    pub fn count(&self, reduced: Option<f64>, fallback: bool) {
        let mut s = self.stats.lock().unwrap_or_else(|e| e.into_inner());
        match reduced {
            Some(eta) => {
                s.reduced_runs += 1;
                s.max_backward_error = s.max_backward_error.max(eta);
            }
            None => {
                s.full_runs += 1;
                s.fallbacks += usize::from(fallback);
            }
        }
    }

    /// The counts so far.
    pub fn stats(&self) -> Stats {
        *self.stats.lock().unwrap_or_else(|e| e.into_inner())
    }
}

thread_local! {
    static PLAN: RefCell<Option<Arc<Plan>>> = const { RefCell::new(None) };
}

/// Run `f` with `plan` as this thread's plan (the previous one restored after).
pub fn within<R>(plan: Option<&Arc<Plan>>, f: impl FnOnce() -> R) -> R {
    let prev = PLAN.with(|p| p.replace(plan.cloned()));
    let r = f();
    PLAN.with(|p| *p.borrow_mut() = prev);
    r
}

/// This thread's plan.
pub fn current() -> Option<Arc<Plan>> {
    PLAN.with(|p| p.borrow().clone())
}
