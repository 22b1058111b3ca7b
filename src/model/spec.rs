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
    /// General springs: full symmetric stiffness matrices between two points or to the ground.
    pub spring_matrices: Vec<SpringMatrixSpec>,
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

impl ModelSpec {
    /// Every group the spec names (materials, supports, couplings, prescribed motion, point
    /// masses, springs, parts), in that order, repeats kept: to check them against a mesh before
    /// any model is built.
    pub fn group_names(&self) -> Vec<&str> {
        let mut g: Vec<&str> = Vec::new();
        g.extend(self.group_materials.iter().map(|(n, _)| n.as_str()));
        g.extend(self.fixes.iter().map(|(n, _)| n.as_str()));
        g.extend(self.couplings.iter().map(|c| c.group.as_str()));
        g.extend(self.prescribed.iter().map(|(n, _)| n.as_str()));
        g.extend(self.point_masses.iter().map(|p| p.group.as_str()));
        for (a, b) in self
            .springs
            .iter()
            .map(|s| (&s.a, &s.b))
            .chain(self.spring_matrices.iter().map(|s| (&s.a, &s.b)))
        {
            g.push(a);
            g.extend(b.as_deref());
        }
        g.extend(self.shells.iter().map(|p| p.group.as_str()));
        g.extend(self.beams.iter().map(|p| p.group.as_str()));
        g.extend(self.solid_groups.iter().flatten().map(String::as_str));
        g
    }
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
            spring_matrices: vec![],
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

/// A general discrete spring: a full symmetric positive semi-definite stiffness matrix in
/// global axes, between two points (12×12, the six components ux, uy, uz, rx, ry, rz of `a`
/// first, then those of `b`) or from one point to the ground (6×6). A point is a coupled group's
/// reference node or a one-node group. Built for springs condensed from FE parts (a leaf
/// spring between its clamp and its guided end) and for springs away from the point they act
/// on ([`rigid_offset`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SpringMatrixSpec {
    /// First end.
    pub a: String,
    /// Second end, or `None` for the ground.
    pub b: Option<String>,
    /// Stiffness, row-major: 144 entries between two points, 36 to the ground (N/m, N/rad,
    /// N·m/rad).
    pub k: Vec<f64>,
    /// What the spring is, for messages.
    pub label: String,
}

/// The 6×6 rigid-offset matrix `T` with `u_p = T u_r` for a point at `r = x_p − x_r` from a
/// reference point that moves rigidly with it: `u_p = u_r + θ_r × r`, `θ_p = θ_r` (row-major).
/// A stiffness `k_p` acting at the point acts on the reference as `Tᵀ k_p T`.
pub fn rigid_offset(r: [f64; 3]) -> [[f64; 6]; 6] {
    let mut t = [[0.0; 6]; 6];
    for (i, row) in t.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    // θ × r = −[r]× θ
    t[0][4] = r[2];
    t[0][5] = -r[1];
    t[1][3] = -r[2];
    t[1][5] = r[0];
    t[2][3] = r[1];
    t[2][4] = -r[0];
    t
}

/// `Tᵀ K T` for a square row-major `k` of size `6·n` and one 6×6 block `t[i]` per node
/// (block-diagonal `T`).
pub fn transform_blocks(k: &[f64], t: &[[[f64; 6]; 6]]) -> Vec<f64> {
    let n = 6 * t.len();
    debug_assert_eq!(k.len(), n * n);
    let tf = |r: usize, c: usize| -> f64 { if r / 6 == c / 6 { t[r / 6][r % 6][c % 6] } else { 0.0 } };
    // K T
    let mut kt = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            let b = j / 6;
            kt[i * n + j] = (0..6).map(|l| k[i * n + 6 * b + l] * tf(6 * b + l, j)).sum();
        }
    }
    let mut out = vec![0.0; n * n];
    for i in 0..n {
        let b = i / 6;
        for j in 0..n {
            out[i * n + j] = (0..6).map(|l| tf(6 * b + l, i) * kt[(6 * b + l) * n + j]).sum();
        }
    }
    out
}
