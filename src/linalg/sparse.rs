//! Symmetric sparse matrices stored in full (both triangles) compressed sparse columns.
//!
//! K, M and K − σM share one [`Pattern`]. Storing both triangles doubles the memory of the
//! values but makes the matrix–vector product a parallel, deterministic gather (each output
//! row is a dot product of one column), and faer's factorisation reads just the upper triangle.

use faer::sparse::SymbolicSparseColMat;
use faer::{MatMut, MatRef};
use rayon::prelude::*;
use std::sync::Arc;

/// A square sparsity pattern in CSC form, rows sorted within each column.
#[derive(Debug)]
pub struct Pattern {
    /// Dimension.
    pub n: usize,
    /// Column pointers, length `n + 1`.
    pub col_ptr: Vec<usize>,
    /// Row indices (32-bit: half the memory of the structure, and of the traffic of every
    /// sparse product; a model has fewer than 2³² equations).
    pub row_idx: Vec<u32>,
}

impl Pattern {
    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }
    /// The structure with faer's index type (a copy of the row indices, for its symbolic
    /// analysis).
    pub fn to_faer(&self) -> SymbolicSparseColMat<usize> {
        let rows: Vec<usize> = self.row_idx.iter().map(|&i| i as usize).collect();
        SymbolicSparseColMat::new_checked(self.n, self.n, self.col_ptr.clone(), None, rows)
    }
    /// Whether every entry of `sub` is an entry of this pattern (same dimension). M may be
    /// stored on a pattern of its own, which must lie in K's (the factorisations of K − σM are
    /// laid out on K's).
    pub fn contains(&self, sub: &Pattern) -> bool {
        if std::ptr::eq(self, sub) {
            return true;
        }
        if self.n != sub.n || sub.col_ptr.len() != sub.n + 1 {
            return false;
        }
        (0..self.n).into_par_iter().with_min_len(1024).all(|j| {
            let mut mine = self.row_idx[self.col_ptr[j]..self.col_ptr[j + 1]].iter();
            sub.row_idx[sub.col_ptr[j]..sub.col_ptr[j + 1]]
                .iter()
                .all(|r| mine.by_ref().any(|q| q == r))
        })
    }
    /// Position of entry `(row, col)` in the value array, if stored.
    pub fn position(&self, row: usize, col: usize) -> Option<usize> {
        let s = self.col_ptr[col];
        let rows = &self.row_idx[s..self.col_ptr[col + 1]];
        let row = u32::try_from(row).ok()?;
        rows.binary_search(&row).ok().map(|k| s + k)
    }
}

/// How many entries ahead the products ask for the row of x they will read. The rows of a
/// column come from all over x (gmsh numbers the mid-side nodes after every corner node), so
/// nearly every read misses the per-core cache and waits on the shared one; asked for this far
/// ahead, the rows are on their way while the entries before them are summed. Measured on the
/// 119k-DOF tet10 plate (M·X, 6 columns, 52 products per run): 1.46 s without, 1.23 s at 16,
/// 0.97–1.19 s at 32 and 64 (two runs each, one binary); 48 lies between them.
const PREFETCH_AHEAD: usize = 48;

/// Ask the cache for `xr[at..]` (a hint: nothing happens off x86-64 or past the end).
#[inline(always)]
fn prefetch(xr: &[f64], at: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(r) = xr.get(at) {
        // SAFETY: a prefetch reads nothing and writes nothing; the address is inside xr.
        unsafe { std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>((r as *const f64).cast()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (xr, at);
}

/// `body()` compiled for AVX-512F where the CPU has it, else as is. The products' per-entry
/// updates of up to eight columns then take one vector multiply and one add instead of four
/// of each (the baseline x86-64 target has two-wide vectors only): the same operations in the
/// same order, so the same bits. On the 119k-DOF tet10 plate (medians of 15, three runs each):
/// K·X with the backward errors' norms, 19 columns, 0.089–0.102 → 0.067–0.076 s; M·X alone,
/// bound by the memory more than by the arithmetic, 0.039 → 0.032–0.034 s.
#[inline(always)]
fn wide<R>(body: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        #[target_feature(enable = "avx512f")]
        unsafe fn run<R>(body: impl FnOnce() -> R) -> R {
            body()
        }
        // SAFETY: the CPU has AVX-512F (checked above).
        return unsafe { run(body) };
    }
    body()
}

/// `f::<w>(args)` for a chunk width `w` of 1 to 8 (the compile-time widths of the kernels).
macro_rules! by_width {
    ($w:expr, $f:ident($($a:expr),*)) => {
        match $w {
            1 => $f::<1>($($a),*),
            2 => $f::<2>($($a),*),
            3 => $f::<3>($($a),*),
            4 => $f::<4>($($a),*),
            5 => $f::<5>($($a),*),
            6 => $f::<6>($($a),*),
            7 => $f::<7>($($a),*),
            _ => $f::<8>($($a),*),
        }
    };
}

/// `Σ_i f(A[i, j]) · x[i, c]` for the B columns of `xr` (row-major x), entry by entry in the
/// stored order, each row of x asked for [`PREFETCH_AHEAD`] entries before its use.
#[inline(always)]
fn column_sums<const B: usize>(p: &Pattern, vals: &[f64], xr: &[f64], j: usize, f: impl Fn(f64) -> f64) -> [f64; B] {
    let (s, e) = (p.col_ptr[j], p.col_ptr[j + 1]);
    let mut acc = [0.0f64; B];
    let ahead = p.row_idx.get(s + PREFETCH_AHEAD..e + PREFETCH_AHEAD).unwrap_or(&[]);
    for (k, (&i, &a)) in p.row_idx[s..e].iter().zip(&vals[s..e]).enumerate() {
        if let Some(&q) = ahead.get(k) {
            prefetch(xr, q as usize * B);
        }
        let (i, a) = (i as usize, f(a));
        let xi: &[f64; B] = xr[i * B..i * B + B].try_into().expect("row of width B");
        for c in 0..B {
            acc[c] += a * xi[c];
        }
    }
    acc
}

/// [`column_sums`] of `A` and of `|A|` on `|x|` at once (one pass over the column and the rows
/// of x for both): the same sums, in the same order, as two calls.
#[inline(always)]
fn column_sums_and_abs<const B: usize>(p: &Pattern, vals: &[f64], xr: &[f64], j: usize) -> ([f64; B], [f64; B]) {
    let (s, e) = (p.col_ptr[j], p.col_ptr[j + 1]);
    let (mut acc, mut abs) = ([0.0f64; B], [0.0f64; B]);
    let ahead = p.row_idx.get(s + PREFETCH_AHEAD..e + PREFETCH_AHEAD).unwrap_or(&[]);
    for (k, (&i, &a)) in p.row_idx[s..e].iter().zip(&vals[s..e]).enumerate() {
        if let Some(&q) = ahead.get(k) {
            prefetch(xr, q as usize * B);
        }
        let i = i as usize;
        let xi: &[f64; B] = xr[i * B..i * B + B].try_into().expect("row of width B");
        for c in 0..B {
            acc[c] += a * xi[c];
            abs[c] += a.abs() * xi[c].abs();
        }
    }
    (acc, abs)
}

/// [`gather_rows`] and [`abs_norms`] in one pass: `out = A x` and `‖|A|·|x_c|‖₂`, in
/// [`abs_norms`]' chunks of rows, so both are the same bits as alone.
fn gather_rows_and_abs_norms<const B: usize>(p: &Pattern, vals: &[f64], xr: &[f64], out: MatMut<'_, f64>) -> Vec<f64> {
    let parts: Vec<[f64; B]> = out
        .par_row_chunks_mut(ABS_ROWS)
        .enumerate()
        .map(|(ch, mut o)| {
            wide(
                #[inline(always)]
                || {
                    let mut s2 = [0.0f64; B];
                    for jj in 0..o.nrows() {
                        let (acc, abs) = column_sums_and_abs::<B>(p, vals, xr, ch * ABS_ROWS + jj);
                        for c in 0..B {
                            o[(jj, c)] = acc[c];
                            s2[c] += abs[c] * abs[c];
                        }
                    }
                    s2
                },
            )
        })
        .collect();
    summed_norms(&parts)
}

/// Block product kernel with the block width known at compile time, so the accumulators stay
/// in registers: `out[j, c] = Σ_i A[i, j] · x[i, c]` for `x` row-major (`xr`, width B); the
/// results go straight into the columns of `out`, in parallel chunks of rows.
fn gather_rows<const B: usize>(p: &Pattern, vals: &[f64], xr: &[f64], out: MatMut<'_, f64>) {
    const ROWS: usize = 256;
    out.par_row_chunks_mut(ROWS).enumerate().for_each(|(ch, mut o)| {
        wide(
            #[inline(always)]
            || {
                for jj in 0..o.nrows() {
                    let acc = column_sums::<B>(p, vals, xr, ch * ROWS + jj, |a| a);
                    for (c, v) in acc.iter().enumerate() {
                        o[(jj, c)] = *v;
                    }
                }
            },
        )
    });
}

/// The columns of `x` in chunks of at most eight, each entry through `f`: `each(c0, w, xr)` with
/// `xr` the chunk's row-major copy (width `w`), so that each row a product gathers is one
/// contiguous piece and the chunk's width can be a compile-time constant.
fn column_chunks(x: MatRef<'_, f64>, f: impl Fn(f64) -> f64 + Sync, mut each: impl FnMut(usize, usize, &[f64])) {
    /// Rows per parallel piece of the copy.
    const ROWS: usize = 4096;
    let (n, b) = (x.nrows(), x.ncols());
    let mut c0 = 0;
    while c0 < b {
        let w = (b - c0).min(8);
        // Zeroed by the allocator (fresh pages come zeroed, without a pass over them): the copy
        // below, in parallel, is the first to touch them.
        let mut xr = vec![0.0f64; n * w];
        xr.par_chunks_mut(ROWS * w).enumerate().for_each(|(ch, piece)| {
            let i0 = ch * ROWS;
            for c in 0..w {
                let col = x.col(c0 + c);
                for (r, row) in piece.chunks_exact_mut(w).enumerate() {
                    row[c] = f(col[i0 + r]);
                }
            }
        });
        each(c0, w, &xr);
        c0 += w;
    }
}

/// `‖|A|·|x_c|‖₂` for the B columns of `xr` (row-major |x|): the rows' sums in fixed chunks of
/// rows in parallel, their squares summed in row order within a chunk and the chunks' totals in
/// chunk order (the same sums whatever the thread count).
fn abs_norms<const B: usize>(p: &Pattern, vals: &[f64], xr: &[f64]) -> Vec<f64> {
    let n = p.n;
    let parts: Vec<[f64; B]> = (0..n.div_ceil(ABS_ROWS))
        .into_par_iter()
        .map(|ch| {
            wide(
                #[inline(always)]
                || {
                    let mut s2 = [0.0f64; B];
                    for j in ch * ABS_ROWS..((ch + 1) * ABS_ROWS).min(n) {
                        let acc = column_sums::<B>(p, vals, xr, j, f64::abs);
                        for c in 0..B {
                            s2[c] += acc[c] * acc[c];
                        }
                    }
                    s2
                },
            )
        })
        .collect();
    summed_norms(&parts)
}

/// Rows per chunk of [`abs_norms`] (the chunks' sums are added in chunk order).
const ABS_ROWS: usize = 2048;

/// The square roots of the chunks' sums of squares, added in chunk order.
fn summed_norms<const B: usize>(parts: &[[f64; B]]) -> Vec<f64> {
    let mut out = [0.0f64; B];
    for part in parts {
        for c in 0..B {
            out[c] += part[c];
        }
    }
    out.iter().map(|v| v.sqrt()).collect()
}

/// A symmetric matrix on a shared pattern (both triangles stored).
#[derive(Clone, Debug)]
pub struct SymMatrix {
    /// The structure.
    pub pattern: Arc<Pattern>,
    /// Values, one per pattern entry.
    pub values: Vec<f64>,
}

impl SymMatrix {
    /// Zero matrix on `pattern`.
    pub fn zeros(pattern: Arc<Pattern>) -> Self {
        let nnz = pattern.nnz();
        SymMatrix {
            pattern,
            values: vec![0.0; nnz],
        }
    }
    /// Zero matrix on `pattern`; an allocation failure is an error naming `what` and the
    /// bytes it needed ([`crate::Error::out_of_memory`]) instead of an abort.
    pub fn try_zeros(pattern: Arc<Pattern>, what: &str) -> crate::Result<Self> {
        let nnz = pattern.nnz();
        let mut values = Vec::new();
        values
            .try_reserve_exact(nnz)
            .map_err(|_| crate::Error::out_of_memory(what, 8 * nnz as u64))?;
        values.resize(nnz, 0.0);
        Ok(SymMatrix { pattern, values })
    }
    /// Dimension.
    pub fn n(&self) -> usize {
        self.pattern.n
    }
    /// `self − s·other` on this matrix's pattern; `other`'s pattern must be the same or a
    /// subset of it ([`Pattern::contains`]).
    pub fn sub_scaled(&self, s: f64, other: &SymMatrix) -> SymMatrix {
        if !Arc::ptr_eq(&self.pattern, &other.pattern) {
            let other = other.on_pattern(self.pattern.clone());
            return self.sub_scaled(s, &other);
        }
        let values = self
            .values
            .par_iter()
            .zip(&other.values)
            .map(|(a, b)| a - s * b)
            .collect();
        SymMatrix {
            pattern: self.pattern.clone(),
            values,
        }
    }
    /// The same matrix without its stored zeros, on a pattern of its own. A solid's consistent
    /// mass matrix couples only equal components of two nodes (M = Mₛ ⊗ I₃ node by node), so
    /// on the stiffness pattern two of every three of its stored values are exact zeros:
    /// dropping them keeps a third of the values and of the work of each product `M x`.
    pub fn without_zeros(&self) -> SymMatrix {
        let p = &*self.pattern;
        // Counted per column, then copied in parallel by ranges of 2048 columns (the result
        // does not depend on the ranges).
        const COLS: usize = 2048;
        let ranges: Vec<(usize, usize)> = (0..p.n).step_by(COLS).map(|c| (c, (c + COLS).min(p.n))).collect();
        let kept_in = |j: usize| {
            self.values[p.col_ptr[j]..p.col_ptr[j + 1]]
                .iter()
                .filter(|&&v| v != 0.0)
                .count()
        };
        let counts: Vec<usize> = (0..p.n).into_par_iter().with_min_len(COLS).map(kept_in).collect();
        let mut col_ptr = Vec::with_capacity(p.n + 1);
        col_ptr.push(0);
        for c in &counts {
            col_ptr.push(col_ptr.last().copied().unwrap_or(0) + c);
        }
        let kept = col_ptr[p.n];
        let mut row_idx = vec![0u32; kept];
        let mut values = vec![0.0f64; kept];
        let mut pieces = Vec::with_capacity(ranges.len());
        let (mut ri, mut va) = (&mut row_idx[..], &mut values[..]);
        for &(c0, c1) in &ranges {
            let len = col_ptr[c1] - col_ptr[c0];
            let (r_here, r_rest) = std::mem::take(&mut ri).split_at_mut(len);
            let (v_here, v_rest) = std::mem::take(&mut va).split_at_mut(len);
            pieces.push((c0, c1, r_here, v_here));
            (ri, va) = (r_rest, v_rest);
        }
        pieces.into_par_iter().for_each(|(c0, c1, r, v)| {
            let mut t = 0;
            for q in p.col_ptr[c0]..p.col_ptr[c1] {
                if self.values[q] != 0.0 {
                    r[t] = p.row_idx[q];
                    v[t] = self.values[q];
                    t += 1;
                }
            }
        });
        SymMatrix {
            pattern: Arc::new(Pattern {
                n: p.n,
                col_ptr,
                row_idx,
            }),
            values,
        }
    }
    /// Bytes of the values, and of the pattern when it is not `shared` (the pattern of K, which
    /// the caller counts once).
    pub fn bytes_beside(&self, shared: &Arc<Pattern>) -> usize {
        let own = if Arc::ptr_eq(&self.pattern, shared) {
            0
        } else {
            8 * self.pattern.col_ptr.len() + 4 * self.pattern.row_idx.len()
        };
        self.value_bytes() + own
    }
    /// Diagonal entries (parallel over columns: a binary search in each reads most of the
    /// pattern, ~7 ms for K at 119k DOFs on one thread, and a modal run asks several times).
    pub fn diagonal(&self) -> Vec<f64> {
        (0..self.n())
            .into_par_iter()
            .with_min_len(4096)
            .map(|j| self.pattern.position(j, j).map_or(0.0, |p| self.values[p]))
            .collect()
    }
    /// `y = A x` for a block of vectors (columns of `x`). Parallel over rows, deterministic.
    /// Columns go in chunks of at most eight with the width known at compile time (the
    /// accumulators of a row stay in registers); each column's sums are the same in any chunk.
    pub fn mul_block(&self, x: MatRef<'_, f64>, mut y: MatMut<'_, f64>) {
        let n = self.n();
        let b = x.ncols();
        assert!(x.nrows() == n && y.nrows() == n && y.ncols() == b);
        let p = &*self.pattern;
        let vals = &self.values;
        column_chunks(
            x,
            |v| v,
            |c0, w, xr| {
                let out = y.as_mut().subcols_mut(c0, w);
                by_width!(w, gather_rows(p, vals, xr, out))
            },
        );
    }
    /// `‖|A|·|x_c|‖₂` for each column `x_c` of `x` (|A|: the entries' magnitudes), the scale of
    /// the rounding in forming `A x_c`. Parallel over fixed chunks of rows, summed in order.
    pub fn abs_mul_norms(&self, x: MatRef<'_, f64>) -> Vec<f64> {
        let n = self.n();
        let b = x.ncols();
        assert_eq!(x.nrows(), n);
        let (p, vals) = (&*self.pattern, &self.values);
        let mut out = Vec::with_capacity(b);
        // Each column's sums are the same in any chunk.
        column_chunks(x, f64::abs, |_, w, xr| out.extend(by_width!(w, abs_norms(p, vals, xr))));
        out
    }
    /// [`SymMatrix::mul_block`] into `y` and [`SymMatrix::abs_mul_norms`] returned, in one pass
    /// over the matrix (the same bits as the two calls).
    pub fn mul_block_abs_norms(&self, x: MatRef<'_, f64>, mut y: MatMut<'_, f64>) -> Vec<f64> {
        let n = self.n();
        let b = x.ncols();
        assert!(x.nrows() == n && y.nrows() == n && y.ncols() == b);
        let (p, vals) = (&*self.pattern, &self.values);
        let mut out = Vec::with_capacity(b);
        column_chunks(
            x,
            |v| v,
            |c0, w, xr| {
                let o = y.as_mut().subcols_mut(c0, w);
                out.extend(by_width!(w, gather_rows_and_abs_norms(p, vals, xr, o)))
            },
        );
        out
    }
    /// Bytes of the values (the pattern is shared and counted once elsewhere).
    pub fn value_bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<f64>()
    }
    /// `y = A x` for one vector.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        let p = &*self.pattern;
        (0..self.n())
            .into_par_iter()
            .with_min_len(1024)
            .map(|j| {
                let mut s = 0.0;
                for k in p.col_ptr[j]..p.col_ptr[j + 1] {
                    s += self.values[k] * x[p.row_idx[k] as usize];
                }
                s
            })
            .collect()
    }
}

impl SymMatrix {
    /// Build from triplets `(i, j, v)` of the upper or lower triangle (each off-diagonal pair
    /// given once; it is mirrored). Duplicates are summed. For tests and small models.
    pub fn from_triplets(n: usize, t: &[(usize, usize, f64)]) -> SymMatrix {
        let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
        for &(i, j, v) in t {
            cols[j].push((i, v));
            if i != j {
                cols[i].push((j, v));
            }
        }
        let mut col_ptr = vec![0usize];
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        for c in cols.iter_mut() {
            c.sort_by_key(|e| e.0);
            let mut last: Option<usize> = None;
            for &(i, v) in c.iter() {
                if last == Some(i) {
                    *values.last_mut().unwrap() += v;
                } else {
                    row_idx.push(u32::try_from(i).expect("a dimension below 2³²"));
                    values.push(v);
                    last = Some(i);
                }
            }
            col_ptr.push(row_idx.len());
        }
        SymMatrix {
            pattern: Arc::new(Pattern { n, col_ptr, row_idx }),
            values,
        }
    }

    /// Same values on another pattern that contains this one's (entries not stored here are 0).
    pub fn on_pattern(&self, pattern: Arc<Pattern>) -> SymMatrix {
        if Arc::ptr_eq(&self.pattern, &pattern) {
            return self.clone();
        }
        let mut out = SymMatrix::zeros(pattern.clone());
        let p = &*self.pattern;
        for j in 0..p.n {
            for k in p.col_ptr[j]..p.col_ptr[j + 1] {
                if let Some(pos) = pattern.position(p.row_idx[k] as usize, j) {
                    out.values[pos] = self.values[k];
                }
            }
        }
        out
    }
}
