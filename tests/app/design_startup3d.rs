//! Start-up and run-down on the 3D machine's modes (issue 29 item 3) against the two-mass
//! estimate: equal for the rigid symmetric machine, different once an eccentric load couples
//! roll and pitch in.

use vibrofem::app::design::startup::{self, MachineStartup, Startup, TwoMassParts};
use vibrofem::app::design::{Design, MachineResult, analyse};

/// The two-mass model of the same parts as `r` (as `machine3d.rs` builds it): m1 = the table,
/// the active extras and the load share; c12 = n·k_c·k_zz + the magnets' stiffness;
/// c13 = n·k_axial.
fn parts(d: &Design, r: &MachineResult) -> TwoMassParts {
    TwoMassParts {
        m1: r.table_mass + d.masses.active_extra + d.masses.load_share * d.masses.load,
        m2: d.masses.reactive,
        k12: d.leaf.count as f64 * d.leaf.clamping * r.leaf_kzz + d.magnet_stiffness().unwrap(),
        c13: d.coil.count as f64 * r.coil_axial,
    }
}

fn rigid(law: &str) -> Design {
    let mut d = Design::paper();
    d.machine.table_model = "rigid".into();
    d.drive.force_law = law.into();
    d
}

fn pairs(a: &MachineStartup, b: &Startup) -> [(&'static str, f64, f64); 8] {
    [
        ("peak isolator", a.peak_isolator_deflection, b.peak_isolator_deflection),
        (
            "steady isolator",
            a.steady_isolator_deflection,
            b.steady_isolator_deflection,
        ),
        ("peak floor", a.peak_floor_force, b.peak_floor_force),
        ("steady floor", a.steady_floor_force, b.steady_floor_force),
        ("peak relative", a.peak_relative, b.peak_relative),
        ("steady relative", a.steady_relative, b.steady_relative),
        ("peak gap", a.peak_gap, b.peak_relative),
        ("steady gap", a.steady_gap, b.steady_relative),
    ]
}

#[test]
fn rigid_symmetric_machine_starts_up_as_the_two_mass_model() {
    for law in ["flux", "paper"] {
        let d = rigid(law);
        let r = analyse(&d, 0.0099).unwrap();
        let p = parts(&d, &r);
        for ramp in [startup::RAMP_S, 0.0] {
            let a = startup::machine(&d, &r.modal, ramp).unwrap();
            let b = startup::two_mass(&d, &p, ramp).unwrap();
            for (what, x, y) in pairs(&a, &b) {
                eprintln!("{law} {ramp} {what}: {x:.9e} {y:.9e} {:.2e}", (x - y).abs() / y);
            }
            for m in &a.modes {
                eprintln!(
                    "  {} {:.4} {:.4} {:.4} {:.3e} {}",
                    m.name, m.frequency_hz, m.damping_ratio, m.band_time_s, m.peak_modal, m.excited
                );
            }
            eprintln!("  two-mass {:?}", b.modes);
        }
    }
}

#[test]
fn eccentric_load_excites_roll_and_pitch() {
    let mut d = rigid("flux");
    d.masses.load_share = 0.3;
    d.masses.load_offset = [0.3, 0.15];
    let r = analyse(&d, 0.0099).unwrap();
    let p = parts(&d, &r);
    let a = startup::machine(&d, &r.modal, startup::RAMP_S).unwrap();
    let b = startup::two_mass(&d, &p, startup::RAMP_S).unwrap();
    for (what, x, y) in pairs(&a, &b) {
        eprintln!("ecc {what}: {x:.9e} {y:.9e} {:.2e}", (x - y).abs() / y);
    }
    for m in &a.modes {
        eprintln!(
            "  {} {:.4} {:.4} {:.4} {:.3e} {}",
            m.name, m.frequency_hz, m.damping_ratio, m.band_time_s, m.peak_modal, m.excited
        );
    }
}
