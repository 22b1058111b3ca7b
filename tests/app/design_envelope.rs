//! The design envelope (issue 29 items 2 and 7): load cases and tolerance bands set by design
//! keys, every check over them, the corners equal to single runs, and the section's errors.

use vibrofem::app::design::envelope::{self, EnvelopeDesign, LoadCase, Tolerance, corner_patterns};
use vibrofem::app::design::{Design, cache, run_design};

/// The paper's design made cheap for envelope tests: table `table_model` on a coarse mesh,
/// coarse leaves, no tuning, a start-up of `transient_s`, no search; its envelope on, full runs,
/// with the default envelope's load cases and bands numbered `cases` and `bands`.
pub(crate) fn coarse(table_model: &str, transient_s: f64, cases: &[usize], bands: &[usize]) -> Design {
    let mut d = Design::paper();
    d.machine.table_model = table_model.into();
    d.table.elem_size = 0.05;
    d.leaf.divisions = [12, 4, 1];
    d.leaf.thickness = 0.0096;
    d.tune = "none".into();
    d.drive.transient_s = transient_s;
    d.search.enabled = false;
    let full = EnvelopeDesign::default();
    d.envelope = EnvelopeDesign {
        enabled: true,
        load_cases: cases.iter().map(|&i| full.load_cases[i].clone()).collect(),
        tolerances: bands.iter().map(|&i| full.tolerances[i].clone()).collect(),
        fd_step: 0.1,
        reduced: false,
        reduced_tol: full.reduced_tol,
    };
    d
}

/// A small design: the rigid table on a coarse mesh, coarse leaves, no tuning (each chain a
/// fraction of a second), with two load cases and two bands.
fn small() -> Design {
    coarse("rigid", 0.1, &[1, 2], &[0, 4])
}

#[test]
fn envelope_corners_equal_single_runs() {
    let d = small();
    let r = run_design(&d, None, &|_| {}).unwrap();
    let e = envelope::run(&d, &r, &|_| {}).unwrap();
    // Nominal, two differences, then corners for each of the two load cases.
    assert!(e.runs.len() >= 5, "{}", e.runs.len());
    let ids: Vec<&str> = r.checks.iter().map(|c| c.id.as_str()).collect();
    assert_eq!(e.checks.iter().map(|c| c.id.as_str()).collect::<Vec<_>>(), ids);
    for c in &e.checks {
        assert!(
            c.min <= c.nominal && c.nominal <= c.max,
            "{}: {} {} {}",
            c.id,
            c.min,
            c.nominal,
            c.max
        );
    }
    // The nominal point of the as-built design is the design's own run (same leaves, no tuning).
    for (a, b) in r.checks.iter().zip(&e.runs[0].checks) {
        assert_eq!(a.value.to_bits(), b.value.to_bits(), "{}", a.id);
    }
    // A corner of the second load case equals a single run of its design, its FE parts
    // computed afresh (memo emptied): the memo returns what the computation gives. 1e-12: the
    // same operations in the same order; only a parallel reduction could reorder sums.
    let corner = e
        .runs
        .iter()
        .rev()
        .find(|x| x.label.contains("share corner"))
        .expect("a corner of the share case");
    assert_eq!(corner.design.masses.load_share, 0.3);
    assert!(((corner.design.leaf.clamping - 0.75).abs() - 0.03).abs() < 1e-12);
    cache::clear();
    let single = run_design(&corner.design, None, &|_| {}).unwrap();
    for (a, b) in single.checks.iter().zip(&corner.checks) {
        let tol = 1e-12 * a.value.abs().max(1e-300);
        assert!(
            (a.value - b.value).abs() <= tol || a.value == b.value,
            "{}: {} vs {}",
            a.id,
            a.value,
            b.value
        );
    }
    // In JSON, every check under its id with its envelope.
    let json = serde_json::to_value(&e).unwrap();
    for c in &e.checks {
        let j = &json["checks"][&c.id];
        assert_eq!(j["min"].as_f64(), Some(c.min), "{}", c.id);
        assert_eq!(j["max"].as_f64(), Some(c.max), "{}", c.id);
    }
    assert!(
        json["sensitivities"]["clamping"]["d_value"]["leaf_stress"]
            .as_f64()
            .is_some()
    );
}

#[test]
fn bands_and_load_cases_set_design_keys() {
    let mut d = small();
    d.envelope.tolerances.push(Tolerance {
        id: "young".into(),
        name: "E".into(),
        keys: vec!["leaf.material.0".into()],
        minus: 0.01,
        plus: 0.02,
        relative: true,
    });
    d.validate().unwrap();
    let e = &d.envelope;
    let v = e.design_at(&d, Some(1), &[-1.0, 1.0, 1.0]).unwrap();
    assert_eq!(v.masses.load_share, 0.3);
    assert_eq!(v.leaf.clamping, 0.75 - 0.03);
    assert_eq!(v.damping.mu12, 1830.0 * 1.3);
    assert_eq!(v.leaf.material[0], 2.1e11 * 1.02);
    assert!(!v.envelope.enabled && !v.search.enabled);
    // The mains band takes the first key the design has.
    let mains = &EnvelopeDesign::default().tolerances[3];
    assert!(mains.keys[0].contains('|'));
}

#[test]
fn envelope_section_errors_name_the_key() {
    let mut d = small();
    d.envelope.tolerances[0].keys = vec!["leaf.clamp".into()];
    let err = d.validate().unwrap_err().to_string();
    assert!(
        err.contains("envelope.tolerances[0]") && err.contains("leaf.clamp"),
        "{err}"
    );
    let mut d = small();
    d.envelope.load_cases.push(LoadCase {
        name: "heavy".into(),
        set: [("masses.load_share".to_string(), serde_json::json!(1.5))]
            .into_iter()
            .collect(),
    });
    let err = d.validate().unwrap_err().to_string();
    assert!(
        err.contains("envelope.load_cases[2]") && err.contains("load_share"),
        "{err}"
    );
    let mut d = small();
    d.envelope.tolerances[0].plus = 0.3; // clamping 1.05: out of its range
    let err = d.validate().unwrap_err().to_string();
    assert!(
        err.contains("envelope.tolerances[0]") && err.contains("leaf.clamping"),
        "{err}"
    );
    let mut d = small();
    d.masses.load_offset = [2.0, 0.0];
    let err = d.validate().unwrap_err().to_string();
    assert!(err.contains("masses.load_offset"), "{err}");
}

#[test]
fn corner_patterns_are_the_worst_and_opposite_corners() {
    // Check 1: margin grows with p0, falls with p1 → worst corner (−, +), opposite (+, −).
    // Check 2 shares them; check 3 has no gradient; check 4 adds (−, −) and (+, +).
    let g = vec![vec![2.0, -1.0], vec![1.0, -5.0], vec![0.0, 0.0], vec![3.0, 3.0]];
    let p = corner_patterns(&g);
    assert_eq!(
        p,
        vec![vec![-1.0, 1.0], vec![1.0, -1.0], vec![-1.0, -1.0], vec![1.0, 1.0]]
    );
}

#[test]
fn linear_transient_matches_the_two_mass_startup() {
    // The generic n-DOF integration (matrices, ramped phase, bisected kinks) against the
    // two-mass start-up's own right-hand side switched onto the mains at t = 0: the same
    // equations by two codings, both at rtol 1e-10; 1e-7 of the amplitude allows for the kink
    // times differing in their last bits (bisection against the closed form).
    use vibrofem::app::dynamics::electromagnet::RectifiedDrive;
    use vibrofem::app::dynamics::ode::Dopri5Options;
    use vibrofem::app::dynamics::transient::{Ramp, TransientOptions, simulate_linear, simulate_startup};
    use vibrofem::app::dynamics::two_mass::TwoMass;
    let tm = TwoMass::paper();
    let drive = RectifiedDrive::paper();
    let opts = TransientOptions {
        t_end: 0.1,
        samples_per_period: 40,
        ..Default::default()
    };
    let a = simulate_startup(&tm, &drive, &opts).unwrap();
    let (m, c, k) = tm.matrices();
    let flat = |x: nalgebra::Matrix2<f64>| vec![x[(0, 0)], x[(0, 1)], x[(1, 0)], x[(1, 1)]];
    let ramp = Ramp {
        omega_mains: drive.omega_mains,
        up_s: 0.0,
        hold_s: 1.0,
        down_s: 0.0,
    };
    let dt = std::f64::consts::TAU / drive.omega_force() / 40.0;
    let b = simulate_linear(
        &flat(m),
        &flat(c),
        &flat(k),
        &[-1.0, 1.0],
        drive.p_em,
        &ramp,
        0.1,
        dt,
        &Dopri5Options::default(),
    )
    .unwrap();
    assert_eq!(a.t.len(), b.t.len());
    let scale = a.x1.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    for i in 0..a.t.len() {
        assert!((a.x1[i] - b.x[i][0]).abs() < 1e-7 * scale, "x1 at {}", a.t[i]);
        assert!((a.x2[i] - b.x[i][1]).abs() < 1e-7 * scale, "x2 at {}", a.t[i]);
    }
}

#[test]
fn ramp_phase_and_kinks() {
    use vibrofem::app::dynamics::transient::Ramp;
    let r = Ramp {
        omega_mains: 314.0,
        up_s: 2.0,
        hold_s: 1.0,
        down_s: 2.0,
    };
    // Continuous phase at the switching times; the frequency runs 0 → ω → 0.
    for t in [2.0, 3.0] {
        assert!((r.phase(t - 1e-9).unwrap() - r.phase(t + 1e-9).unwrap()).abs() < 1e-6);
    }
    assert_eq!(r.omega_at(1.0), 157.0);
    assert!(r.phase(5.5).is_none());
    // Every kink is a zero of sin φ: φ = nπ.
    for t in r.kinks(6.0).into_iter().filter(|t| ![2.0, 3.0, 5.0].contains(t)) {
        let ph = r.phase(t).unwrap() / std::f64::consts::PI;
        assert!((ph - ph.round()).abs() < 1e-9, "{t}: {ph}");
    }
}
