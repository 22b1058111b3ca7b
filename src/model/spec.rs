//! What a user asks a model to be: materials, formulations per group, supports, couplings,
//! discrete masses and springs. Plain data with no mesh attached; [`super::Model::build`]
//! binds it to a mesh.

use crate::dof::DofMask;
use crate::element::MassLumping;
use crate::material::Material;

/// What to build from a mesh.
#[derive(Clone, Debug)]
pub struct ModelSpec {
    /// Material of every solid cell not in a group with its own.
    pub material: Material,
    /// Per-group materials (later entries win where groups overlap).
    pub group_materials: Vec<(String, Material)>,
    /// Fixed components per group: `(group, mask)`.
    pub fixes: Vec<(String, DofMask)>,
    /// Mass matrix form.
    pub lumping: MassLumping,
    /// Formulation of hex8 cells (standard or with incompatible modes).
    pub hex8: crate::element::incompatible::Hex8Formulation,
    /// Rigid couplings of groups to reference nodes.
    pub couplings: Vec<CouplingSpec>,
    /// Prescribed displacements per group: `(group, [ux, uy, uz, rx, ry, rz])`, `None` = free.
    /// On a coupled group they apply to its reference node.
    pub prescribed: Vec<(String, [Option<f64>; 6])>,
    /// Point masses.
    pub point_masses: Vec<PointMassSpec>,
    /// Discrete springs.
    pub springs: Vec<SpringSpec>,
    /// Groups meshed with surface cells analysed as shells.
    pub shells: Vec<ShellPart>,
    /// Groups meshed with line cells analysed as beams.
    pub beams: Vec<BeamPart>,
    /// Volume groups analysed as solids; `None`: every volume cell of the mesh when there are no
    /// shell or beam parts, none otherwise.
    pub solid_groups: Option<Vec<String>>,
}

/// A shell part: a surface group with a section and (optionally) its own material.
#[derive(Clone, Debug, PartialEq)]
pub struct ShellPart {
    /// Surface group (tri3/quad4 cells).
    pub group: String,
    /// Thickness, offset, drilling.
    pub section: crate::section::ShellSection,
    /// Material (default: the model's).
    pub material: Option<Material>,
}

/// How a beam's local y axis is oriented.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Orientation {
    /// One vector for all elements (must not be parallel to any element axis).
    Vector([f64; 3]),
    /// Radial from an axis through `centre` along `axis` (helices, rings): the element
    /// midpoint's offset from the axis.
    Radial {
        /// A point on the axis.
        centre: [f64; 3],
        /// Axis direction.
        axis: [f64; 3],
    },
}

/// A beam part: a line group with a section and an orientation.
#[derive(Clone, Debug, PartialEq)]
pub struct BeamPart {
    /// Line group (line2/line3 cells).
    pub group: String,
    /// Section properties.
    pub section: crate::section::BeamSection,
    /// Local y axis.
    pub orientation: Orientation,
    /// Material (default: the model's).
    pub material: Option<Material>,
}

impl Default for ModelSpec {
    fn default() -> Self {
        ModelSpec {
            material: Material::steel(),
            group_materials: vec![],
            fixes: vec![],
            lumping: MassLumping::Consistent,
            hex8: Default::default(),
            couplings: vec![],
            prescribed: vec![],
            point_masses: vec![],
            springs: vec![],
            shells: vec![],
            beams: vec![],
            solid_groups: None,
        }
    }
}

/// A rigid coupling (RBE2 / kinematic coupling): every node of `group` follows a reference node
/// (at the group's centroid unless placed) as a rigid body, u_s = u_R + θ_R × (x_s − x_R) (and θ_s = θ_R for
/// nodes with rotations). Implemented by eliminating the slave DOFs, not by penalty springs.
#[derive(Clone, Debug, PartialEq)]
pub struct CouplingSpec {
    /// The coupled group.
    pub group: String,
    /// "Guided": the reference node may only translate along this axis (0 = x, 1 = y, 2 = z)
    /// and may not rotate.
    pub guided: Option<usize>,
    /// Where the reference node sits (m); `None`: the centroid of the group's nodes. A load on
    /// the reference node acts there, so an eccentric point gives a moment.
    pub reference: Option<[f64; 3]>,
}

/// A point mass with rotary inertia.
#[derive(Clone, Debug, PartialEq)]
pub struct PointMassSpec {
    /// Where: a coupled group (its reference node), a one-node group, or a group whose nodes
    /// share the mass equally (translations only).
    pub group: String,
    /// Mass, kg.
    pub mass: f64,
    /// Inertia tensor about the point, kg·m²: Ixx, Iyy, Izz, Ixy, Iyz, Ixz.
    pub inertia: [f64; 6],
}

/// A discrete spring with a diagonal 6×6 stiffness, between two groups' points or from one
/// point to the ground. A point is a coupled group's reference node or a one-node group.
#[derive(Clone, Debug, PartialEq)]
pub struct SpringSpec {
    /// First end.
    pub a: String,
    /// Second end, or `None` for the ground.
    pub b: Option<String>,
    /// Stiffness in ux, uy, uz (N/m) and rx, ry, rz (N·m/rad).
    pub k: [f64; 6],
}
