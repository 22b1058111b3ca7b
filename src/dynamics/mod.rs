//! Lumped dynamics of the vibratory machine (in progress).
