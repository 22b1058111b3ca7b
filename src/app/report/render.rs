//! The renderers: one per format, each writing every [`Block`] kind the same way for every
//! report.
//!
//! - [`text`]: the terminal (fixed-width columns);
//! - [`markdown`]: `report.md` (GitHub tables, figures as image links);
//! - [`html`]: `report.html`, one self-contained page (the SVG figures inlined);
//! - [`json`]: `report.json`, the report's data payload.

use super::{Block, Cell, CheckRow, QuantityRow, Report, Section, Table, fmt_sig};
use crate::{Error, Result};
use std::fmt::Write;
use std::path::Path;

/// A section's heading: its title, with the verdict of its checks when it has any
/// (`Checks: all passed`).
fn heading(s: &Section) -> String {
    let checks: Vec<&CheckRow> = s
        .blocks
        .iter()
        .flat_map(|b| match b {
            Block::Checks(c) => c.as_slice(),
            _ => &[],
        })
        .collect();
    if checks.is_empty() {
        return s.title.clone();
    }
    let failed = checks.iter().filter(|c| !c.ok).count();
    let verdict = if failed == 0 {
        "all passed".to_string()
    } else {
        format!("{failed} of {} failed", checks.len())
    };
    format!("{}: {verdict}", s.title)
}

/// A check's margin as printed ([`margin_text`]).
fn margin(c: &CheckRow) -> String {
    margin_text(c.margin, c.points)
}

/// A margin as every table prints it: a fraction of the limit as `+12.3 %`, or a difference in
/// percentage points (`points`) as `+1.2 points`.
pub fn margin_text(margin: f64, points: bool) -> String {
    if points {
        format!("{margin:+.1} points")
    } else {
        format!("{:+.1} %", 100.0 * margin)
    }
}

/// The published value as its source gives it and the difference, or a dash and nothing.
fn published(q: &QuantityRow) -> (String, String) {
    match (q.published, q.difference()) {
        (Some(p), Some(d)) => (
            if p != 0.0 && !(1e-3..1e5).contains(&p.abs()) {
                format!("{p:e}")
            } else {
                format!("{p}")
            },
            format!("{:+.1} %", 100.0 * d),
        ),
        _ => ("–".into(), String::new()),
    }
}

fn any_published(q: &[QuantityRow]) -> bool {
    q.iter().any(|x| x.published.is_some())
}

/// The report as terminal text.
pub fn text(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{}", r.title);
    for sec in &r.sections {
        let h = heading(sec);
        if !h.is_empty() {
            let _ = writeln!(s, "\n{h}");
        }
        for b in &sec.blocks {
            text_block(&mut s, b);
        }
    }
    s
}

fn text_block(s: &mut String, b: &Block) {
    match b {
        Block::Checks(rows) => {
            for c in rows {
                let unit = if c.unit.is_empty() {
                    String::new()
                } else {
                    format!(" {}", c.unit)
                };
                let _ = writeln!(
                    s,
                    "  [{}] {:<56} {:>10} vs {:>10}{unit}  margin {}",
                    if c.ok { " ok " } else { "FAIL" },
                    c.name,
                    fmt_sig(c.value, 4),
                    fmt_sig(c.limit, 4),
                    margin(c)
                );
            }
        }
        Block::Quantities(rows) => {
            if any_published(rows) {
                let _ = writeln!(
                    s,
                    "{:<48} {:>11} {:>11} {:>9}  {:<6} note",
                    "quantity", "value", "published", "diff", "unit"
                );
            } else {
                let _ = writeln!(s, "{:<48} {:>11}  {:<6} note", "quantity", "value", "unit");
            }
            for q in rows {
                let v = fmt_sig(q.value, q.digits);
                if any_published(rows) {
                    let (p, d) = published(q);
                    let _ = writeln!(s, "{:<48} {v:>11} {p:>11} {d:>9}  {:<6} {}", q.name, q.unit, q.note);
                } else {
                    let _ = writeln!(s, "{:<48} {v:>11}  {:<6} {}", q.name, q.unit, q.note);
                }
            }
        }
        Block::Table(t) => text_table(s, t),
        Block::Figure(f) => {
            let _ = writeln!(s, "figure: {} ({})", f.file, f.caption);
        }
        Block::Notes(n) => {
            for n in n {
                let _ = writeln!(s, "note: {n}");
            }
        }
        Block::Text(t) => {
            let _ = writeln!(s, "{}", t.trim_end());
        }
    }
}

/// A table in fixed-width columns: numbers right-aligned, text left-aligned.
fn text_table(s: &mut String, t: &Table) {
    if let Some(c) = &t.caption {
        let _ = writeln!(s, "{c}");
    }
    let heads: Vec<String> = t.columns.iter().map(|c| c.heading()).collect();
    let cells: Vec<Vec<String>> = t.rows.iter().map(|r| r.iter().map(Cell::show).collect()).collect();
    let mut w: Vec<usize> = heads.iter().map(|h| h.chars().count()).collect();
    for row in &cells {
        for (j, c) in row.iter().enumerate() {
            if j < w.len() {
                w[j] = w[j].max(c.chars().count());
            }
        }
    }
    let numeric = |j: usize| t.rows.iter().any(|r| r.get(j).is_some_and(Cell::numeric));
    let pad = |x: &str, j: usize| {
        let fill = w[j].saturating_sub(x.chars().count());
        if numeric(j) {
            format!("{}{x}", " ".repeat(fill))
        } else {
            format!("{x}{}", " ".repeat(fill))
        }
    };
    let line = |row: &[String]| {
        let parts: Vec<String> = row.iter().enumerate().take(w.len()).map(|(j, c)| pad(c, j)).collect();
        format!("  {}", parts.join("  ").trim_end())
    };
    let _ = writeln!(s, "{}", line(&heads));
    for row in &cells {
        let _ = writeln!(s, "{}", line(row));
    }
}

/// The report as markdown (`report.md`).
pub fn markdown(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# {}", r.title);
    for sec in &r.sections {
        let h = heading(sec);
        if !h.is_empty() {
            let _ = writeln!(s, "\n## {h}");
        }
        for b in &sec.blocks {
            s.push('\n');
            markdown_block(&mut s, b);
        }
    }
    s
}

/// A table cell's text with the characters that would break a markdown table escaped.
fn md_cell(t: &str) -> String {
    t.replace('|', "\\|").replace('\n', " ")
}

fn markdown_block(s: &mut String, b: &Block) {
    match b {
        Block::Checks(rows) => {
            let _ = writeln!(
                s,
                "| check | value | limit | unit | margin | verdict |\n|---|---:|---:|---|---:|---|"
            );
            for c in rows {
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} |",
                    md_cell(&c.name),
                    fmt_sig(c.value, 4),
                    fmt_sig(c.limit, 4),
                    md_cell(&c.unit),
                    margin(c),
                    if c.ok { "ok" } else { "**FAIL**" }
                );
            }
        }
        Block::Quantities(rows) => {
            let p = any_published(rows);
            let _ = writeln!(
                s,
                "| id | quantity | value |{} unit | note |\n|---|---|---:|{}---|---|",
                if p { " published | difference |" } else { "" },
                if p { "---:|---:|" } else { "" }
            );
            for q in rows {
                let (pv, d) = published(q);
                let pub_cells = if p { format!(" {pv} | {d} |") } else { String::new() };
                let _ = writeln!(
                    s,
                    "| `{}` | {} | {} |{pub_cells} {} | {} |",
                    q.id,
                    md_cell(&q.name),
                    fmt_sig(q.value, q.digits),
                    md_cell(&q.unit),
                    md_cell(&q.note)
                );
            }
        }
        Block::Table(t) => {
            if let Some(c) = &t.caption {
                let _ = writeln!(s, "*{c}*\n");
            }
            let heads: Vec<String> = t.columns.iter().map(|c| md_cell(&c.heading())).collect();
            let _ = writeln!(s, "| {} |", heads.join(" | "));
            let align: Vec<&str> = (0..t.columns.len())
                .map(|j| {
                    if t.rows.iter().any(|r| r.get(j).is_some_and(Cell::numeric)) {
                        "---:"
                    } else {
                        "---"
                    }
                })
                .collect();
            let _ = writeln!(s, "|{}|", align.join("|"));
            for row in &t.rows {
                let cells: Vec<String> = row.iter().map(|c| md_cell(&c.show())).collect();
                let _ = writeln!(s, "| {} |", cells.join(" | "));
            }
        }
        Block::Figure(f) => {
            let _ = writeln!(s, "![{}]({})", f.caption, f.file);
        }
        Block::Notes(n) => {
            for n in n {
                let _ = writeln!(s, "- {n}");
            }
        }
        Block::Text(t) => {
            let _ = writeln!(s, "{}", t.trim_end());
        }
    }
}

/// `&`, `<`, `>` and `"` escaped for HTML text and attributes.
pub fn html_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

const STYLE: &str = "body{font-family:sans-serif;max-width:72em;margin:2em auto;padding:0 1em}\
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:.25em .6em}\
td.n{text-align:right;font-variant-numeric:tabular-nums}.ok{color:#070}.fail{color:#b00;font-weight:bold}\
figure{margin:1.5em 0}figure svg{max-width:100%;height:auto}pre{white-space:pre-wrap}";

/// The report as one self-contained HTML page (`report.html`): the figures are read from
/// `dir` and inlined, so the page stands alone.
pub fn html(r: &Report, dir: &Path) -> String {
    let mut s = String::new();
    let t = html_escape(&r.title);
    let _ = writeln!(
        s,
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>{STYLE}</style></head><body>\n<h1>{t}</h1>"
    );
    for sec in &r.sections {
        let h = heading(sec);
        if !h.is_empty() {
            let _ = writeln!(s, "<h2 id=\"{}\">{}</h2>", html_escape(&sec.id), html_escape(&h));
        }
        for b in &sec.blocks {
            html_block(&mut s, b, dir);
        }
    }
    let _ = writeln!(s, "</body></html>");
    s
}

fn td_num(x: &str) -> String {
    format!("<td class=n>{x}</td>")
}

fn html_block(s: &mut String, b: &Block, dir: &Path) {
    match b {
        Block::Checks(rows) => {
            let _ = writeln!(
                s,
                "<table class=checks><tr><th>check</th><th>value</th><th>limit</th><th>unit</th><th>margin</th><th>verdict</th></tr>"
            );
            for c in rows {
                let _ = writeln!(
                    s,
                    "<tr><td>{}</td>{}{}<td>{}</td>{}<td class={}>{}</td></tr>",
                    html_escape(&c.name),
                    td_num(&fmt_sig(c.value, 4)),
                    td_num(&fmt_sig(c.limit, 4)),
                    html_escape(&c.unit),
                    td_num(&margin(c)),
                    if c.ok { "ok" } else { "fail" },
                    if c.ok { "ok" } else { "FAIL" }
                );
            }
            let _ = writeln!(s, "</table>");
        }
        Block::Quantities(rows) => {
            let p = any_published(rows);
            let _ = writeln!(
                s,
                "<table class=quantities><tr><th>id</th><th>quantity</th><th>value</th>{}<th>unit</th><th>note</th></tr>",
                if p { "<th>published</th><th>difference</th>" } else { "" }
            );
            for q in rows {
                let (pv, d) = published(q);
                let pub_cells = if p {
                    format!("{}{}", td_num(&pv), td_num(&d))
                } else {
                    String::new()
                };
                let _ = writeln!(
                    s,
                    "<tr><td><code>{}</code></td><td>{}</td>{}{pub_cells}<td>{}</td><td>{}</td></tr>",
                    html_escape(&q.id),
                    html_escape(&q.name),
                    td_num(&fmt_sig(q.value, q.digits)),
                    html_escape(&q.unit),
                    html_escape(&q.note)
                );
            }
            let _ = writeln!(s, "</table>");
        }
        Block::Table(t) => html_table(s, t),
        Block::Figure(f) => {
            // Inline the SVG (its XML prologue dropped) so the page stands alone.
            match std::fs::read_to_string(dir.join(&f.file)) {
                Ok(svg) => {
                    let body = svg.find("<svg").map_or(svg.as_str(), |i| &svg[i..]);
                    let _ = writeln!(
                        s,
                        "<figure id=\"{}\">{body}<figcaption>{}</figcaption></figure>",
                        html_escape(&f.id),
                        html_escape(&f.caption)
                    );
                }
                Err(_) => {
                    let _ = writeln!(
                        s,
                        "<p class=fail>figure {} not found beside the report</p>",
                        html_escape(&f.file)
                    );
                }
            }
        }
        Block::Notes(n) => {
            let _ = writeln!(s, "<ul class=notes>");
            for n in n {
                let _ = writeln!(s, "<li>{}</li>", html_escape(n));
            }
            let _ = writeln!(s, "</ul>");
        }
        Block::Text(t) => {
            let _ = writeln!(s, "<pre>{}</pre>", html_escape(t.trim_end()));
        }
    }
}

fn html_table(s: &mut String, t: &Table) {
    let _ = write!(s, "<table id=\"{}\">", html_escape(&t.id));
    if let Some(c) = &t.caption {
        let _ = write!(s, "<caption>{}</caption>", html_escape(c));
    }
    let _ = write!(s, "<tr>");
    for c in &t.columns {
        let _ = write!(s, "<th>{}</th>", html_escape(&c.heading()));
    }
    let _ = writeln!(s, "</tr>");
    for row in &t.rows {
        let _ = write!(s, "<tr>");
        for c in row {
            if c.numeric() {
                let _ = write!(s, "{}", td_num(&c.show()));
            } else {
                let _ = write!(s, "<td>{}</td>", html_escape(&c.show()));
            }
        }
        let _ = writeln!(s, "</tr>");
    }
    let _ = writeln!(s, "</table>");
}

/// The report's data payload as pretty JSON (`report.json`, `--json`).
pub fn json(r: &Report) -> Result<String> {
    serde_json::to_string_pretty(&r.data).map_err(|e| Error::output("report JSON", e))
}

/// Writes `report.md`, `report.html` and `report.json` into `dir` (where the figures already
/// are).
pub fn write_all(r: &Report, dir: &Path) -> Result<()> {
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).map_err(|e| Error::output(p.display(), e))
    };
    write("report.md", &markdown(r))?;
    write("report.html", &html(r, dir))?;
    write("report.json", &(json(r)? + "\n"))
}

#[cfg(test)]
mod tests {
    use super::super::{Column, Figure};
    use super::*;

    fn sample() -> Report {
        let mut r = Report::new("design: sample", serde_json::json!({"x": 1.5}));
        r.section("checks", "Checks").push(Block::Checks(vec![
            CheckRow::upper("stress", "leaf stress", "MPa", 90.0, 170.0),
            CheckRow::lower("clear", "mode clearance", "%", 8.0, 10.0).in_points(),
        ]));
        r.section("q", "Quantities").push(Block::Quantities(vec![
            QuantityRow::new("c12", "leaf stiffness", "N/m", 4.99e6).published(Some(5.0e6)),
        ]));
        r.section("modes", "Modes").push(Block::Table(Table {
            id: "modes".into(),
            caption: None,
            columns: vec![
                Column::new("#", None),
                Column::new("f", Some("Hz")),
                Column::new("name", None),
            ],
            rows: vec![vec![
                Cell::Fixed {
                    value: 1.0,
                    decimals: 0,
                },
                Cell::num(101.73),
                Cell::text("working"),
            ]],
        }));
        r.section("fig", "Plots").push(Block::Figure(Figure {
            id: "f".into(),
            file: "missing.svg".into(),
            caption: "a plot".into(),
        }));
        r
    }

    #[test]
    fn margins_and_verdicts() {
        let c = CheckRow::upper("s", "stress", "MPa", 90.0, 170.0);
        assert!(c.ok && (c.margin - 80.0 / 170.0).abs() < 1e-15);
        let c = CheckRow::lower("c", "clearance", "%", 8.0, 10.0).in_points();
        assert!(!c.ok && (c.margin + 2.0).abs() < 1e-15, "{c:?}");
        // NaN never passes.
        assert!(!CheckRow::upper("n", "nan", "", f64::NAN, 1.0).ok);
        assert!(!CheckRow::lower("n", "nan", "", f64::NAN, 1.0).ok);
    }

    #[test]
    fn every_format_carries_the_same_rows() {
        let r = sample();
        let t = text(&r);
        let m = markdown(&r);
        let h = html(&r, Path::new("/nonexistent"));
        for page in [&t, &m, &h] {
            assert!(page.contains("Checks: 1 of 2 failed"), "{page}");
            assert!(
                page.contains("leaf stiffness") && page.contains("4.990e6") && page.contains("-0.2 %"),
                "{page}"
            );
            assert!(page.contains("+47.1 %") && page.contains("-2.0 points"), "{page}");
            assert!(page.contains("101.7") && page.contains("f (Hz)"), "{page}");
            assert!(page.find("Checks").unwrap() < page.find("leaf stiffness").unwrap());
        }
        assert!(h.contains("figure missing.svg not found"));
        assert_eq!(json(&r).unwrap(), "{\n  \"x\": 1.5\n}");
    }
}
