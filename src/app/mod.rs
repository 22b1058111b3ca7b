//! The vibratory-table application and the command line, above the FE core (feature `app`).
//!
//! - [`dynamics`]: the lumped two-mass machine (paper §5–§8), electromagnet, transient, plots.
//! - [`design`]: the design chain built on the core.
//! - [`machines`]: the seed machines (crank drive, autobalancer, balancer data), one shape each, and
//!   their registry.
//! - [`studies`]: scene files and their runs, batch runs and merges, sweeps, convergence studies.
//! - [`engines`]: the native/SLEPc switch every modal solve goes through, the SLEPc/MPI engine
//!   and its import, and the export of K, M and the DOF map for other solvers.
//! - [`harmonic`]: the harmonic command's run and report.
//! - [`report`], [`output`], [`cli`]: the report model and its renderers, the checked standard
//!   output and output-file checks, clap options.
//! - [`toml_file`]: the one reader of vibrofem's TOML input files (lines, keys, typed errors).
pub mod cli;
pub mod design;
pub mod dynamics;
pub mod engines;
pub mod harmonic;
pub mod machines;
pub mod output;
pub mod report;
pub mod studies;
pub mod toml_file;

/// The scene file and batch runs at their former path `app::scene` (the Python bindings and the
/// tests name it).
pub mod scene {
    pub use super::studies::batch::*;
    pub use super::studies::scene::*;
}
/// Sweeps and the merge of batch shards at their former path `app::sweep`.
pub mod sweep {
    pub use super::studies::merge::merge;
    pub use super::studies::sweep::*;
}
pub use studies::converge;

// The engines' modules under their former paths.
pub use engines::{export, slepc};
