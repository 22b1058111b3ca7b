//! Post-processing of solutions.
pub mod mass;
pub mod modal;
pub mod stress;
