//! The quantities the chain reports, with the paper's published values: ONE table, one row per
//! quantity (its id in `report.json`, name, unit, how it is read from the chain's results, the
//! paper's value where there is one, and the source or why the two differ).
//!
//! The paper's values are those of the 100 Hz table (docs/spec/paper.md, scenes S3–S8).

use super::file::Design;
use super::results::{ChainValues, Quantity};

/// The note of a row: fixed, or written from the design and the results.
#[derive(Clone, Copy)]
pub enum Note {
    /// A fixed text.
    Text(&'static str),
    /// Written from the design and the results.
    Of(fn(&Design, &ChainValues) -> String),
}

/// One row of the reference table.
#[derive(Clone, Copy)]
pub struct Reference {
    /// Stable id (`report.json`).
    pub id: &'static str,
    /// What.
    pub name: &'static str,
    /// Unit the value is given in.
    pub unit: &'static str,
    /// The value, from the chain's results.
    pub value: fn(&ChainValues) -> f64,
    /// The paper's value, in the same unit.
    pub published: Option<f64>,
    /// Source, or why the two differ.
    pub note: Note,
}

const fn row(
    id: &'static str,
    name: &'static str,
    unit: &'static str,
    value: fn(&ChainValues) -> f64,
    published: Option<f64>,
    note: &'static str,
) -> Reference {
    Reference {
        id,
        name,
        unit,
        value,
        published,
        note: Note::Text(note),
    }
}

const fn row_of(
    id: &'static str,
    name: &'static str,
    unit: &'static str,
    value: fn(&ChainValues) -> f64,
    published: Option<f64>,
    note: fn(&Design, &ChainValues) -> String,
) -> Reference {
    Reference {
        id,
        name,
        unit,
        value,
        published,
        note: Note::Of(note),
    }
}

/// The paper's coil stiffness (S5, N/m).
const K_COIL_PAPER: f64 = 60266.0;

/// Every quantity of the report, in the order reported.
#[rustfmt::skip]
pub const TABLE: &[Reference] = &[
    row("table_mass", "work-table mass (FE shells)", "kg", |v| v.m_table, Some(163.0),
        "S7 reconstruction: no edge thinning, so heavier"),
    row("table_f1", "work-table first elastic frequency", "Hz",
        |v| v.f_table.first().copied().unwrap_or(f64::NAN), Some(300.82), "S7"),
    row("m1", "active mass m1", "kg", |v| v.m1, Some(206.7), "FE table + other active parts"),
    row("m2", "reactive mass m2", "kg", |v| v.m2, Some(161.8), "given"),
    row("m_red", "reduced mass m_red", "kg", |v| v.m_red, Some(90.75), "eq. (5)"),
    row("k_leaf_given", "FE leaf stiffness, h as given", "N/m", |v| v.k_leaf_given, Some(5.163e6),
        "S3: 1000 N / 1.937e-4 m"),
    row_of("leaf_thickness", "leaf thickness used", "mm", |v| v.h * 1e3, Some(9.0),
        |d, _| if d.tune == "leaf" { "tuned for z by FE" } else { "given" }.into()),
    row("k_leaf", "FE leaf stiffness, used", "N/m", |v| v.k_leaf, None, ""),
    row("c12", "c12 = n · k_leaf · k_c", "N/m", |v| v.c12, Some(3.808e7), "paper: from z = 0.97 (eq. 5)"),
    row("z", "detuning z = Ω/ω0", "-", |v| v.z, Some(0.97), ""),
    row("k_coil", "FE coil stiffness (beam helix)", "N/m", |v| v.k_coil, Some(K_COIL_PAPER),
        "S5: formula at i = 6.3; FE 9.96 mm → 60 240"),
    row("c13", "c13 = n · k_coil", "N/m", |v| v.c13, Some(8.0 * K_COIL_PAPER), ""),
    row("f_n1", "natural frequency 1 (isolation)", "Hz", |v| v.w1, Some(5.0), "paper: 5 Hz design"),
    row("f_n2", "natural frequency 2 (resonant)", "Hz", |v| v.w2, Some(103.09), "ω0 = Ω/z"),
    row("drive_force", "drive force amplitude F = 4/(3π)·n·P_em", "N", |v| v.force, Some(1256.0), "eq. (11)"),
    row("constant_pull", "constant pull", "N", |v| v.constant_pull, Some(1884.0), "eq. (9)"),
    row("static_offset", "static offset P_const/c12", "mm", |v| v.offset * 1e3, Some(0.05), ""),
    row("x1", "work-table amplitude X1", "mm", |v| v.x1 * 1e3, Some(0.2), "steady state at the excitation"),
    row("x2", "reactive amplitude X2", "mm", |v| v.x2 * 1e3, None, ""),
    row("table_acceleration", "work-table acceleration", "g",
        |v| v.x1 * v.omega * v.omega / 9.81, Some(8.0), ""),
    row("gamma1", "dynamic factor γ1", "-", |v| v.gamma1, Some(13.0), "eq. (7)"),
    row("gamma2", "dynamic factor γ2", "-", |v| v.gamma2, Some(13.0), "eq. (7)"),
    row("relative_amplitude", "relative amplitude |X1 − X2|", "mm", |v| v.rel * 1e3, Some(0.46),
        "A0 = A(1 + m1/m2)"),
    row("leaf_von_mises", "leaf von Mises at the working amplitude (FE)", "MPa", |v| v.sigma_leaf / 1e6,
        Some(83.0), "S3 FE; hand 91 MPa"),
    row("magnet_pull", "pull per magnet for the target amplitude", "N", |v| v.p_req, Some(370.0), "eq. (15)"),
    row_of("drive_power", "drive power, eq. (6)", "W", |v| v.power, Some(2200.0), |d, _| {
        format!(
            "at {} g, m_pr {} kg, η = {}",
            d.drive.power_overload_g, d.drive.power_load_share, d.drive.efficiency
        )
    }),
    row("transient_x1", "transient: steady X1", "mm", |v| v.transient.amplitude1 * 1e3, Some(0.2), "Fig. 22"),
    row("transient_offset", "transient: static offset of x1 − x2", "mm", |v| v.transient.relative_mean * 1e3,
        Some(-0.05), "Fig. 22"),
    row("transient_settling_time", "transient: settling time of x1 (2 %)", "s",
        |v| v.transient.settling_time1.unwrap_or(f64::NAN), None, ""),
    row("f_isolation", "isolation frequency", "Hz", |v| v.f_iso, Some(5.0), ""),
    row("transmissibility", "transmissibility at the excitation", "-", |v| v.trans, Some(1.0 / 400.0),
        "1/(r² − 1)"),
    row("coil_shear_stress", "coil shear stress at static load (Wahl)", "MPa", |v| v.tau / 1e6, Some(290.0),
        "K from C = D/d"),
    row_of("machine_working_hz", "3D machine: working mode", "Hz", |v| v.working_hz(), Some(103.09), |d, v| {
        format!("two-mass model {:.2} Hz; table as {}", v.w2, d.machine.table_model)
    }),
    row("machine_nearest_mode_hz", "3D machine: other mode nearest the excitation", "Hz",
        |v| v.machine.nearest_other.map_or(f64::NAN, |x| x.0), None, ""),
    row_of("surface_mean_amplitude", "work surface: mean amplitude", "mm", |v| v.machine.mean * 1e3, Some(0.2),
        |_, v| format!("{} nodes; two-mass X1 {:.4} mm", v.machine.surface.len(), v.x1 * 1e3)),
    row("surface_min_amplitude", "work surface: min amplitude", "mm", |v| v.machine.min * 1e3, None, ""),
    row("surface_max_amplitude", "work surface: max amplitude", "mm", |v| v.machine.max * 1e3, None, ""),
    row("surface_nonuniformity", "work surface: non-uniformity (max − min)/mean", "%",
        |v| v.machine.nonuniformity * 100.0, None, ""),
    row_of("machine_reactive_amplitude", "3D machine: reactive-mass amplitude", "mm",
        |v| v.machine.reactive_amplitude * 1e3, None, |_, v| format!("two-mass X2 {:.4} mm", v.x2 * 1e3)),
    row("leaf_kzz", "condensed leaf: guided vertical stiffness", "N/m", |v| v.machine.leaf_kzz, None,
        "12×12 from 6 FE statics"),
    row("coil_lateral", "FE coil lateral stiffness (beam helix)", "N/m", |v| v.machine.coil_lateral, None,
        "top end guided along x"),
];

/// With `tune = "mass"`: the reactive mass that reaches the target detuning (the paper tunes
/// with plates on the reactive mass).
pub const M2_FOR_TARGET: Reference = row(
    "m2_for_target_z",
    "reactive mass for the target z",
    "kg",
    |v| match v.m2_for_target {
        Some(Ok(m)) => m,
        _ => f64::NAN,
    },
    Some(161.8),
    "tuning plates",
);

impl Reference {
    /// The row's quantity for this run.
    pub fn quantity(&self, d: &Design, v: &ChainValues) -> Quantity {
        Quantity {
            id: self.id.into(),
            name: self.name.into(),
            unit: self.unit.into(),
            value: (self.value)(v),
            published: self.published,
            note: match self.note {
                Note::Text(t) => t.into(),
                Note::Of(f) => f(d, v),
            },
        }
    }
}

/// The report's quantities: every row of [`TABLE`] whose value is finite or has a published
/// value, and the reactive mass for the target z when the design tunes by mass.
pub fn quantities(d: &Design, v: &ChainValues) -> Vec<Quantity> {
    let mut q: Vec<Quantity> = TABLE.iter().map(|r| r.quantity(d, v)).collect();
    q.retain(|x| x.value.is_finite() || x.published.is_some());
    if matches!(v.m2_for_target, Some(Ok(_))) {
        q.push(M2_FOR_TARGET.quantity(d, v));
    }
    q
}
