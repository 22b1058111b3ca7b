//! The crank drive's figures: the steady revolution, the setups, the runs from rest.

use std::f64::consts::TAU;
use std::path::Path;

use super::case::CrankCase;
use super::model::{RunUp, SteadyRun};
use crate::Result;
use crate::app::machines::plot::{Mark, Panel, Series, write_panels_svg};
use crate::app::report::fmt_sig;

pub(crate) fn crank_plot(path: &Path, c: &CrankCase, bar: &SteadyRun, ef: &SteadyRun) -> Result<()> {
    let d = &c.drive;
    let n = 720;
    let grid: Vec<f64> = (0..=n).map(|k| TAU * k as f64 / n as f64).collect();
    let phi0 = c.run.start_angle;
    let deg = |p: f64| p.to_degrees();
    let i_curve: Vec<(f64, f64)> = grid.iter().map(|p| (deg(*p), d.reduced_inertia(phi0 + p).0)).collect();
    let mr: Vec<(f64, f64)> = grid
        .iter()
        .map(|p| (deg(*p), d.mechanism.resisting_moment(phi0 + p)))
        .collect();
    let mut panels = vec![
        Panel {
            title: format!("{}: reduced inertia I(φ)", c.name),
            x_label: "crank angle φ (from the start angle), deg".into(),
            y_label: "I, kg·m²".into(),
            series: vec![Series::new("I(φ)", i_curve, 0, Mark::Line)],
            x_range: Some((0.0, 360.0)),
            ..Panel::default()
        },
        Panel {
            title: "Resisting moment M_r(φ) and driving moment M_d(ω(φ)) on the steady revolution".into(),
            x_label: "crank angle φ, deg".into(),
            y_label: "moment, N·m".into(),
            series: vec![Series::new("M_r(φ)", mr, 1, Mark::Line)],
            x_range: Some((0.0, 360.0)),
            ..Panel::default()
        },
    ];
    let mut w_series = Vec::new();
    let mut e_series = Vec::new();
    for (run, color, mark) in [(ef, 0usize, Mark::Line), (bar, 1usize, Mark::Dashed)] {
        if run.metrics.is_none() {
            continue;
        }
        let s = &run.last;
        let short = if run.method == "baranov" {
            format!("Baranov, Δφ = {}°", fmt_sig(c.run.step.to_degrees(), 3))
        } else {
            "adaptive, energy form".to_string()
        };
        w_series.push(Series::new(
            format!("ω(φ), {short}"),
            s.phi.iter().zip(&s.omega).map(|(p, w)| (deg(*p), *w)).collect(),
            color,
            mark,
        ));
        e_series.push(Series::new(
            format!("ε(φ), {short}"),
            s.phi.iter().zip(&s.eps).map(|(p, e)| (deg(*p), *e)).collect(),
            color,
            mark,
        ));
    }
    if let Some(s) = ef.metrics.map(|_| &ef.last) {
        panels[1].series.push(Series::new(
            "M_d(ω(φ)), adaptive",
            s.phi
                .iter()
                .zip(&s.omega)
                .map(|(p, w)| (deg(*p), d.driving_moment(*w)))
                .collect(),
            0,
            Mark::Line,
        ));
    }
    panels.push(Panel {
        title: "Crank speed ω(φ) on the steady revolution".into(),
        x_label: "crank angle φ, deg".into(),
        y_label: "ω, rad/s".into(),
        series: w_series,
        x_range: Some((0.0, 360.0)),
        ..Panel::default()
    });
    panels.push(Panel {
        title: "Angular acceleration ε(φ) = dω/dt".into(),
        x_label: "crank angle φ, deg".into(),
        y_label: "ε, rad/s²".into(),
        series: e_series,
        x_range: Some((0.0, 360.0)),
        ..Panel::default()
    });
    write_panels_svg(path, &panels, 1000, 360)
}

pub(crate) fn setups_plot(path: &Path, c: &CrankCase, runs: &[(String, Option<SteadyRun>)]) -> Result<()> {
    let mut w = Vec::new();
    let mut mr = Vec::new();
    let mut inertia = Vec::new();
    for (k, ((name, run), s)) in runs.iter().zip(&c.setups).enumerate() {
        let sd = c.setup_drive(s);
        let grid: Vec<f64> = (0..=720).map(|j| TAU * j as f64 / 720.0).collect();
        mr.push(Series::new(
            name.clone(),
            grid.iter()
                .map(|p| (p.to_degrees(), sd.mechanism.resisting_moment(c.run.start_angle + p)))
                .collect(),
            k,
            Mark::Line,
        ));
        inertia.push(Series::new(
            name.clone(),
            grid.iter()
                .map(|p| (p.to_degrees(), sd.reduced_inertia(c.run.start_angle + p).0))
                .collect(),
            k,
            Mark::Line,
        ));
        if let Some(r) = run
            && r.metrics.is_some()
        {
            w.push(Series::new(
                name.clone(),
                r.last
                    .phi
                    .iter()
                    .zip(&r.last.omega)
                    .map(|(p, x)| (p.to_degrees(), *x))
                    .collect(),
                k,
                Mark::Line,
            ));
        }
    }
    let panels = vec![
        Panel {
            title: "Setups: crank speed ω(φ) on the steady revolution (adaptive integrator)".into(),
            x_label: "crank angle φ, deg".into(),
            y_label: "ω, rad/s".into(),
            series: w,
            x_range: Some((0.0, 360.0)),
            ..Panel::default()
        },
        Panel {
            title: "Setups: resisting moment M_r(φ)".into(),
            x_label: "crank angle φ, deg".into(),
            y_label: "M_r, N·m".into(),
            series: mr,
            x_range: Some((0.0, 360.0)),
            ..Panel::default()
        },
        Panel {
            title: "Setups: reduced inertia I(φ)".into(),
            x_label: "crank angle φ, deg".into(),
            y_label: "I, kg·m²".into(),
            series: inertia,
            x_range: Some((0.0, 360.0)),
            ..Panel::default()
        },
    ];
    write_panels_svg(path, &panels, 1000, 360)
}

pub(crate) fn startup_plot(path: &Path, runs: &[(String, RunUp)]) -> Result<()> {
    let mut series = Vec::new();
    let mut revs = Vec::new();
    for (k, (name, r)) in runs.iter().enumerate() {
        let label = match &r.stall {
            Some(s) => format!("{name}: stalls at t = {} s", fmt_sig(s.t, 3)),
            None => name.clone(),
        };
        let stride = (r.samples.t.len() / 4000).max(1);
        series.push(Series::new(
            label.clone(),
            r.samples
                .t
                .iter()
                .zip(&r.samples.omega)
                .step_by(stride)
                .map(|(t, w)| (*t, *w))
                .collect(),
            k,
            Mark::Line,
        ));
        revs.push(Series::new(
            label,
            r.samples
                .t
                .iter()
                .zip(&r.samples.phi)
                .step_by(stride)
                .map(|(t, p)| (*t, (p - r.samples.phi[0]) / TAU))
                .collect(),
            k,
            Mark::Line,
        ));
    }
    let t_end = runs
        .iter()
        .filter_map(|(_, r)| r.samples.t.last().copied())
        .fold(0.0f64, f64::max)
        .max(1e-3);
    let panels = vec![
        Panel {
            title: "Start-up from rest: crank speed".into(),
            x_label: "time, s".into(),
            y_label: "ω, rad/s".into(),
            series,
            x_range: Some((0.0, t_end)),
            ..Panel::default()
        },
        Panel {
            title: "Start-up from rest: revolutions turned".into(),
            x_label: "time, s".into(),
            y_label: "revolutions".into(),
            series: revs,
            x_range: Some((0.0, t_end)),
            ..Panel::default()
        },
    ];
    write_panels_svg(path, &panels, 1000, 380)
}
