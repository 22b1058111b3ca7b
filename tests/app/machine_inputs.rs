//! The machines' commands (`crank-drive`, `autobalancer`, `balancer-data`) against hostile
//! inputs and outputs (issue 28 items 7, 8, 13, 15, 16): a full or closed standard output, case
//! values that ask for unbounded work, values whose only remedy would be a setting the user
//! cannot reach, a byte-order mark, and masses that overflow the results.
//!
//! Every test runs the binary, with a time limit where the failure was a hang.

use std::io::Read;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::bin;

fn tmpdir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("vibrofem-machine-inputs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `cmd` for at most `limit`: (exit code, stdout, stderr, elapsed), or panics naming the
/// hang after killing the process.
fn run_within(cmd: &mut Command, limit: Duration) -> (Option<i32>, String, String, Duration) {
    let t0 = Instant::now();
    let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let ho = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out.read_to_string(&mut s);
        s
    });
    let he = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    loop {
        if let Some(st) = child.try_wait().unwrap() {
            let (o, e) = (ho.join().unwrap(), he.join().unwrap());
            return (st.code(), o, e, t0.elapsed());
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{cmd:?} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A quick autobalancer case: the built-in grinder with a short sweep and run-up.
fn quick_autobalancer() -> String {
    let good = include_str!("../../scenes/machines/grinder_autobalancer.toml");
    good.replace("points = 27", "points = 3")
        .replace("duration = 5.0 ", "duration = 1.0 ")
        .replace("duration = 4.0", "duration = 1.5")
}

/// The three commands with a quick case each, as argument lists (the output folder appended by
/// the caller).
fn commands(dir: &std::path::Path) -> Vec<Vec<String>> {
    let ab = dir.join("quick.toml");
    std::fs::write(&ab, quick_autobalancer()).unwrap();
    vec![
        vec!["crank-drive".into()],
        vec!["autobalancer".into(), ab.display().to_string()],
        vec!["balancer-data".into()],
    ]
}

/// Issue 28 item 7: a full disk behind standard output is exit 4 ("a result could not be
/// written") for the summary and for `--json`, not a panic (101).
#[test]
fn machine_commands_exit_4_on_a_full_stdout() {
    let dir = tmpdir("full");
    for args in commands(&dir) {
        for json in [false, true] {
            let out = dir.join(format!("o-{}-{json}", args[0]));
            let mut c = bin();
            c.args(&args).arg("-o").arg(&out);
            if json {
                c.arg("--json");
            }
            let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
            let o = c.stdout(full).stderr(Stdio::piped()).output().unwrap();
            let e = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(4), "{args:?} json={json}: {e}");
            assert!(!e.contains("panicked"), "{args:?}: {e}");
            assert!(e.contains("standard output"), "{args:?}: {e}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 28 item 7: a closed pipe (`vibrofem crank-drive | head -0`) ends quietly with 141, as
/// a Unix tool killed by SIGPIPE, not with a panic (101).
#[test]
fn machine_commands_exit_141_on_a_closed_stdout() {
    let dir = tmpdir("pipe");
    for args in commands(&dir) {
        let out = dir.join(format!("o-{}", args[0]));
        // The pipe's read end is closed before the child starts: dropping it after `spawn`
        // raced a fast command (balancer-data) that wrote everything into the pipe's buffer
        // first and rightly exited 0.
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let mut child = bin()
            .args(&args)
            .arg("-o")
            .arg(&out)
            .stdout(writer)
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut e = String::new();
        child.stderr.take().unwrap().read_to_string(&mut e).unwrap();
        let st = child.wait().unwrap();
        assert_eq!(st.code(), Some(141), "{args:?}: {e}");
        assert!(!e.contains("panicked"), "{args:?}: {e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 28 item 8: `step_deg = 1e-9` divides 360 and passed validation, then asked for 3.6e11
/// steps per revolution (a hang). Refused before any work, naming the file, line and key.
#[test]
fn crank_drive_step_too_small_is_refused_before_work() {
    let dir = tmpdir("step");
    let good = include_str!("../../scenes/machines/crank_two_carts.toml");
    let f = dir.join("tiny_step.toml");
    let text = good.replace("step_deg = 0.5 ", "step_deg = 1e-9 ");
    assert_ne!(text, good);
    std::fs::write(&f, &text).unwrap();
    let line = text.lines().position(|l| l.starts_with("step_deg")).unwrap() + 1;
    let (code, _, e, t) = run_within(
        bin().arg("crank-drive").arg(&f).arg("-o").arg(dir.join("o")),
        Duration::from_secs(60),
    );
    assert_eq!(code, Some(1), "{e}");
    assert!(
        e.contains("tiny_step.toml") && e.contains(&format!("line {line}")) && e.contains("step_deg"),
        "{e}"
    );
    assert!(t < Duration::from_secs(10), "refused after {t:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 28 item 8: a test-stand CSV of 100 000 mountings took 33 s (a linear search per row
/// for a repeated label). It must take a fraction of that; a repeated label is still refused
/// naming both lines.
#[test]
fn balancer_data_large_csv_reads_in_linear_time() {
    let dir = tmpdir("large");
    let mut csv = String::from("record,label,x,y\nversion,balancer-data,1,\nball,,0.0021,0.030\n");
    for k in 0..100_000 {
        csv.push_str(&format!("mount,m{k},{},{}\n", 90 + k % 17, 250 + k % 13));
    }
    let f = dir.join("large.csv");
    std::fs::write(&f, &csv).unwrap();
    let (code, _, e, t) = run_within(
        bin().arg("balancer-data").arg(&f).arg("-o").arg(dir.join("o")),
        Duration::from_secs(120),
    );
    assert_eq!(code, Some(0), "{e}");
    assert!(t < Duration::from_secs(30), "100 000 rows took {t:?}");
    csv.push_str("mount,m7,1,2\n");
    std::fs::write(&f, &csv).unwrap();
    let (code, _, e, _) = run_within(
        bin().arg("balancer-data").arg(&f).arg("-o").arg(dir.join("o2")),
        Duration::from_secs(120),
    );
    assert_eq!(code, Some(1), "{e}");
    assert!(e.contains("line 100004") && e.contains("repeats line 11"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 28 item 13: `speed_rpm = 1e7` passed validation, ran, and failed with "loosen
/// rtol/atol or raise max_steps", settings an autobalancer file cannot hold. Refused before any
/// work, naming the key and the line, advising nothing out of reach.
#[test]
fn autobalancer_unreachable_speed_is_refused_naming_the_key() {
    let dir = tmpdir("speed");
    let good = include_str!("../../scenes/machines/grinder_autobalancer.toml");
    let text = good.replace("speed_rpm = 10000.0", "speed_rpm = 1e7");
    assert_ne!(text, good);
    let f = dir.join("fast.toml");
    std::fs::write(&f, &text).unwrap();
    let line = text.lines().position(|l| l.starts_with("speed_rpm")).unwrap() + 1;
    let (code, _, e, t) = run_within(
        bin().arg("autobalancer").arg(&f).arg("-o").arg(dir.join("o")),
        Duration::from_secs(300),
    );
    assert_eq!(code, Some(1), "{e}");
    assert!(e.contains(&format!("line {line}")) && e.contains("speed_rpm"), "{e}");
    assert!(!e.contains("max_steps") && !e.contains("rtol"), "{e}");
    assert!(t < Duration::from_secs(10), "refused after {t:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 28 item 15: Excel's "CSV UTF-8" starts with a byte-order mark; the header then read
/// "expected the header 'record,label,x,y', found 'record,label,x,y'". The BOM is skipped and the
/// numbers are those of the same file without it.
#[test]
fn balancer_csv_with_a_byte_order_mark_is_read() {
    let dir = tmpdir("bom");
    let csv = include_str!("../../scenes/machines/balancer_test_stand.csv");
    let (plain, bom) = (dir.join("plain.csv"), dir.join("bom.csv"));
    std::fs::write(&plain, csv).unwrap();
    std::fs::write(&bom, format!("\u{feff}{csv}")).unwrap();
    let mut reductions = Vec::new();
    for (f, o) in [(&plain, "o1"), (&bom, "o2")] {
        let o = bin()
            .arg("balancer-data")
            .arg(f)
            .args(["--json", "-o"])
            .arg(dir.join(o))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        reductions.push(v["reduction"].clone());
    }
    assert_eq!(reductions[0], reductions[1]);
    // The TOML machine files take a BOM too.
    let good = include_str!("../../scenes/machines/crank_two_carts.toml");
    let f = dir.join("bom.toml");
    std::fs::write(
        &f,
        format!(
            "\u{feff}{}",
            good.replace("[[setup]]", "[[unused]]")
                .split("[[unused]]")
                .next()
                .unwrap()
        ),
    )
    .unwrap();
    let o = bin()
        .arg("crank-drive")
        .arg(&f)
        .arg("-o")
        .arg(dir.join("o3"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 28 item 16: a 1e300 kg imbalance (or ball) passed validation; the residual imbalance
/// overflowed and the report said `null` (inf) with exit 0. Such masses are refused before any
/// work, naming the key and the line.
#[test]
fn autobalancer_overflowing_mass_is_refused_naming_the_key() {
    let dir = tmpdir("heavy");
    for (from, to, key) in [
        ("imbalance_mass = 0.001 ", "imbalance_mass = 1e300 ", "imbalance_mass"),
        ("mass = 0.0021 ", "mass = 1e300 ", "mass"),
    ] {
        let text = quick_autobalancer().replacen(from, to, 1);
        assert_ne!(text, quick_autobalancer());
        let f = dir.join("heavy.toml");
        std::fs::write(&f, &text).unwrap();
        let line = text.lines().position(|l| l.starts_with(to.trim_end())).unwrap() + 1;
        let (code, out, e, _) = run_within(
            bin()
                .arg("autobalancer")
                .arg(&f)
                .arg("--json")
                .arg("-o")
                .arg(dir.join("o")),
            Duration::from_secs(300),
        );
        assert_eq!(code, Some(1), "{key}: {e}");
        assert!(e.contains(&format!("line {line}")) && e.contains(key), "{key}: {e}");
        assert!(!out.contains("null"), "{key}: {out}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
