//! The text grammars users write, shared by the command line, scene files, studies and the
//! bindings: mesh sources ([`source`]: files and the `box:`, `helix:`, `sandwich:`, `ibeam-*`
//! generators) and model options ([`options`]: materials, fixes, couplings, sections, loads).
pub mod options;
pub mod source;
