//! Sparse LDLᵀ factorisation of symmetric matrices (faer supernodal), with inertia.
//!
//! One [`SymbolicFactor`] (ordering + elimination structure) serves every numeric
//! factorisation on the same pattern: K − σM for the eigen shift and for the Sturm checks.
//! LDLᵀ without pivoting is used for both SPD and indefinite matrices; its count of negative
//! pivots is the inertia that the Sturm-sequence check needs (Sylvester's law of inertia).

use crate::linalg::sparse::{Pattern, SymMatrix};
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
use std::sync::Arc;

/// Ordering and elimination structure, computed once per pattern.
pub struct SymbolicFactor {
    sym: SymbolicCholesky<usize>,
    /// Floating-point operations of one numeric factorisation (multiply and add counted
    /// separately: Σ_j c_j² over the columns of L, c_j its entries including the diagonal).
    pub flops: f64,
    /// Entries of L.
    pub nnz_l: usize,
}

impl SymbolicFactor {
    /// Symbolic analysis of `pattern` with the permutation `fwd` (`fwd[new] = old`).
    pub fn new(pattern: &Pattern, perm: Option<(&[usize], &[usize])>) -> Result<Self> {
        let ord = match perm {
            Some((fwd, inv)) => SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, pattern.n)),
            None => SymmetricOrdering::Amd,
        };
        let sym = factorize_symbolic_cholesky(pattern.symbolic(), Side::Upper, ord, CholeskySymbolicParams::default())
            .map_err(|e| Error::Factorization(format!("symbolic analysis: {e:?}")))?;
        let (flops, nnz_l) = count_flops(&sym);
        Ok(SymbolicFactor { sym, flops, nnz_l })
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
}

impl Factor {
    /// Factor `a` (stored symmetric, upper triangle read).
    pub fn new(sym: Arc<SymbolicFactor>, a: &SymMatrix) -> Result<Self> {
        let t0 = std::time::Instant::now();
        let mut values = Vec::new();
        values.try_reserve_exact(sym.sym.len_val()).map_err(|_| {
            Error::Factorization(format!(
                "cannot allocate the factor ({:.1} GiB)",
                sym.factor_bytes() as f64 / (1u64 << 30) as f64
            ))
        })?;
        values.resize(sym.sym.len_val(), 0.0);
        let par = Par::rayon(0);
        let req = sym.sym.factorize_numeric_ldlt_scratch::<f64>(par, Default::default());
        let mut mem =
            MemBuffer::try_new(req).map_err(|_| Error::Factorization("cannot allocate factor workspace".into()))?;
        let stack = MemStack::new(&mut mem);
        sym.sym
            .factorize_numeric_ldlt(
                &mut values,
                a.as_faer(),
                Side::Upper,
                LdltRegularization::default(),
                par,
                stack,
                Default::default(),
            )
            .map_err(|e| {
                // A zero pivot names its column of the permuted matrix: map it back to the
                // equation so the model layer can name the node and component.
                let equation = match e {
                    faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index } => {
                        // faer counts the failing pivot from 1.
                        let index = index.saturating_sub(1);
                        Some(match sym.sym.perm() {
                            Some(p) => p.arrays().0.get(index).copied().unwrap_or(index),
                            None => index,
                        })
                    }
                };
                Error::Singular {
                    equation,
                    at: None,
                    msg: format!("LDLᵀ: zero pivot, the matrix is singular ({e:?})"),
                }
            })?;
        log::info!(
            "factorised K − σM: {} entries in L, {:.3e} flop, {:.2} s",
            sym.nnz_l,
            sym.flops,
            t0.elapsed().as_secs_f64()
        );
        let d = diagonal(&sym.sym, &values);
        let adiag = a.diagonal();
        let min_rel_pivot = match sym.sym.perm() {
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
            let equation = match sym.sym.perm() {
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
        Ok(Factor {
            sym,
            values,
            negative_pivots,
            pivot_range: (lo, hi),
            min_rel_pivot,
            probe_residual: 0.0,
        })
    }

    /// Solve `A X = B` in place for a block of right-hand sides.
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let par = Par::Seq;
        let req = self.sym.sym.solve_in_place_scratch::<f64>(rhs.ncols(), par);
        let mut mem = MemBuffer::new(req);
        let stack = MemStack::new(&mut mem);
        LdltRef::new(&self.sym.sym, &self.values).solve_in_place_with_conj(Conj::No, rhs, par, stack);
    }

    /// Measure [`Factor::probe_residual`] against the matrix `a` that was factorised.
    pub fn probe(&mut self, a: &SymMatrix) {
        let n = a.n();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let x: Vec<f64> = (0..n)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        let b = a.mul_vec(&x);
        let mut y = faer::Mat::from_fn(n, 1, |i, _| b[i]);
        self.solve_in_place(y.as_mut());
        let yv: Vec<f64> = (0..n).map(|i| y[(i, 0)]).collect();
        let ay = a.mul_vec(&yv);
        let num: f64 = ay.iter().zip(&b).map(|(p, q)| (p - q) * (p - q)).sum::<f64>().sqrt();
        let den: f64 = b.iter().map(|q| q * q).sum::<f64>().sqrt();
        self.probe_residual = if den > 0.0 { num / den } else { 0.0 };
    }

    /// The symbolic part.
    pub fn symbolic(&self) -> &Arc<SymbolicFactor> {
        &self.sym
    }
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
