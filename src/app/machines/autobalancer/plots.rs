//! The autobalancer's figures: the speed sweep and the run-up.

use std::f64::consts::TAU;
use std::path::Path;

use super::case::AutobalancerCase;
use super::model::{self, AutobalancerFigures, BALANCED_RESIDUAL, Simulation, SweepRow};
use crate::Result;
use crate::app::machines::plot::{Mark, Panel, Series, write_panels_svg};
use crate::app::report::fmt_sig;

pub(crate) fn sweep_plot(
    path: &Path,
    c: &AutobalancerCase,
    fig: &AutobalancerFigures,
    rows: &[SweepRow],
) -> Result<()> {
    let floor = 1e-3; // µm: amplitudes below are drawn at the floor (balanced to rounding)
    let um = |v: f64| (v * 1e6).max(floor);
    let with: Vec<(f64, f64)> = rows.iter().map(|r| (r.ratio, um(r.amplitude_with_balls))).collect();
    let without: Vec<(f64, f64)> = rows.iter().map(|r| (r.ratio, um(r.amplitude_without_balls))).collect();
    let bal: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.balanced)
        .map(|r| (r.ratio, um(r.amplitude_with_balls)))
        .collect();
    let mut vlines = vec![(1.0, "ω = ω_0 (linear criterion)".to_string(), 5)];
    let op = fig.ratio;
    if op >= c.sweep.from_ratio && op <= c.sweep.to_ratio {
        vlines.push((op, "operating speed".to_string(), 4));
    }
    let n_balls = rows.first().map(|r| r.ball_angles_deg.len()).unwrap_or(0);
    let mut angle_series: Vec<Series> = (0..n_balls)
        .map(|i| {
            Series::new(
                format!("ball {}", i + 1),
                rows.iter().map(|r| (r.ratio, r.ball_angles_deg[i])).collect(),
                i % 5,
                Mark::Dots,
            )
        })
        .collect();
    if let Some(a) = fig.balanced_angles_deg {
        for (k, v) in a.iter().enumerate() {
            angle_series.push(Series {
                label: (k == 0).then(|| "balanced position ±(180° − arccos(m_0R_0/2mR))".to_string()),
                points: vec![(c.sweep.from_ratio, *v), (c.sweep.to_ratio, *v)],
                color: 6,
                mark: Mark::Dashed,
            });
        }
    }
    let panels = vec![
        Panel {
            title: format!(
                "Housing vibration with and without balls (ω_0 = {} rpm; operating {} rpm = {} ω_0)",
                fmt_sig(fig.omega0_rpm, 4),
                fmt_sig(fig.speed_rpm, 5),
                fmt_sig(fig.ratio, 3)
            ),
            x_label: "disc speed ω/ω_0".into(),
            y_label: "amplitude, µm (log)".into(),
            series: vec![
                Series::new("without balls", without, 1, Mark::Line),
                Series::new("with balls (below 0.001 µm drawn at 0.001)", with, 0, Mark::Line),
                Series::new(
                    format!("balanced (residual < {} % of the imbalance)", BALANCED_RESIDUAL * 100.0),
                    bal,
                    2,
                    Mark::Circles,
                ),
            ],
            log_y: true,
            x_range: Some((c.sweep.from_ratio, c.sweep.to_ratio)),
            vlines: vlines.clone(),
            ..Panel::default()
        },
        Panel {
            title: format!(
                "Ball angles relative to the imbalance after {} s at each speed",
                fmt_sig(c.sweep.duration, 3)
            ),
            x_label: "disc speed ω/ω_0".into(),
            y_label: "angle, deg".into(),
            series: angle_series,
            x_range: Some((c.sweep.from_ratio, c.sweep.to_ratio)),
            y_range: Some((-200.0, 200.0)),
            vlines: vec![(1.0, String::new(), 5)],
            ..Panel::default()
        },
    ];
    write_panels_svg(path, &panels, 1000, 420)
}

pub(crate) fn runup_plot(
    path: &Path,
    c: &AutobalancerCase,
    with: &Simulation,
    env_w: &[(f64, f64)],
    env_n: &[(f64, f64)],
    res: &[f64],
) -> Result<()> {
    let stride = (with.t.len() / 6000).max(1);
    let rpm: Vec<(f64, f64)> = with
        .t
        .iter()
        .zip(&with.speed)
        .step_by(stride)
        .map(|(t, w)| (*t, w * 60.0 / TAU))
        .collect();
    let mut angle_series = Vec::new();
    for (i, a) in with.ball_angles.iter().enumerate() {
        // Wrapped to (−180°, 180°]; lines break at the wrap.
        let mut pts = Vec::new();
        let mut prev: Option<f64> = None;
        for (t, v) in with.t.iter().zip(a).step_by(stride) {
            let d = model::wrap_deg(v.to_degrees());
            if let Some(p) = prev
                && (d - p).abs() > 180.0
            {
                pts.push((*t, f64::NAN));
            }
            pts.push((*t, d));
            prev = Some(d);
        }
        angle_series.push(Series::new(format!("ball {}", i + 1), pts, i % 5, Mark::Line));
    }
    let resid: Vec<(f64, f64)> = with.t.iter().zip(res).step_by(stride).map(|(t, r)| (*t, *r)).collect();
    let t_end = c.runup.duration;
    let panels = vec![
        Panel {
            title: format!(
                "Run-up from rest to {} rpm in {} s: disc speed",
                fmt_sig(c.grinder.speed * 60.0 / TAU, 5),
                fmt_sig(c.runup.ramp_time, 3)
            ),
            x_label: "time, s".into(),
            y_label: "speed, rpm".into(),
            series: vec![Series::new("disc speed", rpm, 5, Mark::Line)],
            x_range: Some((0.0, t_end)),
            ..Panel::default()
        },
        Panel {
            title: "Housing vibration at the disc centre, per disc revolution (half peak-to-peak)".into(),
            x_label: "time, s".into(),
            y_label: "amplitude, µm (log)".into(),
            series: vec![
                Series::new(
                    "without balls",
                    env_n.iter().map(|p| (p.0, (p.1 * 1e6).max(1e-3))).collect(),
                    1,
                    Mark::Line,
                ),
                Series::new(
                    "with balls",
                    env_w.iter().map(|p| (p.0, (p.1 * 1e6).max(1e-3))).collect(),
                    0,
                    Mark::Line,
                ),
            ],
            log_y: true,
            x_range: Some((0.0, t_end)),
            ..Panel::default()
        },
        Panel {
            title: "Ball angles relative to the imbalance".into(),
            x_label: "time, s".into(),
            y_label: "angle, deg".into(),
            series: angle_series,
            x_range: Some((0.0, t_end)),
            y_range: Some((-200.0, 200.0)),
            ..Panel::default()
        },
        Panel {
            title: "Residual imbalance |m_0R_0 + Σ m_iR_i e^{iα_i}| / m_0R_0 (1 without balls; bunched balls add)"
                .into(),
            x_label: "time, s".into(),
            y_label: "residual".into(),
            series: vec![Series::new("residual", resid, 3, Mark::Line)],
            x_range: Some((0.0, t_end)),
            ..Panel::default()
        },
    ];
    write_panels_svg(path, &panels, 1000, 320)
}
