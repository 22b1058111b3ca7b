//! Tests of the application above the FE core: the two-mass dynamics, the design chain,
//! sweeps and convergence studies, scene files and batch runs, and the command line (its
//! outputs, messages and exit codes).

#[path = "../common/mod.rs"]
mod common;

mod cli;
mod cli_15;
mod cli_15b;
mod design;
mod dynamics;
mod export_engine;
mod harmonic;
mod harmonic_inputs;
mod machine3d;
mod machines;
mod numerics_15;
mod scenes;
mod sweep;
