//! `vibrofem._core`: the compiled half of the Python package. The Python half
//! (`pysrc/vibrofem/__init__.py`) turns keyword arguments into vibrofem's option grammar and
//! arrays into scipy matrices; this module holds meshes, models and their assembled systems and
//! returns numpy arrays.
//!
//! It calls the library's documented entry points only: `input::source::load` (meshes),
//! `model::Model` and `system::System` (K, M, the DOF map), `app::engines::Engine` (the modal
//! solve, native or SLEPc, the same switch as the command line's `--engine`),
//! `analysis::statics::run_static` with `app::report::static_report` (statics), `app::harmonic`
//! (harmonic response, with the command line's sweep rules), `app::engines::export` and
//! `app::scene::run` (scene files).
//!
//! Heavy work runs on a worker thread with the interpreter released, while the calling thread
//! checks for signals: Ctrl-C raises `KeyboardInterrupt` at once (the work already started
//! finishes in the background and its result is dropped). A `Model` may be used from several
//! threads: its system is built once, under a lock, and shared read-only by the analyses.

use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray2};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use vibrofem::analysis::modal::{ModalParams, ModalRun, ModalTarget};
use vibrofem::analysis::statics::{StaticOptions, run_static};
use vibrofem::app::engines::{self, Before, Engine, SlepcOptions};
use vibrofem::dof::{COMPONENT_NAMES, NCOMP};
use vibrofem::input::options::{LoadOptions, ModelOptions, length_scale};
use vibrofem::mesh::{CellKind, Mesh};
use vibrofem::model::Model;
use vibrofem::system::{System, SystemOptions};

mod app;

type Array2 = numpy::ndarray::Array2<f64>;
type Array3 = numpy::ndarray::Array3<f64>;

create_exception!(_core, VibrofemError, PyException, "An error reported by vibrofem.");
create_exception!(
    _core,
    InputError,
    VibrofemError,
    "Bad input: a file, mesh, option, material or group (the command line's exit code 1)."
);
create_exception!(
    _core,
    NumericalError,
    VibrofemError,
    "A numerical failure: no convergence, failed verification, singular model (exit code 2)."
);
create_exception!(
    _core,
    OutputError,
    VibrofemError,
    "A result could not be written (exit code 4)."
);
create_exception!(
    _core,
    EngineError,
    VibrofemError,
    "An external engine (SLEPc, MPI) is missing or failed (exit code 5)."
);

/// The command line's option names in the library's messages and the keywords they are in
/// Python (`--band` is `band=`): longest first, so that a prefix never takes a longer name.
const KEYWORDS: &[(&str, &str)] = &[
    ("--group-material", "group_material"),
    ("--length-unit", "length_unit"),
    ("--point-mass", "point_mass"),
    ("--prestress", "prestress"),
    ("--displace", "displace"),
    ("--material", "material"),
    ("--pressure", "pressure"),
    ("--rayleigh", "rayleigh"),
    ("--damping", "damping"),
    ("--gravity", "gravity"),
    ("--couple", "couple"),
    ("--engine", "engine"),
    ("--format", "format"),
    ("--method", "method"),
    ("--spring", "spring"),
    ("--block", "block"),
    ("--force", "force"),
    ("--modes", "n"),
    ("--probe", "probe"),
    ("--ranks", "ranks"),
    ("--shell", "shell"),
    ("--shift", "shift_hz"),
    ("--solid", "solid"),
    ("--sweep", "sweep"),
    ("--band", "band"),
    ("--beam", "beam"),
    ("--freq", "freq"),
    ("--hex8", "hex8"),
    ("--mass", "mass"),
    ("--fix", "fix"),
];

/// `msg` with each command-line option named by its Python keyword.
fn python_keywords(msg: &str) -> String {
    let mut out = String::with_capacity(msg.len());
    let mut rest = msg;
    'scan: while let Some(i) = rest.find("--") {
        out.push_str(&rest[..i]);
        let tail = &rest[i..];
        for (cli, py) in KEYWORDS {
            let after = tail.as_bytes().get(cli.len()).copied();
            if tail.starts_with(cli) && !after.is_some_and(|c| c.is_ascii_alphanumeric() || c == b'-' || c == b'_') {
                out.push_str(py);
                rest = &tail[cli.len()..];
                continue 'scan;
            }
        }
        out.push_str("--");
        rest = &tail[2..];
    }
    out.push_str(rest);
    out
}

/// The exception of a vibrofem error, with the command line's message (its option names as
/// Python keywords).
fn err(e: vibrofem::Error) -> PyErr {
    let msg = python_keywords(&e.to_string());
    match e.exit_code() {
        1 => InputError::new_err(msg),
        2 => NumericalError::new_err(msg),
        4 => OutputError::new_err(msg),
        5 => EngineError::new_err(msg),
        _ => VibrofemError::new_err(msg),
    }
}

fn json_err(e: serde_json::Error) -> PyErr {
    OutputError::new_err(format!("cannot serialise the report: {e}"))
}

fn json_output(e: serde_json::Error) -> vibrofem::Error {
    vibrofem::Error::output("JSON", e)
}

/// How often the calling thread looks for signals while a worker computes.
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// Run `work` on a worker thread with the interpreter released, checking for signals every
/// 50 ms: Ctrl-C raises `KeyboardInterrupt` at once (the worker finishes in the background, its
/// result dropped). Errors map to vibrofem's exceptions; a panic of the worker resumes here.
fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce() -> vibrofem::Result<T> + Send + 'static,
) -> PyResult<T> {
    let (tx, mut rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("vibrofem".into())
        .spawn(move || {
            let _ = tx.send(std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)));
        })
        .map_err(|e| VibrofemError::new_err(format!("cannot start a worker thread: {e}")))?;
    loop {
        let (got, back) = py.detach(move || (rx.recv_timeout(SIGNAL_POLL), rx));
        rx = back;
        match got {
            Ok(Ok(result)) => {
                // A Ctrl-C that came with the last poll raises before any array is made.
                py.check_signals()?;
                return result.map_err(err);
            }
            Ok(Err(panic)) => std::panic::resume_unwind(panic),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => py.check_signals()?,
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(VibrofemError::new_err("the worker thread ended without a result"));
            }
        }
    }
}

/// A mesh in SI units (read from a gmsh file or a generator).
#[pyclass(name = "Mesh", module = "vibrofem._core", frozen)]
struct PyMesh {
    mesh: Arc<Mesh>,
    source: String,
}

#[pymethods]
impl PyMesh {
    /// The file or generator it was read from.
    #[getter]
    fn source(&self) -> String {
        self.source.clone()
    }

    /// Node coordinates, m (n × 3).
    #[getter]
    fn nodes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let flat: Vec<f64> = self.mesh.nodes.iter().flat_map(|x| x.iter().copied()).collect();
        Array2::from_shape_vec((self.mesh.nodes.len(), 3), flat)
            .expect("n × 3")
            .into_pyarray(py)
    }

    /// The file's tag of each node.
    #[getter]
    fn node_tags<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        self.mesh.node_tags.clone().into_pyarray(py)
    }

    /// Physical groups: (name, dimension, tag, number of cells, number of nodes).
    #[getter]
    fn group_list(&self) -> Vec<(String, u8, i32, usize, usize)> {
        self.mesh
            .groups
            .iter()
            .map(|g| {
                (
                    g.name.clone(),
                    g.dim,
                    g.tag,
                    g.cells.len(),
                    self.mesh.group_nodes(g).len(),
                )
            })
            .collect()
    }

    /// Per group: (name, dimension, tag, [(cell kind, indices in that kind's cells)]).
    #[getter]
    #[allow(clippy::type_complexity)]
    fn group_cells(&self) -> Vec<(String, u8, i32, Vec<(String, Vec<u32>)>)> {
        let m = &self.mesh;
        m.groups
            .iter()
            .map(|g| {
                let mut parts: Vec<(String, Vec<u32>)> = Vec::new();
                for c in &g.cells {
                    let kind = m.blocks[c.block as usize].kind.name();
                    match parts.iter_mut().find(|(k, _)| k == kind) {
                        Some((_, v)) => v.push(c.index),
                        None => parts.push((kind.to_string(), vec![c.index])),
                    }
                }
                (g.name.clone(), g.dim, g.tag, parts)
            })
            .collect()
    }

    /// Cell kinds present and their counts.
    #[getter]
    fn cell_kinds(&self) -> Vec<(String, usize)> {
        self.mesh
            .blocks
            .iter()
            .map(|b| (b.kind.name().to_string(), b.len()))
            .collect()
    }

    /// Connectivity of the cells of one kind (0-based node indices, gmsh node order), c × k.
    fn cells<'py>(&self, py: Python<'py>, kind: &str) -> PyResult<Bound<'py, PyArray2<u32>>> {
        let Some(b) = self.mesh.blocks.iter().find(|b| b.kind.name() == kind) else {
            let have: Vec<&str> = self.mesh.blocks.iter().map(|b| b.kind.name()).collect();
            return Err(InputError::new_err(format!(
                "{}: no {kind} cells (the mesh has: {})",
                self.source,
                have.join(", ")
            )));
        };
        let k = b.kind.n_nodes();
        Ok(numpy::ndarray::Array2::from_shape_vec((b.len(), k), b.conn.clone())
            .expect("c × k")
            .into_pyarray(py))
    }

    /// The file's element tags of the cells of one kind.
    fn cell_tags<'py>(&self, py: Python<'py>, kind: &str) -> PyResult<Bound<'py, PyArray1<u64>>> {
        match self.mesh.blocks.iter().find(|b| b.kind.name() == kind) {
            Some(b) => Ok(b.tags.clone().into_pyarray(py)),
            None => Err(InputError::new_err(format!("{}: no {kind} cells", self.source))),
        }
    }

    /// The nodes of a group (0-based indices, sorted).
    fn group_nodes<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray1<u32>>> {
        let g = self.mesh.group(name).map_err(err)?;
        Ok(self.mesh.group_nodes(g).into_pyarray(py))
    }

    fn __repr__(&self) -> String {
        let kinds: Vec<String> = self
            .mesh
            .blocks
            .iter()
            .map(|b| format!("{} {}", b.len(), b.kind.name()))
            .collect();
        format!(
            "<vibrofem Mesh '{}': {} nodes, {}; groups {}>",
            self.source,
            self.mesh.nodes.len(),
            if kinds.is_empty() {
                "no cells".to_string()
            } else {
                kinds.join(", ")
            },
            self.mesh.group_names()
        )
    }
}

/// Read a gmsh mesh (MSH 2.2 or 4.1) or generate one (`box:…`, `helix:…`, `sandwich:…`,
/// `ibeam-*:…`), scaling coordinates from `length_unit` (m, cm or mm) to metres. A path is
/// text here: the Python half decodes bytes and path objects with `os.fsdecode`.
#[pyfunction]
#[pyo3(signature = (source, length_unit = "m"))]
fn read_mesh(py: Python<'_>, source: &str, length_unit: &str) -> PyResult<PyMesh> {
    let scale = length_scale(length_unit).map_err(err)?;
    let src = source.to_string();
    let mesh = interruptible(py, move || vibrofem::input::source::load(&src, scale))?;
    Ok(PyMesh {
        mesh: Arc::new(mesh),
        source: source.to_string(),
    })
}

/// One cell block given from Python: its kind name and its connectivity (c × k, 0-based).
type BlockIn<'py> = (String, PyReadonlyArray2<'py, i64>);
/// One group given from Python: name, dimension, tag and its cells as (block index, cell indices).
type GroupIn = (String, u8, i32, Vec<(usize, Vec<i64>)>);

/// Node coordinates from an n × 3 array, every one finite.
fn nodes_of(nodes: &PyReadonlyArray2<'_, f64>) -> vibrofem::Result<Vec<[f64; 3]>> {
    let a = nodes.as_array();
    if a.ncols() != 3 {
        return Err(vibrofem::Error::param(
            "points",
            format!("expected n × 3 coordinates, got {} columns", a.ncols()),
        ));
    }
    let mut out = Vec::with_capacity(a.nrows());
    for (i, r) in a.rows().into_iter().enumerate() {
        let x = [r[0], r[1], r[2]];
        if !x.iter().all(|v| v.is_finite()) {
            return Err(vibrofem::Error::node(
                i as u64 + 1,
                format!("coordinates {x:?} are not finite"),
            ));
        }
        out.push(x);
    }
    Ok(out)
}

/// A mesh from arrays: blocks of one kind each (no kind twice), node indices in range, group
/// cells in range and of the group's dimension. Node tags are 1..n, cell tags 1.. through the
/// blocks in order (what messages name).
fn mesh_of(
    nodes: Vec<[f64; 3]>,
    blocks: Vec<(String, Vec<u32>, usize)>,
    groups: Vec<GroupIn>,
) -> vibrofem::Result<Mesh> {
    use vibrofem::Error;
    use vibrofem::mesh::{CellBlock, CellRef, Group};
    let n = nodes.len();
    let mut mesh = Mesh {
        node_tags: (1..=n as u64).collect(),
        nodes,
        ..Default::default()
    };
    let mut next_tag = 1u64;
    for (name, conn, k) in blocks {
        let Some(kind) = CellKind::ALL.iter().copied().find(|c| c.name() == name) else {
            let known: Vec<&str> = CellKind::ALL.iter().map(|c| c.name()).collect();
            return Err(Error::param(
                "cells",
                format!("unknown cell kind '{name}' (known: {})", known.join(", ")),
            ));
        };
        if k != kind.n_nodes() {
            return Err(Error::param(
                "cells",
                format!("{name} cells have {} nodes, got {k} columns", kind.n_nodes()),
            ));
        }
        if mesh.blocks.iter().any(|b| b.kind == kind) {
            return Err(Error::param(
                "cells",
                format!("two blocks of {name} cells: give each kind once"),
            ));
        }
        let mut b = CellBlock::new(kind);
        for cell in conn.chunks(k.max(1)) {
            if let Some(&a) = cell.iter().find(|&&a| a as usize >= n) {
                return Err(Error::element(
                    next_tag,
                    format!("{name} cell refers to node index {a}, the mesh has {n} nodes"),
                ));
            }
            b.push(cell, next_tag);
            next_tag += 1;
        }
        mesh.blocks.push(b);
    }
    for (name, dim, tag, parts) in groups {
        let mut cells = Vec::new();
        for (bi, idx) in parts {
            let Some(b) = mesh.blocks.get(bi) else {
                return Err(Error::group(
                    &name,
                    format!("block {bi} does not exist ({} blocks)", mesh.blocks.len()),
                ));
            };
            if b.kind.dim() != dim as usize {
                return Err(Error::group(
                    &name,
                    format!("a group of dimension {dim} cannot hold {} cells", b.kind.name()),
                ));
            }
            for i in idx {
                if i < 0 || i as usize >= b.len() {
                    return Err(Error::group(
                        &name,
                        format!(
                            "cell {i} of the {} block is out of range (0..{})",
                            b.kind.name(),
                            b.len()
                        ),
                    ));
                }
                cells.push(CellRef {
                    block: bi as u32,
                    index: i as u32,
                });
            }
        }
        cells.sort_unstable();
        cells.dedup();
        mesh.groups.push(Group { name, dim, tag, cells });
    }
    Ok(mesh)
}

/// A mesh from arrays in metres (what `Mesh.from_arrays` and a meshio mesh give): `points` n × 3,
/// `blocks` [(kind, connectivity c × k, 0-based, gmsh node order)], `groups` [(name, dimension,
/// tag, [(block index, cell indices)])]. Bad input names the block, the cell or the group.
#[pyfunction]
#[pyo3(signature = (points, blocks, groups = vec![], source = "<arrays>".to_string()))]
fn mesh_from_arrays(
    points: PyReadonlyArray2<'_, f64>,
    blocks: Vec<BlockIn<'_>>,
    groups: Vec<GroupIn>,
    source: String,
) -> PyResult<PyMesh> {
    let nodes = nodes_of(&points).map_err(err)?;
    let mut flat = Vec::with_capacity(blocks.len());
    for (name, conn) in &blocks {
        let a = conn.as_array();
        let mut v = Vec::with_capacity(a.len());
        for &x in a.iter() {
            if x < 0 || x > u32::MAX as i64 {
                return Err(err(vibrofem::Error::param(
                    "cells",
                    format!("{name} cells: node index {x} is out of range"),
                )));
            }
            v.push(x as u32);
        }
        flat.push((name.clone(), v, a.ncols()));
    }
    let mesh = mesh_of(nodes, flat, groups).map_err(err)?;
    Ok(PyMesh {
        mesh: Arc::new(mesh),
        source,
    })
}

/// A model: a mesh with materials, supports, couplings, parts, in vibrofem's option grammar.
/// Frozen (no mutable borrow): several threads may use one model; the system is built once,
/// by the first that needs it, under a lock.
#[pyclass(name = "Model", module = "vibrofem._core", frozen)]
struct PyModel {
    mesh: Arc<Mesh>,
    source: String,
    options: ModelOptions,
    system: Arc<Mutex<Option<Arc<System>>>>,
}

/// The arrays of a modal solution: report JSON, eigenvalues, free-DOF vectors, nodal shapes.
struct ModesOut {
    json: String,
    lambda: Vec<f64>,
    vectors: Array2,
    shapes: Array3,
}

/// The report and arrays of a modal run: the vectors over the free DOFs and the shapes with
/// rotations at the mesh nodes (n_nodes × 6 × k).
fn modes_out(sys: &System, run: ModalRun) -> vibrofem::Result<ModesOut> {
    let json = serde_json::to_string(&run.report).map_err(json_output)?;
    let nf = run.vectors.nrows();
    let k = run.vectors.ncols();
    let vectors = Array2::from_shape_fn((nf, k), |(i, j)| run.vectors[(i, j)]);
    let model = sys.model();
    let n_mesh = model.n_mesh_nodes;
    let mut shapes = Array3::zeros((n_mesh, 6, k));
    for j in 0..k {
        let col: Vec<f64> = (0..nf).map(|i| run.vectors[(i, j)]).collect();
        let full = model.dofs.full(&col);
        for a in 0..n_mesh {
            for c in 0..6 {
                shapes[(a, c, j)] = full[NCOMP * a + c];
            }
        }
    }
    Ok(ModesOut {
        json,
        lambda: run.lambda,
        vectors,
        shapes,
    })
}

/// A static run's report, displacements at the mesh nodes (n × 6, flat) and nodal von Mises
/// stress of the solids.
fn static_out(
    mesh: &Mesh,
    source: &str,
    opts: &ModelOptions,
    loads: LoadOptions,
) -> vibrofem::Result<(String, Vec<f64>, Vec<f64>)> {
    let mut spec = opts.spec()?;
    let case = loads.apply(&mut spec)?;
    let run = run_static(
        mesh,
        source,
        &StaticOptions {
            spec,
            cases: vec![case],
        },
    )?;
    let mut stresses = vibrofem::app::report::case_stresses(mesh, &run)?;
    let report = vibrofem::app::report::static_report(mesh, source, &run, &stresses)?;
    let json = serde_json::to_string(&report).map_err(json_output)?;
    let n = run.model.n_mesh_nodes;
    let mut u6 = vec![0.0; 6 * n];
    for a in 0..n {
        u6[6 * a..6 * a + 6].copy_from_slice(&run.u[0][NCOMP * a..NCOMP * a + 6]);
    }
    // The solids' nodal von Mises of the one load case, recovered with the report.
    let von_mises = std::mem::take(&mut stresses[0].solids.von_mises);
    Ok((json, u6, von_mises))
}

/// A harmonic run's report and the real and imaginary displacements (frequencies × n_nodes ×
/// 3, flat).
fn harmonic_out(
    sys: &System,
    mesh: &Mesh,
    req: &vibrofem::app::harmonic::HarmonicRequest,
) -> vibrofem::Result<(String, Vec<f64>, Vec<f64>)> {
    let run = vibrofem::app::harmonic::run(sys, mesh, req)?;
    let json = serde_json::to_string(&run.report).map_err(json_output)?;
    let n = mesh.nodes.len();
    let (mut re, mut im) = (Vec::with_capacity(run.nodal.len() * n * 3), Vec::new());
    for nodal in &run.nodal {
        for v in nodal.iter().take(n) {
            for c in &v[..3] {
                re.push(c.re);
                im.push(c.im);
            }
        }
    }
    Ok((json, re, im))
}

/// The frequencies of a harmonic request: one, or a sweep under the command line's rules
/// (0 ≤ f0 < f1, 2 ≤ n ≤ its cap).
fn harmonic_freqs(freq: Option<f64>, sweep: Option<(f64, f64, usize)>) -> PyResult<Vec<f64>> {
    match (freq, sweep) {
        (Some(f), None) => Ok(vec![f]),
        (None, Some((f0, f1, n))) => vibrofem::app::harmonic::sweep_frequencies(f0, f1, n).map_err(err),
        _ => Err(InputError::new_err(
            "harmonic: give freq=Hz or sweep=(f0, f1, n), one of them",
        )),
    }
}

type Csr<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i64>>,
);

fn csr<'py>(py: Python<'py>, a: &vibrofem::linalg::sparse::SymMatrix) -> Csr<'py> {
    // Both triangles stored: the CSC arrays of a symmetric matrix are its CSR arrays.
    let p = &a.pattern;
    (
        a.values.clone().into_pyarray(py),
        p.row_idx.iter().map(|&i| i as i64).collect::<Vec<_>>().into_pyarray(py),
        p.col_ptr.iter().map(|&i| i as i64).collect::<Vec<_>>().into_pyarray(py),
    )
}

impl PyModel {
    /// A task that returns the system `engine` solves: the model's shared one (built here on
    /// first use, one thread at a time), or for SLEPc, before that exists, an assembly of K
    /// and M only (not kept: the factorisation it leaves out is SLEPc's).
    fn system_task(&self, engine: Engine) -> impl FnOnce() -> vibrofem::Result<Arc<System>> + Send + 'static {
        let (mesh, opts, source, slot) = (
            self.mesh.clone(),
            self.options.clone(),
            self.source.clone(),
            self.system.clone(),
        );
        move || {
            let mut slot = slot.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            if let Some(s) = slot.as_ref() {
                return Ok(s.clone());
            }
            let model = Model::build(&mesh, &opts.spec()?, &source)?;
            let sys = Arc::new(engine.system(model, &SystemOptions::default(), &source)?);
            if engine.factorises_here() {
                *slot = Some(sys.clone());
            }
            Ok(sys)
        }
    }

    /// The assembled system (built on first use, then shared by every analysis).
    fn system(&self, py: Python<'_>) -> PyResult<Arc<System>> {
        interruptible(py, self.system_task(Engine::Native))
    }
}

#[pymethods]
impl PyModel {
    #[new]
    #[pyo3(signature = (mesh, material = "steel".to_string(), group_material = vec![], fix = vec![],
        couple = vec![], point_mass = vec![], spring = vec![], mass = "consistent".to_string(),
        solid = vec![], shell = vec![], beam = vec![], hex8 = "standard".to_string()))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        mesh: &PyMesh,
        material: String,
        group_material: Vec<String>,
        fix: Vec<String>,
        couple: Vec<String>,
        point_mass: Vec<String>,
        spring: Vec<String>,
        mass: String,
        solid: Vec<String>,
        shell: Vec<String>,
        beam: Vec<String>,
        hex8: String,
    ) -> PyResult<Self> {
        let options = ModelOptions {
            material,
            group_material,
            fix,
            couple,
            point_mass,
            spring,
            mass,
            solid,
            shell,
            beam,
            hex8,
            length_unit: "m".into(),
        };
        // Check the grammar and the group names now (a bad option fails at construction, as on
        // the command line, not at the first analysis).
        let spec = options.spec().map_err(err)?;
        for g in spec.group_names() {
            mesh.mesh.group(g).map_err(err)?;
        }
        Ok(PyModel {
            mesh: mesh.mesh.clone(),
            source: mesh.source.clone(),
            options,
            system: Arc::new(Mutex::new(None)),
        })
    }

    /// Assemble (once) and return K and M over the free DOFs as CSR arrays
    /// `(data, indices, indptr)` each, and the dimension.
    fn assemble<'py>(&self, py: Python<'py>) -> PyResult<(Csr<'py>, Csr<'py>, usize)> {
        let sys = self.system(py)?;
        let m = sys.m().map_err(err)?;
        Ok((csr(py, sys.k()), csr(py, m), sys.n_free()))
    }

    /// Per free DOF: the node (0-based mesh index; reference nodes of couplings follow the mesh
    /// nodes) and the component (0..6: ux, uy, uz, rx, ry, rz, w).
    fn dof_table<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<i64>>)> {
        let sys = self.system(py)?;
        let d = sys.dofs();
        let (mut node, mut comp) = (Vec::with_capacity(d.n_free), Vec::with_capacity(d.n_free));
        for eq in 0..d.n_free {
            let (a, c) = d.node_comp_of(eq);
            node.push(a as i64);
            comp.push(c as i64);
        }
        Ok((node.into_pyarray(py), comp.into_pyarray(py)))
    }

    /// Number of mesh nodes and of all nodes (reference nodes included).
    fn node_counts(&self, py: Python<'_>) -> PyResult<(usize, usize)> {
        let sys = self.system(py)?;
        Ok((sys.model().n_mesh_nodes, sys.model().nodes.len()))
    }

    /// Volume (m³), mass (kg, point masses included) and the model's notes.
    fn summary(&self, py: Python<'_>) -> PyResult<(f64, f64, Vec<String>)> {
        let sys = self.system(py)?;
        let model = sys.model();
        let (v, m) = model.volume_and_mass().map_err(err)?;
        Ok((v, m + model.discrete_mass(), model.notes.clone()))
    }

    /// Modal analysis with `engine` (`native` or `slepc` on `ranks` MPI ranks: the command
    /// line's `--engine` switch). Returns (report JSON, eigenvalues, free-DOF vectors n × k,
    /// shapes at the mesh nodes n_nodes × 6 × k).
    /// With `prestress` (loads in the command line's grammar: `force`, `pressure`, `gravity`,
    /// `displace`), the modes of the preloaded structure, (K + K_σ)x = λMx (native engine).
    #[pyo3(signature = (n = None, band = None, shift_hz = None, block = 6, engine = "native", ranks = 1,
        prestress = None))]
    #[allow(clippy::type_complexity, clippy::too_many_arguments)]
    fn modes<'py>(
        &self,
        py: Python<'py>,
        n: Option<usize>,
        band: Option<(f64, f64)>,
        shift_hz: Option<f64>,
        block: usize,
        engine: &str,
        ranks: usize,
        prestress: Option<(Vec<String>, Vec<String>, Option<String>, Vec<String>)>,
    ) -> PyResult<(
        String,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray3<f64>>,
    )> {
        let target = match (band, n) {
            (Some(_), Some(_)) => return Err(InputError::new_err("give n or band, not both")),
            (Some((lo, hi)), None) => ModalTarget::Band(lo, hi),
            (None, Some(0)) => return Err(InputError::new_err("n must be at least 1")),
            (None, Some(k)) => ModalTarget::Modes(k),
            (None, None) => ModalTarget::Modes(12),
        };
        if block == 0 {
            return Err(InputError::new_err("block must be at least 1"));
        }
        let params = ModalParams {
            target,
            shift_hz,
            block,
            ..Default::default()
        };
        let engine = Engine::parse(
            engine,
            SlepcOptions {
                ranks,
                ..Default::default()
            },
        )
        .map_err(err)?;
        let out = if let Some((force, pressure, gravity, displace)) = prestress {
            if !matches!(engine, Engine::Native) {
                return Err(InputError::new_err(
                    "prestressed modes are solved by engine='native' only",
                ));
            }
            let loads = LoadOptions {
                force,
                pressure,
                gravity,
                displace,
            };
            let (mesh, opts, source) = (self.mesh.clone(), self.options.clone(), self.source.clone());
            interruptible(py, move || {
                let mut spec = opts.spec()?;
                let case = loads.apply(&mut spec)?;
                let model = Model::build(&mesh, &spec, &source)?;
                let mut sys = System::build(model, &SystemOptions::default(), &source)?;
                vibrofem::analysis::prestress::prestress_system(&mut sys, &mesh, &case)?;
                let run = vibrofem::analysis::modal::solve(&sys, &params)?;
                modes_out(&sys, run)
            })?
        } else {
            let system = self.system_task(engine.clone());
            interruptible(py, move || {
                let sys = system()?;
                let run = engine.solve(&sys, &params, Before::default())?;
                modes_out(&sys, run)
            })?
        };
        Ok((
            out.json,
            out.lambda.into_pyarray(py),
            out.vectors.into_pyarray(py),
            out.shapes.into_pyarray(py),
        ))
    }

    /// Linear buckling (see `vibrofem buckling`) under one load case in the command line's
    /// grammar: the `n` lowest positive load factors. Returns (report JSON, load factors,
    /// shapes at the mesh nodes n_nodes × 3 × k, largest translation 1).
    #[pyo3(signature = (n = 4, force = vec![], pressure = vec![], gravity = None, displace = vec![]))]
    #[allow(clippy::type_complexity)]
    fn buckling<'py>(
        &self,
        py: Python<'py>,
        n: usize,
        force: Vec<String>,
        pressure: Vec<String>,
        gravity: Option<String>,
        displace: Vec<String>,
    ) -> PyResult<(String, Bound<'py, PyArray1<f64>>, Bound<'py, PyArray3<f64>>)> {
        if n == 0 {
            return Err(InputError::new_err("n must be at least 1"));
        }
        let loads = LoadOptions {
            force,
            pressure,
            gravity,
            displace,
        };
        let (mesh, opts, source) = (self.mesh.clone(), self.options.clone(), self.source.clone());
        let run = interruptible(py, move || {
            let mut spec = opts.spec()?;
            let case = loads.apply(&mut spec)?;
            let bo = vibrofem::analysis::buckling::BucklingOptions {
                spec,
                modes: n,
                ..Default::default()
            };
            vibrofem::analysis::buckling::run_buckling(&mesh, &source, &bo, &case, 0.0)
        })?;
        let json = serde_json::to_string(&run.report).map_err(json_output).map_err(err)?;
        let k = run.shapes.len();
        let nn = run.shapes.first().map_or(0, |s| s.len() / 3);
        let shapes = Array3::from_shape_fn((nn, 3, k), |(a, c, j)| run.shapes[j][3 * a + c]);
        Ok((
            json,
            run.report.load_factors.clone().into_pyarray(py),
            shapes.into_pyarray(py),
        ))
    }

    /// Linear static analysis with loads in the command line's grammar. Returns (report JSON,
    /// displacements n_nodes × 6, nodal von Mises stress of the solids, Pa).
    #[pyo3(signature = (force = vec![], pressure = vec![], gravity = None, displace = vec![]))]
    #[allow(clippy::type_complexity)]
    fn static_analysis<'py>(
        &self,
        py: Python<'py>,
        force: Vec<String>,
        pressure: Vec<String>,
        gravity: Option<String>,
        displace: Vec<String>,
    ) -> PyResult<(String, Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>)> {
        let loads = LoadOptions {
            force,
            pressure,
            gravity,
            displace,
        };
        let (mesh, opts, source) = (self.mesh.clone(), self.options.clone(), self.source.clone());
        let (json, u, vm) = interruptible(py, move || static_out(&mesh, &source, &opts, loads))?;
        let n = vm.len();
        let u = Array2::from_shape_vec((n, 6), u).expect("n × 6");
        Ok((json, u.into_pyarray(py), vm.into_pyarray(py)))
    }

    /// Harmonic response (see `vibrofem harmonic`): forces in the command line's grammar
    /// (`GROUP=FX,FY,FZ[@DEG]`), one frequency `freq` (Hz) or a `sweep` (f0, f1, n) under the
    /// command line's rules (0 ≤ f0 < f1, 2 ≤ n ≤ its cap), a modal damping ratio or Rayleigh
    /// (α, β). Returns (report JSON, the frequencies, real and imaginary displacements,
    /// frequencies × n_nodes × 3).
    #[pyo3(signature = (force, freq = None, sweep = None, damping = None, rayleigh = None, method = "modal",
        modes = None, probe = vec![]))]
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    fn harmonic<'py>(
        &self,
        py: Python<'py>,
        force: Vec<String>,
        freq: Option<f64>,
        sweep: Option<(f64, f64, usize)>,
        damping: Option<f64>,
        rayleigh: Option<(f64, f64)>,
        method: &str,
        modes: Option<usize>,
        probe: Vec<String>,
    ) -> PyResult<(
        String,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray3<f64>>,
        Bound<'py, PyArray3<f64>>,
    )> {
        use vibrofem::analysis::harmonic::{Damping, GroupForce};
        use vibrofem::app::harmonic as h;
        let damping = match (damping, rayleigh) {
            (Some(z), None) => Damping::Ratio(z),
            (None, Some((alpha, beta))) => Damping::Rayleigh { alpha, beta },
            _ => {
                return Err(InputError::new_err(
                    "harmonic: give damping=ZETA or rayleigh=(ALPHA, BETA), one of them",
                ));
            }
        };
        damping.validate().map_err(err)?;
        let freqs = harmonic_freqs(freq, sweep)?;
        let forces = force
            .iter()
            .map(|f| GroupForce::parse("force", f))
            .collect::<vibrofem::Result<Vec<_>>>()
            .map_err(err)?;
        let req = h::HarmonicRequest {
            forces,
            freqs_hz: freqs.clone(),
            damping,
            method: h::Method::parse(method).map_err(err)?,
            modes,
            probes: probe,
        };
        let system = self.system_task(Engine::Native);
        let mesh = self.mesh.clone();
        let (json, re, im) = interruptible(py, move || harmonic_out(&*system()?, &mesh, &req))?;
        let nf = freqs.len();
        let n = re.len() / (3 * nf.max(1));
        let arr = |v: Vec<f64>| {
            Array3::from_shape_vec((nf, n, 3), v)
                .expect("frequencies × nodes × 3")
                .into_pyarray(py)
        };
        Ok((json, freqs.into_pyarray(py), arr(re), arr(im)))
    }

    /// Write K, M, the DOF map and model.json into `dir` (see `vibrofem export`); returns the
    /// files written.
    #[pyo3(signature = (dir, format = "both"))]
    fn export(&self, py: Python<'_>, dir: PathBuf, format: &str) -> PyResult<Vec<String>> {
        let formats = engines::export::Formats::parse(format).map_err(err)?;
        let system = self.system_task(Engine::Native);
        let (_, files) = interruptible(py, move || engines::export::export(&*system()?, &dir, formats, None))?;
        Ok(files.iter().map(|p| p.display().to_string()).collect())
    }
}

/// Run a scene file (TOML) and return its report as JSON text; with `out`, the result files
/// the scene asks for are written there (the folder is created).
#[pyfunction]
#[pyo3(signature = (path, out = None))]
fn run_scene(py: Python<'_>, path: PathBuf, out: Option<PathBuf>) -> PyResult<String> {
    let report = interruptible(py, move || match &out {
        None => vibrofem::app::scene::run(&path),
        Some(o) => {
            std::fs::create_dir_all(o).map_err(|e| vibrofem::Error::io(o, e))?;
            vibrofem::app::scene::Scene::load(&path)?.run(Some((o, "")))
        }
    })?;
    serde_json::to_string(&report).map_err(json_err)
}

/// Names of the DOF components, in component order.
#[pyfunction]
fn component_names() -> Vec<&'static str> {
    COMPONENT_NAMES.to_vec()
}

/// Cell kinds vibrofem reads, with their node counts.
#[pyfunction]
fn cell_kind_names() -> Vec<(&'static str, usize)> {
    CellKind::ALL.iter().map(|k| (k.name(), k.n_nodes())).collect()
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMesh>()?;
    m.add_class::<PyModel>()?;
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh_from_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(app::run_design, m)?)?;
    m.add_function(wrap_pyfunction!(app::run_machine, m)?)?;
    m.add_function(wrap_pyfunction!(app::machine_list, m)?)?;
    m.add_function(wrap_pyfunction!(run_scene, m)?)?;
    m.add_function(wrap_pyfunction!(component_names, m)?)?;
    m.add_function(wrap_pyfunction!(cell_kind_names, m)?)?;
    m.add("VibrofemError", m.py().get_type::<VibrofemError>())?;
    m.add("InputError", m.py().get_type::<InputError>())?;
    m.add("NumericalError", m.py().get_type::<NumericalError>())?;
    m.add("OutputError", m.py().get_type::<OutputError>())?;
    m.add("EngineError", m.py().get_type::<EngineError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
