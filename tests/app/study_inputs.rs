//! Study inputs (sweeps, convergence scenes): sizes counted before any design is built, files
//! with a byte-order mark, and errors that name their place as data.

use std::path::PathBuf;
use vibrofem::At;
use vibrofem::app::studies::converge;
use vibrofem::app::studies::sweep::{self, Study, SweepOptions};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vibrofem-test-study-inputs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn study_file(name: &str, text: &str) -> PathBuf {
    let p = tmp(name).join("study.toml");
    std::fs::write(&p, text).unwrap();
    p
}

const BASE: &str = "[study]\nversion = 1\nname = \"t\"\n[table]\nelem_size = 0.1\n";

/// Issue 28, item 8 (the sweep's part): the combinations are counted before they are built, and
/// the count cannot wrap. Five keys of 8192 valid values each are 2^65 designs: the product of
/// the lengths wrapped to 0 in a usize and the sweep "succeeded" with no design at all.
#[test]
fn sweep_counts_its_designs_before_building_them() {
    let mut s = Study::load(&study_file("count", BASE)).unwrap();
    let n = 8192;
    let values = |a: f64, step: f64| (0..n).map(|i| a + step * i as f64).collect::<Vec<f64>>();
    s.set("table.top_thickness", values(0.02, 1e-7));
    s.set("table.bottom_thickness", values(0.008, 1e-7));
    s.set("table.long_web_thickness", values(0.004, 1e-7));
    s.set("table.web_height", values(0.1, 1e-6));
    s.set("table.length", values(1.2, 1e-5));
    let t = std::time::Instant::now();
    let e = s.designs().err().expect("2^65 designs must be refused");
    let msg = e.to_string();
    assert!(
        msg.contains("8192 × 8192 × 8192 × 8192 × 8192 combinations") && msg.contains("at most 100 000"),
        "{msg}"
    );
    assert_eq!(e.at(), Some(At::Param { name: "sweep".into() }));
    let e = sweep::run_sweep(
        &s,
        &SweepOptions {
            out: None,
            jobs: 1,
            progress: false,
            yes: true,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("combinations"), "{e}");
    // 300 × 300 designs: refused by the 1000-design limit with the count, before the 90 000 are
    // built (each built design is validated: that alone would take a while).
    let mut s = Study::load(&study_file("large", BASE)).unwrap();
    s.set("table.top_thickness", values(0.02, 1e-6)[..300].to_vec());
    s.set("table.bottom_thickness", values(0.008, 1e-6)[..300].to_vec());
    let e = sweep::run_sweep(
        &s,
        &SweepOptions {
            out: None,
            jobs: 1,
            progress: false,
            yes: false,
        },
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("the study has 90000 designs (more than 1000)"),
        "{e}"
    );
    assert_eq!(e.at(), Some(At::Option { name: "--yes".into() }));
    assert!(t.elapsed().as_secs_f64() < 30.0, "{:?}", t.elapsed());
    // A key that lists no value is refused (it made a sweep of no design).
    let mut s = Study::load(&study_file("empty", BASE)).unwrap();
    s.set("table.top_thickness", vec![]);
    let e = s.designs().unwrap_err().to_string();
    assert!(e.contains("0 combinations") && e.contains("table.top_thickness"), "{e}");
}

/// A study file saved with a UTF-8 byte-order mark (Windows editors) is a study file: the mark
/// hid its `[study]` line, and the file was read as a scene ("missing [scene] table").
#[test]
fn study_file_with_a_byte_order_mark_is_read() {
    let p = study_file(
        "bom",
        &format!("\u{feff}{BASE}[sweep]\n\"table.top_thickness\" = [0.02, 0.025]\n"),
    );
    let s = Study::load(&p).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.name, "t");
    assert_eq!(s.sweep.len(), 1);
    assert_eq!(s.count().unwrap(), 2);
}

/// Study errors name their place as data: the option, the key (file, line), the parameter.
#[test]
fn study_errors_name_their_place() {
    let e = sweep::parse_set("table.top_thickness").unwrap_err();
    assert_eq!(e.at(), Some(At::Option { name: "--set".into() }));
    let e = sweep::parse_set("table.nonsense=1").unwrap_err();
    assert!(e.to_string().contains("unknown sweep key"), "{e}");
    assert_eq!(
        e.at(),
        Some(At::Param {
            name: "table.nonsense".into()
        })
    );
    // A [sweep] key that is not a table key: the file and the line of the key.
    let p = study_file("badkey", &format!("{BASE}[sweep]\n\"table.nonsense\" = [1.0]\n"));
    let e = Study::load(&p).unwrap_err();
    assert!(
        e.to_string().contains("line 7: unknown sweep key 'table.nonsense'"),
        "{e}"
    );
    // A scene on a mesh file cannot be refined: the [mesh] key of the file.
    let d = tmp("refine");
    let scene = d.join("scene.toml");
    std::fs::write(
        &scene,
        "[scene]\nversion = 1\n[mesh]\nfile = \"m.msh\"\n[[part]]\ngroup = \"v\"\nformulation = \"solid\"\n[modal]\n",
    )
    .unwrap();
    let e = converge::from_scene(&scene, 2).unwrap_err();
    assert!(e.to_string().contains("can be refined"), "{e}");
    match e.at() {
        Some(At::Key { line, key, .. }) => assert_eq!((line, key.as_str()), (Some(4), "mesh")),
        other => panic!("{other:?}"),
    }
    // Too many levels, and too few: one level used to run against itself as the reference
    // (error +0.000 %) and then say that no run was within 1 %.
    for n in [30, 0, 1] {
        let e = converge::from_scene(&scene, n).unwrap_err();
        assert_eq!(
            e.at(),
            Some(At::Option {
                name: "--levels".into()
            }),
            "{e}"
        );
    }
    assert!(converge::builtin("s9").unwrap_err().at().is_some());
}

/// A study file's values are checked when it is read, each error at its line and key. Before,
/// a reversed [sweep] range was reported as a `--set` option never given, ν = 0.5 was refused
/// per case without file or key, a table of 1e6 m blamed the element size, a million webs were
/// "not an integer", and a [check] solid size of 1 µm failed after the whole sweep had run.
#[test]
fn study_file_values_are_refused_at_their_key_when_read() {
    let at = |name: &str, extra: &str| {
        let e = Study::load(&study_file(name, &format!("{BASE}{extra}"))).unwrap_err();
        let line = match e.at() {
            Some(At::Key { line, .. }) => line,
            other => panic!("{name}: {other:?} ({e})"),
        };
        (line, e.to_string())
    };
    // BASE is five lines: [study] (3), [table] and elem_size.
    let (line, e) = at("range", "[sweep]\n\"table.top_thickness\" = \"0.03:0.01:0.001\"\n");
    assert_eq!(line, Some(7), "{e}");
    assert!(
        e.contains("[sweep] 'table.top_thickness'") && e.contains("b ≥ a") && !e.contains("--set"),
        "{e}"
    );
    let (line, e) = at(
        "poisson",
        "[material]\nyoung = 2.1e11\npoisson = 0.5\ndensity = 7850.0\n",
    );
    assert_eq!(line, Some(8), "{e}");
    assert!(e.contains("'material.poisson'") && e.contains("(-1, 0.5)"), "{e}");
    // A modulus out of range is the modulus's key (it was blamed on the density).
    let (line, e) = at("young", "[material]\nyoung = 1e40\npoisson = 0.3\ndensity = 7850.0\n");
    assert_eq!(line, Some(7), "{e}");
    assert!(e.contains("'material.young'") && e.contains("unit slip"), "{e}");
    let text = BASE.replace("[table]\n", "[table]\nlength = 1e6\n");
    let e = Study::load(&study_file("length", &text)).unwrap_err().to_string();
    assert!(
        e.contains("line 5, key 'table.length'") && e.contains("more than 2000"),
        "{e}"
    );
    let (line, e) = at("webs", "[sweep]\n\"table.n_long_webs\" = [3, 1000000]\n");
    assert_eq!(line, Some(7), "{e}");
    assert!(
        e.contains("'table.n_long_webs'") && e.contains("at most 2000 webs"),
        "{e}"
    );
    let (line, e) = at("check", "[check]\ndesigns = 1\nsolid_size = 1e-6\n");
    assert_eq!(line, Some(8), "{e}");
    assert!(e.contains("'check.solid_size'") && e.contains("more than 2000"), "{e}");
    // A constraint no design can be compared with (every design was "infeasible" against NaN).
    let (line, e) = at("nan", "[constraints]\nmin_f1_hz = nan\n");
    assert_eq!(line, Some(7), "{e}");
    assert!(
        e.contains("'constraints.min_f1_hz'") && e.contains("finite frequency"),
        "{e}"
    );
    let (line, e) = at("mass", "[constraints]\nmax_mass_kg = -100.0\n");
    assert_eq!(line, Some(7), "{e}");
    assert!(e.contains("'constraints.max_mass_kg'"), "{e}");
    assert!(
        Study::load(&study_file(
            "nolimit",
            &format!("{BASE}[constraints]\nmax_mass_kg = inf\n")
        ))
        .is_ok()
    );
    let study = study_file("cli", BASE);
    let out = tmp("cli-out");
    for (opt, v) in [("--min-f1", "nan"), ("--max-mass=-100", "")] {
        let mut args = vec!["sweep", study.to_str().unwrap(), "--out", out.to_str().unwrap(), opt];
        if !v.is_empty() {
            args.push(v);
        }
        super::support::expect_error(&args, &[opt.split('=').next().unwrap()]);
    }
    // A hex20 size for a shell sweep sized nothing (the check's size is [check] solid_size).
    let args = [
        "sweep",
        study.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--solid-size",
        "0.05",
    ];
    super::support::expect_error(&args, &["--solid-size", "--formulation solid"]);
    // Without designs to check, the [check] size is not used and not refused.
    assert!(Study::load(&study_file("unused", &format!("{BASE}[check]\nsolid_size = 1e-6\n"))).is_ok());
}

/// Refinement levels are built from the source grammar's types: `box:` divisions doubled (a
/// single hex8 layer carrying shells stays one; a solid one is refined through its thickness,
/// where it kept one layer and converged to its own locked value), `helix:` elements per turn
/// doubled, `sandwich:` size halved.
#[test]
fn converge_refines_generators_by_their_grammar() {
    use converge::Refinable;
    let b = Refinable::parse("box:0.3,0.3,0.02:4,4,1:hex8").unwrap();
    assert_eq!(b.level(0, true), "box:0.3,0.3,0.02:4,4,1:hex8");
    assert_eq!(b.level(2, true), "box:0.3,0.3,0.02:16,16,1:hex8");
    assert_eq!(b.level(2, false), "box:0.3,0.3,0.02:16,16,4:hex8");
    let b = Refinable::parse("box:0.3,0.3,0.02:4,4,1:hex20").unwrap();
    assert_eq!(b.level(1, false), "box:0.3,0.3,0.02:8,8,2:hex20");
    let h = Refinable::parse("helix:0.032,0.01,6,12").unwrap();
    assert_eq!(h.level(1, false), "helix:0.032,0.01,6,24");
    let h = Refinable::parse("helix:0.032,0.01,6,12,line3").unwrap();
    assert_eq!(h.level(2, false), "helix:0.032,0.01,6,48,line3");
    let s = Refinable::parse("sandwich:paper").unwrap();
    assert_eq!(s.level(0, true), "sandwich:paper,0.025");
    assert_eq!(s.level(1, true), "sandwich:paper,0.0125");
    assert!(Refinable::parse("ibeam-line:1,10").is_none());
    assert!(Refinable::parse("box:1,1:2,2,2:hex8").is_none());
}
