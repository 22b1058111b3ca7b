//! `vibrofem harmonic` and the scene's `[harmonic]`: outputs, consistency with the modal and
//! static analyses of the same model, and refusals with their reasons.

use crate::common::{root, run};

const BOX: &str = "box:0.5,0.05,0.02:20,2,2:hex20";

fn json(out: &str) -> serde_json::Value {
    serde_json::from_str(out).unwrap_or_else(|e| panic!("{e}: {out}"))
}

#[test]
fn harmonic_sweep_peaks_at_the_first_mode_and_both_methods_agree() {
    let dir = tempfile_dir("sweep");
    let (vtu, svg) = (dir.join("h.vtu"), dir.join("frf.svg"));
    let (code, out, err) = run(&[
        "harmonic",
        BOX,
        "--fix",
        "xmin",
        "--force",
        "xmax=0,0,10",
        "--sweep",
        "40",
        "100",
        "61",
        "--rayleigh",
        "1,1e-5",
        "--method",
        "both",
        "--modes",
        "30",
        "--json",
        "--vtu",
        vtu.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let r = json(&out);
    let (_, modes_out, _) = run(&["modes", BOX, "--fix", "xmin", "--modes", "1", "--json"]);
    let f1 = json(&modes_out)["frequencies_hz"][0].as_f64().unwrap();
    let points = r["points"].as_array().unwrap();
    assert_eq!(points.len(), 61);
    let peak = points
        .iter()
        .max_by(|a, b| {
            let amp = |p: &serde_json::Value| p["groups"][0]["mean"][2]["amplitude_m"].as_f64().unwrap();
            amp(a).total_cmp(&amp(b))
        })
        .unwrap();
    // Sweep step 1 Hz: the largest response sits at the grid point nearest the first bending mode.
    assert!(
        (peak["freq_hz"].as_f64().unwrap() - f1).abs() <= 0.5 + 1e-9,
        "peak at {} Hz, first mode {f1} Hz",
        peak["freq_hz"]
    );
    // 30 modes plus the static correction against the direct solve (Rayleigh damping is exact in
    // both): agreement well below the 1e-3 an engineer reads.
    for p in points {
        let d = p["modal_vs_direct"].as_f64().unwrap();
        assert!(d < 1e-5, "{} Hz: modal vs direct {d:e}", p["freq_hz"]);
    }
    assert!(
        !r["notes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n.as_str().unwrap().contains("differ by")),
        "{}",
        r["notes"]
    );
    let v = std::fs::read_to_string(&vtu).unwrap();
    for field in [
        "peak_displacement",
        "displacement_real",
        "displacement_imag",
        "phase_deg",
    ] {
        assert!(v.contains(field), "{field} missing from the VTU");
    }
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
}

#[test]
fn scene_harmonic_matches_the_static_stiffness_below_resonance() {
    let dir = tempfile_dir("scene");
    let (code, out, err) = run(&[
        "run",
        root().join("scenes/s3_leaf_harmonic.toml").to_str().unwrap(),
        "-o",
        dir.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let r = json(&out);
    let h = &r["harmonic"];
    let f0 = h["points"][0]["freq_hz"].as_f64().unwrap();
    let u0 = h["points"][0]["groups"][0]["mean"][2]["amplitude_m"].as_f64().unwrap();
    let fn_ = h["mode_frequencies_hz"][0].as_f64().unwrap();
    // The same leaf and coupling in a static run: k = F/u along the guide.
    let (code, sout, serr) = run(&[
        "static",
        root().join("meshes/s3_leaf_hex20_10x6x1.msh").to_str().unwrap(),
        "--fix",
        "clamp_fixed",
        "--couple",
        "clamp_guided:guided=z",
        "--force",
        "clamp_guided=0,0,100",
        "--json",
    ]);
    assert_eq!(code, 0, "{serr}");
    let s = json(&sout);
    let k = s["cases"][0]["references"][0]["stiffness"].as_f64().unwrap();
    // One-DOF response of the 40 kg + leaf system: (F/k)/|1 − r² + iωβ| with r = f/f_n; the
    // leaf's own modes are above 1 kHz, so the static correction adds < 1e-4 at 5 Hz, and the
    // leaf's distributed mass (1.7 kg of 41.7) shifts r² by < 1e-3 there.
    let r2 = (f0 / fn_).powi(2);
    let wb = std::f64::consts::TAU * f0 * 1.13e-4;
    let want = (100.0 / k) / ((1.0 - r2).powi(2) + wb * wb).sqrt();
    assert!(
        (u0 - want).abs() < 1e-3 * want,
        "{f0} Hz: {u0:e} m vs one-DOF {want:e} m (k = {k:e} N/m, f_n = {fn_} Hz)"
    );
    // The resonance of 40 kg on k: √(k/m)/2π within the leaf's mass effect (a few %).
    let f_spring = (k / 40.0).sqrt() / std::f64::consts::TAU;
    assert!(
        fn_ < f_spring && fn_ > 0.95 * f_spring,
        "f_n {fn_} vs √(k/m)/2π {f_spring}"
    );
    for f in ["harmonic.vtu", "frf.svg"] {
        assert!(dir.join(f).exists(), "{f} not written");
    }
}

#[test]
fn harmonic_refuses_what_it_cannot_answer() {
    let cases: &[(&[&str], &str)] = &[
        (&["--fix", "xmin", "--force", "xmax=0,0,1", "--freq", "50"], "--damping"),
        (
            &[
                "--fix",
                "xmin",
                "--force",
                "nope=0,0,1",
                "--freq",
                "50",
                "--damping",
                "0.02",
            ],
            "nope",
        ),
        (
            &[
                "--fix",
                "xmin",
                "--force",
                "xmax=0,0",
                "--freq",
                "50",
                "--damping",
                "0.02",
            ],
            "expected 3 numbers",
        ),
        (
            &[
                "--fix",
                "xmin",
                "--force",
                "xmax=0,0,1@abc",
                "--freq",
                "50",
                "--damping",
                "0.02",
            ],
            "phase",
        ),
        (
            &[
                "--fix",
                "xmin",
                "--force",
                "xmax=0,0,1",
                "--freq",
                "50",
                "--damping",
                "0.02",
                "--plot",
                "/tmp/x.svg",
            ],
            "--sweep",
        ),
        (
            &[
                "--fix",
                "xmin",
                "--force",
                "xmax=0,0,1",
                "--sweep",
                "50",
                "10",
                "5",
                "--damping",
                "0.02",
            ],
            "F0 < F1",
        ),
        (
            &[
                "--fix",
                "xmin",
                "--force",
                "xmin=0,0,1",
                "--freq",
                "50",
                "--damping",
                "0.02",
            ],
            "held",
        ),
        (
            &[
                "--fix",
                "xmin",
                "--force",
                "xmax=0,0,1",
                "--freq",
                "50",
                "--rayleigh",
                "1",
            ],
            "ALPHA,BETA",
        ),
        (
            &[
                "--fix",
                "xmin",
                "--force",
                "xmax=0,0,1",
                "--freq",
                "50",
                "--damping",
                "0.02",
                "--method",
                "fast",
            ],
            "unknown method",
        ),
    ];
    for (args, want) in cases {
        let mut all = vec!["harmonic", BOX];
        all.extend_from_slice(args);
        let (code, _, err) = run(&all);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: expected '{want}' in: {err}");
    }
}

#[test]
fn scene_harmonic_errors_name_the_file_and_line() {
    let dir = tempfile_dir("bad");
    let text = std::fs::read_to_string(root().join("scenes/s3_leaf_harmonic.toml"))
        .unwrap()
        .replace("../meshes/", &format!("{}/meshes/", root().display()));
    for (from, to, want) in [
        ("rayleigh = [0.0, 1.13e-4]", "", "needs 'damping'"),
        (
            "sweep_hz = [5.0, 120.0, 116]",
            "sweep_hz = [5.0, 120.0]",
            "'sweep_hz' must be [F0, F1, N]",
        ),
        ("\"clamp_guided=0,0,100\"", "\"missing_group=0,0,100\"", "missing_group"),
        ("method = \"both\"", "method = \"fast\"", "'method'"),
    ] {
        let path = dir.join("bad.toml");
        std::fs::write(&path, text.replace(from, to)).unwrap();
        let (code, _, err) = run(&["run", path.to_str().unwrap(), "-o", dir.join("o").to_str().unwrap()]);
        assert_eq!(code, 1, "{from} → {to}: {err}");
        assert!(err.contains(want) && err.contains("bad.toml"), "{from} → {to}: {err}");
    }
}

fn tempfile_dir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("vibrofem-harmonic-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 1 m steel cantilever (hex20) loaded at its tip, at 100 Hz.
const CANTILEVER_AT_100: [&str; 8] = [
    "harmonic",
    "box:1,0.1,0.1:10,2,2:hex20",
    "--fix",
    "xmin",
    "--force",
    "xmax=0,0,1",
    "--freq",
    "100",
];

/// Two modes of a 1 m cantilever under mass-proportional damping of α = 1e5 1/s (every mode far
/// overdamped) at 100 Hz: the superposition misses most of the response (350 % from the direct
/// solve, which is exact for the model). The modal response is the one tabulated, so a note must
/// say so and which to take.
#[test]
fn both_methods_far_apart_get_a_note() {
    let (code, out, err) = run(&[
        &CANTILEVER_AT_100[..],
        &["--rayleigh", "1e5,0", "--method", "both", "--json"],
    ]
    .concat());
    assert_eq!(code, 0, "{err}");
    let r = json(&out);
    let d = r["points"][0]["modal_vs_direct"].as_f64().unwrap();
    assert!(d > 0.5, "{d}");
    let notes: Vec<&str> = r["notes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    assert!(
        notes
            .iter()
            .any(|n| n.contains("differ by up to") && n.contains("--method direct")),
        "{notes:?}"
    );
    assert!(
        !notes.iter().any(|n| n.contains("check with --method both")),
        "{notes:?}"
    );
}

/// A damping ratio of 2 (a percentage typed as the ratio) damps every mode past critical: the
/// run says so; 0.02 says nothing of it.
#[test]
fn a_damping_ratio_of_one_or_more_gets_a_note() {
    let notes = |zeta: &str| -> String {
        let (code, out, err) = run(&[&CANTILEVER_AT_100[..], &["--damping", zeta, "--json"]].concat());
        assert_eq!(code, 0, "{err}");
        json(&out)["notes"].to_string()
    };
    assert!(notes("2").contains("critically damped or more"), "{}", notes("2"));
    assert!(!notes("0.02").contains("critically damped"), "{}", notes("0.02"));
}
