//! Dense generalised eigen solver: the oracle for tests and the path for tiny models.
//!
//! With A = K − σM positive definite (σ below the spectrum) and A = LLᵀ, the eigenvalues θ of
//! C = L⁻¹ M L⁻ᵀ give λ = σ + 1/θ; this works for singular M too (θ = 0 is an infinite λ and
//! is dropped). Otherwise, with M positive definite, C = L_M⁻¹ K L_M⁻ᵀ gives λ directly.

use crate::linalg::sparse::SymMatrix;
use crate::{Error, Result};
use faer::Mat;
use nalgebra::DMatrix;

/// Dense copy of a sparse symmetric matrix.
pub fn to_dense(a: &SymMatrix) -> DMatrix<f64> {
    let n = a.n();
    let mut d = DMatrix::zeros(n, n);
    let p = &a.pattern;
    for j in 0..n {
        for k in p.col_ptr[j]..p.col_ptr[j + 1] {
            d[(p.row_idx[k] as usize, j)] = a.values[k];
        }
    }
    d
}

/// Eigenvalues (ascending) and orthonormal eigenvectors of the symmetric matrix `c` (read in
/// full), by faer's blocked solver on `c` scaled to a largest diagonal magnitude of 1.
///
/// faer's dense eigensolver stops on an absolute threshold: on matrices of large or small
/// magnitude it loses accuracy (eigenvalues ~1e11 rad²/s² came back with residuals of 1e-4
/// relative; a 300 × 300 matrix of entries ~1e-9, the size of a Lanczos projection's θ, with
/// residuals of 6e-9 relative to its norm against 1e-15 scaled). Scaled, its residuals are at
/// rounding level.
pub fn scaled_self_adjoint_eigen(c: &Mat<f64>) -> Result<(Vec<f64>, Mat<f64>)> {
    let n = c.nrows();
    let scale = (0..n).map(|i| c[(i, i)].abs()).fold(0.0, f64::max);
    let scale = if scale > 0.0 && scale.is_finite() { scale } else { 1.0 };
    let cs = Mat::from_fn(n, n, |i, j| c[(i, j)] / scale);
    let e = cs
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| Error::Factorization(format!("dense eigen solve: {e:?}")))?;
    Ok(((0..n).map(|i| e.S()[i] * scale).collect(), e.U().to_owned()))
}

/// All finite eigenpairs of K x = λ M x, ascending, eigenvectors M-orthonormal.
///
/// Two reductions to a standard symmetric problem: through the Cholesky factor of K − σM
/// (shift-and-invert: the low modes, which the eigenvalues 1/(λ − σ) dominate, to full relative
/// accuracy; the high ones only to about ε·λ_max/λ_low) or, with `upper`, through the Cholesky
/// factor of M (every pair backward stable with respect to K, so the upper spectrum too). A
/// request for most of the spectrum asks for `upper`; either falls back to the other when its
/// matrix is not positive definite.
pub fn eigen_all(k: &SymMatrix, m: &SymMatrix, sigma: f64, upper: bool) -> Result<(Vec<f64>, Mat<f64>)> {
    use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
    use faer::{Par, Side};
    let kd = to_faer(k);
    let md = to_faer(m);
    let n = kd.nrows();
    let par = Par::rayon(0);
    // C = L⁻¹ B L⁻ᵀ, symmetrised, for a Cholesky factor L.
    let reduce = |l: faer::MatRef<'_, f64>, b: &Mat<f64>| -> Mat<f64> {
        let mut w = b.clone();
        solve_lower_triangular_in_place(l, w.as_mut(), par);
        let mut c = w.transpose().to_owned();
        solve_lower_triangular_in_place(l, c.as_mut(), par);
        Mat::from_fn(n, n, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]))
    };
    let eig = scaled_self_adjoint_eigen;
    let a = Mat::from_fn(n, n, |i, j| kd[(i, j)] - sigma * md[(i, j)]);
    let m_chol = if upper { md.llt(Side::Lower).ok() } else { None };
    let shifted = if m_chol.is_some() {
        None
    } else {
        a.llt(Side::Lower).ok()
    };
    let (mut pairs, mut x) = if let Some(ch) = shifted {
        let l = ch.L();
        let (th, mut y) = eig(&reduce(l, &md))?;
        let thmax = th.iter().fold(0.0f64, |x, t| x.max(t.abs()));
        let pairs: Vec<(f64, usize)> = (0..n)
            .filter(|&i| th[i] > thmax * 1e-13)
            .map(|i| (sigma + 1.0 / th[i], i))
            .collect();
        // x = L⁻ᵀ y
        solve_upper_triangular_in_place(l.transpose(), y.as_mut(), par);
        (pairs, y)
    } else {
        let ch = match m_chol {
            Some(c) => c,
            None => md
                .llt(Side::Lower)
                .map_err(|_| Error::Factorization("dense oracle: neither K − σM nor M is positive definite".into()))?,
        };
        let l = ch.L();
        let (lam, mut y) = eig(&reduce(l, &kd))?;
        let pairs = (0..n).map(|i| (lam[i], i)).collect();
        solve_upper_triangular_in_place(l.transpose(), y.as_mut(), par);
        (pairs, y)
    };
    // Each kept vector, normalised in M (the transformation keeps M-orthogonality; fix the
    // scale), with its Rayleigh quotient xᵀKx as the eigenvalue: it pairs every value with its
    // own vector whatever order the dense solver returned them in, to second order in the
    // vector's error.
    let mut rq: Vec<(f64, Vec<f64>)> = pairs
        .iter()
        .map(|&(_, i)| {
            let col: Vec<f64> = (0..n).map(|r| x[(r, i)]).collect();
            let mx = m.mul_vec(&col);
            let s = col.iter().zip(&mx).map(|(a, b)| a * b).sum::<f64>().sqrt();
            let col: Vec<f64> = col.iter().map(|v| v / s).collect();
            let kx = k.mul_vec(&col);
            (col.iter().zip(&kx).map(|(a, b)| a * b).sum::<f64>(), col)
        })
        .collect();
    rq.sort_by(|a, b| a.0.total_cmp(&b.0));
    pairs.clear();
    x = Mat::from_fn(n, rq.len(), |r, c| rq[c].1[r]);
    Ok((rq.iter().map(|p| p.0).collect(), x))
}

/// Dense faer copy of a sparse symmetric matrix.
fn to_faer(a: &SymMatrix) -> Mat<f64> {
    let n = a.n();
    let mut d = Mat::zeros(n, n);
    let p = &a.pattern;
    for j in 0..n {
        for k in p.col_ptr[j]..p.col_ptr[j + 1] {
            d[(p.row_idx[k] as usize, j)] = a.values[k];
        }
    }
    d
}
