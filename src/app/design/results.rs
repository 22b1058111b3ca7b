//! What the chain computes: the numbers of each step ([`ChainValues`], read by the checks and
//! the reference table) and the run's result ([`DesignReport`], the data of `report.json`).

use super::machine::{MachineMode, MachineResult};
use crate::app::dynamics::transient::TransientSummary;
use serde::Serialize;

/// The numbers of one run of the chain, SI units unless named otherwise.
#[derive(Clone, Debug)]
pub struct ChainValues {
    /// Angular frequency of the excitation Ω (rad/s).
    pub omega: f64,
    /// Work-table mass from the FE shells (kg).
    pub m_table: f64,
    /// Work-table elastic frequencies, first six (Hz).
    pub f_table: Vec<f64>,
    /// FE coil stiffness, axial (N/m).
    pub k_coil: f64,
    /// Active mass m1, reactive mass m2, reduced mass (kg).
    pub m1: f64,
    /// Reactive mass.
    pub m2: f64,
    /// Reduced mass m1 m2 / (m1 + m2).
    pub m_red: f64,
    /// Isolators' stiffness, all together (N/m).
    pub c13: f64,
    /// Leaf thickness as given (m) and the FE leaf stiffness there (N/m).
    pub h_given: f64,
    /// Stiffness of the given leaf.
    pub k_leaf_given: f64,
    /// Leaf thickness used (tuned or given, m).
    pub h: f64,
    /// FE leaf stiffness used (N/m).
    pub k_leaf: f64,
    /// Peak von Mises stress of the leaf per metre of guided displacement (Pa/m).
    pub stress_per_m: f64,
    /// Leaf thicknesses tried while tuning (m) and the detuning each gave.
    pub iters: Vec<(f64, f64)>,
    /// Leaves' stiffness, all together with the clamping coefficient (N/m).
    pub c12: f64,
    /// Detuning z = Ω/ω0.
    pub z: f64,
    /// Natural frequencies of the two-mass model (Hz).
    pub w1: f64,
    /// Second (resonant).
    pub w2: f64,
    /// Drive force amplitude (N) and constant pull (N).
    pub force: f64,
    /// Constant part of the rectified pull.
    pub constant_pull: f64,
    /// Static offset of the leaves under the constant pull (m).
    pub offset: f64,
    /// The model of record (the 3D machine): the work surface's mean vertical amplitude at the
    /// excitation (m).
    pub x1: f64,
    /// The 3D machine: the reactive mass's vertical amplitude (m).
    pub x2: f64,
    /// The 3D machine: the largest vertical amplitude across a leaf (m).
    pub rel: f64,
    /// The two-mass model at the same leaves, force law and magnet stiffness: X1 (m).
    pub x1_two_mass: f64,
    /// The two-mass X2 (m).
    pub x2_two_mass: f64,
    /// The two-mass |X1 − X2| (m).
    pub rel_two_mass: f64,
    /// The two-mass leaf stress (Pa).
    pub sigma_leaf_two_mass: f64,
    /// The two-mass model in full at the model of record's leaves (design force law, magnet
    /// stiffness).
    pub two_mass: LumpedValues,
    /// The paper's chain: the two-mass model with the leaves tuned on it, the paper's force law
    /// and no magnet stiffness (what the published numbers are compared with).
    pub paper: LumpedValues,
    /// Whether the design is the built-in paper design (only it shows published values).
    pub builtin: bool,
    /// The force law (`paper` or `flux`) and the mains frequency (Hz).
    pub force_law: String,
    /// Mains frequency, Hz.
    pub mains_hz: f64,
    /// The magnets' stiffness at the working gap, all together (N/m, negative).
    pub k_magnet: f64,
    /// Detuning of the model of record: excitation / the 3D machine's working mode.
    pub z_machine: f64,
    /// The leaf thickness the two-mass tuning gave (the 3D tuning's starting guess), m.
    pub h_two_mass: f64,
    /// Leaf thicknesses tried on the 3D machine (m) and the detuning each gave.
    pub iters_machine: Vec<(f64, f64)>,
    /// The gap check: static sag under the weight and the mean pull (m).
    pub gap_sag: f64,
    /// Relative amplitude across the magnets (3D, largest, m).
    pub gap_amplitude: f64,
    /// Start-up overshoot of the relative motion beyond its steady peak (m).
    pub gap_startup: f64,
    /// Sag + amplitude + start-up + margin (m), against `drive.gap`.
    pub gap_closing: f64,
    /// Why the two-mass model and the 3D machine differ by more than 5 %, if they do.
    pub model_difference: Option<String>,
    /// Dynamic factors of eq. (7).
    pub gamma1: f64,
    /// Of the reactive mass.
    pub gamma2: f64,
    /// Drive power by eq. (6) (W).
    pub power: f64,
    /// Pull per magnet for the target amplitude (N).
    pub p_req: f64,
    /// The start-up transient's steady values.
    pub transient: TransientSummary,
    /// Isolation frequency (Hz) and transmissibility at the excitation.
    pub f_iso: f64,
    /// Transmissibility.
    pub trans: f64,
    /// Leaf stress at the working relative amplitude (Pa).
    pub sigma_leaf: f64,
    /// Coil shear stress under the static load, Wahl (Pa).
    pub tau: f64,
    /// Reactive mass that would reach the target detuning (`tune = "mass"`), or why none does.
    pub m2_for_target: Option<Result<f64, String>>,
    /// The 3D machine.
    pub machine: MachineResult,
}

impl ChainValues {
    /// The two-mass chain the quantity table shows: the paper's (built-in design), else the
    /// two-mass estimate at the model of record's leaves.
    pub fn lumped(&self) -> &LumpedValues {
        if self.builtin { &self.paper } else { &self.two_mass }
    }

    /// Frequency of the 3D machine's working mode (Hz; NaN without one).
    pub fn working_hz(&self) -> f64 {
        self.machine
            .working
            .map_or(f64::NAN, |i| self.machine.modes[i].frequency_hz)
    }
}

/// The two-mass model's numbers at one set of leaves and one force law.
#[derive(Clone, Debug, Default)]
pub struct LumpedValues {
    /// Force law (`paper`, `flux`).
    pub law: String,
    /// Leaf thickness (m), FE leaf stiffness (N/m), c12 (N/m, leaves only).
    pub h: f64,
    /// FE leaf stiffness.
    pub k_leaf: f64,
    /// Leaves together.
    pub c12: f64,
    /// Magnet stiffness included (N/m, ≤ 0).
    pub k_magnet: f64,
    /// Detuning Ω/ω0 with ω0² = (c12 + k_magnet)/m_red.
    pub z: f64,
    /// Natural frequencies (Hz).
    pub w1: f64,
    /// Second.
    pub w2: f64,
    /// Drive harmonic amplitude at Ω (N) and mean pull (N).
    pub force: f64,
    /// Mean pull.
    pub constant_pull: f64,
    /// Static offset of the leaves under the mean pull (m).
    pub offset: f64,
    /// |X1|, |X2|, |X1 − X2| (m).
    pub x1: f64,
    /// Reactive.
    pub x2: f64,
    /// Relative.
    pub rel: f64,
    /// Dynamic factors of eq. (7).
    pub gamma1: f64,
    /// Of m2.
    pub gamma2: f64,
    /// Eq. (6) (W).
    pub power: f64,
    /// Power dissipated by the dashpots, Ω²/2·Xᴴ C X (W).
    pub dissipated: f64,
    /// Pull per magnet for the target amplitude (N).
    pub p_req: f64,
    /// Leaf stress at |X1 − X2| (Pa).
    pub sigma_leaf: f64,
    /// Floor force |c13 + ikΩμ13|·|X2(kΩ)| per harmonic k with a non-zero drive term:
    /// (k, frequency Hz, amplitude N).
    pub floor: Vec<(u32, f64, f64)>,
}

/// The floor forces of both models.
#[derive(Clone, Debug, Serialize)]
pub struct FloorForces {
    /// The 3D machine (model of record): per harmonic, per isolator and in total.
    pub machine: Vec<super::machine::FloorForce>,
    /// The two-mass model, |c13 + ikΩμ13|·|X2(kΩ)| per harmonic k, shared equally by the
    /// isolators.
    pub two_mass: Vec<super::machine::FloorForce>,
}

/// One input or assumption of the verdict.
#[derive(Clone, Debug, Serialize)]
pub struct Input {
    /// Stable key (the design-file key where there is one).
    #[serde(skip)]
    pub id: String,
    /// What.
    pub name: String,
    /// Its value, as text with the unit.
    pub value: String,
    /// Where it comes from.
    pub source: String,
}

/// One line of the quantity table.
#[derive(Clone, Debug, Serialize)]
pub struct Quantity {
    /// Stable key in `report.json` (`c12`, `k_leaf`, `x1`, …; docs/design-files.md, *The design report*).
    #[serde(skip)]
    pub id: String,
    /// What.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// vibrofem's value.
    pub value: f64,
    /// The paper's value, if published.
    pub published: Option<f64>,
    /// Where the paper's value comes from / why they differ.
    pub note: String,
}

/// A design check.
#[derive(Clone, Debug, Serialize)]
pub struct Check {
    /// Stable key in `report.json`.
    #[serde(skip)]
    pub id: String,
    /// What is checked.
    pub name: String,
    /// Value.
    pub value: f64,
    /// Limit.
    pub limit: f64,
    /// Margin: how far inside the limit, as a fraction of the limit (negative: violated).
    pub margin: f64,
    /// Passed.
    pub ok: bool,
    /// The value must stay at or below the limit (else at or above it).
    #[serde(skip)]
    pub upper: bool,
}

impl Check {
    /// A check whose value must stay at or below `limit` (`upper`) or at or above it.
    pub fn new(id: &str, name: &str, value: f64, limit: f64, upper: bool) -> Check {
        let margin = if upper {
            (limit - value) / limit
        } else {
            (value - limit) / limit
        };
        Check {
            id: id.into(),
            name: name.into(),
            value,
            limit,
            margin,
            ok: margin >= 0.0,
            upper,
        }
    }
}

fn by_id_quantities<S: serde::Serializer>(q: &[Quantity], ser: S) -> std::result::Result<S::Ok, S::Error> {
    crate::app::report::by_id(q, |x| x.id.as_str(), ser)
}

fn by_id_inputs<S: serde::Serializer>(c: &[Input], ser: S) -> std::result::Result<S::Ok, S::Error> {
    crate::app::report::by_id(c, |x| x.id.as_str(), ser)
}

fn by_id_checks<S: serde::Serializer>(c: &[Check], ser: S) -> std::result::Result<S::Ok, S::Error> {
    crate::app::report::by_id(c, |x| x.id.as_str(), ser)
}

/// Everything the chain computed: the data of `report.json` and `design --json`.
#[derive(Clone, Debug, Serialize)]
pub struct DesignReport {
    /// The design's name.
    pub name: String,
    /// Checks, in the order they are reported (in JSON: an object keyed by each check's id).
    #[serde(serialize_with = "by_id_checks")]
    pub checks: Vec<Check>,
    /// Quantities with published values (in JSON: an object keyed by each quantity's id).
    #[serde(serialize_with = "by_id_quantities")]
    pub quantities: Vec<Quantity>,
    /// Work-table elastic frequencies (first six), Hz.
    pub table_frequencies_hz: Vec<f64>,
    /// Leaf thicknesses tried while tuning (m) and the detuning each gave.
    pub leaf_iterations: Vec<(f64, f64)>,
    /// Leaf thickness of the model of record (m): tuned on the 3D machine with `tune = "leaf"`,
    /// else as given. The envelope and the search run the machine as built at this thickness.
    pub leaf_thickness_m: f64,
    /// Modes of the 3D machine up to `machine.mode_range` × the excitation (unique names).
    pub machine_modes: Vec<MachineMode>,
    /// The force law of the verdict (`flux` or `paper`).
    pub force_law: String,
    /// Mains frequency, Hz (the excitation is twice it).
    pub mains_hz: f64,
    /// The force on the floor per isolator and in total, at the excitation and its harmonics,
    /// from both models.
    pub floor_force: FloorForces,
    /// The inputs and assumptions the verdict rests on, each with its source (in JSON: an
    /// object keyed by each input's id).
    #[serde(serialize_with = "by_id_inputs")]
    pub inputs: Vec<Input>,
    /// Wall time per step (s).
    pub timings_s: Vec<(String, f64)>,
    /// Notes.
    pub notes: Vec<String>,
    /// The 3D machine in the modal coordinates of its forced response (for the start-up study).
    #[serde(skip)]
    pub machine_modal: super::machine::MachineModal,
}
