//! Scene files: one analysis described in TOML.
//!
//! A scene names its mesh (a gmsh file relative to the scene, or a built-in generator), the
//! materials, the formulation of each group it includes (the rest of the mesh is ignored, with a
//! note), supports, couplings, point masses, springs, prescribed displacements, load cases and the
//! analyses to run (`[modal]`, `[static]`, `[harmonic]`). The format is strict: `[scene] version =
//! 1` is required and unknown keys are errors; every error names the file and line. See
//! `docs/scenes.md`.
//!
//! - [`parse`]: the file's grammar; [`Scene::load`] / [`Scene::parse`] read and validate it.
//! - [`run`](mod@run): [`Scene::run`] runs it; [`run()`] does both.
//! - Batch runs of a scene over many meshes are in [`crate::app::studies::batch`].

mod parse;
mod run;

pub use run::{generate, run};

use crate::analysis::modal::{ModalReport, ModalTarget};
use crate::analysis::statics::Load;
use crate::app::report::StaticReport;
use crate::model::ModelSpec;
use serde::Serialize;
use std::path::PathBuf;

// ---------------------------------------------------------------------------------------------
// Validated scene.

/// Where the mesh of a scene comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshSource {
    /// A gmsh file (already resolved against the scene's folder).
    File(PathBuf),
    /// A generator spec (the grammar of [`crate::input::source`]: `box:`, `helix:`,
    /// `sandwich:`, `ibeam-line:`, `ibeam-shell:`, `ibeam-solid:`).
    Generator(String),
    /// No mesh given (a batch template: the batch supplies the file).
    Missing,
}

/// The formulation of one part.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Formulation {
    /// Volume cells as solid elements.
    Solid,
    /// Surface cells as MITC shells.
    Shell,
    /// Line cells as Timoshenko beams.
    Beam,
}

/// A group reference of the scene, kept with its line for messages after the mesh is read.
#[derive(Clone, Debug)]
struct GroupRef {
    group: String,
    line: usize,
    what: String,
    /// Cell dimension the group must have (parts only).
    needs_dim: Option<(usize, Formulation)>,
}

/// A parsed and validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// Its `name` (default: the file stem).
    pub name: String,
    /// The mesh.
    pub mesh: MeshSource,
    /// Length unit of the mesh coordinates, as a factor to metres.
    pub length_scale: f64,
    /// The model (materials, parts, supports, couplings, masses, springs, prescribed motion).
    pub spec: ModelSpec,
    /// The parts: group and formulation, in file order.
    pub parts: Vec<(String, Formulation)>,
    /// The modal analysis, if asked: target, shift (Hz), Lanczos block.
    pub modal: Option<(ModalTarget, Option<f64>, usize)>,
    /// `[modal] prestress = N`: the modes of `K + K_σ` preloaded by load case N (0-based here).
    pub prestress: Option<usize>,
    /// `[buckling]`: the load case (0-based) whose multiples buckle the model, and the number
    /// of load factors.
    pub buckling: Option<(usize, usize)>,
    /// The static load cases, if a static analysis is asked.
    pub static_cases: Option<Vec<Vec<Load>>>,
    /// The harmonic analysis, if asked (`[harmonic]`).
    pub harmonic: Option<crate::app::harmonic::HarmonicRequest>,
    /// Write VTU files of the results.
    pub vtu: bool,
    /// Write gmsh `.msh` files with result views.
    pub msh: bool,
    /// `[modal] engine = "slepc"`: solve with SLEPc on this many MPI ranks (`ranks`, default 1);
    /// `None`: the native solver.
    pub slepc_ranks: Option<usize>,
    groups: Vec<GroupRef>,
}

/// The results of one scene run (`summary.json` of `vibrofem run`).
#[derive(Clone, Debug, Serialize)]
pub struct SceneReport {
    /// Scene file.
    pub scene: String,
    /// Scene name.
    pub name: String,
    /// Mesh file or generator.
    pub mesh: String,
    /// Nodes of the mesh.
    pub nodes: usize,
    /// Parts: group and formulation.
    pub parts: Vec<(String, Formulation)>,
    /// Cells of the mesh not in any part (ignored).
    pub ignored_cells: usize,
    /// Modal report, if asked.
    pub modal: Option<ModalReport>,
    /// Static report, if asked.
    #[serde(rename = "static")]
    pub statics: Option<StaticReport>,
    /// Harmonic report, if asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub harmonic: Option<crate::app::harmonic::HarmonicReport>,
    /// Buckling report, if asked (`[buckling]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub buckling: Option<crate::analysis::buckling::BucklingReport>,
    /// Files written.
    pub outputs: Vec<String>,
    /// Notes (ignored cells, model notes).
    pub notes: Vec<String>,
    /// Wall time of the whole scene, s.
    pub time_s: f64,
    /// Mode shapes of the modal analysis at the mesh nodes (3 per node, one per mode of
    /// `modal`), for callers that compare shapes (`converge`); not serialised.
    #[serde(skip)]
    pub mode_shapes: Option<ModeShapes>,
}

/// Mode shapes at mesh nodes.
#[derive(Clone, Debug, Default)]
pub struct ModeShapes {
    /// Node coordinates (m).
    pub points: Vec<[f64; 3]>,
    /// Per mode, 3 displacement components per node.
    pub shapes: Vec<Vec<f64>>,
}

impl SceneReport {
    /// The modal solution (if any) passed its Sturm and residual checks.
    pub fn verified(&self) -> bool {
        self.modal.as_ref().is_none_or(|m| m.complete && m.accurate)
            && self.buckling.as_ref().is_none_or(|b| b.complete && b.accurate)
    }

    /// Human-readable tables (the same as `vibrofem modes` and `vibrofem static`).
    pub fn text(&self) -> String {
        let mut s = format!("scene    {} ({})\n", self.name, self.scene);
        if let Some(m) = &self.modal {
            s.push_str(&crate::app::report::modal_table(m));
        }
        if let Some(st) = &self.statics {
            if self.modal.is_some() {
                s.push('\n');
            }
            s.push_str(&crate::app::report::static_text(st));
        }
        if let Some(h) = &self.harmonic {
            s.push('\n');
            s.push_str(&crate::app::harmonic::text(h));
        }
        s
    }

    /// Stiffness along the guided axis of the first reference node with one, load case 1.
    pub fn stiffness(&self) -> Option<f64> {
        let st = self.statics.as_ref()?;
        st.cases.first()?.references.iter().find_map(|r| r.stiffness)
    }

    /// Largest averaged von Mises stress over the model, load case 1 (Pa).
    pub fn max_von_mises(&self) -> Option<f64> {
        let st = self.statics.as_ref()?;
        st.stress
            .first()?
            .von_mises
            .iter()
            .find(|g| g.group == "(all)")
            .map(|g| g.value)
    }

    /// Largest displacement, load case 1 (m).
    pub fn max_displacement(&self) -> Option<f64> {
        Some(self.statics.as_ref()?.cases.first()?.max_displacement.0)
    }
}
