//! `vibrofem export`: K, M, the DOF map and a model summary for another solver (SLEPc, scipy,
//! MATLAB), and the staging of the SLEPc engine.

use crate::io::matrix;
use crate::system::System;
use crate::{Error, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Which matrix formats to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Formats {
    /// PETSc binary (`K.petsc`, `M.petsc`).
    Petsc,
    /// Matrix Market (`K.mtx`, `M.mtx`).
    MatrixMarket,
    /// Both.
    Both,
}

impl Formats {
    /// `petsc`, `mtx` or `both`.
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "petsc" => Ok(Formats::Petsc),
            "mtx" | "matrix-market" => Ok(Formats::MatrixMarket),
            "both" => Ok(Formats::Both),
            _ => Err(Error::option(
                "--format",
                format!("--format '{s}': use petsc, mtx or both"),
            )),
        }
    }
}

/// `model.json`: what the exported files hold.
#[derive(Clone, Debug, Serialize)]
pub struct ExportSummary {
    /// Format version of this summary.
    pub version: u32,
    /// The mesh file or generator.
    pub source: String,
    /// Units of the matrices and the DOF map.
    pub units: &'static str,
    /// Mesh nodes.
    pub nodes: usize,
    /// Reference nodes of couplings (numbered after the mesh nodes).
    pub reference_nodes: usize,
    /// Free DOFs: the dimension of K and M.
    pub dofs: usize,
    /// Stored entries of K (and M, on the same pattern), both triangles.
    pub nnz: usize,
    /// Cells of the model per kind.
    pub cells: Vec<(String, usize)>,
    /// Volume (m³) and mass (kg) of the model.
    pub volume_m3: f64,
    /// Total mass including point masses, kg.
    pub mass_kg: f64,
    /// `consistent` or `lumped`.
    pub mass_matrix: &'static str,
    /// Files written, by role.
    pub files: Vec<(String, String)>,
    /// How to read them.
    pub conventions: Vec<&'static str>,
    /// The model's notes.
    pub notes: Vec<String>,
}

/// Write K and M (in `formats`), `dofs.csv`, the SLEPc job for `job` if given (`params.json`,
/// `slepc_modes.py`: `mpirun -n N python3 DIR/slepc_modes.py DIR`) and `model.json`, which lists
/// them all, into `dir` (created). Returns the summary (as in `model.json`) and the paths written.
pub fn export(
    sys: &System,
    dir: &Path,
    formats: Formats,
    job: Option<&crate::analysis::modal::ModalParams>,
) -> Result<(ExportSummary, Vec<PathBuf>)> {
    crate::io::create_dir(dir)?;
    let model = sys.model();
    let k = sys.k();
    // M on K's pattern, explicit zeros included: one structure for both files, as other solvers
    // expect (PETSc's K − σM with SAME_NONZERO_PATTERN, the SLEPc script's).
    let m = &sys.m()?.on_pattern(k.pattern.clone());
    let mut files = Vec::new();
    let mut written = Vec::new();
    let comment = format!(
        "vibrofem export of {} ({} free DOFs, SI units); row/column i = equation i-1 of dofs.csv",
        sys.source(),
        sys.n_free()
    );
    for (name, a) in [("K", k), ("M", m)] {
        if formats != Formats::MatrixMarket {
            let p = dir.join(format!("{name}.petsc"));
            matrix::write_petsc(&p, a)?;
            files.push((format!("{name} (PETSc binary AIJ)"), format!("{name}.petsc")));
            written.push(p);
        }
        if formats != Formats::Petsc {
            let p = dir.join(format!("{name}.mtx"));
            matrix::write_matrix_market(&p, a, &comment)?;
            files.push((format!("{name} (Matrix Market)"), format!("{name}.mtx")));
            written.push(p);
        }
    }
    let p = dir.join("dofs.csv");
    matrix::write_dof_map(&p, &model.dofs, &model.nodes, &model.node_tags)?;
    files.push(("DOF map".into(), "dofs.csv".into()));
    written.push(p);
    if let Some(params) = job {
        super::slepc::write_job(sys, params, dir, false)?;
        files.push(("SLEPc job parameters".into(), "params.json".into()));
        files.push((
            "SLEPc job (mpirun -n N python3 slepc_modes.py DIR)".into(),
            "slepc_modes.py".into(),
        ));
        written.extend([dir.join("params.json"), dir.join("slepc_modes.py")]);
    }
    let (volume, solid_mass) = model.volume_and_mass()?;
    let summary = ExportSummary {
        version: 1,
        source: sys.source().to_string(),
        units: "SI: m, kg, s, N, Pa; K in N/m (N·m/rad for rotations), M in kg (kg·m² for rotations)",
        nodes: model.n_mesh_nodes,
        reference_nodes: model.references.len(),
        dofs: sys.n_free(),
        nnz: k.pattern.nnz(),
        cells: model
            .cell_counts()
            .iter()
            .map(|(k, n)| (k.name().to_string(), *n))
            .collect(),
        volume_m3: volume,
        mass_kg: solid_mass + model.discrete_mass(),
        mass_matrix: model.spec.lumping.name(),
        files,
        conventions: vec![
            "row and column i of K and M is equation i of dofs.csv (0-based; Matrix Market counts from 1)",
            "fixed DOFs are eliminated; coupled (slave) DOFs are expressed through their reference node",
            "PETSc files hold both triangles (MatLoad, any number of ranks); Matrix Market files the lower triangle (symmetric)",
            "K x = λ M x with λ = (2πf)², f in Hz",
        ],
        notes: model.notes.clone(),
    };
    let p = dir.join("model.json");
    let json = serde_json::to_string_pretty(&summary).map_err(|e| Error::output(p.display(), e))?;
    std::fs::write(&p, json).map_err(|e| Error::io(&p, e))?;
    written.push(p);
    Ok((summary, written))
}
