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
            _ => Err(Error::InvalidInput(format!(
                "--method: unknown method '{s}' (modal, direct or both)"
            ))),
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
    if !(f0.is_finite() && f1.is_finite() && f0 >= 0.0 && f1 > f0) {
        return Err(Error::InvalidInput(format!(
            "--sweep: need 0 ≤ F0 < F1 (Hz), got {f0} {f1}"
        )));
    }
    if n < 2 {
        return Err(Error::InvalidInput(format!("--sweep: need at least 2 points, got {n}")));
    }
    if n > 100_000 {
        return Err(Error::InvalidInput(format!("--sweep: {n} points is more than 100000")));
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

/// A run: the report and the nodal responses (per frequency, per node [ux..rz]) for fields.
pub struct HarmonicRun {
    /// Report.
    pub report: HarmonicReport,
    /// Per frequency, per node: the complex displacement.
    pub nodal: Vec<Vec<[c64; 6]>>,
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

/// Run the harmonic analysis on an assembled system.
pub fn run(sys: &System, mesh: &Mesh, req: &HarmonicRequest) -> Result<HarmonicRun> {
    let t_all = Instant::now();
    req.damping.validate()?;
    if req.forces.is_empty() {
        return Err(Error::InvalidInput(
            "harmonic: no force given (--force GROUP=FX,FY,FZ[@PHASE_DEG])".into(),
        ));
    }
    if req.freqs_hz.is_empty() {
        return Err(Error::InvalidInput(
            "harmonic: no frequency given (--freq HZ or --sweep F0 F1 N)".into(),
        ));
    }
    if let Some(f) = req.freqs_hz.iter().find(|f| !(f.is_finite() && **f >= 0.0)) {
        return Err(Error::InvalidInput(format!(
            "harmonic: frequency {f} Hz must be finite and ≥ 0"
        )));
    }
    let probes: Vec<String> = if req.probes.is_empty() {
        let mut g: Vec<String> = Vec::new();
        for f in &req.forces {
            if !g.contains(&f.group) {
                g.push(f.group.clone());
            }
        }
        g
    } else {
        req.probes.clone()
    };
    // Nodes of each probe: a coupled group answers with its reference node.
    let model = sys.model();
    let mut probe_nodes = Vec::new();
    for g in &probes {
        let nodes: Vec<usize> = match model.references.iter().find(|r| &r.group == g) {
            Some(r) => vec![r.node],
            None => mesh.group_nodes(mesh.group(g)?).iter().map(|&a| a as usize).collect(),
        };
        if nodes.is_empty() {
            return Err(Error::InvalidInput(format!("harmonic: group '{g}' has no nodes")));
        }
        probe_nodes.push(nodes);
    }
    let load = harmonic::group_load(sys, mesh, &req.forces)?;
    if load.iter().all(|v| v.norm() == 0.0) {
        return Err(Error::InvalidInput(
            "harmonic: the forces are all zero on the free degrees of freedom".into(),
        ));
    }
    let omegas: Vec<f64> = req.freqs_hz.iter().map(|f| std::f64::consts::TAU * f).collect();
    let mut tm = HarmonicTimings::default();
    let mut notes = Vec::new();
    let fmax = req.freqs_hz.iter().copied().fold(0.0, f64::max);
    let (modal_u, modes_used, mode_hz) = if req.method != Method::Direct {
        let t = Instant::now();
        let target = match req.modes {
            Some(0) => return Err(Error::InvalidInput("--modes must be at least 1".into())),
            Some(n) => ModalTarget::Modes(n),
            None => ModalTarget::Band(-1.0, (2.0 * fmax).max(1.0)),
        };
        let params = ModalParams {
            target,
            ..Default::default()
        };
        let mut modes = crate::analysis::modal::solve(sys, &params)?;
        let n_rigid = modes.report.n_rigid;
        if req.modes.is_none() && n_rigid == modes.lambda.len() {
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
        tm.modes = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let u = harmonic::superpose(sys, &modes, &load, &omegas, &req.damping, true)?;
        tm.superpose = t.elapsed().as_secs_f64();
        let hz: Vec<f64> = modes.lambda.iter().map(|&l| crate::post::modal::hz(l)).collect();
        if let Some(&top) = hz.last()
            && top < 1.5 * fmax
        {
            notes.push(format!(
                "the highest mode superposed ({} Hz) is below 1.5 × the highest frequency ({} Hz): the static \
                 correction covers the rest only approximately; raise --modes or check with --method both",
                crate::io::fmt_sig(top, 4),
                crate::io::fmt_sig(fmax, 4)
            ));
        }
        (Some(u), modes.lambda.len(), hz)
    } else {
        (None, 0, Vec::new())
    };
    let direct_u = if req.method != Method::Modal {
        let t = Instant::now();
        if let Damping::Ratio(_) = req.damping {
            notes.push(
                "direct solve: the modal damping ratio ζ is taken as structural damping K(1 + 2iζ), equal to modal \
                 damping at each resonance, not between them; give --rayleigh for a viscous damping matrix"
                    .into(),
            );
        }
        let mut out = Vec::with_capacity(omegas.len());
        for &w in &omegas {
            out.push(harmonic::direct(sys, &load, w, &req.damping)?);
        }
        tm.direct = t.elapsed().as_secs_f64();
        Some(out)
    } else {
        None
    };
    let used = modal_u.as_ref().or(direct_u.as_ref()).expect("one method ran");
    let mut points = Vec::with_capacity(omegas.len());
    let mut nodal = Vec::with_capacity(omegas.len());
    for (k, u) in used.iter().enumerate() {
        let full = harmonic::expand(sys, u);
        let n_mesh = mesh.nodes.len();
        let (mut max_peak, mut max_node) = (0.0f64, 0usize);
        for (a, v) in full.iter().enumerate().take(n_mesh) {
            let p = harmonic::peak(&[v[0], v[1], v[2]]);
            if p > max_peak {
                max_peak = p;
                max_node = a;
            }
        }
        let groups = probes
            .iter()
            .zip(&probe_nodes)
            .map(|(g, nodes)| group_response(g, nodes, &full))
            .collect();
        let modal_vs_direct = match (&modal_u, &direct_u) {
            (Some(m), Some(d)) => {
                let num: f64 = m[k]
                    .iter()
                    .zip(&d[k])
                    .map(|(a, b)| (a - b).norm_sqr())
                    .sum::<f64>()
                    .sqrt();
                let den: f64 = d[k].iter().map(|b| b.norm_sqr()).sum::<f64>().sqrt();
                Some(if den > 0.0 { num / den } else { num })
            }
            _ => None,
        };
        points.push(Point {
            freq_hz: req.freqs_hz[k],
            groups,
            max_peak_m: max_peak,
            max_node,
            modal_vs_direct,
        });
        nodal.push(full);
    }
    tm.total = t_all.elapsed().as_secs_f64();
    let report = HarmonicReport {
        dofs: sys.n_free(),
        method: req.method,
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
        modes_used,
        highest_mode_hz: mode_hz.last().copied(),
        mode_frequencies_hz: mode_hz,
        points,
        notes,
        timings_s: tm,
    };
    Ok(HarmonicRun { report, nodal })
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
    run: &HarmonicRun,
    k: usize,
    vtu: Option<&std::path::Path>,
    msh: Option<&std::path::Path>,
) -> Result<()> {
    let f = fields(mesh, &run.nodal[k]);
    let freq = run.report.points[k].freq_hz;
    if let Some(p) = vtu {
        let pf: Vec<crate::io::vtk::PointField> = f
            .iter()
            .map(|(name, nc, d)| crate::io::vtk::PointField::new(name.clone(), *nc, d))
            .collect();
        crate::io::vtk::write_vtu(p, mesh, &pf)?;
    }
    if let Some(p) = msh {
        let views: Vec<crate::io::msh_out::NodeView> = f
            .iter()
            .filter(|(name, _, _)| name != "amplitude")
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
        return Err(Error::InvalidInput(
            "FRF plot: a sweep of at least two frequencies is needed".into(),
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
