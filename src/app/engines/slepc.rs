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
//! A job run elsewhere (`vibrofem export`, then the script on a cluster) is imported the same
//! way (`--slepc-import DIR`), after checking that it was computed for this model (K and M) and
//! for this request (the modes asked for lie among those computed).
//!
//! SLEPc, PETSc and MUMPS come from Debian's `python3-slepc4py`, mpirun from `openmpi-bin`
//! (`bash validation/setup_slepc.sh` installs them). The Debian build needs `PETSC_DIR` and
//! `SLEPC_DIR`; they default to Debian's paths when unset.

use super::job::{ENGINE, Job, JobTarget, engine_err, fingerprint};
use super::results;
use crate::analysis::modal::{self, ModalParams, ModalRun, ModalTarget, Timings};
use crate::io::matrix;
use crate::linalg::eigen::{self, EigenParams};
use crate::post::modal::lambda_of_hz;
use crate::system::System;
use crate::{Error, Result};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// The script run under MPI.
pub const SCRIPT: &str = include_str!("slepc_modes.py");

/// Debian's PETSc and SLEPc installations (python3-slepc4py).
pub const DEBIAN_PETSC_DIR: &str = "/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real";
/// See [`DEBIAN_PETSC_DIR`].
pub const DEBIAN_SLEPC_DIR: &str = "/usr/lib/slepcdir/slepc3.18/x86_64-linux-gnu-real";

pub(super) const INSTALL: &str =
    "install Debian's python3-slepc4py and openmpi-bin (as root: `bash validation/setup_slepc.sh`)";

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

pub(super) fn python(o: &SlepcOptions) -> String {
    o.python
        .clone()
        .or_else(|| std::env::var("VIBROFEM_SLEPC_PYTHON").ok())
        .unwrap_or_else(|| "/usr/bin/python3".into())
}

pub(super) fn mpirun(o: &SlepcOptions) -> String {
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
pub(super) struct WorkDir {
    pub(super) path: PathBuf,
    remove: bool,
}

impl Drop for WorkDir {
    fn drop(&mut self) {
        if self.remove {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

pub(super) fn workdir(o: &SlepcOptions) -> Result<WorkDir> {
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
    crate::io::create_dir(&path)?;
    Ok(WorkDir { path, remove })
}

/// The SLEPc job of a request on `sys`: σ and the target follow the native solver's
/// conventions (the default shift below the spectrum; a band's lower end).
pub(super) fn job_of(sys: &System, params: &ModalParams) -> Result<Job> {
    crate::analysis::modal::check_params(params)?;
    let k = sys.k();
    let m = sys.m()?;
    let sigma = match (params.shift_hz, params.target) {
        (Some(f), _) => lambda_of_hz(f),
        (None, ModalTarget::Band(lo, _)) if lo > 0.0 => lambda_of_hz(lo) * (1.0 - 1e-9),
        _ => eigen::default_shift(k, m),
    };
    if !sigma.is_finite() {
        return Err(Error::option(
            "--shift",
            format!("--shift: {:?} Hz is not a usable frequency", params.shift_hz),
        ));
    }
    let target = match params.target {
        ModalTarget::Modes(nm) => JobTarget::Nearest(nm.min(sys.n_free())),
        ModalTarget::Band(lo, hi) => {
            let (l, h) = (lambda_of_hz(lo), lambda_of_hz(hi));
            // A band from 0 includes the rigid-body modes, which round to either side of 0.
            let l = if lo <= 0.0 { sigma.min(-1e-9 * h.abs()) } else { l };
            JobTarget::Band(l, h)
        }
    };
    Ok(Job { target, sigma })
}

/// Write the SLEPc job for `sys` into `dir` — `params.json` (what to compute, σ, the model's
/// fingerprint) and the script `slepc_modes.py` — beside K and M in PETSc format (written here
/// when `matrices`). σ and the target follow the native solver's conventions. Returns σ.
pub fn write_job(sys: &System, params: &ModalParams, dir: &Path, matrices: bool) -> Result<f64> {
    let job = job_of(sys, params)?;
    if matrices {
        let k = sys.k();
        matrix::write_petsc(&dir.join("K.petsc"), k)?;
        // On K's pattern: the script forms K − sM with PETSc's SAME_NONZERO_PATTERN.
        matrix::write_petsc(&dir.join("M.petsc"), &sys.m()?.on_pattern(k.pattern.clone()))?;
    }
    let mut p = match job.target {
        JobTarget::Nearest(nev) => serde_json::json!({ "nev": nev, "sigma": job.sigma, "tol": 1e-12 }),
        JobTarget::Band(l, h) => serde_json::json!({ "band": [l, h], "sigma": job.sigma, "tol": 1e-12 }),
    };
    p["model"] = fingerprint(sys)?;
    let path = dir.join("params.json");
    std::fs::write(
        &path,
        serde_json::to_string_pretty(&p).map_err(|e| Error::output(path.display(), e))?,
    )
    .map_err(|e| Error::io(&path, e))?;
    let script = dir.join("slepc_modes.py");
    std::fs::write(&script, SCRIPT).map_err(|e| Error::io(&script, e))?;
    Ok(job.sigma)
}

/// Run the job in `dir` (its script `script`, a file in `dir` unless a path is given) under
/// mpirun (Open MPI's flags only for Open MPI's launchers).
pub(super) fn run_mpi(o: &SlepcOptions, dir: &Path, script: &Path, versions: &str) -> Result<()> {
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
        .arg(dir.join(script))
        .arg(dir)
        // One thread per rank: the ranks are the parallelism.
        .env("OMP_NUM_THREADS", "1")
        .env("OPENBLAS_NUM_THREADS", "1");
    petsc_env(&mut c);
    log::info!("{ENGINE}: {versions}; running {c:?}");
    let mut child = c
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| engine_err(format!("cannot run {mpi} ({e}); {INSTALL}")))?;
    // The job's stderr as it comes: its `progress: …` lines are shown with the elapsed time (a
    // long low-memory run reports its phases and iterations), the last other lines are kept for
    // an error.
    let t0 = Instant::now();
    let mut tail = std::collections::VecDeque::new();
    if let Some(err) = child.stderr.take() {
        for line in BufReader::new(err).lines().map_while(std::io::Result::ok) {
            if let Some(msg) = line.strip_prefix("progress: ") {
                eprintln!("[{:6.1} s] {msg}", t0.elapsed().as_secs_f64());
                continue;
            }
            tail.push_back(line);
            if tail.len() > 12 {
                tail.pop_front();
            }
        }
    }
    let status = child
        .wait()
        .map_err(|e| engine_err(format!("{mpi} -n {}: {e}", o.ranks)))?;
    if !status.success() {
        return Err(engine_err(format!(
            "{mpi} -n {} exited with {status} (work folder {}):\n{}",
            o.ranks,
            dir.display(),
            Vec::from(tail).join("\n")
        )));
    }
    Ok(())
}

/// Solve the modal problem of `sys` with SLEPc under MPI (or import the results of a job run
/// elsewhere) and verify it here.
pub fn solve(sys: &System, params: &ModalParams, o: &SlepcOptions) -> Result<ModalRun> {
    let t_all = Instant::now();
    if o.ranks == 0 {
        return Err(Error::option("--ranks", "--ranks must be at least 1"));
    }
    let want = job_of(sys, params)?;
    // Either run the job here under mpirun, or import the results of one run elsewhere (a
    // cluster) from the folder `vibrofem export` wrote.
    let (wd, (job, notes), t_export, t_slepc) = match &o.import {
        Some(dir) => {
            let job = results::check_job(sys, params, &want, dir)?;
            let wd = WorkDir {
                path: dir.clone(),
                remove: false,
            };
            (wd, job, 0.0, 0.0)
        }
        None => {
            let versions = check_available(o)?;
            let wd = workdir(o)?;
            let t = Instant::now();
            write_job(sys, params, &wd.path, true)?;
            let t_export = t.elapsed().as_secs_f64();
            let t = Instant::now();
            run_mpi(o, &wd.path, Path::new("slepc_modes.py"), &versions)?;
            (wd, (want, Vec::new()), t_export, t.elapsed().as_secs_f64())
        }
    };
    let (sol, ts) = results::load(sys, &wd.path, (&job, &want), notes)?;
    let ts = |k: &str| ts.get(k).copied().unwrap_or(0.0);
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
