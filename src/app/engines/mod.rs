//! The engines that solve the modal problem, and the export of a model for other solvers.
//!
//! - [`Engine`]: the one switch between the native solver (verified block Lanczos in this
//!   process) and SLEPc under MPI. The command line (`modes --engine`, `--slepc-import`),
//!   scenes (`[modal] engine`) and the Python package (`Model.modes(engine=…)`) all solve
//!   through [`Engine::solve`], which also adds the phases timed before the solve (reading the
//!   mesh, building the model) to the report.
//! - [`slepc`]: staging a SLEPc job (`params.json`, the script, K and M), running it under
//!   mpirun, and importing its results (also of a job run on a cluster): checked against the
//!   model and the request, then verified here as a native solution is.
//! - [`lowmem`]: the low-memory iterative path (`--solver iterative|auto`): SLEPc with a
//!   multigrid-preconditioned eigensolver under mpirun, verified here as the SLEPc engine is.
//! - [`export`]: K, M, the DOF map and a model summary for another solver.

pub mod export;
mod job;
pub mod lowmem;
mod results;
pub mod slepc;

pub use lowmem::{LowMemOptions, Solver};
pub use slepc::SlepcOptions;

use crate::analysis::modal::{self, ModalOptions, ModalParams, ModalRun};
use crate::mesh::Mesh;
use crate::model::Model;
use crate::system::{System, SystemOptions};
use crate::{Error, Result};
use std::time::Instant;

/// Which eigen solver computes the modes.
#[derive(Clone, Debug, Default)]
pub enum Engine {
    /// vibrofem's own verified block Lanczos (the default).
    #[default]
    Native,
    /// SLEPc's Krylov–Schur with a MUMPS factorisation under mpirun (or the import of the
    /// results of such a job), verified here.
    Slepc(SlepcOptions),
}

/// The phases of a run timed before its solve, which the report's timings include.
#[derive(Clone, Copy, Debug, Default)]
pub struct Before {
    /// Reading (or generating) the mesh, s.
    pub read_s: f64,
    /// Building the model from the mesh (before the assembly the system times itself), s.
    pub model_s: f64,
}

impl Engine {
    /// The engine named `name` (`native` or `slepc`) with the SLEPc options `o` (their
    /// defaults for the native engine). A job to import (`o.import`) means SLEPc whatever the
    /// name. Errors name the command line's options (`--engine`, `--ranks`, `--slepc-dir`).
    pub fn parse(name: &str, o: SlepcOptions) -> Result<Engine> {
        let name = if o.import.is_some() { "slepc" } else { name };
        match name {
            "native" => {
                if o.ranks != 1 || o.workdir.is_some() {
                    return Err(Error::option(
                        "--ranks",
                        "--ranks and --slepc-dir apply to --engine slepc",
                    ));
                }
                Ok(Engine::Native)
            }
            "slepc" => {
                if o.ranks == 0 {
                    return Err(Error::option("--ranks", "--ranks must be at least 1"));
                }
                Ok(Engine::Slepc(o))
            }
            e => Err(Error::option(
                "--engine",
                format!("--engine '{e}': use native or slepc"),
            )),
        }
    }

    /// SLEPc on `ranks` MPI ranks, other options at their defaults (a scene's
    /// `engine = "slepc"`).
    pub fn slepc(ranks: usize) -> Engine {
        Engine::Slepc(SlepcOptions {
            ranks,
            ..Default::default()
        })
    }

    /// `native` or `slepc`.
    pub fn name(&self) -> &'static str {
        match self {
            Engine::Native => "native",
            Engine::Slepc(_) => "slepc",
        }
    }

    /// Whether this engine factorises in this process (and so needs the ordering and the
    /// memory check of [`System::build`]); SLEPc factorises on its own ranks.
    pub fn factorises_here(&self) -> bool {
        matches!(self, Engine::Native)
    }

    /// The system this engine solves: assembled, ordered and analysed for the native solver;
    /// assembled only (K and M) for SLEPc, whose factorisation is another process's (or
    /// machine's) memory.
    pub fn system(&self, model: Model, opts: &SystemOptions, source: &str) -> Result<System> {
        match self {
            Engine::Native => System::build(model, opts, source),
            Engine::Slepc(_) => System::assemble_only(model, source),
        }
    }

    /// The verified modes of `sys`, their report's timings including the phases `before`.
    pub fn solve(&self, sys: &System, params: &ModalParams, before: Before) -> Result<ModalRun> {
        let mut run = match self {
            Engine::Native => modal::solve(sys, params)?,
            Engine::Slepc(o) => slepc::solve(sys, params, o)?,
        };
        let tm = &mut run.report.timings_s;
        tm.read = before.read_s;
        tm.assemble += before.model_s;
        tm.total += before.read_s + before.model_s;
        modal::retime_floor(&mut run.report);
        Ok(run)
    }

    /// A modal analysis of a mesh in memory: build the model and the system this engine
    /// solves, then [`Engine::solve`]. `read_s` (s) is reported as the read phase.
    pub fn solve_mesh(&self, mesh: &Mesh, source: &str, opts: &ModalOptions, read_s: f64) -> Result<ModalRun> {
        let t = Instant::now();
        let model = Model::build(mesh, &opts.spec, source)?;
        let model_s = t.elapsed().as_secs_f64();
        let sys = self.system(model, &opts.system_options(), source)?;
        self.solve(&sys, &opts.params(), Before { read_s, model_s })
    }
}
