//! Command-line regressions of issue 15 (items 9, 12, 13, 14, 15): memory refusals before
//! assembly and under `ulimit -v`, conflicting options, output paths checked up front.

use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_vibrofem"))
}

fn run(args: &[&str]) -> (i32, String, String) {
    let o = bin().args(args).output().unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

/// Item 14: a model far beyond `--max-memory` is refused from the estimate (exit 1, the
/// estimate and the limit in the message), not aborted in assembly.
#[test]
fn max_memory_refuses_before_assembly() {
    let (code, _, err) = run(&["modes", "box:1,1,1:30,30,30:hex20", "--max-memory", "200M"]);
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
