//! `vibrofem export` and the SLEPc engine's command-line contract: the exported matrices read
//! back equal to the assembled ones, and a missing SLEPc or MPI is a clear error (exit 5) that
//! names the packages, never a hang. (The 2-rank SLEPc solve itself is checked against the
//! native solver by `validation/slepc_check.sh` in CI, after the packages are installed.)

use crate::common::{bin, run_cmd as run};
use vibrofem::input::source;
use vibrofem::model::{Model, ModelSpec};
use vibrofem::system::System;

const PLATE: &str = "box:0.3,0.1,0.02:6,2,1:tet10";

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("vibrofem-export-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Lower triangle of a Matrix Market file as (row, col) → value (0-based).
fn read_mtx(path: &std::path::Path) -> (usize, std::collections::BTreeMap<(usize, usize), f64>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('%'));
    let head: Vec<usize> = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    let mut m = std::collections::BTreeMap::new();
    for l in lines {
        let f: Vec<&str> = l.split_whitespace().collect();
        let (i, j): (usize, usize) = (f[0].parse().unwrap(), f[1].parse().unwrap());
        assert!(
            i >= j,
            "upper-triangle entry ({i}, {j}) in a symmetric Matrix Market file"
        );
        m.insert((i - 1, j - 1), f[2].parse::<f64>().unwrap());
    }
    assert_eq!(m.len(), head[2], "entry count of the header");
    (head[0], m)
}

#[test]
fn export_writes_matrices_that_read_back_exactly() {
    let dir = tmp("plate");
    let (code, out, err) = run(bin().args(["export", PLATE, "--fix", "xmin", "-o"]).arg(&dir));
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("free DOFs"), "{out}");
    // The same model assembled in-process: the reference.
    let mesh = source::load(PLATE, 1.0).unwrap();
    let spec = ModelSpec {
        fixes: vec![("xmin".into(), vibrofem::dof::TRANSLATIONS)],
        ..Default::default()
    };
    let sys = System::assemble_only(Model::build(&mesh, &spec, PLATE).unwrap(), PLATE).unwrap();
    // M is held without its zeros; the files carry it on K's pattern.
    let m_full = sys.m().unwrap().on_pattern(sys.k().pattern.clone());
    for (name, a) in [("K", sys.k()), ("M", &m_full)] {
        let (n, m) = read_mtx(&dir.join(format!("{name}.mtx")));
        assert_eq!(n, sys.n_free());
        let p = &a.pattern;
        let mut lower = 0;
        for j in 0..p.n {
            for q in p.col_ptr[j]..p.col_ptr[j + 1] {
                let i = p.row_idx[q] as usize;
                if i >= j {
                    lower += 1;
                    // Shortest round-trip formatting: the values read back bit for bit.
                    assert_eq!(m[&(i, j)].to_bits(), a.values[q].to_bits(), "{name}[{i},{j}]");
                }
            }
        }
        assert_eq!(lower, m.len());
        // PETSc binary: big-endian header, row lengths, columns, values (both triangles).
        let b = std::fs::read(dir.join(format!("{name}.petsc"))).unwrap();
        let int = |k: usize| i32::from_be_bytes(b[4 * k..4 * k + 4].try_into().unwrap()) as usize;
        assert_eq!(int(0), vibrofem::io::matrix::PETSC_MAT_CLASSID as usize);
        assert_eq!((int(1), int(2), int(3)), (p.n, p.n, p.nnz()));
        let vals = 16 + 4 * (p.n + p.nnz());
        assert_eq!(b.len(), vals + 8 * p.nnz());
        for (q, v) in a.values.iter().enumerate() {
            let x = f64::from_be_bytes(b[vals + 8 * q..vals + 8 * q + 8].try_into().unwrap());
            assert_eq!(x.to_bits(), v.to_bits());
        }
        for k in 0..p.nnz() {
            assert_eq!(int(4 + p.n + k), p.row_idx[k] as usize);
        }
    }
    let csv = std::fs::read_to_string(dir.join("dofs.csv")).unwrap();
    assert_eq!(csv.lines().count(), sys.n_free() + 1);
    // Row i names the node and component of equation i.
    let row = csv.lines().nth(5).unwrap();
    let (a, c) = sys.dofs().node_comp_of(4);
    let f: Vec<&str> = row.split(',').collect();
    assert_eq!(
        (f[0], f[1], f[3]),
        ("4", a.to_string().as_str(), vibrofem::dof::COMPONENT_NAMES[c])
    );
    let json = std::fs::read_to_string(dir.join("model.json")).unwrap();
    assert!(json.contains(&format!("\"dofs\": {}", sys.n_free())), "{json}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn export_refuses_a_bad_format_and_an_unknown_group() {
    let dir = tmp("bad");
    let (code, _, err) = run(bin().args(["export", PLATE, "--format", "hdf5", "-o"]).arg(&dir));
    assert_eq!(code, 1);
    assert!(err.contains("--format 'hdf5'"), "{err}");
    let (code, _, err) = run(bin().args(["export", PLATE, "--fix", "base", "-o"]).arg(&dir));
    assert_eq!(code, 1);
    assert!(err.contains("unknown group 'base'"), "{err}");
    // The SLEPc job's values are checked whatever the format, and with Matrix Market alone
    // (no job written) a band or shift is refused rather than passed over.
    let (code, _, err) = run(bin()
        .args(["export", PLATE, "--format", "mtx", "--shift", "nan", "-o"])
        .arg(&dir));
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--shift"), "{err}");
    let (code, _, err) = run(bin()
        .args(["export", PLATE, "--format", "mtx", "--band", "1", "500", "-o"])
        .arg(&dir));
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--format mtx writes none"), "{err}");
}

/// model.json lists every file the export wrote, the SLEPc job's too.
#[test]
fn the_summary_lists_the_slepc_job() {
    let dir = tmp("job");
    let (code, _, err) = run(bin().args(["export", PLATE, "--format", "petsc", "-o"]).arg(&dir));
    assert_eq!(code, 0, "{err}");
    let json = std::fs::read_to_string(dir.join("model.json")).unwrap();
    for f in ["K.petsc", "M.petsc", "dofs.csv", "params.json", "slepc_modes.py"] {
        assert!(
            json.contains(&format!("\"{f}\"")) && dir.join(f).is_file(),
            "{f}: {json}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_missing_slepc_or_mpi_is_exit_5_naming_the_packages() {
    let (code, _, err) = run(bin()
        .args(["modes", PLATE, "--engine", "slepc", "--ranks", "2"])
        .env("VIBROFEM_SLEPC_PYTHON", "/nonexistent/python3"));
    assert_eq!(code, 5, "{err}");
    assert!(
        err.contains("SLEPc engine") && err.contains("python3-slepc4py") && err.contains("openmpi-bin"),
        "{err}"
    );
    // With Python found (or not), a missing mpirun is named too, before any work is staged.
    let (code, _, err) = run(bin()
        .args(["modes", PLATE, "--engine", "slepc"])
        .env("VIBROFEM_MPIRUN", "/nonexistent/mpirun"));
    assert_eq!(code, 5, "{err}");
    assert!(err.contains("openmpi-bin"), "{err}");
}

#[test]
fn engine_options_are_checked() {
    let (code, _, err) = run(bin().args(["modes", PLATE, "--engine", "arpack"]));
    assert_eq!(code, 1);
    assert!(err.contains("--engine 'arpack'"), "{err}");
    let (code, _, err) = run(bin().args(["modes", PLATE, "--ranks", "4"]));
    assert_eq!(code, 1);
    assert!(err.contains("--engine slepc"), "{err}");
    // Scenes: the same two keys, checked with the file, line and key.
    let dir = tmp("scene");
    std::fs::create_dir_all(&dir).unwrap();
    for (body, want) in [
        ("engine = \"arpack\"", "'engine' must be \"native\" or \"slepc\""),
        ("ranks = 2", "'ranks' applies to engine = \"slepc\""),
        ("engine = \"slepc\"\nranks = 0", "'ranks' must be at least 1"),
    ] {
        let p = dir.join("s.toml");
        std::fs::write(
            &p,
            format!("[scene]\nversion = 1\n[mesh]\ngenerator = \"{PLATE}\"\n[modal]\nmodes = 4\n{body}\n[[part]]\ngroup = \"volume\"\nformulation = \"solid\"\n"),
        )
        .unwrap();
        let (code, _, err) = run(bin().arg("run").arg(&p).arg("-o").arg(dir.join("out")));
        assert_eq!(code, 1, "{body}: {err}");
        assert!(err.contains(want) && err.contains("s.toml"), "{body}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn slepc_results_are_imported_only_for_the_exported_model() {
    let dir = tmp("import");
    let (code, _, err) = run(bin()
        .args(["export", PLATE, "--format", "petsc", "--modes", "8", "-o"])
        .arg(&dir));
    assert_eq!(code, 0, "{err}");
    let params = std::fs::read_to_string(dir.join("params.json")).unwrap();
    assert!(
        params.contains("\"nev\": 8") && params.contains("\"sigma\""),
        "{params}"
    );
    assert!(
        std::fs::read_to_string(dir.join("slepc_modes.py"))
            .unwrap()
            .contains("Krylov")
    );
    // Other model options (a fixed face) make another K: refused before reading any result.
    let (code, _, err) = run(bin()
        .args(["modes", PLATE, "--fix", "xmin", "--slepc-import"])
        .arg(&dir));
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("computed for another model"), "{err}");
    // The same model without results yet: the missing file is named.
    let (code, _, err) = run(bin().args(["modes", PLATE, "--slepc-import"]).arg(&dir));
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("slepc.json"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
