//! Mass lumping: the [`MassLumping`] choice and the lumping schemes on a dense scalar mass
//! matrix.
//!
//! For solids the element mass matrix is block-diagonal by direction, `M = m ⊗ I₃`, with one
//! scalar `n × n` matrix `m_ab = ∫ ρ N_a N_b dV`. Lumping works on `m`:
//!
//! - **HRZ** (Hinton, Rock and Zienkiewicz 1976), the scheme behind [`MassLumping::Lumped`]:
//!   keep the diagonal of the consistent matrix and scale it so that it sums to the element
//!   mass, `m̃_aa = m_aa · ρV / Σ_b m_bb`. Every entry is positive (`m_aa = ∫ ρ N_a² dV > 0`),
//!   also for quadratic elements, whose corner entries the row sum makes zero or negative.
//! - **Row sum**: `m̃_aa = Σ_b m_ab`. Fine for linear elements; for `Tet10`/`Hex20` it gives
//!   zero or negative corner masses, so it is offered only as a building block.
//!
//! Both keep the total `Σ_a m̃_aa = ρV` per direction.

use crate::error::{Error, Result};

/// How an element mass matrix is formed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MassLumping {
    /// Consistent mass `M = ∫ ρ Nᵀ N dV` (the default; converges from above for frequencies).
    #[default]
    Consistent,
    /// Diagonal HRZ lumped mass (diagonal of the consistent matrix scaled to the element mass).
    Lumped,
}

impl MassLumping {
    /// `"consistent"` or `"lumped"`.
    pub const fn name(self) -> &'static str {
        match self {
            MassLumping::Consistent => "consistent",
            MassLumping::Lumped => "lumped",
        }
    }

    /// Parses `"consistent"` or `"lumped"` (also `"hrz"`), ignoring case.
    pub fn parse(s: &str) -> Result<MassLumping> {
        match s.trim().to_ascii_lowercase().as_str() {
            "consistent" => Ok(MassLumping::Consistent),
            "lumped" | "hrz" => Ok(MassLumping::Lumped),
            _ => Err(Error::option(
                "--mass",
                format!("unknown mass matrix '{s}': expected 'consistent' or 'lumped'"),
            )),
        }
    }
}

impl std::fmt::Display for MassLumping {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// HRZ lumping in place: scales the diagonal `diag` (the `m_aa` of a consistent matrix) so
/// that it sums to `total` (the element mass `ρV`). Returns the scale factor `total / Σ m_aa`.
///
/// ```
/// // Tet10 consistent diagonal (in units of ρV/420): 6 at the corners, 32 on the edges.
/// let mut d = [6.0, 6.0, 6.0, 6.0, 32.0, 32.0, 32.0, 32.0, 32.0, 32.0];
/// vibrofem::element::lumping::hrz(&mut d, 1.0);
/// assert!((d.iter().sum::<f64>() - 1.0).abs() < 1e-15);
/// assert!((d[0] - 6.0 / 216.0).abs() < 1e-15);
/// ```
pub fn hrz(diag: &mut [f64], total: f64) -> f64 {
    let s: f64 = diag.iter().sum();
    let scale = total / s;
    for d in diag.iter_mut() {
        *d *= scale;
    }
    scale
}

/// Row-sum lumping of a dense row-major `n × n` matrix `m`: `diag[a] = Σ_b m[a][b]`.
pub fn row_sum(m: &[f64], n: usize, diag: &mut [f64]) {
    assert_eq!(m.len(), n * n, "row_sum: matrix size");
    assert_eq!(diag.len(), n, "row_sum: diagonal size");
    for (a, row) in m.chunks_exact(n).enumerate() {
        diag[a] = row.iter().sum();
    }
}

/// Writes the block matrix `m ⊗ I_dim` of a scalar row-major `n × n` matrix `m` into the
/// row-major `(dim·n) × (dim·n)` matrix `out`, node-major: `out[(dim a + i)(dim n) + dim b + j] =
/// δ_ij m[a][b]`. Every other entry is set to zero.
pub fn expand_blocks(m: &[f64], n: usize, dim: usize, out: &mut [f64]) {
    assert_eq!(m.len(), n * n, "expand_blocks: matrix size");
    let nd = n * dim;
    assert_eq!(out.len(), nd * nd, "expand_blocks: output size");
    out.fill(0.0);
    for a in 0..n {
        for b in 0..n {
            let v = m[a * n + b];
            for i in 0..dim {
                out[(dim * a + i) * nd + dim * b + i] = v;
            }
        }
    }
}

/// Writes the diagonal matrix `diag(d) ⊗ I_dim` into the row-major `(dim·n) × (dim·n)` matrix
/// `out` (all other entries zero).
pub fn expand_diagonal(d: &[f64], dim: usize, out: &mut [f64]) {
    let nd = d.len() * dim;
    assert_eq!(out.len(), nd * nd, "expand_diagonal: output size");
    out.fill(0.0);
    for (a, &v) in d.iter().enumerate() {
        for i in 0..dim {
            let r = dim * a + i;
            out[r * nd + r] = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for m in [MassLumping::Consistent, MassLumping::Lumped] {
            assert_eq!(MassLumping::parse(m.name()).unwrap(), m);
        }
        assert_eq!(MassLumping::parse("HRZ").unwrap(), MassLumping::Lumped);
        assert!(MassLumping::parse("diagonal").is_err());
        assert_eq!(MassLumping::default(), MassLumping::Consistent);
    }

    #[test]
    fn row_sum_and_blocks() {
        let m = [2.0, 1.0, 1.0, 2.0];
        let mut d = [0.0; 2];
        row_sum(&m, 2, &mut d);
        assert_eq!(d, [3.0, 3.0]);
        let mut out = [1.0; 36];
        expand_blocks(&m, 2, 3, &mut out);
        assert_eq!(out[0], 2.0);
        assert_eq!(out[1], 0.0);
        assert_eq!(out[3], 1.0);
        assert_eq!(out[6 * 4 + 1], 1.0);
        assert_eq!(out.iter().sum::<f64>(), 18.0);
    }
}
