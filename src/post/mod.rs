//! Post-processing of solutions.
pub mod fatigue;
pub mod mass;
pub mod modal;
pub mod spring;
pub mod stress;
