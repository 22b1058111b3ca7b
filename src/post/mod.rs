//! Post-processing of solutions.
pub mod modal;
pub mod stress;
