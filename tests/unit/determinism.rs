//! Determinism (issue 7, scope 3): the same input gives the same frequencies, run after run and
//! with 1 or 2 worker threads, to 1e-12 relative.
//!
//! Why it can hold: element matrices are computed in parallel but scattered into K and M in
//! element order (assembly.rs), so the sums do not depend on scheduling; the ordering, the
//! symbolic analysis and the Lanczos start vectors are deterministic (fixed seed); faer's
//! parallel LDLᵀ splits its work by the elimination tree, not by timing. Each case runs the
//! CLI binary (JSON output) as a user would, with `--threads 1` and `--threads 2`.
//!
//! Rigid-body modes have λ ≈ 0 made of rounding, so "relative" is meaningless for them: they
//! are compared in absolute terms against 1e-12 of the first elastic frequency.

use std::process::Command;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Frequencies (Hz) and the number of rigid-body modes from `vibrofem --threads T modes ...`.
fn frequencies(threads: usize, args: &[&str]) -> (Vec<f64>, usize) {
    let t = threads.to_string();
    let mut all = vec!["--threads", &t, "modes"];
    all.extend_from_slice(args);
    all.push("--json");
    let o = Command::new(env!("CARGO_BIN_EXE_vibrofem"))
        .args(&all)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{all:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["complete"], true, "{all:?}");
    assert_eq!(v["accurate"], true, "{all:?}");
    let f = v["frequencies_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    (f, v["n_rigid"].as_u64().unwrap() as usize)
}

/// Largest difference between two runs: relative for elastic modes, absolute (in units of
/// the first elastic frequency) for rigid ones; also whether the runs are bit-identical.
fn difference(a: &(Vec<f64>, usize), b: &(Vec<f64>, usize)) -> (f64, bool) {
    assert_eq!(a.1, b.1, "rigid-mode counts differ");
    assert_eq!(a.0.len(), b.0.len());
    let nr = a.1;
    let scale = a.0.get(nr).copied().unwrap_or(1.0).abs();
    let mut worst = 0.0f64;
    for (i, (x, y)) in a.0.iter().zip(&b.0).enumerate() {
        let d = if i < nr {
            (x - y).abs() / scale
        } else {
            (x - y).abs() / y.abs()
        };
        worst = worst.max(d);
    }
    let identical = a.0.iter().zip(&b.0).all(|(x, y)| x.to_bits() == y.to_bits());
    (worst, identical)
}

/// Run `args` twice with 1 thread and twice with 2; every pair must agree to 1e-12.
fn check(name: &str, args: &[&str]) {
    let runs = [
        frequencies(1, args),
        frequencies(1, args),
        frequencies(2, args),
        frequencies(2, args),
    ];
    for (i, a) in runs.iter().enumerate() {
        for b in &runs[i + 1..] {
            let (d, same) = difference(a, b);
            assert!(d <= 1e-12, "{name}: runs differ by {d:.2e}: {:?} vs {:?}", a.0, b.0);
            if !same {
                eprintln!("{name}: runs agree to {d:.1e} but are not bit-identical");
            }
        }
    }
    eprintln!(
        "{name}: 4 runs (1, 1, 2, 2 threads) agree; {} modes, first elastic {:.9} Hz, bit-identical: {}",
        runs[0].0.len(),
        runs[0].0.get(runs[0].1).copied().unwrap_or(f64::NAN),
        runs.iter().all(|r| difference(&runs[0], r).1)
    );
}

#[test]
fn free_plate_hex20_is_deterministic() {
    // S1 plate, hex20 16 × 16 × 3 (12 597 DOFs, large enough for faer to split the
    // factorisation between threads): six rigid-body modes and six elastic ones.
    check("S1 hex20", &["box:0.3,0.3,0.02:16,16,3:hex20", "--modes", "12"]);
}

#[test]
fn gmsh_tet10_plate_is_deterministic() {
    // The committed S1 tet10 mesh (unstructured, 5562 DOFs): METIS ordering of an irregular
    // graph and a deeper elimination tree than the box meshes.
    check(
        "S1 tet10 h30",
        &[&format!("{ROOT}/meshes/s1_plate_tet10_h30.msh"), "--modes", "10"],
    );
}

#[test]
fn coupled_leaf_with_point_mass_is_deterministic() {
    // S4-like leaf: clamped, guided end coupled to a reference node carrying 11.34 kg, leaf
    // density 1 kg/m³. Exercises the constrained (MPC) scatter path and discrete elements.
    check(
        "S4 leaf",
        &[
            "box:0.169,0.146,0.009:12,4,2:hex20",
            "--material",
            "2.1e11,0.3,1",
            "--fix",
            "xmin",
            "--couple",
            "xmax:guided=z",
            "--point-mass",
            "xmax=11.34",
            "--modes",
            "4",
        ],
    );
}

#[test]
fn band_search_is_deterministic() {
    // A band search (two Sturm factorisations bracket the band) with lumped mass.
    check(
        "S1 hex20 band, lumped",
        &[
            "box:0.3,0.3,0.02:8,8,2:hex20",
            "--band",
            "500",
            "2500",
            "--mass",
            "lumped",
        ],
    );
}
