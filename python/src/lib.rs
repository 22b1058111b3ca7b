//! `vibrofem._core`: the compiled half of the Python package. The Python half
//! (`pysrc/vibrofem/__init__.py`) turns keyword arguments into vibrofem's option grammar and
//! arrays into scipy matrices; this module holds meshes, models and their assembled systems and
//! returns numpy arrays. Heavy work runs with the interpreter detached.

use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use std::sync::Arc;
use vibrofem::analysis::modal::{self, ModalParams, ModalTarget};
use vibrofem::analysis::statics::{StaticOptions, run_static};
use vibrofem::dof::{COMPONENT_NAMES, NCOMP};
use vibrofem::input::options::{LoadOptions, ModelOptions, length_scale};
use vibrofem::mesh::{CellKind, Mesh};
use vibrofem::model::Model;
use vibrofem::system::{System, SystemOptions};

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

/// The exception of a vibrofem error, with the command line's message.
fn err(e: vibrofem::Error) -> PyErr {
    let msg = e.to_string();
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
        numpy::ndarray::Array2::from_shape_vec((self.mesh.nodes.len(), 3), flat)
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
            kinds.join(", "),
            self.mesh.group_names()
        )
    }
}

/// Read a gmsh mesh (MSH 2.2 or 4.1) or generate one (`box:…`, `helix:…`, `sandwich:…`,
/// `ibeam-*:…`), scaling coordinates from `length_unit` (m, cm or mm) to metres.
#[pyfunction]
#[pyo3(signature = (source, length_unit = "m"))]
fn read_mesh(py: Python<'_>, source: &str, length_unit: &str) -> PyResult<PyMesh> {
    let scale = length_scale(length_unit).map_err(err)?;
    let src = source.to_string();
    let mesh = py
        .detach(move || vibrofem::input::source::load(&src, scale))
        .map_err(err)?;
    Ok(PyMesh {
        mesh: Arc::new(mesh),
        source: source.to_string(),
    })
}

/// A model: a mesh with materials, supports, couplings, parts, in vibrofem's option grammar.
#[pyclass(name = "Model", module = "vibrofem._core")]
struct PyModel {
    mesh: Arc<Mesh>,
    source: String,
    options: ModelOptions,
    system: Option<Arc<System>>,
}

impl PyModel {
    /// The assembled system (built on first use, then shared by every analysis).
    fn system(&mut self, py: Python<'_>) -> PyResult<Arc<System>> {
        if let Some(s) = &self.system {
            return Ok(s.clone());
        }
        let (mesh, opts, source) = (self.mesh.clone(), self.options.clone(), self.source.clone());
        let sys = py
            .detach(move || -> vibrofem::Result<System> {
                let model = Model::build(&mesh, &opts.spec()?, &source)?;
                System::build(model, &SystemOptions::default(), &source)
            })
            .map_err(err)?;
        let sys = Arc::new(sys);
        self.system = Some(sys.clone());
        Ok(sys)
    }
}

fn csr<'py>(
    py: Python<'py>,
    a: &vibrofem::linalg::sparse::SymMatrix,
) -> (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i64>>,
) {
    // Both triangles stored: the CSC arrays of a symmetric matrix are its CSR arrays.
    let p = &a.pattern;
    (
        a.values.clone().into_pyarray(py),
        p.row_idx.iter().map(|&i| i as i64).collect::<Vec<_>>().into_pyarray(py),
        p.col_ptr.iter().map(|&i| i as i64).collect::<Vec<_>>().into_pyarray(py),
    )
}

type Csr<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i64>>,
);

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
        // Check the grammar now (a bad option fails at construction, as on the command line).
        options.spec().map_err(err)?;
        Ok(PyModel {
            mesh: mesh.mesh.clone(),
            source: mesh.source.clone(),
            options,
            system: None,
        })
    }

    /// Assemble (once) and return K and M over the free DOFs as CSR arrays
    /// `(data, indices, indptr)` each, and the dimension.
    fn assemble<'py>(&mut self, py: Python<'py>) -> PyResult<(Csr<'py>, Csr<'py>, usize)> {
        let sys = self.system(py)?;
        let m = sys.m().map_err(err)?;
        Ok((csr(py, sys.k()), csr(py, m), sys.n_free()))
    }

    /// Per free DOF: the node (0-based mesh index; reference nodes of couplings follow the mesh
    /// nodes) and the component (0..6: ux, uy, uz, rx, ry, rz, w).
    fn dof_table<'py>(&mut self, py: Python<'py>) -> PyResult<(Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<i64>>)> {
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
    fn node_counts(&mut self, py: Python<'_>) -> PyResult<(usize, usize)> {
        let sys = self.system(py)?;
        Ok((sys.model().n_mesh_nodes, sys.model().nodes.len()))
    }

    /// Volume (m³), mass (kg, point masses included) and the model's notes.
    fn summary(&mut self, py: Python<'_>) -> PyResult<(f64, f64, Vec<String>)> {
        let sys = self.system(py)?;
        let model = sys.model();
        let (v, m) = model.volume_and_mass().map_err(err)?;
        Ok((v, m + model.discrete_mass(), model.notes.clone()))
    }

    /// Modal analysis. Returns (report JSON, eigenvalues, free-DOF vectors n × k, shapes at the
    /// mesh nodes n_nodes × 6 × k).
    #[pyo3(signature = (n = None, band = None, shift_hz = None, block = 6, engine = "native", ranks = 1))]
    #[allow(clippy::type_complexity, clippy::too_many_arguments)]
    fn modes<'py>(
        &mut self,
        py: Python<'py>,
        n: Option<usize>,
        band: Option<(f64, f64)>,
        shift_hz: Option<f64>,
        block: usize,
        engine: &str,
        ranks: usize,
    ) -> PyResult<(
        String,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray2<f64>>,
        Bound<'py, numpy::PyArray3<f64>>,
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
        let run = match engine {
            "native" => {
                let sys = self.system(py)?;
                py.detach(move || modal::solve(&sys, &params)).map_err(err)?
            }
            "slepc" => {
                let (mesh, opts, source) = (self.mesh.clone(), self.options.clone(), self.source.clone());
                py.detach(move || -> vibrofem::Result<_> {
                    let model = Model::build(&mesh, &opts.spec()?, &source)?;
                    let sys = System::assemble_only(model, &source)?;
                    let so = vibrofem::app::slepc::SlepcOptions {
                        ranks,
                        ..Default::default()
                    };
                    vibrofem::app::slepc::solve(&sys, &params, &so)
                })
                .map_err(err)?
            }
            e => return Err(InputError::new_err(format!("engine '{e}': use native or slepc"))),
        };
        let json = serde_json::to_string(&run.report).map_err(json_err)?;
        let nf = run.vectors.nrows();
        let k = run.vectors.ncols();
        let vec = numpy::ndarray::Array2::from_shape_fn((nf, k), |(i, j)| run.vectors[(i, j)]);
        // Shapes with rotations: expand each mode over the mesh nodes, 6 components.
        let sys = self.system(py)?;
        let model = sys.model();
        let n_mesh = model.n_mesh_nodes;
        let mut shapes = numpy::ndarray::Array3::<f64>::zeros((n_mesh, 6, k));
        for j in 0..k {
            let col: Vec<f64> = (0..nf).map(|i| run.vectors[(i, j)]).collect();
            let full = model.dofs.full(&col);
            for a in 0..n_mesh {
                for c in 0..6 {
                    shapes[(a, c, j)] = full[NCOMP * a + c];
                }
            }
        }
        Ok((
            json,
            run.lambda.clone().into_pyarray(py),
            vec.into_pyarray(py),
            shapes.into_pyarray(py),
        ))
    }

    /// Linear static analysis with loads in the command line's grammar. Returns (report JSON,
    /// displacements n_nodes × 6, nodal von Mises stress of the solids, Pa).
    #[pyo3(signature = (force = vec![], pressure = vec![], gravity = None, displace = vec![]))]
    #[allow(clippy::type_complexity)]
    fn static_analysis<'py>(
        &mut self,
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
        let (json, u, vm) = py
            .detach(move || -> vibrofem::Result<(String, Vec<f64>, Vec<f64>)> {
                let mut spec = opts.spec()?;
                let case = loads.apply(&mut spec)?;
                let run = run_static(
                    &mesh,
                    &source,
                    &StaticOptions {
                        spec,
                        cases: vec![case],
                    },
                )?;
                let report = vibrofem::app::report::static_report(&mesh, &source, &run)?;
                let json = serde_json::to_string(&report).map_err(|e| vibrofem::Error::output("JSON", e))?;
                let n = run.model.n_mesh_nodes;
                let mut u6 = vec![0.0; 6 * n];
                for a in 0..n {
                    u6[6 * a..6 * a + 6].copy_from_slice(&run.u[0][NCOMP * a..NCOMP * a + 6]);
                }
                let u3 = vibrofem::app::report::mesh_displacements(&run, 0);
                let ns = vibrofem::post::stress::nodal_stress(&run.model.solids, n, &u3)?;
                Ok((json, u6, ns.von_mises))
            })
            .map_err(err)?;
        let n = vm.len();
        Ok((
            json,
            numpy::ndarray::Array2::from_shape_vec((n, 6), u)
                .expect("n × 6")
                .into_pyarray(py),
            vm.into_pyarray(py),
        ))
    }

    /// Harmonic response (see `vibrofem harmonic`): forces in the command line's grammar
    /// (`GROUP=FX,FY,FZ[@DEG]`), frequencies in Hz, a modal damping ratio or Rayleigh (α, β).
    /// Returns (report JSON, real and imaginary displacements, frequencies × n_nodes × 3).
    #[pyo3(signature = (force, freqs, damping = None, rayleigh = None, method = "modal", modes = None, probe = vec![]))]
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    fn harmonic<'py>(
        &mut self,
        py: Python<'py>,
        force: Vec<String>,
        freqs: Vec<f64>,
        damping: Option<f64>,
        rayleigh: Option<(f64, f64)>,
        method: &str,
        modes: Option<usize>,
        probe: Vec<String>,
    ) -> PyResult<(String, Bound<'py, PyArray3<f64>>, Bound<'py, PyArray3<f64>>)> {
        use vibrofem::analysis::harmonic::{Damping, GroupForce};
        use vibrofem::app::harmonic as h;
        let damping = match (damping, rayleigh) {
            (Some(z), None) => Damping::Ratio(z),
            (None, Some((alpha, beta))) => Damping::Rayleigh { alpha, beta },
            _ => {
                return Err(err(vibrofem::Error::InvalidInput(
                    "harmonic: give damping=ZETA or rayleigh=(ALPHA, BETA), one of them".into(),
                )));
            }
        };
        let forces = force
            .iter()
            .map(|f| GroupForce::parse("force", f))
            .collect::<vibrofem::Result<Vec<_>>>()
            .map_err(err)?;
        let req = h::HarmonicRequest {
            forces,
            freqs_hz: freqs,
            damping,
            method: h::Method::parse(method).map_err(err)?,
            modes,
            probes: probe,
        };
        let sys = self.system(py)?;
        let mesh = self.mesh.clone();
        let (json, re, im, nf) = py
            .detach(move || -> vibrofem::Result<(String, Vec<f64>, Vec<f64>, usize)> {
                let run = h::run(&sys, &mesh, &req)?;
                let json = serde_json::to_string(&run.report).map_err(|e| vibrofem::Error::output("JSON", e))?;
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
                Ok((json, re, im, run.nodal.len()))
            })
            .map_err(err)?;
        let n = re.len() / (3 * nf.max(1));
        let arr = |v: Vec<f64>| {
            numpy::ndarray::Array3::from_shape_vec((nf, n, 3), v)
                .expect("frequencies × nodes × 3")
                .into_pyarray(py)
        };
        Ok((json, arr(re), arr(im)))
    }

    /// Write K, M, the DOF map and model.json into `dir` (see `vibrofem export`); returns the
    /// files written.
    #[pyo3(signature = (dir, format = "both"))]
    fn export(&mut self, py: Python<'_>, dir: std::path::PathBuf, format: &str) -> PyResult<Vec<String>> {
        let formats = vibrofem::app::export::Formats::parse(format).map_err(err)?;
        let sys = self.system(py)?;
        let (_, files) = py
            .detach(move || vibrofem::app::export::export(&sys, &dir, formats))
            .map_err(err)?;
        Ok(files.iter().map(|p| p.display().to_string()).collect())
    }
}

/// Run a scene file (TOML) and return its report as JSON text.
#[pyfunction]
#[pyo3(signature = (path, out = None))]
fn run_scene(py: Python<'_>, path: std::path::PathBuf, out: Option<std::path::PathBuf>) -> PyResult<String> {
    let report = py
        .detach(move || -> vibrofem::Result<_> {
            let scene = vibrofem::app::scene::Scene::load(&path)?;
            match &out {
                Some(o) => {
                    std::fs::create_dir_all(o).map_err(|e| vibrofem::Error::io(o, e))?;
                    scene.run(Some((o, "")))
                }
                None => scene.run(None),
            }
        })
        .map_err(err)?;
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
