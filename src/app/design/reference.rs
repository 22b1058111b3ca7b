//! The quantities the chain reports, with the paper's published values: ONE table, one row per
//! quantity (its id in `report.json`, name, unit, how it is read from the chain's results, the
//! paper's value where there is one, and the source or why the two differ).
//!
//! The paper's values are those of the 100 Hz table (docs/spec/paper.md, scenes S3–S8), shown
//! for the built-in paper design only. The rows of the paper's two-mass chain read
//! [`ChainValues::lumped`]: for the built-in design the chain as the paper ran it (its force law,
//! leaves tuned on the two-mass model, no magnet stiffness); for any other design the two-mass
//! estimate at the model of record's leaves. The model of record's rows (3D machine) follow.

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

/// The start-up rows' source: the paper's chain (its force law, the leaves tuned on the
/// two-mass model, no magnet stiffness) on this design's masses; for a user's design that is not
/// the model of record, whose start-up the report's start-up section gives.
fn transient_note(_: &Design, v: &ChainValues) -> String {
    if v.builtin {
        "Fig. 22".into()
    } else {
        "the paper's chain on this design's masses (paper force law, leaves tuned on the two-mass model, \
         no magnet stiffness); this design's own start-up: section 'Start-up and run-down'"
            .into()
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
    row_of("leaf_thickness", "leaf thickness used", "mm", |v| v.lumped().h * 1e3, Some(9.0),
        |d, _| if d.tune == "leaf" { "tuned for z by FE" } else { "given" }.into()),
    row("k_leaf", "FE leaf stiffness, used", "N/m", |v| v.lumped().k_leaf, None, ""),
    row("c12", "c12 = n · k_leaf · k_c", "N/m", |v| v.lumped().c12, Some(3.808e7), "paper: from z = 0.97 (eq. 5)"),
    row("z", "detuning z = Ω/ω0 (two-mass)", "-", |v| v.lumped().z, Some(0.97), ""),
    row("k_coil", "FE coil stiffness (beam helix)", "N/m", |v| v.k_coil, Some(K_COIL_PAPER),
        "S5: formula at i = 6.3; FE 9.96 mm → 60 240"),
    row("c13", "c13 = n · k_coil", "N/m", |v| v.c13, Some(8.0 * K_COIL_PAPER), ""),
    row("f_n1", "natural frequency 1 (isolation, masses without the load)", "Hz", |v| v.lumped().w1, None,
        "the paper's 5 Hz is the loaded machine's: see f_isolation"),
    row("f_n2", "natural frequency 2 (resonant)", "Hz", |v| v.lumped().w2, Some(103.09),
        "the two-mass eigenfrequency (with c13); the paper gives ω0 = Ω/z"),
    row_of("drive_force", "drive force amplitude at Ω", "N", |v| v.lumped().force, Some(1256.0),
        |_, v| format!("{} law; paper: 4/(3π)·n·P_em, eq. (11)", v.lumped().law)),
    row_of("constant_pull", "constant pull (mean)", "N", |v| v.lumped().constant_pull, Some(1884.0),
        |_, v| format!("{} law; paper: 2/π·n·P_em, eq. (9)", v.lumped().law)),
    row("static_offset", "static offset P_const/c12", "mm", |v| v.lumped().offset * 1e3, Some(0.05), ""),
    row("x1", "work-table amplitude X1 (two-mass)", "mm", |v| v.lumped().x1 * 1e3, Some(0.2),
        "steady state at the excitation"),
    row("x2", "reactive amplitude X2 (two-mass)", "mm", |v| v.lumped().x2 * 1e3, None, ""),
    row("table_acceleration", "work-table acceleration (two-mass)", "g",
        |v| v.lumped().x1 * v.omega * v.omega / 9.81, Some(8.0), ""),
    row("gamma1", "dynamic factor γ1", "-", |v| v.lumped().gamma1, Some(13.0), "eq. (7)"),
    row("gamma2", "dynamic factor γ2", "-", |v| v.lumped().gamma2, Some(13.0), "eq. (7)"),
    row("relative_amplitude", "relative amplitude |X1 − X2| (two-mass)", "mm", |v| v.lumped().rel * 1e3,
        Some(0.46), "A0 = A(1 + m1/m2)"),
    row("leaf_von_mises", "leaf von Mises at the working amplitude (FE, two-mass)", "MPa",
        |v| v.lumped().sigma_leaf / 1e6, Some(83.0), "S3 FE; hand 91 MPa"),
    row("magnet_pull", "pull per magnet for the target amplitude (two-mass)", "N", |v| v.lumped().p_req,
        Some(370.0), "eq. (15)"),
    row_of("drive_power", "drive power, eq. (6) (the paper's sizing formula, not a power balance)", "W",
        |v| v.lumped().power, Some(2200.0), |d, _| {
        format!(
            "at {} g, m_pr {} kg, η = {}",
            d.drive.power_overload_g, d.drive.power_load_share, d.drive.efficiency
        )
    }),
    row("dissipated_power", "power dissipated by the two-mass dashpots Ω²/2·Σμ|X|² (a power balance)", "W",
        |v| v.lumped().dissipated, None, "mechanical power the drive supplies in steady state"),
    row_of("transient_x1", "transient (paper law, two-mass): steady X1", "mm", |v| v.transient.amplitude1 * 1e3, Some(0.2),
        transient_note),
    row_of("transient_offset", "transient: static offset of x1 − x2", "mm", |v| v.transient.relative_mean * 1e3,
        Some(-0.05), transient_note),
    row("transient_settling_time", "transient: settling time of x1 (2 %)", "s",
        |v| v.transient.settling_time1.unwrap_or(f64::NAN), None, ""),
    row("f_isolation", "isolation frequency (whole loaded mass on the isolators)", "Hz", |v| v.f_iso, Some(5.0), ""),
    row("transmissibility", "transmissibility of the whole machine as one rigid mass", "-", |v| v.trans,
        Some(1.0 / 400.0), "1/(r² − 1): not the floor force of a reactive machine (see floor_force_*)"),
    row_of("floor_force_two_mass", "floor force at Ω, two-mass |c13 + iΩμ13|·|X2|", "N",
        |v| v.two_mass.floor.first().map_or(f64::NAN, |f| f.2), None,
        |_, v| format!("{} law, model of record's leaves; per isolator {:.4} N", v.two_mass.law,
            v.two_mass.floor.first().map_or(f64::NAN, |f| f.2) / v.machine.floor.first().map_or(1, |f| f.per_isolator.len()) as f64)),
    row_of("floor_force_machine", "floor force at Ω, 3D machine (sum over the isolators)", "N",
        |v| v.machine.floor.first().map_or(f64::NAN, |f| f.total), None,
        |_, v| format!("largest isolator {:.4} N", v.machine.floor.first().map_or(f64::NAN,
            |f| f.per_isolator.iter().copied().fold(0.0, f64::max)))),
    row("floor_force_ratio", "floor force / drive force at Ω (3D machine): the reactive machine's isolation figure", "-",
        |v| v.machine.floor.first().map_or(f64::NAN, |f| f.total) / v.two_mass.force, None, ""),
    row("coil_shear_stress", "coil shear stress at static load (Wahl)", "MPa", |v| v.tau / 1e6, Some(290.0),
        "K from C = D/d"),
    row_of("machine_working_hz", "3D machine: working mode", "Hz", |v| v.working_hz(), None, |d, v| {
        format!("two-mass model {:.2} Hz; table as {}", v.w2, d.machine.table_model)
    }),
    row("z_machine", "detuning z = f_e/f_working (3D machine, model of record)", "-", |v| v.z_machine, None,
        "the leaves are tuned on it"),
    row("leaf_thickness_machine", "leaf thickness (model of record)", "mm", |v| v.h * 1e3, None, ""),
    row("c12_machine", "c12 of the model of record's leaves", "N/m", |v| v.c12, None, ""),
    row("k_magnet", "magnets' stiffness at the working gap −2P̄/δ", "N/m", |v| v.k_magnet, None,
        "all magnets; in both models"),
    row("x1_machine", "work-surface amplitude X1 (3D, model of record)", "mm", |v| v.x1 * 1e3, None, ""),
    row("x1_two_mass", "work-table amplitude X1 (two-mass estimate, same leaves and law)", "mm",
        |v| v.x1_two_mass * 1e3, None, ""),
    row("relative_amplitude_machine", "relative amplitude across the leaves (3D, worst leaf)", "mm",
        |v| v.rel * 1e3, None, ""),
    row("relative_amplitude_two_mass", "relative amplitude |X1 − X2| (two-mass estimate)", "mm",
        |v| v.rel_two_mass * 1e3, None, ""),
    row("leaf_stress_machine", "leaf stress (3D, worst leaf)", "MPa", |v| v.sigma_leaf / 1e6, None, ""),
    row("leaf_stress_two_mass", "leaf stress (two-mass estimate)", "MPa", |v| v.sigma_leaf_two_mass / 1e6, None, ""),
    row("dissipated_power_machine", "power dissipated by the 3D machine's dashpots", "W",
        |v| v.machine.dissipated_power, None, "Ω²/2·Σ uᴴCu"),
    row("gap_sag", "gap: static sag (weight and mean pull)", "mm", |v| v.gap_sag * 1e3, None, ""),
    row("gap_amplitude", "gap: relative amplitude across the magnets (3D, worst)", "mm",
        |v| v.gap_amplitude * 1e3, None, ""),
    row("gap_startup", "gap: start-up overshoot", "mm", |v| v.gap_startup * 1e3, None,
        "two-mass start-up, design law, scaled to the 3D amplitude"),
    row("machine_nearest_mode_hz", "3D machine: other mode nearest the excitation", "Hz",
        |v| v.machine.nearest_other.map_or(f64::NAN, |x| x.0), None, ""),
    row_of("surface_mean_amplitude", "work surface: mean amplitude (model of record)", "mm",
        |v| v.machine.mean * 1e3, None,
        |_, v| format!("{} nodes; two-mass X1 {:.4} mm", v.machine.surface.len(), v.x1_two_mass * 1e3)),
    row("surface_min_amplitude", "work surface: min amplitude", "mm", |v| v.machine.min * 1e3, None, ""),
    row("surface_max_amplitude", "work surface: max amplitude", "mm", |v| v.machine.max * 1e3, None, ""),
    row("surface_nonuniformity", "work surface: non-uniformity (max − min)/mean", "%",
        |v| v.machine.nonuniformity * 100.0, None, ""),
    row_of("machine_reactive_amplitude", "3D machine: reactive-mass amplitude", "mm",
        |v| v.machine.reactive_amplitude * 1e3, None, |_, v| format!("two-mass X2 {:.4} mm", v.x2_two_mass * 1e3)),
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
    if matches!(v.m2_for_target, Some(Ok(_))) {
        q.push(M2_FOR_TARGET.quantity(d, v));
    }
    if !v.builtin {
        // A user's own design is not the paper's machine: no published values beside it.
        q.iter_mut().for_each(|x| x.published = None);
    }
    q.retain(|x| x.value.is_finite() || x.published.is_some());
    q
}

/// The inputs and assumptions the verdict rests on, each with its source: damping, load share,
/// clamping coefficient, allowables, force law and mains, gap, the reconstructed layout.
pub fn inputs(d: &Design, v: &ChainValues) -> Vec<super::results::Input> {
    let given = |paper: &str| -> String {
        if v.builtin {
            paper.to_string()
        } else {
            "design file (default: the paper's)".to_string()
        }
    };
    let row = |id: &str, name: &str, value: String, source: String| super::results::Input {
        id: id.into(),
        name: name.into(),
        value,
        source,
    };
    let md = &d.machine;
    vec![
        row(
            "damping",
            "viscous damping μ1 (load), μ12 (leaves), μ13 (isolators)",
            format!("{} / {} / {} N·s/m", d.damping.mu1, d.damping.mu12, d.damping.mu13),
            given("the paper's values (§18, Mathcad listing §19); not measured on this machine"),
        ),
        row(
            "masses.load_share",
            "share of the load moving with the table k_pr",
            format!("{} of {} kg", d.masses.load_share, d.masses.load),
            given("the paper's chain: the load acts through μ1 (k_pr = 0 in m1); its weight is in the static sag"),
        ),
        row(
            "leaf.clamping",
            "leaf clamping coefficient k",
            format!("{}", d.leaf.clamping),
            given("the paper, eq. (16): k = 0.75 (\"hard to predict\", §11)"),
        ),
        row(
            "leaf.allowable",
            "leaf allowable stress [σ₋₁]",
            format!("{} MPa", d.leaf.allowable / 1e6),
            given("the paper, §13: steels 60С2, 60С2А, 60С2ХФА, [σ₋₁] = 170 MPa"),
        ),
        row(
            "coil.allowable_shear",
            "coil allowable shear stress (static)",
            format!("{} MPa", d.coil.allowable_shear / 1e6),
            given("spring-steel static allowable (0.5·σ_b of a 60С2-class wire, ≈ 1120 MPa tensile strength)"),
        ),
        row(
            "drive.force_law",
            "magnet force law",
            match d.force_law() {
                crate::app::dynamics::electromagnet::ForceLaw::Flux => {
                    "flux: P·sin²ωt (mean P/2, 2ω amplitude P/2)".to_string()
                }
                crate::app::dynamics::electromagnet::ForceLaw::Paper => {
                    "paper: P·|sin ωt| (eq. (8): mean 2P/π, 2ω amplitude 4P/(3π))".to_string()
                }
            },
            "design file; flux is the default for new designs: a mains-fed coil's pull goes with the flux squared"
                .into(),
        ),
        row(
            "drive.mains_hz",
            "mains frequency (the excitation is twice it)",
            format!("{} Hz → {} Hz", v.mains_hz, d.excitation_hz),
            if d.drive.mains_hz.is_some() {
                "design file".into()
            } else {
                "half of excitation_hz".into()
            },
        ),
        row(
            "drive.gap",
            "working air gap δ and the check's margin",
            format!("{} mm, margin {} mm", d.drive.gap * 1e3, d.drive.gap_margin * 1e3),
            given("the paper gives no gap; 1.8 mm as in the review of this design (issue 29); margin an assumption"),
        ),
        row(
            "magnet_stiffness",
            "magnets' stiffness −2P̄/δ (pull ∝ 1/δ² at constant current linkage)",
            format!("{:.4e} N/m", v.k_magnet),
            "Roters, Electromagnetic Devices (1941), ch. 7; conservative against a constant-flux coil (zero)".into(),
        ),
        row(
            "machine.layout",
            "layout of leaves, magnets, isolators",
            format!(
                "{} leaves, {} magnets, {} isolators; reactive block {:?} m at {:?}",
                md.leaves.len(),
                md.magnets.len(),
                md.isolators.len(),
                md.reactive_box,
                md.reactive_centre
            ),
            given("reconstructed: the paper gives the parts, not their places (docs/design.md, The 3D machine)"),
        ),
        row(
            "table",
            "work-table construction",
            format!("{} spacers", d.spacers),
            given("reconstruction S7 of the paper's Fig. 9 (edge thinning and taper not given)"),
        ),
    ]
}
