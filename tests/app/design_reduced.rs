//! The envelope's 3D machine runs in a reduced (Ritz) basis (issue 29 item 2, cost): the reduced
//! envelope agrees with the full one, a bar no reduced run meets gives the full envelope back,
//! and a rigid table (12 DOFs) runs full without a basis.

use std::sync::Arc;
use vibrofem::app::design::envelope::{self, EnvelopeResult};
use vibrofem::app::design::reduced::{DEFAULT_TOL, Plan, within};
use vibrofem::app::design::{Design, analyse, machine, run_design};

/// The shell table on a coarse mesh, coarse leaves, no tuning, one load case besides the
/// nominal one and three bands (stiffness of the leaves, damping, mains).
fn small_shell() -> Design {
    let mut d = super::design_envelope::coarse("shells", 0.2, &[1, 3], &[0, 3, 4]);
    d.envelope.reduced = true;
    d
}

/// The envelope of `d` with `envelope.reduced` and `envelope.reduced_tol` set.
fn envelope_with(d: &Design, reduced: bool, tol: f64) -> EnvelopeResult {
    let mut d = d.clone();
    d.envelope.reduced = reduced;
    d.envelope.reduced_tol = tol;
    let r = run_design(&d, None, &|_| {}).unwrap();
    envelope::run(&d, &r, &|_| {}).unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-300)
}

/// Reduced against full: the checks' envelopes (min, nominal, max) and every run's values agree
/// to `TOL`.
///
/// Why 1e-6: a reduced run is accepted when every mode it uses has a backward error
/// η ≤ `reduced_tol` (1e-7): the pair is exact for K and M perturbed by η relative to |K|, |M|.
/// The modes' frequencies then move by about η × ‖|K||x|‖/(λ‖Mx‖) (the table's shells make the
/// first factor up to ~1e3 times the second), and the static part of the response is exact in
/// the basis; the response near resonance amplifies a frequency error by about 1/(2ζ) (ζ ≈ 2 %:
/// × 25). That bounds the values' relative change by ~1e-7 × 1e3 × 25 ≈ 3e-3 at worst; measured
/// (the built-in design: 6.6e-10 on the checks' envelopes, with η ≤ 9.2e-9), it is far below (the basis carries K0⁻¹B and K0⁻¹MK0⁻¹B, whose error is
/// second order in λ/λ_c), and 1e-6 leaves a margin over it while any lost mode or a wrong
/// static correction (per cent changes) fails.
const TOL: f64 = 1e-6;

#[test]
fn reduced_envelope_agrees_with_the_full_one() {
    let d = small_shell();
    let full = envelope_with(&d, false, DEFAULT_TOL);
    let red = envelope_with(&d, true, DEFAULT_TOL);
    assert_eq!(full.reduced_runs, 0);
    assert!(red.reduced_runs > 0, "no run was reduced");
    assert_eq!(red.reduced_runs + red.full_runs, full.full_runs);
    assert!(red.reduced_max_backward_error <= DEFAULT_TOL);
    assert_eq!(full.runs.len(), red.runs.len());
    for (a, b) in full.checks.iter().zip(&red.checks) {
        assert_eq!(a.id, b.id);
        for (what, x, y) in [
            ("min", a.min, b.min),
            ("nominal", a.nominal, b.nominal),
            ("max", a.max, b.max),
        ] {
            assert!(rel(x, y) <= TOL, "{} {what}: full {x} reduced {y}", a.id);
        }
        assert_eq!(
            a.nominal.to_bits(),
            b.nominal.to_bits(),
            "{}: the nominal run is full",
            a.id
        );
    }
    for (a, b) in full.runs.iter().zip(&red.runs) {
        assert_eq!(a.label, b.label);
        for (id, x) in &a.values {
            let y = b.values[id];
            assert!(
                rel(*x, y) <= TOL || (x.is_nan() && y.is_nan()),
                "{} {id}: {x} vs {y}",
                a.label
            );
        }
    }
    // In JSON, the counts.
    let json = serde_json::to_value(&red).unwrap();
    assert_eq!(json["reduced_runs"].as_u64(), Some(red.reduced_runs as u64));
    assert_eq!(json["full_runs"].as_u64(), Some(red.full_runs as u64));
    assert!(json["reduced_max_backward_error"].as_f64().is_some());
}

/// One corner of the eccentric case, machine to machine: the modes' frequencies, the
/// work-surface amplitude X1, the relative motion across each leaf (the leaf stress is
/// proportional to it) and the floor force agree with the full run to `TOL`.
#[test]
fn reduced_corner_machine_matches_the_full_run() {
    let d = small_shell();
    let e = &d.envelope;
    let built = d.clone();
    let reference = e.design_at(&built, Some(1), &[0.0, 0.0, 0.0]).unwrap();
    let corner = e.design_at(&built, Some(1), &[-1.0, 1.0, -1.0]).unwrap();
    let h = corner.leaf.thickness;
    let plan = Arc::new(Plan::new(true, DEFAULT_TOL));
    machine::prepare_basis(&reference, &plan).unwrap();
    let red = within(Some(&plan), || analyse(&corner, h)).unwrap();
    let stats = plan.stats();
    assert_eq!((stats.reduced_runs, stats.full_runs), (1, 0), "{stats:?}");
    let full = analyse(&corner, h).unwrap();
    assert_eq!(full.modes.len(), red.modes.len());
    for (a, b) in full.modes.iter().zip(&red.modes) {
        assert!(
            rel(a.frequency_hz, b.frequency_hz) <= TOL,
            "{} vs {}",
            a.frequency_hz,
            b.frequency_hz
        );
        assert_eq!(a.name, b.name);
    }
    assert!(rel(full.mean, red.mean) <= TOL, "X1 {} vs {}", full.mean, red.mean);
    for (a, b) in full.leaf_relative.iter().zip(&red.leaf_relative) {
        assert!(rel(*a, *b) <= TOL, "leaf {a} vs {b}");
    }
    for (a, b) in full.floor.iter().zip(&red.floor) {
        assert!(rel(a.total, b.total) <= TOL, "floor {} vs {}", a.total, b.total);
    }
}

/// A bar no reduced run meets: every run falls back to the full model, and the envelope equals
/// the full one (1e-12: the same operations; only a parallel reduction could reorder sums).
#[test]
fn every_run_over_the_bar_falls_back_to_the_full_model() {
    let mut d = small_shell();
    d.envelope.load_cases.truncate(1);
    d.envelope.tolerances.truncate(1);
    let full = envelope_with(&d, false, DEFAULT_TOL);
    let fell = envelope_with(&d, true, 1e-300);
    assert_eq!(fell.reduced_runs, 0);
    assert_eq!(fell.reduced_fallbacks, fell.full_runs);
    assert_eq!(fell.full_runs, full.full_runs);
    for (a, b) in full.runs.iter().zip(&fell.runs) {
        for (id, x) in &a.values {
            let y = b.values[id];
            assert!(
                (x - y).abs() <= 1e-12 * x.abs() || x.to_bits() == y.to_bits(),
                "{} {id}: {x} vs {y}",
                a.label
            );
        }
    }
}

/// A rigid table (12 DOFs) needs no basis: its runs are full whatever `envelope.reduced` says
/// (and not counted: the counts are of the shell table's runs), and the envelope equals the one
/// with reduction off.
#[test]
fn rigid_table_runs_full_without_a_basis() {
    let mut d = small_shell();
    d.machine.table_model = "rigid".into();
    d.envelope.load_cases.truncate(1);
    let off = envelope_with(&d, false, DEFAULT_TOL);
    let on = envelope_with(&d, true, DEFAULT_TOL);
    assert_eq!(on.reduced_runs, 0);
    assert_eq!(on.reduced_fallbacks, 0);
    assert_eq!((on.full_runs, off.full_runs), (0, 0));
    for (a, b) in off.checks.iter().zip(&on.checks) {
        assert_eq!(a.min.to_bits(), b.min.to_bits(), "{}", a.id);
        assert_eq!(a.max.to_bits(), b.max.to_bits(), "{}", a.id);
    }
}
