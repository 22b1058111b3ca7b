//! gmsh as a subprocess: find it, and mesh a `.geo` geometry at one element size and order
//! within a time limit (for `vibrofem converge PART.geo`, [`super::converge::run_user`]).
//!
//! gmsh is found, in this order, as: the path given (`--gmsh`, else the environment variable
//! `VIBROFEM_GMSH`), the `gmsh` executable on `PATH`, a `python3` or `python` on `PATH` that
//! imports the `gmsh` module (the PyPI wheel, `pip install gmsh`). A given path whose file name
//! starts with `python` is used as a Python interpreter with the `gmsh` module, any other as the
//! gmsh executable.
//!
//! Each level is meshed by a small driver script in a work folder: it sets the parser constant
//! `size` to the level's size, includes the part's `.geo` (a part that declares
//! `DefineConstant[ size = … ];` gets the level's size, e.g. for transfinite counts), then sets
//! `Mesh.MeshSizeMax` to the size (so it overrides the part's own), `Mesh.ElementOrder` to the
//! order with `Mesh.SecondOrderIncomplete = 1` (hex20 and wedge15 at order 2, not hex27), one
//! thread, and meshes in 3D and saves MSH 4.1.

use crate::{Error, Result};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Environment variable naming the gmsh executable or a Python with the gmsh module.
pub const GMSH_ENV: &str = "VIBROFEM_GMSH";

/// How gmsh is run.
#[derive(Clone, Debug, PartialEq)]
pub enum Gmsh {
    /// The gmsh executable (`gmsh driver.geo -`).
    Exe(PathBuf),
    /// A Python interpreter with the `gmsh` module (`python -c 'gmsh.open(driver.geo)'`).
    Python(PathBuf),
}

/// What a finished subprocess gave: exit success, stdout and stderr, or the time limit hit.
struct Output {
    success: bool,
    text: String,
    timed_out: bool,
}

/// Run `cmd` with a time limit, collecting stdout and stderr (read on threads, so a chatty
/// child cannot block on a full pipe); the child is killed when the limit passes.
fn run_limited(mut cmd: Command, limit: Duration) -> std::io::Result<Output> {
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    let reader = |r: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut s = String::new();
            if let Some(mut r) = r {
                let mut buf = Vec::new();
                let _ = r.read_to_end(&mut buf);
                s = String::from_utf8_lossy(&buf).into_owned();
            }
            s
        })
    };
    let out = reader(child.stdout.take().map(|s| Box::new(s) as Box<dyn Read + Send>));
    let err = reader(child.stderr.take().map(|s| Box::new(s) as Box<dyn Read + Send>));
    let start = Instant::now();
    let (status, timed_out) = loop {
        if let Some(s) = child.try_wait()? {
            break (Some(s), false);
        }
        if start.elapsed() >= limit {
            let _ = child.kill();
            let _ = child.wait();
            break (None, true);
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut text = out.join().unwrap_or_default();
    text.push_str(&err.join().unwrap_or_default());
    Ok(Output {
        success: status.is_some_and(|s| s.success()),
        text,
        timed_out,
    })
}

/// The first `n` lines of gmsh's output that report an error or a warning, joined.
fn gmsh_messages(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| {
            (l.starts_with("Error") || l.starts_with("Warning") || l.contains("rror:"))
                && !l.contains("----")
                && !l.contains("error summary")
                && !l.contains("Check the full log")
                && !l.ends_with(" errors")
                && !l.ends_with(" warnings")
        })
        .collect();
    if lines.is_empty() {
        let last: Vec<&str> = text.lines().rev().filter(|l| !l.trim().is_empty()).take(3).collect();
        return last.into_iter().rev().collect::<Vec<_>>().join("; ");
    }
    lines.into_iter().take(n).collect::<Vec<_>>().join("; ")
}

/// Does this candidate run? Returns the reason it does not.
fn probe(g: &Gmsh) -> std::result::Result<(), String> {
    let (prog, args): (&Path, Vec<&str>) = match g {
        Gmsh::Exe(p) => (p, vec!["-version"]),
        Gmsh::Python(p) => (p, vec!["-c", "import gmsh"]),
    };
    let mut cmd = Command::new(prog);
    cmd.args(&args);
    match run_limited(cmd, Duration::from_secs(60)) {
        Ok(o) if o.success => Ok(()),
        Ok(o) if o.timed_out => Err("did not answer within 60 s".into()),
        Ok(o) => Err(format!("failed: {}", gmsh_messages(&o.text, 2))),
        Err(e) => Err(e.to_string()),
    }
}

/// The candidate for a path given by the user: a Python interpreter if its file name starts
/// with `python`, else the gmsh executable.
fn classify(p: &Path) -> Gmsh {
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    // A relative path is made absolute (symlinks kept: a venv's python is one, and resolving it
    // would leave the venv); a bare name is searched on PATH by the OS.
    let p = &if p.components().count() > 1 {
        std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
    } else {
        p.to_path_buf()
    };
    if name.starts_with("python") {
        Gmsh::Python(p.to_path_buf())
    } else {
        Gmsh::Exe(p.to_path_buf())
    }
}

/// Programs named `name` on `PATH`.
fn on_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join(name)).find(|p| p.is_file())
}

impl Gmsh {
    /// Find gmsh: `given` (the `--gmsh` option) or `VIBROFEM_GMSH`, else `gmsh` on `PATH`, else a
    /// `python3`/`python` on `PATH` with the gmsh module. The error names what was tried.
    pub fn find(given: Option<&Path>) -> Result<Gmsh> {
        let env = std::env::var_os(GMSH_ENV).filter(|v| !v.is_empty()).map(PathBuf::from);
        if let Some((what, p)) = given
            .map(|p| ("--gmsh", p.to_path_buf()))
            .or(env.map(|p| (GMSH_ENV, p)))
        {
            let g = classify(&p);
            return match probe(&g) {
                Ok(()) => Ok(g),
                Err(e) => Err(Error::Engine {
                    engine: "gmsh".into(),
                    msg: format!(
                        "{what} '{}': {} {e}",
                        p.display(),
                        match g {
                            Gmsh::Exe(_) => "as the gmsh executable (`-version`)",
                            Gmsh::Python(_) => "as a Python with the gmsh module (`import gmsh`)",
                        }
                    ),
                }),
            };
        }
        let mut tried = Vec::new();
        let mut candidates = Vec::new();
        match on_path("gmsh") {
            Some(p) => candidates.push(Gmsh::Exe(p)),
            None => tried.push("`gmsh` on PATH: not found".to_string()),
        }
        for py in ["python3", "python"] {
            match on_path(py) {
                Some(p) => candidates.push(Gmsh::Python(p)),
                None => tried.push(format!("`{py}` on PATH: not found")),
            }
        }
        for c in candidates {
            match probe(&c) {
                Ok(()) => return Ok(c),
                Err(e) => tried.push(format!("{}: {e}", c.describe())),
            }
        }
        Err(Error::Engine {
            engine: "gmsh".into(),
            msg: format!(
                "no gmsh found; looked for --gmsh, {GMSH_ENV}, the gmsh executable on PATH and a python3/python \
                 on PATH with the gmsh module ({}). Install it with `pip install gmsh` (or `bash \
                 validation/setup.sh`) and pass --gmsh PATH/TO/python or --gmsh PATH/TO/gmsh",
                tried.join("; ")
            ),
        })
    }

    /// What runs (for messages).
    pub fn describe(&self) -> String {
        match self {
            Gmsh::Exe(p) => format!("gmsh executable {}", p.display()),
            Gmsh::Python(p) => format!("{} with the gmsh module", p.display()),
        }
    }

    /// Mesh `geo` at element size `size` (the geometry's units) and `order` (1 or 2) into
    /// `out` (MSH 4.1), within `limit`. The error text (without the size, which the caller
    /// names) carries gmsh's own messages; on success, gmsh's warnings (empty if none), for the
    /// caller to show when the mesh turns out unusable (an open surface loop gives a volume
    /// gmsh cannot fill, and gmsh only warns).
    pub fn mesh(
        &self,
        geo: &Path,
        size: f64,
        order: usize,
        out: &Path,
        limit: Duration,
    ) -> std::result::Result<String, String> {
        // Absolute paths: gmsh resolves the driver's paths against the driver's folder.
        let geo = std::fs::canonicalize(geo).map_err(|e| format!("{}: {e}", geo.display()))?;
        let out = &std::path::absolute(out).map_err(|e| format!("{}: {e}", out.display()))?;
        let _ = std::fs::remove_file(out);
        let q = |p: &Path| p.display().to_string().replace('\\', "\\\\").replace('"', "\\\"");
        let driver = out.with_extension("driver.geo");
        let text = format!(
            "General.Terminal = 1;\nGeneral.Verbosity = 2;\nGeneral.NumThreads = 1;\nsize = {size:e};\n\
             Include \"{}\";\nMesh.MeshSizeMax = {size:e};\nMesh.ElementOrder = {order};\n\
             Mesh.SecondOrderIncomplete = 1;\nMesh.MshFileVersion = 4.1;\nMesh.Binary = 0;\nMesh 3;\n\
             Save \"{}\";\n",
            q(&geo),
            q(out)
        );
        std::fs::write(&driver, text).map_err(|e| format!("{}: {e}", driver.display()))?;
        let cmd = match self {
            Gmsh::Exe(p) => {
                let mut c = Command::new(p);
                c.arg(&driver).arg("-");
                c
            }
            Gmsh::Python(p) => {
                let mut c = Command::new(p);
                c.arg("-c")
                    .arg(
                        "import sys, gmsh\ngmsh.initialize(readConfigFiles=False)\ntry:\n    gmsh.open(sys.argv[1])\n\
                         finally:\n    gmsh.finalize()\n",
                    )
                    .arg(&driver);
                c
            }
        };
        let o = run_limited(cmd, limit).map_err(|e| format!("could not start the {}: {e}", self.describe()))?;
        let _ = std::fs::remove_file(&driver);
        if o.timed_out {
            return Err(format!(
                "gmsh did not finish within the time limit of {} s (--mesh-timeout)",
                limit.as_secs_f64()
            ));
        }
        if !o.success || o.text.lines().any(|l| l.trim_start().starts_with("Error")) || !out.is_file() {
            return Err(format!("gmsh failed: {}", gmsh_messages(&o.text, 4)));
        }
        Ok(if o.text.contains("Warning") {
            gmsh_messages(&o.text, 4)
        } else {
            String::new()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gmsh_messages_keep_errors_and_drop_the_summary() {
        let t = "Info : x\nWarning : No tetrahedra in region 1\nWarning : ------\nWarning : Mesh generation error \
                 summary\nWarning :     2 warnings\nError : boom\n";
        assert_eq!(gmsh_messages(t, 4), "Warning : No tetrahedra in region 1; Error : boom");
    }

    #[test]
    fn a_python_path_is_a_python() {
        assert!(matches!(
            classify(Path::new("/x/.venv/bin/python3.11")),
            Gmsh::Python(_)
        ));
        assert!(matches!(classify(Path::new("/usr/bin/gmsh")), Gmsh::Exe(_)));
    }
}
