//! `vibrofem harmonic` and the scene's `[harmonic]`: steady-state response to harmonic group
//! forces at one frequency or over a sweep, per-group amplitude and phase, fields for ParaView and
//! gmsh, an FRF plot.
//!
//! Conventions: F(t) = Re(F̂ e^{iωt}), u(t) = Re(û e^{iωt}); amplitudes in m (reports in mm),
//! phases in degrees relative to a force of phase 0, frequencies in Hz. A group's response is the
//! mean of its nodes' complex displacements (its motion as one body); its `peak` is the largest
//! displacement over a period (the semi-major axis of the orbit), `max_node_peak` the largest of
//! its nodes'.

use crate::analysis::harmonic::{self, Damping, GroupForce};
use crate::analysis::modal::{ModalParams, ModalTarget};
use crate::mesh::Mesh;
use crate::system::System;
use crate::{Error, Result};
use faer::c64;
use serde::Serialize;
use std::time::Instant;

/// How the response is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Modal superposition with the static residual correction.
    Modal,
    /// Direct complex solve at every frequency.
    Direct,
    /// Both, with their difference reported.
    Both,
}

impl Method {
    /// `modal`, `direct` or `both`.
    pub fn parse(s: &str) -> Result<Method> {
        match s {
            "modal" => Ok(Method::Modal),
            "direct" => Ok(Method::Direct),
            "both" => Ok(Method::Both),
            _ => Err(Error::option(
                "--method",
                format!("--method: unknown method '{s}' (modal, direct or both)"),
            )),
        }
    }
}

/// What to compute.
#[derive(Clone, Debug)]
pub struct HarmonicRequest {
    /// The forces.
    pub forces: Vec<GroupForce>,
    /// Frequencies (Hz), ascending.
    pub freqs_hz: Vec<f64>,
    /// Damping.
    pub damping: Damping,
    /// Method.
    pub method: Method,
    /// Modes for the superposition: the N lowest; `None`: every mode below 2 × the highest
    /// frequency (at least 12 and the rigid-body modes).
    pub modes: Option<usize>,
    /// Groups reported (and plotted); empty: the loaded groups.
    pub probes: Vec<String>,
}

/// Frequencies of a sweep: `n` points from `f0` to `f1` Hz, evenly spaced.
pub fn sweep_frequencies(f0: f64, f1: f64, n: usize) -> Result<Vec<f64>> {
    use crate::io::fmt_sig;
    if !(f0.is_finite() && f1.is_finite() && f0 >= 0.0 && f1 > f0) {
        return Err(Error::option(
            "--sweep",
            format!(
                "--sweep: need 0 ≤ F0 < F1 (Hz), got {} {}",
                fmt_sig(f0, 4),
                fmt_sig(f1, 4)
            ),
        ));
    }
    if let Some(p) = frequency_problem(f1) {
        return Err(Error::option(
            "--sweep",
            format!("--sweep: F1 = {} Hz: {p}", fmt_sig(f1, 4)),
        ));
    }
    if n < 2 {
        return Err(Error::option(
            "--sweep",
            format!("--sweep: need at least 2 points, got {n}"),
        ));
    }
    if n > 100_000 {
        return Err(Error::option(
            "--sweep",
            format!("--sweep: {n} points is more than 100000"),
        ));
    }
    Ok((0..n).map(|i| f0 + (f1 - f0) * i as f64 / (n - 1) as f64).collect())
}

/// Amplitude and phase of one complex component.
#[derive(Clone, Debug, Serialize)]
pub struct Component {
    /// Amplitude |û| (m).
    pub amplitude_m: f64,
    /// Phase arg û (degrees).
    pub phase_deg: f64,
}

fn component(v: c64) -> Component {
    Component {
        amplitude_m: v.norm(),
        phase_deg: if v.norm() > 0.0 {
            v.im.atan2(v.re).to_degrees()
        } else {
            0.0
        },
    }
}

/// The response of one group at one frequency.
#[derive(Clone, Debug, Serialize)]
pub struct GroupResponse {
    /// Group name.
    pub group: String,
    /// Nodes averaged.
    pub nodes: usize,
    /// Mean motion: ux, uy, uz amplitude and phase.
    pub mean: [Component; 3],
    /// Peak displacement of the mean motion (m).
    pub peak_m: f64,
    /// Largest peak displacement of a node of the group (m).
    pub max_node_peak_m: f64,
    /// Smallest (m).
    pub min_node_peak_m: f64,
}

/// The response at one frequency.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// Frequency (Hz).
    pub freq_hz: f64,
    /// Reported groups.
    pub groups: Vec<GroupResponse>,
    /// Largest peak displacement of any node (m) and that node (0-based, as in the mesh).
    pub max_peak_m: f64,
    /// Node of `max_peak_m`.
    pub max_node: usize,
    /// With method `both`: ‖û_modal − û_direct‖ / ‖û_direct‖ over the free DOFs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modal_vs_direct: Option<f64>,
}

/// Phase times (s).
#[derive(Clone, Debug, Default, Serialize)]
pub struct HarmonicTimings {
    /// Modes for the superposition (factorisation, Lanczos, verification).
    pub modes: f64,
    /// Superposition, residual correction included.
    pub superpose: f64,
    /// Direct solves.
    pub direct: f64,
    /// Whole analysis after assembly.
    pub total: f64,
}

/// The analysis report.
#[derive(Clone, Debug, Serialize)]
pub struct HarmonicReport {
    /// Free DOFs.
    pub dofs: usize,
    /// Method used.
    pub method: Method,
    /// Damping in words.
    pub damping: String,
    /// The forces.
    pub forces: Vec<ForceRow>,
    /// Modes superposed (rigid-body modes included) and the highest (Hz).
    pub modes_used: usize,
    /// Frequency of the highest mode superposed (Hz).
    pub highest_mode_hz: Option<f64>,
    /// Frequencies of the modes superposed (Hz).
    pub mode_frequencies_hz: Vec<f64>,
    /// One entry per frequency.
    pub points: Vec<Point>,
    /// Remarks.
    pub notes: Vec<String>,
    /// Times.
    pub timings_s: HarmonicTimings,
    /// Peak resident memory of the process when the response was complete, bytes (Linux
    /// VmHWM), if known.
    pub peak_memory_bytes: Option<u64>,
}

/// A force as applied.
#[derive(Clone, Debug, Serialize)]
pub struct ForceRow {
    /// Group.
    pub group: String,
    /// Fx, Fy, Fz (N).
    pub force_n: [f64; 3],
    /// Phase (degrees).
    pub phase_deg: f64,
}

/// A run: the report and the nodal responses (per node [ux..rz]) kept for fields.
pub struct HarmonicRun {
    /// Report.
    pub report: HarmonicReport,
    /// Per kept frequency, per node: the complex displacement ([`Fields::All`]: every frequency,
    /// in order; [`Fields::Peak`]: the largest response's).
    pub nodal: Vec<Vec<[c64; 6]>>,
    /// Index in `report.points` of each entry of `nodal`.
    pub field_points: Vec<usize>,
}

fn damping_text(d: &Damping) -> String {
    match *d {
        Damping::Ratio(z) => format!("modal damping ratio ζ = {}", crate::io::fmt_sig(z, 4)),
        Damping::Rayleigh { alpha, beta } => format!(
            "Rayleigh C = αM + βK, α = {} 1/s, β = {} s",
            crate::io::fmt_sig(alpha, 4),
            crate::io::fmt_sig(beta, 4)
        ),
    }
}

/// Highest excitation frequency computed (Hz): (2π · 2f)², the top of the default modal band,
/// stays far from the overflow of double precision (1.8e308).
pub const MAX_FREQ_HZ: f64 = 1e150;

/// Modes below 2 × the highest frequency beyond which the default modal superposition is not
/// used: finding them all costs more than solving directly at a few frequencies.
pub const MAX_BAND_MODES: usize = 200;

/// Frequencies up to which a default modal request of more than [`MAX_BAND_MODES`] modes is
/// solved directly instead (a longer sweep is refused with the choices).
pub const DIRECT_MAX_FREQS: usize = 50;

/// What is wrong with an excitation frequency `f` (Hz), if anything (the caller names where it
/// was given).
pub fn frequency_problem(f: f64) -> Option<String> {
    if !(f.is_finite() && f >= 0.0) {
        return Some("a frequency must be a finite number ≥ 0 (Hz)".into());
    }
    if f > MAX_FREQ_HZ {
        return Some(format!(
            "above the highest frequency computed, {} Hz (beyond it (2πf)² nears the overflow of double \
             precision)",
            crate::io::fmt_sig(MAX_FREQ_HZ, 3)
        ));
    }
    None
}

/// The smallest damping ratio taken as damping: below it the amplification at a resonance,
/// 1/(2ζ), is above 5e8 and K − ω²M + iωC is singular to the rounding of its entries (a ζ of
/// 1e-300 gave 94 km by modes and 8.6e11 mm by the direct solve, both silently).
pub const MIN_DAMPING_RATIO: f64 = 1e-9;

/// Refuse damping that leaves a resonance infinite (ζ = 0, or α = β = 0, or a ratio below
/// [`MIN_DAMPING_RATIO`], for Rayleigh damping at every frequency of `freqs_hz`) besides what
/// [`Damping::validate`] refuses; `ratio` and `rayleigh` name the options (or keys) that set them.
pub fn check_damping(d: &Damping, ratio: &str, rayleigh: &str, freqs_hz: &[f64]) -> Result<()> {
    d.validate()?;
    if let Damping::Ratio(z) = *d
        && z > 0.0
        && z < MIN_DAMPING_RATIO
    {
        return Err(Error::option(
            ratio,
            format!(
                "{ratio} {z}: a damping ratio below {MIN_DAMPING_RATIO:e} is no damping in double precision (the \
                 response at a resonance, 1/(2ζ) times the static one, would be above 5e8 of it): give a ratio of \
                 a structure (0.001–0.05)"
            ),
        ));
    }
    if let Damping::Rayleigh { alpha, beta } = *d {
        let zeta = |f: f64| {
            let w = 2.0 * std::f64::consts::PI * f;
            if w > 0.0 {
                alpha / (2.0 * w) + beta * w / 2.0
            } else {
                f64::INFINITY
            }
        };
        let largest = freqs_hz.iter().map(|&f| zeta(f)).fold(0.0f64, f64::max);
        if (alpha > 0.0 || beta > 0.0) && !freqs_hz.is_empty() && largest < MIN_DAMPING_RATIO {
            return Err(Error::option(
                rayleigh,
                format!(
                    "{rayleigh} {alpha},{beta}: a damping ratio of at most {largest:.1e} at the frequencies asked, \
                     below {MIN_DAMPING_RATIO:e}: no damping in double precision; give α and β of a structure (e.g. \
                     0,1e-5)"
                ),
            ));
        }
    }
    match *d {
        Damping::Ratio(z) if z == 0.0 => Err(Error::option(
            ratio,
            format!(
                "{ratio} 0: no damping; the response at a resonance would be infinite: give a ratio > 0 (e.g. \
                 0.02)"
            ),
        )),
        Damping::Rayleigh { alpha, beta } if alpha == 0.0 && beta == 0.0 => Err(Error::option(
            rayleigh,
            format!(
                "{rayleigh} 0,0: no damping; the response at a resonance would be infinite: give α > 0 or β > 0 \
                 (e.g. 0,1e-5)"
            ),
        )),
        _ => Ok(()),
    }
}

/// Which nodal fields a run keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fields {
    /// Every frequency's (for a library caller's arrays); refused when they would need more than
    /// half the memory available.
    All,
    /// Only the field of the largest response (what the VTU and MSH outputs write): a sweep of
    /// any length needs the memory of one field.
    Peak,
}

/// Run the harmonic analysis on an assembled system, keeping every frequency's nodal field.
pub fn run(sys: &System, mesh: &Mesh, req: &HarmonicRequest) -> Result<HarmonicRun> {
    run_with(sys, mesh, req, Fields::All)
}

/// Run the harmonic analysis on an assembled system: check the request, build the load, pick
/// the method, find the modes it needs, then solve one frequency at a time (each point's report
/// rows are kept, its field only as `keep` says).
pub fn run_with(sys: &System, mesh: &Mesh, req: &HarmonicRequest, keep: Fields) -> Result<HarmonicRun> {
    let t_all = Instant::now();
    let probes = check_request(req)?;
    if keep == Fields::All {
        check_field_memory(sys, req.freqs_hz.len())?;
    }
    let mut notes = Vec::new();
    if let Damping::Ratio(z) = req.damping
        && z >= 1.0
    {
        // A percentage typed as the ratio (2 for 2 %) damps every mode critically or more.
        notes.push(format!(
            "damping ratio ζ = {}: every mode is critically damped or more (no resonance); ζ is a ratio \
             (0.02 for 2 %)",
            crate::io::fmt_plain(z)
        ));
    }
    let (load, scale) = scaled_load(sys, mesh, &req.forces, &mut notes)?;
    let probe_nodes = probe_nodes(sys, mesh, &probes, &mut notes)?;
    let mut tm = HarmonicTimings::default();
    let t = Instant::now();
    let (method, target) = plan(sys, req, &mut notes)?;
    let free = free_motions(sys, req, method)?;
    let modes = target
        .map(|target| modal_modes(sys, req, target, &mut notes))
        .transpose()?;
    let rigid = match method {
        Method::Modal => None,
        _ => rigid_basis(sys, modes.as_ref(), &free)?,
    };
    tm.modes = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let sup = modes
        .as_ref()
        .map(|m| harmonic::Superposition::new(sys, m, &load, &req.damping, true))
        .transpose()?;
    tm.superpose = t.elapsed().as_secs_f64();
    if method != Method::Modal
        && let Damping::Ratio(_) = req.damping
    {
        notes.push(
            "direct solve: the modal damping ratio ζ is taken as structural damping K(1 + 2iζ), equal to modal \
             damping at each resonance, not between them; give --rayleigh for a viscous damping matrix"
                .into(),
        );
    }
    let solver = Solver {
        sys,
        load: &load,
        scale,
        damping: &req.damping,
        sup,
        direct: method != Method::Modal,
        rigid,
    };
    let ctx = PointContext {
        sys,
        mesh,
        probes: &probes,
        probe_nodes: &probe_nodes,
        forces: &req.forces,
        free: free.count > 0 || modes.as_ref().is_some_and(|m| m.report.n_rigid > 0),
    };
    let mut points: Vec<Point> = Vec::with_capacity(req.freqs_hz.len());
    let (mut nodal, mut field_points) = (Vec::new(), Vec::new());
    for (k, &f) in req.freqs_hz.iter().enumerate() {
        let (modal_u, direct_u) = solver.at(std::f64::consts::TAU * f, &mut tm)?;
        let (point, full) = ctx.point(f, modal_u.as_deref(), direct_u.as_deref())?;
        let keep_this = match keep {
            Fields::All => true,
            Fields::Peak => field_points
                .first()
                .is_none_or(|&b: &usize| point.max_peak_m > points[b].max_peak_m),
        };
        if keep_this {
            if keep == Fields::Peak {
                nodal.clear();
                field_points.clear();
            }
            nodal.push(full);
            field_points.push(k);
        }
        points.push(point);
    }
    tm.total = t_all.elapsed().as_secs_f64();
    disagreement_note(&points, &mut notes);
    let mode_hz: Vec<f64> = modes.as_ref().map_or_else(Vec::new, |m| {
        m.lambda.iter().map(|&l| crate::post::modal::hz(l)).collect()
    });
    let report = HarmonicReport {
        dofs: sys.n_free(),
        method,
        damping: damping_text(&req.damping),
        forces: req
            .forces
            .iter()
            .map(|f| ForceRow {
                group: f.group.clone(),
                force_n: f.force,
                phase_deg: f.phase_deg,
            })
            .collect(),
        modes_used: mode_hz.len(),
        highest_mode_hz: mode_hz.last().copied(),
        mode_frequencies_hz: mode_hz,
        points,
        notes,
        timings_s: tm,
        peak_memory_bytes: crate::util::memory::peak_memory(),
    };
    Ok(HarmonicRun {
        report,
        nodal,
        field_points,
    })
}

/// The largest modal-vs-direct difference (`--method both`) above which a note says which to
/// trust: the superposition's truncation and its static correction are approximations, the
/// direct solve is exact for the model; 1 % is the accuracy a response is read to.
const MODAL_DIRECT_NOTE: f64 = 1e-2;

/// With both methods run: a note when they differ by more than [`MODAL_DIRECT_NOTE`] (the modal
/// response is the one tabulated).
fn disagreement_note(points: &[Point], notes: &mut Vec<String>) {
    let worst = points
        .iter()
        .filter_map(|p| p.modal_vs_direct.map(|d| (d, p.freq_hz)))
        .max_by(|a, b| a.0.total_cmp(&b.0));
    if let Some((d, f)) = worst.filter(|w| w.0 > MODAL_DIRECT_NOTE) {
        // The truncation note (if any) asked for this check: drop its advice, which is done.
        notes.retain(|n| !n.contains("check with --method both"));
        notes.push(format!(
            "modal superposition and the direct solve differ by up to {} % (at {} Hz): the direct solve is \
             exact for the model, the superposition is not here (modes missing above the ones superposed, or \
             damping too heavy for the static correction); take --method direct, or raise --modes",
            crate::io::fmt_sig(100.0 * d, 3),
            crate::io::fmt_sig(f, 4)
        ));
    }
}

/// Refuse a request without forces or frequencies, with a frequency out of range, without
/// damping or with `modes = 0`; the groups reported otherwise (the loaded ones by default).
fn check_request(req: &HarmonicRequest) -> Result<Vec<String>> {
    check_damping(&req.damping, "damping", "rayleigh", &req.freqs_hz)?;
    if req.forces.is_empty() {
        return Err(Error::param(
            "forces",
            "harmonic: no force given (--force GROUP=FX,FY,FZ[@PHASE_DEG])",
        ));
    }
    if req.freqs_hz.is_empty() {
        return Err(Error::param(
            "freqs_hz",
            "harmonic: no frequency given (--freq HZ or --sweep F0 F1 N)",
        ));
    }
    for &f in &req.freqs_hz {
        if let Some(p) = frequency_problem(f) {
            return Err(Error::param(
                "freqs_hz",
                format!("harmonic: frequency {} Hz: {p}", crate::io::fmt_sig(f, 4)),
            ));
        }
    }
    if req.modes == Some(0) {
        return Err(Error::param("modes", "--modes must be at least 1"));
    }
    Ok(if req.probes.is_empty() {
        let mut g: Vec<String> = Vec::new();
        for f in &req.forces {
            if !g.contains(&f.group) {
                g.push(f.group.clone());
            }
        }
        g
    } else {
        req.probes.clone()
    })
}

/// Refuse, before the work, a run keeping every frequency's field when they would take more than
/// half the memory available (the command line and scenes keep only the peak's).
fn check_field_memory(sys: &System, n_freqs: usize) -> Result<()> {
    // Per frequency and node: 6 complex displacements, and the caller's real and imaginary
    // copies of the translations.
    let per_freq = sys.dofs().n_nodes() as u64 * (96 + 48);
    let need = per_freq.saturating_mul(n_freqs as u64);
    let budget = crate::system::available_memory().unwrap_or(8 << 30) / 2;
    if need > budget {
        return Err(Error::param(
            "freqs_hz",
            format!(
                "harmonic: the fields of {n_freqs} frequencies on {} nodes need about {} (more than half of the {} \
                 available): fewer frequencies, or the report alone (the command line and scenes keep one field)",
                sys.dofs().n_nodes(),
                crate::io::fmt_bytes(need),
                crate::io::fmt_bytes(budget * 2)
            ),
        ));
    }
    Ok(())
}

/// Nodes of each probe that the model uses: a coupled group answers with its reference node;
/// nodes of no element are left out of the mean (with a note), a group with none is refused.
fn probe_nodes(sys: &System, mesh: &Mesh, probes: &[String], notes: &mut Vec<String>) -> Result<Vec<Vec<usize>>> {
    let model = sys.model();
    let dofs = sys.dofs();
    let mut out = Vec::new();
    for g in probes {
        if let Some(r) = model.references.iter().find(|r| &r.group == g) {
            out.push(vec![r.node]);
            continue;
        }
        let all: Vec<usize> = mesh.group_nodes(mesh.group(g)?).iter().map(|&a| a as usize).collect();
        if all.is_empty() {
            return Err(Error::group(g.as_str(), format!("harmonic: group '{g}' has no nodes")));
        }
        let used: Vec<usize> = all
            .iter()
            .copied()
            .filter(|&a| dofs.active.get(a).is_some_and(|&m| m != 0))
            .collect();
        if used.is_empty() {
            return Err(Error::group(
                g.as_str(),
                format!(
                    "harmonic: none of the {} nodes of group '{g}' belongs to an element of the model: it has no \
                     response to report",
                    all.len()
                ),
            ));
        }
        if used.len() < all.len() {
            notes.push(format!(
                "group '{g}': {} of its {} nodes belong to no element of the model and are left out of its mean \
                 motion",
                all.len() - used.len(),
                all.len()
            ));
        }
        out.push(used);
    }
    Ok(out)
}

/// The free-DOF load of the forces divided by a power of two near its largest entry (exact: the
/// response is scaled back exactly), so that huge forces overflow only where the response does.
fn scaled_load(sys: &System, mesh: &Mesh, forces: &[GroupForce], notes: &mut Vec<String>) -> Result<(Vec<c64>, f64)> {
    let mut load = harmonic::group_load(sys, mesh, forces)?;
    let loads: Vec<crate::analysis::statics::Load> = forces
        .iter()
        .map(|f| crate::analysis::statics::Load::Force {
            group: f.group.clone(),
            force: f.force,
        })
        .collect();
    notes.extend(crate::analysis::statics::load_notes(mesh, sys.model(), &loads));
    let big = load.iter().map(|v| v.re.abs().max(v.im.abs())).fold(0.0, f64::max);
    if big == 0.0 {
        return Err(Error::param(
            "forces",
            "harmonic: the forces are all zero on the free degrees of freedom",
        ));
    }
    let scale = 2f64.powi(big.log2().floor() as i32);
    if scale.is_finite() && scale >= f64::MIN_POSITIVE && scale != 1.0 {
        for v in &mut load {
            *v /= scale;
        }
        return Ok((load, scale));
    }
    Ok((load, 1.0))
}

/// The method and the modes asked of the modal solve. By default (`modes` not given) every mode
/// below 2 × the highest frequency is superposed; when that band holds more than
/// [`MAX_BAND_MODES`] (a Sturm count, one factorisation), a short list of frequencies is solved
/// directly, `both` superposes the [`MAX_BAND_MODES`] lowest, a long sweep is refused.
fn plan(sys: &System, req: &HarmonicRequest, notes: &mut Vec<String>) -> Result<(Method, Option<ModalTarget>)> {
    if req.method == Method::Direct {
        return Ok((Method::Direct, None));
    }
    let fmax = req.freqs_hz.iter().copied().fold(0.0, f64::max);
    let top = (2.0 * fmax).max(1.0);
    if let Some(n) = req.modes {
        return Ok((req.method, Some(ModalTarget::Modes(n))));
    }
    let band = ModalTarget::Band(-1.0, top);
    if sys.n_free() <= crate::linalg::eigen::EigenParams::default().dense_below {
        return Ok((req.method, Some(band)));
    }
    let Some(count) = modes_below(sys, top) else {
        return Ok((req.method, Some(band)));
    };
    if count <= MAX_BAND_MODES {
        return Ok((req.method, Some(band)));
    }
    let fs = crate::io::fmt_sig(top, 4);
    let nf = req.freqs_hz.len();
    match req.method {
        Method::Both => {
            notes.push(format!(
                "{count} modes lie below {fs} Hz (2 × the highest frequency): the superposition uses the \
                 {MAX_BAND_MODES} lowest with the static correction, the direct solve checks it"
            ));
            Ok((Method::Both, Some(ModalTarget::Modes(MAX_BAND_MODES))))
        }
        _ if nf <= DIRECT_MAX_FREQS => {
            notes.push(format!(
                "{count} modes lie below {fs} Hz (2 × the highest frequency), more than {MAX_BAND_MODES}: solved \
                 directly at the {nf} frequenc{} instead of superposing them (--modes N superposes the N lowest)",
                if nf == 1 { "y" } else { "ies" }
            ));
            Ok((Method::Direct, None))
        }
        _ => Err(Error::option(
            "--method",
            format!(
                "harmonic: {count} modes lie below {fs} Hz (2 × the highest frequency), more than \
                 {MAX_BAND_MODES}: finding them all would take longer than the sweep; give --modes N to superpose \
                 the N lowest with the static correction, or --method direct ({nf} complex solves)"
            ),
        )),
    }
}

/// Number of eigenvalues below `hz` (Hz): the inertia of K − (2π hz)² M. `None` if that
/// factorisation fails (the modal solve then reports the problem).
fn modes_below(sys: &System, hz: f64) -> Option<usize> {
    let lam = (std::f64::consts::TAU * hz).powi(2);
    let fac =
        crate::linalg::factor::Factor::new_shifted(sys.symbolic().ok()?.clone(), sys.k(), Some((sys.m().ok()?, lam)))
            .ok()?;
    Some(fac.negative_pivots)
}

/// The free rigid motions of the model (none when supported).
struct FreeMotions {
    /// Their number (the rigid-body modes).
    count: usize,
    /// Names of the basic ones (`ux`, …, `rz`).
    names: Vec<&'static str>,
}

/// The model's free rigid motions, found when the method solves directly or a frequency is 0
/// (where a free body is refused: an unbalanced force has no static response).
fn free_motions(sys: &System, req: &HarmonicRequest, method: Method) -> Result<FreeMotions> {
    let at_zero = req.freqs_hz.contains(&0.0);
    if method == Method::Modal && !at_zero {
        return Ok(FreeMotions {
            count: 0,
            names: vec![],
        });
    }
    let model = sys.model();
    let parts = crate::post::modal::RigidParts::new(sys.k(), sys.m()?, &model.dofs, &model.nodes);
    let free = FreeMotions {
        count: parts.free.iter().map(|p| p.count).sum(),
        names: parts.free.iter().flat_map(|p| p.motions.iter().copied()).collect(),
    };
    if at_zero && free.count > 0 {
        return Err(Error::param(
            "freqs_hz",
            format!(
                "harmonic: a frequency of 0 Hz on a model that moves freely as a rigid body ({} free motion{}{}): \
                 an unbalanced force has no static response; support the model (--fix) or start above 0 Hz",
                free.count,
                if free.count == 1 { "" } else { "s" },
                if free.names.is_empty() {
                    String::new()
                } else {
                    format!(": {}", free.names.join(", "))
                }
            ),
        ));
    }
    Ok(free)
}

/// The verified modes of the superposition (at least one elastic mode beyond the rigid ones, for
/// the static correction's shift).
fn modal_modes(
    sys: &System,
    req: &HarmonicRequest,
    target: ModalTarget,
    notes: &mut Vec<String>,
) -> Result<crate::analysis::modal::ModalRun> {
    let params = ModalParams {
        target,
        ..Default::default()
    };
    let mut modes = crate::analysis::modal::solve(sys, &params)?;
    let n_rigid = modes.report.n_rigid;
    if matches!(target, ModalTarget::Band(..)) && n_rigid == modes.lambda.len() {
        // Only rigid-body modes in the band: the static correction needs the first elastic
        // one (its shift sits below it).
        let params = ModalParams {
            target: ModalTarget::Modes(n_rigid + 6),
            ..Default::default()
        };
        modes = crate::analysis::modal::solve(sys, &params)?;
    }
    if !modes.report.complete || !modes.report.accurate {
        return Err(Error::Verification(format!(
            "the modes for the superposition failed their checks (complete: {}, accurate: {}); use \
             --method direct",
            modes.report.complete, modes.report.accurate
        )));
    }
    let fmax = req.freqs_hz.iter().copied().fold(0.0, f64::max);
    // (Modes spanning every degree of freedom are exact at any frequency.)
    if let Some(&top) = modes.lambda.last()
        && crate::post::modal::hz(top) < 1.5 * fmax
        && modes.lambda.len() < sys.n_free()
    {
        notes.push(format!(
            "the highest mode superposed ({} Hz) is below 1.5 × the highest frequency ({} Hz): the static \
             correction covers the rest only approximately; raise --modes or check with --method both",
            crate::io::fmt_sig(crate::post::modal::hz(top), 4),
            crate::io::fmt_sig(fmax, 4)
        ));
    }
    Ok(modes)
}

/// The rigid-body modes the direct solve deflates on a free model (M-orthonormal columns): those
/// of the superposition's modes, or of a modal solve for them alone; `None` on a supported model.
fn rigid_basis(
    sys: &System,
    modes: Option<&crate::analysis::modal::ModalRun>,
    free: &FreeMotions,
) -> Result<Option<faer::Mat<f64>>> {
    if free.count == 0 {
        return Ok(None);
    }
    let own;
    let modes = match modes {
        Some(m) if m.report.n_rigid >= free.count => m,
        _ => {
            let params = ModalParams {
                target: ModalTarget::Modes(free.count),
                ..Default::default()
            };
            own = crate::analysis::modal::solve(sys, &params)?;
            &own
        }
    };
    let r = modes.report.n_rigid;
    if r != free.count || !modes.report.accurate {
        return Err(Error::Verification(format!(
            "the model moves freely in {} rigid motions, but {r} verified rigid-body modes were found: the direct \
             solve cannot separate the rigid response; support the model or use --method modal",
            free.count
        )));
    }
    Ok(Some(modes.vectors.subcols(0, r).to_owned()))
}

/// The solves at one frequency: the superposition and/or the direct solve of the scaled load.
struct Solver<'a> {
    sys: &'a System,
    load: &'a [c64],
    scale: f64,
    damping: &'a Damping,
    sup: Option<harmonic::Superposition<'a>>,
    direct: bool,
    rigid: Option<faer::Mat<f64>>,
}

impl Solver<'_> {
    /// (modal, direct) responses at ω (rad/s), each when its method runs.
    fn at(&self, w: f64, tm: &mut HarmonicTimings) -> Result<(Option<Vec<c64>>, Option<Vec<c64>>)> {
        let unscale = |mut u: Vec<c64>| {
            if self.scale != 1.0 {
                u.iter_mut().for_each(|v| *v *= self.scale);
            }
            u
        };
        let t = Instant::now();
        let modal = self.sup.as_ref().map(|s| s.at(w)).transpose()?.map(unscale);
        tm.superpose += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let direct = if self.direct {
            let u = match &self.rigid {
                Some(r) => harmonic::direct_free(self.sys, self.load, w, self.damping, r.as_ref())?,
                None => harmonic::direct(self.sys, self.load, w, self.damping)?,
            };
            Some(unscale(u))
        } else {
            None
        };
        tm.direct += t.elapsed().as_secs_f64();
        Ok((modal, direct))
    }
}

/// What a point's report needs besides the response.
struct PointContext<'a> {
    sys: &'a System,
    mesh: &'a Mesh,
    probes: &'a [String],
    probe_nodes: &'a [Vec<usize>],
    forces: &'a [GroupForce],
    free: bool,
}

impl PointContext<'_> {
    /// The report of frequency `f` (Hz) from the modal and/or direct response (the modal one is
    /// reported when both ran) and the nodal field; a non-finite result is refused (exit 2).
    fn point(&self, f: f64, modal: Option<&[c64]>, direct: Option<&[c64]>) -> Result<(Point, Vec<[c64; 6]>)> {
        let u = modal.or(direct).expect("one method ran");
        let full = harmonic::expand(self.sys, u);
        let (mut max_peak, mut max_node) = (0.0f64, 0usize);
        let mut finite = true;
        for (a, v) in full.iter().enumerate().take(self.mesh.nodes.len()) {
            let p = harmonic::peak(&[v[0], v[1], v[2]]);
            finite &= p.is_finite();
            if p > max_peak {
                max_peak = p;
                max_node = a;
            }
        }
        let groups: Vec<GroupResponse> = self
            .probes
            .iter()
            .zip(self.probe_nodes)
            .map(|(g, nodes)| group_response(g, nodes, &full))
            .collect();
        let modal_vs_direct = match (modal, direct) {
            (Some(m), Some(d)) => {
                // ‖m − d‖ / ‖d‖ with the norms scaled (a response of 1e-300 m squares to zero),
                // and 1 (all of it differs) when the direct response is exactly zero and the modal
                // one is not: never an absolute difference reported as a relative one.
                let num = scaled_norm(m.iter().zip(d).map(|(a, b)| a - b));
                let den = scaled_norm(d.iter().copied());
                Some(if den > 0.0 {
                    num / den
                } else if num > 0.0 {
                    1.0
                } else {
                    0.0
                })
            }
            _ => None,
        };
        finite &= groups.iter().all(|g| {
            g.peak_m.is_finite()
                && g.max_node_peak_m.is_finite()
                && g.mean
                    .iter()
                    .all(|c| c.amplitude_m.is_finite() && c.phase_deg.is_finite())
        });
        if !finite {
            return Err(self.not_finite(f));
        }
        let point = Point {
            freq_hz: f,
            groups,
            max_peak_m: max_peak,
            max_node,
            modal_vs_direct,
        };
        Ok((point, full))
    }

    /// The error of a response that overflows double precision, with its likely cause.
    fn not_finite(&self, f: f64) -> Error {
        let fmax = self
            .forces
            .iter()
            .flat_map(|g| g.force)
            .map(f64::abs)
            .fold(0.0, f64::max);
        Error::Factorization(format!(
            "the harmonic response at {} Hz is not finite: it overflows double precision (forces up to {} N{}); \
             the response is linear in the forces: scale them down",
            crate::io::fmt_sig(f, 4),
            crate::io::fmt_sig(fmax, 4),
            if self.free {
                ", on a free body, whose rigid response grows as 1/f² towards 0 Hz"
            } else {
                ""
            }
        ))
    }
}

fn group_response(group: &str, nodes: &[usize], full: &[[c64; 6]]) -> GroupResponse {
    let mut mean = [c64::new(0.0, 0.0); 3];
    let (mut hi, mut lo) = (0.0f64, f64::INFINITY);
    for &a in nodes {
        let v = &full[a];
        for c in 0..3 {
            mean[c] += v[c];
        }
        let p = harmonic::peak(&[v[0], v[1], v[2]]);
        hi = hi.max(p);
        lo = lo.min(p);
    }
    for m in &mut mean {
        *m /= nodes.len() as f64;
    }
    GroupResponse {
        group: group.to_string(),
        nodes: nodes.len(),
        mean: [component(mean[0]), component(mean[1]), component(mean[2])],
        peak_m: harmonic::peak(&mean),
        max_node_peak_m: hi,
        min_node_peak_m: lo,
    }
}

/// The report as tables.
pub fn text(r: &HarmonicReport) -> String {
    use crate::io::fmt_sig;
    let mut s = String::new();
    s.push_str(&format!("harmonic response: {} free DOFs, {}\n", r.dofs, r.damping));
    for f in &r.forces {
        s.push_str(&format!(
            "  force on {}: ({}, {}, {}) N at phase {}°\n",
            f.group,
            fmt_sig(f.force_n[0], 4),
            fmt_sig(f.force_n[1], 4),
            fmt_sig(f.force_n[2], 4),
            fmt_sig(f.phase_deg, 4)
        ));
    }
    match r.method {
        Method::Direct => s.push_str("  method: direct complex solve\n"),
        _ => s.push_str(&format!(
            "  method: modal superposition of {} modes (up to {} Hz) with static correction{}\n",
            r.modes_used,
            r.highest_mode_hz.map_or("–".into(), |f| fmt_sig(f, 4)),
            if r.method == Method::Both {
                ", checked by direct solve"
            } else {
                ""
            }
        )),
    }
    s.push('\n');
    let both = r.method == Method::Both;
    s.push_str(&format!(
        "{:>10}  {:<16} {:>11} {:>9} {:>11} {:>9} {:>11} {:>9} {:>11}{}\n",
        "f [Hz]",
        "group",
        "|ux| [mm]",
        "φx [°]",
        "|uy| [mm]",
        "φy [°]",
        "|uz| [mm]",
        "φz [°]",
        "max [mm]",
        if both { "  modal vs direct" } else { "" }
    ));
    for p in &r.points {
        for (i, g) in p.groups.iter().enumerate() {
            s.push_str(&format!(
                "{:>10}  {:<16} {:>11} {:>9.1} {:>11} {:>9.1} {:>11} {:>9.1} {:>11}{}\n",
                if i == 0 { fmt_sig(p.freq_hz, 5) } else { String::new() },
                g.group,
                fmt_sig(g.mean[0].amplitude_m * 1e3, 4),
                g.mean[0].phase_deg,
                fmt_sig(g.mean[1].amplitude_m * 1e3, 4),
                g.mean[1].phase_deg,
                fmt_sig(g.mean[2].amplitude_m * 1e3, 4),
                g.mean[2].phase_deg,
                fmt_sig(g.max_node_peak_m * 1e3, 4),
                match (i, p.modal_vs_direct) {
                    (0, Some(d)) => format!("  {d:.1e}"),
                    _ => String::new(),
                }
            ));
        }
    }
    s.push_str(&format!(
        "\ntime: modes {:.2} s, superposition {:.2} s, direct {:.2} s (total {:.2} s)\n",
        r.timings_s.modes, r.timings_s.superpose, r.timings_s.direct, r.timings_s.total
    ));
    s
}

/// Nodal fields of one frequency: peak displacement (scalar), real and imaginary parts (vectors),
/// amplitude and phase (degrees) of ux, uy, uz. Names and data, node-major.
pub fn fields(mesh: &Mesh, nodal: &[[c64; 6]]) -> Vec<(String, usize, Vec<f64>)> {
    let n = mesh.nodes.len();
    let mut peak = Vec::with_capacity(n);
    let (mut re, mut im, mut amp, mut ph) = (
        Vec::with_capacity(3 * n),
        Vec::with_capacity(3 * n),
        Vec::with_capacity(3 * n),
        Vec::with_capacity(3 * n),
    );
    for v in nodal.iter().take(n) {
        peak.push(harmonic::peak(&[v[0], v[1], v[2]]));
        for c in 0..3 {
            re.push(v[c].re);
            im.push(v[c].im);
            amp.push(v[c].norm());
            ph.push(if v[c].norm() > 0.0 {
                v[c].im.atan2(v[c].re).to_degrees()
            } else {
                0.0
            });
        }
    }
    vec![
        ("peak_displacement".into(), 1, peak),
        ("displacement_real".into(), 3, re),
        ("displacement_imag".into(), 3, im),
        ("amplitude".into(), 3, amp),
        ("phase_deg".into(), 3, ph),
    ]
}

/// Write the fields of frequency `k` as VTU and/or MSH.
pub fn write_fields(
    mesh: &Mesh,
    cells: Option<&[crate::mesh::CellBlock]>,
    run: &HarmonicRun,
    k: usize,
    vtu: Option<&std::path::Path>,
    msh: Option<&std::path::Path>,
) -> Result<()> {
    write_fields_with(mesh, cells, run, k, vtu, msh, vec![])
}

/// [`write_fields`] with `extra` fields (name, components, node-major data) appended.
pub fn write_fields_with(
    mesh: &Mesh,
    cells: Option<&[crate::mesh::CellBlock]>,
    run: &HarmonicRun,
    k: usize,
    vtu: Option<&std::path::Path>,
    msh: Option<&std::path::Path>,
    extra: Vec<(String, usize, Vec<f64>)>,
) -> Result<()> {
    let Some(i) = run.field_points.iter().position(|&p| p == k) else {
        return Err(Error::param(
            "k",
            format!("harmonic: the field of frequency {k} was not kept by the run"),
        ));
    };
    let mut f = fields(mesh, &run.nodal[i]);
    f.extend(extra);
    let freq = run.report.points[k].freq_hz;
    if let Some(p) = vtu {
        let pf: Vec<crate::io::vtk::PointField> = f
            .iter()
            .map(|(name, nc, d)| crate::io::vtk::PointField::new(name.clone(), *nc, d))
            .collect();
        crate::io::vtk::write_vtu_cells(p, mesh, cells, &pf)?;
    }
    if let Some(p) = msh {
        let views: Vec<crate::io::msh_out::NodeView> = f
            .iter()
            .map(|(name, nc, d)| crate::io::msh_out::NodeView {
                name: format!("{name} at {} Hz", crate::io::fmt_sig(freq, 5)),
                step: 0,
                time: freq,
                n_comp: *nc,
                data: d,
            })
            .collect();
        crate::io::msh_out::write_msh_views(p, mesh, &views)?;
    }
    Ok(())
}

/// The frequency of the largest response (for the fields of a sweep).
pub fn peak_index(r: &HarmonicReport) -> usize {
    let mut best = 0;
    for (k, p) in r.points.iter().enumerate() {
        if p.max_peak_m > r.points[best].max_peak_m {
            best = k;
        }
    }
    best
}

/// FRF plot of a sweep: amplitude (mm, log) and phase (deg) of each reported group's mean motion
/// in its dominant direction, with the superposed modes marked.
pub fn write_frf_svg(path: &std::path::Path, r: &HarmonicReport) -> Result<()> {
    use plotters::prelude::*;
    let perr = |e: &dyn std::fmt::Display| Error::io(path, std::io::Error::other(format!("plotting failed: {e}")));
    let fs: Vec<f64> = r.points.iter().map(|p| p.freq_hz).collect();
    let (f0, f1) = (fs[0], *fs.last().unwrap_or(&fs[0]));
    if !(f1 > f0) {
        return Err(Error::option(
            "--plot",
            "FRF plot: a sweep of at least two frequencies is needed",
        ));
    }
    let ng = r.points[0].groups.len();
    // Each group's dominant direction over the sweep.
    let dirs: Vec<usize> = (0..ng)
        .map(|g| {
            let mut s = [0.0f64; 3];
            for p in &r.points {
                for (c, v) in s.iter_mut().enumerate() {
                    *v += p.groups[g].mean[c].amplitude_m;
                }
            }
            (0..3).max_by(|&a, &b| s[a].total_cmp(&s[b])).unwrap_or(2)
        })
        .collect();
    let amps: Vec<Vec<f64>> = (0..ng)
        .map(|g| {
            r.points
                .iter()
                .map(|p| p.groups[g].mean[dirs[g]].amplitude_m * 1e3)
                .collect()
        })
        .collect();
    let phases: Vec<Vec<f64>> = (0..ng)
        .map(|g| {
            let raw: Vec<f64> = r
                .points
                .iter()
                .map(|p| p.groups[g].mean[dirs[g]].phase_deg.to_radians())
                .collect();
            crate::app::dynamics::two_mass::unwrap_phase(&raw)
                .into_iter()
                .map(f64::to_degrees)
                .collect()
        })
        .collect();
    let pos = amps.iter().flatten().copied().filter(|v| *v > 0.0 && v.is_finite());
    let amax = pos.clone().fold(0.0, f64::max);
    let amin = pos.fold(f64::INFINITY, f64::min);
    let (amin, amax) = if amax > 0.0 {
        (amin.max(amax * 1e-8) * 0.8, amax * 1.5)
    } else {
        (1e-9, 1.0)
    };
    let (mut pmin, mut pmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in phases.iter().flatten() {
        pmin = pmin.min(*v);
        pmax = pmax.max(*v);
    }
    if !(pmax > pmin) {
        pmin -= 10.0;
        pmax += 10.0;
    }
    let colours = [
        RGBColor(0, 90, 181),
        RGBColor(220, 50, 32),
        RGBColor(0, 150, 60),
        RGBColor(120, 60, 160),
    ];
    let root = SVGBackend::new(path, (1000, 800)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| perr(&e))?;
    let (top, bottom) = root.split_vertically(440);
    let axis = ["x", "y", "z"];
    {
        let mut ch = ChartBuilder::on(&top)
            .caption(format!("Harmonic response ({})", r.damping), ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(70)
            .build_cartesian_2d(f0..f1, (amin..amax).log_scale())
            .map_err(|e| perr(&e))?;
        ch.configure_mesh()
            .x_desc("frequency, Hz")
            .y_desc("amplitude, mm")
            .draw()
            .map_err(|e| perr(&e))?;
        for &fm in &r.mode_frequencies_hz {
            if fm > f0 && fm < f1 {
                ch.draw_series(LineSeries::new(
                    [(fm, amin), (fm, amax)],
                    ShapeStyle::from(&RGBColor(180, 180, 180)).stroke_width(1),
                ))
                .map_err(|e| perr(&e))?;
            }
        }
        for g in 0..ng {
            let c = colours[g % colours.len()];
            ch.draw_series(LineSeries::new(
                fs.iter()
                    .zip(&amps[g])
                    .filter(|(_, a)| **a > 0.0)
                    .map(|(f, a)| (*f, *a)),
                ShapeStyle::from(&c).stroke_width(2),
            ))
            .map_err(|e| perr(&e))?
            .label(format!("{} u{}", r.points[0].groups[g].group, axis[dirs[g]]))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
        }
        ch.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| perr(&e))?;
    }
    {
        let mut ch = ChartBuilder::on(&bottom)
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(70)
            .build_cartesian_2d(f0..f1, pmin..pmax)
            .map_err(|e| perr(&e))?;
        ch.configure_mesh()
            .x_desc("frequency, Hz")
            .y_desc("phase, deg")
            .draw()
            .map_err(|e| perr(&e))?;
        for g in 0..ng {
            let c = colours[g % colours.len()];
            ch.draw_series(LineSeries::new(
                fs.iter().zip(&phases[g]).map(|(f, p)| (*f, *p)),
                ShapeStyle::from(&c).stroke_width(2),
            ))
            .map_err(|e| perr(&e))?;
        }
    }
    root.present().map_err(|e| perr(&e))?;
    Ok(())
}

/// The 2-norm of complex numbers, scaled by their largest modulus so that neither tiny nor huge
/// values underflow or overflow in the squares.
fn scaled_norm(v: impl Iterator<Item = c64> + Clone) -> f64 {
    let s = v.clone().fold(0.0f64, |a, z| a.max(z.norm()));
    if s == 0.0 || !s.is_finite() {
        return s;
    }
    s * v.map(|z| (z / s).norm_sqr()).sum::<f64>().sqrt()
}

/// Cap of the safety factor written to the VTU field (unloaded nodes have an infinite one).
pub const SAFETY_FIELD_CAP: f64 = 1e3;

/// A fatigue assessment of a harmonic run (`--fatigue`; docs/fatigue.md): the alternating state
/// is the response at one frequency, the mean state a static case on the same model.
#[derive(Clone, Debug)]
pub struct FatigueRequest {
    /// Material, surface, criterion, correction and cycles.
    pub settings: crate::post::fatigue::FatigueSettings,
    /// The mean (static) loads: one case on the harmonic model (empty: zero mean).
    pub mean_loads: Vec<crate::analysis::statics::Load>,
    /// Nodes closer than this to a fixed group are left out of the hot spots (m; 0: none).
    pub clamp_distance: f64,
    /// Rows of the hot-spot table.
    pub hot_spots: usize,
}

/// The fatigue result under stable JSON keys (`fatigue` in `harmonic --json`).
#[derive(Clone, Debug, Serialize)]
pub struct FatigueReport {
    /// The material data with their source.
    pub material: crate::post::fatigue::FatigueMaterial,
    /// `signed principal` or `signed von Mises`.
    pub criterion: String,
    /// `fkm`, `goodman` or `gerber`.
    pub mean_stress: String,
    /// Cycles required.
    pub cycles: f64,
    /// Frequency of the alternating state (Hz).
    pub frequency_hz: f64,
    /// The corrected endurance limit and its factors.
    pub endurance: crate::post::fatigue::Endurance,
    /// Strength at the cycles (Pa).
    pub strength: f64,
    /// FKM mean-stress sensitivity M_σ.
    pub m_sigma: f64,
    /// Lowest safety over the assessed nodes (`null` when nothing is loaded).
    pub min_safety: Option<f64>,
    /// Lowest first-cycle yield safety.
    pub min_yield_safety: Option<f64>,
    /// The hot spots, lowest safety first.
    pub hot_spots: Vec<crate::post::fatigue::HotSpot>,
    /// Distance from the fixed groups within which nodes are not assessed (m).
    pub clamp_distance: f64,
    /// Nodes left out by it.
    pub excluded_nodes: usize,
    /// Notes.
    pub notes: Vec<String>,
}

/// The fatigue field and its report.
pub struct FatigueRun {
    /// Report.
    pub report: FatigueReport,
    /// Per-node field.
    pub field: crate::post::fatigue::FatigueField,
}

/// Mask of the nodes at least `distance` from every node of the fixed groups of `spec`.
fn clamp_mask(mesh: &Mesh, spec: &crate::model::ModelSpec, distance: f64) -> Vec<bool> {
    let n = mesh.nodes.len();
    if distance <= 0.0 {
        return vec![true; n];
    }
    let fixed: Vec<[f64; 3]> = spec
        .fixes
        .iter()
        .filter_map(|(g, _)| mesh.groups.iter().find(|x| &x.name == g))
        .flat_map(|g| mesh.group_nodes(g))
        .map(|a| mesh.nodes[a as usize])
        .collect();
    let d2 = distance * distance;
    mesh.nodes
        .iter()
        .map(|x| {
            fixed
                .iter()
                .all(|f| (x[0] - f[0]).powi(2) + (x[1] - f[1]).powi(2) + (x[2] - f[2]).powi(2) >= d2)
        })
        .collect()
}

/// Nodal stresses of a displacement field given per mesh node (3 per node).
fn nodal_tensors(sys: &System, u: &[f64]) -> Result<crate::post::stress::NodalStress> {
    let m = sys.model();
    crate::post::stress::nodal_stress(&m.solids, m.n_mesh_nodes, u)
}

/// Assess the response of frequency index `k` of `run` (a kept field) against the mean static
/// case of `req` solved on the same mesh and model options.
pub fn fatigue(sys: &System, mesh: &Mesh, run: &HarmonicRun, k: usize, req: &FatigueRequest) -> Result<FatigueRun> {
    let Some(i) = run.field_points.iter().position(|&p| p == k) else {
        return Err(Error::param(
            "k",
            format!("fatigue: the field of frequency {k} was not kept"),
        ));
    };
    let n = mesh.nodes.len();
    let nodal = &run.nodal[i];
    let part = |f: fn(&c64) -> f64| -> Vec<f64> {
        (0..n)
            .flat_map(|a| [f(&nodal[a][0]), f(&nodal[a][1]), f(&nodal[a][2])])
            .collect()
    };
    let alt_re = nodal_tensors(sys, &part(|z| z.re))?;
    let alt_im = nodal_tensors(sys, &part(|z| z.im))?;
    let mut notes = vec![];
    let mean = if req.mean_loads.is_empty() {
        notes.push("no mean load given: fully reversed stress (mean 0)".to_string());
        vec![[0.0; 6]; n]
    } else {
        let opts = crate::analysis::statics::StaticOptions {
            spec: sys.model().spec.clone(),
            cases: vec![req.mean_loads.clone()],
        };
        let st = crate::analysis::statics::run_static(mesh, "fatigue mean load", &opts)?;
        let u = crate::app::report::mesh_displacements(&st, 0);
        nodal_tensors(sys, &u)?.stress
    };
    let solid: Vec<bool> = alt_re.count.iter().map(|&c| c > 0).collect();
    let field = crate::post::fatigue::assess(&req.settings, &mean, &alt_re.stress, &alt_im.stress, &solid)?;
    let mask = clamp_mask(mesh, &sys.model().spec, req.clamp_distance);
    let excluded = (0..n).filter(|&a| solid[a] && !mask[a]).count();
    let mut shown = field.clone();
    for a in (0..n).filter(|&a| !mask[a]) {
        shown.safety[a] = f64::INFINITY;
    }
    let hot = crate::post::fatigue::hot_spots(mesh, &shown, req.hot_spots);
    if req.clamp_distance <= 0.0 {
        let on_fixed = clamp_mask(mesh, &sys.model().spec, 1e-12 * mesh_size(mesh));
        if let Some(h) = hot.first() {
            let a = mesh.node_tags.iter().position(|&t| t == h.node).unwrap_or(0);
            if !on_fixed[a] {
                notes.push(format!(
                    "the hot spot (node {}) lies on a fixed group: a rigid clamp makes the stress there grow with \
                     mesh refinement; give --clamp-distance (e.g. one element or the part's thickness) to read \
                     the hot spot at that distance (docs/fatigue.md)",
                    h.node
                ));
            }
        }
    }
    let min_of = |v: &[f64]| -> Option<f64> {
        (0..n)
            .filter(|&a| mask[a] && v[a].is_finite())
            .map(|a| v[a])
            .min_by(f64::total_cmp)
    };
    let s = &req.settings;
    let report = FatigueReport {
        material: s.material.clone(),
        criterion: s.criterion.name().into(),
        mean_stress: s.mean_stress.name().into(),
        cycles: s.cycles,
        frequency_hz: run.report.points[k].freq_hz,
        endurance: field.endurance.clone(),
        strength: field.strength,
        m_sigma: field.m_sigma,
        min_safety: min_of(&field.safety),
        min_yield_safety: min_of(&field.yield_safety),
        hot_spots: hot,
        clamp_distance: req.clamp_distance,
        excluded_nodes: excluded,
        notes,
    };
    Ok(FatigueRun { report, field })
}

/// The mesh's bounding-box diagonal (m).
fn mesh_size(mesh: &Mesh) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for x in &mesh.nodes {
        for c in 0..3 {
            lo[c] = lo[c].min(x[c]);
            hi[c] = hi[c].max(x[c]);
        }
    }
    (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt()
}

/// The fatigue fields for VTU (`fatigue_safety` capped at [`SAFETY_FIELD_CAP`],
/// `fatigue_sigma_a`, `fatigue_sigma_m` in Pa).
pub fn fatigue_fields(f: &crate::post::fatigue::FatigueField) -> Vec<(String, usize, Vec<f64>)> {
    vec![
        (
            "fatigue_safety".into(),
            1,
            f.safety.iter().map(|&s| s.min(SAFETY_FIELD_CAP)).collect(),
        ),
        ("fatigue_sigma_a".into(), 1, f.sigma_a.clone()),
        ("fatigue_sigma_m".into(), 1, f.sigma_m.clone()),
    ]
}

/// The fatigue section of the text report.
pub fn fatigue_text(r: &FatigueReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let m = &r.material;
    let _ = writeln!(
        s,
        "\nFatigue at {} Hz, {:.3e} cycles: {} ({}; R_m {:.0} MPa, R_e {:.0} MPa, σ_W {:.0} MPa, k {}, N_D {:.0e}), \
         {} stress, {} mean-stress correction",
        crate::io::fmt_sig(r.frequency_hz, 5),
        r.cycles,
        m.name,
        m.source,
        m.r_m / 1e6,
        m.r_e / 1e6,
        m.sigma_w / 1e6,
        m.slope,
        m.knee_cycles,
        r.criterion,
        r.mean_stress
    );
    for f in &r.endurance.factors {
        let _ = writeln!(s, "  {f}");
    }
    let _ = writeln!(
        s,
        "  endurance S_e = {:.1} MPa, strength at the cycles {:.1} MPa, M_σ = {:.3}",
        r.endurance.value / 1e6,
        r.strength / 1e6,
        r.m_sigma
    );
    match r.min_safety {
        Some(x) => {
            let _ = writeln!(s, "  lowest safety {x:.3}");
        }
        None => {
            let _ = writeln!(s, "  nothing loaded");
        }
    }
    let _ = writeln!(
        s,
        "  {:>8}  {:<16} {:>10} {:>10} {:>9} {:>10}",
        "node", "group", "σ_a MPa", "σ_m MPa", "safety", "life"
    );
    for h in &r.hot_spots {
        let _ = writeln!(
            s,
            "  {:>8}  {:<16} {:>10.2} {:>10.2} {:>9.3} {:>10}",
            h.node,
            h.group,
            h.sigma_a / 1e6,
            h.sigma_m / 1e6,
            h.safety,
            h.life.map_or("∞".to_string(), |l| format!("{l:.3e}"))
        );
    }
    s
}
