//! The autobalancer result ([`AutobalancerReport`]) as a [`Report`]: the grinder, the linear
//! criterion, the nonlinear model at the operating speed, the cutting scan, the speed sweep and
//! its threshold, the run-up, plots.

use std::f64::consts::TAU;

use super::model::BALANCED_RESIDUAL;
use super::run::AutobalancerReport;
use crate::Result;
use crate::app::machines::{figures, report_of};
use crate::app::report::{Block, Cell, Column, QuantityRow, Report, Table, fmt_sig};

/// Sections printed on the terminal.
pub const SUMMARY: &[&str] = &["criterion", "operating", "threshold", "runup"];

/// The report of an autobalancer run; its data is `r` serialised.
pub fn report(r: &AutobalancerReport) -> Result<Report> {
    let mut rep = report_of(format!("Autobalancer: {}", r.name), r)?;
    rep.section("input", "").push(Block::Text(format!(
        "Input: `{}`. Units SI; angles relative to the imbalance.",
        r.file
    )));
    grinder(&mut rep, r);
    criterion(&mut rep, r);
    operating(&mut rep, r);
    if !r.cutting_scan.is_empty() {
        cutting_scan(&mut rep, r);
    }
    sweep(&mut rep, r);
    runup(&mut rep, r);
    let figs = figures(&r.outputs, |f| match f {
        "sweep.svg" => "Housing vibration and ball angles over the speed sweep".into(),
        _ => "Run-up from rest: speed, vibration, ball angles, residual imbalance".into(),
    });
    if !figs.is_empty() {
        rep.section("plots", "Plots").blocks = figs;
    }
    Ok(rep)
}

/// An amplitude in µm with three digits; below 1e-12 m (rounding of the integration) as text.
fn um(v: f64) -> Cell {
    if v.abs() < 1e-12 {
        Cell::text("< 1e-6")
    } else {
        Cell::Num {
            value: v * 1e6,
            digits: 3,
        }
    }
}

fn num(value: f64, digits: usize) -> Cell {
    Cell::Num { value, digits }
}

fn angles(a: &[f64], digits: usize) -> Cell {
    Cell::text(a.iter().map(|x| fmt_sig(*x, digits)).collect::<Vec<_>>().join(", "))
}

fn yes(b: bool) -> Cell {
    Cell::text(if b { "yes" } else { "no" })
}

fn q(id: &str, name: &str, unit: &str, value: f64, digits: usize) -> QuantityRow {
    let mut q = QuantityRow::new(id, name, unit, value);
    q.digits = digits;
    q
}

fn table(id: &str, columns: Vec<Column>, rows: Vec<Vec<Cell>>) -> Block {
    Block::Table(Table {
        id: id.into(),
        caption: None,
        columns,
        rows,
    })
}

fn grinder(rep: &mut Report, r: &AutobalancerReport) {
    let g = &r.grinder;
    let mut lines = vec![
        format!(
            "rocker: arm l = {} m, J_0 = {} kg·m², hinge c = {} N/m, h = {} N·s/m",
            g.arm,
            g.rocker_inertia,
            fmt_sig(g.stiffness, 4),
            fmt_sig(g.damping, 4)
        ),
        format!(
            "disc: m_d = {} kg, J_d = {} kg·m², R = {} m; imbalance {} g at {} mm ({} g·mm) at {}°; speed {} rpm",
            g.disc_mass,
            g.disc_inertia,
            g.disc_radius,
            fmt_sig(g.imbalance_mass * 1e3, 3),
            fmt_sig(g.imbalance_radius * 1e3, 3),
            fmt_sig(g.imbalance_mass * g.imbalance_radius * 1e6, 3),
            fmt_sig(g.imbalance_angle.to_degrees(), 3),
            fmt_sig(r.figures.speed_rpm, 5)
        ),
    ];
    for (i, b) in g.balls.iter().enumerate() {
        lines.push(format!(
            "ball {}: {} g on a {} mm race, drag {} N·s/m, starts at {}°",
            i + 1,
            fmt_sig(b.mass * 1e3, 3),
            fmt_sig(b.radius * 1e3, 3),
            b.drag,
            fmt_sig(b.initial_angle.to_degrees(), 3)
        ));
    }
    if let Some(c) = &r.cutting {
        lines.push(format!(
            "cutting: c_r = {} N/m, f_r = {}, θ = {}°, moment {} N·m",
            fmt_sig(c.surface_stiffness, 3),
            c.friction,
            fmt_sig(c.contact_angle.to_degrees(), 3),
            c.moment
        ));
    }
    rep.section("grinder", "Grinder").push(Block::Text(lines.join("\n")));
}

fn criterion(rep: &mut Report, r: &AutobalancerReport) {
    let f = &r.figures;
    let mut rows = vec![
        q("inertia", "J with the balls", "kg·m²", f.inertia, 4),
        q("omega0", "ω_0 = √(c l²/J)", "rad/s", f.omega0, 4),
        q("omega0_rpm", "ω_0", "rpm", f.omega0_rpm, 4),
        q("h_tilde", "h̃", "1/s", f.h_tilde, 4),
        q("epsilon", "ε = l m_0 R_0/J", "", f.epsilon, 3),
        q("ratio", "operating ω/ω_0", "", f.ratio, 3),
        q("n_factor", "N at the operating speed", "", f.n_factor, 4),
        q(
            "mean_projection",
            "mean projection l ε N/2 of the disc centre",
            "µm",
            f.mean_projection * 1e6,
            3,
        ),
    ];
    // Why no speed balances, when the balls cannot cancel the imbalance in any placement.
    let cannot = (!f.balls_can_cancel).then(|| {
        if r.grinder.balls.is_empty() {
            "no balls".to_string()
        } else {
            format!(
                "the balls cannot cancel the imbalance in any placement: capacity Σ m R = {} m_0 R_0, and no ball may outweigh the others by more than m_0 R_0",
                fmt_sig(f.capacity_ratio, 3)
            )
        }
    });
    let verdict = |balances: bool, below: &str| match (&cannot, balances) {
        (_, true) => "balances".to_string(),
        (Some(why), false) => format!("does not balance ({why})"),
        (None, false) => format!("does not balance ({below})"),
    };
    let mut verdicts = vec![format!(
        "idle: {}",
        if f.balances_idle {
            "balances (ω > ω_0)".to_string()
        } else {
            verdict(false, "ω ≤ ω_0")
        }
    )];
    if let (Some(w0c), Some(b), Some(cr), Some(crp)) =
        (f.omega0_cutting, f.balances_cutting, f.cr_bound, f.cr_bound_paper)
    {
        rows.push(q("omega0_cutting", "ω_0' while cutting", "rad/s", w0c, 4));
        // A bound only where one exists: none is needed when cutting does not raise ω_0 (at
        // this contact angle), and none helps when the grinder does not balance even at idle.
        if cr.is_finite() && cr > 0.0 {
            rows.push(q(
                "cr_bound",
                "surface stiffness bound c_r at the given θ",
                "N/m",
                cr,
                4,
            ));
        } else if cr > 0.0 {
            verdicts.push("surface stiffness: no bound (at this contact angle cutting does not raise ω_0)".into());
        } else {
            verdicts.push("surface stiffness: no c_r balances (the grinder does not balance even at idle)".into());
        }
        if crp.is_finite() && crp > 0.0 {
            rows.push(
                q(
                    "cr_bound_paper",
                    "surface stiffness bound c_r, seed's closed form",
                    "N/m",
                    crp,
                    4,
                )
                .note("worst θ, cos θ = −f_r/2"),
            );
        }
        verdicts.push(format!("cutting: {}", verdict(b, "ω ≤ ω_0'")));
    }
    rows.push(q("capacity", "ball capacity Σ m R / m_0 R_0", "", f.capacity_ratio, 3));
    if let Some(a) = f.balanced_angles_deg {
        rows.push(q("balanced_angle_1", "balanced ball angle 1", "deg", a[0], 4));
        rows.push(q("balanced_angle_2", "balanced ball angle 2", "deg", a[1], 4));
    }
    rep.section("criterion", "Linear criterion (closed form)")
        .push(Block::Quantities(rows))
        .push(Block::Text(verdicts.join("\n")));
}

fn operating(rep: &mut Report, r: &AutobalancerReport) {
    let rows = r
        .operating
        .iter()
        .map(|o| {
            vec![
                Cell::text(&o.case),
                um(o.with_balls.amplitude),
                um(o.without_balls.amplitude),
                angles(&o.with_balls.ball_angles_deg, 4),
                num(o.with_balls.residual, 2),
                yes(o.balanced),
            ]
        })
        .collect();
    let columns = vec![
        Column::new("case", None),
        Column::new("amplitude with balls", Some("µm")),
        Column::new("without balls", Some("µm")),
        Column::new("ball angles", Some("deg")),
        Column::new("residual", None),
        Column::new("balanced", None),
    ];
    let sec = rep.section("operating", "Nonlinear model at the operating speed");
    if r.figures.h_tilde == 0.0 {
        // Nothing damps the rocker's free vibration from the start: it stays in the amplitudes.
        sec.push(Block::Text(
            "The hinge has no damping: the rocker's free vibration from the start never decays and is in both \
             amplitudes; whether the balls balance is read from the residual imbalance."
                .into(),
        ));
    }
    sec.push(table("operating", columns, rows));
}

fn cutting_scan(rep: &mut Report, r: &AutobalancerReport) {
    let rows = r
        .cutting_scan
        .iter()
        .map(|row| {
            vec![
                num(row.fraction_of_bound, 3),
                num(row.surface_stiffness, 4),
                num(row.ratio, 4),
                um(row.amplitude_with_balls),
                num(row.residual, 2),
                num(row.drift_deg_s, 2),
                yes(row.balanced),
            ]
        })
        .collect();
    let columns = vec![
        Column::new("c_r / bound", None),
        Column::new("c_r", Some("N/m")),
        Column::new("ω/ω_0'", None),
        Column::new("amplitude with balls", Some("µm")),
        Column::new("residual", None),
        Column::new("drift", Some("deg/s")),
        Column::new("balanced", None),
    ];
    rep.section("cutting", "Cutting: surface stiffness against its bound")
        .push(Block::Text(
            "Nonlinear model at the operating speed, c_r as a fraction of the bound (at the file's contact angle); \
             ω_0' is the rocker frequency while cutting."
                .into(),
        ))
        .push(table("cutting", columns, rows));
}

fn sweep(rep: &mut Report, r: &AutobalancerReport) {
    let rows = r
        .sweep
        .iter()
        .map(|row| {
            vec![
                num(row.ratio, 3),
                num(row.speed_rpm, 4),
                um(row.amplitude_with_balls),
                um(row.amplitude_without_balls),
                angles(&row.ball_angles_deg, 3),
                num(row.residual, 2),
                num(row.drift_deg_s, 2),
                yes(row.balanced),
                Cell::text(if row.predicted { "balances" } else { "no" }),
            ]
        })
        .collect();
    let columns = vec![
        Column::new("ω/ω_0", None),
        Column::new("speed", Some("rpm")),
        Column::new("with balls", Some("µm")),
        Column::new("without balls", Some("µm")),
        Column::new("ball angles", Some("deg")),
        Column::new("residual", None),
        Column::new("drift", Some("deg/s")),
        Column::new("balanced", None),
        Column::new("linear criterion", None),
    ];
    rep.section("sweep", "Speed sweep at idle")
        .push(Block::Text(format!(
            "Each speed: {} s from the balls' initial angles, steady values over the last 10 revolutions. \
             Balanced = residual imbalance below {} % of the disc's.",
            fmt_sig(r.sweep_duration, 3),
            BALANCED_RESIDUAL * 100.0
        )))
        .push(table("sweep", columns, rows));
    let threshold = match r.threshold_ratio {
        Some((a, b)) => format!(
            "Unbalanced at ω/ω_0 = {}, balanced from {} on (linear criterion: 1).",
            fmt_sig(a, 3),
            fmt_sig(b, 3)
        ),
        None => "No threshold inside the sweep (all rows balanced, or the fastest not).".into(),
    };
    rep.section("threshold", "Balancing threshold of the sweep")
        .push(Block::Text(threshold));
}

fn runup(rep: &mut Report, r: &AutobalancerReport) {
    let u = &r.runup;
    let mut rows = vec![
        q(
            "peak_with",
            "largest vibration with balls",
            "µm",
            u.peak_with_balls.0 * 1e6,
            3,
        ),
        q("peak_with_time", "at the time", "s", u.peak_with_balls.1, 3),
        q(
            "peak_speed",
            "at the disc speed",
            "rpm",
            u.speed_at_peak * 60.0 / TAU,
            4,
        ),
        q(
            "peak_without",
            "largest vibration without balls",
            "µm",
            u.peak_without_balls.0 * 1e6,
            3,
        ),
        q("peak_without_time", "at the time", "s", u.peak_without_balls.1, 3),
        {
            let row = q(
                "max_residual",
                "largest residual imbalance",
                "× m_0 R_0",
                u.max_residual,
                3,
            );
            // The balls bunch with the imbalance below ω_0: the largest residual is met while
            // passing it, or all along when the disc never gets past it.
            match (r.grinder.balls.is_empty(), r.figures.ratio > 1.0) {
                (true, _) => row.note("no balls: the disc's imbalance alone"),
                (false, true) => row.note("balls bunched with the imbalance while passing ω_0"),
                (false, false) => row.note("balls bunched with the imbalance: the disc stays below ω_0"),
            }
        },
    ];
    if let Some(t) = u.balanced_from {
        rows.push(q("balanced_from", "balanced from", "s", t, 3));
    }
    rows.push(q(
        "end_amplitude",
        "amplitude at the end",
        "µm",
        u.end.amplitude * 1e6,
        3,
    ));
    let mut text = vec![if r.grinder.balls.is_empty() {
        format!(
            "The disc accelerates linearly to the operating speed in {} s; there are no balls.",
            fmt_sig(u.ramp_time, 3)
        )
    } else {
        format!(
            "The disc accelerates linearly to the operating speed in {} s; the balls start at rest on the disc. \
             At the end the balls are at {}°.",
            fmt_sig(u.ramp_time, 3),
            u.end
                .ball_angles_deg
                .iter()
                .map(|a| fmt_sig(*a, 4))
                .collect::<Vec<_>>()
                .join("°, ")
        )
    }];
    if u.balanced_from.is_none() {
        text.push("Not balanced within the run.".into());
    }
    rep.section("runup", "Run-up from rest")
        .push(Block::Text(text.join("\n")))
        .push(Block::Quantities(rows));
}
