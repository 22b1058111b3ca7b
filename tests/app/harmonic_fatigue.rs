//! `vibrofem harmonic --fatigue`: the JSON keys, the mean and alternating states (a cantilever
//! far below its first mode: the response is the static one, so σ_m/σ_a is the ratio of the
//! loads), the clamp note and `--clamp-distance`, the VTU field and the Haigh diagram, refusals.

use crate::common::run;

const BOX: &str = "box:0.5,0.05,0.02:20,2,2:hex20";

fn dir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("vibrofem-hfat-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn harmonic_fatigue_reports_hot_spots_under_stable_keys() {
    let d = dir("keys");
    let (vtu, svg) = (d.join("f.vtu"), d.join("haigh.svg"));
    let base = [
        "harmonic",
        BOX,
        "--fix",
        "xmin",
        "--force",
        "xmax=0,0,10",
        "--freq",
        "1",
        "--damping",
        "0.02",
        "--fatigue",
        "60Si2Mn",
        "--mean-force",
        "xmax=0,0,20",
        "--mean-stress",
        "goodman",
        "--json",
    ];
    let mut args: Vec<&str> = base.to_vec();
    args.extend(["--vtu", vtu.to_str().unwrap(), "--haigh", svg.to_str().unwrap()]);
    let (code, out, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    let r: serde_json::Value = serde_json::from_str(&out).unwrap();
    let f = &r["fatigue"];
    for k in [
        "material",
        "criterion",
        "mean_stress",
        "cycles",
        "frequency_hz",
        "endurance",
        "strength",
        "m_sigma",
        "min_safety",
        "hot_spots",
        "clamp_distance",
        "excluded_nodes",
    ] {
        assert!(!f[k].is_null(), "fatigue.{k} missing: {f}");
    }
    let h = &f["hot_spots"][0];
    let (sa, sm) = (h["sigma_a"].as_f64().unwrap(), h["sigma_m"].as_f64().unwrap());
    // 1 Hz against a first mode near 65 Hz: the dynamic factor is 1 + 2.4e-4; σ_m/σ_a = 20/10.
    assert!((sm / sa - 2.0).abs() < 2e-3, "{sm} / {sa}");
    // Goodman at the hot spot from its own numbers.
    let (se, rm) = (f["strength"].as_f64().unwrap(), 1570e6);
    let n = 1.0 / (sa / se + sm / rm);
    assert!((h["safety"].as_f64().unwrap() - n).abs() < 1e-9 * n);
    assert_eq!(f["min_safety"].as_f64().unwrap(), h["safety"].as_f64().unwrap());
    // The hot spot is on the clamp: a note says so.
    assert!(err.contains("--clamp-distance"), "{err}");
    assert!(std::fs::read_to_string(&vtu).unwrap().contains("fatigue_safety"));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("Goodman"));
    // Read at a distance: no node within 50 mm of the clamp.
    let mut args: Vec<&str> = base.to_vec();
    args.extend(["--clamp-distance", "0.05"]);
    let (code, out, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    let r: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(r["fatigue"]["excluded_nodes"].as_u64().unwrap() > 0);
    assert!(r["fatigue"]["hot_spots"][0]["coords"][0].as_f64().unwrap() >= 0.05 - 1e-12);
    assert!(!err.contains("lies on a fixed group"), "{err}");
}

#[test]
fn harmonic_fatigue_refuses_bad_options_by_name() {
    let base = [
        "harmonic",
        BOX,
        "--fix",
        "xmin",
        "--force",
        "xmax=0,0,10",
        "--freq",
        "1",
        "--damping",
        "0.02",
    ];
    for (extra, want) in [
        (&["--fatigue", "unobtainium"][..], "--fatigue"),
        (&["--mean-force", "xmax=0,0,1"][..], "--mean-force"),
        (&["--fatigue", "65Mn", "--reliability", "0.98"][..], "--reliability"),
        (
            &["--fatigue", "65Mn", "--mean-stress", "soderberg"][..],
            "--mean-stress",
        ),
        (&["--fatigue", "65Mn", "--cycles", "0"][..], "--cycles"),
    ] {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        let (code, _, err) = run(&args);
        assert_ne!(code, 0, "{extra:?}");
        assert!(err.contains(want), "{extra:?}: {err}");
    }
}
