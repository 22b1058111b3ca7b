//! Readers and writers: gmsh MSH (4.1 and 2.2, ASCII and binary), VTU, JSON.
//!
//! vibrofem keeps gmsh's node ordering internally; writers that need another convention
//! (VTK) permute at output, with the permutation tables kept next to the writer
//! ([`vtk::gmsh_to_vtk`]).

pub mod gmsh;
pub mod msh_out;
pub mod source;
pub mod vtk;

/// A float in the shortest form that reads back exactly: plain decimals for ordinary
/// magnitudes, exponent form for very small or large ones (Rust's plain form of `1e-300`
/// would have 300 zeros).
pub(crate) fn fmt_f64(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (1e-4..1e15).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}
