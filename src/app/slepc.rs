//! The SLEPc engine: `vibrofem modes --engine slepc --ranks N`.
//!
//! vibrofem assembles K and M, writes them in PETSc's binary format with `params.json` into a
//! work folder, and runs `mpirun -n N python3 slepc_modes.py DIR` (the script is built into
//! the binary and written beside the matrices): SLEPc's Krylov–Schur with shift-and-invert on a
//! MUMPS LDLᵀ factorisation, then MUMPS inertias of K − sM at both ends of the range found
//! (Sturm counts). vibrofem reads the eigenpairs back and post-processes them as a native run:
//! it recomputes every residual and backward error with its own K and M, the M-orthonormality,
//! participation and shapes, and takes completeness from the MUMPS Sturm counts.
//!
//! SLEPc, PETSc and MUMPS come from Debian's `python3-slepc4py`, mpirun from `openmpi-bin`
//! (`bash validation/setup_slepc.sh` installs them). The Debian build needs `PETSC_DIR` and
//! `SLEPC_DIR`; they default to Debian's paths when unset.

use crate::analysis::modal::{self, ModalParams, ModalRun, ModalTarget, Timings};
use crate::io::matrix;
use crate::linalg::eigen::{self, EigenParams, EigenSolution, SturmCheck};
use crate::post::modal::lambda_of_hz;
use crate::system::System;
use crate::{Error, Result};
use faer::Mat;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// The script run under MPI.
pub const SCRIPT: &str = include_str!("slepc_modes.py");

/// Debian's PETSc and SLEPc installations (python3-slepc4py).
pub const DEBIAN_PETSC_DIR: &str = "/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real";
/// See [`DEBIAN_PETSC_DIR`].
pub const DEBIAN_SLEPC_DIR: &str = "/usr/lib/slepcdir/slepc3.18/x86_64-linux-gnu-real";

const ENGINE: &str = "SLEPc engine";
const INSTALL: &str = "install Debian's python3-slepc4py and openmpi-bin (as root: `bash validation/setup_slepc.sh`)";

/// How to run SLEPc.
#[derive(Clone, Debug)]
pub struct SlepcOptions {
    /// MPI ranks.
    pub ranks: usize,
    /// Python with slepc4py (default: `$VIBROFEM_SLEPC_PYTHON`, else `/usr/bin/python3`,
    /// Debian's, which sees the Debian packages).
    pub python: Option<String>,
    /// mpirun (default: `$VIBROFEM_MPIRUN`, else `mpirun` on the PATH).
    pub mpirun: Option<String>,
    /// Keep the work folder here (default: a temporary folder, removed after the run).
    pub workdir: Option<PathBuf>,
    /// Read the results of a job run elsewhere (e.g. on a cluster) from this folder, written by
    /// `vibrofem export` and completed by `slepc_modes.py`, instead of running one.
    pub import: Option<PathBuf>,
}

impl Default for SlepcOptions {
    fn default() -> Self {
        SlepcOptions {
            ranks: 1,
            python: None,
            mpirun: None,
            workdir: None,
            import: None,
        }
    }
}

fn engine_err(msg: impl Into<String>) -> Error {
    Error::Engine {
        engine: ENGINE.into(),
        msg: msg.into(),
    }
}

fn python(o: &SlepcOptions) -> String {
    o.python
        .clone()
        .or_else(|| std::env::var("VIBROFEM_SLEPC_PYTHON").ok())
        .unwrap_or_else(|| "/usr/bin/python3".into())
}

fn mpirun(o: &SlepcOptions) -> String {
    o.mpirun
        .clone()
        .or_else(|| std::env::var("VIBROFEM_MPIRUN").ok())
        .unwrap_or_else(|| "mpirun".into())
}

/// PETSC_DIR and SLEPC_DIR as set, or Debian's when unset.
fn petsc_env(cmd: &mut Command) {
    if std::env::var_os("PETSC_DIR").is_none() {
        cmd.env("PETSC_DIR", DEBIAN_PETSC_DIR);
    }
    if std::env::var_os("SLEPC_DIR").is_none() {
        cmd.env("SLEPC_DIR", DEBIAN_SLEPC_DIR);
    }
}

fn is_root() -> bool {
    // The effective uid from /proc (no libc call needed): Open MPI refuses root unless told.
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("Uid:"))
                .and_then(|l| l.split_whitespace().nth(2).map(|u| u == "0"))
        })
        .unwrap_or(false)
}

/// Check that Python imports slepc4py and that mpirun runs, quickly, with the remedy in the
/// error (never a hang: both commands return at once when the packages are missing).
pub fn check_available(o: &SlepcOptions) -> Result<String> {
    let py = python(o);
    let mut c = Command::new(&py);
    c.args([
        "-c",
        "import numpy, petsc4py, slepc4py; print('slepc4py', slepc4py.__version__, 'petsc4py', petsc4py.__version__)",
    ]);
    petsc_env(&mut c);
    let out = c
        .output()
        .map_err(|e| engine_err(format!("cannot run {py} ({e}); {INSTALL}")))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let last = err.lines().last().unwrap_or("").trim();
        return Err(engine_err(format!("{py} cannot import slepc4py ({last}); {INSTALL}")));
    }
    let versions = String::from_utf8_lossy(&out.stdout).trim().to_string();
    let mpi = mpirun(o);
    let v = Command::new(&mpi)
        .arg("--version")
        .output()
        .map_err(|e| engine_err(format!("cannot run {mpi} ({e}); {INSTALL}")))?;
    if !v.status.success() {
        return Err(engine_err(format!("{mpi} --version failed; {INSTALL}")));
    }
    let mpi_version = String::from_utf8_lossy(&v.stdout)
        .lines()
        .next()
        .unwrap_or("")
        .trim()
        .to_string();
    Ok(format!("{versions}, {mpi_version}"))
}

/// A work folder that removes itself unless the user asked to keep it.
struct WorkDir {
    path: PathBuf,
    remove: bool,
}

impl Drop for WorkDir {
    fn drop(&mut self) {
        if self.remove {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

fn workdir(o: &SlepcOptions) -> Result<WorkDir> {
    let (path, remove) = match &o.workdir {
        Some(p) => (p.clone(), false),
        None => {
            let stamp = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos());
            (
                std::env::temp_dir().join(format!("vibrofem-slepc-{}-{stamp}", std::process::id())),
                true,
            )
        }
    };
    std::fs::create_dir_all(&path).map_err(|e| Error::io(&path, e))?;
    Ok(WorkDir { path, remove })
}

/// A fingerprint of K (size, entries, Σ|Kij|) that ties SLEPc results to the model they were
/// computed for: importing them for other model options is refused.
fn fingerprint(sys: &System) -> serde_json::Value {
    let k = sys.k();
    let sum: f64 = k.values.iter().map(|v| v.abs()).sum();
    serde_json::json!({ "n": sys.n_free(), "nnz": k.pattern.nnz(), "abs_sum": sum })
}

/// Write the SLEPc job for `sys` into `dir` — `params.json` (what to compute, σ, the model's
/// fingerprint) and the script `slepc_modes.py` — beside K and M in PETSc format (written here
/// when `matrices`). σ and the target follow the native solver's conventions. Returns σ.
pub fn write_job(sys: &System, params: &ModalParams, dir: &Path, matrices: bool) -> Result<f64> {
    let k = sys.k();
    let m = sys.m()?;
    if matrices {
        matrix::write_petsc(&dir.join("K.petsc"), k)?;
        // On K's pattern: the script forms K − sM with PETSc's SAME_NONZERO_PATTERN.
        matrix::write_petsc(&dir.join("M.petsc"), &m.on_pattern(k.pattern.clone()))?;
    }
    let sigma = match (params.shift_hz, params.target) {
        (Some(f), _) => lambda_of_hz(f),
        (None, ModalTarget::Band(lo, _)) if lo > 0.0 => lambda_of_hz(lo) * (1.0 - 1e-9),
        _ => eigen::default_shift(k, m),
    };
    if !sigma.is_finite() {
        return Err(Error::InvalidInput(format!(
            "--shift: {:?} Hz is not a usable frequency",
            params.shift_hz
        )));
    }
    let n = sys.n_free();
    let mut p = match params.target {
        ModalTarget::Modes(nm) => serde_json::json!({ "nev": nm.min(n), "sigma": sigma, "tol": 1e-12 }),
        ModalTarget::Band(lo, hi) => {
            if !(lo < hi) {
                return Err(Error::InvalidInput(format!(
                    "--band: lower frequency {lo} must be below the upper {hi}"
                )));
            }
            let (l, h) = (lambda_of_hz(lo), lambda_of_hz(hi));
            // A band from 0 includes the rigid-body modes, which round to either side of 0.
            let l = if lo <= 0.0 { sigma.min(-1e-9 * h.abs()) } else { l };
            serde_json::json!({ "band": [l, h], "sigma": sigma, "tol": 1e-12 })
        }
    };
    p["model"] = fingerprint(sys);
    let path = dir.join("params.json");
    std::fs::write(
        &path,
        serde_json::to_string_pretty(&p).map_err(|e| Error::output(path.display(), e))?,
    )
    .map_err(|e| Error::io(&path, e))?;
    let script = dir.join("slepc_modes.py");
    std::fs::write(&script, SCRIPT).map_err(|e| Error::io(&script, e))?;
    Ok(sigma)
}

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
    timings_s: std::collections::BTreeMap<String, f64>,
    slepc: String,
}

/// Run the job in `dir` under mpirun (Open MPI's flags only for Open MPI's launchers).
fn run_mpi(o: &SlepcOptions, dir: &Path, versions: &str) -> Result<()> {
    let mpi = mpirun(o);
    let mut c = Command::new(&mpi);
    let open_mpi = matches!(
        Path::new(&mpi).file_name().and_then(|f| f.to_str()),
        Some("mpirun" | "mpiexec" | "orterun")
    );
    if open_mpi && is_root() {
        c.arg("--allow-run-as-root");
    }
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    if open_mpi && o.ranks > cores {
        c.arg("--oversubscribe");
    }
    c.args(["-n", &o.ranks.to_string(), &python(o)])
        .arg(dir.join("slepc_modes.py"))
        .arg(dir)
        // One thread per rank: the ranks are the parallelism.
        .env("OMP_NUM_THREADS", "1")
        .env("OPENBLAS_NUM_THREADS", "1");
    petsc_env(&mut c);
    log::info!("{ENGINE}: {versions}; running {c:?}");
    let out = c
        .output()
        .map_err(|e| engine_err(format!("cannot run {mpi} ({e}); {INSTALL}")))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let tail: Vec<&str> = err.lines().rev().take(12).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        return Err(engine_err(format!(
            "{mpi} -n {} exited with {} (work folder {}):\n{}",
            o.ranks,
            out.status,
            dir.display(),
            tail.join("\n")
        )));
    }
    Ok(())
}

/// The shift of the job in `dir`, after checking that it was exported from this very model
/// (same K: size, entries and Σ|Kij| to rounding).
fn check_import(sys: &System, dir: &Path) -> Result<f64> {
    let path = dir.join("params.json");
    let p: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?)
        .map_err(|e| Error::InvalidInput(format!("{}: {e}", path.display())))?;
    let want = fingerprint(sys);
    let have = &p["model"];
    let same = have["n"] == want["n"]
        && have["nnz"] == want["nnz"]
        && match (have["abs_sum"].as_f64(), want["abs_sum"].as_f64()) {
            (Some(a), Some(b)) => (a - b).abs() <= 1e-12 * b.abs(),
            _ => false,
        };
    if !same {
        return Err(Error::InvalidInput(format!(
            "{}: these results were computed for another model (exported: {} DOFs, {} entries; this model: {} DOFs, {} entries, or other values): give the mesh and model options of the export",
            dir.display(),
            have["n"],
            have["nnz"],
            want["n"],
            want["nnz"]
        )));
    }
    p["sigma"]
        .as_f64()
        .ok_or_else(|| Error::InvalidInput(format!("{}: no 'sigma'", path.display())))
}

/// Solve the modal problem of `sys` with SLEPc under MPI and verify it here.
pub fn solve(sys: &System, params: &ModalParams, o: &SlepcOptions) -> Result<ModalRun> {
    let t_all = Instant::now();
    if o.ranks == 0 {
        return Err(Error::InvalidInput("--ranks must be at least 1".into()));
    }
    // Either run the job here under mpirun, or import the results of one run elsewhere (a
    // cluster) from the folder `vibrofem export` wrote.
    let (wd, sigma, t_export, t_slepc) = match &o.import {
        Some(dir) => {
            let sigma = check_import(sys, dir)?;
            (
                WorkDir {
                    path: dir.clone(),
                    remove: false,
                },
                sigma,
                0.0,
                0.0,
            )
        }
        None => {
            let versions = check_available(o)?;
            let wd = workdir(o)?;
            let t = Instant::now();
            let sigma = write_job(sys, params, &wd.path, true)?;
            let t_export = t.elapsed().as_secs_f64();
            let t = Instant::now();
            run_mpi(o, &wd.path, &versions)?;
            (wd, sigma, t_export, t.elapsed().as_secs_f64())
        }
    };
    let dir = &wd.path;
    let info_path = dir.join("slepc.json");
    let info: SlepcOut =
        serde_json::from_str(&std::fs::read_to_string(&info_path).map_err(|e| Error::io(&info_path, e))?)
            .map_err(|e| engine_err(format!("{}: {e}", info_path.display())))?;
    let n = sys.n_free();
    if info.n != n {
        return Err(engine_err(format!(
            "SLEPc solved a problem of size {} for a model of {n} DOFs",
            info.n
        )));
    }
    let lam_all = matrix::read_f64_le(&dir.join("lambda.bin"))?;
    let x_all = matrix::read_f64_le(&dir.join("vectors.bin"))?;
    if lam_all.len() != info.nconv || x_all.len() != n * info.nconv {
        return Err(engine_err(format!(
            "expected {} eigenpairs of size {n} in {}, found {} values and {} vector entries",
            info.nconv,
            dir.display(),
            lam_all.len(),
            x_all.len()
        )));
    }

    // Keep what was asked for, ascending: the nearest to σ, or the band.
    let tv = Instant::now();
    let mut idx: Vec<usize> = (0..info.nconv).collect();
    match params.target {
        ModalTarget::Modes(nm) => {
            // The script kept the nearest to σ already; this guards the count.
            idx.sort_by(|&a, &b| (lam_all[a] - sigma).abs().total_cmp(&(lam_all[b] - sigma).abs()));
            idx.truncate(nm.min(n));
        }
        ModalTarget::Band(..) => {
            idx.retain(|&i| lam_all[i] > info.lower.0 && lam_all[i] <= info.upper.0);
        }
    }
    idx.sort_by(|&a, &b| lam_all[a].total_cmp(&lam_all[b]));
    let k = sys.k();
    let m = sys.m()?;
    let mut x = Mat::zeros(n, idx.len());
    let mut lambda = Vec::with_capacity(idx.len());
    for (c, &i) in idx.iter().enumerate() {
        let col = &x_all[i * n..(i + 1) * n];
        // M-normalise here (SLEPc's B-normalisation, re-done in our arithmetic).
        let mx = m.mul_vec(col);
        let s = col.iter().zip(&mx).map(|(a, b)| a * b).sum::<f64>().sqrt();
        let s = if s > 0.0 { 1.0 / s } else { 1.0 };
        for r in 0..n {
            x[(r, c)] = col[r] * s;
        }
        lambda.push(lam_all[i]);
    }
    let (rel_residual, m_orth, backward_error) = eigen::verify_with_backward_errors(k, m, &lambda, x.as_ref(), sigma);
    let found = lambda.iter().filter(|&&l| l > info.lower.0 && l < info.upper.0).count();
    let expected = info.upper.1.saturating_sub(info.lower.1);
    let sturm = SturmCheck {
        lower: info.lower,
        upper: info.upper,
        expected,
        found,
        complete: expected == found,
    };
    let time_verify = tv.elapsed().as_secs_f64();
    let sol = EigenSolution {
        lambda,
        vectors: x,
        rel_residual,
        backward_error,
        notes: vec![format!(
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
        )],
        m_orthonormality: m_orth,
        sturm,
        shift: sigma,
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
    let ts = |k: &str| info.timings_s.get(k).copied().unwrap_or(0.0);
    let tm = Timings {
        assemble: sys.timings.assemble + t_export,
        order: sys.timings.order,
        // Loading, factorising at σ and iterating happen inside SLEPc's solve: reported as
        // "solve"; MPI start-up and the transfer of the vectors as "post".
        solve: ts("load") + ts("solve"),
        verify: sol.time_verify,
        post: (t_slepc - ts("load") - ts("solve") - ts("sturm")).max(0.0),
        ..Default::default()
    };
    log::info!("{ENGINE}: mpirun took {t_slepc:.2} s");
    let post_engine = tm.post;
    let mut run = modal::finish(sys, sol, tm, t_all, EigenParams::default().verify_tol)?;
    run.report.timings_s.post += post_engine;
    run.report.timings_s.total = t_all.elapsed().as_secs_f64() + sys.timings.wall;
    Ok(run)
}
