//! The crank-drive result ([`CrankReport`]) as a [`Report`]: drive, motor, steady state, the
//! setups against the paper's Table 1, the runs from rest, notes and plots.

use super::model::Metrics;
use super::run::{CrankReport, law_name};
use crate::Result;
use crate::app::machines::{figures, report_of};
use crate::app::report::{Block, Cell, Column, QuantityRow, Report, Table, fmt_sig};

/// Sections printed on the terminal.
pub const SUMMARY: &[&str] = &["drive", "steady", "setups", "startup", "notes"];

/// The report of a crank-drive run; its data is `r` serialised.
pub fn report(r: &CrankReport) -> Result<Report> {
    let mut rep = report_of(format!("Crank drive: {}", r.name), r)?;
    rep.section("input", "").push(Block::Text(format!(
        "Input: `{}`. Units SI; speeds of the crank shaft in rad/s.",
        r.file
    )));
    drive(&mut rep, r);
    motor(&mut rep, r);
    steady(&mut rep, r);
    if !r.setups.is_empty() {
        setups(&mut rep, r);
    }
    startup(&mut rep, r);
    if !r.notes.is_empty() {
        rep.section("notes", "Notes").push(Block::Notes(r.notes.clone()));
    }
    let figs = figures(&r.outputs, |f| match f {
        "crank_drive.svg" => "Reduced inertia, moments, speed and acceleration on the steady revolution".into(),
        "setups.svg" => "The setups: speed, resisting moment and reduced inertia".into(),
        _ => "Start-up from rest".into(),
    });
    if !figs.is_empty() {
        rep.section("plots", "Plots").blocks = figs;
    }
    Ok(rep)
}

fn q(id: &str, name: &str, unit: &str, value: f64, digits: usize) -> QuantityRow {
    let mut q = QuantityRow::new(id, name, unit, value);
    q.digits = digits;
    q
}

fn drive(rep: &mut Report, r: &CrankReport) {
    let d = &r.drive;
    let m = &d.mechanism;
    let phases: Vec<String> = m.phases.iter().map(|p| fmt_sig(p.to_degrees(), 4)).collect();
    let text = format!(
        "{} cart(s), crank phases {} deg; r = {} m, l = {} m (λ = {}), q = {} kg/m, m = {} kg, F = {} N per cart\n\
         reducer i = {}, η = {}, drive inertia I_p = {} kg·m² on the motor shaft (I_p i² = {} kg·m²)",
        m.phases.len(),
        phases.join(", "),
        m.crank_radius,
        m.rod_length,
        fmt_sig(m.lambda(), 3),
        m.rod_mass_per_length,
        m.cart_mass,
        m.cart_resistance,
        d.reducer.ratio,
        d.reducer.efficiency,
        d.reducer.inertia,
        fmt_sig(d.reducer.inertia * d.reducer.ratio * d.reducer.ratio, 4)
    );
    let rows = vec![
        q("inertia_min", "reduced inertia, least", "kg·m²", r.inertia_range[0], 4),
        q(
            "inertia_max",
            "reduced inertia, largest",
            "kg·m²",
            r.inertia_range[1],
            4,
        ),
        q(
            "resisting_min",
            "resisting moment, least",
            "N·m",
            r.resisting_range[0],
            4,
        ),
        q(
            "resisting_max",
            "resisting moment, largest",
            "N·m",
            r.resisting_range[1],
            4,
        ),
        q(
            "mean_resisting",
            "mean resisting moment",
            "N·m",
            r.mean_resisting_moment,
            6,
        ),
        q(
            "mean_resisting_closed",
            "mean resisting moment, closed form n·2Fr/π",
            "N·m",
            r.mean_resisting_moment_closed_form,
            6,
        ),
        q("design_power", "design power M_mean·ω/η", "kW", r.design_power / 1e3, 4)
            .note(&format!("at {} rad/s", r.design_speed)),
    ];
    rep.section("drive", "Drive")
        .push(Block::Text(text))
        .push(Block::Quantities(rows));
}

fn motor(rep: &mut Report, r: &CrankReport) {
    let m = &r.motor;
    let mut rows = Vec::new();
    if let (Some(w), Some(t)) = (m.nominal_speed, m.torque_at_nominal) {
        rows.push(
            q("torque_nominal", "motor torque at the nominal speed", "N·m", t, 4)
                .published(m.catalogue_nominal_torque)
                .note(&format!("at {w} rad/s; published: catalogue")),
        );
    }
    rows.push(
        q(
            "kloss_standstill",
            "Kloss torque at standstill",
            "N·m",
            m.kloss_at_standstill,
            3,
        )
        .published(m.catalogue_starting_torque)
        .note("published: catalogue starting torque"),
    );
    rows.push(q(
        "torque_standstill",
        "the law's torque at standstill",
        "N·m",
        m.torque_at_standstill,
        4,
    ));
    rows.push(q(
        "moment_rest",
        "driving moment at the crank at standstill",
        "N·m",
        m.driving_moment_at_rest,
        4,
    ));
    rows.push(q(
        "moment_critical",
        "driving moment at the crank at the critical speed",
        "N·m",
        m.driving_moment_at_critical,
        4,
    ));
    rep.section("motor", &format!("Motor ({})", law_name(r.drive.motor.law)))
        .push(Block::Quantities(rows));
}

/// Columns ω_min … k_p of a metrics row.
fn metric_columns() -> Vec<Column> {
    vec![
        Column::new("ω_min", Some("rad/s")),
        Column::new("ω_max", Some("rad/s")),
        Column::new("ω_mean", Some("rad/s")),
        Column::new("|ε|max", Some("rad/s²")),
        Column::new("δ", None),
        Column::new("μ", None),
        Column::new("k_p", None),
    ]
}

fn num(value: f64, digits: usize) -> Cell {
    Cell::Num { value, digits }
}

fn opt(v: Option<f64>, digits: usize) -> Cell {
    v.map_or(Cell::Empty, |v| num(v, digits))
}

/// The cells of [`metric_columns`] (a stalled run: "stalls" and empty cells).
fn metric_cells(m: &Option<Metrics>) -> Vec<Cell> {
    match m {
        Some(m) => vec![
            num(m.omega_min, 4),
            num(m.omega_max, 4),
            num(m.omega_mean, 5),
            num(m.eps_max, 4),
            num(m.delta, 3),
            num(m.mu, 3),
            num(m.k_p, 3),
        ],
        None => {
            let mut v = vec![Cell::text("stalls")];
            v.resize(7, Cell::Empty);
            v
        }
    }
}

fn steady(rep: &mut Report, r: &CrankReport) {
    let mut columns = vec![
        Column::new("integrator", None),
        Column::new("revolutions", None),
        Column::new("steady", None),
    ];
    columns.extend(metric_columns());
    columns.push(Column::new("midrange", Some("rad/s")));
    columns.push(Column::new("angle mean", Some("rad/s")));
    let rows = [&r.baranov, &r.energy_form]
        .iter()
        .map(|run| {
            let mut row = vec![
                Cell::text(&run.method),
                Cell::Fixed {
                    value: run.revolutions as f64,
                    decimals: 0,
                },
                Cell::text(if run.converged { "yes" } else { "no" }),
            ];
            row.extend(metric_cells(&run.metrics));
            row.push(opt(run.omega_midrange, 5));
            row.push(opt(run.omega_angle_mean, 5));
            row
        })
        .collect();
    let stalls: Vec<String> = [&r.baranov, &r.energy_form]
        .iter()
        .filter_map(|run| run.stall.as_ref().map(|st| format!("{}: {}", run.method, st.message)))
        .collect();
    let s = rep.section(
        "steady",
        &format!("Steady state from {} rad/s", fmt_sig(r.start_speed, 4)),
    );
    s.push(Block::Table(Table {
        id: "steady".into(),
        caption: None,
        columns,
        rows,
    }));
    if !stalls.is_empty() {
        s.push(Block::Notes(stalls));
    }
    s.push(Block::Text(
        "Baranov's step is first order in Δφ; the adaptive integrator holds a local error of rtol per step. \
         ω_mean is the time mean 2π/T of the revolution."
            .into(),
    ));
}

fn setups(rep: &mut Report, r: &CrankReport) {
    let mut columns = vec![
        Column::new("setup", None),
        Column::new("M_mean", Some("N·m")),
        Column::new("P", Some("kW")),
        Column::new("motor ×", None),
        Column::new("source", None),
    ];
    columns.extend(metric_columns());
    let mut rows = Vec::new();
    for row in &r.setups {
        let mut cells = vec![
            Cell::text(&row.name),
            num(row.mean_moment, 5),
            num(row.design_power / 1e3, 4),
            num(row.torque_scale, 3),
            Cell::text("vibrofem"),
        ];
        cells.extend(metric_cells(&row.metrics));
        rows.push(cells);
        if let (Some(p), Some(q)) = (&row.paper, &row.paper_recomputed) {
            let mut printed = vec![Cell::Empty, Cell::Empty, Cell::Empty, Cell::Empty, Cell::text("paper")];
            for v in [p.omega_min, p.omega_max, p.omega_mean, p.eps_max, p.delta, p.mu, p.k_p] {
                printed.push(Cell::text(format!("{v}")));
            }
            rows.push(printed);
            let mut recomputed = vec![
                Cell::Empty,
                Cell::Empty,
                Cell::Empty,
                Cell::Empty,
                Cell::text("paper's extremes → metrics"),
            ];
            recomputed.extend([Cell::Empty, Cell::Empty, Cell::Empty, Cell::Empty]);
            recomputed.extend([num(q.delta, 4), num(q.mu, 4), num(q.k_p, 4)]);
            rows.push(recomputed);
        }
    }
    let stalls: Vec<String> = r
        .setups
        .iter()
        .filter_map(|row| row.stall.as_ref().map(|m| format!("{}: {m}", row.name)))
        .collect();
    let s = rep.section("setups", "Setups against the paper's Table 1");
    s.push(Block::Text(format!(
        "Adaptive integrator, steady revolution from {} rad/s. \"motor ×\" is the factor on the motor torque \
         (\"power\": the ratio of mean resisting moments). The paper's rows show its printed values and the \
         metrics recomputed from its extremes.",
        fmt_sig(r.start_speed, 4)
    )));
    s.push(Block::Table(Table {
        id: "setups".into(),
        caption: None,
        columns,
        rows,
    }));
    if !stalls.is_empty() {
        s.push(Block::Notes(stalls));
    }
}

fn startup(rep: &mut Report, r: &CrankReport) {
    let rows = r
        .startup
        .iter()
        .map(|st| {
            let outcome = match &st.stall {
                Some(x) => format!("stalls at t = {} s", fmt_sig(x.t, 3)),
                None => format!("runs up ({} revolutions in all)", fmt_sig(st.revolutions, 3)),
            };
            vec![
                Cell::text(&st.case),
                Cell::text(outcome),
                opt(st.time_to_95, 3),
                opt(st.revolutions_to_95, 3),
                opt(st.metrics.map(|m| m.omega_mean), 5),
                opt(st.metrics.map(|m| m.delta), 3),
                opt(st.metrics.map(|m| m.mu), 3),
            ]
        })
        .collect();
    let stalls: Vec<String> = r
        .startup
        .iter()
        .filter_map(|st| st.stall.as_ref().map(|x| format!("{}: {}", st.case, x.message)))
        .collect();
    let s = rep.section("startup", "Start-up from rest");
    s.push(Block::Text(
        "Time domain, (φ, ω) by Dormand–Prince; the cart resistance holds the drive at rest while the motor \
         cannot move it."
            .into(),
    ));
    s.push(Block::Table(Table {
        id: "startup".into(),
        caption: None,
        columns: vec![
            Column::new("case", None),
            Column::new("outcome", None),
            Column::new("time to 95 % of ω_mean", Some("s")),
            Column::new("revolutions by then", None),
            Column::new("steady ω_mean", Some("rad/s")),
            Column::new("δ", None),
            Column::new("μ", None),
        ],
        rows,
    }));
    if !stalls.is_empty() {
        s.push(Block::Notes(stalls));
    }
}
