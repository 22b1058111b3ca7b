//! The design room: the vibratory-table design chain, the 3D machine and the search for a
//! passing variant.
//!
//! Dependencies point one way (each file uses only those above it):
//! - [`file`]: the design file ([`Design`] and its parts), read from TOML and checked before any
//!   work;
//! - [`parts`]: the FE parts built from it (leaf, coil, work table);
//! - [`machine`]: the 3D machine assembled from the parts (modes, forced response);
//! - [`results`]: what a run computes ([`ChainValues`], [`DesignReport`]);
//! - [`checks`], [`reference`]: the checks, and the quantity table with the paper's values;
//! - [`plots`]: the figures written beside the report;
//! - [`chain`]: the run as named steps ([`run_design`]);
//! - [`report`]: [`DesignReport`] as a [`crate::app::report::Report`];
//! - [`envelope`]: every check over the load cases and tolerance bands (through [`run_design`];
//!   [`cache`] memoises the FE parts the runs share);
//! - [`search`]: the lightest passing variant, through [`run_design`] (the chain does not know
//!   the search exists).
//!
//! The lumped dynamics it uses (two-mass model, magnet, isolation, transient, tuning, plots) are
//! the shared toolkit of [`crate::app::dynamics`].

pub mod cache;
pub mod chain;
pub mod checks;
pub mod envelope;
pub mod fatigue;
pub mod file;
pub mod job;
pub mod machine;
pub mod parts;
pub mod plots;
pub mod reduced;
pub mod reference;
pub mod report;
pub mod results;
pub mod search;
pub mod startup;

pub use chain::run_design;
pub use envelope::{EnvelopeDesign, EnvelopeResult};
pub use file::{
    CoilDesign, DampingDesign, Design, DriveDesign, LeafDesign, MAX_TRANSIENT_S, MachineDesign, MassDesign,
    SearchDesign, TableDesign,
};
pub use machine::{MachineMode, MachineResult, analyse};
pub use parts::{
    CHANNEL10_FLANGE, LARGE_DESIGN_DOFS, coil_fe, coil_stiffness, coil_stiffness_along, estimate_dofs,
    leaf_end_stiffness, leaf_fe, leaf_matrix, sandwich_clear_webs, table_fe, table_mass, table_parts,
};
pub use report::{report_html, report_markdown, verdict_text};
pub use results::{ChainValues, Check, DesignReport, Quantity};
pub use search::{Candidate, SearchOutcome, search, search_text, search_with};
