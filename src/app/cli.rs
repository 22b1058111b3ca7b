//! Parsing of the command-line model options shared by `modes` and `static`.
//!
//! Every parser returns an [`Error::InvalidInput`] that quotes the option and the offending text.

use crate::analysis::statics::Load;
use crate::dof::parse_components;
use crate::element::MassLumping;
use crate::material::Material;
use crate::model::{BeamPart, CouplingSpec, ModelSpec, Orientation, PointMassSpec, ShellPart, SpringSpec};
use crate::{Error, Result};

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
    /// Couple a group rigidly to a reference node at its centroid: `GROUP`, or
    /// `GROUP:guided=z` to let the reference node move only along z, without rotation.
    #[arg(long, value_name = "GROUP[:guided=AXIS]")]
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
    /// Analyse only these volume groups as solids (default: every volume cell).
    #[arg(long = "solid", value_name = "GROUP")]
    pub solid: Vec<String>,
    /// Shell part: `GROUP=t` or `GROUP=t,offset` (m; the offset moves the mid-surface from the
    /// nodes along the normal, e.g. −t/2 for a plate meshed on its bottom face).
    #[arg(long, value_name = "GROUP=T[,OFFSET]", allow_hyphen_values = true)]
    pub shell: Vec<String>,
    /// Beam part: `GROUP=SECTION@ORIENT`. SECTION: `rect:b,h`, `circle:d`, `tube:d,wall`,
    /// `i:h,b,s,t`, `channel:h,b,s,t`, `gost8239-10`, `gost8240-10`,
    /// `custom:A,Iy,Iz,J,ky,kz,Cw` (m, m², m⁴, m⁶), with `+warping` for a 7th (warping) DOF.
    /// ORIENT: the local y axis `x,y,z`, or `radial:cx,cy,cz,ax,ay,az` (from an axis).
    #[arg(long, value_name = "GROUP=SECTION@ORIENT", allow_hyphen_values = true)]
    pub beam: Vec<String>,
    /// Length unit of the mesh coordinates: m (default) or mm.
    #[arg(long = "length-unit", default_value = "m")]
    pub length_unit: String,
}

/// Numbers separated by commas.
pub fn numbers(opt: &str, text: &str, s: &str) -> Result<Vec<f64>> {
    s.split(',')
        .map(|v| {
            let x: f64 = v
                .trim()
                .parse()
                .map_err(|_| Error::InvalidInput(format!("{opt} '{text}': '{}' is not a number", v.trim())))?;
            if !x.is_finite() {
                return Err(Error::InvalidInput(format!("{opt} '{text}': {x} is not finite")));
            }
            Ok(x)
        })
        .collect()
}

/// `GROUP=a,b,c` with exactly `n` numbers.
pub fn group_values(opt: &str, text: &str, n: usize) -> Result<(String, Vec<f64>)> {
    let (g, v) = text
        .split_once('=')
        .ok_or_else(|| Error::InvalidInput(format!("{opt} '{text}': expected GROUP=values")))?;
    let v = numbers(opt, text, v)?;
    if v.len() != n {
        return Err(Error::InvalidInput(format!(
            "{opt} '{text}': expected {n} numbers, got {}",
            v.len()
        )));
    }
    Ok((g.trim().to_string(), v))
}

/// Length unit name → factor to metres.
pub fn length_scale(u: &str) -> Result<f64> {
    match u {
        "m" => Ok(1.0),
        "mm" => Ok(1e-3),
        "cm" => Ok(1e-2),
        _ => Err(Error::InvalidInput(format!(
            "--length-unit: unknown unit '{u}' (use m or mm)"
        ))),
    }
}

fn axis(opt: &str, text: &str, a: &str) -> Result<usize> {
    match a.trim() {
        "x" => Ok(0),
        "y" => Ok(1),
        "z" => Ok(2),
        _ => Err(Error::InvalidInput(format!("{opt} '{text}': axis must be x, y or z"))),
    }
}

impl ModelArgs {
    /// Build the model specification.
    pub fn spec(&self) -> Result<ModelSpec> {
        let mut spec = ModelSpec {
            material: Material::parse(&self.material)?,
            ..Default::default()
        };
        for gm in &self.group_material {
            let (g, m) = gm
                .split_once('=')
                .ok_or_else(|| Error::InvalidInput(format!("--group-material '{gm}': expected GROUP=MATERIAL")))?;
            spec.group_materials.push((g.to_string(), Material::parse(m)?));
        }
        for f in &self.fix {
            let (g, comps) = match f.split_once(':') {
                Some((g, c)) => (g, c),
                None => (f.as_str(), "ux,uy,uz"),
            };
            let mask = parse_components(comps).ok_or_else(|| {
                Error::InvalidInput(format!(
                    "--fix '{f}': unknown components '{comps}' (use ux,uy,uz,rx,ry,rz)"
                ))
            })?;
            spec.fixes.push((g.to_string(), mask));
        }
        for c in &self.couple {
            let (g, guided) = match c.split_once(':') {
                None => (c.clone(), None),
                Some((g, opt)) => {
                    let a = opt.strip_prefix("guided=").ok_or_else(|| {
                        Error::InvalidInput(format!("--couple '{c}': expected GROUP or GROUP:guided=AXIS"))
                    })?;
                    (g.to_string(), Some(axis("--couple", c, a)?))
                }
            };
            spec.couplings.push(CouplingSpec { group: g, guided });
        }
        for p in &self.point_mass {
            let (g, v) = p
                .split_once('=')
                .ok_or_else(|| Error::InvalidInput(format!("--point-mass '{p}': expected GROUP=m[,Ixx,...]")))?;
            let v = numbers("--point-mass", p, v)?;
            if v.len() != 1 && v.len() != 7 {
                return Err(Error::InvalidInput(format!(
                    "--point-mass '{p}': give the mass, or the mass and 6 inertias (Ixx,Iyy,Izz,Ixy,Iyz,Ixz)"
                )));
            }
            let mut inertia = [0.0; 6];
            if v.len() == 7 {
                inertia.copy_from_slice(&v[1..]);
            }
            spec.point_masses.push(PointMassSpec {
                group: g.to_string(),
                mass: v[0],
                inertia,
            });
        }
        for s in &self.spring {
            let (ends, v) = s
                .split_once('=')
                .ok_or_else(|| Error::InvalidInput(format!("--spring '{s}': expected A[:B]=kx,ky,kz,krx,kry,krz")))?;
            let v = numbers("--spring", s, v)?;
            if v.len() != 6 {
                return Err(Error::InvalidInput(format!("--spring '{s}': expected 6 stiffnesses")));
            }
            let (a, b) = match ends.split_once(':') {
                Some((a, b)) => (a.to_string(), Some(b.to_string())),
                None => (ends.to_string(), None),
            };
            let mut k = [0.0; 6];
            k.copy_from_slice(&v);
            spec.springs.push(SpringSpec { a, b, k });
        }
        spec.lumping = MassLumping::parse(&self.mass)?;
        if !self.solid.is_empty() {
            spec.solid_groups = Some(self.solid.clone());
        }
        for sh in &self.shell {
            let (g, v) = sh.split_once('=').ok_or_else(|| {
                Error::InvalidInput(format!(
                    "--shell '{sh}': expected GROUP=thickness[,offset] (a shell needs a thickness)"
                ))
            })?;
            let v = numbers("--shell", sh, v)?;
            if v.is_empty() || v.len() > 2 {
                return Err(Error::InvalidInput(format!(
                    "--shell '{sh}': expected thickness[,offset]"
                )));
            }
            let mut sec = crate::section::ShellSection::new(v[0]);
            if v.len() == 2 {
                sec = sec.with_offset(v[1]);
            }
            spec.shells.push(ShellPart {
                group: g.to_string(),
                section: sec,
                material: None,
            });
        }
        for b in &self.beam {
            spec.beams.push(parse_beam(b)?);
        }
        Ok(spec)
    }
}

/// Parse a `--beam GROUP=SECTION@ORIENT` option.
pub fn parse_beam(b: &str) -> Result<BeamPart> {
    use crate::section::BeamSection;
    let (g, rest) = b.split_once('=').ok_or_else(|| {
        Error::InvalidInput(format!(
            "--beam '{b}': expected GROUP=SECTION@ORIENT (a beam needs a section)"
        ))
    })?;
    let (sec, orient) = rest.split_once('@').ok_or_else(|| {
        Error::InvalidInput(format!(
            "--beam '{b}': missing orientation, e.g. '@0,0,1' (the local y axis)"
        ))
    })?;
    let (sec, warping) = match sec.strip_suffix("+warping") {
        Some(s) => (s, true),
        None => (sec, false),
    };
    let (name, vals) = sec.split_once(':').unwrap_or((sec, ""));
    let v = if vals.is_empty() {
        vec![]
    } else {
        numbers("--beam", b, vals)?
    };
    let need = |n: usize| -> Result<()> {
        if v.len() == n {
            Ok(())
        } else {
            Err(Error::InvalidInput(format!(
                "--beam '{b}': section '{name}' needs {n} numbers, got {}",
                v.len()
            )))
        }
    };
    let section = match name {
        "rect" => {
            need(2)?;
            BeamSection::rectangle(v[0], v[1])
        }
        "circle" => {
            need(1)?;
            BeamSection::circle(v[0])
        }
        "tube" => {
            need(2)?;
            BeamSection::tube(v[0], v[1])
        }
        "i" => {
            need(4)?;
            BeamSection::i_beam(v[0], v[1], v[2], v[3])
        }
        "channel" => {
            need(4)?;
            BeamSection::channel(v[0], v[1], v[2], v[3])
        }
        "gost8239-10" => {
            need(0)?;
            BeamSection::gost_8239_i10()
        }
        "gost8240-10" => {
            need(0)?;
            BeamSection::gost_8240_channel10()
        }
        "custom" => {
            need(7)?;
            BeamSection::custom(v[0], v[1], v[2], v[3], v[4], v[5], v[6])
        }
        _ => {
            return Err(Error::InvalidInput(format!(
                "--beam '{b}': unknown section '{name}' (rect, circle, tube, i, channel, gost8239-10, gost8240-10, custom)"
            )));
        }
    }
    .with_warping(warping);
    let orientation = if let Some(r) = orient.strip_prefix("radial:") {
        let v = numbers("--beam", b, r)?;
        if v.len() != 6 {
            return Err(Error::InvalidInput(format!(
                "--beam '{b}': radial orientation needs cx,cy,cz,ax,ay,az"
            )));
        }
        Orientation::Radial {
            centre: [v[0], v[1], v[2]],
            axis: [v[3], v[4], v[5]],
        }
    } else {
        let v = numbers("--beam", b, orient)?;
        if v.len() != 3 || v.iter().all(|x| *x == 0.0) {
            return Err(Error::InvalidInput(format!(
                "--beam '{b}': orientation must be a non-zero vector x,y,z"
            )));
        }
        Orientation::Vector([v[0], v[1], v[2]])
    };
    Ok(BeamPart {
        group: g.to_string(),
        section,
        orientation,
        material: None,
    })
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
        let mut loads = Vec::new();
        for f in &self.force {
            let (g, v) = group_values("--force", f, 3)?;
            loads.push(Load::Force {
                group: g,
                force: [v[0], v[1], v[2]],
            });
        }
        for p in &self.pressure {
            let (g, v) = group_values("--pressure", p, 1)?;
            loads.push(Load::Pressure { group: g, p: v[0] });
        }
        if let Some(g) = &self.gravity {
            let v = numbers("--gravity", g, g)?;
            if v.len() != 3 {
                return Err(Error::InvalidInput(format!("--gravity '{g}': expected gx,gy,gz")));
            }
            loads.push(Load::Acceleration([v[0], v[1], v[2]]));
        }
        for d in &self.displace {
            let (g, v) = d
                .split_once('=')
                .ok_or_else(|| Error::InvalidInput(format!("--displace '{d}': expected GROUP=ux,uy,uz")))?;
            let parts: Vec<&str> = v.split(',').collect();
            if parts.len() != 3 && parts.len() != 6 {
                return Err(Error::InvalidInput(format!(
                    "--displace '{d}': expected 3 (or 6) values"
                )));
            }
            let mut vals = [None; 6];
            for (i, p) in parts.iter().enumerate() {
                let p = p.trim();
                if p == "-" || p.is_empty() {
                    continue;
                }
                let x: f64 = p
                    .parse()
                    .map_err(|_| Error::InvalidInput(format!("--displace '{d}': '{p}' is not a number")))?;
                if !x.is_finite() {
                    return Err(Error::InvalidInput(format!("--displace '{d}': {x} is not finite")));
                }
                vals[i] = Some(x);
            }
            spec.prescribed.push((g.to_string(), vals));
        }
        Ok(loads)
    }
}
