//! vibrofem: finite-element modal and stiffness analysis for vibrating machines.
//!
//! Data flows one way: mesh file → [`mesh::Mesh`] → [`model::Model`] (materials, fixes) →
//! [`dof::DofMap`] → [`assembly`] (K, M on one pattern) → [`solve::eigen`] (verified
//! shift-invert block Lanczos) → [`post::modal`] → writers in [`io`].
//!
//! Units are SI throughout (m, kg, s, N, Pa); a mesh drawn in millimetres is scaled on reading.
#![warn(missing_docs)]

pub mod element;
pub mod error;
pub mod io;
pub mod material;
pub mod mesh;
pub mod quadrature;
pub mod shape;

pub use error::{Error, Result};
pub mod analysis;
pub mod assembly;
pub mod cli;
pub mod converge;
pub mod design;
pub mod dof;
pub mod dynamics;
pub mod machines_cli;
pub mod model;
pub mod ordering;
pub mod post;
pub mod report;
pub mod scene;
pub mod section;
pub mod solve;
pub mod sparse;
pub mod statics;
pub mod sweep;
