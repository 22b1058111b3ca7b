//! Element kernels: local stiffness and mass matrices, volumes and stress recovery.
//!
//! Kernels know no global numbering. They write dense row-major local matrices with node-major
//! degrees of freedom (`[n0.ux, n0.uy, n0.uz, n1.ux, …]`) into caller-provided buffers, so
//! assembly can reuse one buffer per thread and allocate nothing per element. A non-positive
//! Jacobian determinant comes back as `Err(det)`; the caller names the element in the
//! [`crate::Error::InvertedElement`] it reports.
//!
//! - [`solid`]: isoparametric 3D solids (`Tet4/10`, `Hex8/20/27`, `Wedge6/15`).
//! - [`lumping`]: the [`MassLumping`] choice and the HRZ and row-sum lumping schemes.

pub mod beam;
pub mod lumping;
pub mod shell;
pub mod solid;

pub use lumping::MassLumping;
