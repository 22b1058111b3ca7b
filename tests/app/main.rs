//! Tests of the application above the FE core: the two-mass dynamics, the design chain,
//! sweeps and convergence studies, scene files and batch runs, and the command line (its
//! outputs, messages and exit codes).

#[path = "../common/mod.rs"]
mod common;

mod batch_resume;
mod cli;
mod conditioning;
mod converge_geo;
mod converge_pairing;
mod design;
mod design_envelope;
mod design_fatigue;
mod design_inputs;
mod design_machine;
mod design_memo;
mod design_reduced;
mod design_startup3d;
mod dynamics;
mod export_engine;
mod harmonic;
mod harmonic_fatigue;
mod harmonic_inputs;
mod lowmem;
mod machine3d;
mod machine_inputs;
mod machines;
mod mesh_files;
mod model_options;
mod options;
mod outputs;
mod resource_limits;
mod scene_buckling;
mod scenes;
mod slepc_import;
mod solid_elements;
mod study_inputs;
mod support;
mod sweep;
