//! The reductions of autobalancer test-stand data (docs/spec/machines.md §C; the formulas are in
//! the documentation of [`super::case`]): correction cut, imbalance scatter, sensitivity,
//! efficiency.

// `!(x > 0.0)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use serde::Serialize;

use super::case::{Ctx, Labelled, StandData};
use crate::{Error, Result};

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
        return Err(Error::Input {
            file: file.to_string(),
            line: None,
            key: None,
            msg: "nothing to reduce (give spread, mount, accel or test_mass records)".into(),
        });
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
