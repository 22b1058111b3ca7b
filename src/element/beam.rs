//! 3D Timoshenko beam elements (in progress).
