//! Where the results go: a closed pipe on stdout ends quietly, a full disk is an output error
//! (exit 4), and output paths are checked (and missing folders created) before the run.

use super::support::{BAR, expect_error, tmp};
use crate::common::{bin, run};
use std::process::Stdio;

/// Item 10: stdout closed before anything is written: no panic (101); quiet exit 0 or 141.
#[test]
fn closed_stdout_is_quiet() {
    for args in [
        &["modes", BAR, "--fix", "xmin", "--modes", "2"][..],
        &["modes", BAR, "--fix", "xmin", "--modes", "2", "--json"][..],
        &["mesh-info", BAR][..],
    ] {
        // The reader is gone before the child starts, so the first write meets a closed pipe.
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let child = bin().args(args).stdout(writer).stderr(Stdio::piped()).spawn().unwrap();
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        let code = o.status.code();
        assert_eq!(code, Some(141), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// Item 10: a full disk on stdout is an output error (exit 4), not a panic.
#[test]
fn full_stdout_exits_4() {
    if !std::path::Path::new("/dev/full").exists() {
        return;
    }
    for args in [
        &["modes", BAR, "--fix", "xmin", "--modes", "2"][..],
        &["mesh-info", BAR][..],
    ] {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let o = bin().args(args).stdout(full).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(4), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// An output folder (or a folder on a result file's path) that is an existing file: the
/// message was the system's bare "File exists (os error 17)"; now it says which path is a file.
#[test]
fn an_output_folder_that_is_a_file_is_named() {
    let f = tmp("folder_is_file").join("results");
    std::fs::write(&f, "").unwrap();
    let fs = f.to_str().unwrap();
    expect_error(
        &["sweep", "scenes/studies/study_s7_table.toml", "-o", fs],
        &["is a file, not a folder"],
    );
    let inner = format!("{fs}/sub/modes.vtu");
    expect_error(
        &["modes", BAR, "--fix", "xmin", "--modes", "2", "--vtu", &inner],
        &[&format!("'{fs}' in the path is a file")],
    );
}

/// The same for a result file on a full disk (`--vtu`, `--msh-out`): created, not written,
/// exit 4 as the README's table says, where it was 1 (an input error).
#[test]
fn full_disk_for_a_result_file_exits_4() {
    if !std::path::Path::new("/dev/full").exists() {
        return;
    }
    for opt in ["--vtu", "--msh-out"] {
        let (code, _, err) = run(&["modes", BAR, "--fix", "xmin", "--modes", "2", opt, "/dev/full"]);
        assert_eq!(code, 4, "{opt}: {err}");
        assert!(err.contains("/dev/full") && !err.contains("panicked"), "{opt}: {err}");
    }
}

/// Item 12: an output path that cannot be written is refused before the run, naming it; a
/// missing folder is created.
#[test]
fn output_paths_are_checked_before_the_run() {
    let cube = "box:0.1,0.1,0.1:2,2,2:hex8";
    expect_error(&["modes", cube, "--vtu", "/proc/no/such/x.vtu"], &["/proc/no"]);
    let d = tmp("outputs");
    expect_error(&["modes", cube, "--vtu", d.to_str().unwrap()], &["is a folder"]);
    expect_error(
        &["static", cube, "--fix", "xmin", "--msh-out", "/proc/no/x.msh"],
        &["/proc/no"],
    );
    expect_error(
        &["run", "scenes/s3_leaf_stiffness.toml", "-o", "/proc/no/run"],
        &["/proc/no/run"],
    );
    let f = d.join("new/folder/m.vtu");
    let (code, out, err) = run(&["modes", cube, "--modes", "7", "--vtu", f.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(f.is_file());
}
