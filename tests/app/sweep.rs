//! `vibrofem sweep`, `converge` and `merge`: a small sweep's trends, validation before meshing,
//! the Pareto front, a tiny convergence study and the merge of batch shards.

use crate::common::root;
use std::path::{Path, PathBuf};
use vibrofem::app::converge;
use vibrofem::app::scene::{BatchOptions, BatchRow, run_batch};
use vibrofem::app::sweep::{self, Study, SweepOptions, SweepRow, mark_pareto};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vibrofem-test-sweep-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn study(text: &str, name: &str) -> Study {
    let d = tmp(name);
    let p = d.join("study.toml");
    std::fs::write(&p, text).unwrap();
    Study::load(&p).unwrap()
}

const BASE: &str = "[study]\nversion = 1\nname = \"t\"\n[table]\nelem_size = 0.1\n";

#[test]
fn two_by_two_sweep_has_four_rows_and_monotone_mass() {
    let mut s = study(BASE, "2x2");
    s.set(
        "table.top_thickness",
        sweep::parse_values("k", "0.015:0.02:0.005").unwrap(),
    );
    s.set("table.n_trans_webs", vec![0.0, 2.0]);
    let out = tmp("2x2-out");
    let o = sweep::run_sweep(
        &s,
        &SweepOptions {
            out: Some(out.clone()),
            jobs: 1,
            progress: false,
            yes: false,
        },
    )
    .unwrap();
    assert_eq!(o.rows.len(), 4);
    // Rows: (0.015, 0), (0.015, 2), (0.02, 0), (0.02, 2).
    assert_eq!(o.rows[0].values, vec![0.015, 0.0]);
    assert_eq!(o.rows[3].values, vec![0.02, 2.0]);
    assert!(o.rows[2].mass_kg > o.rows[0].mass_kg && o.rows[3].mass_kg > o.rows[1].mass_kg);
    // Diaphragms add mass and stop the racking mode.
    assert!(o.rows[1].mass_kg > o.rows[0].mass_kg && o.rows[1].f1_hz > 1.5 * o.rows[0].f1_hz);
    for r in &o.rows {
        assert!(r.f1_hz > 50.0 && r.f1_hz < 1000.0, "{r:?}");
    }
    assert!(o.rows.iter().any(|r| r.pareto));
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5);
    assert!(csv.starts_with("case,table.top_thickness,table.n_trans_webs,mass_kg"));
    assert!(out.join("sweep.json").is_file());
    let svg = std::fs::read_to_string(out.join("pareto.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("Pareto front"));
    let text = sweep::table_text(&o);
    assert!(text.contains("designs meet the constraints"));
}

#[test]
fn out_of_range_values_fail_before_meshing_naming_the_key() {
    let mut s = study(BASE, "bad");
    // A huge mesh would take long: the error must come from validation, not from meshing.
    s.table.elem_size = 0.001;
    s.set("table.top_thickness", vec![0.02, -0.01]);
    let e = sweep::run_sweep(
        &s,
        &SweepOptions {
            out: None,
            jobs: 1,
            progress: false,
            yes: false,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("table.top_thickness = -0.01"), "{e}");
    let mut s = study(BASE, "bad2");
    s.set("table.n_long_webs", vec![3.0, 100.0]);
    let e = s.designs().unwrap_err().to_string();
    assert!(e.contains("table.n_long_webs = 100") && e.contains("overlap"), "{e}");
    let mut s = study(BASE, "bad3");
    s.set("table.n_trans_webs", vec![1.5]);
    let e = s.designs().unwrap_err().to_string();
    assert!(e.contains("table.n_trans_webs") && e.contains("integer"), "{e}");
    assert!(
        sweep::parse_set("table.nonsense=1")
            .unwrap_err()
            .to_string()
            .contains("unknown sweep key")
    );
    assert!(sweep::parse_set("table.top_thickness=0.03:0.01:0.01").is_err());
    // Combination errors name every swept value.
    let mut s = study(BASE, "bad4");
    s.set("table.web_thickness", vec![0.0045, 0.2]);
    s.set("table.n_long_webs", vec![3.0]);
    let e = s.designs().unwrap_err().to_string();
    assert!(e.contains("table.web_thickness = 0.2"), "{e}");
}

/// A value out of range beside the base table may be in range beside another swept value: a
/// 0.3 m bottom plate under the base's 0.3 m web span put its webs at its edges, and the
/// sweep was refused though the combination with a 0.2 m span is a valid table (the same
/// values in `[table]` run). Such a value is kept; a combination that is no table is a failed
/// design named by all its values, the others run; a value no combination takes is refused
/// by its key as before.
#[test]
fn values_are_checked_in_combination() {
    let mut s = study(BASE, "combined");
    s.set("table.bottom_width", vec![0.3]);
    s.set("table.long_web_span", vec![0.2]);
    let d = s.designs().unwrap();
    assert_eq!(d.len(), 1);
    assert!(d[0].1.is_ok(), "{:?}", d[0].1.as_ref().err());
    s.set("table.long_web_span", vec![0.2, 0.3]);
    let o = sweep::run_sweep(
        &s,
        &SweepOptions {
            out: None,
            jobs: 1,
            progress: false,
            yes: false,
        },
    )
    .unwrap();
    assert_eq!(o.rows.len(), 1);
    assert_eq!(o.rows[0].values, vec![0.3, 0.2]);
    assert_eq!(o.failed.len(), 1, "{:?}", o.failed);
    let f = &o.failed[0];
    assert_eq!((f.case, f.stage), (2, "design"));
    assert!(
        f.error.contains("table.bottom_width = 0.3") && f.error.contains("table.long_web_span = 0.3"),
        "{}",
        f.error
    );
    s.set("table.long_web_span", vec![0.3, 0.35]);
    let e = s.designs().unwrap_err().to_string();
    assert!(e.contains("table.bottom_width = 0.3"), "{e}");
}

/// A sweep of a scene takes its parts' thicknesses (a 15 mm top plate was swept as the
/// reconstruction's 25 mm: 184.16 kg where `run` gives 129.74 kg), and refuses what its free
/// table in one material cannot carry (a part in aluminium was analysed as steel), naming it.
#[test]
fn a_scene_sweep_takes_the_scene_parts_or_refuses_them() {
    let scene = |top: &str| {
        format!(
            "[scene]\nversion = 1\nname = \"s7\"\n[mesh]\ngenerator = \"sandwich:paper,0.1\"\n\
             [[material]]\nname = \"steel\"\nyoung = 2.1e11\npoisson = 0.3\ndensity = 7850.0\n\
             [[material]]\nname = \"alu\"\nyoung = 7e10\npoisson = 0.33\ndensity = 2700.0\n\
             [[part]]\ngroup = \"top_plate\"\nformulation = \"shell\"\nthickness = 0.015\n{top}\
             [[part]]\ngroup = \"bottom_plate\"\nformulation = \"shell\"\nthickness = 0.006\n\
             [[part]]\ngroup = \"webs_long\"\nformulation = \"shell\"\nthickness = 0.005\n[modal]\nmodes = 7\n"
        )
    };
    let d = tmp("scene-parts");
    let p = d.join("s7.toml");
    std::fs::write(&p, scene("")).unwrap();
    let s = Study::load(&p).unwrap();
    assert_eq!(
        (
            s.table.top_thickness,
            s.table.bottom_thickness,
            s.table.long_web_thickness
        ),
        (0.015, 0.006, 0.005)
    );
    std::fs::write(&p, scene("material = \"alu\"\n")).unwrap();
    let e = Study::load(&p).unwrap_err().to_string();
    assert!(e.contains("part 'top_plate' has a material of its own"), "{e}");
}

#[test]
fn pareto_front_is_non_dominated() {
    let pts = [
        (100.0, 200.0),
        (110.0, 250.0),
        (105.0, 190.0),
        (120.0, 250.0),
        (90.0, 150.0),
        (130.0, 400.0),
    ];
    let mut rows: Vec<SweepRow> = pts
        .iter()
        .enumerate()
        .map(|(i, &(m, f))| SweepRow {
            case: i + 1,
            values: vec![],
            mass_kg: m,
            model_mass_kg: m,
            f1_hz: f,
            f2_hz: f,
            dofs: 0,
            time_s: 0.0,
            feasible: false,
            pareto: false,
        })
        .collect();
    mark_pareto(&mut rows);
    let front: Vec<usize> = rows.iter().filter(|r| r.pareto).map(|r| r.case).collect();
    assert_eq!(front, vec![1, 2, 5, 6]);
    for a in rows.iter().filter(|r| r.pareto) {
        for b in &rows {
            let dominates =
                b.mass_kg <= a.mass_kg && b.f1_hz >= a.f1_hz && (b.mass_kg < a.mass_kg || b.f1_hz > a.f1_hz);
            assert!(!dominates, "{} dominated by {}", a.case, b.case);
        }
    }
    for a in rows.iter().filter(|r| !r.pareto) {
        assert!(
            rows.iter()
                .any(|b| b.pareto && b.mass_kg <= a.mass_kg && b.f1_hz >= a.f1_hz)
        );
    }
}

#[test]
fn converge_tiny_names_a_cheapest_formulation() {
    let case = converge::builtin("tiny").unwrap();
    let c = converge::run_case(&case, &|_| {}).unwrap();
    assert_eq!(c.rows.len(), 5);
    assert!(c.reference > 600.0 && c.reference < 800.0, "{}", c.reference);
    let best = converge::cheapest_within(&c, 0.01).expect("something within 1 %");
    assert!(best.error.abs() <= 0.01);
    assert!(c.rows.iter().all(|r| r.dofs > 0 && r.time_s >= 0.0));
    let md = converge::table_markdown(&c);
    assert!(md.contains("cheapest within 1 %: "), "{md}");
    let out = tmp("converge");
    converge::write_outputs(&c, &out).unwrap();
    assert!(
        std::fs::read_to_string(out.join("converge.svg"))
            .unwrap()
            .contains("<svg")
    );
    assert!(converge::builtin("s9").is_err());
    assert!((converge::richardson([1.0, 1.75, 1.9375]).unwrap().0 - 2.0).abs() < 1e-12);
}

fn strip_time(rows: &[BatchRow]) -> Vec<String> {
    rows.iter()
        .map(|r| {
            let mut r = r.clone();
            r.time_s = 0.0;
            serde_json::to_string(&r).unwrap()
        })
        .collect()
}

fn run(d: &Path, out: &str, shard: Option<(usize, usize)>) -> Vec<BatchRow> {
    run_batch(&BatchOptions {
        pattern: d.join("meshes/*.msh").display().to_string(),
        template: d.join("template.toml"),
        out: d.join(out),
        jobs: 1,
        force: false,
        shard,
        progress_bar: false,
    })
    .unwrap()
    .rows
}

#[test]
fn merge_of_shards_equals_the_unsharded_batch() {
    let d = tmp("merge");
    std::fs::create_dir_all(d.join("meshes")).unwrap();
    for h in ["h20", "h30"] {
        std::fs::copy(
            root().join(format!("meshes/s1_plate_tet4_{h}.msh")),
            d.join(format!("meshes/s1_plate_tet4_{h}.msh")),
        )
        .unwrap();
    }
    let text = std::fs::read(root().join("meshes/s1_plate_tet4_h30.msh")).unwrap();
    std::fs::write(d.join("meshes/broken.msh"), &text[..text.len() / 2]).unwrap();
    std::fs::write(
        d.join("template.toml"),
        "[scene]\nversion = 1\nname = \"m\"\n[[part]]\ngroup = \"body\"\nformulation = \"solid\"\n[modal]\nmodes = 7\n",
    )
    .unwrap();
    let all = run(&d, "all", None);
    let a = run(&d, "s1", Some((1, 2)));
    let b = run(&d, "s2", Some((2, 2)));
    assert_eq!(a.len() + b.len(), 3);
    // Shard 2 given first: the merge sorts by file.
    let m = sweep::merge(&[d.join("s2"), d.join("s1")], Some(&d.join("merged"))).unwrap();
    assert_eq!(strip_time(&m.rows), strip_time(&all));
    assert_eq!(m.failed, 1);
    assert!(d.join("merged/summary.csv").is_file());
    assert_eq!(m.shards, [[1, 2], [2, 2]]);
    assert!(vibrofem::app::studies::merge::missing_shards(&m).is_empty());
    // One shard alone: merged, the other named as missing.
    let one = sweep::merge(&[d.join("s1")], None).unwrap();
    assert_eq!(vibrofem::app::studies::merge::missing_shards(&one), ["2/2"]);
    // A shard of another template is refused (its rows mixed 7 and 3 frequencies silently).
    let tpl = std::fs::read_to_string(d.join("template.toml")).unwrap();
    std::fs::write(d.join("template.toml"), tpl.replace("modes = 7", "modes = 3")).unwrap();
    run(&d, "s2_other", Some((2, 2)));
    std::fs::write(d.join("template.toml"), &tpl).unwrap();
    let e = sweep::merge(&[d.join("s1"), d.join("s2_other")], None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("different template scenes"), "{e}");
    // The same shard twice is fine; a case with different results is an error naming it.
    assert_eq!(
        sweep::merge(&[d.join("s1"), d.join("s1")], None).unwrap().rows.len(),
        a.len()
    );
    let js = std::fs::read_to_string(d.join("all/summary.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&js).unwrap();
    let ok = v["rows"]
        .as_array()
        .unwrap()
        .iter()
        .position(|r| r["status"] == "ok")
        .unwrap();
    let file = v["rows"][ok]["file"].as_str().unwrap().to_string();
    v["rows"][ok]["mass_kg"] = serde_json::json!(1.0);
    std::fs::create_dir_all(d.join("bad")).unwrap();
    std::fs::write(d.join("bad/summary.json"), v.to_string()).unwrap();
    let e = sweep::merge(&[d.join("all"), d.join("bad")], None)
        .unwrap_err()
        .to_string();
    assert!(e.contains(&file) && e.contains("different results"), "{e}");
    assert!(sweep::merge(&[d.join("nowhere")], None).is_err());
}

#[test]
fn cli_sweep_and_merge_work() {
    let d = tmp("cli");
    let p = d.join("s.toml");
    std::fs::write(&p, BASE).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_vibrofem"))
        .args([
            "sweep",
            p.to_str().unwrap(),
            "--set",
            "table.bottom_thickness=0.006,0.01",
            "-o",
        ])
        .arg(d.join("out"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        text.contains("2 designs meet") || text.contains("of 2 designs meet"),
        "{text}"
    );
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_vibrofem"))
        .args(["sweep", p.to_str().unwrap(), "--set", "table.bottom_width=-1"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("table.bottom_width = -1"));
}

#[test]
fn committed_s7_study_is_valid() {
    let s = Study::load(&root().join("scenes/studies/study_s7_table.toml")).unwrap();
    assert_eq!(s.designs().unwrap().len(), 810);
    assert_eq!((s.constraints.min_f1_hz, s.constraints.max_mass_kg), (300.0, 165.0));
    assert_eq!(s.check.designs, 4);
}

/// Issue 15, item 15: `converge --levels 30` ran on; more than MAX_LEVELS levels is refused
/// up front with the growth it would mean.
#[test]
fn converge_refuses_too_many_levels() {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_vibrofem"))
        .args(["converge", "scenes/s1_plate_solid.toml", "--levels", "30", "-o"])
        .arg(std::env::temp_dir().join(format!("vibrofem-cv-levels-{}", std::process::id())))
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--levels 30: at most 6"), "{err}");
}

/// A design whose analysis fails (a 1 µm long table: its K is too ill-conditioned for the
/// modes to be verified) is reported with its error and the study goes on: the other design is
/// analysed and tabulated, the CSV keeps both in case order, and the command ends with exit
/// code 3 as `batch` does for a run in which some cases failed.
#[test]
fn a_failing_design_is_reported_and_the_study_goes_on() {
    let d = tmp("fail-cli");
    let p = d.join("study.toml");
    std::fs::write(&p, BASE).unwrap();
    let out = d.join("out");
    let (code, stdout, stderr) = crate::common::run(&[
        "sweep",
        p.to_str().unwrap(),
        "--set",
        "table.length=1e-6,1.2",
        "--jobs",
        "2",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 3, "{stdout}\n{stderr}");
    assert!(
        stderr.contains("[") && stderr.contains("failed: verification failed"),
        "{stderr}"
    );
    assert!(stdout.contains("1 failed (the study went on past them)"), "{stdout}");
    assert!(
        stdout.contains("case 1 (table.length=1e-6): verification failed"),
        "{stdout}"
    );
    assert!(stdout.contains("of 1 designs meet the constraints"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 3, "{csv}");
    assert!(lines[0].ends_with(",feasible,pareto,error"), "{csv}");
    assert!(
        lines[1].starts_with("1,1e-6,,,,,,,false,false,\"verification failed"),
        "{csv}"
    );
    // The analysed design: its numbers and an empty error.
    let f: Vec<&str> = lines[2].split(',').collect();
    assert_eq!(f[0], "2");
    assert!(f[4].parse::<f64>().unwrap() > 1.0 && f.last() == Some(&""), "{csv}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(json["failed"][0]["case"], 1);
    assert_eq!(json["failed"][0]["stage"], "design");
    assert_eq!(json["rows"].as_array().unwrap().len(), 1);
}

/// An absurd dimension (1e308 m) is named as the geometry's fault, not the element size's (the
/// grid-line count overflows either way; before, the error said "elem_size = 0.1 is too small").
#[test]
fn an_absurd_dimension_is_not_blamed_on_the_element_size() {
    let mut s = study(BASE, "absurd");
    s.set("table.top_thickness", vec![1e308]);
    let opts = SweepOptions {
        out: None,
        jobs: 1,
        progress: false,
        yes: false,
    };
    let o = sweep::run_sweep(&s, &opts).unwrap();
    assert!(o.rows.is_empty());
    let e = &o.failed[0].error;
    assert!(e.contains("check its dimensions") && !e.contains("too small"), "{e}");
    assert!(sweep::table_text(&o).contains("table.top_thickness=1e308"));
}
