//! The design file: every input of the chain ([`Design`] and its parts), read from TOML and
//! checked before any work.
//!
//! Defaults are the paper's 100 Hz table ([`Design::paper`]); a TOML file gives the same fields
//! (unknown keys are errors, missing ones take the paper's values). [`Design::validate`] checks
//! the range of every value and names the key; [`Design::from_toml`] adds the file and the line.
//! The `[machine]` layout ([`MachineDesign`]) and the `[search]` lists ([`SearchDesign`]) are
//! part of the file and are read and checked here too.

use crate::io::fmt_plain;
use crate::material::Material;
use crate::mesh::CellKind;
use crate::mesh::parametric::{MAX_TABLE_DIVISIONS, SandwichParams};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// A design: every input of the chain, SI units. Defaults are the paper's table.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Design {
    /// Format version (1).
    pub version: u32,
    /// Name of the design.
    pub name: String,
    /// Forced-vibration frequency, Hz.
    pub excitation_hz: f64,
    /// Target work-table amplitude, m.
    pub target_amplitude: f64,
    /// Target detuning z = Ω/ω0 (for `tune`).
    pub target_detuning: f64,
    /// `"none"`, `"leaf"` (iterate the leaf thickness to reach `target_detuning`) or `"mass"`
    /// (report the reactive mass that would reach it, keep the design as given).
    pub tune: String,
    /// Structural steel of the table.
    pub steel: [f64; 3],
    /// Work table.
    pub table: TableDesign,
    /// Masses.
    pub masses: MassDesign,
    /// Leaf springs.
    pub leaf: LeafDesign,
    /// Coil isolators.
    pub coil: CoilDesign,
    /// Electromagnetic drive.
    pub drive: DriveDesign,
    /// Viscous damping, N·s/m.
    pub damping: DampingDesign,
    /// The 3D machine: layout of leaves, magnets and isolators, and its limits.
    pub machine: MachineDesign,
    /// What spaces the plates: `"plates"` (flat webs, the S7 reconstruction) or `"channel10"`
    /// (the paper's words: channel No. 10 of GOST 8240, h = 100 mm, flanges 46 × 7.6 mm on the
    /// plates, web 4.5 mm; see [`table_parts`]).
    pub spacers: String,
    /// The search for a passing variant when a check fails.
    pub search: SearchDesign,
    /// Load cases and tolerance bands every check must hold over ([`super::envelope`]).
    pub envelope: super::envelope::EnvelopeDesign,
}

/// The sandwich work table (shell model): the generator's own parameters, read from `[table]`.
pub type TableDesign = SandwichParams;

/// Masses of the two-mass system.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MassDesign {
    /// Load on the table (concrete products and moulds), kg.
    pub load: f64,
    /// Share of the load moving with the table in m1 (k_pr).
    pub load_share: f64,
    /// Other parts of the active mass (armatures, shoes, clamps), kg.
    pub active_extra: f64,
    /// Reactive mass m2 (magnet cores, frame, tuning plates), kg.
    pub reactive: f64,
    /// Centre `[x, y]` (m, from the table centre) of the load moving with the table: at the
    /// centre it is spread over the whole work surface; elsewhere (an eccentric load) over the
    /// work-surface nodes within a quarter of the table's length and width of that point.
    pub load_offset: [f64; 2],
}

/// Flat leaf springs.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LeafDesign {
    /// Free length, m.
    pub length: f64,
    /// Width, m.
    pub width: f64,
    /// Thickness, m (the starting value when tuning).
    pub thickness: f64,
    /// Number of leaves in parallel.
    pub count: usize,
    /// Clamping coefficient k_c.
    pub clamping: f64,
    /// Spring steel E, ν, ρ.
    pub material: [f64; 3],
    /// Allowable stress [σ₋₁], Pa.
    pub allowable: f64,
    /// hex20 divisions along length, width, thickness.
    pub divisions: [usize; 3],
    /// Fatigue inputs (`[leaf.fatigue]`, docs/fatigue.md).
    pub fatigue: LeafFatigue,
}

/// The leaves' fatigue inputs (`[leaf.fatigue]`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LeafFatigue {
    /// Fatigue material: a built-in name (`60Si2Mn`, `65Mn`, `50CrVA`, `51CrMoV4`) or
    /// `rm=MPA,re=MPA[,sw=…,tw=…,k=…,nd=…]`.
    pub material: String,
    /// Required safety factor.
    pub safety: f64,
    /// Cycles the leaves must survive.
    pub cycles: f64,
    /// Surface roughness R_z, µm (200: rolled, DIN 4768 indicative value).
    pub roughness: f64,
    /// Reliability of the endurance limit (0.5, 0.9, 0.95, 0.99, 0.999, …).
    pub reliability: f64,
    /// Mean-stress correction: `fkm`, `goodman` or `gerber`.
    pub mean_stress: String,
}

impl Default for LeafFatigue {
    fn default() -> Self {
        LeafFatigue {
            material: "60Si2Mn".into(),
            safety: 1.5,
            cycles: 1e9,
            roughness: 200.0,
            reliability: 0.99,
            mean_stress: "fkm".into(),
        }
    }
}

/// The coil isolators' fatigue, binding and surge inputs (`[coil.fatigue]`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CoilFatigue {
    /// Wire material (built-in name or `rm=MPA,re=MPA`): its R_m gives S_su = 0.67 R_m.
    pub material: String,
    /// Required fatigue safety factor.
    pub safety: f64,
    /// The line through Zimmerli's point: `goodman` or `gerber`.
    pub criterion: String,
    /// Shot-peened wire (Zimmerli's peened data).
    pub peened: bool,
    /// End type: `plain`, `plain_ground`, `squared`, `squared_ground` (free and solid lengths).
    pub ends: String,
    /// Least fractional overrun to closure ξ = travel/deflection − 1 (Shigley: 0.15); also the
    /// least reserve of the critical buckling deflection over the same deflection.
    pub overrun: f64,
    /// Seating (end-condition) coefficient ν of the buckling check (EN 13906-1 §9.2, Fig. 6):
    /// 0.5 both ends clamped parallel, 0.7 one clamped and one pinned, 1 both pinned, or both
    /// clamped parallel with one end free to move sideways (an isolator under a swaying body:
    /// the default), 2 one end clamped and the other free.
    pub seating: f64,
    /// Least clearance of the surge frequency from every force harmonic (fraction).
    pub surge_clearance: f64,
}

impl Default for CoilFatigue {
    fn default() -> Self {
        CoilFatigue {
            material: "60Si2Mn".into(),
            safety: 1.5,
            criterion: "goodman".into(),
            peened: false,
            ends: "squared_ground".into(),
            overrun: 0.15,
            seating: 1.0,
            surge_clearance: 0.10,
        }
    }
}

/// Coil isolators.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CoilDesign {
    /// Wire diameter, m.
    pub wire: f64,
    /// Mean coil diameter, m.
    pub mean_diameter: f64,
    /// Active turns.
    pub turns: f64,
    /// Pitch, m.
    pub pitch: f64,
    /// Number of isolators.
    pub count: usize,
    /// Shear modulus G, Pa (E = 2G(1+ν) with ν = 0.3).
    pub shear_modulus: f64,
    /// Allowable shear stress under the static load, Pa.
    pub allowable_shear: f64,
    /// Beam elements (3-node) per turn.
    pub elements_per_turn: usize,
    /// Fatigue, binding and surge inputs (`[coil.fatigue]`, docs/fatigue.md).
    pub fatigue: CoilFatigue,
}

/// Electromagnetic drive.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DriveDesign {
    /// Number of single-stroke magnets.
    pub magnets: usize,
    /// Peak pull of one magnet P_em, N.
    pub pull: f64,
    /// Drive efficiency η for eq. (6).
    pub efficiency: f64,
    /// Installed electrical power, W.
    pub installed_power: f64,
    /// Transient simulation length, s.
    pub transient_s: f64,
    /// Overload at which eq. (6) sizes the drive, g (the paper: 11 g, a margin over 8 g).
    pub power_overload_g: f64,
    /// Load share m_pr in eq. (6), kg (the paper: 100 kg, "taken with a margin").
    pub power_load_share: f64,
    /// How the pull varies over a mains period: `"flux"` (P·sin²ωt, a coil fed from the mains:
    /// mean P/2, one harmonic at 2ω of amplitude P/2; the default) or `"paper"` (the paper's
    /// P·|sin ωt|, eq. (8)).
    pub force_law: String,
    /// Mains frequency, Hz; the excitation is twice it under both laws. Missing: half of
    /// `excitation_hz`; given alone in a file, it sets `excitation_hz`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mains_hz: Option<f64>,
    /// Working air gap between armature and core, m (the magnets' stiffness −2P̄/δ is taken
    /// there, and the gap check closes against it).
    pub gap: f64,
    /// Clearance the gap check keeps beyond sag, amplitude and start-up peak, m.
    pub gap_margin: f64,
}

/// Damping coefficients.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DampingDesign {
    /// External damping on m1 (the load), N·s/m.
    pub mu1: f64,
    /// Damping in the leaf springs, N·s/m.
    pub mu12: f64,
    /// Damping in the isolators, N·s/m.
    pub mu13: f64,
}

impl Default for Design {
    fn default() -> Self {
        Design::paper()
    }
}
impl Default for MassDesign {
    fn default() -> Self {
        // The paper's m1 = 206.7 kg is the CAD mass of the active part; its work organ weighs
        // 163 kg, so 43.7 kg are other active parts. The load is carried by μ1 (load_share 0).
        MassDesign {
            load: 120.0,
            load_share: 0.0,
            active_extra: 206.7 - 163.0,
            reactive: 161.8,
            load_offset: [0.0, 0.0],
        }
    }
}
impl Default for LeafDesign {
    fn default() -> Self {
        LeafDesign {
            length: 0.169,
            width: 0.146,
            thickness: 0.009,
            count: 8,
            clamping: 0.75,
            material: [2.1e11, 0.3, 7850.0],
            allowable: 170e6,
            divisions: [24, 8, 2],
            fatigue: LeafFatigue::default(),
        }
    }
}
impl Default for CoilDesign {
    fn default() -> Self {
        CoilDesign {
            wire: 0.006,
            mean_diameter: 0.032,
            turns: 6.0,
            pitch: 0.010,
            count: 8,
            shear_modulus: 7.7e10,
            allowable_shear: 560e6,
            // Line3 beams, 12 per turn: converged to 0.03 % (validation/springs_s3_s4_s5.py).
            elements_per_turn: 12,
            fatigue: CoilFatigue::default(),
        }
    }
}
impl Default for DriveDesign {
    fn default() -> Self {
        DriveDesign {
            magnets: 8,
            pull: 370.0,
            efficiency: 0.57,
            installed_power: 8.0 * 330.0,
            transient_s: 0.6,
            power_overload_g: 11.0,
            power_load_share: 100.0,
            force_law: "flux".into(),
            mains_hz: None,
            // The working gap (the paper gives none); the margin covers the plates'
            // flatness and the assembly tolerance of the gap (an assumption, stated in the report).
            gap: 1.8e-3,
            gap_margin: 0.2e-3,
        }
    }
}
impl Default for DampingDesign {
    fn default() -> Self {
        DampingDesign {
            mu1: 2400.0,
            mu12: 1830.0,
            mu13: 230.0,
        }
    }
}

/// Longest start-up transient a design file may ask for (s of machine time).
pub const MAX_TRANSIENT_S: f64 = 30.0;

/// Fewest excitation periods the transient may cover: its steady values are read from the last
/// ten.
pub const MIN_TRANSIENT_PERIODS: f64 = 10.0;

/// Most excitation periods the transient may cover ([`MAX_TRANSIENT_S`] at the paper's 100 Hz).
pub const MAX_TRANSIENT_PERIODS: f64 = 3000.0;

/// Highest excitation frequency (Hz): the machine model takes the leaves as massless springs,
/// which holds well below their own first mode (about 1.7 kHz for the paper's leaves).
pub const MAX_EXCITATION_HZ: f64 = 1000.0;

/// The highest mains frequency (Hz): the force repeats at twice it.
const MAX_MAINS_HZ: f64 = 0.5 * MAX_EXCITATION_HZ;

/// Plausibility bounds of a design's values, far outside any machine of this family but inside
/// what the chain computes with: beyond them a unit slip (1e300, 1e-300) surfaced late, as a
/// support "not free", an "undamped resonance" or a non-finite stiffness, with no key named.
/// Masses, kg (the paper's reactive mass is 161.8 kg).
const MAX_MASS: f64 = 1e6;
/// The smallest reactive mass, kg.
const MIN_MASS: f64 = 1e-3;
/// Lengths of a part, m.
const MAX_LENGTH: f64 = 100.0;
/// The thinnest leaf, m (0.1 mm; the paper's are 9 mm).
const MIN_THICKNESS: f64 = 1e-4;
/// Coil turns (the paper's coil has 6).
const MIN_TURNS: f64 = 0.5;
/// The most coil turns.
const MAX_TURNS: f64 = 1000.0;
/// A shear modulus, Pa (steel 7.7e10).
const MAX_MODULUS: f64 = 1e13;
/// A magnet's pull, N (the paper's 370 N).
const MAX_FORCE: f64 = 1e8;
/// A dashpot, N·s/m (the paper's 2400).
const MAX_DAMPING: f64 = 1e9;

/// Range of the target detuning z = Ω/ω0: a resonant machine works near resonance; z a decade
/// away asks for leaves far outside their design (thinner than a foil, or blocks).
pub const MIN_DETUNING: f64 = 0.1;
/// Upper end of the target detuning's range.
pub const MAX_DETUNING: f64 = 10.0;

/// The range a design-file number must lie in (every value is also finite).
#[derive(Clone, Copy, Debug)]
enum Range {
    /// > 0.
    Positive,
    /// ≥ 0.
    NonNegative,
    /// Above `lo` (or at it, when the flag is set) and at most `hi`.
    Between(f64, f64, bool),
}

impl Range {
    fn check(self, key: &str, v: f64) -> Result<()> {
        let ok = v.is_finite()
            && match self {
                Range::Positive => v > 0.0,
                Range::NonNegative => v >= 0.0,
                Range::Between(lo, hi, closed) => (v > lo || (closed && v == lo)) && v <= hi,
            };
        if ok {
            return Ok(());
        }
        let want = match self {
            Range::Positive => "positive".to_string(),
            Range::NonNegative => "zero or positive".to_string(),
            Range::Between(lo, hi, true) => format!("between {} and {}", fmt_plain(lo), fmt_plain(hi)),
            Range::Between(lo, hi, false) => format!("above {} and at most {}", fmt_plain(lo), fmt_plain(hi)),
        };
        let hint = if v.is_finite() && v != 0.0 {
            " (check the units: kg, m, N, Pa, N·s/m)"
        } else {
            ""
        };
        Err(bad(key, format!("must be {want}, got {}{hint}", fmt_plain(v))))
    }
}

/// A bad value of the design file at `key`: `design: 'key' msg` (the file and line are added by
/// [`Design::from_toml`]).
pub(crate) fn bad(key: &str, msg: String) -> Error {
    Error::key(String::new(), None, key, format!("design: '{key}' {msg}"))
}

impl Design {
    /// The paper's 100 Hz table (S3–S8 of docs/spec/scenes.md), with the S7 table reconstruction.
    pub fn paper() -> Design {
        Design {
            version: 1,
            name: "paper 100 Hz two-mass table".into(),
            excitation_hz: 100.0,
            target_amplitude: 0.2e-3,
            target_detuning: 0.97,
            tune: "leaf".into(),
            steel: [2.1e11, 0.3, 7850.0],
            table: TableDesign::default(),
            masses: MassDesign::default(),
            leaf: LeafDesign::default(),
            coil: CoilDesign::default(),
            drive: DriveDesign::default(),
            damping: DampingDesign::default(),
            machine: Default::default(),
            spacers: "plates".into(),
            search: Default::default(),
            envelope: Default::default(),
        }
    }

    /// Read a design TOML file (fields as [`Design`]; missing ones take the paper's values).
    pub fn from_toml(path: &std::path::Path) -> Result<Design> {
        use crate::app::toml_file;
        let text = toml_file::read(path)?;
        let mut d: Design = toml_file::parse(path, &text)?;
        toml_file::check_version(path, &text, "design", d.version as i64)?;
        // The mains frequency given alone sets the excitation (twice it, under both laws); one
        // out of its range is left to its own check, which names it (not the excitation).
        if let (Some(f), Ok(raw)) = (d.drive.mains_hz, text.parse::<toml::Table>())
            && !raw.contains_key("excitation_hz")
            && f > 0.0
            && f <= MAX_MAINS_HZ
        {
            d.excitation_hz = 2.0 * f;
        }
        d.validate().map_err(|e| toml_file::locate(path, &text, e))?;
        Ok(d)
    }

    /// Check the range of every value before any work; the error names the key of the first
    /// bad one ([`Design::from_toml`] adds the file and the line). The FE parts, the two-mass
    /// model and the transient then never meet a value they would refuse late.
    pub fn validate(&self) -> Result<()> {
        for (key, v, range) in self.ranges() {
            range.check(key, v)?;
        }
        self.validate_counts()?;
        self.validate_transient()?;
        self.validate_choices()?;
        self.validate_parts()?;
        self.validate_fatigue()?;
        self.machine.validate(self)?;
        self.search.validate()?;
        self.envelope.validate(self)
    }

    /// Every number of the file with its range.
    fn ranges(&self) -> Vec<(&'static str, f64, Range)> {
        use Range::*;
        let (m, l, c, dr, dp) = (&self.masses, &self.leaf, &self.coil, &self.drive, &self.damping);
        vec![
            (
                "excitation_hz",
                self.excitation_hz,
                Between(0.0, MAX_EXCITATION_HZ, false),
            ),
            ("target_amplitude", self.target_amplitude, Positive),
            (
                "target_detuning",
                self.target_detuning,
                Between(MIN_DETUNING, MAX_DETUNING, true),
            ),
            ("masses.load", m.load, Between(0.0, MAX_MASS, true)),
            ("masses.load_share", m.load_share, Between(0.0, 1.0, true)),
            ("masses.active_extra", m.active_extra, Between(0.0, MAX_MASS, true)),
            ("masses.reactive", m.reactive, Between(MIN_MASS, MAX_MASS, true)),
            ("leaf.thickness", l.thickness, Between(MIN_THICKNESS, MAX_LENGTH, true)),
            ("leaf.length", l.length, Between(0.0, MAX_LENGTH, false)),
            ("leaf.width", l.width, Between(0.0, MAX_LENGTH, false)),
            ("leaf.clamping", l.clamping, Between(0.0, 1.0, false)),
            ("leaf.allowable", l.allowable, Positive),
            ("coil.wire", c.wire, Between(0.0, MAX_LENGTH, false)),
            ("coil.mean_diameter", c.mean_diameter, Between(0.0, MAX_LENGTH, false)),
            ("coil.turns", c.turns, Between(MIN_TURNS, MAX_TURNS, true)),
            ("coil.pitch", c.pitch, Between(0.0, MAX_LENGTH, false)),
            ("coil.shear_modulus", c.shear_modulus, Between(0.0, MAX_MODULUS, false)),
            ("coil.allowable_shear", c.allowable_shear, Positive),
            ("drive.pull", dr.pull, Between(0.0, MAX_FORCE, false)),
            ("drive.efficiency", dr.efficiency, Between(0.0, 1.0, false)),
            ("drive.installed_power", dr.installed_power, Positive),
            ("drive.transient_s", dr.transient_s, Positive),
            ("drive.power_overload_g", dr.power_overload_g, Positive),
            ("drive.power_load_share", dr.power_load_share, NonNegative),
            (
                "drive.mains_hz",
                dr.mains_hz.unwrap_or(0.5 * self.excitation_hz),
                Between(0.0, MAX_MAINS_HZ, false),
            ),
            ("drive.gap", dr.gap, Positive),
            ("drive.gap_margin", dr.gap_margin, NonNegative),
            ("damping.mu1", dp.mu1, Between(0.0, MAX_DAMPING, true)),
            ("damping.mu12", dp.mu12, Between(0.0, MAX_DAMPING, true)),
            ("damping.mu13", dp.mu13, Between(0.0, MAX_DAMPING, true)),
        ]
    }

    /// Counts and mesh sizes: at least one of each part, meshes of bounded size.
    fn validate_counts(&self) -> Result<()> {
        for (key, n) in [
            ("leaf.count", self.leaf.count),
            ("coil.count", self.coil.count),
            ("drive.magnets", self.drive.magnets),
        ] {
            if n == 0 {
                return Err(bad(key, "must be at least 1, got 0".into()));
            }
        }
        // One length that must exceed another (the parts' builders refuse these too, but late,
        // after FE work, and without the key).
        let (c, l) = (&self.coil, &self.leaf);
        for (key, v, what, other, o, why) in [
            (
                "coil.mean_diameter",
                c.mean_diameter,
                "the wire diameter",
                "coil.wire",
                c.wire,
                "spring index D/d > 1",
            ),
            (
                "coil.pitch",
                c.pitch,
                "the wire diameter",
                "coil.wire",
                c.wire,
                "the coils would touch",
            ),
            (
                "leaf.length",
                l.length,
                "the leaf's thickness",
                "leaf.thickness",
                l.thickness,
                "a leaf spring is a slender plate",
            ),
        ] {
            if !(v > o) {
                return Err(bad(
                    key,
                    format!("must exceed {what} '{other}' = {o} m ({why}), got {v}"),
                ));
            }
        }
        if self.leaf.divisions.contains(&0) || self.leaf.divisions.iter().product::<usize>() > 200_000 {
            return Err(bad(
                "leaf.divisions",
                format!(
                    "must be at least 1 each and at most 200 000 cells in all, got {:?}",
                    self.leaf.divisions
                ),
            ));
        }
        if !(self.table.elem_size >= 0.002 && self.table.elem_size.is_finite()) {
            return Err(bad(
                "table.element_size",
                format!("must be at least 0.002 m, got {}", self.table.elem_size),
            ));
        }
        let t = &self.table;
        if let Some((side, v)) = t.oversized_side(t.elem_size) {
            return Err(bad(
                &format!("table.{side}"),
                format!(
                    "= {v} m is {:.3e} elements of 'table.element_size' = {} m, more than {MAX_TABLE_DIVISIONS} \
                     along one side (a table of metres, or a coarser element size)",
                    v / t.elem_size,
                    t.elem_size
                ),
            ));
        }
        if self.coil.elements_per_turn < 3 || self.coil.elements_per_turn > 1000 {
            return Err(bad(
                "coil.elements_per_turn",
                format!("must be between 3 and 1000, got {}", self.coil.elements_per_turn),
            ));
        }
        Ok(())
    }

    /// The start-up transient: long enough for its steady values (the last ten periods), short
    /// enough for the integrator (issue 15 item 12: hours of machine time ran for minutes).
    fn validate_transient(&self) -> Result<()> {
        let (t, f) = (self.drive.transient_s, self.excitation_hz);
        if t > MAX_TRANSIENT_S {
            // The start-up settles within about 0.4 s; a run of hours of machine time takes the
            // integrator millions of steps (it used to stop with "more than max_steps" after minutes).
            return Err(bad(
                "drive.transient_s",
                format!(
                    "= {t} s is longer than {MAX_TRANSIENT_S} s (the start-up settles within a second; \
                     {MAX_TRANSIENT_S} s is {} periods of the excitation)",
                    (MAX_TRANSIENT_S * f).round()
                ),
            ));
        }
        let periods = t * f;
        if periods < MIN_TRANSIENT_PERIODS {
            return Err(bad(
                "drive.transient_s",
                format!(
                    "= {t} s is {periods:.3} periods of the {f} Hz excitation: the steady values are read from \
                     the last {MIN_TRANSIENT_PERIODS} periods; give at least {} s",
                    MIN_TRANSIENT_PERIODS / f
                ),
            ));
        }
        if periods > MAX_TRANSIENT_PERIODS {
            return Err(bad(
                "drive.transient_s",
                format!(
                    "= {t} s is {periods:.0} periods of the {f} Hz excitation, more than {MAX_TRANSIENT_PERIODS} \
                     (the integrator resolves every period); give at most {} s",
                    MAX_TRANSIENT_PERIODS / f
                ),
            ));
        }
        Ok(())
    }

    /// Named choices: `tune`, `spacers`.
    fn validate_choices(&self) -> Result<()> {
        if !["none", "leaf", "mass"].contains(&self.tune.as_str()) {
            return Err(bad("tune", format!("must be none, leaf or mass, got '{}'", self.tune)));
        }
        if crate::app::dynamics::electromagnet::ForceLaw::parse(&self.drive.force_law).is_none() {
            return Err(bad(
                "drive.force_law",
                format!("must be flux or paper, got '{}'", self.drive.force_law),
            ));
        }
        if let Some(f) = self.drive.mains_hz
            && (2.0 * f - self.excitation_hz).abs() > 1e-9 * self.excitation_hz
        {
            return Err(bad(
                "drive.mains_hz",
                format!(
                    "= {f} Hz drives the magnets at twice it, {} Hz, but 'excitation_hz' is {} Hz: give one of \
                     them, or make excitation_hz twice the mains frequency",
                    2.0 * f,
                    self.excitation_hz
                ),
            ));
        }
        if !["plates", "channel10"].contains(&self.spacers.as_str()) {
            return Err(bad(
                "spacers",
                format!("must be plates or channel10, got '{}'", self.spacers),
            ));
        }
        Ok(())
    }

    /// Checks of the parts' own builders, here so that the message names the design key.
    fn validate_parts(&self) -> Result<()> {
        for (key, [young, poisson, density]) in [("steel", self.steel), ("leaf.material", self.leaf.material)] {
            Material {
                young,
                poisson,
                density,
            }
            .validate(&format!("'{key}'"))
            .map_err(|e| crate::app::toml_file::bad_value(key, e))?;
        }
        // The generator names its parameter ("length"): the file's key is table.<it> (its size
        // is written `element_size` there).
        self.sandwich().validate().map_err(|e| {
            let key_of = |name: String| match name.as_str() {
                "elem_size" => "table.element_size".to_string(),
                _ => format!("table.{name}"),
            };
            match crate::app::toml_file::param_as_key(e, key_of) {
                Ok((key, msg)) => crate::app::toml_file::bad_value(&key, msg),
                Err(e) => crate::app::toml_file::bad_value("table", e),
            }
        })
    }

    /// The mains frequency, Hz: given, or half the excitation.
    pub fn mains_hz(&self) -> f64 {
        self.drive.mains_hz.unwrap_or(0.5 * self.excitation_hz)
    }

    /// The force law (`drive.force_law`; flux if unreadable, which validation refuses first).
    pub fn force_law(&self) -> crate::app::dynamics::electromagnet::ForceLaw {
        crate::app::dynamics::electromagnet::ForceLaw::parse(&self.drive.force_law).unwrap_or_default()
    }

    /// The magnets' pull under the design's force law, on its mains frequency.
    pub fn magnet_drive(&self) -> Result<crate::app::dynamics::electromagnet::MagnetDrive> {
        crate::app::dynamics::electromagnet::MagnetDrive::from_magnets(
            self.force_law(),
            self.drive.magnets,
            self.drive.pull,
            std::f64::consts::TAU * self.mains_hz(),
        )
    }

    /// The magnets' stiffness at the working gap, all together (N/m, negative): −2P̄/δ with the
    /// mean pull of the design's force law.
    pub fn magnet_stiffness(&self) -> Result<f64> {
        crate::app::dynamics::electromagnet::magnet_stiffness(self.magnet_drive()?.mean(), self.drive.gap)
    }

    /// Whether this is the built-in paper design (every input as [`Design::paper`]): only it is
    /// compared with the paper's published numbers.
    pub fn is_builtin(&self) -> bool {
        serde_json::to_value(self).ok() == serde_json::to_value(Design::paper()).ok()
    }

    /// The `[leaf.fatigue]` and `[coil.fatigue]` inputs, each error naming its key.
    fn validate_fatigue(&self) -> Result<()> {
        use crate::post::fatigue::{FatigueMaterial, MeanStress, reliability_factor};
        let (lf, cf) = (&self.leaf.fatigue, &self.coil.fatigue);
        for (key, m) in [
            ("leaf.fatigue.material", &lf.material),
            ("coil.fatigue.material", &cf.material),
        ] {
            FatigueMaterial::parse(key, m).map_err(|e| bad(key, format!("{e}")))?;
        }
        MeanStress::parse("leaf.fatigue.mean_stress", &lf.mean_stress)
            .map_err(|e| bad("leaf.fatigue.mean_stress", format!("{e}")))?;
        reliability_factor(lf.reliability).map_err(|e| bad("leaf.fatigue.reliability", format!("{e}")))?;
        for (key, v, range) in [
            ("leaf.fatigue.safety", lf.safety, Range::Positive),
            ("leaf.fatigue.cycles", lf.cycles, Range::Between(1.0, 1e15, true)),
            (
                "leaf.fatigue.roughness",
                lf.roughness,
                Range::Between(0.0, 1000.0, true),
            ),
            ("coil.fatigue.safety", cf.safety, Range::Positive),
            ("coil.fatigue.overrun", cf.overrun, Range::NonNegative),
            ("coil.fatigue.seating", cf.seating, Range::Between(0.5, 2.0, true)),
            (
                "coil.fatigue.surge_clearance",
                cf.surge_clearance,
                Range::Between(0.0, 1.0, true),
            ),
        ] {
            range.check(key, v)?;
        }
        if !["goodman", "gerber"].contains(&cf.criterion.as_str()) {
            return Err(bad(
                "coil.fatigue.criterion",
                format!("must be goodman or gerber, got '{}'", cf.criterion),
            ));
        }
        if !["plain", "plain_ground", "squared", "squared_ground"].contains(&cf.ends.as_str()) {
            return Err(bad(
                "coil.fatigue.ends",
                format!(
                    "must be plain, plain_ground, squared or squared_ground, got '{}'",
                    cf.ends
                ),
            ));
        }
        Ok(())
    }

    /// The table generator's parameters (quad4 shells).
    pub(crate) fn sandwich(&self) -> SandwichParams {
        SandwichParams {
            shell_kind: CellKind::Quad4,
            ..self.table.clone()
        }
    }
}

/// The 3D machine's layout and limits (`[machine]` of a design file).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MachineDesign {
    /// `"shells"` (the FE work table) or `"rigid"` (the table as one rigid body with the shell
    /// model's mass and inertia).
    pub table_model: String,
    /// One per leaf: `[x, y, dx, dy]`, the table end (m, from the table centre) and the
    /// horizontal direction from it to the clamp on the reactive mass.
    pub leaves: Vec<[f64; 4]>,
    /// Height of the leaves' mid-plane (m; the bottom plate's mid-surface is z = 0).
    pub leaf_level: f64,
    /// Length of a leaf's shoe on the bottom plate (m, along the leaf; across: the leaf width).
    pub shoe_length: f64,
    /// One per magnet: `[x, y]` (m) of its armature centre (on the bottom plate) and its core.
    pub magnets: Vec<[f64; 2]>,
    /// Armature patch on the bottom plate, `[along x, along y]` (m).
    pub armature: [f64; 2],
    /// One per isolator: `[x, y, z]` (m), where it holds the reactive mass.
    pub isolators: Vec<[f64; 3]>,
    /// Centre of the reactive mass (m).
    pub reactive_centre: [f64; 3],
    /// The reactive mass as a uniform block `[a, b, c]` (m) for its inertia.
    pub reactive_box: [f64; 3],
    /// Modes are reported up to this multiple of the excitation.
    pub mode_range: f64,
    /// Modes up to this multiple of the excitation carry the forced response.
    pub response_range: f64,
    /// No mode but the working one may lie within this fraction of the excitation.
    pub mode_clearance: f64,
    /// Limit on the work surface's amplitude non-uniformity (max − min)/mean.
    pub max_nonuniformity: f64,
}

impl Default for MachineDesign {
    fn default() -> Self {
        let mut leaves = vec![];
        for x in [0.55, 0.25] {
            for sx in [1.0, -1.0] {
                for y in [0.12, -0.12] {
                    leaves.push([sx * x, y, -sx, 0.0]);
                }
            }
        }
        let mut magnets = vec![];
        let mut isolators = vec![];
        for x in [-0.4, -0.1, 0.1, 0.4] {
            for y in [-0.1, 0.1] {
                magnets.push([x, y]);
            }
        }
        for x in [-0.45, -0.15, 0.15, 0.45] {
            for y in [-0.15, 0.15] {
                isolators.push([x, y, -0.2]);
            }
        }
        MachineDesign {
            table_model: "shells".into(),
            leaves,
            leaf_level: -0.06,
            shoe_length: 0.05,
            magnets,
            armature: [0.1, 0.1],
            isolators,
            reactive_centre: [0.0, 0.0, -0.17],
            reactive_box: [1.0, 0.35, 0.06],
            mode_range: 3.0,
            response_range: 6.0,
            mode_clearance: 0.10,
            max_nonuniformity: 0.10,
        }
    }
}

impl MachineDesign {
    /// Check the layout against the rest of the design (counts, finite positions, limits).
    pub fn validate(&self, d: &Design) -> Result<()> {
        if !["shells", "rigid"].contains(&self.table_model.as_str()) {
            return Err(bad(
                "machine.table_model",
                format!("must be shells or rigid, got '{}'", self.table_model),
            ));
        }
        let counts = [
            ("machine.leaves", self.leaves.len(), d.leaf.count, "leaf.count"),
            ("machine.magnets", self.magnets.len(), d.drive.magnets, "drive.magnets"),
            ("machine.isolators", self.isolators.len(), d.coil.count, "coil.count"),
        ];
        for (key, n, want, other) in counts {
            if n != want {
                return Err(bad(key, format!("lists {n} positions but '{other}' is {want}")));
            }
        }
        // Positions within the plausible part length of the origin (an isolator at 1e300 m
        // surfaced as a non-finite spring stiffness).
        let finite = |key: &str, v: &[f64]| -> Result<()> {
            if v.iter().all(|x| x.is_finite() && x.abs() <= MAX_LENGTH) {
                Ok(())
            } else {
                let shown: Vec<String> = v.iter().map(|&x| fmt_plain(x)).collect();
                Err(bad(
                    key,
                    format!(
                        "must be finite and within {} m, got [{}]",
                        fmt_plain(MAX_LENGTH),
                        shown.join(", ")
                    ),
                ))
            }
        };
        for l in &self.leaves {
            finite("machine.leaves", l)?;
            if (l[2] * l[2] + l[3] * l[3]).sqrt() < 1e-9 {
                return Err(bad("machine.leaves", format!("{l:?}: the direction (dx, dy) is zero")));
            }
        }
        for m in &self.magnets {
            finite("machine.magnets", m)?;
        }
        for i in &self.isolators {
            finite("machine.isolators", i)?;
        }
        finite("machine.reactive_centre", &self.reactive_centre)?;
        finite("machine.leaf_level", &[self.leaf_level])?;
        let pos = |key: &str, v: f64| -> Result<()> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(bad(key, format!("must be positive, got {v}")))
            }
        };
        pos("machine.shoe_length", self.shoe_length)?;
        pos("machine.armature", self.armature[0].min(self.armature[1]))?;
        pos(
            "machine.reactive_box",
            self.reactive_box.iter().copied().fold(f64::INFINITY, f64::min),
        )?;
        pos("machine.mode_range", self.mode_range)?;
        pos("machine.mode_clearance", self.mode_clearance)?;
        pos("machine.max_nonuniformity", self.max_nonuniformity)?;
        if !(self.response_range >= self.mode_range) {
            return Err(bad(
                "machine.response_range",
                format!(
                    "must be at least machine.mode_range ({}), got {}",
                    self.mode_range, self.response_range
                ),
            ));
        }
        Ok(())
    }
}

/// What the search may vary (`[search]` of a design file).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SearchDesign {
    /// Search when a check fails.
    pub enabled: bool,
    /// Top-plate thicknesses (m).
    pub top_thickness: Vec<f64>,
    /// Bottom-plate thicknesses (m).
    pub bottom_thickness: Vec<f64>,
    /// Bottom-plate widths (m).
    pub bottom_width: Vec<f64>,
    /// Numbers of longitudinal webs.
    pub n_long_webs: Vec<usize>,
    /// Distances between the outermost longitudinal webs (m; the webs evenly spaced, centred);
    /// spans that would put a web within 10 mm of the bottom plate's edge are skipped.
    pub long_web_span: Vec<f64>,
    /// Numbers of transverse webs (evenly spaced over `trans_web_span`).
    pub n_trans_webs: Vec<usize>,
    /// Span of the transverse webs (m).
    pub trans_web_span: f64,
    /// Spacers: `"plates"`, `"channel10"`.
    pub spacers: Vec<String>,
    /// At most this many whole chains (each some seconds; over the envelope, each variant's
    /// corners).
    pub max_full_runs: usize,
    /// Thinnest top plate the bolt recess allows (m): thinner `top_thickness` values are skipped.
    pub top_min: f64,
    /// Peak pulls per magnet to try (N); empty: the design's `drive.pull` only.
    pub pull: Vec<f64>,
    /// Moves of every leaf's table end along its own direction (m, towards its clamp; negative:
    /// outwards) to try; `[0.0]` keeps the layout.
    pub leaf_shift: Vec<f64>,
    /// Margin every check must keep over the whole envelope (a fraction of its limit, as the
    /// checks' margins).
    pub required_margin: f64,
    /// Judge the variants over the envelope (`[envelope]`); else at the nominal point only.
    pub over_envelope: bool,
}

impl Default for SearchDesign {
    /// The family the built-in design's search covers: the bottom plate as wide as the top one
    /// with the longitudinal webs spread over 500 mm, three transverse webs, top plates of 12 to
    /// 20 mm, plate webs or channels. (A broader list, 288 variants with 400 mm bottom plates and
    /// webs over 300 mm, found no passing variant in its six lightest whole chains: docs/design.md.)
    fn default() -> Self {
        SearchDesign {
            enabled: true,
            top_thickness: vec![0.012, 0.016, 0.02],
            bottom_thickness: vec![0.008],
            bottom_width: vec![0.6],
            n_long_webs: vec![3, 5],
            long_web_span: vec![0.5],
            n_trans_webs: vec![3],
            trans_web_span: 1.1,
            spacers: vec!["plates".into(), "channel10".into()],
            max_full_runs: 3,
            top_min: 0.012,
            pull: vec![330.0, 370.0, 410.0],
            leaf_shift: vec![0.0, 0.03],
            required_margin: 0.05,
            over_envelope: true,
        }
    }
}

impl SearchDesign {
    /// The pull, leaf-position and margin fields.
    fn validate_envelope_fields(&self) -> Result<()> {
        let bad = |k: &str, m: String| bad(&format!("search.{k}"), m);
        if !(self.top_min.is_finite() && self.top_min >= 0.0) {
            return Err(bad(
                "top_min",
                format!("must be zero or positive, got {}", self.top_min),
            ));
        }
        if self.top_thickness.iter().all(|&t| t < self.top_min) {
            return Err(bad(
                "top_min",
                format!(
                    "= {} m leaves no value of search.top_thickness {:?}",
                    self.top_min, self.top_thickness
                ),
            ));
        }
        if self.pull.iter().any(|p| !(p.is_finite() && *p > 0.0)) {
            return Err(bad(
                "pull",
                format!("must list positive pulls (N), got {:?}", self.pull),
            ));
        }
        if self.leaf_shift.is_empty() || self.leaf_shift.iter().any(|x| !(x.is_finite() && x.abs() < 1.0)) {
            return Err(bad(
                "leaf_shift",
                format!("must list moves under 1 m (e.g. [0.0]), got {:?}", self.leaf_shift),
            ));
        }
        if !(self.required_margin.is_finite() && (0.0..1.0).contains(&self.required_margin)) {
            return Err(bad(
                "required_margin",
                format!("must be at least 0 and below 1, got {}", self.required_margin),
            ));
        }
        Ok(())
    }
}

/// At most this many valid variants in a search (each is screened, the lightest run whole).
pub const MAX_SEARCH_VARIANTS: usize = 1000;
/// At most this many combinations of the `[search]` lists (each screened without FE work).
pub const MAX_SEARCH_COMBINATIONS: usize = 100_000;

impl SearchDesign {
    /// The product of the lists' lengths: the combinations the search screens (saturating).
    pub fn combinations(&self) -> usize {
        [
            self.top_thickness.len(),
            self.bottom_thickness.len(),
            self.bottom_width.len(),
            self.n_long_webs.len(),
            self.n_trans_webs.len(),
            self.spacers.len(),
            self.long_web_span.len(),
            self.pull.len().max(1),
            self.leaf_shift.len(),
        ]
        .iter()
        .fold(1usize, |a, &n| a.saturating_mul(n))
    }

    /// Check the lists (non-empty, positive, known spacer names, a bounded product).
    pub fn validate(&self) -> Result<()> {
        let bad = |k: &str, m: String| bad(&format!("search.{k}"), m);
        for (k, v) in [
            ("top_thickness", &self.top_thickness),
            ("bottom_thickness", &self.bottom_thickness),
            ("bottom_width", &self.bottom_width),
            ("long_web_span", &self.long_web_span),
        ] {
            if v.is_empty() || v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
                return Err(bad(k, format!("must list positive values, got {v:?}")));
            }
        }
        if self.n_long_webs.is_empty() || self.n_trans_webs.is_empty() || self.spacers.is_empty() {
            return Err(bad("n_long_webs", "n_trans_webs and spacers must not be empty".into()));
        }
        if let Some(s) = self
            .spacers
            .iter()
            .find(|s| !["plates", "channel10"].contains(&s.as_str()))
        {
            return Err(bad("spacers", format!("lists '{s}': plates or channel10")));
        }
        if self.n_long_webs.iter().chain(&self.n_trans_webs).any(|&n| n > 50) {
            return Err(bad("n_long_webs", "and n_trans_webs must be at most 50".into()));
        }
        if !(self.trans_web_span.is_finite() && self.trans_web_span > 0.0) {
            return Err(bad(
                "trans_web_span",
                format!("must be positive, got {}", self.trans_web_span),
            ));
        }
        let n = self.combinations();
        if n > MAX_SEARCH_COMBINATIONS {
            return Err(bad(
                "top_thickness",
                format!(
                    "and the other lists of [search] give {n} combinations (at most {MAX_SEARCH_COMBINATIONS}, of \
                     which at most {MAX_SEARCH_VARIANTS} valid variants): shorten them"
                ),
            ));
        }
        self.validate_envelope_fields()?;
        if self.max_full_runs == 0 || self.max_full_runs > 50 {
            return Err(bad(
                "max_full_runs",
                format!("must be 1 to 50, got {}", self.max_full_runs),
            ));
        }
        Ok(())
    }
}
