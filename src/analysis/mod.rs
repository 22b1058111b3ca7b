//! Analyses on an assembled [`crate::system::System`]: [`modal`] (verified natural frequencies
//! and mode shapes) and [`statics`] (displacements, reactions, stiffness).
pub mod harmonic;
pub mod modal;
pub mod statics;
