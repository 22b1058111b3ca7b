//! Analyses on an assembled [`crate::system::System`]: [`modal`] (verified natural frequencies
//! and mode shapes), [`statics`] (displacements, reactions, stiffness) and [`prestress`] (the
//! geometric stiffness of a static case and the modes of the preloaded structure).
pub mod harmonic;
pub mod modal;
pub mod prestress;
pub mod statics;
