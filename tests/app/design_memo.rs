//! The memo of the 3D machine's base (issue 29 item 2, cost): the machine without its leaves and
//! magnets is built once per geometry and load case, and a run that reuses it equals a run that
//! builds it afresh.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use vibrofem::app::design::machine::base_memo_key;
use vibrofem::app::design::{Design, analyse, cache};

/// The rigid table on a coarse mesh (a run is a fraction of a second).
fn small() -> Design {
    let mut d = Design::paper();
    d.machine.table_model = "rigid".into();
    d.table.elem_size = 0.05;
    d.leaf.divisions = [12, 4, 1];
    d
}

#[test]
fn machine_memo_keys_on_geometry_and_load_only() {
    for d in [Design::paper(), small()] {
        let k = base_memo_key(&d);
        // What each run applies to the base: the leaves, the magnets' pull, damping, drive.
        let mut same: Vec<(&str, Design)> = vec![];
        let mut v = d.clone();
        v.leaf.thickness *= 1.01;
        same.push(("leaf.thickness", v));
        let mut v = d.clone();
        v.leaf.clamping = 0.72;
        same.push(("leaf.clamping", v));
        let mut v = d.clone();
        v.leaf.material[0] *= 0.985;
        same.push(("leaf E", v));
        let mut v = d.clone();
        v.damping.mu12 *= 1.3;
        v.damping.mu13 *= 0.7;
        same.push(("damping", v));
        let mut v = d.clone();
        v.drive.mains_hz = Some(50.2);
        same.push(("drive.mains_hz", v));
        let mut v = d.clone();
        v.excitation_hz *= 1.004;
        same.push(("excitation_hz", v));
        for (what, v) in &same {
            assert_eq!(base_memo_key(v), k, "{what} must not change the machine's base");
        }
        // The geometry and the load case do.
        let mut other: Vec<(&str, Design)> = vec![];
        let mut v = d.clone();
        v.masses.load = 0.0;
        other.push(("masses.load", v));
        let mut v = d.clone();
        v.masses.load_share = 0.3;
        other.push(("masses.load_share", v));
        let mut v = d.clone();
        v.masses.load_share = 0.3;
        v.masses.load_offset = [0.3, 0.15];
        other.push(("masses.load_offset", v));
        let mut v = d.clone();
        v.table.elem_size *= 0.8;
        other.push(("table.elem_size", v));
        let mut v = d.clone();
        v.leaf.length *= 1.1;
        other.push(("leaf.length", v));
        for (what, v) in &other {
            assert_ne!(base_memo_key(v), k, "{what} must change the machine's base");
        }
    }
    assert_ne!(
        base_memo_key(&Design::paper()),
        base_memo_key(&{
            let mut d = Design::paper();
            d.machine.table_model = "rigid".into();
            d
        })
    );
}

#[test]
fn memo_returns_the_stored_value_without_computing() {
    let key = format!("test_memo_same_value:{}", std::process::id());
    let computed = AtomicUsize::new(0);
    let make = || {
        computed.fetch_add(1, Ordering::SeqCst);
        Ok(vec![1.0f64, 2.0, 3.0])
    };
    let a: Arc<Vec<f64>> = cache::get_or_large(key.clone(), make).unwrap();
    // Another test may empty the memo in between (cache::clear); then the value is computed
    // again, which is the only other outcome allowed. A few tries see the hit.
    let mut hit = false;
    for _ in 0..5 {
        let before = computed.load(Ordering::SeqCst);
        let b: Arc<Vec<f64>> = cache::get_or_large(key.clone(), make).unwrap();
        assert_eq!(*a, *b);
        if computed.load(Ordering::SeqCst) == before {
            assert!(Arc::ptr_eq(&a, &b), "a hit returns the stored value itself");
            hit = true;
            break;
        }
    }
    assert!(hit, "the memo never returned the stored value");
}

#[test]
fn memoised_machine_equals_a_fresh_build() {
    let d = small();
    let h = 0.0101;
    let warm = analyse(&d, h).unwrap();
    // A second design on the same base (other clamping and damping): the base is reused.
    let mut e = d.clone();
    e.leaf.clamping = 0.72;
    e.damping.mu12 *= 1.3;
    assert_eq!(base_memo_key(&d), base_memo_key(&e));
    let reused = analyse(&e, h).unwrap();
    cache::clear();
    let fresh = analyse(&e, h).unwrap();
    let again = analyse(&d, h).unwrap();
    // 1e-12: the same operations in the same order (the base's K copied, the leaves added).
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()) || a == b;
    for (x, y) in [(&reused, &fresh), (&warm, &again)] {
        assert_eq!(x.modes.len(), y.modes.len());
        for (m, n) in x.modes.iter().zip(&y.modes) {
            assert!(
                close(m.frequency_hz, n.frequency_hz),
                "{} {}",
                m.frequency_hz,
                n.frequency_hz
            );
        }
        for (a, b) in [
            (x.mean, y.mean),
            (x.reactive_amplitude, y.reactive_amplitude),
            (x.floor[0].total, y.floor[0].total),
            (x.dissipated_power, y.dissipated_power),
        ] {
            assert!(close(a, b), "{a} vs {b}");
        }
        for (a, b) in x.leaf_relative.iter().zip(&y.leaf_relative) {
            assert!(close(*a, *b), "{a} vs {b}");
        }
    }
    // The other clamping does change the machine (the memo did not return the first run).
    assert!((reused.mean - warm.mean).abs() > 1e-6 * warm.mean);
}
