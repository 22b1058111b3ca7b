//! vibrofem: finite-element modal and stiffness analysis for vibrating machines.
//!
//! Data flows one way: mesh file → [`mesh::Mesh`] → [`model::Model`] (materials, fixes) →
//! [`dof::DofMap`] → [`assembly`] (K, M on one pattern) → [`linalg::eigen`] (verified
//! shift-invert block Lanczos) → [`post::modal`] → writers in [`io`].
//!
//! Units are SI throughout (m, kg, s, N, Pa); a mesh drawn in millimetres is scaled on reading.
//!
//! # Layers
//! The FE core (everything but [`app`]) knows nothing of the command line, plots or the
//! vibratory table; it builds alone with `cargo build --lib --no-default-features`. The
//! application (feature `app`, on by default) holds the table's lumped dynamics, the design
//! chain, studies, scenes, reports and the CLI vocabulary.
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

#[cfg(feature = "app")]
pub mod app;

pub use error::{Error, Result};
