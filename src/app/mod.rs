//! The vibratory-table application and the command line, above the FE core (feature `app`).
//!
//! - [`dynamics`]: the lumped two-mass machine (paper §5–§8), electromagnet, transient, plots.
//! - [`design`], [`sweep`], [`converge`]: the design chain and the studies built on the core.
//! - [`scene`], [`report`], [`cli`]: scene files, batch runs, text reports, clap options.
//! - [`engines`]: the native/SLEPc switch every modal solve goes through, the SLEPc/MPI engine
//!   and its import, and the export of K, M and the DOF map for other solvers.
pub mod cli;
pub mod converge;
pub mod design;
pub mod design_search;
pub mod dynamics;
pub mod engines;
pub mod harmonic;
pub mod machine3d;
pub mod machines_cli;
pub mod report;
pub mod scene;
pub mod sweep;
pub mod toml_file;

// The engines' modules under their former paths.
pub use engines::{export, slepc};
