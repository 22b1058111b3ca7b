//! Importing the results of a SLEPc job (`vibrofem modes --slepc-import DIR`) without SLEPc: the
//! job folder is written by `vibrofem export`, then completed here with the eigenpairs of the
//! native solver in the script's file formats (`lambda.bin`, `vectors.bin`, `slepc.json`), or
//! with damaged ones. The import must accept exactly what it can verify: the model and the
//! request the job was exported for, regular files of the sizes the header gives, finite
//! values, as many pairs as asked (more are fine), and a verdict that a NaN cannot pass.

use crate::common::{bin, run_cmd as run};
use std::path::{Path, PathBuf};
use vibrofem::analysis::modal::{self, ModalParams, ModalTarget};
use vibrofem::input::source;
use vibrofem::model::{Model, ModelSpec};
use vibrofem::system::{System, SystemOptions};

const PLATE: &str = "box:0.3,0.1,0.02:6,2,1:tet10";

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vibrofem-slepc-import-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The plate clamped at x = 0 (the model of `--fix xmin`).
fn clamped_plate() -> System {
    let mesh = source::load(PLATE, 1.0).unwrap();
    let spec = ModelSpec {
        fixes: vec![("xmin".into(), vibrofem::dof::TRANSLATIONS)],
        ..Default::default()
    };
    System::build(
        Model::build(&mesh, &spec, PLATE).unwrap(),
        &SystemOptions::default(),
        PLATE,
    )
    .unwrap()
}

/// What the script writes: eigenvalues, vectors (column after column) and the Sturm counts.
struct Pairs {
    n: usize,
    lambda: Vec<f64>,
    vectors: Vec<f64>,
    lower: (f64, usize),
    upper: (f64, usize),
}

/// The `k` lowest pairs of `sys` from the native solver, with the Sturm counts the script
/// would give: none below a point under the lowest, `k` below the middle of the gap above.
fn pairs_of(sys: &System, k: usize) -> Pairs {
    let run = modal::solve(
        sys,
        &ModalParams {
            target: ModalTarget::Modes(k + 2),
            ..Default::default()
        },
    )
    .unwrap();
    let n = sys.n_free();
    let mut vectors = Vec::with_capacity(n * k);
    for j in 0..k {
        vectors.extend((0..n).map(|i| run.vectors[(i, j)]));
    }
    let l = &run.lambda;
    Pairs {
        n,
        lambda: l[..k].to_vec(),
        vectors,
        lower: (-1e3, 0),
        upper: (0.5 * (l[k - 1] + l[k]), k),
    }
}

/// The `k` lowest pairs of the clamped plate.
fn native_pairs(k: usize) -> Pairs {
    pairs_of(&clamped_plate(), k)
}

/// `vibrofem export` of the clamped plate (plus `extra` model options) with `job` (e.g.
/// `--modes 8`) into `dir`.
fn export(dir: &Path, extra: &[&str], job: &[&str]) {
    let (code, _, err) = run(bin()
        .args(["export", PLATE, "--fix", "xmin", "--format", "petsc", "-o"])
        .arg(dir)
        .args(extra)
        .args(job));
    assert_eq!(code, 0, "{err}");
}

/// Complete the job in `dir` as `slepc_modes.py` would, with `p`.
fn write_results(dir: &Path, p: &Pairs) {
    let params: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("params.json")).unwrap()).unwrap();
    let le = |v: &[f64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    std::fs::write(dir.join("lambda.bin"), le(&p.lambda)).unwrap();
    std::fs::write(dir.join("vectors.bin"), le(&p.vectors)).unwrap();
    let info = serde_json::json!({
        "n": p.n,
        "nconv": p.lambda.len(),
        "converged": p.lambda.len(),
        "iterations": 3,
        "ranks": 1,
        "sigma": params["sigma"],
        "lower": [p.lower.0, p.lower.1],
        "upper": [p.upper.0, p.upper.1],
        "zero_pivots": [0, 0],
        "timings_s": {"load": 0.01, "solve": 0.1, "refinements": 1, "refine": 0.01, "gather": 0.0, "sturm": 0.02},
        "slepc": "3.18.2",
        "petsc": "3.18.5",
    });
    std::fs::write(dir.join("slepc.json"), info.to_string()).unwrap();
}

/// `vibrofem modes PLATE --fix xmin ARGS --slepc-import DIR --json` with a time limit (a hang
/// is a failure, not a stuck test) and a memory limit (a file read without end must not take
/// the machine's memory).
fn import(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let mut cmd = std::process::Command::new("sh");
    cmd.arg("-c")
        .arg("ulimit -v 4000000; exec \"$@\"")
        .arg("sh")
        .arg(env!("CARGO_BIN_EXE_vibrofem"))
        .args(["modes", PLATE, "--fix", "xmin", "--json"])
        .args(args)
        .arg("--slepc-import")
        .arg(dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
    let mut child = cmd.spawn().unwrap();
    let t = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t.elapsed().as_secs() > 60 {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the import of {} did not end within 60 s", dir.display());
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let o = child.wait_with_output().unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

fn report(out: &str) -> serde_json::Value {
    serde_json::from_str(out).unwrap_or_else(|e| panic!("{e}: {out}"))
}

#[test]
fn a_complete_job_is_imported_and_verified() {
    let dir = tmp("good");
    export(&dir, &[], &["--modes", "8"]);
    let p = native_pairs(8);
    write_results(&dir, &p);
    let (code, out, err) = import(&dir, &["--modes", "8"]);
    assert_eq!(code, 0, "{err}");
    let r = report(&out);
    assert_eq!(r["complete"], true);
    assert_eq!(r["accurate"], true);
    assert_eq!(r["modes"].as_array().unwrap().len(), 8);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_nan_in_the_vectors_is_refused() {
    let dir = tmp("nan");
    export(&dir, &[], &["--modes", "8"]);
    let mut p = native_pairs(8);
    // One entry of the third pair.
    p.vectors[2 * p.n + 17] = f64::NAN;
    write_results(&dir, &p);
    let (code, _, err) = import(&dir, &["--modes", "8"]);
    assert_ne!(code, 0, "a NaN in vectors.bin was accepted: {err}");
    assert!(err.contains("vectors.bin") && err.contains("pair 3"), "{err}");
    // And in the eigenvalues.
    let mut p = native_pairs(8);
    p.lambda[4] = f64::NAN;
    write_results(&dir, &p);
    let (code, _, err) = import(&dir, &["--modes", "8"]);
    assert_ne!(code, 0, "a NaN in lambda.bin was accepted: {err}");
    assert!(err.contains("lambda.bin") && err.contains("pair 5"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A NaN backward error (a pair of NaN) cannot pass the accuracy verdict: the maxima that
/// decide it propagate NaN instead of dropping it.
#[test]
fn a_nan_backward_error_fails_the_verdict() {
    use vibrofem::linalg::eigen::{self, EigenParams, Target};
    let sys = clamped_plate();
    let params = EigenParams {
        target: Target::Nearest(6),
        ..Default::default()
    };
    let solve = || eigen::solve(sys.k(), sys.m().unwrap(), sys.symbolic().unwrap(), &params).unwrap();
    let t = std::time::Instant::now();
    let good = modal::finish(&sys, solve(), Default::default(), t, params.verify_tol).unwrap();
    assert!(good.report.accurate);
    let mut sol = solve();
    sol.backward_error[2] = f64::NAN;
    sol.rel_residual[2] = f64::NAN;
    let bad = modal::finish(&sys, sol, Default::default(), t, params.verify_tol).unwrap();
    assert!(!bad.report.accurate, "a NaN backward error passed");
    let mut sol = solve();
    sol.m_orthonormality = f64::NAN;
    let bad = modal::finish(&sys, sol, Default::default(), t, params.verify_tol).unwrap();
    assert!(!bad.report.accurate, "a NaN M-orthonormality passed");
    // The M-orthonormality of vectors holding a NaN is NaN, not the largest of the others.
    let mut x = solve().vectors;
    x[(5, 1)] = f64::NAN;
    let lambda = solve().lambda;
    let (_, orth, _) = eigen::verify_with_backward_errors(sys.k(), sys.m().unwrap(), &lambda, x.as_ref(), 0.0);
    assert!(orth.is_nan(), "M-orthonormality {orth} of vectors with a NaN");
}

#[test]
fn a_job_with_fewer_pairs_than_asked_is_not_complete() {
    let dir = tmp("fewer");
    export(&dir, &[], &["--modes", "8"]);
    // Five pairs of the eight asked, with honest Sturm counts around the five.
    write_results(&dir, &native_pairs(5));
    let (code, out, err) = import(&dir, &["--modes", "8"]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(report(&out)["complete"], false, "{out}");
    assert!(err.contains("8 asked") && err.contains("5"), "{err}");
    // None at all.
    let none = Pairs {
        n: native_pairs(1).n,
        lambda: vec![],
        vectors: vec![],
        lower: (-1e3, 0),
        upper: (-1e3, 0),
    };
    write_results(&dir, &none);
    let (code, _, err) = import(&dir, &["--modes", "8"]);
    assert_eq!(code, 2, "a job without pairs: {err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn band_and_shift_of_the_import_must_be_the_jobs() {
    let dir = tmp("request");
    export(&dir, &[], &["--modes", "8"]);
    write_results(&dir, &native_pairs(8));
    // A band request on a job of the 8 lowest modes: not what was computed.
    let (code, _, err) = import(&dir, &["--band", "0", "500"]);
    assert_eq!(code, 1, "--band ignored: {err}");
    assert!(err.contains("--band"), "{err}");
    // A shift the job was not computed about.
    let (code, _, err) = import(&dir, &["--modes", "8", "--shift", "300"]);
    assert_eq!(code, 1, "--shift ignored: {err}");
    assert!(err.contains("--shift"), "{err}");
    // More modes than the job holds.
    let (code, _, err) = import(&dir, &["--modes", "10"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--modes") && err.contains("8"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_band_job_is_imported_for_its_band_or_a_band_inside() {
    let dir = tmp("band");
    let p = native_pairs(8);
    let f = |l: f64| l.sqrt() / (2.0 * std::f64::consts::PI);
    // A band from 0 to between the 6th and 7th modes.
    let hi = 0.5 * (f(p.lambda[5]) + f(p.lambda[6]));
    let his = format!("{hi}");
    export(&dir, &[], &["--band", "0", &his]);
    let params: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("params.json")).unwrap()).unwrap();
    let band = params["band"].as_array().unwrap();
    let (l, h) = (band[0].as_f64().unwrap(), band[1].as_f64().unwrap());
    // The script's counts: none below the lower end, six below the upper.
    let six = Pairs {
        n: p.n,
        lambda: p.lambda[..6].to_vec(),
        vectors: p.vectors[..6 * p.n].to_vec(),
        lower: (l, 0),
        upper: (h, 6),
    };
    write_results(&dir, &six);
    let (code, out, err) = import(&dir, &["--band", "0", &his]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(report(&out)["modes"].as_array().unwrap().len(), 6);
    // A band inside the job's: the modes in it, complete (the job's band was).
    let mid = format!("{}", 0.5 * (f(p.lambda[2]) + f(p.lambda[3])));
    let (code, out, err) = import(&dir, &["--band", &mid, &his]);
    assert_eq!(code, 0, "{err}");
    let r = report(&out);
    assert_eq!(r["modes"].as_array().unwrap().len(), 3, "{out}");
    assert_eq!(r["complete"], true);
    // A band reaching past the job's is refused, naming --band.
    let past = format!("{}", 2.0 * hi);
    let (code, _, err) = import(&dir, &["--band", "0", &past]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--band"), "{err}");
    // --modes on a band job: the job's request must be repeated.
    let (code, _, err) = import(&dir, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--band"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn export_refuses_a_band_or_shift_without_a_representable_eigenvalue() {
    let dir = tmp("band1e200");
    for (args, opt) in [
        (&["--band", "0", "1e200"][..], "--band"),
        (&["--band", "-1e200", "10"][..], "--band"),
        (&["--band", "10", "inf"][..], "--band"),
        (&["--shift", "1e200"][..], "--shift"),
    ] {
        let (code, _, err) = run(bin()
            .args(["export", PLATE, "--format", "petsc", "-o"])
            .arg(&dir)
            .args(args));
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains(opt), "{args:?}: {err}");
        let params = std::fs::read_to_string(dir.join("params.json")).unwrap_or_default();
        assert!(!params.contains("null"), "{args:?}: {params}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn only_regular_files_of_the_announced_size_are_read() {
    let dir = tmp("fifo");
    export(&dir, &[], &["--modes", "8"]);
    write_results(&dir, &native_pairs(8));
    // A FIFO nobody writes to: opening it for reading would block for ever.
    std::fs::remove_file(dir.join("lambda.bin")).unwrap();
    let ok = std::process::Command::new("mkfifo")
        .arg(dir.join("lambda.bin"))
        .status()
        .unwrap();
    assert!(ok.success());
    let (code, _, err) = import(&dir, &["--modes", "8"]);
    assert_ne!(code, 0, "{err}");
    assert!(
        err.contains("lambda.bin") && err.contains("not a regular file"),
        "{err}"
    );
    // A link to a device without end.
    std::fs::remove_file(dir.join("lambda.bin")).unwrap();
    write_results(&dir, &native_pairs(8));
    std::fs::remove_file(dir.join("vectors.bin")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.join("vectors.bin")).unwrap();
    let (code, _, err) = import(&dir, &["--modes", "8"]);
    assert_ne!(code, 0, "{err}");
    assert!(
        err.contains("vectors.bin") && err.contains("not a regular file"),
        "{err}"
    );
    // A file larger than the header says: refused by its size, before reading.
    std::fs::remove_file(dir.join("vectors.bin")).unwrap();
    write_results(&dir, &native_pairs(8));
    let big = std::fs::OpenOptions::new()
        .append(true)
        .open(dir.join("vectors.bin"))
        .unwrap();
    big.set_len(1 << 40).unwrap();
    let (code, _, err) = import(&dir, &["--modes", "8"]);
    assert_ne!(code, 0, "{err}");
    assert!(err.contains("vectors.bin") && err.contains("bytes"), "{err}");
    // A header announcing more pairs than any file could hold.
    write_results(&dir, &native_pairs(8));
    let info = std::fs::read_to_string(dir.join("slepc.json")).unwrap();
    let info = info.replacen("\"nconv\":8", "\"nconv\":4611686018427387904", 1);
    std::fs::write(dir.join("slepc.json"), info).unwrap();
    let (code, _, err) = import(&dir, &["--modes", "8"]);
    assert_ne!(code, 0, "{err}");
    assert!(err.contains("lambda.bin"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn more_pairs_than_asked_are_imported() {
    let dir = tmp("more");
    // The README's cluster recipe: a job of many modes, imported with the default 12 (here 12
    // computed, 8 asked).
    export(&dir, &[], &["--modes", "12"]);
    let p = native_pairs(12);
    write_results(&dir, &p);
    let (code, out, err) = import(&dir, &["--modes", "8"]);
    assert_eq!(code, 0, "{err}");
    let r = report(&out);
    assert_eq!(r["complete"], true, "{out}");
    assert_eq!(r["accurate"], true, "{out}");
    let f = r["frequencies_hz"].as_array().unwrap();
    assert_eq!(f.len(), 8);
    for (i, fi) in f.iter().enumerate() {
        let want = p.lambda[i].sqrt() / (2.0 * std::f64::consts::PI);
        assert!((fi.as_f64().unwrap() - want).abs() <= 1e-9 * want, "mode {}", i + 1);
    }
    // The default request (12) on this job of 12.
    let (code, _, err) = import(&dir, &[]);
    assert_eq!(code, 0, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn results_of_another_mass_are_results_of_another_model() {
    let dir = tmp("mass");
    export(&dir, &["--couple", "xmax"], &["--modes", "8"]);
    // The pairs of the coupled plate.
    let mesh = source::load(PLATE, 1.0).unwrap();
    let spec = vibrofem::input::options::ModelOptions {
        fix: vec!["xmin".into()],
        couple: vec!["xmax".into()],
        ..Default::default()
    }
    .spec()
    .unwrap();
    let sys = System::build(
        Model::build(&mesh, &spec, PLATE).unwrap(),
        &SystemOptions::default(),
        PLATE,
    )
    .unwrap();
    write_results(&dir, &pairs_of(&sys, 8));
    let (code, _, err) = import(&dir, &["--couple", "xmax", "--modes", "8"]);
    assert_eq!(code, 0, "the exported model itself: {err}");
    // Same K, another M: density, lumped mass, a point mass.
    for extra in [
        &["--couple", "xmax", "--material", "2.1e11,0.3,7000"][..],
        &["--couple", "xmax", "--mass", "lumped"][..],
        &["--couple", "xmax", "--point-mass", "xmax=5"][..],
    ] {
        let mut args = extra.to_vec();
        args.extend(["--modes", "8"]);
        let (code, _, err) = import(&dir, &args);
        assert_eq!(code, 1, "{extra:?}: {err}");
        assert!(
            err.contains("computed for another model") && err.contains("M"),
            "{extra:?}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
