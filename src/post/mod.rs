//! Post-processing of solutions.
pub mod modal;
