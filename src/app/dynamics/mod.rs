//! Lumped dynamics of the two-mass electromagnetic vibratory table (docs/spec/paper.md §5–§8, §16–§19).
//!
//! - [`two_mass`]: the model of eq. (1) ([`TwoMass`]), steady state by eq. (2)–(4), dynamic factors
//!   eq. (7), amplitude–frequency and phase curves, resonance peaks, closed-form natural frequencies,
//!   static response, floor force, drive power.
//! - [`tuning`]: c12 from the tuning z (eq. (5)) and back, leaf thickness eq. (16) and its inverse,
//!   leaf stress, damping from a loss factor, drive power eq. (6).
//! - [`electromagnet`]: the rectified single-stroke magnet force P_em·|sin ωt|, its Fourier terms,
//!   the pull needed for a target amplitude, the static offset, and the periodic steady state under
//!   the full force by harmonic balance.
//! - [`transient`]: start-up from rest under the rectified force ([`simulate_startup`]), integrated
//!   with the Dormand–Prince 5(4) integrator of [`ode`]; steady amplitude, offset and settling time.
//! - [`isolation`]: isolator stiffness from the isolation frequency, transmissibility, coil springs.
//! - [`plot`]: SVG figures.
//! - [`ode`]: the Dormand–Prince 5(4) integrator shared with the machines ([`crate::app::machines`]).
//!
//! Units are SI throughout: kg, m, s, N, N/m, N·s/m, rad/s (angular frequencies) and Hz (where
//! named `_hz`). Bad input gives [`crate::Error::param`] naming the parameter; nothing panics.
//!
//! Which mass carries the isolators is in doubt in the paper (printed k-terms against eq. (1)):
//! see [`KTerms`].

pub mod electromagnet;
pub mod isolation;
pub mod ode;
pub mod plot;
pub mod transient;
pub mod tuning;
pub mod two_mass;

pub use electromagnet::{PeriodicResponse, PeriodicSummary, RectifiedDrive, fourier_coefficient};
pub use isolation::CoilSpring;
pub use transient::{Transient, TransientOptions, TransientSummary, simulate_startup};
pub use two_mass::{DynamicStiffness, KTerms, Mass, ResonancePeak, SteadyState, TwoMass};
