//! The design's fatigue checks (issue 30, item 5): the built-in design's `design --json` carries
//! `leaf_fatigue`, `coil_fatigue`, `coil_binding` and `coil_surge` beside the paper's reference
//! `leaf_stress`; one coil number by hand; the `[leaf.fatigue]` / `[coil.fatigue]` keys' errors.

use vibrofem::app::design::fatigue::{coil_lengths, coil_surge_values};
use vibrofem::app::design::{Design, run_design};

#[test]
fn builtin_design_reports_fatigue_checks() {
    let d = Design::paper();
    let r = run_design(&d, None, &|_| {}).unwrap();
    let json: serde_json::Value = serde_json::to_value(&r).unwrap();
    for c in &r.checks {
        eprintln!(
            "{:<24} {:>10.4} {:>10.4} {}",
            c.id,
            c.value,
            c.limit,
            if c.ok { "ok" } else { "FAIL" }
        );
    }
    for id in [
        "leaf_fatigue",
        "coil_fatigue",
        "coil_binding",
        "coil_surge",
        "leaf_stress",
    ] {
        let c = &json["checks"][id];
        assert!(c["value"].as_f64().is_some_and(f64::is_finite), "{id}: {c}");
        assert!(c["ok"].is_boolean(), "{id}: {c}");
    }
    assert!(
        json["checks"]["leaf_stress"]["name"]
            .as_str()
            .unwrap()
            .contains("paper's reference")
    );
    // The coil's surge frequency by hand: f = d/(2π N D²)·√(G/(2ρ)) with d = 6 mm, D = 32 mm,
    // N = 6, G = 77 GPa, ρ = 7850 kg/m³: 0.006/(2π·6·0.032²)·√(7.7e10/15700) = 344.2 Hz; of the
    // harmonics of 100 Hz, 300 Hz is 14.7 % away and 400 Hz 13.9 % (relative to the harmonic).
    let (fs, k, cl) = coil_surge_values(&d);
    let hand = 0.006 / (2.0 * std::f64::consts::PI * 6.0 * 0.032f64.powi(2)) * (7.7e10f64 / 15700.0).sqrt();
    assert!((fs - hand).abs() < 1e-9 * hand && (fs - 344.2).abs() < 0.1, "{fs}");
    assert_eq!(k, 4);
    assert!((cl - (400.0 - hand) / 400.0).abs() < 1e-12);
    assert!((json["checks"]["coil_surge"]["value"].as_f64().unwrap() - cl * 100.0).abs() < 1e-9);
    // Squared and ground ends (Shigley Table 10-1): L0 = p N + 2d = 72 mm, Ls = d (N + 2) = 48 mm.
    let (l0, ls, _) = coil_lengths(&d);
    assert!((l0 - 0.072).abs() < 1e-12 && (ls - 0.048).abs() < 1e-12);
}

#[test]
fn fatigue_keys_are_validated_by_name() {
    let mut d = Design::paper();
    d.leaf.fatigue.material = "unobtainium".into();
    let e = d.validate().unwrap_err().to_string();
    assert!(e.contains("leaf.fatigue.material"), "{e}");
    let mut d = Design::paper();
    d.coil.fatigue.ends = "hooked".into();
    let e = d.validate().unwrap_err().to_string();
    assert!(e.contains("coil.fatigue.ends"), "{e}");
    let mut d = Design::paper();
    d.leaf.fatigue.reliability = 0.98;
    let e = d.validate().unwrap_err().to_string();
    assert!(e.contains("leaf.fatigue.reliability"), "{e}");
    let mut d = Design::paper();
    d.leaf.fatigue.safety = -1.0;
    let e = d.validate().unwrap_err().to_string();
    assert!(e.contains("leaf.fatigue.safety"), "{e}");
}
