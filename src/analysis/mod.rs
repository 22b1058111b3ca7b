//! Analyses on an assembled [`crate::system::System`]: [`modal`] (verified natural frequencies
//! and mode shapes), [`statics`] (displacements, reactions, stiffness) and [`prestress`] (the
//! geometric stiffness of a static case and the modes of the preloaded structure) and [`buckling`]
//! (the load factors at which a static case makes the structure unstable).
pub mod buckling;
pub mod harmonic;
pub mod modal;
pub mod prestress;
pub mod statics;
