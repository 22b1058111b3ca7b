//! Helpers at the bottom of the crate, for every layer: the formatting of numbers for
//! messages ([`fmt`]), the memory of the process ([`memory`]) and unequal tasks scheduled
//! heaviest first ([`queue`]). Nothing here uses the rest of the crate.

pub mod fmt;
pub mod memory;
pub mod queue;

/// The larger of two numbers, NaN if either is: a verdict (largest residual, backward error)
/// must not drop a NaN as `f64::max` does.
pub fn max_nan(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() { f64::NAN } else { a.max(b) }
}
