//! Structured mesh generators.
