//! The test-stand data of a grinder autobalancer (docs/spec/machines.md §C): the CSV file.
//!
//! - Correction cut of the autobalancer housing: two balls (mass m, race radius R) that settle
//!   α0 apart on a balanced disc leave an imbalance S = 2 m R |cos(α0/2)| (the housing's own);
//!   removing S/L of material at radius L, on the side opposite the balls' bisector, cancels it.
//! - Imbalance scatter over n re-mountings of the disc (ball angles α_i, β_i from the disc mark):
//!   X = −R cos α, Y = R sin α per ball, S_x,i = m (X_i1 + X_i2), S_y,i = m (Y_i1 + Y_i2),
//!   S_i = |(S_x,i, S_y,i)|; means S_xc, S_yc, S_c = mean S_i; ΔS_i = |(S_x,i − S_xc, S_y,i − S_yc)|,
//!   η_i = ΔS_i/S_c and η = mean ΔS / S_c.
//! - Sensitivity η = m_min/m_max; efficiency e = (a_max − a)/a_max from housing acceleration
//!   amplitudes without (a_max) and with (a) the balancer.
//!
//! The input is a CSV file ([`parse_csv`]; a UTF-8 byte-order mark is skipped) with the header `record,label,x,y`; its first record
//! must be `version,balancer-data,1`. Records (units SI, angles in degrees):
//!
//! | record | label | x | y |
//! |---|---|---|---|
//! | `version` | `balancer-data` | 1 | |
//! | `ball` | (any) | ball mass m, kg | race radius R, m |
//! | `cut_radius` | (any) | correction radius L, m | |
//! | `spread` | test name | angle α0 between the two settled balls, deg | |
//! | `mount` | mounting name | α (ball 1), deg | β (ball 2), deg |
//! | `accel` | `without` or a case name | acceleration amplitude, m/s² | |
//! | `test_mass` | `min` or `max` | mass, kg | |
//!
//! Blank lines and lines starting with `#` are ignored. Every error names the file and line.

// `!(x > 0.0)` is deliberate: it also rejects NaN.

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::collections::HashMap;
use std::path::Path;

use serde::Serialize;

use crate::{Error, Result};

/// One re-mounting of the disc: the two ball angles from the disc mark.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Mount {
    /// Name of the mounting.
    pub label: String,
    /// Ball 1 angle α, degrees.
    pub alpha_deg: f64,
    /// Ball 2 angle β, degrees.
    pub beta_deg: f64,
    /// Line in the file.
    pub line: usize,
}

/// A labelled value with its line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Labelled {
    /// Label column.
    pub label: String,
    /// Value (x column).
    pub value: f64,
    /// Line in the file.
    pub line: usize,
}

/// The measurements of a CSV file.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct StandData {
    /// Ball mass (kg) and race radius (m), with the line.
    pub ball: Option<(f64, f64, usize)>,
    /// Correction radius L (m), with the line.
    pub cut_radius: Option<(f64, usize)>,
    /// Settled ball spreads α0, degrees.
    pub spreads: Vec<Labelled>,
    /// Re-mountings.
    pub mounts: Vec<Mount>,
    /// Housing accelerations, m/s².
    pub accels: Vec<Labelled>,
    /// Smallest test mass the balancer responds to, kg, with the line.
    pub test_mass_min: Option<(f64, usize)>,
    /// Largest test mass it balances, kg, with the line.
    pub test_mass_max: Option<(f64, usize)>,
}

/// Errors of one file, naming its line (and the column, for a value).
pub(crate) struct Ctx<'a> {
    /// The file as named in messages.
    pub file: &'a str,
}

impl Ctx<'_> {
    /// An error of a whole record at `line`.
    pub fn err(&self, line: usize, msg: impl std::fmt::Display) -> Error {
        Error::Input {
            file: self.file.to_string(),
            line: Some(line),
            key: None,
            msg: msg.to_string(),
        }
    }

    /// An error of the file as a whole.
    fn whole(&self, msg: impl std::fmt::Display) -> Error {
        Error::Input {
            file: self.file.to_string(),
            line: None,
            key: None,
            msg: msg.to_string(),
        }
    }
}

const RECORDS: &str = "version, ball, cut_radius, spread, mount, accel, test_mass";
const COLUMNS: [&str; 4] = ["record", "label", "x", "y"];

/// Reads a balancer-data CSV file.
pub fn read_csv(path: &Path) -> Result<StandData> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_csv(&path.display().to_string(), &text)
}

/// One data row: its line and fields.
struct Row<'a, 'c> {
    ctx: &'c Ctx<'c>,
    line: usize,
    rec: String,
    label: String,
    f: Vec<&'a str>,
}

impl Row<'_, '_> {
    fn err(&self, msg: impl std::fmt::Display) -> Error {
        self.ctx.err(self.line, msg)
    }

    /// The number in column `col` (0-based), named `name` in messages.
    fn num(&self, col: usize, name: &str) -> Result<f64> {
        let s = self.f.get(col).copied().unwrap_or("");
        let at = |msg: String| Error::key(self.ctx.file, Some(self.line), COLUMNS[col], msg);
        if s.is_empty() {
            return Err(at(format!("'{}' needs {name} in column {}", self.rec, col + 1)));
        }
        let v: f64 = s
            .parse()
            .map_err(|_| at(format!("{name}: cannot read '{s}' as a number")))?;
        if !v.is_finite() {
            return Err(at(format!("{name}: {v} is not finite")));
        }
        Ok(v)
    }

    /// Column `col` (0-based) must be empty.
    fn none_after(&self, col: usize) -> Result<()> {
        match self.f.get(col) {
            Some(s) if !s.is_empty() => Err(self.err(format!("'{}' takes no value in column {}", self.rec, col + 1))),
            _ => Ok(()),
        }
    }
}

/// Parses balancer-data CSV text; `file` names it in messages. See the module documentation.
pub fn parse_csv(file: &str, text: &str) -> Result<StandData> {
    let ctx = Ctx { file };
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut d = StandData::default();
    let mut header_seen = false;
    let mut version_seen = false;
    // Labels of mountings, spreads and cases must be unique within their record: (record,
    // label) → first line.
    let mut labels_seen: HashMap<(String, String), usize> = HashMap::new();
    for (idx, raw) in text.lines().enumerate() {
        let line = idx + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        // Fields are plain (no CSV quoting): a quote is refused rather than kept in a label or
        // a quoted comma read as a separator.
        if l.contains('"') {
            return Err(ctx.err(
                line,
                "a quote: fields are read without CSV quoting, so a label cannot hold quotes or commas",
            ));
        }
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        if !header_seen {
            if f.len() != 4 || f.iter().zip(COLUMNS).any(|(a, b)| !a.eq_ignore_ascii_case(b)) {
                return Err(ctx.err(line, format!("expected the header 'record,label,x,y', found '{l}'")));
            }
            header_seen = true;
            continue;
        }
        if f.len() > 4 {
            return Err(ctx.err(
                line,
                format!("{} fields; a row has at most 4 (record,label,x,y)", f.len()),
            ));
        }
        let row = Row {
            ctx: &ctx,
            line,
            rec: f[0].to_ascii_lowercase(),
            label: f.get(1).copied().unwrap_or("").to_string(),
            f,
        };
        if !version_seen && row.rec != "version" {
            return Err(row.err("the first record must be 'version,balancer-data,1'"));
        }
        if matches!(row.rec.as_str(), "mount" | "spread" | "accel") && !row.label.is_empty() {
            let key = (row.rec.clone(), row.label.clone());
            if let Some(l0) = labels_seen.get(&key) {
                return Err(row.err(format!("'{}' label '{}' repeats line {l0}", row.rec, row.label)));
            }
            labels_seen.insert(key, line);
        }
        if row.rec == "version" {
            if version_seen {
                return Err(row.err("a second 'version' record"));
            }
            version(&row)?;
            version_seen = true;
        } else {
            record(&row, &mut d)?;
        }
    }
    if !header_seen {
        return Err(ctx.whole("empty file (expected the header 'record,label,x,y')"));
    }
    if !version_seen {
        return Err(ctx.whole("no records (the first must be 'version,balancer-data,1')"));
    }
    Ok(d)
}

/// The `version,balancer-data,1` record.
fn version(row: &Row) -> Result<()> {
    if row.label != "balancer-data" {
        return Err(row.err(format!("version: label must be 'balancer-data', got '{}'", row.label)));
    }
    let v = row.num(2, "the version")?;
    if v != 1.0 {
        return Err(row.err(format!("unsupported version {v} (this vibrofem reads version 1)")));
    }
    row.none_after(3)
}

/// Any data record, stored into `d`.
fn record(row: &Row, d: &mut StandData) -> Result<()> {
    let (line, label) = (row.line, row.label.clone());
    match row.rec.as_str() {
        "ball" => {
            if let Some((_, _, l0)) = d.ball {
                return Err(row.err(format!("a second 'ball' record (the first is on line {l0})")));
            }
            let m = row.num(2, "the ball mass (kg)")?;
            let r = row.num(3, "the race radius (m)")?;
            if m <= 0.0 || r <= 0.0 {
                return Err(row.err(format!("ball mass and race radius must be > 0, got {m}, {r}")));
            }
            d.ball = Some((m, r, line));
        }
        "cut_radius" => {
            if let Some((_, l0)) = d.cut_radius {
                return Err(row.err(format!("a second 'cut_radius' record (the first is on line {l0})")));
            }
            let v = row.num(2, "the correction radius (m)")?;
            if v <= 0.0 {
                return Err(row.err(format!(
                    "the correction radius must be > 0, got {}",
                    crate::io::fmt_plain(v)
                )));
            }
            row.none_after(3)?;
            d.cut_radius = Some((v, line));
        }
        "spread" => {
            let v = row.num(2, "the ball spread α0 (deg)")?;
            if !(0.0..=360.0).contains(&v) {
                return Err(row.err(format!(
                    "the ball spread must be in [0, 360] degrees, got {}",
                    crate::io::fmt_plain(v)
                )));
            }
            row.none_after(3)?;
            d.spreads.push(Labelled { label, value: v, line });
        }
        "mount" => {
            let a = row.num(2, "ball angle α (deg)")?;
            let b = row.num(3, "ball angle β (deg)")?;
            // A reading on the race: within a turn either way (1e300° has no angle left in it).
            if let Some(v) = [a, b].into_iter().find(|v| v.abs() > 360.0) {
                return Err(row.err(format!(
                    "a ball angle must lie within ±360°, got {}",
                    crate::io::fmt_plain(v)
                )));
            }
            d.mounts.push(Mount {
                label,
                alpha_deg: a,
                beta_deg: b,
                line,
            });
        }
        "accel" => {
            if label.is_empty() {
                return Err(row.err("'accel' needs a label: 'without' or a case name"));
            }
            let v = row.num(2, "the acceleration amplitude (m/s²)")?;
            if v < 0.0 {
                return Err(row.err(format!(
                    "an acceleration amplitude must be ≥ 0, got {}",
                    crate::io::fmt_plain(v)
                )));
            }
            row.none_after(3)?;
            d.accels.push(Labelled { label, value: v, line });
        }
        "test_mass" => test_mass(row, d)?,
        _ => return Err(row.err(format!("unknown record '{}' (known: {RECORDS})", row.f[0]))),
    }
    Ok(())
}

/// A `test_mass,min|max,MASS` record.
fn test_mass(row: &Row, d: &mut StandData) -> Result<()> {
    let v = row.num(2, "the test mass (kg)")?;
    if v <= 0.0 {
        return Err(row.err(format!("a test mass must be > 0, got {}", crate::io::fmt_plain(v))));
    }
    row.none_after(3)?;
    let label = &row.label;
    let slot = match label.as_str() {
        "min" => &mut d.test_mass_min,
        "max" => &mut d.test_mass_max,
        _ => return Err(row.err(format!("test_mass: label must be 'min' or 'max', got '{label}'"))),
    };
    if let Some((_, l0)) = slot {
        return Err(row.err(format!("a second 'test_mass,{label}' (the first is on line {l0})")));
    }
    *slot = Some((v, row.line));
    Ok(())
}
