//! The design checks: each a function of the design's limits and the chain's results, giving a
//! value against its limit (never text: the report renders them).

use super::file::Design;
use super::results::{ChainValues, Check};

/// Every check, in the order they are reported.
pub fn all(d: &Design, v: &ChainValues) -> Vec<Check> {
    [
        table_f1_vs_excitation,
        isolation,
        leaf_stress,
        coil_stress,
        table_amplitude,
        drive_power,
        mode_clearance,
        surface_uniformity,
        magnet_gap,
        super::fatigue::leaf_fatigue,
        super::fatigue::coil_fatigue,
        super::fatigue::coil_binding,
        super::fatigue::coil_buckling,
        super::fatigue::coil_surge,
    ]
    .iter()
    .map(|check| check(d, v))
    .collect()
}

/// The work table's first elastic mode at least three times the excitation.
pub fn table_f1_vs_excitation(d: &Design, v: &ChainValues) -> Check {
    Check::new(
        "table_f1_vs_excitation",
        "work-table first elastic mode ≥ 3 × excitation [Hz]",
        v.f_table.first().copied().unwrap_or(0.0),
        3.0 * d.excitation_hz,
        false,
    )
}

/// The rigid-body isolation frequency (the whole loaded machine on the isolators) at most a
/// fifth of the excitation (the paper's rule, §7). The force on the floor of a reactive machine
/// is reported beside it (`floor_force_*` quantities), not judged by this figure.
pub fn isolation(d: &Design, v: &ChainValues) -> Check {
    Check::new(
        "isolation",
        "rigid-body isolation frequency (whole loaded mass) ≤ excitation / 5 [Hz]",
        v.f_iso,
        d.excitation_hz / 5.0,
        true,
    )
}

/// The leaf stress at the largest relative amplitude across a leaf of the 3D machine (the model
/// of record) within the allowable.
pub fn leaf_stress(d: &Design, v: &ChainValues) -> Check {
    Check::new(
        "leaf_stress",
        "leaf stress at the working amplitude (3D machine, worst leaf) ≤ allowable: the paper's reference check [MPa]",
        v.sigma_leaf / 1e6,
        d.leaf.allowable / 1e6,
        true,
    )
}

/// The coil's shear stress under the static load within the allowable.
pub fn coil_stress(d: &Design, v: &ChainValues) -> Check {
    Check::new(
        "coil_stress",
        "coil shear stress under static load ≤ allowable [MPa]",
        v.tau / 1e6,
        d.coil.allowable_shear / 1e6,
        true,
    )
}

/// The work surface's mean amplitude on the 3D machine (the model of record) reaches the target.
pub fn table_amplitude(d: &Design, v: &ChainValues) -> Check {
    Check::new(
        "table_amplitude",
        "work-surface mean amplitude (3D machine) reaches the target [mm]",
        v.x1 * 1e3,
        d.target_amplitude * 1e3,
        false,
    )
}

/// The armature clears the core: static sag (weight and mean pull on the leaves and magnets) +
/// the largest relative amplitude across a magnet (3D) + the start-up overshoot + the margin
/// `drive.gap_margin` within the working gap `drive.gap`.
pub fn magnet_gap(d: &Design, v: &ChainValues) -> Check {
    Check::new(
        "magnet_gap",
        "gap closed by sag + amplitude + start-up + margin ≤ working gap [mm]",
        v.gap_closing * 1e3,
        d.drive.gap * 1e3,
        true,
    )
}

/// The drive power of eq. (6) within the installed power.
pub fn drive_power(d: &Design, v: &ChainValues) -> Check {
    Check::new(
        "drive_power",
        "drive power within installed power [W]",
        v.power,
        d.drive.installed_power,
        true,
    )
}

/// No machine mode but the working one within the clearance of the excitation.
pub fn mode_clearance(d: &Design, v: &ChainValues) -> Check {
    Check::new(
        "mode_clearance",
        "no other machine mode within the clearance of the excitation [%]",
        v.machine.nearest_other.map_or(f64::INFINITY, |x| x.1 * 100.0),
        d.machine.mode_clearance * 100.0,
        false,
    )
}

/// The work surface's amplitude non-uniformity within the limit.
pub fn surface_uniformity(d: &Design, v: &ChainValues) -> Check {
    Check::new(
        "surface_uniformity",
        "work-surface amplitude non-uniformity ≤ limit [%]",
        v.machine.nonuniformity * 100.0,
        d.machine.max_nonuniformity * 100.0,
        true,
    )
}
