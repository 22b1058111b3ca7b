//! The text grammar of model options and loads, shared by the command line, scene files and
//! the bindings, so that `GROUP=t,offset` or `i:h,b,s,t@0,0,1` mean the same everywhere.
//!
//! Every parser returns an error placed at the option ([`Error::option`]; a beam section or
//! orientation read alone, at [`Error::param`]) whose message quotes the option (by its
//! command-line name, which the scene and binding documentation also use) and the offending text.

use crate::dof::parse_components;
use crate::element::MassLumping;
use crate::material::Material;
use crate::model::{
    BeamPart, CouplingSpec, GroupForce, Load, ModelSpec, Orientation, PointMassSpec, ShellPart, SpringSpec,
};
use crate::section::BeamSection;
use crate::{Error, Result};

/// Model options in the shared text grammar (the command line's `--material`, `--fix`, …;
/// the bindings' keyword arguments). [`ModelOptions::spec`] parses them into a [`ModelSpec`].
#[derive(Clone, Debug, PartialEq)]
pub struct ModelOptions {
    /// Material of all volume cells: `steel` or `E,NU,RHO` in Pa, -, kg/m³.
    pub material: String,
    /// Material of one group: `GROUP=steel` or `GROUP=E,NU,RHO` (repeatable).
    pub group_material: Vec<String>,
    /// Fix a group's nodes: `GROUP` (all translations) or `GROUP:ux,uy,uz` (repeatable).
    pub fix: Vec<String>,
    /// Couple a group rigidly to a reference node: `GROUP` (at its centroid) or `GROUP@X,Y,Z`,
    /// with `:guided=AXIS` to let the reference node move only along that axis, without rotation.
    pub couple: Vec<String>,
    /// Point mass: `GROUP=m` or `GROUP=m,Ixx,Iyy,Izz,Ixy,Iyz,Ixz` (kg, kg·m²); on a coupled
    /// group it sits at the reference node.
    pub point_mass: Vec<String>,
    /// Discrete spring: `A=kx,ky,kz,krx,kry,krz` to the ground or `A:B=...` between two points
    /// (coupled groups or one-node groups); N/m and N·m/rad.
    pub spring: Vec<String>,
    /// Mass matrix: consistent (default) or lumped (HRZ).
    pub mass: String,
    /// Hex8 formulation: `standard` (default) or `incompatible` (Wilson–Taylor incompatible
    /// modes, condensed: bends without locking).
    pub hex8: String,
    /// Analyse only these volume groups as solids (default: every volume cell).
    pub solid: Vec<String>,
    /// Shell part: `GROUP=t` or `GROUP=t,offset` (m; the offset is the nodes' signed distance
    /// from the mid-surface along the normal, which puts the mid-surface at x − offset·n: −t/2
    /// for a plate meshed on its bottom face, the plate on the side its normal points to).
    pub shell: Vec<String>,
    /// Beam part: `GROUP=SECTION@ORIENT`. SECTION: `rect:b,h`, `circle:d`, `tube:d,wall`,
    /// `i:h,b,s,t`, `channel:h,b,s,t`, `gost8239-10`, `gost8240-10`,
    /// `custom:A,Iy,Iz,J,ky,kz,Cw` (m, m², m⁴, m⁶), with `+warping` for a 7th (warping) DOF.
    /// ORIENT: the local y axis `x,y,z`, or `radial:cx,cy,cz,ax,ay,az` (from an axis).
    pub beam: Vec<String>,
    /// Length unit of the mesh coordinates: m (default), cm or mm.
    pub length_unit: String,
}

impl Default for ModelOptions {
    fn default() -> Self {
        ModelOptions {
            material: "steel".into(),
            group_material: vec![],
            fix: vec![],
            couple: vec![],
            point_mass: vec![],
            spring: vec![],
            mass: "consistent".into(),
            hex8: "standard".into(),
            solid: vec![],
            shell: vec![],
            beam: vec![],
            length_unit: "m".into(),
        }
    }
}

/// Split `text` into a group and what follows its `:` — where the group may itself be an
/// unnamed group's `dimension:tag` (`2:5:ux` is group `2:5`, components `ux`).
pub fn split_group(text: &str) -> (&str, Option<&str>) {
    let mut parts = text.splitn(3, ':');
    let (a, b) = (parts.next().unwrap_or(""), parts.next());
    let numeric = |s: &str| !s.is_empty() && s.bytes().all(|c| c.is_ascii_digit());
    match b {
        Some(b) if numeric(a) && numeric(b) => (&text[..a.len() + 1 + b.len()], parts.next()),
        _ => match text.split_once(':') {
            Some((g, rest)) => (g, Some(rest)),
            None => (text, None),
        },
    }
}

/// Numbers separated by commas.
pub fn numbers(opt: &str, text: &str, s: &str) -> Result<Vec<f64>> {
    s.split(',')
        .map(|v| {
            let x: f64 = v
                .trim()
                .parse()
                .map_err(|_| Error::option(opt, format!("{opt} '{text}': '{}' is not a number", v.trim())))?;
            if !x.is_finite() {
                return Err(Error::option(opt, format!("{opt} '{text}': {x} is not finite")));
            }
            Ok(x)
        })
        .collect()
}

/// `GROUP=a,b,c` with exactly `n` numbers.
pub fn group_values(opt: &str, text: &str, n: usize) -> Result<(String, Vec<f64>)> {
    let (g, v) = text
        .split_once('=')
        .ok_or_else(|| Error::option(opt, format!("{opt} '{text}': expected GROUP=values")))?;
    let v = numbers(opt, text, v)?;
    if v.len() != n {
        return Err(Error::option(
            opt,
            format!("{opt} '{text}': expected {n} numbers, got {}", v.len()),
        ));
    }
    Ok((g.trim().to_string(), v))
}

/// Length unit name → factor to metres.
pub fn length_scale(u: &str) -> Result<f64> {
    match u {
        "m" => Ok(1.0),
        "mm" => Ok(1e-3),
        "cm" => Ok(1e-2),
        _ => Err(Error::option(
            "--length-unit",
            format!("--length-unit: unknown unit '{u}' (use m, cm or mm)"),
        )),
    }
}

fn axis(opt: &str, text: &str, a: &str) -> Result<usize> {
    match a.trim() {
        "x" => Ok(0),
        "y" => Ok(1),
        "z" => Ok(2),
        _ => Err(Error::option(opt, format!("{opt} '{text}': axis must be x, y or z"))),
    }
}

impl ModelOptions {
    /// Build the model specification.
    pub fn spec(&self) -> Result<ModelSpec> {
        let mut spec = ModelSpec {
            material: Material::parse(&self.material)?,
            ..Default::default()
        };
        for gm in &self.group_material {
            let (g, m) = gm.split_once('=').ok_or_else(|| {
                Error::option(
                    "--group-material",
                    format!("--group-material '{gm}': expected GROUP=MATERIAL"),
                )
            })?;
            spec.group_materials.push((g.to_string(), Material::parse(m)?));
        }
        for f in &self.fix {
            let (g, comps) = match split_group(f) {
                (g, Some(c)) => (g, c),
                (g, None) => (g, "ux,uy,uz"),
            };
            let mask = parse_components(comps).ok_or_else(|| {
                Error::option(
                    "--fix",
                    format!("--fix '{f}': unknown components '{comps}' (use ux,uy,uz,rx,ry,rz)"),
                )
            })?;
            spec.fixes.push((g.to_string(), mask));
        }
        for c in &self.couple {
            spec.couplings.push(parse_coupling(c)?);
        }
        for p in &self.point_mass {
            let (g, v) = p.split_once('=').ok_or_else(|| {
                Error::option(
                    "--point-mass",
                    format!("--point-mass '{p}': expected GROUP=m[,Ixx,...]"),
                )
            })?;
            let v = numbers("--point-mass", p, v)?;
            if v.len() != 1 && v.len() != 7 {
                return Err(Error::option(
                    "--point-mass",
                    format!("--point-mass '{p}': give the mass, or the mass and 6 inertias (Ixx,Iyy,Izz,Ixy,Iyz,Ixz)"),
                ));
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
            let (ends, v) = s.split_once('=').ok_or_else(|| {
                Error::option(
                    "--spring",
                    format!("--spring '{s}': expected A[:B]=kx,ky,kz,krx,kry,krz"),
                )
            })?;
            let v = numbers("--spring", s, v)?;
            if v.len() != 6 {
                return Err(Error::option(
                    "--spring",
                    format!("--spring '{s}': expected 6 stiffnesses"),
                ));
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
        spec.hex8 = crate::element::incompatible::Hex8Formulation::parse(&self.hex8)?;
        if !self.solid.is_empty() {
            spec.solid_groups = Some(self.solid.clone());
        }
        for sh in &self.shell {
            let (g, v) = sh.split_once('=').ok_or_else(|| {
                Error::option(
                    "--shell",
                    format!("--shell '{sh}': expected GROUP=thickness[,offset] (a shell needs a thickness)"),
                )
            })?;
            let v = numbers("--shell", sh, v)?;
            if v.is_empty() || v.len() > 2 {
                return Err(Error::option(
                    "--shell",
                    format!("--shell '{sh}': expected thickness[,offset]"),
                ));
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
        // A group given twice would be assembled twice (two layers, twice the mass).
        let mut seen = std::collections::BTreeSet::new();
        for g in spec
            .shells
            .iter()
            .map(|s| &s.group)
            .chain(spec.beams.iter().map(|b| &b.group))
        {
            if !seen.insert(g.as_str()) {
                return Err(Error::group(
                    g.as_str(),
                    format!("group '{g}' is given two sections (--shell/--beam twice): each group takes one"),
                ));
            }
        }
        Ok(spec)
    }
}

/// Parse a `--couple GROUP[@X,Y,Z][:guided=AXIS]` option: the group, where its reference
/// node sits (default: the group's centroid) and the guided axis.
pub fn parse_coupling(c: &str) -> Result<CouplingSpec> {
    let bad = || {
        Error::option(
            "--couple",
            format!("--couple '{c}': expected GROUP[@X,Y,Z][:guided=AXIS]"),
        )
    };
    let (head, guided) = match c.rsplit_once(":guided=") {
        Some((h, a)) => (h, Some(axis("--couple", c, a)?)),
        None => (c, None),
    };
    let (g, reference) = match head.split_once('@') {
        Some((g, p)) => {
            let v = numbers("--couple", c, p)?;
            if v.len() != 3 {
                return Err(bad());
            }
            (g, Some([v[0], v[1], v[2]]))
        }
        None => (head, None),
    };
    // Anything after ':' left in the group is an option this grammar does not know (a
    // dimension:tag group name, `2:5`, is a group).
    if let (_, Some(_)) = split_group(g) {
        let numeric = g
            .split(':')
            .all(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()));
        if !numeric {
            return Err(bad());
        }
    }
    if g.is_empty() {
        return Err(bad());
    }
    Ok(CouplingSpec {
        group: g.to_string(),
        guided,
        reference,
    })
}

/// Parse a `--beam GROUP=SECTION@ORIENT` option.
pub fn parse_beam(b: &str) -> Result<BeamPart> {
    let (g, rest) = b.split_once('=').ok_or_else(|| {
        Error::option(
            "--beam",
            format!("--beam '{b}': expected GROUP=SECTION@ORIENT (a beam needs a section)"),
        )
    })?;
    let (sec, orient) = rest.split_once('@').ok_or_else(|| {
        Error::option(
            "--beam",
            format!("--beam '{b}': missing orientation, e.g. '@0,0,1' (the local y axis)"),
        )
    })?;
    let ctx = |e: Error| match e {
        Error::Invalid { msg, .. } => Error::option("--beam", format!("--beam '{b}': {msg}")),
        e => e,
    };
    Ok(BeamPart {
        group: g.to_string(),
        section: parse_section(sec).map_err(ctx)?,
        orientation: parse_orientation(orient).map_err(ctx)?,
        material: None,
    })
}

/// Parse a beam section: `rect:b,h`, `circle:d`, `tube:d,wall`, `i:h,b,s,t`, `channel:h,b,s,t`,
/// `gost8239-10`, `gost8240-10` or `custom:A,Iy,Iz,J,ky,kz,Cw` (m, m², m⁴, m⁶), with `+warping`
/// for a seventh (warping) DOF per node.
pub fn parse_section(sec: &str) -> Result<BeamSection> {
    let (sec, warping) = match sec.strip_suffix("+warping") {
        Some(s) => (s, true),
        None => (sec, false),
    };
    let (name, vals) = sec.split_once(':').unwrap_or((sec, ""));
    let v = if vals.is_empty() {
        vec![]
    } else {
        numbers("section", sec, vals)?
    };
    let need = |n: usize| -> Result<()> {
        if v.len() == n {
            Ok(())
        } else {
            Err(Error::param(
                "section",
                format!("section '{name}' needs {n} numbers, got {}", v.len()),
            ))
        }
    };
    // Dimensions of the shape sections: positive and finite, and a shape that exists (a
    // squared or fourth-power formula would take a negative diameter silently).
    if matches!(name, "rect" | "circle" | "tube" | "i" | "channel") {
        let labels: &[&str] = match name {
            "rect" => &["b", "h"],
            "circle" => &["d"],
            "tube" => &["d", "wall"],
            _ => &["h", "b", "s", "t"],
        };
        for (l, x) in labels.iter().zip(&v) {
            if !(x.is_finite() && *x > 0.0) {
                return Err(Error::param(
                    "section",
                    format!("section '{sec}': {l} = {x} m must be positive and finite"),
                ));
            }
        }
        if name == "tube" && v.len() == 2 && v[1] > v[0] / 2.0 {
            return Err(Error::param(
                "section",
                format!(
                    "section '{sec}': wall {} m exceeds the radius {} m (at most d/2: a solid circle)",
                    v[1],
                    v[0] / 2.0
                ),
            ));
        }
        if matches!(name, "i" | "channel") && v.len() == 4 {
            let (h, b, s, t) = (v[0], v[1], v[2], v[3]);
            if 2.0 * t >= h {
                return Err(Error::param(
                    "section",
                    format!("section '{sec}': two flanges of t = {t} m fill the height h = {h} m (2t must be below h)"),
                ));
            }
            if s > b {
                return Err(Error::param(
                    "section",
                    format!("section '{sec}': web s = {s} m is wider than the flanges b = {b} m"),
                ));
            }
        }
    }
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
            return Err(Error::param(
                "section",
                format!("unknown section '{name}' (rect, circle, tube, i, channel, gost8239-10, gost8240-10, custom)"),
            ));
        }
    };
    Ok(section.with_warping(warping))
}

/// Parse a beam orientation: the local y axis `x,y,z`, or `radial:cx,cy,cz,ax,ay,az` (from an
/// axis through the point c along a).
pub fn parse_orientation(orient: &str) -> Result<Orientation> {
    if let Some(r) = orient.strip_prefix("radial:") {
        let v = numbers("orientation", orient, r)?;
        if v.len() != 6 {
            return Err(Error::param(
                "orientation",
                "radial orientation needs cx,cy,cz,ax,ay,az".to_string(),
            ));
        }
        if v[3..].iter().all(|x| *x == 0.0) {
            return Err(Error::param(
                "orientation",
                format!("radial orientation '{orient}': the axis ax,ay,az must be a non-zero vector"),
            ));
        }
        Ok(Orientation::Radial {
            centre: [v[0], v[1], v[2]],
            axis: [v[3], v[4], v[5]],
        })
    } else {
        let v = numbers("orientation", orient, orient)?;
        if v.len() != 3 || v.iter().all(|x| *x == 0.0) {
            return Err(Error::param(
                "orientation",
                "orientation must be a non-zero vector x,y,z".to_string(),
            ));
        }
        Ok(Orientation::Vector([v[0], v[1], v[2]]))
    }
}

/// Loads and prescribed displacements in the shared text grammar (`vibrofem static`'s
/// `--force`, `--pressure`, `--gravity`, `--displace`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// Total force on a group: `GROUP=Fx,Fy,Fz` (N). A coupled group takes it at its reference
    /// node; a surface group as a uniform traction; other groups split it between their nodes.
    pub force: Vec<String>,
    /// Pressure on a surface group: `GROUP=p` (Pa, positive into the solid).
    pub pressure: Vec<String>,
    /// Body acceleration `gx,gy,gz` (m/s²), e.g. `0,0,-9.81`.
    pub gravity: Option<String>,
    /// Prescribed displacement: `GROUP=ux,uy,uz` (m; `-` leaves a component free). On a coupled
    /// group it moves the reference node.
    pub displace: Vec<String>,
}

impl LoadOptions {
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
                return Err(Error::option(
                    "--gravity",
                    format!("--gravity '{g}': expected gx,gy,gz"),
                ));
            }
            loads.push(Load::Acceleration([v[0], v[1], v[2]]));
        }
        for d in &self.displace {
            let (g, v) = d
                .split_once('=')
                .ok_or_else(|| Error::option("--displace", format!("--displace '{d}': expected GROUP=ux,uy,uz")))?;
            let parts: Vec<&str> = v.split(',').collect();
            if parts.len() != 3 && parts.len() != 6 {
                return Err(Error::option(
                    "--displace",
                    format!("--displace '{d}': expected 3 (or 6) values"),
                ));
            }
            let mut vals = [None; 6];
            for (i, p) in parts.iter().enumerate() {
                let p = p.trim();
                if p == "-" || p.is_empty() {
                    continue;
                }
                let x: f64 = p
                    .parse()
                    .map_err(|_| Error::option("--displace", format!("--displace '{d}': '{p}' is not a number")))?;
                if !x.is_finite() {
                    return Err(Error::option(
                        "--displace",
                        format!("--displace '{d}': {x} is not finite"),
                    ));
                }
                vals[i] = Some(x);
            }
            spec.prescribed.push((g.to_string(), vals));
        }
        Ok(loads)
    }
}

/// A harmonic group force in the same grammar as a static `--force`, with a phase.
impl GroupForce {
    /// `GROUP=Fx,Fy,Fz` or `GROUP=Fx,Fy,Fz@PHASE_DEG` (`opt` names the option in messages:
    /// `--force`).
    pub fn parse(opt: &str, text: &str) -> Result<GroupForce> {
        let (body, phase) = match text.rsplit_once('@') {
            Some((b, p)) => {
                let v: f64 = p.trim().parse().map_err(|_| {
                    Error::option(
                        opt,
                        format!("{opt} '{text}': cannot read the phase '{p}' (degrees, e.g. GROUP=0,0,100@90)"),
                    )
                })?;
                if !v.is_finite() {
                    return Err(Error::option(opt, format!("{opt} '{text}': the phase must be finite")));
                }
                (b, v)
            }
            None => (text, 0.0),
        };
        let (group, v) = group_values(opt, body, 3)?;
        Ok(GroupForce {
            group,
            force: [v[0], v[1], v[2]],
            phase_deg: phase,
        })
    }
}
