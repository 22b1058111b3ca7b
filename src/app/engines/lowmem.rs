//! The low-memory modal path: `vibrofem modes --solver iterative` (or `auto` when the in-core
//! factorisation does not fit the memory).
//!
//! vibrofem assembles K and M, writes them with the six rigid-body motions of the free DOFs
//! (`R.bin`) and `params.json` into a work folder, and runs `slepc_lowmem.py` under mpirun on
//! `--ranks` ranks (the folder protocol of docs/lowmem.md): a multigrid-preconditioned
//! eigensolver whose memory grows with the matrices, not with a factor. While the ranks run,
//! this process may drop its own K and M (when the memory is tight) and assemble them again
//! afterwards. The eigenpairs are then verified here exactly as the SLEPc engine's are:
//! residuals, backward errors and M-orthonormality recomputed with vibrofem's own K and M;
//! completeness from the script's Sturm count (MUMPS's inertia of K − sM, out of core) when it
//! ran within the memory budget, otherwise the report says that the count was not verified and
//! why.
//!
//! Rigid-body motions: a translational DOF of a node at x moves by t + ω × (x − x₀), a
//! rotational DOF (shells, beams, reference nodes of couplings) by ω, a warping DOF not at
//! all. Fixed DOFs are eliminated, so on supports these are only candidates: the script keeps
//! the combinations K annihilates (Rayleigh–Ritz, backward error at rounding level) and stops
//! with an error when a zero-energy mode outside their span remains (a mechanism), never with
//! a silent answer.

use super::job::{ENGINE, engine_err};
use super::results;
use super::slepc::{self, SlepcOptions};
use super::{Before, Engine};
use crate::analysis::modal::{self, ModalOptions, ModalRun, ModalTarget, Timings};
use crate::linalg::eigen::{self, EigenParams, EigenSolution, SturmCheck};
use crate::mesh::{CellKind, Mesh};
use crate::model::Model;
use crate::system::{System, memory_budget, peak_memory, resident_memory};
use crate::util::fmt::fmt_bytes;
use crate::util::max_nan;
use crate::{Error, Result};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The script run under MPI.
pub const SCRIPT: &str = include_str!("slepc_lowmem.py");

/// Which solver computes the modes: `--solver direct|iterative|auto`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Solver {
    /// A factorisation of K − σM (the engine's: native or SLEPc + MUMPS); refused when it does
    /// not fit the memory.
    Direct,
    /// The low-memory path (SLEPc, multigrid-preconditioned, under mpirun).
    Iterative,
    /// Direct unless its in-core estimate exceeds `--max-memory` or the memory available,
    /// then iterative with a note.
    #[default]
    Auto,
}

impl Solver {
    /// `direct`, `iterative` or `auto`.
    pub fn parse(s: &str) -> Result<Solver> {
        match s {
            "direct" => Ok(Solver::Direct),
            "iterative" => Ok(Solver::Iterative),
            "auto" => Ok(Solver::Auto),
            _ => Err(Error::option(
                "--solver",
                format!("--solver '{s}': use direct, iterative or auto"),
            )),
        }
    }
}

/// How to run the low-memory path.
#[derive(Clone, Debug, Default)]
pub struct LowMemOptions {
    /// Ranks, python, mpirun and the work folder, as for the SLEPc engine.
    pub slepc: SlepcOptions,
    /// The script's eigensolver (`params.json` key `method`); `None`: the script's default
    /// (or `$VIBROFEM_LOWMEM_METHOD`).
    pub method: Option<String>,
    /// The memory budget, bytes (`--max-memory`); `None`: what the machine has available.
    pub max_memory: Option<u64>,
}

/// What the low-memory path adds to the `--json` report (key `solver`).
#[derive(Clone, Debug, Serialize)]
pub struct LowMemInfo {
    /// `iterative`.
    pub solver: &'static str,
    /// `slepc-lowmem`.
    pub engine: &'static str,
    /// The script's eigensolver.
    pub method: String,
    /// MPI ranks.
    pub ranks: usize,
    /// Why the iterative path was taken (`--solver auto`), if not forced.
    pub reason: Option<String>,
    /// Rigid-body motions the script found and deflated.
    pub rigid: usize,
    /// Whether the Sturm count ran (completeness verified).
    pub sturm_verified: bool,
    /// Why not, when it did not.
    pub sturm_not_verified: Option<String>,
    /// Whether this process dropped K and M while the ranks ran (memory tight).
    pub matrices_dropped: bool,
    /// The memory budget the run planned with, bytes, and where it comes from.
    pub budget_bytes: Option<u64>,
    /// Bytes given to the script for its out-of-core Sturm factorisation.
    pub sturm_budget_bytes: u64,
    /// Memory by phase, MiB.
    pub memory_mib: MemoryMib,
    /// Wall time by phase of the script, s.
    pub script_timings_s: BTreeMap<String, f64>,
}

/// Memory by phase of the low-memory path, MiB.
#[derive(Clone, Debug, Default, Serialize)]
pub struct MemoryMib {
    /// The script's peak resident memory summed over its ranks after each of its phases.
    pub script: BTreeMap<String, f64>,
    /// This process's peak resident memory in each of its phases (`assemble`, `write`,
    /// `wait`: while the ranks ran, `verify`: reassembly if dropped, verification and post).
    pub vibrofem: BTreeMap<String, f64>,
    /// The peak of the whole job: the larger of this process's peaks outside the wait and
    /// its resident memory during the wait plus the script's peak.
    pub total_peak: f64,
}

const MIB: f64 = 1048576.0;

/// Peak resident memory of this process since the last [`reset_peak`], MiB.
fn peak_mib() -> f64 {
    peak_memory().map_or(0.0, |b| b as f64 / MIB)
}

/// Restart the peak resident memory count (Linux: `5` to /proc/self/clear_refs), so each
/// phase's peak is its own. Where it cannot be reset the peaks are cumulative (upper bounds).
fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// The six rigid-body motions of `model`'s free DOFs (6 rows of n, row-major): translations
/// along x, y, z, then rotations about x, y, z through the centroid of the nodes. Translational
/// DOFs take t + ω × (x − x₀), rotational ones ω, warping ones 0.
pub fn rigid_motions(model: &Model) -> Vec<f64> {
    let dofs = &model.dofs;
    let n = dofs.n_free;
    let nodes = &model.nodes;
    let count = nodes.len().max(1) as f64;
    let mut x0 = [0.0; 3];
    for p in nodes.iter() {
        for d in 0..3 {
            x0[d] += p[d] / count;
        }
    }
    let mut r = vec![0.0; 6 * n];
    for eq in 0..n {
        let (a, c) = dofs.node_comp_of(eq);
        let p = nodes.get(a).copied().unwrap_or(x0);
        let d = [p[0] - x0[0], p[1] - x0[1], p[2] - x0[2]];
        match c {
            0..=2 => {
                r[c * n + eq] = 1.0;
                // Rotation about axis k: (e_k × d)_c.
                for k in 0..3 {
                    let mut e = [0.0; 3];
                    e[k] = 1.0;
                    let u = [
                        e[1] * d[2] - e[2] * d[1],
                        e[2] * d[0] - e[0] * d[2],
                        e[0] * d[1] - e[1] * d[0],
                    ];
                    r[(3 + k) * n + eq] = u[c];
                }
            }
            3..=5 => r[c * n + eq] = 1.0,
            _ => {}
        }
    }
    r
}

/// Mid-edge node `4 + k` of a tet10 cell lies on the edge `TET10_EDGES[k]` (gmsh order, as in
/// src/fe/shape.rs).
const TET10_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [2, 3], [1, 3]];

/// For a model of tet10 solids only: per free equation the two equations it is interpolated from
/// on the P1 space of the same mesh (`2n` entries): its own twice at a vertex DOF, the same
/// component of the edge's two end nodes at a mid-edge DOF (−1 for an end that is not free).
/// The script's coarse level (parents.bin). `None` for any other model, or a mesh where a node
/// is a vertex of one cell and a mid-edge node of another (not conforming): then the script's
/// multigrid is GAMG on the whole operator.
pub fn vertex_parents(model: &Model) -> Option<Vec<i64>> {
    if model.solids.is_empty()
        || model.solids.iter().any(|s| s.kind != CellKind::Tet10)
        || !model.shells.is_empty()
        || !model.beams.is_empty()
    {
        return None;
    }
    let nn = model.nodes.len();
    let mut parent = vec![[u32::MAX; 2]; nn];
    let mut vertex = vec![false; nn];
    for set in &model.solids {
        for cell in set.conn.chunks_exact(10) {
            for &v in &cell[..4] {
                vertex[v as usize] = true;
            }
            for (k, [a, b]) in TET10_EDGES.iter().enumerate() {
                let p = [cell[*a].min(cell[*b]), cell[*a].max(cell[*b])];
                let m = &mut parent[cell[4 + k] as usize];
                if m[0] == u32::MAX {
                    *m = p;
                } else if *m != p {
                    return None;
                }
            }
        }
    }
    if (0..nn).any(|a| vertex[a] && parent[a][0] != u32::MAX) {
        return None;
    }
    let dofs = &model.dofs;
    let mut out = Vec::with_capacity(2 * dofs.n_free);
    for eq in 0..dofs.n_free {
        let (a, c) = dofs.node_comp_of(eq);
        match parent.get(a) {
            Some(p) if p[0] != u32::MAX => {
                for &q in p {
                    out.push(dofs.eq_of(q as usize, c).map_or(-1, |e| e as i64));
                }
            }
            _ => out.extend([eq as i64, eq as i64]),
        }
    }
    Some(out)
}

/// The nodes' block size for the multigrid: 3 (or 6) when every node with free DOFs has
/// exactly its three translations (or six components) free, else 1.
fn block_size(model: &Model) -> usize {
    let f = &model.dofs.first;
    let sizes: std::collections::BTreeSet<usize> = f.windows(2).map(|w| w[1] - w[0]).filter(|&s| s > 0).collect();
    match sizes.iter().collect::<Vec<_>>().as_slice() {
        [3] => 3,
        [6] => 6,
        _ => 1,
    }
}

/// A modal analysis of `mesh` with `solver` (and the direct path's `engine`): the run and, when
/// the iterative path solved, what it adds to the JSON report.
pub fn solve_mesh(
    engine: &Engine,
    solver: Solver,
    (mesh, source): (&Mesh, &str),
    opts: &ModalOptions,
    read_s: f64,
    lm: &LowMemOptions,
) -> Result<(ModalRun, Option<LowMemInfo>)> {
    match solver {
        Solver::Direct => Ok((engine.solve_mesh(mesh, source, opts, read_s)?, None)),
        Solver::Iterative => {
            let (run, info) = solve_iterative((mesh, source), opts, read_s, lm, None)?;
            Ok((run, Some(info)))
        }
        Solver::Auto if !engine.factorises_here() => Ok((engine.solve_mesh(mesh, source, opts, read_s)?, None)),
        Solver::Auto => {
            let t = Instant::now();
            let model = Model::build(mesh, &opts.spec, source)?;
            let model_s = t.elapsed().as_secs_f64();
            let refusal = match engine.system(model, &opts.system_options(), source) {
                Ok(sys) => {
                    return Ok((engine.solve(&sys, &opts.params(), Before { read_s, model_s })?, None));
                }
                Err(e) if e.is_memory_refusal() => e,
                Err(e) => return Err(e),
            };
            let reason = format!(
                "{refusal}; --solver auto takes the low-memory iterative path (SLEPc under mpirun) instead \
                 (--solver direct refuses)"
            );
            if let Err(e) = slepc::check_available(&lm.slepc) {
                // Both reasons: the direct path does not fit, the iterative one is not installed.
                return Err(Error::InvalidInput(format!(
                    "{refusal}; the low-memory iterative path that --solver auto would take instead is not \
                     available either: {e}"
                )));
            }
            // At once (the run may be long); the report's notes repeat it.
            eprintln!("note: the direct solver does not fit the memory: taking the low-memory iterative path");
            let (mut run, info) = solve_iterative((mesh, source), opts, read_s, lm, Some(reason.clone()))?;
            run.report.notes.insert(0, reason);
            Ok((run, Some(info)))
        }
    }
}

/// The request's checks for the iterative path: the lowest `--modes N` only.
fn check_request(opts: &ModalOptions) -> Result<usize> {
    if opts.shift_hz.is_some() {
        return Err(Error::option(
            "--shift",
            "--shift: the iterative solver computes the lowest modes; a shift needs --solver direct",
        ));
    }
    match opts.target {
        ModalTarget::Modes(0) => Err(Error::option("--modes", "--modes must be at least 1")),
        ModalTarget::Modes(n) => Ok(n),
        ModalTarget::Band(..) => Err(Error::option(
            "--band",
            "--band: the iterative solver computes the lowest --modes N; a band needs --solver direct",
        )),
    }
}

/// The ranks' memory estimate, bytes: PETSc's K and M with the multigrid hierarchy (about 60
/// bytes per stored entry), the eigensolver's blocks (about 4 vectors per wanted mode plus
/// the rigid-body motions) and each rank's interpreter and libraries (about 120 MiB).
fn ranks_estimate(nnz: u64, n: u64, nev: u64, ranks: u64) -> u64 {
    60 * nnz + 8 * n * (4 * nev + 12) + ranks * 120 * (1 << 20)
}

/// Write K, M, R.bin, params.json and the script into `dir`; returns the Sturm budget given.
fn write_folder(sys: &System, opts: &ModalOptions, dir: &Path, lm: &LowMemOptions, sturm_budget: u64) -> Result<()> {
    slepc::write_job(sys, &opts.params(), dir, true)?;
    let r = rigid_motions(sys.model());
    let path = dir.join("R.bin");
    let bytes: Vec<u8> = r.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&path, bytes).map_err(|e| Error::io(&path, e))?;
    if let Some(par) = vertex_parents(sys.model()) {
        let path = dir.join("parents.bin");
        let bytes: Vec<u8> = par.iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(&path, bytes).map_err(|e| Error::io(&path, e))?;
    }
    let pj = dir.join("params.json");
    let text = std::fs::read_to_string(&pj).map_err(|e| Error::io(&pj, e))?;
    let mut p: serde_json::Value = serde_json::from_str(&text).map_err(|e| Error::output(pj.display(), e))?;
    p["rigid"] = 6.into();
    p["block_size"] = block_size(sys.model()).into();
    p["sturm_budget"] = (sturm_budget as f64).into();
    let method = lm
        .method
        .clone()
        .or_else(|| std::env::var("VIBROFEM_LOWMEM_METHOD").ok());
    if let Some(m) = method {
        p["method"] = m.into();
    }
    std::fs::write(
        &pj,
        serde_json::to_string_pretty(&p).map_err(|e| Error::output(pj.display(), e))?,
    )
    .map_err(|e| Error::io(&pj, e))?;
    let script = dir.join("slepc_lowmem.py");
    std::fs::write(&script, SCRIPT).map_err(|e| Error::io(&script, e))
}

/// The script to run: the built-in one written into the folder, or `$VIBROFEM_LOWMEM_SCRIPT`
/// (a development copy).
fn script_path() -> PathBuf {
    std::env::var_os("VIBROFEM_LOWMEM_SCRIPT").map_or_else(|| PathBuf::from("slepc_lowmem.py"), PathBuf::from)
}

/// The script's `error` in `slepc.json`, if it wrote one.
fn script_error(dir: &Path) -> Option<String> {
    let text = std::fs::read_to_string(dir.join("slepc.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v.get("error").and_then(|e| e.as_str()).map(str::to_string)
}

/// Solve on the low-memory path (checks, assembly, the folder, the ranks, the verification).
fn solve_iterative(
    (mesh, source): (&Mesh, &str),
    opts: &ModalOptions,
    read_s: f64,
    lm: &LowMemOptions,
    reason: Option<String>,
) -> Result<(ModalRun, LowMemInfo)> {
    let t_all = Instant::now();
    let nev = check_request(opts)?;
    let o = &lm.slepc;
    if o.import.is_some() {
        return Err(Error::option(
            "--slepc-import",
            "--slepc-import reads a direct SLEPc job: give --solver direct",
        ));
    }
    if o.ranks == 0 {
        return Err(Error::option("--ranks", "--ranks must be at least 1"));
    }
    let versions = slepc::check_available(o)?;
    let mut mem = MemoryMib::default();
    reset_peak();
    let t = Instant::now();
    let build = || System::assemble_only(Model::build(mesh, &opts.spec, source)?, source);
    let mut sys = Some(build()?);
    let t_assemble = t.elapsed().as_secs_f64();
    mem.vibrofem.insert("assemble".into(), peak_mib());
    let s = sys.as_ref().expect("assembled");
    let (n, nnz) = (s.n_free() as u64, s.k().pattern.nnz() as u64);
    let km_bytes = 2 * 12 * nnz;
    let budget = memory_budget(lm.max_memory);
    let est = ranks_estimate(nnz, n, nev as u64, o.ranks as u64);
    let tight = budget.as_ref().is_some_and(|b| km_bytes + est > b.bytes);
    let sturm_budget = budget.as_ref().map_or(0, |b| {
        let keep = if tight { 0 } else { km_bytes };
        b.bytes.saturating_sub(est + keep)
    });
    reset_peak();
    let wd = slepc::workdir(o)?;
    let t = Instant::now();
    write_folder(s, opts, &wd.path, lm, sturm_budget)?;
    let t_write = t.elapsed().as_secs_f64();
    mem.vibrofem.insert("write".into(), peak_mib());
    if tight {
        // The ranks need the memory more than this process's copy of K and M.
        sys = None;
        crate::system::release_free_memory();
    }
    reset_peak();
    let t = Instant::now();
    let ran = slepc::run_mpi(o, &wd.path, &script_path(), &versions);
    let t_script = t.elapsed().as_secs_f64();
    let wait_rss = resident_memory().map_or(0.0, |b| b as f64 / MIB);
    mem.vibrofem.insert("wait".into(), peak_mib().max(wait_rss));
    if let Err(e) = ran {
        return Err(match script_error(&wd.path) {
            Some(msg) => engine_err(format!("the low-memory path stopped: {msg}")),
            None => e,
        });
    }
    reset_peak();
    let t = Instant::now();
    let sys = match sys {
        Some(s) => s,
        None => build()?,
    };
    let t_reassemble = t.elapsed().as_secs_f64();
    let out = load(&sys, &wd.path, nev)?;
    let mut info = LowMemInfo {
        solver: "iterative",
        engine: "slepc-lowmem",
        method: out.info.method.clone().unwrap_or_else(|| "?".into()),
        ranks: out.info.ranks,
        reason,
        rigid: out.info.rigid,
        sturm_verified: out.info.upper.is_some(),
        sturm_not_verified: out.not_verified.clone(),
        matrices_dropped: tight,
        budget_bytes: budget.as_ref().map(|b| b.bytes),
        sturm_budget_bytes: sturm_budget,
        memory_mib: mem,
        script_timings_s: out.info.timings_s.clone(),
    };
    let ts = |k: &str| info.script_timings_s.get(k).copied().unwrap_or(0.0);
    let script_solve: f64 = ["load", "rigid", "shift", "solve", "refine"]
        .iter()
        .map(|k| ts(k))
        .sum();
    let tm = Timings {
        read: read_s,
        assemble: t_assemble + t_write + t_reassemble,
        solve: script_solve,
        verify: out.sol.time_verify,
        post: (t_script - script_solve - ts("sturm")).max(0.0),
        ..Default::default()
    };
    let mut run = modal::finish(&sys, out.sol, tm.clone(), t_all, EigenParams::default().verify_tol)?;
    run.report.timings_s.post += tm.post;
    run.report.timings_s.read = read_s;
    run.report.timings_s.total = t_all.elapsed().as_secs_f64() + read_s;
    info.memory_mib.vibrofem.insert("verify".into(), peak_mib());
    info.memory_mib.script = out.info.memory_mib.clone();
    let own = |k: &str| info.memory_mib.vibrofem.get(k).copied().unwrap_or(0.0);
    let script_peak = info.memory_mib.script.values().fold(0.0, |a: f64, &b| a.max(b));
    info.memory_mib.total_peak = own("assemble")
        .max(own("write"))
        .max(own("verify"))
        .max(own("wait") + script_peak);
    // The process's peak over the whole run (the per-phase resets hide it from VmHWM).
    let own_peak = ["assemble", "write", "wait", "verify"]
        .iter()
        .map(|k| own(k))
        .fold(0.0, f64::max);
    run.report.peak_memory_bytes = Some((own_peak * MIB) as u64);
    if let Some(why) = &info.sturm_not_verified {
        // Not a failed count: no count.
        run.report.notes.retain(|n| !n.starts_with("Sturm check failed"));
        run.report.notes.push(format!("Sturm count not verified: {why}"));
    }
    Ok((run, info))
}

/// What `slepc_lowmem.py` reports in `slepc.json` (optional keys may be added).
#[derive(Debug, serde::Deserialize)]
struct LowMemOut {
    n: usize,
    nconv: usize,
    #[serde(default)]
    converged: usize,
    #[serde(default)]
    iterations: usize,
    ranks: usize,
    sigma: f64,
    #[serde(default)]
    rigid: usize,
    #[serde(default)]
    method: Option<String>,
    lower: (f64, usize),
    #[serde(default)]
    upper: Option<(f64, usize)>,
    #[serde(default)]
    sturm_skipped: Option<String>,
    #[serde(default)]
    timings_s: BTreeMap<String, f64>,
    #[serde(default)]
    memory_mib: BTreeMap<String, f64>,
    #[serde(default)]
    slepc: String,
}

/// The verified eigen solution of the job in `dir` and what the script reported.
struct Loaded {
    sol: EigenSolution,
    info: LowMemOut,
    not_verified: Option<String>,
}

/// Read the job's results back and verify them with `sys`'s K and M (`nev` modes asked).
fn load(sys: &System, dir: &Path, nev: usize) -> Result<Loaded> {
    let info_path = dir.join("slepc.json");
    let info: LowMemOut = serde_json::from_str(&results::read_text(&info_path)?)
        .map_err(|e| engine_err(format!("{}: {e}", info_path.display())))?;
    let n = sys.n_free();
    if info.n != n {
        return Err(engine_err(format!(
            "{ENGINE}: the low-memory script solved a problem of size {} for a model of {n} DOFs",
            info.n
        )));
    }
    let lam = results::read_f64s(
        &dir.join("lambda.bin"),
        Some(info.nconv),
        &format!("{} eigenvalues", info.nconv),
    )?;
    let x = results::read_f64s(
        &dir.join("vectors.bin"),
        info.nconv.checked_mul(n),
        &format!("{} vectors of {n} entries", info.nconv),
    )?;
    results::check_finite(&lam, &x, n, dir)?;
    let tv = Instant::now();
    let mut idx: Vec<usize> = (0..lam.len()).collect();
    idx.sort_by(|&a, &b| lam[a].total_cmp(&lam[b]));
    let (k, m) = (sys.k(), sys.m()?);
    let (lambda, vectors) = results::normalised(m, &lam, &x, n, &idx);
    let (rel_residual, m_orth, backward_error) =
        eigen::verify_with_backward_errors(k, m, &lambda, vectors.as_ref(), info.sigma);
    let (sturm, not_verified, mut notes) = sturm_of(&info, &lambda, nev);
    let worst = backward_error.iter().fold(0.0, |a, &b| max_nan(a, b));
    notes.insert(
        0,
        format!(
            "solved by the low-memory iterative path: SLEPc {} (method {}, {} rigid-body motions deflated) on {} MPI rank{}, {} iterations, {} pairs converged; residuals, backward errors (largest \
             {worst:.1e}) and M-orthonormality ({m_orth:.1e}) recomputed here with vibrofem's K and M",
            info.slepc,
            info.method.as_deref().unwrap_or("the script's default method"),
            info.rigid,
            info.ranks,
            if info.ranks == 1 { "" } else { "s" },
            info.iterations,
            info.converged
        ),
    );
    let sol = EigenSolution {
        lambda,
        vectors,
        rel_residual,
        backward_error,
        notes,
        m_orthonormality: m_orth,
        sturm,
        shift: info.sigma,
        applications: 0,
        factorizations: usize::from(info.upper.is_some()),
        time_factor: 0.0,
        time_iterate: info.timings_s.get("solve").copied().unwrap_or(0.0),
        time_verify: tv.elapsed().as_secs_f64() + info.timings_s.get("sturm").copied().unwrap_or(0.0),
        factor_backward_error: 0.0,
        memory: Default::default(),
    };
    Ok(Loaded {
        sol,
        info,
        not_verified,
    })
}

/// The Sturm check of the script's count: complete when the count between its points equals
/// the modes found there and every asked mode was returned; "not verified" (with why) when the
/// count did not run.
fn sturm_of(info: &LowMemOut, lambda: &[f64], nev: usize) -> (SturmCheck, Option<String>, Vec<String>) {
    let mut notes = Vec::new();
    let Some(upper) = info.upper else {
        let why = format!(
            "{}; whether a mode was missed is not known (MUMPS's out-of-core inertia of K − sM did not run \
             within the memory budget)",
            info.sturm_skipped.as_deref().unwrap_or("the script did not count")
        );
        let sturm = SturmCheck {
            lower: info.lower,
            upper: (info.lower.0, info.lower.1),
            expected: 0,
            found: 0,
            complete: false,
        };
        return (sturm, Some(why), notes);
    };
    let found = lambda.iter().filter(|&&l| l > info.lower.0 && l < upper.0).count();
    let expected = upper.1.saturating_sub(info.lower.1);
    let mut complete = expected == found;
    if lambda.len() < nev {
        complete = false;
        notes.push(format!(
            "the low-memory path returned {} eigenpairs, {nev} asked: not complete",
            lambda.len()
        ));
    }
    notes.push(format!(
        "completeness from MUMPS's out-of-core inertia of K − sM at s = {:.6e} (Sturm count {}); below σ = {:.4e} \
         no eigenvalue (K positive semidefinite)",
        upper.0, upper.1, info.lower.0
    ));
    let sturm = SturmCheck {
        lower: info.lower,
        upper,
        expected,
        found,
        complete,
    };
    (sturm, None, notes)
}

/// The text report of an iterative run: the modal table with its completeness line saying
/// "not verified" when the Sturm count did not run, and one line on the solver and its memory.
pub fn table(run: &ModalRun, info: &LowMemInfo) -> String {
    let text = crate::app::report::modal_table(&run.report);
    let mut out = String::with_capacity(text.len() + 200);
    for line in text.lines() {
        match (&info.sturm_not_verified, line.starts_with("complete: ")) {
            (Some(why), true) => out.push_str(&format!("complete: Sturm count not verified ({why})")),
            _ => out.push_str(line),
        }
        out.push('\n');
    }
    let m = &info.memory_mib;
    let script = m.script.values().fold(0.0, |a: f64, &b| a.max(b));
    out.push_str(&format!(
        "solver: iterative (SLEPc low-memory path, {}, {} rank{}); memory peak {:.1} MiB: script {:.1} MiB, this \
         process {:.1} MiB{}\n",
        info.method,
        info.ranks,
        if info.ranks == 1 { "" } else { "s" },
        m.total_peak,
        script,
        m.vibrofem.values().fold(0.0, |a: f64, &b| a.max(b)),
        if info.matrices_dropped {
            format!(
                " (K and M dropped while the ranks ran, budget {})",
                fmt_bytes(info.budget_bytes.unwrap_or(0))
            )
        } else {
            String::new()
        }
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;
    use crate::model::ModelSpec;

    /// The P1 interpolation from parents.bin reproduces a linear field at every DOF: a mid-edge
    /// node lies halfway between its two parents (same component), a vertex DOF is its own
    /// parent, and the vertex DOFs are those of the tet4 mesh with the same divisions.
    #[test]
    fn tet10_parents_interpolate_linear_fields() {
        let mesh = box_mesh(CellKind::Tet10, [0.3, 0.2, 0.1], [3, 2, 1]);
        let model = Model::build(&mesh, &ModelSpec::default(), "box").unwrap();
        let par = vertex_parents(&model).expect("a tet10 model has a P1 coarse space");
        let dofs = &model.dofs;
        assert_eq!(par.len(), 2 * dofs.n_free);
        let mut vertex = 0;
        for eq in 0..dofs.n_free {
            let (a, c) = dofs.node_comp_of(eq);
            let (p, q) = (par[2 * eq] as usize, par[2 * eq + 1] as usize);
            if p == eq && q == eq {
                vertex += 1;
                continue;
            }
            let (pa, pc) = dofs.node_comp_of(p);
            let (qa, qc) = dofs.node_comp_of(q);
            assert_eq!((pc, qc), (c, c));
            for d in 0..3 {
                let mid = 0.5 * (model.nodes[pa][d] + model.nodes[qa][d]);
                assert!((model.nodes[a][d] - mid).abs() < 1e-12, "equation {eq}");
            }
        }
        let tet4 = box_mesh(CellKind::Tet4, [0.3, 0.2, 0.1], [3, 2, 1]);
        assert_eq!(vertex, 3 * tet4.n_nodes());
        let hex = box_mesh(CellKind::Hex20, [0.3, 0.2, 0.1], [3, 2, 1]);
        assert!(vertex_parents(&Model::build(&hex, &ModelSpec::default(), "box").unwrap()).is_none());
    }
}
