//! Test-stand data reduction for grinder autobalancers (docs/spec/machines.md §C).
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
//! The input is a CSV file ([`parse_csv`]) with the header `record,label,x,y`; its first record
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

/// Imbalance S = 2 m R |cos(α0/2)| (kg·m) left by two balls settled `spread_deg` apart, and the
/// correction mass S/L (kg) at radius `l`.
pub fn correction_cut(mass: f64, radius: f64, spread_deg: f64, l: f64) -> (f64, f64) {
    let s = 2.0 * mass * radius * (spread_deg.to_radians() / 2.0).cos().abs();
    (s, s / l)
}

/// Efficiency e = (a_max − a)/a_max.
pub fn efficiency(a_max: f64, a: f64) -> f64 {
    (a_max - a) / a_max
}

/// Sensitivity η = m_min/m_max.
pub fn sensitivity(m_min: f64, m_max: f64) -> f64 {
    m_min / m_max
}

/// Imbalance vector (S_x, S_y) of two balls at angles α, β (degrees): m (−R cos α − R cos β,
/// R sin α + R sin β), kg·m.
pub fn ball_imbalance(mass: f64, radius: f64, alpha_deg: f64, beta_deg: f64) -> (f64, f64) {
    let (a, b) = (alpha_deg.to_radians(), beta_deg.to_radians());
    (
        mass * (-radius * a.cos() - radius * b.cos()),
        mass * (radius * a.sin() + radius * b.sin()),
    )
}

/// One row of the correction-cut table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CutRow {
    /// Test name.
    pub label: String,
    /// α0, degrees.
    pub spread_deg: f64,
    /// Imbalance S, kg·m.
    pub imbalance: f64,
    /// Correction mass S/L, kg.
    pub cut_mass: f64,
}

/// One re-mounting's imbalance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScatterRow {
    /// Mounting name.
    pub label: String,
    /// S_x, kg·m.
    pub sx: f64,
    /// S_y, kg·m.
    pub sy: f64,
    /// S = |(S_x, S_y)|, kg·m.
    pub s: f64,
    /// ΔS = distance from the mean vector, kg·m.
    pub ds: f64,
    /// η_i = ΔS_i/S_c.
    pub eta: f64,
}

/// Scatter statistics of the imbalance over the re-mountings.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scatter {
    /// Per mounting.
    pub rows: Vec<ScatterRow>,
    /// Mean S_x, kg·m.
    pub sx_mean: f64,
    /// Mean S_y, kg·m.
    pub sy_mean: f64,
    /// S_c = mean S_i, kg·m.
    pub s_mean: f64,
    /// Mean ΔS, kg·m.
    pub ds_mean: f64,
    /// η = mean ΔS / S_c.
    pub eta: f64,
    /// Smallest η_i.
    pub eta_min: f64,
    /// Largest η_i.
    pub eta_max: f64,
}

/// Efficiency of one case against the run without the balancer.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EfficiencyRow {
    /// Case name.
    pub label: String,
    /// a_max (without the balancer), m/s².
    pub a_max: f64,
    /// a (this case), m/s².
    pub a: f64,
    /// e = (a_max − a)/a_max.
    pub efficiency: f64,
}

/// Sensitivity from the test masses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sensitivity {
    /// m_min, kg.
    pub m_min: f64,
    /// m_max, kg.
    pub m_max: f64,
    /// η = m_min/m_max.
    pub eta: f64,
}

/// All reductions the data allow.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Reduction {
    /// Ball mass, kg, and race radius, m (if given).
    pub ball: Option<(f64, f64)>,
    /// Correction radius L, m (if given).
    pub cut_radius: Option<f64>,
    /// Correction cut per spread test.
    pub correction: Vec<CutRow>,
    /// Imbalance scatter (needs at least two mountings).
    pub scatter: Option<Scatter>,
    /// Sensitivity.
    pub sensitivity: Option<Sensitivity>,
    /// Efficiency per case.
    pub efficiency: Vec<EfficiencyRow>,
}

struct Ctx<'a> {
    file: &'a str,
}

impl Ctx<'_> {
    fn err(&self, line: usize, msg: impl std::fmt::Display) -> Error {
        Error::InvalidInput(format!("{}, line {line}: {msg}", self.file))
    }
}

const RECORDS: &str = "version, ball, cut_radius, spread, mount, accel, test_mass";

/// Reads a balancer-data CSV file.
pub fn read_csv(path: &Path) -> Result<StandData> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_csv(&path.display().to_string(), &text)
}

/// Parses balancer-data CSV text; `file` names it in messages. See the module documentation.
pub fn parse_csv(file: &str, text: &str) -> Result<StandData> {
    let ctx = Ctx { file };
    let mut d = StandData::default();
    let mut header_seen = false;
    let mut version_seen = false;
    let mut labels_seen: Vec<(String, String, usize)> = Vec::new();
    for (idx, raw) in text.lines().enumerate() {
        let line = idx + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        if !header_seen {
            let want = ["record", "label", "x", "y"];
            if f.len() != 4 || f.iter().zip(want).any(|(a, b)| !a.eq_ignore_ascii_case(b)) {
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
        let rec = f[0].to_ascii_lowercase();
        let label = f.get(1).copied().unwrap_or("").to_string();
        let num = |col: usize, name: &str| -> Result<f64> {
            let s = f.get(col).copied().unwrap_or("");
            if s.is_empty() {
                return Err(ctx.err(line, format!("'{rec}' needs {name} in column {}", col + 1)));
            }
            let v: f64 = s
                .parse()
                .map_err(|_| ctx.err(line, format!("{name}: cannot read '{s}' as a number")))?;
            if !v.is_finite() {
                return Err(ctx.err(line, format!("{name}: {v} is not finite")));
            }
            Ok(v)
        };
        let none_after = |col: usize| -> Result<()> {
            match f.get(col) {
                Some(s) if !s.is_empty() => Err(ctx.err(line, format!("'{rec}' takes no value in column {}", col + 1))),
                _ => Ok(()),
            }
        };
        if !version_seen && rec != "version" {
            return Err(ctx.err(line, "the first record must be 'version,balancer-data,1'"));
        }
        // Labels of mountings, spreads and cases must be unique within their record.
        if matches!(rec.as_str(), "mount" | "spread" | "accel") && !label.is_empty() {
            if let Some((_, _, l0)) = labels_seen.iter().find(|(r, lb, _)| *r == rec && *lb == label) {
                return Err(ctx.err(line, format!("'{rec}' label '{label}' repeats line {l0}")));
            }
            labels_seen.push((rec.clone(), label.clone(), line));
        }
        match rec.as_str() {
            "version" => {
                if version_seen {
                    return Err(ctx.err(line, "a second 'version' record"));
                }
                if label != "balancer-data" {
                    return Err(ctx.err(line, format!("version: label must be 'balancer-data', got '{label}'")));
                }
                let v = num(2, "the version")?;
                if v != 1.0 {
                    return Err(ctx.err(line, format!("unsupported version {v} (this vibrofem reads version 1)")));
                }
                none_after(3)?;
                version_seen = true;
            }
            "ball" => {
                if let Some((_, _, l0)) = d.ball {
                    return Err(ctx.err(line, format!("a second 'ball' record (the first is on line {l0})")));
                }
                let m = num(2, "the ball mass (kg)")?;
                let r = num(3, "the race radius (m)")?;
                if m <= 0.0 || r <= 0.0 {
                    return Err(ctx.err(line, format!("ball mass and race radius must be > 0, got {m}, {r}")));
                }
                d.ball = Some((m, r, line));
            }
            "cut_radius" => {
                if let Some((_, l0)) = d.cut_radius {
                    return Err(ctx.err(
                        line,
                        format!("a second 'cut_radius' record (the first is on line {l0})"),
                    ));
                }
                let v = num(2, "the correction radius (m)")?;
                if v <= 0.0 {
                    return Err(ctx.err(line, format!("the correction radius must be > 0, got {v}")));
                }
                none_after(3)?;
                d.cut_radius = Some((v, line));
            }
            "spread" => {
                let v = num(2, "the ball spread α0 (deg)")?;
                if !(0.0..=360.0).contains(&v) {
                    return Err(ctx.err(line, format!("the ball spread must be in [0, 360] degrees, got {v}")));
                }
                none_after(3)?;
                d.spreads.push(Labelled { label, value: v, line });
            }
            "mount" => {
                let a = num(2, "ball angle α (deg)")?;
                let b = num(3, "ball angle β (deg)")?;
                d.mounts.push(Mount {
                    label,
                    alpha_deg: a,
                    beta_deg: b,
                    line,
                });
            }
            "accel" => {
                if label.is_empty() {
                    return Err(ctx.err(line, "'accel' needs a label: 'without' or a case name"));
                }
                let v = num(2, "the acceleration amplitude (m/s²)")?;
                if v < 0.0 {
                    return Err(ctx.err(line, format!("an acceleration amplitude must be ≥ 0, got {v}")));
                }
                none_after(3)?;
                d.accels.push(Labelled { label, value: v, line });
            }
            "test_mass" => {
                let v = num(2, "the test mass (kg)")?;
                if v <= 0.0 {
                    return Err(ctx.err(line, format!("a test mass must be > 0, got {v}")));
                }
                none_after(3)?;
                let slot = match label.as_str() {
                    "min" => &mut d.test_mass_min,
                    "max" => &mut d.test_mass_max,
                    _ => return Err(ctx.err(line, format!("test_mass: label must be 'min' or 'max', got '{label}'"))),
                };
                if let Some((_, l0)) = slot {
                    return Err(ctx.err(
                        line,
                        format!("a second 'test_mass,{label}' (the first is on line {l0})"),
                    ));
                }
                *slot = Some((v, line));
            }
            _ => {
                return Err(ctx.err(line, format!("unknown record '{}' (known: {RECORDS})", f[0])));
            }
        }
    }
    if !header_seen {
        return Err(Error::InvalidInput(format!(
            "{file}: empty file (expected the header 'record,label,x,y')"
        )));
    }
    if !version_seen {
        return Err(Error::InvalidInput(format!(
            "{file}: no records (the first must be 'version,balancer-data,1')"
        )));
    }
    Ok(d)
}

/// Reduces the measurements. Errors (naming the line) when a record lacks what it needs: mountings
/// or spreads without a `ball` record, spreads without `cut_radius`, a single mounting, cases
/// without the `accel,without` run, or test masses with m_min > m_max.
pub fn reduce(file: &str, d: &StandData) -> Result<Reduction> {
    let ctx = Ctx { file };
    let need_ball = |line: usize, what: &str| -> Result<(f64, f64)> {
        d.ball.map(|(m, r, _)| (m, r)).ok_or_else(|| {
            ctx.err(
                line,
                format!("{what} needs a 'ball' record (ball mass and race radius)"),
            )
        })
    };
    let mut correction = Vec::new();
    if let Some(first) = d.spreads.first() {
        let (m, r) = need_ball(first.line, "'spread'")?;
        let (l, _) = d
            .cut_radius
            .ok_or_else(|| ctx.err(first.line, "'spread' needs a 'cut_radius' record"))?;
        for s in &d.spreads {
            let (imb, cut) = correction_cut(m, r, s.value, l);
            correction.push(CutRow {
                label: s.label.clone(),
                spread_deg: s.value,
                imbalance: imb,
                cut_mass: cut,
            });
        }
    }
    let scatter = match d.mounts.len() {
        0 => None,
        1 => {
            return Err(ctx.err(
                d.mounts[0].line,
                "the imbalance scatter needs at least two 'mount' records",
            ));
        }
        n => {
            let (m, r) = need_ball(d.mounts[0].line, "'mount'")?;
            let v: Vec<(f64, f64)> = d
                .mounts
                .iter()
                .map(|mt| ball_imbalance(m, r, mt.alpha_deg, mt.beta_deg))
                .collect();
            let nf = n as f64;
            let sx_mean = v.iter().map(|p| p.0).sum::<f64>() / nf;
            let sy_mean = v.iter().map(|p| p.1).sum::<f64>() / nf;
            let s_mean = v.iter().map(|p| p.0.hypot(p.1)).sum::<f64>() / nf;
            if !(s_mean > 0.0) {
                return Err(ctx.err(
                    d.mounts[0].line,
                    "every mounting has zero imbalance (balls exactly opposite): η is undefined",
                ));
            }
            let rows: Vec<ScatterRow> = d
                .mounts
                .iter()
                .zip(&v)
                .map(|(mt, p)| {
                    let ds = (p.0 - sx_mean).hypot(p.1 - sy_mean);
                    ScatterRow {
                        label: mt.label.clone(),
                        sx: p.0,
                        sy: p.1,
                        s: p.0.hypot(p.1),
                        ds,
                        eta: ds / s_mean,
                    }
                })
                .collect();
            let ds_mean = rows.iter().map(|r| r.ds).sum::<f64>() / nf;
            let eta_min = rows.iter().map(|r| r.eta).fold(f64::INFINITY, f64::min);
            let eta_max = rows.iter().map(|r| r.eta).fold(f64::NEG_INFINITY, f64::max);
            Some(Scatter {
                rows,
                sx_mean,
                sy_mean,
                s_mean,
                ds_mean,
                eta: ds_mean / s_mean,
                eta_min,
                eta_max,
            })
        }
    };
    let sensitivity = match (d.test_mass_min, d.test_mass_max) {
        (None, None) => None,
        (Some((_, l)), None) | (None, Some((_, l))) => {
            return Err(ctx.err(l, "the sensitivity needs both 'test_mass,min' and 'test_mass,max'"));
        }
        (Some((a, _)), Some((b, lb))) => {
            if a > b {
                return Err(ctx.err(lb, format!("test_mass: min {a} kg exceeds max {b} kg")));
            }
            Some(Sensitivity {
                m_min: a,
                m_max: b,
                eta: sensitivity(a, b),
            })
        }
    };
    let mut eff = Vec::new();
    let base = d.accels.iter().find(|a| a.label.eq_ignore_ascii_case("without"));
    let others: Vec<&Labelled> = d
        .accels
        .iter()
        .filter(|a| !a.label.eq_ignore_ascii_case("without"))
        .collect();
    match (base, others.first()) {
        (None, Some(o)) => {
            return Err(ctx.err(
                o.line,
                "the efficiency needs the run without the balancer: 'accel,without,A_MAX'",
            ));
        }
        (Some(b), _) => {
            if others.is_empty() {
                return Err(ctx.err(b.line, "'accel,without' needs at least one case with the balancer"));
            }
            if !(b.value > 0.0) {
                return Err(ctx.err(b.line, "a_max must be > 0"));
            }
            for o in others {
                eff.push(EfficiencyRow {
                    label: o.label.clone(),
                    a_max: b.value,
                    a: o.value,
                    efficiency: efficiency(b.value, o.value),
                });
            }
        }
        (None, None) => {}
    }
    if correction.is_empty() && scatter.is_none() && sensitivity.is_none() && eff.is_empty() {
        return Err(Error::InvalidInput(format!(
            "{file}: nothing to reduce (give spread, mount, accel or test_mass records)"
        )));
    }
    Ok(Reduction {
        ball: d.ball.map(|(m, r, _)| (m, r)),
        cut_radius: d.cut_radius.map(|(l, _)| l),
        correction,
        scatter,
        sensitivity,
        efficiency: eff,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cut_zero_at_180() {
        let (s, c) = correction_cut(0.002, 0.03, 180.0, 0.04);
        assert!(s.abs() < 1e-18 && c.abs() < 1e-16);
    }
}
