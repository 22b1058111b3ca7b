//! The design's report: [`DesignReport`] as a [`Report`] (checks first, the quantities against
//! the paper, the work table's and the 3D machine's modes, notes, figures, timings). The text,
//! `report.md` and `report.html` come from the one renderer ([`crate::app::report::render`]);
//! `report.json` and `design --json` are the [`DesignReport`] itself.

use super::plots::FIGURES;
use super::results::{Check, DesignReport, Quantity};
use crate::Result;
use crate::app::report::{Block, Cell, CheckRow, Column, Figure, QuantityRow, Report, Table, render};
use std::path::Path;

/// The run as a report.
pub fn report(r: &DesignReport) -> Report {
    let data = serde_json::to_value(r).unwrap_or(serde_json::Value::Null);
    let mut rep = Report::new(format!("design: {}", r.name), data);
    rep.section("checks", "Checks")
        .push(Block::Checks(r.checks.iter().map(check_row).collect()));
    rep.section("inputs", "Inputs and assumptions")
        .push(Block::Table(inputs(r)));
    rep.section("floor", "Force on the floor (isolators)")
        .push(Block::Table(floor(r)));
    rep.section("quantities", "Quantities")
        .push(Block::Quantities(r.quantities.iter().map(quantity_row).collect()));
    rep.section("table_modes", "Work-table elastic frequencies (shell model)")
        .push(Block::Table(table_modes(r)));
    if !r.machine_modes.is_empty() {
        rep.section("machine_modes", "3D machine modes")
            .push(Block::Table(machine_modes(r)));
    }
    if !r.notes.is_empty() {
        rep.section("notes", "Notes").push(Block::Notes(r.notes.clone()));
    }
    let plots = rep.section("plots", "Plots");
    for (i, (file, caption)) in FIGURES.iter().enumerate() {
        plots.push(Block::Figure(Figure {
            id: format!("figure{}", i + 1),
            file: (*file).into(),
            caption: (*caption).into(),
        }));
    }
    plots.push(Block::Text(
        "Mode shapes: table_modes.vtu (ParaView), table_modes.msh (gmsh); forced response of the 3D machine: \
         machine_response.vtu."
            .into(),
    ));
    rep.section("timings", "").push(Block::Text(timings(r)));
    rep
}

/// A check's name without its unit, and the unit given in it as `[unit]` (empty: none).
pub(super) fn name_and_unit(name: &str) -> (&str, &str) {
    match name.rsplit_once(" [") {
        Some((n, u)) if u.ends_with(']') => (n, u.trim_end_matches(']')),
        _ => (name, ""),
    }
}

/// A check as a report row: the unit, given in the name as `[unit]`, goes to its column.
fn check_row(c: &Check) -> CheckRow {
    let (name, unit) = name_and_unit(&c.name);
    let row = if c.upper {
        CheckRow::upper(&c.id, name, unit, c.value, c.limit)
    } else {
        CheckRow::lower(&c.id, name, unit, c.value, c.limit)
    };
    // Percentages against percentages: the margin in points, not a percentage of a percentage.
    if unit == "%" { row.in_points() } else { row }
}

fn quantity_row(q: &Quantity) -> QuantityRow {
    QuantityRow::new(&q.id, &q.name, &q.unit, q.value)
        .published(q.published)
        .note(&q.note)
}

/// The inputs and assumptions with their sources.
fn inputs(r: &DesignReport) -> Table {
    Table {
        id: "inputs".into(),
        caption: None,
        columns: vec![
            Column::new("input", None),
            Column::new("value", None),
            Column::new("source", None),
        ],
        rows: r
            .inputs
            .iter()
            .map(|i| {
                vec![
                    Cell::text(i.name.clone()),
                    Cell::text(i.value.clone()),
                    Cell::text(i.source.clone()),
                ]
            })
            .collect(),
    }
}

/// The floor forces: per harmonic, both models' totals and the 3D machine's largest isolator.
fn floor(r: &DesignReport) -> Table {
    let f = &r.floor_force;
    Table {
        id: "floor_force".into(),
        caption: Some(format!(
            "{} force law; the two-mass model shares its force equally among the isolators",
            r.force_law
        )),
        columns: vec![
            Column::new("harmonic", None),
            Column::new("f", Some("Hz")),
            Column::new("two-mass total", Some("N")),
            Column::new("3D total", Some("N")),
            Column::new("3D largest isolator", Some("N")),
            Column::new("3D smallest isolator", Some("N")),
        ],
        rows: f
            .machine
            .iter()
            .map(|m| {
                let two = f
                    .two_mass
                    .iter()
                    .find(|t| t.harmonic == m.harmonic)
                    .map_or(f64::NAN, |t| t.total);
                vec![
                    Cell::Fixed {
                        value: m.harmonic as f64,
                        decimals: 0,
                    },
                    Cell::num(m.frequency_hz),
                    Cell::num(two),
                    Cell::num(m.total),
                    Cell::num(m.per_isolator.iter().copied().fold(0.0, f64::max)),
                    Cell::num(m.per_isolator.iter().copied().fold(f64::INFINITY, f64::min)),
                ]
            })
            .collect(),
    }
}

/// The work table's first six elastic modes (7 to 12 of the free–free table).
fn table_modes(r: &DesignReport) -> Table {
    Table {
        id: "table_modes".into(),
        caption: None,
        columns: vec![Column::new("mode", None), Column::new("f", Some("Hz"))],
        rows: r
            .table_frequencies_hz
            .iter()
            .enumerate()
            .map(|(i, f)| {
                vec![
                    Cell::Fixed {
                        value: (i + 7) as f64,
                        decimals: 0,
                    },
                    Cell::num(*f),
                ]
            })
            .collect(),
    }
}

/// The 3D machine's modes with their strain-energy split.
fn machine_modes(r: &DesignReport) -> Table {
    let pct = |value: f64| Cell::Pct { value, decimals: 1 };
    Table {
        id: "machine_modes".into(),
        caption: None,
        columns: vec![
            Column::new("#", None),
            Column::new("f", Some("Hz")),
            Column::new("strain energy: leaves", None),
            Column::new("isolators", None),
            Column::new("table", None),
            Column::new("kinetic in m2", None),
            Column::new("mode", None),
        ],
        rows: r
            .machine_modes
            .iter()
            .enumerate()
            .map(|(i, m)| {
                vec![
                    Cell::Fixed {
                        value: (i + 1) as f64,
                        decimals: 0,
                    },
                    Cell::num(m.frequency_hz),
                    pct(m.energy_leaves),
                    pct(m.energy_isolators),
                    pct(m.energy_table),
                    pct(m.kinetic_reactive),
                    Cell::text(m.name.clone()),
                ]
            })
            .collect(),
    }
}

/// `time: step 1.2 s, …  (total 9.9 s)`.
fn timings(r: &DesignReport) -> String {
    let total: f64 = r.timings_s.iter().map(|t| t.1).sum();
    let steps: Vec<String> = r.timings_s.iter().map(|(n, t)| format!("{n} {t:.1} s")).collect();
    format!("time: {}  (total {total:.1} s)", steps.join(", "))
}

/// The report as terminal text.
pub fn verdict_text(r: &DesignReport) -> String {
    render::text(&report(r))
}

/// The report as markdown (`report.md`).
pub fn report_markdown(r: &DesignReport) -> String {
    render::markdown(&report(r))
}

/// The report as one self-contained HTML page (`report.html`), the figures inlined from `dir`.
pub fn report_html(r: &DesignReport, dir: &Path) -> String {
    render::html(&report(r), dir)
}

/// Write `report.md`, `report.html` and `report.json` into `dir` (beside the figures).
pub fn write(r: &DesignReport, dir: &Path) -> Result<()> {
    render::write_all(&report(r), dir)
}
