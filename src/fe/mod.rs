//! Reference-element mathematics shared by every formulation: shape functions ([`shape`]),
//! integration rules ([`quadrature`]) and the geometry of mapped cells ([`geometry`]).
pub mod geometry;
pub mod quadrature;
pub mod shape;
