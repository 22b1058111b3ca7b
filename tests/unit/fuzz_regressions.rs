//! Inputs found by the fuzzers (`fuzz/`, see `fuzz/README.md`) and hand-made hostile headers,
//! kept as regression tests: each must give a clean `Err` — never a panic, a hang or an
//! allocation sized by a count read from the file.
//!
//! `tests/data/fuzz/*.msh` go through the gmsh reader, `*.scene.toml` through the scene parser,
//! `*.design.toml` through the design-file parser.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use vibrofem::Error;

fn inputs(suffix: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_string_lossy().ends_with(suffix))
        .collect();
    v.sort();
    v
}

/// Every input must be rejected quickly: the largest is 8 KB.
const FAST: Duration = Duration::from_secs(5);

#[test]
fn msh_inputs_give_clean_errors() {
    let files = inputs(".msh");
    assert!(!files.is_empty());
    for p in files {
        let bytes = std::fs::read(&p).unwrap();
        for scale in [1.0, 1e-3] {
            let t = Instant::now();
            let r = vibrofem::io::gmsh::read_bytes(&bytes, &p, scale);
            assert!(t.elapsed() < FAST, "{}: took {:?}", p.display(), t.elapsed());
            match r {
                Ok(m) => panic!("{}: accepted ({} nodes)", p.display(), m.nodes.len()),
                Err(e) => {
                    assert!(
                        matches!(
                            e,
                            Error::MeshParse { .. } | Error::UnsupportedElement { .. } | Error::EmptyModel { .. }
                        ),
                        "{}: {e:?}",
                        p.display()
                    );
                    assert_eq!(e.exit_code(), 1);
                }
            }
        }
    }
}

#[test]
fn huge_header_counts_name_the_overclaim() {
    // A header claiming 1e12 nodes: no allocation from the count, and the message says why.
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz/huge_node_count_41.msh");
    let e = vibrofem::io::gmsh::read(&p, 1.0).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("1000000000000"), "{msg}");
}

#[test]
fn scene_inputs_give_clean_errors() {
    for p in inputs(".scene.toml") {
        let text = std::fs::read_to_string(&p).unwrap();
        let t = Instant::now();
        let r = vibrofem::app::scene::Scene::parse(Path::new("/nonexistent-fuzz/scene.toml"), &text);
        assert!(t.elapsed() < FAST, "{}: took {:?}", p.display(), t.elapsed());
        let e = r.err().unwrap_or_else(|| panic!("{}: accepted", p.display()));
        assert_eq!(e.exit_code(), 1, "{}: {e}", p.display());
    }
}

#[test]
fn design_inputs_give_clean_errors() {
    for p in inputs(".design.toml") {
        let e = vibrofem::app::design::Design::from_toml(&p).unwrap_err();
        assert_eq!(e.exit_code(), 1, "{}: {e}", p.display());
    }
}
