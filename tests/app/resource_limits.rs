//! Resource limits: a model beyond `--max-memory` or `ulimit -v` is refused from its estimate
//! (an allocation that still fails is a clear error, never an abort), and design files and
//! studies that make minutes of work need `--yes`.

use crate::common::run;
use std::process::Command;

/// Item 14: a model far beyond `--max-memory` is refused from the estimate (exit 1, the
/// estimate and the limit in the message), not aborted in assembly. Issue 31: with the direct
/// solver only (`--solver auto`, the default, takes the iterative path instead: see
/// tests/app/lowmem.rs).
#[test]
fn max_memory_refuses_before_assembly() {
    let (code, _, err) = run(&[
        "modes",
        "box:1,1,1:30,30,30:hex20",
        "--max-memory",
        "200M",
        "--solver",
        "direct",
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("needs at least") && err.contains("--max-memory is 200 MiB"),
        "{err}"
    );
}

/// Item 14: `ulimit -v` is honoured: the same model is refused naming the limit, and with
/// `--max-memory` set beyond it the allocation failure is still a clear error, never an abort.
#[test]
fn ulimit_is_honoured_and_allocation_failure_is_an_error() {
    let exe = env!("CARGO_BIN_EXE_vibrofem");
    for extra in ["", "--max-memory 100G"] {
        let o = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "ulimit -v 1500000 && exec {exe} modes box:1,1,1:30,30,30:hex20 --modes 3 {extra}"
            ))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{extra}: {err}");
        assert!(
            err.contains("ulimit -v") || err.contains("cannot allocate"),
            "{extra}: {err}"
        );
    }
}

/// Item 12: design-file values within range that make minutes of work, and studies of tens of
/// thousands of designs, are refused with their size before any analysis unless `--yes`.
#[test]
fn large_designs_and_studies_need_yes() {
    let dir = std::env::temp_dir().join(format!("vibrofem-yes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = crate::common::root();
    let text = std::fs::read_to_string(root.join("scenes/designs/s8_transverse_webs.toml")).unwrap();
    assert!(text.contains("element_size = 0.025"));
    let big = dir.join("big.toml");
    std::fs::write(&big, text.replace("element_size = 0.025", "element_size = 0.004")).unwrap();
    let (code, _, err) = run(&["design", big.to_str().unwrap(), "-o", dir.join("d").to_str().unwrap()]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("DOFs") && err.contains("--yes"), "{err}");
    // The estimate is the models' size from their meshes: the built-in design is far below it.
    let paper = vibrofem::app::design::Design::paper();
    let n = vibrofem::app::design::estimate_dofs(&paper).unwrap();
    assert!(n > 1000 && n < vibrofem::app::design::LARGE_DESIGN_DOFS, "{n}");
    let study = root.join("scenes/studies/study_s7_table.toml");
    let (code, _, err) = run(&[
        "sweep",
        study.to_str().unwrap(),
        "--set",
        "top_thickness=0.01:0.03:0.0005",
        "--set",
        "bottom_thickness=0.005:0.02:0.0005",
        "-o",
        dir.join("s").to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("designs (more than 1000)") && err.contains("--yes"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
