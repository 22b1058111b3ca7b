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
            d[(p.row_idx[k], j)] = a.values[k];
        }
    }
    d
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
    let kd = to_dense(k);
    let md = to_dense(m);
    let n = kd.nrows();
    let a = &kd - &md * sigma;
    let shifted = if upper && md.clone().cholesky().is_some() {
        None
    } else {
        a.clone().cholesky()
    };
    let (mut pairs, l) = if let Some(ch) = shifted {
        let l = ch.l();
        let linv = l
            .clone()
            .try_inverse()
            .ok_or_else(|| Error::Factorization("dense L not invertible".into()))?;
        let c = &linv * &md * linv.transpose();
        let c = (&c + c.transpose()) * 0.5;
        let eig = c.symmetric_eigen();
        let thmax = eig.eigenvalues.iter().fold(0.0f64, |x, t| x.max(t.abs()));
        let pairs: Vec<(f64, usize)> = (0..n)
            .filter(|&i| eig.eigenvalues[i] > thmax * 1e-13)
            .map(|i| (sigma + 1.0 / eig.eigenvalues[i], i))
            .collect();
        // x = L⁻ᵀ y
        (pairs, (linv.transpose() * eig.eigenvectors))
    } else {
        let ch = md
            .clone()
            .cholesky()
            .ok_or_else(|| Error::Factorization("dense oracle: neither K − σM nor M is positive definite".into()))?;
        let linv = ch
            .l()
            .try_inverse()
            .ok_or_else(|| Error::Factorization("dense L_M not invertible".into()))?;
        let c = &linv * &kd * linv.transpose();
        let c = (&c + c.transpose()) * 0.5;
        let eig = c.symmetric_eigen();
        let pairs = (0..n).map(|i| (eig.eigenvalues[i], i)).collect();
        (pairs, linv.transpose() * eig.eigenvectors)
    };
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut x = Mat::zeros(n, pairs.len());
    for (c, &(_, i)) in pairs.iter().enumerate() {
        // Normalise in M (the transformation keeps M-orthogonality; fix the scale).
        let col = l.column(i);
        let mx = &md * col;
        let s = col.dot(&mx).sqrt();
        for r in 0..n {
            x[(r, c)] = col[r] / s;
        }
    }
    Ok((pairs.iter().map(|p| p.0).collect(), x))
}
