//! Unit tests of the FE core, one module per layer or subject: element kernels and property
//! sweeps, shells and beams, mesh input and output, generators, the solver, statics, stress
//! recovery, numerical extremes, determinism, the error audit and fuzz regressions.
//!
//! One test binary (rather than one per file) because each binary links the whole crate, which
//! costs more than running the tests on 2 cores.

#[path = "../common/mod.rs"]
mod common;

mod buckling_shift;
mod couplings;
mod determinism;
mod elements;
mod errors_audit;
mod extremes;
mod fatigue_closed_forms;
mod fuzz_regressions;
mod gmsh_bookkeeping;
mod group_names;
mod job_beside;
mod memory_estimate;
mod mesh_io;
mod modal_requests;
mod model_notes;
mod parametric;
mod rigid_modes;
mod shell_orientation;
mod solid_elements;
mod solver;
mod statics;
mod stress;
mod structural_elements;
mod sturm_clusters;
