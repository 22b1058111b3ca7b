//! The run of a scene: the mesh read or generated, the scene's groups checked against it, one
//! model and one system assembled, then the analyses the scene asks for (modal, static,
//! harmonic), each writing the result files asked for in `[output]`.

use super::{Formulation, MeshSource, ModeShapes, Scene, SceneReport};
use crate::app::engines::{Before, Engine};
use crate::app::toml_file;
use crate::mesh::Mesh;
use crate::system::System;
use crate::{Error, Result};
use std::path::Path;
use std::time::Instant;

/// Where a run writes its result files: a folder and a file-name prefix.
type Out<'a> = Option<(&'a Path, &'a str)>;

/// What the analyses of one run share: the mesh, its name, the system, and what they add to
/// the report (notes, files written).
struct Run<'a> {
    scene: &'a Scene,
    mesh: Mesh,
    source: String,
    sys: System,
    read_time: f64,
    model_time: f64,
    notes: Vec<String>,
    outputs: Vec<String>,
}

impl Scene {
    /// The mesh as text for reports: the file path or the generator spec.
    pub fn mesh_name(&self) -> String {
        match &self.mesh {
            MeshSource::File(p) => p.display().to_string(),
            MeshSource::Generator(g) => g.clone(),
            MeshSource::Missing => "(none)".into(),
        }
    }

    /// Read or generate the mesh.
    pub fn load_mesh(&self) -> Result<Mesh> {
        let file = self.path.display().to_string();
        match &self.mesh {
            MeshSource::File(p) => crate::io::gmsh::read(p, self.length_scale),
            MeshSource::Generator(g) => generate(g, self.length_scale).map_err(|e| match e {
                Error::InvalidInput(m) | Error::Invalid { msg: m, .. } => {
                    toml_file::file_error(file, None, format!("[mesh] {m}"))
                }
                e => e,
            }),
            MeshSource::Missing => Err(toml_file::file_error(
                file,
                None,
                "no mesh: give [mesh] file = \"...\" or generator = \"...\"",
            )),
        }
    }

    /// Check the scene's group names and part formulations against the mesh; errors name the
    /// scene's line. Returns the number of ignored cells and a note about them.
    pub fn check_groups(&self, mesh: &Mesh) -> Result<(usize, Option<String>)> {
        let file = self.path.display().to_string();
        for g in &self.groups {
            let at = |msg: String| toml_file::file_error(file.clone(), Some(g.line), msg);
            let grp = mesh
                .group(&g.group)
                .map_err(|e| at(format!("{} names an {e}", g.what)))?;
            let Some((dim, form)) = g.needs_dim else {
                continue;
            };
            let ok = grp.cells.iter().any(|c| {
                let k = mesh.blocks[c.block as usize].kind;
                match form {
                    Formulation::Solid => k.dim() == 3,
                    Formulation::Shell => crate::element::shell::supports(k),
                    Formulation::Beam => crate::element::beam::supports(k),
                }
            });
            if !ok {
                let mut d: Vec<u8> = grp
                    .cells
                    .iter()
                    .map(|c| mesh.blocks[c.block as usize].kind.dim() as u8)
                    .collect();
                d.sort_unstable();
                d.dedup();
                let dims: Vec<String> = d.iter().map(|x| format!("{x}D")).collect();
                let need = match dim {
                    3 => "volume cells (tet, hex, wedge)",
                    2 => "surface cells (tri3, quad4)",
                    _ => "line cells (line2, line3)",
                };
                let form = match form {
                    Formulation::Solid => "solid",
                    Formulation::Shell => "shell",
                    Formulation::Beam => "beam",
                };
                let has = if dims.is_empty() {
                    "no".to_string()
                } else {
                    dims.join(", ")
                };
                return Err(at(format!(
                    "{} is a {form} part but group '{}' has no {need} (it has {has} cells)",
                    g.what, g.group
                )));
            }
        }
        Ok(self.ignored_cells(mesh))
    }

    /// Cells of the part dimensions in no part: how many, and a note saying so.
    fn ignored_cells(&self, mesh: &Mesh) -> (usize, Option<String>) {
        let mut used: Vec<Vec<bool>> = mesh.blocks.iter().map(|b| vec![false; b.len()]).collect();
        let mut dims_in_use = [false; 4];
        for (g, f) in &self.parts {
            let d = match f {
                Formulation::Solid => 3,
                Formulation::Shell => 2,
                Formulation::Beam => 1,
            };
            dims_in_use[d] = true;
            if let Ok(grp) = mesh.group(g) {
                for c in &grp.cells {
                    used[c.block as usize][c.index as usize] = true;
                }
            }
        }
        let mut ignored = 0;
        let mut total = 0;
        for (bi, b) in mesh.blocks.iter().enumerate() {
            let d = b.kind.dim();
            // Volume cells always count; surface and line cells only where parts of that
            // dimension exist (otherwise they are boundary faces and edges).
            if d == 3 || (d >= 1 && dims_in_use[d]) {
                total += b.len();
                ignored += used[bi].iter().filter(|u| !**u).count();
            }
        }
        let note = (ignored > 0)
            .then(|| format!("{ignored} of {total} cells are in no [[part]] of the scene and were ignored"));
        (ignored, note)
    }

    /// Run the scene's analyses. With `out = Some((dir, prefix))` the result files asked for in
    /// `[output]` are written to `dir/<prefix>modes.vtu`, `dir/<prefix>static.vtu` (and `.msh`).
    pub fn run(&self, out: Option<(&Path, &str)>) -> Result<SceneReport> {
        let t0 = Instant::now();
        let mesh = self.load_mesh()?;
        let read_time = t0.elapsed().as_secs_f64();
        log::info!("scene {}: mesh read in {read_time:.3} s", self.name);
        let (ignored_cells, note) = self.check_groups(&mesh)?;
        let mut run = self.prepare(mesh, read_time)?;
        run.notes.extend(note);
        let (modal, mode_shapes) = match &self.modal {
            None => (None, None),
            Some(m) => {
                let (r, s) = run.modal(*m, out)?;
                (Some(r), Some(s))
            }
        };
        let buckling = match self.buckling {
            None => None,
            Some((case, modes)) => Some(run.buckling(case, modes, out)?),
        };
        let statics = match &self.static_cases {
            None => None,
            Some(cases) => Some(run.statics(cases, modal.is_none(), out)?),
        };
        let harmonic = match &self.harmonic {
            None => None,
            Some(req) => Some(run.harmonic(req, out)?),
        };
        if let Some((dir, prefix)) = out {
            remove_stale_outputs(dir, prefix, &run.outputs, &mut run.notes);
        }
        run.notes.dedup();
        Ok(SceneReport {
            scene: self.path.display().to_string(),
            name: self.name.clone(),
            mesh: run.source,
            nodes: run.mesh.n_nodes(),
            parts: self.parts.clone(),
            ignored_cells,
            modal,
            statics,
            harmonic,
            buckling,
            outputs: run.outputs,
            notes: run.notes,
            time_s: t0.elapsed().as_secs_f64(),
            mode_shapes,
        })
    }

    /// One model and one system for every analysis: assembled and ordered once.
    fn prepare(&self, mesh: Mesh, read_time: f64) -> Result<Run<'_>> {
        let source = self.mesh_name();
        let t_model = Instant::now();
        let model = crate::model::Model::build(&mesh, &self.spec, &source)?;
        let model_time = t_model.elapsed().as_secs_f64();
        let engine = self.slepc_ranks.map_or(Engine::Native, Engine::slepc);
        let sys = if !engine.factorises_here() && self.static_cases.is_none() && self.harmonic.is_none() {
            // SLEPc factorises on its ranks: no ordering or memory check for this machine.
            System::assemble_only(model, &source)?
        } else {
            System::build(
                model,
                &crate::system::SystemOptions {
                    mass: self.modal.is_some() || self.harmonic.is_some(),
                    ..Default::default()
                },
                &source,
            )?
        };
        Ok(Run {
            scene: self,
            mesh,
            source,
            sys,
            read_time,
            model_time,
            notes: Vec::new(),
            outputs: Vec::new(),
        })
    }
}

impl Run<'_> {
    /// The result files `<prefix><what>.vtu` / `.msh` the scene's `[output]` asks for.
    fn field_files(&self, out: Out, what: &str) -> (Option<std::path::PathBuf>, Option<std::path::PathBuf>) {
        match out {
            None => (None, None),
            Some((dir, prefix)) => (
                self.scene.vtu.then(|| dir.join(format!("{prefix}{what}.vtu"))),
                self.scene.msh.then(|| dir.join(format!("{prefix}{what}.msh"))),
            ),
        }
    }

    /// The modal analysis: its report (timings include the mesh read and the model build) and
    /// the shapes at the mesh nodes.
    fn modal(
        &mut self,
        (target, shift_hz, block): (crate::analysis::modal::ModalTarget, Option<f64>, usize),
        out: Out,
    ) -> Result<(crate::analysis::modal::ModalReport, ModeShapes)> {
        let scene = self.scene;
        let params = crate::analysis::modal::ModalParams {
            target,
            shift_hz,
            block,
            ..Default::default()
        };
        let engine = scene.slepc_ranks.map_or(Engine::Native, Engine::slepc);
        let before = Before {
            read_s: self.read_time,
            model_s: self.model_time,
        };
        let mut run = match (scene.prestress, &scene.static_cases) {
            (Some(c), Some(cases)) => {
                // K + K_σ for the modal solve only: the static and harmonic analyses after it
                // keep K.
                let loads = cases.get(c).cloned().unwrap_or_default();
                let k = self.sys.k().clone();
                let (pre, case, _) = crate::analysis::prestress::prestress_system(&mut self.sys, &self.mesh, &loads)?;
                let solved = engine.solve(&self.sys, &params, before);
                self.sys.replace_stiffness(k)?;
                let mut r = solved?;
                r.report.notes.push(format!(
                    "prestressed modes: K + K_σ from load case {} (applied force {:.4e} N); stress from {:.3} MPa to {:.3} MPa",
                    c + 1,
                    (case.applied.force.iter().map(|f| f * f).sum::<f64>()).sqrt(),
                    pre.compression.value / 1e6,
                    pre.tension.value / 1e6
                ));
                r
            }
            _ => engine.solve(&self.sys, &params, before)?,
        };
        let tm = &run.report.timings_s;
        log::info!(
            "scene {}: modal: assemble {:.3} s, factor {:.3} s, eigen {:.3} s",
            scene.name,
            tm.assemble,
            tm.factor,
            tm.solve
        );
        if out.is_some() {
            let (vtu, msh) = self.field_files(out, "modes");
            for p in crate::app::output::write_shapes(
                &self.mesh,
                Some(self.sys.model()),
                (&run.shapes, run.vectors.as_ref()),
                ("frequencies_hz", &run.report.frequencies_hz),
                vtu.as_deref(),
                msh.as_deref(),
            )? {
                self.outputs.push(p.display().to_string());
            }
        }
        self.notes.extend(run.report.notes.iter().cloned());
        let shapes = ModeShapes {
            points: self.mesh.nodes.clone(),
            shapes: std::mem::take(&mut run.shapes),
        };
        Ok((run.report, shapes))
    }

    /// Linear buckling under load case `case` (0-based): the `modes` lowest positive factors.
    fn buckling(&mut self, case: usize, modes: usize, out: Out) -> Result<crate::analysis::buckling::BucklingReport> {
        let loads = self
            .scene
            .static_cases
            .as_ref()
            .and_then(|c| c.get(case))
            .cloned()
            .unwrap_or_default();
        let opts = crate::analysis::buckling::BucklingOptions {
            spec: self.scene.spec.clone(),
            modes,
            ..Default::default()
        };
        let run =
            crate::analysis::buckling::solve(&self.sys, &self.mesh, &loads, &opts, self.read_time, self.model_time)?;
        self.notes.extend(run.report.notes.iter().cloned());
        // The shapes as `buckling.vtu` (largest translation 1, load factors as field data), as
        // `vibrofem buckling --vtu` writes them; gmsh views are not written for buckling.
        if let (Some(vtu), _) = self.field_files(out, "buckling") {
            for p in crate::app::output::write_shapes(
                &self.mesh,
                Some(self.sys.model()),
                (&run.shapes, run.vectors.as_ref()),
                ("load_factors", &run.report.load_factors),
                Some(&vtu),
                None,
            )? {
                self.outputs.push(p.display().to_string());
            }
        }
        Ok(run.report)
    }

    /// The static analysis of the load cases; `alone`: no modal analysis ran (the model build
    /// counts in its assembly time, and its notes are the run's).
    fn statics(
        &mut self,
        cases: &[Vec<crate::analysis::statics::Load>],
        alone: bool,
        out: Out,
    ) -> Result<crate::app::report::StaticReport> {
        let mut run = crate::analysis::statics::solve(&self.sys, &self.mesh, cases)?;
        if alone {
            run.timings.assemble += self.model_time;
        }
        let t = run.timings;
        log::info!(
            "scene {}: static: assemble {:.3} s, factor {:.3} s, solve {:.3} s",
            self.scene.name,
            t.assemble,
            t.factor,
            t.solve
        );
        let stresses = crate::app::report::case_stresses(&self.mesh, &run)?;
        let rep = crate::app::report::static_report(&self.mesh, &self.source, &run, &stresses)?;
        let (vtu, msh) = self.field_files(out, "static");
        if vtu.is_some() || msh.is_some() {
            crate::app::report::write_static_fields(&self.mesh, &run, &stresses, vtu.as_deref(), msh.as_deref())?;
            self.outputs
                .extend(vtu.iter().chain(msh.iter()).map(|p| p.display().to_string()));
        }
        if alone {
            self.notes.extend(rep.notes.iter().cloned());
        }
        Ok(rep)
    }

    /// The harmonic analysis: fields at the peak and the response curve of a sweep.
    fn harmonic(
        &mut self,
        req: &crate::app::harmonic::HarmonicRequest,
        out: Out,
    ) -> Result<crate::app::harmonic::HarmonicReport> {
        let run = crate::app::harmonic::run_with(&self.sys, &self.mesh, req, crate::app::harmonic::Fields::Peak)?;
        if let Some((dir, prefix)) = out {
            let k = crate::app::harmonic::peak_index(&run.report);
            let (vtu, msh) = self.field_files(out, "harmonic");
            if vtu.is_some() || msh.is_some() {
                crate::app::harmonic::write_fields(
                    &self.mesh,
                    Some(&self.sys.model().cell_blocks()),
                    &run,
                    k,
                    vtu.as_deref(),
                    msh.as_deref(),
                )?;
                self.outputs
                    .extend(vtu.iter().chain(msh.iter()).map(|p| p.display().to_string()));
            }
            if run.report.points.len() > 1 {
                let svg = dir.join(format!("{prefix}frf.svg"));
                crate::app::harmonic::write_frf_svg(&svg, &run.report)?;
                self.outputs.push(svg.display().to_string());
            }
        }
        self.notes.extend(run.report.notes.iter().cloned());
        Ok(run.report)
    }
}

/// Read and run a scene file (no result files written).
pub fn run(path: &Path) -> Result<SceneReport> {
    Scene::load(path)?.run(None)
}

/// A mesh from a generator spec (any of [`crate::input::source::GENERATORS`]); a spec that is
/// not a generator is an error (a scene names files with `file =`).
pub fn generate(spec: &str, length_scale: f64) -> Result<Mesh> {
    if !crate::input::source::is_generator(spec) {
        return Err(Error::param(
            "generator",
            format!("unknown generator '{spec}' ({})", crate::input::source::GENERATORS),
        ));
    }
    crate::input::source::load(spec, length_scale)
}

/// The result files a scene run may write (after its prefix).
const RESULT_FILES: [&str; 8] = [
    "buckling.vtu",
    "modes.vtu",
    "modes.msh",
    "static.vtu",
    "static.msh",
    "harmonic.vtu",
    "harmonic.msh",
    "frf.svg",
];

/// Remove the result files of an earlier run in `dir` (with this `prefix`) that this run did
/// not write (`written`), each with a note: a `static.vtu` of another scene beside a summary that
/// lists no files read as this run's result. What cannot be removed is said, not an error.
fn remove_stale_outputs(dir: &Path, prefix: &str, written: &[String], notes: &mut Vec<String>) {
    for name in RESULT_FILES {
        let p = dir.join(format!("{prefix}{name}"));
        if !p.is_file() || written.iter().any(|w| Path::new(w) == p) {
            continue;
        }
        notes.push(match std::fs::remove_file(&p) {
            Ok(()) => format!(
                "removed {} left by an earlier run (this run does not write it)",
                p.display()
            ),
            Err(e) => format!(
                "{} is left from an earlier run and could not be removed: {e}",
                p.display()
            ),
        });
    }
}
