//! The test-stand data's figure: the imbalance scatter over the re-mountings.

use std::f64::consts::TAU;
use std::path::Path;

use super::model::Scatter;
use crate::Result;
use crate::app::machines::plot::{Mark, Panel, Series, write_panels_svg};

/// The residual imbalance of each mounting, its mean and the mean scatter around it (g·mm).
pub(crate) fn scatter_plot(path: &Path, sc: &Scatter) -> Result<()> {
    let g_mm = |v: f64| v * 1e6; // kg·m → g·mm
    let pts: Vec<(f64, f64)> = sc.rows.iter().map(|r| (g_mm(r.sx), g_mm(r.sy))).collect();
    let circle: Vec<(f64, f64)> = (0..=180)
        .map(|k| {
            let a = TAU * k as f64 / 180.0;
            (
                g_mm(sc.sx_mean + sc.ds_mean * a.cos()),
                g_mm(sc.sy_mean + sc.ds_mean * a.sin()),
            )
        })
        .collect();
    let panels = vec![Panel {
        title: format!(
            "Residual imbalance over {} re-mountings: η = mean ΔS / S_c = {:.1} %",
            sc.rows.len(),
            100.0 * sc.eta
        ),
        x_label: "S_x, g·mm".into(),
        y_label: "S_y, g·mm".into(),
        series: vec![
            Series::new("S_i per mounting", pts, 0, Mark::Dots),
            Series::new(
                "mean (S_xc, S_yc)",
                vec![(g_mm(sc.sx_mean), g_mm(sc.sy_mean))],
                1,
                Mark::Circles,
            ),
            Series::new("mean ΔS around the mean", circle, 6, Mark::Dashed),
        ],
        ..Panel::default()
    }];
    write_panels_svg(path, &panels, 900, 700)
}
