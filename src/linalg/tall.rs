//! Products with tall matrices (n × k with n large, k small: Krylov bases, blocks of vectors),
//! parallel over fixed chunks of rows. The chunks do not depend on the thread count and partial
//! sums are added in chunk order, so the results are the same on any number of threads.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

/// Rows per chunk.
const ROWS: usize = 4096;

/// `out = a·b` (`Accum::Replace`) or `out += alpha·a·b` (`Accum::Add`, alpha applied in both
/// cases), with `a` tall (n × k) and `b` small (k × m).
pub fn mul(out: MatMut<'_, f64>, accum: Accum, a: MatRef<'_, f64>, b: MatRef<'_, f64>, alpha: f64) {
    let n = out.nrows();
    assert!(a.nrows() == n && a.ncols() == b.nrows() && b.ncols() == out.ncols());
    if n <= ROWS || b.ncols() == 0 {
        matmul(out, accum, a, b, alpha, Par::Seq);
        return;
    }
    out.par_row_chunks_mut(ROWS).enumerate().for_each(|(i, o)| {
        let rows = o.nrows();
        matmul(o, accum, a.subrows(i * ROWS, rows), b, alpha, Par::Seq);
    });
}

/// `a[:, 0..k] = a[:, 0..c]·y` in place for `y` (c × k, k ≤ c): each chunk of rows is
/// multiplied into a small buffer and written back, so no second tall matrix is allocated
/// (a thick restart of the Lanczos basis, and its final Ritz vectors, at the memory peak).
pub fn combine_columns_in_place(a: MatMut<'_, f64>, y: MatRef<'_, f64>) {
    let (c, k) = (y.nrows(), y.ncols());
    assert!(k <= c && c <= a.ncols());
    if k == 0 {
        return;
    }
    a.par_row_chunks_mut(ROWS).for_each(|rows| {
        let mut tmp = Mat::zeros(rows.nrows(), k);
        matmul(
            tmp.as_mut(),
            Accum::Replace,
            rows.as_ref().get(.., 0..c),
            y,
            1.0,
            Par::Seq,
        );
        rows.get_mut(.., 0..k).copy_from(&tmp);
    });
}

/// `out[:, j] += s[j]·a[:, j]` for tall `out` and `a` of the same shape.
pub fn add_scaled_columns(out: MatMut<'_, f64>, a: MatRef<'_, f64>, s: &[f64]) {
    assert!(out.nrows() == a.nrows() && out.ncols() == a.ncols() && a.ncols() == s.len());
    out.par_row_chunks_mut(ROWS).enumerate().for_each(|(c, mut o)| {
        let a = a.subrows(c * ROWS, o.nrows());
        for (j, &sj) in s.iter().enumerate() {
            for i in 0..o.nrows() {
                o[(i, j)] += sj * a[(i, j)];
            }
        }
    });
}

/// `aᵀ·b` for tall `a` (n × k) and `b` (n × m): per-chunk products summed in chunk order.
pub fn gram(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let n = a.nrows();
    assert_eq!(b.nrows(), n);
    let (k, m) = (a.ncols(), b.ncols());
    let mut out = Mat::zeros(k, m);
    if n <= ROWS || k == 0 || m == 0 {
        matmul(out.as_mut(), Accum::Replace, a.transpose(), b, 1.0, Par::Seq);
        return out;
    }
    let parts: Vec<Mat<f64>> = (0..n.div_ceil(ROWS))
        .into_par_iter()
        .map(|i| {
            let r0 = i * ROWS;
            let rows = ROWS.min(n - r0);
            let mut c = Mat::zeros(k, m);
            matmul(
                c.as_mut(),
                Accum::Replace,
                a.subrows(r0, rows).transpose(),
                b.subrows(r0, rows),
                1.0,
                Par::Seq,
            );
            c
        })
        .collect();
    for p in &parts {
        out += p;
    }
    out
}

/// Column dot products `Σ_i a[i, c]·b[i, c]`, parallel over columns.
pub fn col_dots(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Vec<f64> {
    assert!(a.nrows() == b.nrows() && a.ncols() == b.ncols());
    (0..a.ncols())
        .into_par_iter()
        .map(|c| a.col(c).iter().zip(b.col(c).iter()).map(|(x, y)| x * y).sum())
        .collect()
}
