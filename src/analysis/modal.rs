//! Orchestration of analyses: mesh → model → assembly → solve → report. No formatting here.

use crate::linalg::eigen::{self, EigenParams, SturmCheck, Target};
use crate::linalg::floor::{FloorReport, RunWork};
use crate::linalg::ordering::Ordering;
use crate::linalg::sparse::SymMatrix;
use crate::mesh::Mesh;
use crate::model::{Model, ModelSpec};
use crate::post::modal::{
    ParticipationBasis, ParticipationTable, RigidParts, hz, lambda_of_hz, participation_of, rigid_analysis_of,
};
use crate::system::{System, SystemOptions};
use crate::util::max_nan;
use crate::{Error, Result};
use serde::Serialize;
use std::time::Instant;

/// What a modal analysis computes.
#[derive(Clone, Debug)]
pub struct ModalOptions {
    /// Model definition.
    pub spec: ModelSpec,
    /// Number of modes nearest the shift (lowest, by default), or a band in Hz.
    pub target: ModalTarget,
    /// Shift in Hz (negative means a negative λ shift, −(2πf)²); `None` for the default.
    pub shift_hz: Option<f64>,
    /// Lanczos block size.
    pub block: usize,
    /// Fill-reducing ordering.
    pub ordering: Ordering,
    /// Refuse to factorise if the factor would need more than this many bytes.
    pub max_memory: Option<u64>,
    /// Limit on eigen-iteration work (operator applications).
    pub max_applications: usize,
}

impl Default for ModalOptions {
    fn default() -> Self {
        ModalOptions {
            spec: ModelSpec::default(),
            target: ModalTarget::Modes(12),
            shift_hz: None,
            block: 6,
            ordering: Ordering::Metis,
            max_memory: None,
            max_applications: 20_000,
        }
    }
}

/// Which modes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ModalTarget {
    /// The lowest N modes (rigid-body modes included), or the N nearest a user shift.
    Modes(usize),
    /// All modes with frequency in [lo, hi] Hz.
    Band(f64, f64),
}

/// One mode of the report.
#[derive(Clone, Debug, Serialize)]
pub struct ModeRow {
    /// 1-based mode number (rigid-body modes first, as commercial codes number them).
    pub mode: usize,
    /// Frequency in Hz.
    pub frequency_hz: f64,
    /// Eigenvalue ω² (rad²/s²).
    pub eigenvalue: f64,
    /// `"rigid"` or `"elastic"`.
    pub kind: &'static str,
    /// Relative residual ‖Kx − λMx‖/‖Kx‖ (rigid-body modes: relative to the elastic scale).
    pub rel_residual: f64,
    /// Backward error ‖Kx − λMx‖ / (‖|K||x|‖ + |λ|‖|M||x|‖), the acceptance test.
    pub backward_error: f64,
    /// Participation factors (X, Y, Z, RX, RY, RZ).
    pub participation: [f64; 6],
    /// Effective masses (kg, kg·m²).
    pub effective_mass: [f64; 6],
    /// Cumulative effective-mass ratio after this mode.
    pub cumulative_ratio: [f64; 6],
}

/// Wall time per phase, seconds.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Timings {
    /// Reading the mesh.
    pub read: f64,
    /// Building the model, pattern and K, M.
    pub assemble: f64,
    /// Ordering and symbolic factorisation.
    pub order: f64,
    /// Numeric factorisation of K − σM.
    pub factor: f64,
    /// Lanczos iteration.
    pub solve: f64,
    /// Residuals, orthonormality and Sturm counts.
    pub verify: f64,
    /// Post-processing (participation).
    pub post: f64,
    /// Total.
    pub total: f64,
}

/// Bytes of the large allocations of a modal run, by phase. The mesh, the model and K, M live
/// through the run; the node graph and the element scratch of the assembly are freed before the
/// factorisation; K − σM and the factorisation scratch exist only while one factorisation is
/// computed (never two factors at once); the solve workspaces and the Lanczos basis coexist
/// with one factor.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct MemoryByPhase {
    /// Node coordinates and element connectivity of the model.
    pub mesh: u64,
    /// K's sparsity pattern and values, and M's values with its own pattern (its nonzeros).
    pub k_and_m: u64,
    /// Values of one LDLᵀ factor while it is factorised (faer's layout).
    pub factor: u64,
    /// The factor packed for the solves (what the iteration holds).
    pub factor_packed: u64,
    /// K − σM while it is factorised.
    pub shifted_matrix: u64,
    /// Scratch of the numeric factorisation.
    pub factor_workspace: u64,
    /// Solve workspaces kept with the factor.
    pub solve_workspace: u64,
    /// Lanczos basis, the next block's M-image and the projected matrix.
    pub lanczos_basis: u64,
}

/// Everything a modal run reports (the `--json` document).
#[derive(Clone, Debug, Serialize)]
pub struct ModalReport {
    /// Mesh file.
    pub mesh: String,
    /// Nodes in the mesh.
    pub nodes: usize,
    /// Cells of the model per kind (solids, shells, beams).
    pub cells: Vec<(String, usize)>,
    /// Free DOFs (equations).
    pub dofs: usize,
    /// Total volume, m³.
    pub volume_m3: f64,
    /// Total mass, kg.
    pub mass_kg: f64,
    /// `"consistent"` or `"lumped"`.
    pub mass_matrix: &'static str,
    /// Shift used, λ units.
    pub shift: f64,
    /// Frequencies of all reported modes, Hz, ascending.
    pub frequencies_hz: Vec<f64>,
    /// Number of rigid-body modes among them.
    pub n_rigid: usize,
    /// Per-mode rows.
    pub modes: Vec<ModeRow>,
    /// Sturm-sequence check.
    pub sturm: SturmCheck,
    /// No mode was missed.
    pub complete: bool,
    /// Every backward error below the verification tolerance, the modes M-orthonormal and
    /// the factorisations stable.
    pub accurate: bool,
    /// Largest relative residual.
    pub max_rel_residual: f64,
    /// Largest backward error (the acceptance test; tolerance 1e-10).
    pub max_backward_error: f64,
    /// max |XᵀMX − I|.
    pub m_orthonormality: f64,
    /// Worst backward error of a probe solve with the factorisations used (stability check).
    pub factor_backward_error: f64,
    /// Total participating mass per direction and the centre of mass.
    pub participation_total: [f64; 6],
    /// Centre of mass, m.
    pub centre_of_mass: [f64; 3],
    /// Phase timings.
    pub timings_s: Timings,
    /// Peak resident memory of the process, bytes (Linux VmHWM), if known.
    pub peak_memory_bytes: Option<u64>,
    /// The large allocations by phase, bytes.
    pub memory_bytes: MemoryByPhase,
    /// Flops of one numeric factorisation.
    pub factor_flops: f64,
    /// Achieved rate of the numeric factorisation itself (flops over the mean time of the
    /// run's numeric factorisations), GFLOP/s.
    pub factor_gflops: f64,
    /// Entries of the factor L.
    pub factor_nnz: usize,
    /// Numeric factorisations done (shift plus Sturm points).
    pub factorizations: usize,
    /// Operator applications (vectors) in the iteration.
    pub operator_applications: usize,
    /// Each phase against its floor (factorisation flops at the measured DGEMM rate, bytes
    /// of factor read by the block solves at the measured bandwidth, operator applications per
    /// mode); `None` when another engine solved.
    pub floor: Option<FloorReport>,
    /// Notes and warnings for the user.
    pub notes: Vec<String>,
}

impl ModalReport {
    /// Frequencies of the elastic (non-rigid-body) modes, ascending, Hz.
    pub fn elastic_frequencies(&self) -> Vec<f64> {
        self.modes
            .iter()
            .filter(|m| m.kind == "elastic")
            .map(|m| m.frequency_hz)
            .collect()
    }
}

/// A modal solution with its shapes, for writers.
pub struct ModalRun {
    /// The report.
    pub report: ModalReport,
    /// Mode shapes expanded to nodes: per mode, 3 components per node (node-major), M-normalised.
    pub shapes: Vec<Vec<f64>>,
    /// Eigenvalues ω² (rad²/s²), ascending.
    pub lambda: Vec<f64>,
    /// M-normalised eigenvectors over the free DOFs (one column per mode; see
    /// [`crate::dof::DofMap`] for the DOF of each row).
    pub vectors: faer::Mat<f64>,
    /// The model solved (for the result files: its cells and the vectors' rotations); `None`
    /// for a run made without one (the design's reduced basis).
    pub model: Option<std::sync::Arc<Model>>,
}

pub use crate::system::check_memory;
pub use crate::util::memory::{available_memory, peak_memory};

impl ModalOptions {
    /// How to build the system for this analysis.
    pub fn system_options(&self) -> SystemOptions {
        SystemOptions {
            ordering: self.ordering,
            max_memory: self.max_memory,
            mass: true,
            // The lowest modes (no shift) start from the corner space's Galerkin model.
            coarse_model: matches!(self.target, ModalTarget::Modes(_)) && self.shift_hz.is_none(),
        }
    }

    /// The eigen-solve parameters.
    pub fn params(&self) -> ModalParams {
        ModalParams {
            target: self.target,
            shift_hz: self.shift_hz,
            block: self.block,
            max_applications: self.max_applications,
        }
    }
}

/// What a modal solve on an assembled [`System`] computes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModalParams {
    /// Number of modes nearest the shift (lowest, by default), or a band in Hz.
    pub target: ModalTarget,
    /// Shift in Hz (negative means a negative λ shift, −(2πf)²); `None` for the default.
    pub shift_hz: Option<f64>,
    /// Lanczos block size.
    pub block: usize,
    /// Limit on eigen-iteration work (operator applications).
    pub max_applications: usize,
}

impl Default for ModalParams {
    fn default() -> Self {
        ModalOptions::default().params()
    }
}

/// Run a modal analysis on a mesh already in memory: build the model and its [`System`], then
/// [`solve`]. `source` names the mesh in messages; `read_time` (s) is reported as the read phase.
pub fn run_modal(mesh: &Mesh, source: &str, opts: &ModalOptions, read_time: f64) -> Result<ModalRun> {
    let t = Instant::now();
    let model = Model::build(mesh, &opts.spec, source)?;
    let t_model = t.elapsed().as_secs_f64();
    let sys = System::build(model, &opts.system_options(), source)?;
    let mut run = solve(&sys, &opts.params())?;
    let tm = &mut run.report.timings_s;
    tm.read = read_time;
    tm.assemble += t_model;
    tm.total += read_time + t_model;
    retime_floor(&mut run.report);
    Ok(run)
}

/// The floor report's phases timed around the solve (reading, assembly and ordering, the whole
/// run) from the report's timings, once the caller has added its own phases to them.
pub fn retime_floor(report: &mut ModalReport) {
    let tm = &report.timings_s;
    let (read, assemble_and_order, total) = (tm.read, tm.assemble.max(tm.order), tm.total);
    if let Some(f) = report.floor.as_mut() {
        f.retime(read, assemble_and_order, total);
    }
}

/// Natural frequencies and mode shapes of an assembled system, verified: residuals,
/// M-orthonormality, a Sturm count and the backward error of every factorisation.
pub fn solve(sys: &System, opts: &ModalParams) -> Result<ModalRun> {
    let t_all = Instant::now();
    let mut tm = Timings {
        assemble: sys.timings.assemble,
        order: sys.timings.order,
        ..Default::default()
    };
    let k_mat = sys.k();
    let m_mat = sys.m()?;
    let sym = sys.symbolic()?;
    check_params(opts)?;
    let target = match opts.target {
        ModalTarget::Modes(n) => Target::Nearest(n),
        ModalTarget::Band(lo, hi) => Target::Band(lambda_of_hz(lo), lambda_of_hz(hi)),
    };
    let iterating = eigen::Signal::default();
    let params = EigenParams {
        target,
        shift: opts.shift_hz.map(lambda_of_hz),
        block: opts.block,
        max_applications: opts.max_applications,
        null_candidates: Some(rigid_candidates(sys.model())),
        iterating: Some(iterating.clone()),
        ..Default::default()
    };
    // The post-processing's model part (the parts, their free motions, the rigid-body vectors'
    // images) is formed beside the iteration, on a thread of least priority: it fills the cores
    // the iteration leaves idle (~1.7 of 2 busy on the 119k-DOF plate) and takes ~0.1 s off
    // the post-processing there. It waits for the iteration with the last factorisation (not
    // to compete with the factorisation or with the prefault of its factor); when the solve
    // takes another path, or fails, it is called off and formed in the post-processing.
    let model = sys.model();
    let (sol, basis) = std::thread::scope(|s| {
        let basis = s.spawn(|| {
            if !iterating.wait() {
                return None;
            }
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .start_handler(|_| crate::util::memory::lower_thread_priority())
                .build()
                .ok()?;
            Some(pool.install(|| PostBasis::new(k_mat, m_mat, model)))
        });
        let off = iterating.off_on_drop();
        let sol = eigen::solve_with_prepared(k_mat, m_mat, sym, &params, sys.coarse_space(), sys.take_coarse_model());
        drop(off);
        // A panic in the background leaves the post-processing to form it itself.
        (sol, basis.join().ok().flatten())
    });
    let mut sol = sol.map_err(|e| e.locate(|eq| sys.describe_equation(eq)))?;
    // A request for at most the rigid-body modes of a free body iterates for them: reported as
    // a deflating solve reports them.
    if let Some(c) = &params.null_candidates {
        canonical_rigid(k_mat, m_mat, c, &mut sol);
    }
    tm.factor = sol.time_factor;
    tm.solve = sol.time_iterate;
    tm.verify = sol.time_verify;
    finish_with(sys, sol, tm, t_all, params.verify_tol, basis)
}

/// What the post-processing needs of the model alone, whatever the modes: the participation
/// factors' rigid-body basis and the connected parts with their free motions.
struct PostBasis {
    participation: ParticipationBasis,
    rigid: RigidParts,
}

impl PostBasis {
    /// Both parts for the model of `k`, `m`, side by side.
    fn new(k: &SymMatrix, m: &SymMatrix, model: &Model) -> Self {
        let (participation, rigid) = rayon::join(
            || ParticipationBasis::new(m, &model.dofs, &model.nodes),
            || RigidParts::new(k, m, &model.dofs, &model.nodes),
        );
        PostBasis { participation, rigid }
    }
}

/// [`eigen::canonical_null_pairs`] on `sol`, verified again when replaced: the rigid-body pairs
/// in the same form whichever path or engine found them.
pub(crate) fn canonical_rigid(
    k: &crate::linalg::sparse::SymMatrix,
    m: &crate::linalg::sparse::SymMatrix,
    cand: &eigen::NullCandidates,
    sol: &mut eigen::EigenSolution,
) {
    if eigen::canonical_null_pairs(k, m, cand, &mut sol.lambda, &mut sol.vectors) {
        let (res, orth, back) = eigen::verify_with_backward_errors(k, m, &sol.lambda, sol.vectors.as_ref(), sol.shift);
        sol.rel_residual = res;
        sol.m_orthonormality = orth;
        sol.backward_error = back;
    }
}

/// The six rigid-body motions about the centre of the nodes' bounding box, offered to the
/// eigen solver as candidates for K's null space (it keeps those that are: a free model's).
pub(crate) fn rigid_candidates(model: &crate::model::Model) -> eigen::NullCandidates {
    let (lo, hi) = crate::mesh::bounding_box(&model.nodes);
    let c: [f64; 3] = std::array::from_fn(|d| 0.5 * (lo[d] + hi[d]));
    eigen::NullCandidates(std::sync::Arc::new(crate::post::modal::rigid_vectors(
        &model.dofs,
        &model.nodes,
        c,
    )))
}

/// Whether `f` Hz can be a shift or a band end: finite, with its eigenvalue (2πf)² finite.
pub fn usable_hz(f: f64) -> bool {
    f.is_finite() && lambda_of_hz(f).is_finite()
}

/// Check the numbers of a modal request before any work: a shift and a band whose eigenvalues
/// (2πf)² are finite ([`usable_hz`]), a band from low to high, at least one mode. Errors name
/// the option.
pub fn check_params(params: &ModalParams) -> Result<()> {
    let usable = usable_hz;
    // As typed for ordinary values; 1e300 as 1e300, not as 301 digits.
    let show = crate::io::fmt_plain;
    if let Some(f) = params.shift_hz {
        if !usable(f) {
            return Err(Error::option(
                "--shift",
                format!(
                    "--shift: {} Hz is not a usable frequency (finite, with (2πf)² representable)",
                    show(f)
                ),
            ));
        }
    }
    match params.target {
        ModalTarget::Modes(0) => Err(Error::option("--modes", "--modes must be at least 1")),
        ModalTarget::Modes(_) => Ok(()),
        ModalTarget::Band(lo, hi) if !usable(lo) || !usable(hi) => Err(Error::option(
            "--band",
            format!(
                "--band: [{}, {}] Hz is not a usable band (finite, with (2πf)² representable)",
                show(lo),
                show(hi)
            ),
        )),
        ModalTarget::Band(lo, hi) if !(lo < hi) => Err(Error::option(
            "--band",
            format!(
                "--band: lower frequency {} must be below the upper {}",
                show(lo),
                show(hi)
            ),
        )),
        ModalTarget::Band(..) => Ok(()),
    }
}

/// The report of a verified eigen solution of `sys` (from [`eigen::solve`], or from another
/// engine whose pairs were verified here): participation, rigid-body modes, shapes at the
/// nodes, notes. `tm` holds the phases timed so far; `t_all` started the solve.
pub fn finish(
    sys: &System,
    sol: eigen::EigenSolution,
    tm: Timings,
    t_all: Instant,
    verify_tol: f64,
) -> Result<ModalRun> {
    finish_with(sys, sol, tm, t_all, verify_tol, None)
}

/// [`finish`] with the model's part of the post-processing formed already (`None`: formed
/// here).
fn finish_with(
    sys: &System,
    sol: eigen::EigenSolution,
    mut tm: Timings,
    t_all: Instant,
    verify_tol: f64,
    basis: Option<PostBasis>,
) -> Result<ModalRun> {
    let model = sys.model();
    let m_mat = sys.m()?;
    let k_mat = sys.k();
    let t = Instant::now();
    // Participation; rigid-body modes: shapes in the span of the free rigid motions of the
    // model's connected parts (they come first); the shapes at the nodes. Independent, side by
    // side, after the model's part when it was not formed beside the iteration (its parts'
    // search is sequential: 0.04 s of its 0.1 s at 119k DOFs).
    let ((part, parts), shapes) = rayon::join(
        || {
            let basis = basis.unwrap_or_else(|| PostBasis::new(k_mat, m_mat, model));
            rayon::join(
                || participation_of(&basis.participation, sol.vectors.as_ref()),
                || rigid_analysis_of(m_mat, &basis.rigid, sol.vectors.as_ref()),
            )
        },
        || node_shapes(model, &sol),
    );
    let n_rigid = parts.rigid.iter().take_while(|&&r| r).count();
    let modes = mode_rows(&sol, &part, &parts);
    tm.post = t.elapsed().as_secs_f64();
    tm.total = t_all.elapsed().as_secs_f64() + sys.timings.wall;
    let (volume, solid_mass) = model.volume_and_mass()?;
    let discrete_mass = model.discrete_mass();
    let mass = solid_mass + discrete_mass;

    let max_res = sol.rel_residual.iter().fold(0.0f64, |a, &b| max_nan(a, b));
    let max_back = sol.backward_error.iter().fold(0.0f64, |a, &b| max_nan(a, b));
    let verified = max_back <= verify_tol && sol.m_orthonormality <= 1e-8 && sol.factor_backward_error <= 1e-8;
    let rounding = sys.k_is_assembled().then(|| rounding_note(&modes)).flatten();
    let accurate = verified && rounding.is_none();
    let mut notes = solution_notes(model, &sol, &parts, &modes, verify_tol, verified);
    notes.extend(rounding);
    notes.extend(mass_contrast_note(solid_mass, discrete_mass, accurate));
    // The factorisation this process analysed (none when another engine solved).
    let (factor_flops, factor_nnz) = sys.symbolic().map_or((0.0, 0), |s| (s.flops, s.nnz_l));
    let memory_bytes = memory_by_phase(sys, &sol)?;
    let floor = floor_report(&sol, factor_flops, &tm);
    let report = ModalReport {
        mesh: sys.source().to_string(),
        nodes: model.n_mesh_nodes,
        cells: model
            .cell_counts()
            .iter()
            .map(|(k, n)| (k.name().to_string(), *n))
            .collect(),
        dofs: model.dofs.n_free,
        volume_m3: volume,
        mass_kg: mass,
        mass_matrix: model.spec.lumping.name(),
        shift: sol.shift,
        frequencies_hz: sol.lambda.iter().map(|&l| hz(l)).collect(),
        n_rigid,
        modes,
        complete: sol.sturm.complete,
        sturm: sol.sturm,
        accurate,
        max_rel_residual: max_res,
        max_backward_error: max_back,
        m_orthonormality: sol.m_orthonormality,
        factor_backward_error: sol.factor_backward_error,
        participation_total: part.total,
        centre_of_mass: part.centre_of_mass,
        timings_s: tm.clone(),
        peak_memory_bytes: peak_memory(),
        memory_bytes,
        factor_flops,
        // The factorisation itself: flops over the mean time of the run's numeric factorisations.
        factor_gflops: if sol.memory.numeric_seconds > 0.0 {
            factor_flops * sol.memory.numeric_count as f64 / sol.memory.numeric_seconds / 1e9
        } else {
            0.0
        },
        factor_nnz,
        factorizations: sol.factorizations,
        operator_applications: sol.applications,
        floor,
        notes,
    };
    Ok(ModalRun {
        report,
        shapes,
        lambda: sol.lambda,
        vectors: sol.vectors,
        model: Some(sys.model_arc().clone()),
    })
}

/// The run's phases against their floors ([`FloorReport`]), when this process factorised.
fn floor_report(sol: &eigen::EigenSolution, factor_flops: f64, tm: &Timings) -> Option<FloorReport> {
    let mem = &sol.memory;
    if mem.numeric_count == 0 || factor_flops <= 0.0 {
        return None;
    }
    Some(FloorReport::new(&RunWork {
        factor_flops,
        factorisations: mem.numeric_count,
        factor_seconds: mem.numeric_seconds,
        solves: mem.solves,
        read: mem.read_rate,
        applications: sol.applications,
        modes: sol.lambda.len(),
        iteration: mem.iteration,
        phases: [
            tm.read,
            tm.assemble,
            tm.order,
            tm.factor,
            tm.solve,
            tm.verify,
            tm.post,
            tm.total,
        ],
    }))
}

/// One row per mode: frequency, rigid or elastic, verification, participation.
fn mode_rows(
    sol: &eigen::EigenSolution,
    part: &ParticipationTable,
    parts: &crate::post::modal::RigidAnalysis,
) -> Vec<ModeRow> {
    let mut modes = Vec::with_capacity(sol.lambda.len());
    for (i, &l) in sol.lambda.iter().enumerate() {
        modes.push(ModeRow {
            mode: i + 1,
            frequency_hz: hz(l),
            eigenvalue: l,
            kind: if parts.rigid[i] { "rigid" } else { "elastic" },
            rel_residual: sol.rel_residual[i],
            backward_error: sol.backward_error[i],
            participation: part.modes[i].factor,
            effective_mass: part.modes[i].effective,
            cumulative_ratio: part.cumulative_ratio[i],
        });
    }
    modes
}

/// The mode shapes at the mesh nodes: 3 translations per node, node-major, one per mode.
fn node_shapes(model: &crate::model::Model, sol: &eigen::EigenSolution) -> Vec<Vec<f64>> {
    let n_mesh = model.n_mesh_nodes;
    (0..sol.vectors.ncols())
        .map(|c| {
            let mut s = model.dofs.expand(&eigen::column(&sol.vectors, c), 3);
            s.truncate(3 * n_mesh);
            s
        })
        .collect()
}

/// Point masses at least this many times the elements' mass make a failed accuracy check
/// likely the contrast's: a clamped hex20 cantilever verifies with a tip mass up to 6e9 times
/// its own (6e12: backward error 2e-7; 6e30: 1); the 20k-DOF tet10 plate on a coupled face with
/// springs verifies at 9e5 and not at 9e8 (backward error 1.2e-8).
const MASS_CONTRAST: f64 = 1e8;

/// Why accuracy was not reached, when point masses outweigh the elements by [`MASS_CONTRAST`]
/// or more (the large-mass method needs about 1e6; a larger ratio is often a unit slip).
fn mass_contrast_note(elements: f64, discrete: f64, accurate: bool) -> Option<String> {
    let ratio = discrete / elements;
    (!accurate && elements > 0.0 && ratio >= MASS_CONTRAST).then(|| {
        format!(
            "the point masses ({discrete:.3e} kg) are {ratio:.1e} times the mass of the elements ({elements:.3e} kg): \
             at such a contrast double precision may not resolve the modes of the structure beside them. \
             The large-mass method needs about 1e6 times; check the units of --point-mass"
        )
    })
}

/// The note for elastic modes with negative eigenvalues of an assembled K (positive
/// semidefinite in exact arithmetic): their values are the rounding of an ill-conditioned
/// model, and every mode as low as their magnitude is unresolved. The run is then not
/// verified: a backward-stable pair of the rounded K, Kx = λMx to 1e-16, still says nothing of
/// the structure's frequency (a 1 µm wide shell strip gives −14…−2.5 Hz for its rigid-body
/// motions and first bending mode, 1.5 Hz).
fn rounding_note(modes: &[ModeRow]) -> Option<String> {
    let negative: Vec<&ModeRow> = modes
        .iter()
        .filter(|m| m.kind == "elastic" && m.eigenvalue < 0.0)
        .collect();
    let noise = negative.iter().map(|m| -m.eigenvalue).fold(0.0, f64::max);
    (noise > 0.0).then(|| {
        let below = modes
            .iter()
            .filter(|m| m.kind == "elastic" && m.eigenvalue.abs() <= 10.0 * noise)
            .count();
        format!(
            "{} mode(s) have negative eigenvalues (down to {:.3e} rad²/s²), which K as assembled cannot have: \
             they are the rounding of an ill-conditioned model, and the {below} elastic mode(s) below {:.4} Hz \
             (ten times that eigenvalue) are not resolved; rigid-body motions among them are not recognised. \
             Slender or thin parts (elements much narrower than long), or stiffness contrasts of many orders: \
             coarsen across the thin direction, or model rigid parts with --couple",
            negative.len(),
            -noise,
            (10.0 * noise).sqrt() / std::f64::consts::TAU
        )
    })
}

/// The report's notes: the model's and the solver's, free parts, and what limits the accuracy
/// (backward error, conditioning, an unstable factorisation, a failed Sturm check).
fn solution_notes(
    model: &crate::model::Model,
    sol: &eigen::EigenSolution,
    parts: &crate::post::modal::RigidAnalysis,
    modes: &[ModeRow],
    verify_tol: f64,
    accurate: bool,
) -> Vec<String> {
    let max_res = sol.rel_residual.iter().fold(0.0f64, |a, &b| max_nan(a, b));
    let max_back = sol.backward_error.iter().fold(0.0f64, |a, &b| max_nan(a, b));
    let mut notes = model.notes.clone();
    notes.extend(sol.notes.iter().cloned());
    notes.extend(free_part_notes(model, parts));
    if !accurate {
        notes.push(format!(
            "accuracy not guaranteed: largest backward error {max_back:.2e} (tolerance {:.0e}; relative residual {max_res:.2e}), M-orthonormality error {:.2e} (tolerance 1e-8), factorisation probe backward error {:.1e} (tolerance 1e-8)",
            verify_tol, sol.m_orthonormality, sol.factor_backward_error
        ));
    }
    // The backward error accepts what the data allow; how far that is from the exact modes
    // depends on the conditioning, which the residual relative to ‖Kx‖ measures (to first
    // order it bounds the relative error of λ). Say so when that exceeds the old 1e-6 criterion.
    let max_res_elastic = modes
        .iter()
        .filter(|m| m.kind == "elastic")
        .fold(0.0f64, |a, m| max_nan(a, m.rel_residual));
    if accurate && max_res_elastic > 1e-6 {
        notes.push(format!(
            "ill-conditioned model: the modes are backward stable (backward error {max_back:.1e}), but residuals \
             relative to ‖Kx‖ reach {max_res_elastic:.1e}, which bounds the relative error of the eigenvalues \
             (slender or thin parts; stiffness contrasts: model rigid parts with --couple)"
        ));
    }
    // (NaN, a probe that overflowed — stiffnesses near 1e300 — is unstable too.)
    if !(sol.factor_backward_error <= 1e-8) {
        notes.push(format!(
            "a factorisation of K − σM is unstable (probe backward error {:.1e}, pivot growth or overflow: \
             stiffnesses of extreme magnitude?): results may be wrong",
            sol.factor_backward_error
        ));
    }
    if !sol.sturm.complete && sol.sturm.expected == sol.sturm.found && sol.sturm.lower.1 > 0 {
        notes.push(format!(
            "Sturm check: {} eigenvalue(s) lie below the lowest mode found ({:.6e} rad²/s², {:.4} Hz): the modes \
             listed are not the lowest (a preload past buckling has its lowest far below zero); ask for at least {} \
             modes (--modes) to have them",
            sol.sturm.lower.1,
            sol.sturm.lower.0,
            crate::post::modal::hz(sol.sturm.lower.0),
            sol.sturm.upper.1
        ));
    } else if !sol.sturm.complete {
        notes.push(format!(
            "Sturm check failed: {} modes expected between {:.6e} and {:.6e} rad²/s², {} found",
            sol.sturm.expected, sol.sturm.lower.0, sol.sturm.upper.0, sol.sturm.found
        ));
    }
    notes
}

/// The memory of each phase: the mesh (coordinates and connectivity), K and M, and the
/// solver's buffers.
fn memory_by_phase(sys: &System, sol: &eigen::EigenSolution) -> Result<MemoryByPhase> {
    let model = sys.model();
    let (k_mat, m_mat) = (sys.k(), sys.m()?);
    Ok(MemoryByPhase {
        mesh: {
            let sets = model.element_sets();
            let conn: usize = sets
                .iter()
                .map(|s| (0..s.len()).map(|e| s.nodes(e).len()).sum::<usize>())
                .sum();
            (24 * model.nodes.len() + 4 * conn) as u64
        },
        k_and_m: {
            let pat = sys.pattern();
            (8 * pat.col_ptr.len() + 4 * pat.row_idx.len() + k_mat.value_bytes() + m_mat.bytes_beside(pat)) as u64
        },
        factor: sol.memory.factor,
        factor_packed: sol.memory.factor_packed,
        shifted_matrix: sol.memory.shifted_matrix,
        factor_workspace: sol.memory.factor_workspace,
        solve_workspace: sol.memory.solve_workspace,
        lanczos_basis: sol.memory.lanczos_basis,
    })
}

/// Notes naming the parts of a model that can move freely while others are supported (or that
/// are one of several separate free bodies): node count, one node, the element sets in them and
/// their free motions. A single free body has no note (its rigid modes are expected).
fn free_part_notes(model: &crate::model::Model, parts: &crate::post::modal::RigidAnalysis) -> Vec<String> {
    let any_fixed = model.dofs.fixed.iter().any(|&f| f != 0);
    if parts.free.is_empty() || (parts.n_parts == 1 && !any_fixed) {
        return vec![];
    }
    let sets = model.element_sets();
    parts
        .free
        .iter()
        .map(|p| {
            let mut inside = vec![false; model.nodes.len()];
            p.node_list.iter().for_each(|&a| inside[a] = true);
            let mut names: Vec<String> = Vec::new();
            for s in &sets {
                if (0..s.len()).any(|e| s.nodes(e).iter().any(|&a| inside[a as usize])) {
                    let g = s.group().to_string();
                    if !names.contains(&g) {
                        names.push(g);
                    }
                }
            }
            let node = model
                .node_tags
                .get(p.first_node)
                .map_or_else(|| format!("reference node #{}", p.first_node), |t| format!("node {t}"));
            let motions = if p.motions.len() == p.count {
                p.motions.join(", ")
            } else {
                format!("{} combined motions", p.count)
            };
            format!(
                "a part of {} nodes ({}; e.g. {node}) is not connected to the supports or the rest of the \
                 model: it moves freely in {motions}, and its {} rigid-body modes are labelled rigid; \
                 connect it (shared nodes, --couple, --spring) or support it",
                p.nodes,
                names.join(", "),
                p.count
            )
        })
        .collect()
}
