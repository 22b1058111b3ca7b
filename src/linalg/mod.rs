//! Sparse linear algebra: symmetric storage ([`sparse`]), the node graph ([`graph`]),
//! fill-reducing orderings ([`ordering`]), the LDLᵀ factorisation with inertia ([`factor`]), a
//! dense oracle ([`dense`]) and the verified shift-invert block Lanczos eigen solver
//! ([`eigen`]). Nothing here knows a mesh: indices are equations, mapped to nodes and
//! components by [`crate::dof::DofMap`].
pub mod coarse;
pub mod dense;
pub mod eigen;
pub mod factor;
pub mod floor;
pub mod graph;
pub mod ordering;
pub mod sparse;
pub mod supernodal;
pub mod tall;
pub mod trisolve;
