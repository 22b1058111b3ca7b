//! Validation against independent references, one module per source:
//!
//! - `skfem_modes`, `skfem_static`: scikit-fem on the very same meshes with the same elements
//!   (references in `validation/reference/`, regenerated live by `validation/run_live.sh`);
//! - `published_shells_beams`: published benchmarks (Scordelis–Lo roof, Navier plate, MacNeal–
//!   Harder, closed-form beams) and the formulation comparisons of scenes S1, S2, S5, S6, S7;
//! - `buckling`: linear buckling against Euler columns (beams, hex20, tet10 with Engesser's
//!   shear correction), the k = 4 plate and the prestressed beam's vanishing frequency;
//! - `prestress`: prestressed modes against the axially loaded beam's closed form, and the
//!   geometric stiffness kernels' exact properties;
//! - `haringx`: the coil spring buckling criterion against Shigley's form;
//! - `prestress_one_mode`: a prestressed request for a single mode passes its Sturm check.

#[path = "../common/mod.rs"]
mod common;

mod buckling;
mod fatigue;
mod haringx;
mod harmonic;
mod prestress;
mod prestress_one_mode;
mod published_shells_beams;
mod skfem_modes;
mod skfem_static;
