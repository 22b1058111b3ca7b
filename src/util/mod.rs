//! Helpers at the bottom of the crate, for every layer: the formatting of numbers for
//! messages ([`fmt`]) and the memory of the process ([`memory`]). Nothing here uses the rest of
//! the crate.

pub mod fmt;
pub mod memory;
