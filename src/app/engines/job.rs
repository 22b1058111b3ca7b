//! A SLEPc job as vibrofem writes and reads it: its target, its shift, the fingerprint that ties
//! its results to one model, and the engine's error (used by the writer and by the import).

use crate::system::System;
use crate::{Error, Result};

/// The engine's name in messages.
pub(super) const ENGINE: &str = "SLEPc engine";

/// An error of the SLEPc engine (exit 5).
pub(super) fn engine_err(msg: impl Into<String>) -> Error {
    Error::Engine {
        engine: ENGINE.into(),
        msg: msg.into(),
    }
}

/// A fingerprint of K and M (size, entries, Σ|Kij|, Σ|Mij|, Σ Mii, the mass matrix's kind)
/// that ties SLEPc results to the model they were computed for: importing them for other model
/// options (supports, couplings, materials, density, lumped mass, point masses) is refused.
pub(super) fn fingerprint(sys: &System) -> Result<serde_json::Value> {
    let k = sys.k();
    let m = sys.m()?;
    let abs_sum = |v: &[f64]| v.iter().map(|x| x.abs()).sum::<f64>();
    Ok(serde_json::json!({
        "n": sys.n_free(),
        "nnz": k.pattern.nnz(),
        "abs_sum": abs_sum(&k.values),
        "m_nnz": m.pattern.nnz(),
        "m_abs_sum": abs_sum(&m.values),
        "m_diag_sum": m.diagonal().iter().sum::<f64>(),
        "mass_matrix": sys.model().spec.lumping.name(),
    }))
}

/// What a SLEPc job computes: the pairs nearest σ, or every eigenvalue in a band (λ units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum JobTarget {
    /// The `nev` eigenvalues nearest σ.
    Nearest(usize),
    /// Every eigenvalue in [lo, hi], rad²/s².
    Band(f64, f64),
}

/// A SLEPc job: its target and shift σ (rad²/s²), as `params.json` holds them.
#[derive(Clone, Copy, Debug)]
pub(super) struct Job {
    pub target: JobTarget,
    pub sigma: f64,
}
