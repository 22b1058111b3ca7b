//! The command line's model and load options (clap), over the core grammar of
//! [`crate::input::options`].

use crate::Result;
use crate::analysis::statics::Load;
use crate::input::options::{LoadOptions, ModelOptions};
use crate::model::ModelSpec;

pub use crate::input::options::{group_values, length_scale, numbers, parse_beam};

/// Model options as given on the command line.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct ModelArgs {
    /// Material of all volume cells: `steel` or `E,NU,RHO` in Pa, -, kg/m³.
    #[arg(long, default_value = "steel", allow_hyphen_values = true)]
    pub material: String,
    /// Material of one group: `GROUP=steel` or `GROUP=E,NU,RHO` (repeatable).
    #[arg(long = "group-material", value_name = "GROUP=MAT", allow_hyphen_values = true)]
    pub group_material: Vec<String>,
    /// Fix a group's nodes: `GROUP` (all translations) or `GROUP:ux,uy,uz` (repeatable).
    #[arg(long, value_name = "GROUP[:COMPONENTS]")]
    pub fix: Vec<String>,
    /// Couple a group rigidly to a reference node: `GROUP` (node at the group's centroid),
    /// `GROUP@X,Y,Z` (node at that point, m), with `:guided=z` to let the reference node move
    /// only along z, without rotation (e.g. `end_top@0,0,0.06:guided=z`).
    #[arg(long, value_name = "GROUP[@X,Y,Z][:guided=AXIS]", allow_hyphen_values = true)]
    pub couple: Vec<String>,
    /// Point mass: `GROUP=m` or `GROUP=m,Ixx,Iyy,Izz,Ixy,Iyz,Ixz` (kg, kg·m²); on a coupled
    /// group it sits at the reference node.
    #[arg(long = "point-mass", value_name = "GROUP=M[,I...]")]
    pub point_mass: Vec<String>,
    /// Discrete spring: `A=kx,ky,kz,krx,kry,krz` to the ground or `A:B=...` between two points
    /// (coupled groups or one-node groups); N/m and N·m/rad.
    #[arg(long, value_name = "A[:B]=K6")]
    pub spring: Vec<String>,
    /// Mass matrix: consistent (default) or lumped (HRZ).
    #[arg(long, default_value = "consistent")]
    pub mass: String,
    /// Hex8 formulation: standard (default; locks in bending, e.g. one element through a
    /// thickness) or incompatible (Wilson–Taylor incompatible modes, condensed per element).
    #[arg(long, default_value = "standard", value_name = "standard|incompatible")]
    pub hex8: String,
    /// Analyse only these volume groups as solids (default: every volume cell).
    #[arg(long = "solid", value_name = "GROUP")]
    pub solid: Vec<String>,
    /// Shell part: `GROUP=t` or `GROUP=t,offset` (m; the offset moves the mid-surface from the
    /// nodes along the normal, e.g. −t/2 for a plate meshed on its bottom face).
    #[arg(long, value_name = "GROUP=T[,OFFSET]", allow_hyphen_values = true)]
    pub shell: Vec<String>,
    /// Beam part: `GROUP=SECTION@ORIENT`. SECTION: `rect:b,h`, `circle:d`, `tube:d,wall`,
    /// `i:h,b,s,t`, `channel:h,b,s,t`, `gost8239-10`, `gost8240-10`,
    /// `custom:A,Iy,Iz,J,ky,kz,Cw` (m, m², m⁴, m⁶), with `+warping` for a 7th (warping) DOF
    /// (line2 cells only; line3 beams refuse it). ORIENT: the local y axis `x,y,z` (made
    /// orthogonal to the element axis x; z = x × y), or `radial:cx,cy,cz,ax,ay,az` (from an
    /// axis). Sections put their depth h along local z and their width b (the flanges of I and
    /// channel sections) along local y: the orientation vector points along the flanges.
    #[arg(long, value_name = "GROUP=SECTION@ORIENT", allow_hyphen_values = true)]
    pub beam: Vec<String>,
    /// Length unit of the mesh coordinates: m (default), cm or mm.
    #[arg(long = "length-unit", default_value = "m")]
    pub length_unit: String,
}

impl ModelArgs {
    /// The options in the core grammar.
    pub fn options(&self) -> ModelOptions {
        ModelOptions {
            material: self.material.clone(),
            group_material: self.group_material.clone(),
            fix: self.fix.clone(),
            couple: self.couple.clone(),
            point_mass: self.point_mass.clone(),
            spring: self.spring.clone(),
            mass: self.mass.clone(),
            hex8: self.hex8.clone(),
            solid: self.solid.clone(),
            shell: self.shell.clone(),
            beam: self.beam.clone(),
            length_unit: self.length_unit.clone(),
        }
    }

    /// Build the model specification.
    pub fn spec(&self) -> Result<ModelSpec> {
        self.options().spec()
    }
}

/// Loads and prescribed displacements given to `vibrofem static`.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct LoadArgs {
    /// Total force on a group: `GROUP=Fx,Fy,Fz` (N). A coupled group takes it at its reference
    /// node; a surface group as a uniform traction; other groups split it between their nodes.
    #[arg(long, value_name = "GROUP=FX,FY,FZ", allow_hyphen_values = true)]
    pub force: Vec<String>,
    /// Pressure on a surface group: `GROUP=p` (Pa, positive into the solid).
    #[arg(long, value_name = "GROUP=P", allow_hyphen_values = true)]
    pub pressure: Vec<String>,
    /// Body acceleration `gx,gy,gz` (m/s²), e.g. `0,0,-9.81`.
    #[arg(long, value_name = "GX,GY,GZ", allow_hyphen_values = true)]
    pub gravity: Option<String>,
    /// Prescribed displacement: `GROUP=ux,uy,uz` (m; `-` leaves a component free). On a coupled
    /// group it moves the reference node.
    #[arg(long, value_name = "GROUP=UX,UY,UZ", allow_hyphen_values = true)]
    pub displace: Vec<String>,
}

impl LoadArgs {
    /// Add the prescribed displacements to `spec` and return the loads (one case).
    pub fn apply(&self, spec: &mut ModelSpec) -> Result<Vec<Load>> {
        LoadOptions {
            force: self.force.clone(),
            pressure: self.pressure.clone(),
            gravity: self.gravity.clone(),
            displace: self.displace.clone(),
        }
        .apply(spec)
    }
}

/// A count that must be at least 1 (`--jobs`, `--levels`): clap's parser for such options.
pub fn at_least_one(s: &str) -> std::result::Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(v) => Ok(v),
        Err(e) => Err(format!("expected a whole number ≥ 1 ({e})")),
    }
}
