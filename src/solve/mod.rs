//! Linear and eigen solvers.
pub mod dense;
pub mod eigen;
pub mod factor;
