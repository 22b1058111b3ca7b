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
use crate::mesh::Mesh;
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
    /// The multigrid's coarse level: `p1` (the linear elements of the same mesh, from
    /// parents.bin: tet10, hex20, hex27, wedge15) or `gamg` (GAMG on the whole operator); `None` for
    /// `ks-mumps`.
    pub coarse: Option<String>,
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
    /// LOBPCG's block (the block the script used, its default, the smallest allowed, the
    /// ranks' estimated peak with it and whether that fits the budget); `None` for the other
    /// methods.
    pub lobpcg_block: Option<BlockChoice>,
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

/// The parents of every free equation on the linear space of the same mesh (the script's coarse
/// level: parents.bin and parent_weights.bin, `width` int64 and f64 per equation): at a vertex
/// DOF itself (weight 1, the other entries −1 and 0); at a DOF of a higher-order node the same
/// component of the corners of its cell whose linear shape functions are not zero there, with
/// those values as weights (½ and ½ at a mid-edge node of tet10, hex20 or wedge15; ¼ each at a
/// hex27 face node, ⅛ each at its centre), −1 for a corner whose component is not free.
pub struct Parents {
    /// Entries per equation: the most parents of a node (2 without hex27, 8 with).
    pub width: usize,
    /// Parent equations, `width` per free equation.
    pub eqs: Vec<i64>,
    /// Their weights.
    pub weights: Vec<f64>,
}

/// For a model of quadratic solids (tet10, hex20, hex27, wedge15, mixed as long as the mesh is
/// conforming): the interpolation of every free equation from the corner DOFs ([`Parents`]).
/// The linear shape functions at a higher-order node's reference position interpolate linear
/// fields exactly on straight cells, so the space is the mesh's linear elements (tet4 in tet10,
/// the trilinear hex8 in hex20 and hex27, wedge6 in wedge15) and holds the rigid-body motions.
/// `None` for any other model (shells, beams, linear solids), or a mesh where a node is a corner
/// of one cell and a higher-order node of another, or a higher-order node that two cells
/// interpolate differently (not conforming): then the script's multigrid is GAMG on the whole
/// operator.
pub fn vertex_parents(model: &Model) -> Option<Parents> {
    if model.solids.is_empty() || !model.shells.is_empty() || !model.beams.is_empty() {
        return None;
    }
    let nn = model.nodes.len();
    let mut parent: Vec<Option<Vec<(u32, f64)>>> = vec![None; nn];
    let mut vertex = vec![false; nn];
    for set in &model.solids {
        let kind = set.kind;
        if kind.linear() == kind {
            return None;
        }
        let corners = kind.linear().n_nodes();
        // Each higher-order node's corners and weights in the reference cell, once per kind.
        let local = crate::fe::shape::corner_weights(kind);
        for cell in set.conn.chunks_exact(kind.n_nodes()) {
            for &v in &cell[..corners] {
                vertex[v as usize] = true;
            }
            for (k, w) in local.iter().enumerate() {
                let mut p: Vec<(u32, f64)> = w.iter().map(|&(i, wi)| (cell[i], wi)).collect();
                p.sort_by_key(|e| e.0);
                let m = &mut parent[cell[corners + k] as usize];
                match m {
                    None => *m = Some(p),
                    Some(q) => {
                        let same = q.len() == p.len()
                            && q.iter().zip(&p).all(|(a, b)| a.0 == b.0 && (a.1 - b.1).abs() < 1e-12);
                        if !same {
                            return None;
                        }
                    }
                }
            }
        }
    }
    if (0..nn).any(|a| vertex[a] && parent[a].is_some()) {
        return None;
    }
    let width = parent.iter().flatten().map(Vec::len).max().unwrap_or(1).max(1);
    let dofs = &model.dofs;
    let (mut eqs, mut weights) = (
        Vec::with_capacity(width * dofs.n_free),
        Vec::with_capacity(width * dofs.n_free),
    );
    for eq in 0..dofs.n_free {
        let (a, c) = dofs.node_comp_of(eq);
        let row: Vec<(i64, f64)> = match parent.get(a) {
            Some(Some(p)) => p
                .iter()
                .map(|&(q, w)| (dofs.eq_of(q as usize, c).map_or(-1, |e| e as i64), w))
                .collect(),
            _ => vec![(eq as i64, 1.0)],
        };
        for i in 0..width {
            let (e, w) = row.get(i).copied().unwrap_or((-1, 0.0));
            eqs.push(e);
            weights.push(w);
        }
    }
    Some(Parents { width, eqs, weights })
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

/// Bytes per stored entry of K that the ranks hold besides LOBPCG's vectors: K − σM (BAIJ),
/// M without its zeros, the P1 level and GAMG's hierarchy. Measured (the script's peak less
/// LOBPCG's vectors and the interpreter, docs/lowmem.md): 18.5 at 1M DOFs (83.1 M entries),
/// 13.6 at 120k (9.37 M); 20 keeps the estimate above both.
const BYTES_PER_ENTRY: u64 = 20;
/// Each rank's interpreter, PETSc and SLEPc, bytes.
const RANK_BYTES: u64 = 160 << 20;
/// Bytes per stored entry of K that each rank after the first adds (the distributed matrices'
/// off-process parts and their communication buffers). Measured, the script's peak on 2 ranks
/// less 1 rank's (docs/lowmem.md): +150–163 MiB at 120k DOFs (9.37 M entries) and +270 MiB at
/// 1M (83.1 M): ~140 MiB per rank (in RANK_BYTES) plus 1.6 bytes per entry.
const GHOST_BYTES_PER_ENTRY: u64 = 2;
/// The script's LOBPCG (method `lobpcg`) holds nine vectors of n per column of its block (X, W,
/// P and their products with A and M) plus its slices' temporaries; one more keeps the estimate
/// above what was measured (docs/lowmem.md). SLEPc's LOBPCG (method `slepc-lobpcg`, kept for
/// comparison) holds about 21 (V and Z of three blocks each and cached M-products); a run that
/// names it is planned as if it held 10.
const VECTORS_PER_COLUMN: u64 = 10;
/// Vectors of n besides the block: the constraints Y (rigid-body pairs and wanted modes, per
/// mode asked) plus this many (work vectors, the rigid-body pairs' copies).
const VECTORS_FIXED: u64 = 8;
/// The smallest LOBPCG block is the elastic modes wanted plus this (params.json
/// `lobpcg_min_extra`): the last wanted pairs converge at about the rate λ_wanted/λ_(block+1),
/// so each column cut costs iterations (120k plate, 12 wanted: 31, 40 and 45 iterations with
/// blocks 16, 14 and 13; docs/lowmem.md) but a block of wanted + 1 still converges.
pub const LOBPCG_MIN_EXTRA: usize = 1;
/// What this process keeps resident while the ranks run, K and M dropped, bytes.
const OWN_WAIT_BYTES: u64 = 64 << 20;

/// The script's default LOBPCG block for `wanted` elastic modes: wanted + max(4, wanted / 3).
pub fn default_block(wanted: usize) -> usize {
    wanted + (wanted / 3).max(4)
}

/// The ranks' memory estimate, bytes, with a LOBPCG block of `block` and `nev` modes asked:
/// the matrices and the multigrid (per stored entry of K), LOBPCG's vectors (per block column
/// and per mode), each rank's interpreter and libraries, and the off-process parts every rank
/// after the first adds.
pub fn ranks_estimate(n: u64, nnz: u64, ranks: u64, nev: usize, block: usize) -> u64 {
    BYTES_PER_ENTRY * nnz
        + 8 * n * (VECTORS_PER_COLUMN * block as u64 + nev as u64 + VECTORS_FIXED)
        + ranks * RANK_BYTES
        + ranks.saturating_sub(1) * GHOST_BYTES_PER_ENTRY * nnz
}

/// The largest LOBPCG block (at most `cap`) whose [`ranks_estimate`] fits `avail` bytes; 0 when
/// not even a block of 1 fits.
pub fn block_max(n: u64, nnz: u64, ranks: u64, nev: usize, avail: u64, cap: usize) -> usize {
    (1..=cap)
        .rev()
        .find(|&b| ranks_estimate(n, nnz, ranks, nev, b) <= avail)
        .unwrap_or(0)
}

/// LOBPCG's block for a run, chosen from the memory budget.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct BlockChoice {
    /// The block: the default when the estimate fits (or no budget is known), else the largest
    /// that fits, never below `min`.
    pub block: usize,
    /// The script's default for the wanted modes.
    pub default: usize,
    /// The smallest allowed: wanted + [`LOBPCG_MIN_EXTRA`].
    pub min: usize,
    /// The ranks' estimated peak with `block`, bytes.
    pub estimate_bytes: u64,
    /// Whether that estimate fits the budget (true without a budget).
    pub fits: bool,
}

/// The block for `wanted` elastic modes (`nev` modes asked in all) on a model of `n` DOFs and
/// `nnz` stored entries of K, `ranks` ranks, `avail` bytes for the ranks (`None`: no limit):
/// the default if it fits, else the largest block that fits, else the smallest allowed (the run
/// goes on; the note says the budget is not met). The script applies the same rule with
/// params.json's `lobpcg_block_max` ([`block_max`]) once it knows how many rigid-body modes it
/// deflated.
pub fn choose_block(n: u64, nnz: u64, ranks: u64, nev: usize, wanted: usize, avail: Option<u64>) -> BlockChoice {
    let default = default_block(wanted);
    let min = (wanted + LOBPCG_MIN_EXTRA).min(default);
    let block = avail.map_or(default, |a| block_max(n, nnz, ranks, nev, a, default).max(min));
    let estimate_bytes = ranks_estimate(n, nnz, ranks, nev, block);
    BlockChoice {
        block,
        default,
        min,
        estimate_bytes,
        fits: avail.is_none_or(|a| estimate_bytes <= a),
    }
}

/// How a run uses its memory budget.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
struct Plan {
    /// This process drops K and M while the ranks run.
    tight: bool,
    /// Bytes left for the ranks (`None`: no budget known).
    avail: Option<u64>,
    /// The largest LOBPCG block within `avail` (params.json `lobpcg_block_max`).
    block_max: Option<usize>,
    /// Bytes for the script's out-of-core Sturm count.
    sturm_budget: u64,
}

/// The plan for `nev` modes on `n` DOFs, `nnz` entries, `ranks` ranks within `budget` bytes:
/// K and M (`km_bytes`) are dropped while the ranks run when the ranks' estimate at the default
/// block does not fit beside them; the block is cut to fit what is left; the Sturm count gets
/// the rest.
fn plan(n: u64, nnz: u64, ranks: u64, nev: usize, km_bytes: u64, budget: Option<u64>) -> Plan {
    let Some(b) = budget else { return Plan::default() };
    let cap = default_block(nev);
    let full = ranks_estimate(n, nnz, ranks, nev, cap);
    let tight = km_bytes + OWN_WAIT_BYTES + full > b;
    let avail = b.saturating_sub(OWN_WAIT_BYTES + if tight { 0 } else { km_bytes });
    let bm = block_max(n, nnz, ranks, nev, avail, cap);
    let est = ranks_estimate(n, nnz, ranks, nev, bm.max(1));
    Plan {
        tight,
        avail: Some(avail),
        block_max: Some(bm),
        sturm_budget: avail.saturating_sub(est),
    }
}

/// Write K, M, R.bin, params.json and the script into `dir`; returns the Sturm budget given.
fn write_folder(sys: &System, opts: &ModalOptions, dir: &Path, lm: &LowMemOptions, plan: &Plan) -> Result<()> {
    slepc::write_job(sys, &opts.params(), dir, true)?;
    let r = rigid_motions(sys.model());
    let path = dir.join("R.bin");
    let bytes: Vec<u8> = r.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&path, bytes).map_err(|e| Error::io(&path, e))?;
    let parents = vertex_parents(sys.model());
    if let Some(pa) = &parents {
        let path = dir.join("parents.bin");
        let bytes: Vec<u8> = pa.eqs.iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(&path, bytes).map_err(|e| Error::io(&path, e))?;
        let path = dir.join("parent_weights.bin");
        let bytes: Vec<u8> = pa.weights.iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(&path, bytes).map_err(|e| Error::io(&path, e))?;
    }
    let pj = dir.join("params.json");
    let text = std::fs::read_to_string(&pj).map_err(|e| Error::io(&pj, e))?;
    let mut p: serde_json::Value = serde_json::from_str(&text).map_err(|e| Error::output(pj.display(), e))?;
    p["rigid"] = 6.into();
    p["block_size"] = block_size(sys.model()).into();
    p["parents_width"] = parents.as_ref().map_or(0, |pa| pa.width).into();
    p["sturm_budget"] = (plan.sturm_budget as f64).into();
    if let Some(bm) = plan.block_max {
        p["lobpcg_block_max"] = bm.into();
        p["lobpcg_min_extra"] = LOBPCG_MIN_EXTRA.into();
    }
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
    let plan = plan(n, nnz, o.ranks as u64, nev, km_bytes, budget.as_ref().map(|b| b.bytes));
    let tight = plan.tight;
    reset_peak();
    let wd = slepc::workdir(o)?;
    let t = Instant::now();
    write_folder(s, opts, &wd.path, lm, &plan)?;
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
        coarse: out.info.coarse.clone(),
        sturm_verified: out.info.upper.is_some(),
        sturm_not_verified: out.not_verified.clone(),
        matrices_dropped: tight,
        budget_bytes: budget.as_ref().map(|b| b.bytes),
        sturm_budget_bytes: plan.sturm_budget,
        lobpcg_block: None,
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
    let (choice, note) = block_note(&out.info, (n, nnz, o.ranks as u64, nev), &plan, budget.as_ref());
    info.lobpcg_block = choice;
    run.report.notes.extend(note);
    if let Some(why) = &info.sturm_not_verified {
        // Not a failed count: no count.
        run.report.notes.retain(|n| !n.starts_with("Sturm check failed"));
        run.report.notes.push(format!("Sturm count not verified: {why}"));
    }
    Ok((run, info))
}

/// The block LOBPCG ran with (from the script's report) and, when the budget cut it below its
/// default or could not be met at the smallest block, a note saying so. `size`: n, stored
/// entries, ranks, modes asked.
fn block_note(
    out: &LowMemOut,
    (n, nnz, ranks, nev): (u64, u64, u64, usize),
    plan: &Plan,
    budget: Option<&crate::system::MemoryBudget>,
) -> (Option<BlockChoice>, Option<String>) {
    let Some(used) = out.lobpcg_block else {
        return (None, None);
    };
    let wanted = nev.saturating_sub(out.rigid);
    let mut c = choose_block(n, nnz, ranks, nev, wanted, plan.avail);
    c.block = used;
    c.estimate_bytes = ranks_estimate(n, nnz, ranks, nev, used);
    c.fits = plan.avail.is_none_or(|a| c.estimate_bytes <= a);
    let (Some(avail), Some(b)) = (plan.avail, budget) else {
        return (Some(c), None);
    };
    let note = if !c.fits {
        Some(format!(
            "the memory budget ({} {}) is not met: even LOBPCG's smallest block ({used} for {wanted} elastic \
             modes; default {}) makes the ranks' estimated peak {}, above the {} left for them; the run went on",
            b.what,
            fmt_bytes(b.bytes),
            c.default,
            fmt_bytes(c.estimate_bytes),
            fmt_bytes(avail)
        ))
    } else if used < c.default {
        Some(format!(
            "LOBPCG block {used} for {wanted} elastic modes (default {}): the largest whose estimated peak \
             ({} for the ranks) fits the {} left for them ({} {})",
            c.default,
            fmt_bytes(c.estimate_bytes),
            fmt_bytes(avail),
            b.what,
            fmt_bytes(b.bytes)
        ))
    } else {
        None
    };
    (Some(c), note)
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
    lobpcg_block: Option<usize>,
    #[serde(default)]
    coarse: Option<String>,
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
    let (mut lambda, mut vectors) = results::normalised(m, &lam, &x, n, &idx);
    // The script's rigid-body pairs (the lowest: K ⪰ 0) are Ritz pairs of the motions whose
    // Rayleigh quotients are rounding: reported as the direct path reports them, at λ = 0.
    let cand = crate::analysis::modal::rigid_candidates(sys.model());
    eigen::canonical_null_pairs(k, m, &cand, &mut lambda, &mut vectors);
    let (mut rel_residual, m_orth, mut backward_error) =
        eigen::verify_with_backward_errors(k, m, &lambda, vectors.as_ref(), info.sigma);
    let (sturm, not_verified, mut notes) = sturm_of(&info, &lambda, nev);
    // The count checked every pair returned (the rigid ones when fewer were asked, the rest of
    // a repeated root at the cut); the report keeps the modes asked for, as the direct path's.
    if lambda.len() > nev {
        lambda.truncate(nev);
        vectors = vectors.get(.., 0..nev).to_owned();
        rel_residual.truncate(nev);
        backward_error.truncate(nev);
    }
    let worst = backward_error.iter().fold(0.0, |a, &b| max_nan(a, b));
    notes.insert(
        0,
        format!(
            "solved by the low-memory iterative path: method {} (PETSc/SLEPc {}, {} rigid-body motions deflated) on {} MPI rank{}, {} iterations, {} pairs converged; residuals, backward errors (largest \
             {worst:.1e}) and M-orthonormality ({m_orth:.1e}) recomputed here with vibrofem's K and M",
            info.method.as_deref().unwrap_or("the script's default method"),
            info.slepc,
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
    use crate::mesh::CellKind;
    use crate::mesh::generate::box_mesh;
    use crate::model::ModelSpec;

    /// Checks the parents of `model` and returns its vertex DOFs and the parent counts seen: a
    /// vertex DOF is its own only parent (weight 1); any other DOF has at least two parents, all
    /// vertex DOFs of its own component, whose weights sum to 1 and whose weighted position is
    /// its node's (so the interpolation is exact for linear fields on these straight cells).
    fn check_parents(model: &Model) -> (usize, std::collections::BTreeSet<usize>) {
        let pa = vertex_parents(model).expect("a coarse level");
        let (w, dofs) = (pa.width, &model.dofs);
        assert_eq!((pa.eqs.len(), pa.weights.len()), (w * dofs.n_free, w * dofs.n_free));
        let own = |e: usize| pa.eqs[w * e] == e as i64;
        let (mut vertex, mut counts) = (0, std::collections::BTreeSet::new());
        for eq in 0..dofs.n_free {
            let (a, c) = dofs.node_comp_of(eq);
            let row: Vec<(usize, f64)> = (0..w)
                .filter(|&i| pa.eqs[w * eq + i] >= 0)
                .map(|i| (pa.eqs[w * eq + i] as usize, pa.weights[w * eq + i]))
                .collect();
            if own(eq) {
                assert_eq!(row, vec![(eq, 1.0)], "equation {eq}");
                vertex += 1;
                continue;
            }
            assert!(row.len() >= 2, "equation {eq}: {row:?}");
            counts.insert(row.len());
            let mut at = [0.0; 3];
            for &(p, wp) in &row {
                assert!(own(p), "equation {eq}: parent {p} is not a vertex DOF");
                let (pa_, pc) = dofs.node_comp_of(p);
                assert_eq!(pc, c);
                for d in 0..3 {
                    at[d] += wp * model.nodes[pa_][d];
                }
            }
            assert!(
                (row.iter().map(|r| r.1).sum::<f64>() - 1.0).abs() < 1e-12,
                "equation {eq}"
            );
            for d in 0..3 {
                assert!((model.nodes[a][d] - at[d]).abs() < 1e-12, "equation {eq}");
            }
        }
        (vertex, counts)
    }

    fn build(mesh: &Mesh) -> Model {
        Model::build(mesh, &ModelSpec::default(), "box").unwrap()
    }

    /// The P1 interpolation from parents.bin reproduces a linear field at every DOF: a mid-edge
    /// node lies halfway between its two parents (same component), a vertex DOF is its own
    /// parent, and the vertex DOFs are those of the tet4 mesh with the same divisions. A linear
    /// mesh has no coarse level.
    #[test]
    fn tet10_parents_interpolate_linear_fields() {
        let mesh = box_mesh(CellKind::Tet10, [0.3, 0.2, 0.1], [3, 2, 1]);
        let (vertex, counts) = check_parents(&build(&mesh));
        assert_eq!(counts, [2].into());
        let tet4 = box_mesh(CellKind::Tet4, [0.3, 0.2, 0.1], [3, 2, 1]);
        assert_eq!(vertex, 3 * tet4.n_nodes());
        let hex8 = box_mesh(CellKind::Hex8, [0.3, 0.2, 0.1], [3, 2, 1]);
        assert!(vertex_parents(&build(&hex8)).is_none());
    }

    /// Hex20 (serendipity) and wedge15 boxes: every mid-edge DOF points at the two corners of
    /// its edge; hex27 adds face nodes (four corners, ¼ each) and centre nodes (eight, ⅛ each).
    /// The corner DOFs are those of the linear mesh: the trilinear (or wedge6) coarse space.
    #[test]
    fn hex20_hex27_wedge15_parents_are_the_linear_interpolation() {
        let (size, n) = ([0.3, 0.2, 0.1], [3, 2, 1]);
        let hex8 = 3 * box_mesh(CellKind::Hex8, size, n).n_nodes();
        let (vertex, counts) = check_parents(&build(&box_mesh(CellKind::Hex20, size, n)));
        assert_eq!((vertex, counts), (hex8, [2].into()));
        let hex27 = vertex_parents(&build(&box_mesh(CellKind::Hex27, size, n))).expect("a coarse level");
        assert_eq!(hex27.width, 8);
        let (vertex, counts) = check_parents(&build(&box_mesh(CellKind::Hex27, size, n)));
        assert_eq!((vertex, counts), (hex8, [2, 4, 8].into()));
        let (vertex, counts) = check_parents(&build(&box_mesh(CellKind::Wedge15, size, n)));
        assert_eq!(
            (vertex, counts),
            (3 * box_mesh(CellKind::Wedge6, size, n).n_nodes(), [2].into())
        );
    }

    /// LOBPCG's block from the memory budget (the 1M plate's size: 1 005 282 DOFs, 83 121 714
    /// entries, 18 modes of which 12 elastic): the default 16 when it fits or no budget is
    /// known; the largest block that fits a budget between the smallest (13) and the default;
    /// the smallest, marked as not fitting, below it. The estimate grows by
    /// 8 n × VECTORS_PER_COLUMN bytes per column.
    #[test]
    fn lobpcg_block_fits_the_budget() {
        let (n, nnz, r) = (1_005_282u64, 83_121_714u64, 1u64);
        let est = |b: usize| ranks_estimate(n, nnz, r, 18, b);
        assert_eq!(est(16) - est(15), 8 * n * VECTORS_PER_COLUMN);
        let c = choose_block(n, nnz, r, 18, 12, None);
        assert_eq!((c.block, c.default, c.min, c.fits), (16, 16, 13, true));
        assert_eq!(c.estimate_bytes, est(16));
        assert_eq!(choose_block(n, nnz, r, 18, 12, Some(64 << 30)).block, 16);
        for b in 13..=16 {
            let c = choose_block(n, nnz, r, 18, 12, Some(est(b)));
            assert_eq!((c.block, c.fits), (b, true));
            let c = choose_block(n, nnz, r, 18, 12, Some(est(b) - 1));
            if b > 13 {
                assert_eq!((c.block, c.fits), (b - 1, true));
                assert!(c.estimate_bytes < est(b));
            } else {
                assert_eq!((c.block, c.fits), (13, false));
                assert_eq!(c.estimate_bytes, est(13));
            }
        }
        assert_eq!(choose_block(n, nnz, r, 18, 12, Some(0)).block, 13);
        // Above what the script was measured to hold at block 16 (docs/lowmem.md), summed over
        // its ranks: 1M on 1 rank ~3 050 MiB, on 2 ranks 3 320 MiB; 120k on 2 ranks 554 MiB.
        assert!(est(16) > 3050 << 20 && est(16) < 3400 << 20, "{}", est(16) >> 20);
        let two = ranks_estimate(n, nnz, 2, 18, 16);
        assert!(two > 3320 << 20 && two < 3700 << 20, "{}", two >> 20);
        let two_120k = ranks_estimate(119_181, 9_368_955, 2, 18, 16);
        assert!(two_120k > 554 << 20, "{}", two_120k >> 20);
        // Few modes: the smallest block is wanted + 1 (the default's 4 extra columns cut).
        let c = choose_block(n, nnz, r, 3, 2, Some(0));
        assert_eq!((c.block, c.default, c.fits), (3, 6, false));
        // The 1M plate under --max-memory 4G: K and M dropped, the default block fits (the run
        // measured 3.4 GiB in all, docs/lowmem.md); under 3G the block is cut to fit.
        let km = 2 * 12 * nnz;
        let p = plan(n, nnz, r, 18, km, Some(4 << 30));
        assert!(p.tight);
        assert_eq!(p.avail, Some((4 << 30) - OWN_WAIT_BYTES));
        let c = choose_block(n, nnz, r, 18, 12, p.avail);
        assert!(c.fits && c.block == 16 && p.block_max >= Some(16), "{c:?} {p:?}");
        // The plan budgets the largest block it allows (it does not yet know how many rigid-body
        // modes the script deflates), so the Sturm count gets what that block leaves.
        assert_eq!(p.sturm_budget, p.avail.unwrap() - est(p.block_max.unwrap()));
        assert!(p.sturm_budget <= p.avail.unwrap() - est(c.block));
        let p = plan(n, nnz, r, 18, km, Some(3 << 30));
        let c = choose_block(n, nnz, r, 18, 12, p.avail);
        assert!(c.fits && c.block < 16 && Some(c.block) == p.block_max, "{c:?} {p:?}");
        // Ample memory: K and M kept, the default block, the rest for the Sturm count.
        let p = plan(n, nnz, r, 18, km, Some(64 << 30));
        assert!(!p.tight);
        assert_eq!(p.block_max, Some(default_block(18)));
        assert!(p.sturm_budget > 0);
        assert_eq!(plan(n, nnz, r, 18, km, None), Plan::default());
    }

    /// A conforming mix: one brick of hex20 beside one of two wedge15 (sharing a quad face)
    /// has a coarse level; the same mix with a hex8 brick (a linear cell) has none.
    #[test]
    fn mixed_hex20_wedge15_parents() {
        let mut mesh = box_mesh(CellKind::Wedge15, [0.2, 0.1, 0.1], [2, 1, 1]);
        let hex = box_mesh(CellKind::Hex20, [0.1, 0.1, 0.1], [1, 1, 1]);
        let find = |p: [f64; 3]| {
            mesh.nodes
                .iter()
                .position(|q| (0..3).all(|d| (p[d] - q[d]).abs() < 1e-12))
                .expect("a lattice node") as u32
        };
        let cell: Vec<u32> = hex
            .blocks
            .iter()
            .find(|b| b.kind == CellKind::Hex20)
            .unwrap()
            .conn
            .iter()
            .map(|&a| find(hex.nodes[a as usize]))
            .collect();
        let mut block = crate::mesh::CellBlock::new(CellKind::Hex20);
        block.conn = cell;
        block.tags = vec![1000];
        // The wedges of the first brick (centroid x < 0.1) give way to the hex20 cell.
        let nodes = mesh.nodes.clone();
        for b in mesh.blocks.iter_mut().filter(|b| b.kind == CellKind::Wedge15) {
            let (mut conn, mut tags) = (Vec::new(), Vec::new());
            for (c, &t) in b.conn.chunks_exact(15).zip(&b.tags) {
                let x: f64 = c[..6].iter().map(|&a| nodes[a as usize][0]).sum::<f64>() / 6.0;
                if x > 0.1 {
                    conn.extend_from_slice(c);
                    tags.push(t);
                }
            }
            (b.conn, b.tags) = (conn, tags);
        }
        mesh.blocks.push(block);
        let model = build(&mesh);
        assert_eq!(model.solids.len(), 2);
        check_parents(&model);
        let hex8 = crate::mesh::CellBlock {
            kind: CellKind::Hex8,
            conn: mesh.blocks.last().unwrap().conn[..8].to_vec(),
            tags: vec![1000],
        };
        mesh.blocks.pop();
        mesh.blocks.push(hex8);
        assert!(vertex_parents(&build(&mesh)).is_none());
    }
}
