//! Beam and shell cross-section properties (in progress).
