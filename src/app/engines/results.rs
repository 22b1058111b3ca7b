//! Reading the results of a SLEPc job back (`lambda.bin`, `vectors.bin`, `slepc.json`, written
//! by `slepc_modes.py`), for a run here or a job imported from elsewhere.
//!
//! Only what can be verified is accepted: a job exported for this model (the fingerprint of K
//! and M in `params.json`) and for this request (the modes asked for are among those computed,
//! about the same shift); regular files of exactly the sizes `slepc.json` announces, checked
//! before they are read (a FIFO would block, a link to a device would never end); finite
//! values. Residuals, backward errors and M-orthonormality are recomputed here; completeness
//! comes from the job's Sturm counts, and a job holding more pairs than asked for is verified
//! whole before the asked ones are taken from it.

use super::job::{Job, JobTarget, engine_err, fingerprint};
use crate::analysis::modal::ModalParams;
use crate::linalg::eigen::{self, EigenParams, EigenSolution, SturmCheck};
use crate::linalg::sparse::SymMatrix;
use crate::post::modal::hz;
use crate::system::System;
use crate::{Error, Result};
use faer::Mat;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;
use std::time::Instant;

/// The largest `params.json` or `slepc.json` read (they hold a few hundred bytes).
const MAX_JSON_BYTES: u64 = 16 << 20;

/// What the script reports in `slepc.json`.
#[derive(Debug, serde::Deserialize)]
struct SlepcOut {
    n: usize,
    nconv: usize,
    converged: usize,
    iterations: usize,
    ranks: usize,
    sigma: f64,
    lower: (f64, usize),
    upper: (f64, usize),
    timings_s: BTreeMap<String, f64>,
    slepc: String,
}

/// `params.json` as `vibrofem export` writes it.
#[derive(Debug, serde::Deserialize)]
struct JobFile {
    #[serde(default)]
    nev: Option<usize>,
    #[serde(default)]
    band: Option<[f64; 2]>,
    sigma: f64,
    #[serde(default)]
    model: serde_json::Value,
}

use crate::util::max_nan;

/// `a` and `b` equal to rounding.
fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
}

fn not_regular(path: &Path, what: &str) -> Error {
    Error::io(
        path,
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("not a regular file ({what}): a SLEPc job folder holds the files slepc_modes.py wrote"),
        ),
    )
}

/// The length of the regular file at `path` (links followed). Anything else is refused before
/// it is opened: opening a FIFO blocks, a device reads without end.
fn regular_len(path: &Path) -> Result<u64> {
    let md = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if md.is_file() {
        return Ok(md.len());
    }
    let what = if md.is_dir() {
        "a directory"
    } else {
        "a FIFO, a device or a socket"
    };
    Err(not_regular(path, what))
}

/// The `len` bytes of the regular file at `path` (checked again on the file opened).
fn read_exact_file(path: &Path, len: u64) -> Result<Vec<u8>> {
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let md = f.metadata().map_err(|e| Error::io(path, e))?;
    if !md.is_file() {
        return Err(not_regular(path, "replaced while opened"));
    }
    let size = usize::try_from(len).map_err(|_| Error::out_of_memory(&path.display().to_string(), len))?;
    let mut buf = Vec::new();
    buf.try_reserve_exact(size)
        .map_err(|_| Error::out_of_memory(&path.display().to_string(), len))?;
    (&mut f)
        .take(len + 1)
        .read_to_end(&mut buf)
        .map_err(|e| Error::io(path, e))?;
    if buf.len() as u64 != len {
        return Err(engine_err(format!(
            "{}: {} bytes read where the file had {len}: it changed while read",
            path.display(),
            buf.len()
        )));
    }
    Ok(buf)
}

/// A small JSON file of the job folder as text.
pub(super) fn read_text(path: &Path) -> Result<String> {
    let len = regular_len(path)?;
    if len > MAX_JSON_BYTES {
        return Err(engine_err(format!(
            "{}: {len} bytes, more than a SLEPc job's JSON file holds (at most {MAX_JSON_BYTES})",
            path.display()
        )));
    }
    String::from_utf8(read_exact_file(path, len)?).map_err(|e| engine_err(format!("{}: {e}", path.display())))
}

/// `count` little-endian f64 values from `path`, whose size must be exactly theirs (`what` says
/// what `slepc.json` announced, for the message).
pub(super) fn read_f64s(path: &Path, count: Option<usize>, what: &str) -> Result<Vec<f64>> {
    let len = regular_len(path)?;
    let want = count.and_then(|c| c.checked_mul(8)).ok_or_else(|| {
        engine_err(format!(
            "{}: slepc.json announces {what}, more than a file can hold",
            path.display()
        ))
    })?;
    if len != want as u64 {
        return Err(engine_err(format!(
            "{}: {len} bytes where slepc.json announces {what} ({want} bytes)",
            path.display()
        )));
    }
    Ok(read_exact_file(path, len)?
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect())
}

/// A frequency in Hz for messages (a negative λ as a negative frequency).
fn hz_of(lambda: f64) -> String {
    let f = if lambda < 0.0 { -hz(-lambda) } else { hz(lambda) };
    crate::io::fmt_sig(f, 6)
}

/// Check that the job in `dir` was exported for this model (K and M) and covers this request
/// (`want`: the job an export with these options would write); returns the job's own target
/// and shift, and notes.
pub(super) fn check_job(sys: &System, params: &ModalParams, want: &Job, dir: &Path) -> Result<(Job, Vec<String>)> {
    let path = dir.join("params.json");
    let file: JobFile = serde_json::from_str(&read_text(&path)?).map_err(|e| Error::Input {
        file: path.display().to_string(),
        line: Some(e.line()),
        key: None,
        msg: e.to_string(),
    })?;
    let notes = check_model(sys, &file.model, dir)?;
    // A job not run yet says so before anything about the request.
    regular_len(&dir.join("slepc.json"))?;
    let target = match (file.nev, file.band) {
        (Some(nev), None) => JobTarget::Nearest(nev),
        (None, Some([l, h])) => JobTarget::Band(l, h),
        _ => {
            return Err(Error::key(
                path.display().to_string(),
                None,
                "nev",
                "give 'nev' (modes nearest sigma) or 'band' (every mode in [lo, hi]), one of them",
            ));
        }
    };
    let job = Job {
        target,
        sigma: file.sigma,
    };
    check_request(params, want, &job, dir)?;
    Ok((job, notes))
}

/// The model of the results against this one: K, then M (density, lumped mass, point masses).
fn check_model(sys: &System, have: &serde_json::Value, dir: &Path) -> Result<Vec<String>> {
    let want = fingerprint(sys)?;
    // Sums to rounding, counts and names exactly.
    let same = |key: &str| match (&have[key], &want[key]) {
        (a, b) if a.is_f64() || b.is_f64() => matches!((a.as_f64(), b.as_f64()), (Some(a), Some(b)) if close(a, b)),
        (a, b) => a == b,
    };
    let another = |what: &str| {
        Error::option(
            "--slepc-import",
            format!(
                "{}: these results were computed for another model (exported: {} DOFs, {} entries in K, {} mass; \
                 this model: {} DOFs, {} entries, {} mass; {what}): give the mesh and model options of the export",
                dir.display(),
                have["n"],
                have["nnz"],
                have["mass_matrix"].as_str().unwrap_or("?"),
                want["n"],
                want["nnz"],
                want["mass_matrix"].as_str().unwrap_or("?"),
            ),
        )
    };
    if !(same("n") && same("nnz") && same("abs_sum")) {
        return Err(another(
            "another K: mesh, supports, couplings, materials or parts differ",
        ));
    }
    if have.get("m_abs_sum").is_none() {
        return Ok(vec![format!(
            "{}: exported by an earlier vibrofem, without the fingerprint of M: the model's M is checked by the \
             residuals only",
            dir.display()
        )]);
    }
    if !(same("m_nnz") && same("m_abs_sum") && same("m_diag_sum") && same("mass_matrix")) {
        return Err(another(
            "the same K with another M: density, --mass or point masses differ",
        ));
    }
    Ok(Vec::new())
}

/// The request against the job: the modes asked for must be among those computed, about the
/// same shift. Errors name the option to change.
fn check_request(params: &ModalParams, want: &Job, job: &Job, dir: &Path) -> Result<()> {
    let d = dir.display();
    match (want.target, job.target) {
        (JobTarget::Nearest(n), JobTarget::Nearest(have)) if n > have => {
            return Err(Error::option(
                "--modes",
                format!(
                    "--modes {n}: the job in {d} computed {have} modes (exported with --modes {have}); ask for at \
                     most {have}, or export and run the job again"
                ),
            ));
        }
        (JobTarget::Band(l, h), JobTarget::Band(jl, jh))
            if !(jl <= l || close(jl, l)) || !(h <= jh || close(h, jh)) =>
        {
            return Err(Error::option(
                "--band",
                format!(
                    "--band: [{}, {}] Hz is not inside the band of the job in {d}, [{}, {}] Hz; ask for a band \
                     inside it, or export and run the job again",
                    hz_of(l),
                    hz_of(h),
                    hz_of(jl),
                    hz_of(jh)
                ),
            ));
        }
        (JobTarget::Nearest(_), JobTarget::Band(jl, jh)) => {
            return Err(Error::option(
                "--band",
                format!(
                    "the job in {d} computed every mode in [{}, {}] Hz: give --band with that band (or one inside it)",
                    hz_of(jl),
                    hz_of(jh)
                ),
            ));
        }
        (JobTarget::Band(..), JobTarget::Nearest(have)) => {
            return Err(Error::option(
                "--band",
                format!(
                    "--band: the job in {d} computed the {have} modes nearest its shift, not a band: give \
                     --modes {have} (or fewer)"
                ),
            ));
        }
        _ => {}
    }
    // The modes nearest a shift depend on it; a band's shift only places the factorisation.
    let shift_matters = matches!(job.target, JobTarget::Nearest(_)) || params.shift_hz.is_some();
    if shift_matters && !close(want.sigma, job.sigma) {
        return Err(Error::option(
            "--shift",
            format!(
                "--shift: the job in {d} was computed about σ = {:.6e} rad²/s² ({} Hz), this run asks about \
                 σ = {:.6e} ({} Hz{}): give the --shift of the export",
                job.sigma,
                hz_of(job.sigma),
                want.sigma,
                hz_of(want.sigma),
                if params.shift_hz.is_none() { ", the default" } else { "" }
            ),
        ));
    }
    Ok(())
}

/// The pairs of the job to keep (ascending λ): the nearest σ, or those in the band.
fn select(lam: &[f64], info: &SlepcOut, job: &Job, want: &Job) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..lam.len()).collect();
    match (want.target, job.target) {
        (JobTarget::Nearest(nm), _) => {
            // The script kept the nearest to σ already; this takes the asked ones of them.
            idx.sort_by(|&a, &b| (lam[a] - job.sigma).abs().total_cmp(&(lam[b] - job.sigma).abs()));
            idx.truncate(nm);
        }
        (JobTarget::Band(l, h), JobTarget::Band(jl, jh)) if close(l, jl) && close(h, jh) => {
            idx.retain(|&i| lam[i] > info.lower.0 && lam[i] <= info.upper.0);
        }
        (JobTarget::Band(l, h), _) => idx.retain(|&i| lam[i] >= l && lam[i] <= h),
    }
    idx.sort_by(|&a, &b| lam[a].total_cmp(&lam[b]));
    idx
}

/// The pairs `idx` (of `n` entries each in `x`), M-normalised here (SLEPc's B-normalisation,
/// re-done in our arithmetic).
pub(super) fn normalised(m: &SymMatrix, lam: &[f64], x: &[f64], n: usize, idx: &[usize]) -> (Vec<f64>, Mat<f64>) {
    let mut out = Mat::zeros(n, idx.len());
    let mut lambda = Vec::with_capacity(idx.len());
    for (c, &i) in idx.iter().enumerate() {
        let col = &x[i * n..(i + 1) * n];
        let mx = m.mul_vec(col);
        let s = col.iter().zip(&mx).map(|(a, b)| a * b).sum::<f64>().sqrt();
        let s = if s > 0.0 { 1.0 / s } else { 1.0 };
        for r in 0..n {
            out[(r, c)] = col[r] * s;
        }
        lambda.push(lam[i]);
    }
    (lambda, out)
}

/// The job's Sturm check for the pairs kept, with notes. Completeness of the kept pairs when
/// the job holds more: every pair of the job verified, the count matching, and (for the modes
/// nearest σ) the kept ones' distance to σ inside the counted range on both sides.
fn sturm_check(
    sys: &System,
    (lam, x): (&[f64], &[f64]),
    info: &SlepcOut,
    (job, want): (&Job, &Job),
    kept: &[f64],
) -> Result<(SturmCheck, Vec<String>)> {
    let in_range = |l: &&f64| **l > info.lower.0 && **l < info.upper.0;
    let expected = info.upper.1.saturating_sub(info.lower.1);
    let mut notes = Vec::new();
    let (found, mut complete) = if kept.len() == lam.len() {
        let found = kept.iter().filter(in_range).count();
        (found, expected == found)
    } else {
        let found = lam.iter().filter(in_range).count();
        let (all, xs) = normalised(sys.m()?, lam, x, sys.n_free(), &(0..lam.len()).collect::<Vec<_>>());
        let (_, orth, back) = eigen::verify_with_backward_errors(sys.k(), sys.m()?, &all, xs.as_ref(), job.sigma);
        let worst = back.iter().fold(0.0, |a, &b| max_nan(a, b));
        let verified = worst <= EigenParams::default().verify_tol && orth <= 1e-8;
        let covered = match want.target {
            JobTarget::Nearest(_) => {
                let d = kept.iter().fold(0.0, |a, &l| max_nan(a, (l - job.sigma).abs()));
                (info.lower.1 == 0 || info.lower.0 < job.sigma - d) && job.sigma + d < info.upper.0
            }
            JobTarget::Band(..) => true,
        };
        notes.push(format!(
            "the SLEPc job holds {} eigenpairs, {} of them asked for: all verified here (largest backward error \
             {worst:.1e}, M-orthonormality {orth:.1e}), {found} between the Sturm points where {expected} are counted{}",
            lam.len(),
            kept.len(),
            if covered { "" } else { "; the asked ones reach beyond the counted range" }
        ));
        (found, expected == found && verified && covered)
    };
    if let JobTarget::Nearest(nm) = want.target {
        if kept.len() < nm {
            complete = false;
            notes.push(format!(
                "the SLEPc job holds {} eigenpairs, {nm} asked: not complete (SLEPc converged fewer; run the job \
                 again, with more iterations)",
                kept.len()
            ));
        }
    }
    let sturm = SturmCheck {
        lower: info.lower,
        upper: info.upper,
        expected,
        found,
        complete,
    };
    Ok((sturm, notes))
}

/// Refuse a non-finite eigenvalue or vector entry, naming the file, the pair and the row.
pub(super) fn check_finite(lam: &[f64], x: &[f64], n: usize, dir: &Path) -> Result<()> {
    if let Some(i) = lam.iter().position(|v| !v.is_finite()) {
        return Err(engine_err(format!(
            "{}: the eigenvalue of pair {} is {}: the SLEPc run failed (run the job again)",
            dir.join("lambda.bin").display(),
            i + 1,
            lam[i]
        )));
    }
    if let Some(q) = x.iter().position(|v| !v.is_finite()) {
        return Err(engine_err(format!(
            "{}: pair {} holds {} in row {}: the SLEPc run failed (run the job again)",
            dir.join("vectors.bin").display(),
            q / n.max(1) + 1,
            x[q],
            q % n.max(1)
        )));
    }
    Ok(())
}

/// The results of the job in `dir` (computed for `job`, `want` asked), verified here: the
/// eigen solution and the script's timings (s, by phase).
pub(super) fn load(
    sys: &System,
    dir: &Path,
    (job, want): (&Job, &Job),
    mut notes: Vec<String>,
) -> Result<(EigenSolution, BTreeMap<String, f64>)> {
    let info_path = dir.join("slepc.json");
    let info: SlepcOut = serde_json::from_str(&read_text(&info_path)?)
        .map_err(|e| engine_err(format!("{}: {e}", info_path.display())))?;
    let n = sys.n_free();
    if info.n != n {
        return Err(engine_err(format!(
            "SLEPc solved a problem of size {} for a model of {n} DOFs",
            info.n
        )));
    }
    let lam_all = read_f64s(
        &dir.join("lambda.bin"),
        Some(info.nconv),
        &format!("{} eigenvalues", info.nconv),
    )?;
    let x_all = read_f64s(
        &dir.join("vectors.bin"),
        info.nconv.checked_mul(n),
        &format!("{} vectors of {n} entries", info.nconv),
    )?;
    check_finite(&lam_all, &x_all, n, dir)?;

    let tv = Instant::now();
    let idx = select(&lam_all, &info, job, want);
    let (k, m) = (sys.k(), sys.m()?);
    let (mut lambda, mut x) = normalised(m, &lam_all, &x_all, n, &idx);
    // SLEPc's rigid-body pairs (not deflated) reported as the direct path reports them, at λ = 0.
    let cand = crate::analysis::modal::rigid_candidates(sys.model());
    eigen::canonical_null_pairs(k, m, &cand, &mut lambda, &mut x);
    let (rel_residual, m_orth, backward_error) =
        eigen::verify_with_backward_errors(k, m, &lambda, x.as_ref(), job.sigma);
    let (sturm, more) = sturm_check(sys, (&lam_all, &x_all), &info, (job, want), &lambda)?;
    notes.push(format!(
        "solved by SLEPc {} (Krylov–Schur, shift-and-invert at σ = {:.4e} rad²/s², MUMPS LDLᵀ) on {} MPI ranks \
         in {} restarts ({} pairs converged, {} kept, refined by {} inverse iteration(s) with Rayleigh–Ritz); \
         residuals, backward errors and M-orthonormality recomputed here; \
         completeness from the inertia of MUMPS factorisations of K − sM at s = {:.6e} and {:.6e} (Sturm counts {} and {})",
        info.slepc,
        info.sigma,
        info.ranks,
        info.iterations,
        info.converged,
        info.nconv,
        info.timings_s.get("refinements").copied().unwrap_or(0.0),
        info.lower.0,
        info.upper.0,
        info.lower.1,
        info.upper.1
    ));
    notes.extend(more);
    let time_verify = tv.elapsed().as_secs_f64();
    let sol = EigenSolution {
        lambda,
        vectors: x,
        rel_residual,
        backward_error,
        notes,
        m_orthonormality: m_orth,
        sturm,
        shift: job.sigma,
        applications: 0,
        // The shift factorisation and the Sturm factorisation at the upper end (the lower one
        // is a second factorisation unless SLEPc's shift is the lower point).
        factorizations: 3,
        time_factor: 0.0,
        time_iterate: info.timings_s.get("solve").copied().unwrap_or(0.0),
        time_verify: time_verify + info.timings_s.get("sturm").copied().unwrap_or(0.0),
        // MUMPS's factorisations are not probed here; the recomputed backward errors are the check.
        factor_backward_error: 0.0,
        memory: Default::default(),
    };
    Ok((sol, info.timings_s))
}
