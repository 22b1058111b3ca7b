//! vibrofem: finite-element modal and stiffness analysis for vibrating machines.
//!
//! Data flows one way: mesh file → [`mesh::Mesh`] → [`model::Model`] (materials, fixes) →
//! [`dof::DofMap`] → [`assembly`] (K, M on one pattern) → [`linalg::eigen`] (verified
//! shift-invert block Lanczos) → [`post::modal`] → writers in [`io`].
//!
//! Units are SI throughout (m, kg, s, N, Pa); a mesh drawn in millimetres is scaled on reading.
//!
//! # Example: the lowest modes of a clamped steel plate
//!
//! ```
//! use vibrofem::{analysis::modal, input::source, model::{Model, ModelSpec}, system::{System, SystemOptions}};
//!
//! let mesh = source::load("box:0.3,0.3,0.02:6,6,1:hex20", 1.0)?;        // or a gmsh .msh file
//! let spec = ModelSpec { fixes: vec![("xmin".into(), vibrofem::dof::TRANSLATIONS)], ..Default::default() };
//! let model = Model::build(&mesh, &spec, "plate")?;                      // steel by default
//! let sys = System::build(model, &SystemOptions::default(), "plate")?;   // K, M, ordering: once
//! println!("{} free DOFs, K has {} entries", sys.n_free(), sys.k().pattern.nnz());
//! let run = modal::solve(&sys, &modal::ModalParams { target: modal::ModalTarget::Modes(4), ..Default::default() })?;
//! assert!(run.report.complete && run.report.accurate);                   // Sturm count, residuals
//! // Cantilevered plate strip: f1 = (1.8751²/2π)·√(D/(ρtL⁴)), D = Et³/12(1−ν²): 194.7 Hz;
//! // the 6×6×1 hex20 mesh is within 1 % of it.
//! let f1 = run.report.frequencies_hz[0];
//! assert!((f1 / 194.7 - 1.0).abs() < 0.01, "f1 = {f1} Hz");
//! # Ok::<(), vibrofem::Error>(())
//! ```
//!
//! # Layers
//! The FE core (everything but [`app`]) knows nothing of the command line, plots or the
//! vibratory table; it builds alone with `cargo build --lib --no-default-features`. The
//! application (feature `app`, on by default) holds the table's lumped dynamics, the design
//! chain, studies, scenes, reports and the CLI vocabulary.
//!
//! Inside the core a module uses only the layers below it, lowest first: [`util`] (number
//! formatting, process memory) → [`error`] → [`mesh`], [`dof`], [`material`], [`section`] →
//! [`fe`] → [`linalg`] → [`io`] → [`element`] → [`model`] (with the loads) → [`assembly`] →
//! [`system`] → [`post`] → [`analysis`] → [`input`] (the text grammars) → [`app`].
//! `tools/arch_metrics.py` prints the import graph and any import against this order.
#![warn(missing_docs)]

pub mod analysis;
pub mod assembly;
pub mod dof;
pub mod element;
pub mod error;
pub mod fe;
pub mod input;
pub mod io;
pub mod linalg;
pub mod material;
pub mod mesh;
pub mod model;
pub mod post;
pub mod section;
pub mod system;
pub mod util;

#[cfg(feature = "app")]
pub mod app;

pub use error::{At, Error, Result};
