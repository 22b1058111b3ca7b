//! Reference-element mathematics shared by every formulation: shape functions ([`shape`]) and
//! integration rules ([`quadrature`]).
pub mod quadrature;
pub mod shape;
