//! Studies: one analysis described in a file, and the studies built on it.
//!
//! - [`scene`]: the scene file (grammar and parse) and its run;
//! - [`batch`]: a template scene over many meshes (parallel, resumable, sharded, summarised);
//! - [`merge`]: the summaries of batch shards joined into one;
//! - [`sweep`]: parametric studies of the sandwich work table (Pareto front of mass and first
//!   frequency);
//! - [`converge`]: speed–accuracy studies over mesh refinements and formulations;
//! - [`geo`]: gmsh as a subprocess, meshing a user's `.geo` for [`converge`].
//!
//! Every input file here is read through [`crate::app::toml_file`].

pub mod batch;
pub mod converge;
pub mod geo;
pub mod merge;
pub mod scene;
pub mod sweep;
