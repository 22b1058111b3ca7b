//! Command-line options: usage errors exit 1 (help 0), negative numbers for `--band` and
//! `--shift`, an unusable shift refused by name, a band from 0 Hz on a free body, and the
//! thread-count bound.

use super::support::BAR;
use crate::common::run;

/// Item 11: usage errors are input errors (1), not the numerical-failure code 2; help is 0.
#[test]
fn usage_errors_exit_1() {
    for args in [
        &["modes", BAR, "--no-such-option"][..],
        &["modes"][..],
        &["modes", BAR, "--modes", "x"][..],
        &["no-such-command"][..],
    ] {
        let (code, _, err) = run(args);
        assert_eq!(code, 1, "{args:?}: {err}");
    }
    let (code, out, _) = run(&["--help"]);
    assert_eq!(code, 0);
    assert!(out.contains("Usage"), "{out}");
}

/// Item 11: negative numbers are accepted by `--band` and `--shift`.
#[test]
fn negative_band_and_shift_are_accepted() {
    let (code, out, err) = run(&["modes", BAR, "--fix", "xmin", "--band", "-10", "1000"]);
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, err) = run(&["modes", BAR, "--fix", "xmin", "--modes", "2", "--shift", "-100"]);
    assert_eq!(code, 0, "{out}{err}");
}

/// Item 11: `--band 0 F` on a free body holds the rigid-body modes and passes its Sturm check.
#[test]
fn band_from_zero_on_a_free_body() {
    let (code, out, err) = run(&["modes", BAR, "--band", "0", "1"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("rigid-body modes: 6"), "{out}");
}

/// Item 12: a shift that is not a usable number is refused as input (exit 1), by name.
#[test]
fn unusable_shift_exits_1() {
    for s in ["nan", "inf", "1e300"] {
        let (code, _, err) = run(&["modes", BAR, "--fix", "xmin", "--shift", s]);
        assert_eq!(code, 1, "{s}: {err}");
        assert!(err.contains("--shift"), "{s}: {err}");
    }
}

/// Item 10: an absurd thread count is bounded (with a note) instead of panicking in rayon.
#[test]
fn huge_thread_count_is_bounded() {
    let (code, out, err) = run(&["--threads", "5000", "modes", BAR, "--fix", "xmin", "--modes", "2"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(err.contains("capped"), "{err}");
}
