//! SVG plots of the two-mass model (plotters, SVG backend): amplitude–frequency and phase curves
//! with the operating point, the transient start-up, and the electromagnet force with its harmonics.
//! Displacements are drawn in mm, frequencies in Hz, times in s, forces in N, phases in degrees.

use std::path::Path;

use plotters::prelude::*;

use super::electromagnet::RectifiedDrive;
use super::transient::Transient;
use super::two_mass::{TwoMass, unwrap_phase};
use crate::{Error, Result};

const W: u32 = 1000;
const H: u32 = 900;
const C1: RGBColor = RGBColor(0, 90, 181);
const C2: RGBColor = RGBColor(220, 50, 32);
const C3: RGBColor = RGBColor(0, 150, 60);

/// A labelled polyline: (legend label, points, style).
type Curve = (String, Vec<(f64, f64)>, ShapeStyle);

fn perr<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| Error::io(path, std::io::Error::other(format!("plotting failed: {e}")))
}

fn ensure_parent(path: &Path) -> Result<()> {
    if let Some(dir) = path.parent()
        && !dir.as_os_str().is_empty()
        && !dir.exists()
    {
        return Err(Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::NotFound, "output directory does not exist"),
        ));
    }
    Ok(())
}

fn finite_range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    if hi - lo <= 1e-300 {
        let d = lo.abs().max(1e-12) * 0.1;
        return (lo - d, hi + d);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// Writes the amplitude–frequency (|X1|, |X2| in mm, log scale) and phase (deg, unwrapped) curves
/// of both masses from `f_lo` to `f_hi` Hz (`n` points, force amplitude `force` N), with the
/// operating point `operating_hz` (Hz) marked by a dashed line and dots.
///
/// Errors: those of [`TwoMass::frequency_response`], and I/O or plotting failures.
pub fn write_frequency_response_svg(
    path: impl AsRef<Path>,
    model: &TwoMass,
    f_lo: f64,
    f_hi: f64,
    n: usize,
    force: f64,
    operating_hz: Option<f64>,
) -> Result<()> {
    let path = path.as_ref();
    ensure_parent(path)?;
    let curve = model.frequency_response(f_lo, f_hi, n, force)?;
    let op = match operating_hz {
        Some(f) => Some(model.steady_state(std::f64::consts::TAU * f, force)?),
        None => None,
    };
    let fs: Vec<f64> = curve.iter().map(|s| s.freq_hz()).collect();
    let a1: Vec<f64> = curve.iter().map(|s| s.amp1() * 1e3).collect();
    let a2: Vec<f64> = curve.iter().map(|s| s.amp2() * 1e3).collect();
    let p1 = unwrap_phase(&curve.iter().map(|s| s.phase1()).collect::<Vec<_>>());
    let p2 = unwrap_phase(&curve.iter().map(|s| s.phase2()).collect::<Vec<_>>());
    let p1: Vec<f64> = p1.iter().map(|v| v.to_degrees()).collect();
    let p2: Vec<f64> = p2.iter().map(|v| v.to_degrees()).collect();

    let positive = a1.iter().chain(&a2).copied().filter(|v| *v > 0.0 && v.is_finite());
    let amin = positive.clone().fold(f64::INFINITY, f64::min);
    let amax = positive.fold(0.0, f64::max);
    let (amin, amax) = if amax > 0.0 {
        (amin.max(amax * 1e-6) * 0.8, amax * 1.5)
    } else {
        (1e-6, 1.0)
    };

    let data = Curves { fs, a1, a2, p1, p2 };
    let root = SVGBackend::new(path, (W, H)).into_drawing_area();
    root.fill(&WHITE).map_err(perr(path))?;
    let (top, bottom) = root.split_vertically(H / 2);
    let title = format!(
        "Two-mass model, F = {force:.0} N: amplitude–frequency characteristic ({})",
        match model.k_terms {
            super::KTerms::Eq1 => "eq. (1)",
            super::KTerms::AsPrinted => "k-terms as printed",
        }
    );
    draw_amplitudes(&top, path, title, &data, (f_lo, f_hi), (amin, amax), op.as_ref())?;
    draw_phases(&bottom, path, &data, (f_lo, f_hi), op.as_ref())?;
    root.present().map_err(perr(path))?;
    Ok(())
}

/// The sampled response curves: frequencies (Hz), amplitudes (mm) and unwrapped phases (deg).
struct Curves {
    fs: Vec<f64>,
    a1: Vec<f64>,
    a2: Vec<f64>,
    p1: Vec<f64>,
    p2: Vec<f64>,
}

type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;

/// The amplitude panel: |X1|, |X2| on a log scale, the operating point dashed and dotted.
fn draw_amplitudes(
    area: &Area,
    path: &Path,
    title: String,
    data: &Curves,
    (f_lo, f_hi): (f64, f64),
    (amin, amax): (f64, f64),
    op: Option<&super::two_mass::SteadyState>,
) -> Result<()> {
    let Curves { fs, a1, a2, .. } = data;
    let mut ch = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(f_lo..f_hi, (amin..amax).log_scale())
        .map_err(perr(path))?;
    ch.configure_mesh()
        .x_desc("frequency, Hz")
        .y_desc("amplitude, mm")
        .draw()
        .map_err(perr(path))?;
    ch.draw_series(LineSeries::new(
        fs.iter()
            .zip(a1.iter())
            .filter(|(_, a)| **a > 0.0)
            .map(|(f, a)| (*f, *a)),
        C1.stroke_width(2),
    ))
    .map_err(perr(path))?
    .label("|X1| active mass m1")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], C1.stroke_width(2)));
    ch.draw_series(LineSeries::new(
        fs.iter()
            .zip(a2.iter())
            .filter(|(_, a)| **a > 0.0)
            .map(|(f, a)| (*f, *a)),
        C2.stroke_width(2),
    ))
    .map_err(perr(path))?
    .label("|X2| reactive mass m2")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], C2.stroke_width(2)));
    if let Some(s) = op {
        let f = s.freq_hz();
        ch.draw_series(DashedLineSeries::new(
            vec![(f, amin), (f, amax)],
            6,
            4,
            BLACK.stroke_width(1),
        ))
        .map_err(perr(path))?
        .label(format!(
            "operating point {f:.1} Hz: X1 = {:.4} mm, X2 = {:.4} mm",
            s.amp1() * 1e3,
            s.amp2() * 1e3
        ))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        for (a, c) in [(s.amp1() * 1e3, C1), (s.amp2() * 1e3, C2)] {
            if a > 0.0 {
                ch.draw_series(std::iter::once(Circle::new((f, a), 5, c.filled())))
                    .map_err(perr(path))?;
            }
        }
    }
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(perr(path))?;
    Ok(())
}

/// The phase panel: both masses' unwrapped phases, the operating phases marked on their branch.
fn draw_phases(
    area: &Area,
    path: &Path,
    data: &Curves,
    (f_lo, f_hi): (f64, f64),
    op: Option<&super::two_mass::SteadyState>,
) -> Result<()> {
    let Curves { fs, p1, p2, .. } = data;
    let (pmin, pmax) = finite_range(p1.iter().chain(p2).copied());
    let mut ch = ChartBuilder::on(area)
        .caption("Phase against the force on m2", ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(f_lo..f_hi, pmin..pmax)
        .map_err(perr(path))?;
    ch.configure_mesh()
        .x_desc("frequency, Hz")
        .y_desc("phase, deg")
        .draw()
        .map_err(perr(path))?;
    ch.draw_series(LineSeries::new(
        fs.iter().copied().zip(p1.iter().copied()),
        C1.stroke_width(2),
    ))
    .map_err(perr(path))?
    .label("φ1 active mass")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], C1.stroke_width(2)));
    ch.draw_series(LineSeries::new(
        fs.iter().copied().zip(p2.iter().copied()),
        C2.stroke_width(2),
    ))
    .map_err(perr(path))?
    .label("φ2 reactive mass")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], C2.stroke_width(2)));
    if let Some(s) = op {
        let f = s.freq_hz();
        ch.draw_series(DashedLineSeries::new(
            vec![(f, pmin), (f, pmax)],
            6,
            4,
            BLACK.stroke_width(1),
        ))
        .map_err(perr(path))?;
        // Mark the operating phases on the unwrapped curves (nearest sample's branch).
        let i = fs
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - f).abs().total_cmp(&(b.1 - f).abs()))
            .map(|(i, _)| i)
            .unwrap_or(0);
        for (ph, curve, c) in [(s.phase1(), p1, C1), (s.phase2(), p2, C2)] {
            let mut v = ph.to_degrees();
            if let Some(&near) = curve.get(i) {
                v += 360.0 * ((near - v) / 360.0).round();
            }
            ch.draw_series(std::iter::once(Circle::new((f, v), 5, c.filled())))
                .map_err(perr(path))?;
        }
    }
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(perr(path))?;
    Ok(())
}

/// Writes the transient start-up of both masses (x1 and x2 in mm against time in s), one panel
/// each, decimated to at most 8000 points per curve. `offsets` (m), when given, draws the steady
/// static offsets (x1, x2) as dashed lines.
pub fn write_transient_svg(path: impl AsRef<Path>, tr: &Transient, offsets: Option<(f64, f64)>) -> Result<()> {
    let path = path.as_ref();
    ensure_parent(path)?;
    if tr.t.len() < 2 {
        return Err(Error::param("tr", "transient plot: fewer than 2 samples"));
    }
    let stride = tr.t.len().div_ceil(8000).max(1);
    let t0 = tr.t[0];
    let t1 = tr.t[tr.t.len() - 1];
    let root = SVGBackend::new(path, (W, H)).into_drawing_area();
    root.fill(&WHITE).map_err(perr(path))?;
    let panels = root.split_evenly((2, 1));
    for (j, area) in panels.iter().enumerate() {
        let (x, name, c, off) = if j == 0 {
            (&tr.x1, "x1, active mass m1", C1, offsets.map(|o| o.0))
        } else {
            (&tr.x2, "x2, reactive mass m2", C2, offsets.map(|o| o.1))
        };
        let ys: Vec<(f64, f64)> = tr.t.iter().zip(x).step_by(stride).map(|(t, v)| (*t, v * 1e3)).collect();
        let (lo, hi) = finite_range(x.iter().map(|v| v * 1e3));
        let mut ch = ChartBuilder::on(area)
            .caption(
                format!("Start-up from rest under the rectified force: {name}"),
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(t0..t1, lo..hi)
            .map_err(perr(path))?;
        ch.configure_mesh()
            .x_desc("time, s")
            .y_desc("displacement, mm")
            .draw()
            .map_err(perr(path))?;
        ch.draw_series(LineSeries::new(ys, c.stroke_width(1)))
            .map_err(perr(path))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
        if let Some(o) = off {
            ch.draw_series(DashedLineSeries::new(
                vec![(t0, o * 1e3), (t1, o * 1e3)],
                6,
                4,
                BLACK.stroke_width(1),
            ))
            .map_err(perr(path))?
            .label(format!("static offset {:.4} mm", o * 1e3))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        }
        ch.configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(perr(path))?;
    }
    root.present().map_err(perr(path))?;
    Ok(())
}

/// Writes the electromagnet force: top panel P(t) = P_em·|sin ωt| over `mains_periods` mains
/// periods with its constant part, the constant + Ω harmonic (the paper's Fig. 7) and the partial
/// sum with `n_harmonics` harmonics; bottom panel the amplitude spectrum |a_k|·P_em at kΩ, N.
pub fn write_electromagnet_svg(
    path: impl AsRef<Path>,
    drive: &RectifiedDrive,
    n_harmonics: u32,
    mains_periods: f64,
) -> Result<()> {
    let path = path.as_ref();
    ensure_parent(path)?;
    let drive = RectifiedDrive::new(drive.p_em, drive.omega_mains)?;
    if n_harmonics == 0 || n_harmonics > 1000 {
        return Err(Error::param(
            "n_harmonics",
            format!("electromagnet plot: n_harmonics must be in 1..=1000, got {n_harmonics}"),
        ));
    }
    if !(mains_periods.is_finite() && mains_periods > 0.0 && mains_periods <= 1000.0) {
        return Err(Error::param(
            "mains_periods",
            format!("electromagnet plot: mains_periods must be in (0, 1000], got {mains_periods}"),
        ));
    }
    let t_end = mains_periods * std::f64::consts::TAU / drive.omega_mains;
    let npts = 2000;
    let ts: Vec<f64> = (0..=npts).map(|i| t_end * i as f64 / npts as f64).collect();
    let pc = drive.constant();
    let f = drive.harmonic_amplitude();
    let w = drive.omega_force();
    let p_max = drive.p_em.max(1e-12);

    let root = SVGBackend::new(path, (W, H)).into_drawing_area();
    root.fill(&WHITE).map_err(perr(path))?;
    let (top, bottom) = root.split_vertically(H / 2);
    {
        let mut ch = ChartBuilder::on(&top)
            .caption(
                format!(
                    "Single-stroke electromagnets: P(t) = {:.0}·|sin ωt| N, P_const = {pc:.1} N, F = {f:.1} N",
                    drive.p_em
                ),
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..t_end, (-0.55 * p_max)..(1.6 * p_max))
            .map_err(perr(path))?;
        ch.configure_mesh()
            .x_desc("time, s")
            .y_desc("force, N")
            .draw()
            .map_err(perr(path))?;
        let series: [Curve; 4] = [
            (
                "P(t) = P_em |sin ωt|".into(),
                ts.iter().map(|&t| (t, drive.force(t))).collect(),
                BLACK.stroke_width(2),
            ),
            (
                "constant part (2/π) P_em".into(),
                vec![(0.0, pc), (t_end, pc)],
                C3.stroke_width(2),
            ),
            (
                "Ω harmonic −(4/(3π)) P_em cos Ωt".into(),
                ts.iter().map(|&t| (t, -f * (w * t).cos())).collect(),
                C2.stroke_width(2),
            ),
            (
                format!("sum of {n_harmonics} harmonics + constant"),
                ts.iter().map(|&t| (t, drive.partial_sum(t, n_harmonics))).collect(),
                C1.stroke_width(1),
            ),
        ];
        for (label, pts, style) in series {
            ch.draw_series(LineSeries::new(pts, style))
                .map_err(perr(path))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        }
        ch.configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(perr(path))?;
    }
    {
        let fw = w / std::f64::consts::TAU;
        let kmax = n_harmonics as f64;
        let mut ch = ChartBuilder::on(&bottom)
            .caption("Amplitude spectrum of P(t)", ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5 * fw..(kmax + 0.5) * fw, 0.0..(0.7 * p_max))
            .map_err(perr(path))?;
        ch.configure_mesh()
            .x_desc("frequency, Hz")
            .y_desc("amplitude, N")
            .draw()
            .map_err(perr(path))?;
        ch.draw_series((0..=n_harmonics).map(|k| {
            let x = k as f64 * fw;
            let a = drive.cos_coefficient(k).abs();
            let c = if k == 0 {
                C3
            } else if k == 1 {
                C2
            } else {
                C1
            };
            Rectangle::new([(x - 0.15 * fw, 0.0), (x + 0.15 * fw, a)], c.filled())
        }))
        .map_err(perr(path))?;
        ch.draw_series((0..=n_harmonics.min(6)).map(|k| {
            let x = k as f64 * fw;
            let a = drive.cos_coefficient(k).abs();
            Text::new(format!("{a:.0}"), (x - 0.2 * fw, a + 0.03 * p_max), ("sans-serif", 14))
        }))
        .map_err(perr(path))?;
    }
    root.present().map_err(perr(path))?;
    Ok(())
}
