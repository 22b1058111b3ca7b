//! Loads on a model, by group: the static loads ([`Load`], per load case of
//! [`crate::analysis::statics`]) and the harmonic group forces ([`GroupForce`], of
//! [`crate::analysis::harmonic`]). Plain data, like [`super::ModelSpec`]; the text grammar that
//! reads them from options is [`crate::input::options`] (`--force`, `--pressure`, `--gravity`,
//! [`GroupForce::parse`]).

/// One load.
#[derive(Clone, Debug, PartialEq)]
pub enum Load {
    /// Total force (N) on a group.
    Force {
        /// Group.
        group: String,
        /// Fx, Fy, Fz.
        force: [f64; 3],
    },
    /// Pressure (Pa) on a surface group, positive into the solid.
    Pressure {
        /// Surface group.
        group: String,
        /// Pressure.
        p: f64,
    },
    /// Body acceleration (m/s²), e.g. gravity [0, 0, −9.81].
    Acceleration([f64; 3]),
}

/// A harmonic force on a group: F(t) = Re(F e^{i(ωt + φ)}), F total over the group (N), spread
/// as a static force is (a coupled group at its reference node, a surface group as a uniform
/// traction, other groups equally over their nodes).
#[derive(Clone, Debug, PartialEq)]
pub struct GroupForce {
    /// Group (or coupled group).
    pub group: String,
    /// Fx, Fy, Fz amplitudes (N).
    pub force: [f64; 3],
    /// Phase φ (degrees).
    pub phase_deg: f64,
}
