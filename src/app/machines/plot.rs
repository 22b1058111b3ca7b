//! SVG figures of the crank drive, the autobalancer and the test-stand data: stacked panels of
//! labelled curves and points (plotters, SVG backend, the colours and sizes of [`crate::app::dynamics::plot`]).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::{Error, Result};

const PALETTE: [RGBColor; 7] = [
    RGBColor(0, 90, 181),
    RGBColor(220, 50, 32),
    RGBColor(0, 150, 60),
    RGBColor(120, 60, 170),
    RGBColor(230, 150, 0),
    RGBColor(0, 0, 0),
    RGBColor(130, 130, 130),
];

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mark {
    /// Solid line (broken at non-finite points).
    Line,
    /// Dashed line.
    Dashed,
    /// Filled dots.
    Dots,
    /// Hollow circles.
    Circles,
}

/// One labelled series of a panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry (None: not in the legend).
    pub label: Option<String>,
    /// Points (x, y); a non-finite y breaks a line.
    pub points: Vec<(f64, f64)>,
    /// Index into the palette (blue, red, green, purple, orange, black, grey).
    pub color: usize,
    /// How it is drawn.
    pub mark: Mark,
}

impl Series {
    /// A labelled series.
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>, color: usize, mark: Mark) -> Series {
        Series {
            label: Some(label.into()),
            points,
            color,
            mark,
        }
    }
}

/// One panel: axes, title and series.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Panel {
    /// Caption.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Y axis label.
    pub y_label: String,
    /// Series.
    pub series: Vec<Series>,
    /// Logarithmic y axis (non-positive values are left out).
    pub log_y: bool,
    /// Fixed x range (default: the data's).
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range (default: the data's, padded).
    pub y_range: Option<(f64, f64)>,
    /// Vertical dashed marker lines (x, legend label, palette index).
    pub vlines: Vec<(f64, String, usize)>,
}

fn perr<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| Error::io(path, std::io::Error::other(format!("plotting failed: {e}")))
}

fn range(vals: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (1e-3, 1.0) } else { (-1.0, 1.0) };
    }
    if log {
        let (lo, hi) = if hi / lo < 10.0 { (lo / 2.0, hi * 2.0) } else { (lo, hi) };
        return (lo / 1.5, hi * 1.5);
    }
    if hi - lo <= 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
        let d = lo.abs().max(1e-12) * 0.1;
        return (lo - d, hi + d);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// Splits a polyline at non-finite (or, on a log axis, non-positive) points.
fn segments(points: &[(f64, f64)], log: bool) -> Vec<Vec<(f64, f64)>> {
    let mut out = vec![Vec::new()];
    for &(x, y) in points {
        if x.is_finite() && y.is_finite() && (!log || y > 0.0) {
            out.last_mut().expect("non-empty").push((x, y));
        } else if !out.last().expect("non-empty").is_empty() {
            out.push(Vec::new());
        }
    }
    out.retain(|s| !s.is_empty());
    out
}

macro_rules! draw_panel {
    ($area:expr, $p:expr, $path:expr, $xr:expr, $yr:expr, $ylo:expr, $yhi:expr, $log:expr) => {{
        let mut ch = ChartBuilder::on($area)
            .caption(&$p.title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(38)
            .y_label_area_size(80)
            .build_cartesian_2d($xr, $yr)
            .map_err(perr($path))?;
        ch.configure_mesh()
            .x_desc($p.x_label.as_str())
            .y_desc($p.y_label.as_str())
            .draw()
            .map_err(perr($path))?;
        let mut any_label = false;
        for s in &$p.series {
            let c = PALETTE[s.color % PALETTE.len()];
            let segs = segments(&s.points, $log);
            let mut labelled = false;
            match s.mark {
                Mark::Line | Mark::Dashed => {
                    for seg in segs {
                        let style = c.stroke_width(2);
                        let anno = if s.mark == Mark::Line {
                            ch.draw_series(LineSeries::new(seg, style)).map_err(perr($path))?
                        } else {
                            ch.draw_series(DashedLineSeries::new(seg, 7, 4, style))
                                .map_err(perr($path))?
                        };
                        if let (Some(l), false) = (&s.label, labelled) {
                            anno.label(l.clone())
                                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
                            labelled = true;
                            any_label = true;
                        }
                    }
                }
                Mark::Dots | Mark::Circles => {
                    let pts: Vec<(f64, f64)> = segs.into_iter().flatten().collect();
                    let filled = s.mark == Mark::Dots;
                    let anno = ch
                        .draw_series(pts.iter().map(|p| {
                            if filled {
                                Circle::new(*p, 4, c.filled())
                            } else {
                                Circle::new(*p, 5, c.stroke_width(2))
                            }
                        }))
                        .map_err(perr($path))?;
                    if let Some(l) = &s.label {
                        anno.label(l.clone()).legend(move |(x, y)| {
                            if filled {
                                Circle::new((x + 10, y), 4, c.filled())
                            } else {
                                Circle::new((x + 10, y), 5, c.stroke_width(2))
                            }
                        });
                        any_label = true;
                    }
                }
            }
        }
        for (x, l, ci) in &$p.vlines {
            let c = PALETTE[ci % PALETTE.len()];
            let anno = ch
                .draw_series(DashedLineSeries::new(
                    vec![(*x, $ylo), (*x, $yhi)],
                    6,
                    4,
                    c.stroke_width(1),
                ))
                .map_err(perr($path))?;
            if !l.is_empty() {
                anno.label(l.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
                any_label = true;
            }
        }
        if any_label {
            ch.configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(perr($path))?;
        }
    }};
}

fn draw(area: &DrawingArea<SVGBackend, Shift>, p: &Panel, path: &Path) -> Result<()> {
    let xs = p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0));
    let (x0, x1) = p.x_range.unwrap_or_else(|| {
        let (a, b) = range(xs, false);
        let pad = 0.05 / 1.1 * (b - a);
        (a + pad, b - pad)
    });
    let ys = p
        .series
        .iter()
        .flat_map(|s| s.points.iter().filter(|q| q.0 >= x0 && q.0 <= x1).map(|q| q.1));
    let labelled = p.series.iter().any(|s| s.label.is_some()) || p.vlines.iter().any(|v| !v.1.is_empty());
    let (y0, y1) = p.y_range.unwrap_or_else(|| {
        let (a, b) = range(ys, p.log_y);
        // Head room for the legend in the upper right corner.
        let room = 0.06 * (p.series.len() + p.vlines.len()) as f64;
        match (labelled, p.log_y) {
            (false, _) => (a, b),
            (true, false) => (a, b + room * (b - a)),
            (true, true) => (a, b * (b / a).powf(room)),
        }
    });
    if p.log_y {
        draw_panel!(area, p, path, x0..x1, (y0..y1).log_scale(), y0, y1, true);
    } else {
        draw_panel!(area, p, path, x0..x1, y0..y1, y0, y1, false);
    }
    Ok(())
}

/// Writes `panels` stacked vertically into one SVG, `width` × `panel_height` pixels each.
///
/// Errors: the folder does not exist, no panel, or plotting fails.
pub fn write_panels_svg(path: impl AsRef<Path>, panels: &[Panel], width: u32, panel_height: u32) -> Result<()> {
    let path = path.as_ref();
    if let Some(dir) = path.parent()
        && !dir.as_os_str().is_empty()
        && !dir.exists()
    {
        return Err(Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::NotFound, "output directory does not exist"),
        ));
    }
    if panels.is_empty() || panels.len() > 12 {
        return Err(Error::param(
            "panels",
            format!("plot: 1–12 panels, got {}", panels.len()),
        ));
    }
    let root = SVGBackend::new(path, (width, panel_height * panels.len() as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(perr(path))?;
    let areas = root.split_evenly((panels.len(), 1));
    for (a, p) in areas.iter().zip(panels) {
        draw(a, p, path)?;
    }
    root.present().map_err(perr(path))?;
    Ok(())
}
