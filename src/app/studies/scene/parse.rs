//! The scene file grammar: the raw TOML schema (every field optional, so that a missing key gets
//! our own message), and [`Scene::parse`] section by section — header, `[mesh]`, materials,
//! parts, supports and couplings, masses and springs, prescribed motion, loads, `[harmonic]`,
//! `[modal]`, `[output]`. Every error names the file and the line of its table.

use super::{Formulation, GroupRef, MeshSource, Scene};
use crate::analysis::modal::ModalTarget;
use crate::analysis::statics::Load;
use crate::app::toml_file;
use crate::dof::parse_components;
use crate::element::MassLumping;
use crate::material::Material;
use crate::model::{CouplingSpec, ModelSpec, PointMassSpec, ShellPart, SpringSpec};
use crate::section::ShellSection;
use crate::{Error, Result};
use serde::Deserialize;
use std::path::Path;
use toml::Spanned;

type Span = std::ops::Range<usize>;

// ---------------------------------------------------------------------------------------------
// Raw TOML schema (every field optional so that missing keys get our own messages).

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawScene {
    scene: Option<Spanned<RawHeader>>,
    mesh: Option<Spanned<RawMesh>>,
    #[serde(default)]
    material: Vec<Spanned<RawMaterial>>,
    #[serde(default)]
    part: Vec<Spanned<RawPart>>,
    #[serde(default)]
    fix: Vec<Spanned<RawFix>>,
    #[serde(default)]
    couple: Vec<Spanned<RawCouple>>,
    #[serde(default)]
    point_mass: Vec<Spanned<RawPointMass>>,
    #[serde(default)]
    spring: Vec<Spanned<RawSpring>>,
    #[serde(default)]
    displace: Vec<Spanned<RawDisplace>>,
    #[serde(default)]
    load: Vec<Spanned<RawLoad>>,
    #[serde(default)]
    load_case: Vec<Spanned<RawLoadCase>>,
    modal: Option<Spanned<RawModal>>,
    #[serde(rename = "static")]
    statics: Option<Spanned<RawStatic>>,
    harmonic: Option<Spanned<RawHarmonic>>,
    buckling: Option<Spanned<RawBuckling>>,
    output: Option<Spanned<RawOutput>>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawHeader {
    version: Option<i64>,
    name: Option<String>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    file: Option<String>,
    generator: Option<String>,
    length_unit: Option<String>,
    hex8: Option<String>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    name: Option<String>,
    young: Option<f64>,
    poisson: Option<f64>,
    density: Option<f64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(untagged)]
enum RawOrientation {
    Vector(Vec<f64>),
    Text(String),
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawPart {
    group: Option<String>,
    formulation: Option<String>,
    material: Option<String>,
    thickness: Option<f64>,
    offset: Option<f64>,
    section: Option<String>,
    orientation: Option<RawOrientation>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawFix {
    group: Option<String>,
    dofs: Option<Vec<String>>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawCouple {
    group: Option<String>,
    guided: Option<String>,
    reference: Option<Vec<f64>>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawPointMass {
    group: Option<String>,
    mass: Option<f64>,
    inertia: Option<Vec<f64>>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawSpring {
    a: Option<String>,
    b: Option<String>,
    k: Option<Vec<f64>>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawDisplace {
    group: Option<String>,
    ux: Option<f64>,
    uy: Option<f64>,
    uz: Option<f64>,
    rx: Option<f64>,
    ry: Option<f64>,
    rz: Option<f64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawLoad {
    group: Option<String>,
    force: Option<Vec<f64>>,
    pressure: Option<f64>,
    gravity: Option<Vec<f64>>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawLoadCase {
    /// The case's name, for the reader of the file (reports number the cases).
    #[allow(dead_code)]
    name: Option<String>,
    #[serde(default)]
    load: Vec<Spanned<RawLoad>>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawModal {
    modes: Option<i64>,
    band: Option<Vec<f64>>,
    shift_hz: Option<f64>,
    mass: Option<String>,
    block: Option<i64>,
    engine: Option<String>,
    ranks: Option<i64>,
    prestress: Option<i64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawBuckling {
    modes: Option<i64>,
    case: Option<i64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawStatic {}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawHarmonic {
    /// `"GROUP=FX,FY,FZ"` or `"GROUP=FX,FY,FZ@PHASE_DEG"`, as `--force` of `vibrofem harmonic`.
    #[serde(default)]
    force: Vec<String>,
    freq_hz: Option<f64>,
    sweep_hz: Option<Vec<f64>>,
    damping: Option<f64>,
    rayleigh: Option<Vec<f64>>,
    method: Option<String>,
    modes: Option<i64>,
    #[serde(default)]
    probe: Vec<String>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    vtu: Option<bool>,
    msh: Option<bool>,
}

// ---------------------------------------------------------------------------------------------
// Messages.

/// Context for messages: the file and the line of a span.
struct Ctx<'a> {
    file: String,
    text: &'a str,
}

impl Ctx<'_> {
    fn line(&self, offset: usize) -> usize {
        toml_file::line_of(self.text, offset)
    }
    fn err<T>(&self, span: Span, msg: impl std::fmt::Display) -> Result<T> {
        Err(self.error(span, msg))
    }
    /// An error at the line where `span` starts.
    fn error(&self, span: Span, msg: impl std::fmt::Display) -> Error {
        toml_file::file_error(self.file.clone(), Some(self.line(span.start)), msg.to_string())
    }
    /// An error about the whole file (no line).
    fn whole(&self, msg: impl std::fmt::Display) -> Error {
        toml_file::file_error(self.file.clone(), None, msg.to_string())
    }
    fn need<'v, T>(&self, v: &'v Option<T>, span: Span, key: &str, place: &str) -> Result<&'v T> {
        match v {
            Some(x) => Ok(x),
            None => self.err(span, format!("missing '{key}' key in {place}")),
        }
    }
    fn finite(&self, span: Span, what: &str, v: &[f64]) -> Result<()> {
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return self.err(span, format!("{what}: {x} is not finite"));
        }
        Ok(())
    }
    fn vec3(&self, span: Span, what: &str, v: &[f64]) -> Result<[f64; 3]> {
        if v.len() != 3 {
            return self.err(span, format!("{what} needs 3 numbers, got {}", v.len()));
        }
        self.finite(span, what, v)?;
        Ok([v[0], v[1], v[2]])
    }
}

fn unit_scale(u: &str) -> Option<f64> {
    match u {
        "m" => Some(1.0),
        "cm" => Some(1e-2),
        "mm" => Some(1e-3),
        _ => None,
    }
}

fn formulation_name(f: Formulation) -> &'static str {
    match f {
        Formulation::Solid => "solid",
        Formulation::Shell => "shell",
        Formulation::Beam => "beam",
    }
}

// ---------------------------------------------------------------------------------------------
// The sections.

/// The scene being read: the model spec and the group references filled section by section.
struct Reader<'a> {
    ctx: Ctx<'a>,
    spec: ModelSpec,
    groups: Vec<GroupRef>,
}

impl Scene {
    /// Read and validate a scene file. Errors name the file, line and key.
    pub fn load(path: &Path) -> Result<Scene> {
        let text = toml_file::read(path)?;
        Scene::parse(path, &text)
    }

    /// Parse scene text; `path` names the file in messages and anchors relative mesh paths.
    pub fn parse(path: &Path, text: &str) -> Result<Scene> {
        let text = text.strip_prefix(toml_file::BOM).unwrap_or(text);
        let raw: RawScene = toml_file::parse(path, text)?;
        let mut r = Reader {
            ctx: Ctx {
                file: path.display().to_string(),
                text,
            },
            spec: ModelSpec::default(),
            groups: Vec::new(),
        };
        let name = r.header(&raw, path)?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let (mesh, length_scale) = r.mesh(&raw, &base)?;
        let materials = r.materials(&raw.material)?;
        let parts = r.parts(&raw.part, &materials)?;
        r.supports(&raw)?;
        r.masses_and_springs(&raw)?;
        r.displacements(&raw.displace)?;
        let static_cases = r.load_cases(&raw)?;
        let harmonic = r.harmonic(&raw.harmonic)?;
        let (modal, slepc_ranks) = r.modal(&raw.modal)?;
        let n_cases = static_cases.as_ref().map_or(0, Vec::len);
        let prestress = match &raw.modal {
            Some(m) => r.case_number(m.get_ref().prestress, m.span(), "[modal] 'prestress'", n_cases)?,
            None => None,
        };
        if prestress.is_some() && slepc_ranks.is_some() {
            return r.ctx.err(
                raw.modal.as_ref().map_or(0..0, |m| m.span()),
                "prestressed modes are solved by engine = \"native\" only",
            );
        }
        let buckling = r.buckling(&raw.buckling, n_cases)?;
        if modal.is_none() && static_cases.is_none() && harmonic.is_none() && buckling.is_none() {
            return Err(r.ctx.whole(
                "the scene asks for no analysis: add [modal], [harmonic], [buckling], or [static] / [[load]] / [[displace]]",
            ));
        }
        let (vtu, msh) = raw
            .output
            .as_ref()
            .map(|o| (o.get_ref().vtu.unwrap_or(false), o.get_ref().msh.unwrap_or(false)))
            .unwrap_or((false, false));
        Ok(Scene {
            path: path.to_path_buf(),
            name,
            mesh,
            length_scale,
            spec: r.spec,
            parts,
            modal,
            prestress,
            buckling,
            static_cases,
            harmonic,
            vtu,
            msh,
            slepc_ranks,
            groups: r.groups,
        })
    }
}

impl Reader<'_> {
    /// A group named by a table of the scene, checked against the mesh later.
    fn refer(&mut self, group: &str, span: Span, what: String) {
        let line = self.ctx.line(span.start);
        self.groups.push(GroupRef {
            group: group.to_string(),
            line,
            what,
            needs_dim: None,
        });
    }

    /// `[scene]`: the version (1) and the name (default: the file stem).
    fn header(&self, raw: &RawScene, path: &Path) -> Result<String> {
        let ctx = &self.ctx;
        let header = raw
            .scene
            .as_ref()
            .ok_or_else(|| ctx.whole("missing [scene] table (with version = 1)"))?;
        let version = *ctx.need(&header.get_ref().version, header.span(), "version", "[scene]")?;
        if version != toml_file::VERSION {
            return ctx.err(
                header.span(),
                format!("unsupported scene version {version} (this vibrofem reads version 1)"),
            );
        }
        Ok(header.get_ref().name.clone().unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        }))
    }

    /// `[mesh]`: the source, the length unit and the hex8 formulation (into the spec).
    fn mesh(&mut self, raw: &RawScene, base: &Path) -> Result<(MeshSource, f64)> {
        let ctx = &self.ctx;
        let Some(m) = &raw.mesh else {
            return Ok((MeshSource::Missing, 1.0));
        };
        let r = m.get_ref();
        let src = match (&r.file, &r.generator) {
            (Some(_), Some(_)) => {
                return ctx.err(m.span(), "[mesh] takes either 'file' or 'generator', not both");
            }
            (Some(f), None) if f.trim().is_empty() => {
                return ctx.err(m.span(), "[mesh] 'file' is empty: give the mesh file's path");
            }
            (Some(f), None) => MeshSource::File(base.join(f)),
            (None, Some(g)) => MeshSource::Generator(g.clone()),
            (None, None) => MeshSource::Missing,
        };
        let scale = match &r.length_unit {
            None => 1.0,
            Some(u) => unit_scale(u).ok_or_else(|| {
                ctx.error(
                    m.span(),
                    format!("unknown 'length_unit' '{u}' in [mesh] (use m, cm or mm)"),
                )
            })?,
        };
        if let Some(h) = &r.hex8 {
            self.spec.hex8 = crate::element::incompatible::Hex8Formulation::parse(h)
                .map_err(|e| ctx.error(m.span(), format!("[mesh] 'hex8': {e}")))?;
        }
        Ok((src, scale))
    }

    /// `[[material]]` tables: named, complete, valid, each once.
    fn materials(&self, raw: &[Spanned<RawMaterial>]) -> Result<Vec<(String, Material)>> {
        let ctx = &self.ctx;
        let mut materials: Vec<(String, Material)> = Vec::new();
        for m in raw {
            let r = m.get_ref();
            let name = ctx.need(&r.name, m.span(), "name", "[[material]]")?.clone();
            let place = format!("material '{name}'");
            let mat = Material {
                young: *ctx.need(&r.young, m.span(), "young", &place)?,
                poisson: *ctx.need(&r.poisson, m.span(), "poisson", &place)?,
                density: *ctx.need(&r.density, m.span(), "density", &place)?,
            };
            if materials.iter().any(|(n, _)| *n == name) {
                return ctx.err(m.span(), format!("material '{name}' is defined twice"));
            }
            if let Err(e) = mat.validate(&format!("'{name}'")) {
                return ctx.err(m.span(), e);
            }
            materials.push((name, mat));
        }
        Ok(materials)
    }

    /// The material a part names (none: the first defined, else steel).
    fn find_material(
        &self,
        materials: &[(String, Material)],
        n: &Option<String>,
        span: Span,
        place: &str,
    ) -> Result<Material> {
        let Some(n) = n else {
            return Ok(materials.first().map(|m| m.1).unwrap_or_else(Material::steel));
        };
        match materials.iter().find(|m| m.0 == *n) {
            Some(m) => Ok(m.1),
            None if n == "steel" => Ok(Material::steel()),
            None => {
                let known: Vec<&str> = materials.iter().map(|m| m.0.as_str()).collect();
                let known = if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                };
                self.ctx.err(
                    span,
                    format!("unknown material '{n}' in {place} (defined: {known}; 'steel' is built in)"),
                )
            }
        }
    }

    /// `[[part]]` tables: the groups the scene includes, each with its formulation and
    /// material (into the spec). The first solid part's material is the model's default.
    fn parts(
        &mut self,
        raw: &[Spanned<RawPart>],
        materials: &[(String, Material)],
    ) -> Result<Vec<(String, Formulation)>> {
        if raw.is_empty() {
            return Err(self.ctx.whole(
                "no [[part]]: a scene includes only the groups it names (e.g. group = \"body\", formulation = \"solid\")",
            ));
        }
        let mut parts: Vec<(String, Formulation)> = Vec::new();
        let mut solid_groups = Vec::new();
        let mut default_material = None;
        for p in raw {
            let r = p.get_ref();
            let sp = p.span();
            let group = self.ctx.need(&r.group, sp.clone(), "group", "[[part]]")?.clone();
            let place = format!("part '{group}'");
            let form = match self
                .ctx
                .need(&r.formulation, sp.clone(), "formulation", &place)?
                .as_str()
            {
                "solid" => Formulation::Solid,
                "shell" => Formulation::Shell,
                "beam" => Formulation::Beam,
                f => {
                    return self.ctx.err(
                        sp,
                        format!("unknown formulation '{f}' in {place} (use solid, shell or beam)"),
                    );
                }
            };
            if parts.iter().any(|(g, _)| *g == group) {
                return self.ctx.err(sp, format!("group '{group}' is named by two parts"));
            }
            let mat = self.find_material(materials, &r.material, sp.clone(), &place)?;
            self.keys_apply(r, form, sp.clone(), &place)?;
            match form {
                Formulation::Solid => {
                    default_material.get_or_insert(mat);
                    self.spec.group_materials.push((group.clone(), mat));
                    solid_groups.push(group.clone());
                }
                Formulation::Shell => self.shell_part(r, &group, mat, sp.clone(), &place)?,
                Formulation::Beam => self.beam_part(r, &group, mat, sp.clone(), &place)?,
            }
            let dim = match form {
                Formulation::Solid => 3,
                Formulation::Shell => 2,
                Formulation::Beam => 1,
            };
            self.groups.push(GroupRef {
                group: group.clone(),
                line: self.ctx.line(sp.start),
                what: place,
                needs_dim: Some((dim, form)),
            });
            parts.push((group, form));
        }
        self.spec.material =
            default_material.unwrap_or_else(|| materials.first().map(|m| m.1).unwrap_or_else(Material::steel));
        if !solid_groups.is_empty() {
            self.spec.solid_groups = Some(solid_groups);
        }
        Ok(parts)
    }

    /// Refuse the keys of a part that its formulation does not take.
    fn keys_apply(&self, r: &RawPart, form: Formulation, sp: Span, place: &str) -> Result<()> {
        let given = [
            ("thickness", r.thickness.is_some(), form != Formulation::Shell),
            ("offset", r.offset.is_some(), form != Formulation::Shell),
            ("section", r.section.is_some(), form != Formulation::Beam),
            ("orientation", r.orientation.is_some(), form != Formulation::Beam),
        ];
        for (key, present, refused) in given {
            if present && refused {
                return self.ctx.err(
                    sp,
                    format!("'{key}' does not apply to a {} part ({place})", formulation_name(form)),
                );
            }
        }
        Ok(())
    }

    /// A shell part: thickness (required, positive) and offset.
    fn shell_part(&mut self, r: &RawPart, group: &str, mat: Material, sp: Span, place: &str) -> Result<()> {
        let t = *self.ctx.need(&r.thickness, sp.clone(), "thickness", place)?;
        if !(t.is_finite() && t > 0.0) {
            return self
                .ctx
                .err(sp, format!("'thickness' must be positive, got {t} in {place}"));
        }
        let mut section = ShellSection::new(t);
        if let Some(o) = r.offset {
            self.ctx.finite(sp.clone(), "'offset'", &[o])?;
            section = section.with_offset(o);
        }
        self.spec.shells.push(ShellPart {
            group: group.to_string(),
            section,
            material: Some(mat),
        });
        Ok(())
    }

    /// A beam part: section and orientation (both required).
    fn beam_part(&mut self, r: &RawPart, group: &str, mat: Material, sp: Span, place: &str) -> Result<()> {
        let ctx = &self.ctx;
        let sec = ctx.need(&r.section, sp.clone(), "section", place)?;
        let orientation = match ctx.need(&r.orientation, sp.clone(), "orientation", place)? {
            RawOrientation::Vector(v) => {
                let v = ctx.vec3(sp.clone(), "'orientation'", v)?;
                if v.iter().all(|x| *x == 0.0) {
                    return ctx.err(sp, format!("{place}: orientation must be a non-zero vector x,y,z"));
                }
                crate::model::Orientation::Vector(v)
            }
            RawOrientation::Text(s) => crate::input::options::parse_orientation(s)
                .map_err(|e| ctx.error(sp.clone(), format!("{place}: {e}")))?,
        };
        let section =
            crate::input::options::parse_section(sec).map_err(|e| ctx.error(sp.clone(), format!("{place}: {e}")))?;
        if let Err(e) = section.validate(place) {
            return ctx.err(sp, e);
        }
        self.spec.beams.push(crate::model::BeamPart {
            group: group.to_string(),
            section,
            orientation,
            material: Some(mat),
        });
        Ok(())
    }

    /// `[[fix]]` and `[[couple]]` tables.
    fn supports(&mut self, raw: &RawScene) -> Result<()> {
        for f in &raw.fix {
            let r = f.get_ref();
            let g = self.ctx.need(&r.group, f.span(), "group", "[[fix]]")?;
            let comps = r
                .dofs
                .clone()
                .unwrap_or_else(|| vec!["ux".into(), "uy".into(), "uz".into()]);
            let mask = parse_components(&comps.join(",")).ok_or_else(|| {
                self.ctx.error(
                    f.span(),
                    format!("unknown 'dofs' {comps:?} in fix '{g}' (use ux, uy, uz, rx, ry, rz or all)"),
                )
            })?;
            self.refer(g, f.span(), format!("fix '{g}'"));
            self.spec.fixes.push((g.clone(), mask));
        }
        for c in &raw.couple {
            let r = c.get_ref();
            let g = self.ctx.need(&r.group, c.span(), "group", "[[couple]]")?;
            let guided = match r.guided.as_deref() {
                None => None,
                Some("x") => Some(0),
                Some("y") => Some(1),
                Some("z") => Some(2),
                Some(a) => {
                    return self.ctx.err(
                        c.span(),
                        format!("'guided' must be x, y or z, got '{a}' in couple '{g}'"),
                    );
                }
            };
            let reference = match &r.reference {
                None => None,
                Some(v) => Some(self.ctx.vec3(c.span(), "'reference'", v)?),
            };
            self.refer(g, c.span(), format!("couple '{g}'"));
            self.spec.couplings.push(CouplingSpec {
                group: g.clone(),
                guided,
                reference,
            });
        }
        Ok(())
    }

    /// `[[point_mass]]` and `[[spring]]` tables.
    fn masses_and_springs(&mut self, raw: &RawScene) -> Result<()> {
        for p in &raw.point_mass {
            let r = p.get_ref();
            let g = self.ctx.need(&r.group, p.span(), "group", "[[point_mass]]")?;
            let place = format!("point_mass '{g}'");
            let m = *self.ctx.need(&r.mass, p.span(), "mass", &place)?;
            if !(m.is_finite() && m >= 0.0) {
                return self
                    .ctx
                    .err(p.span(), format!("'mass' must be non-negative, got {m} in {place}"));
            }
            let mut inertia = [0.0; 6];
            if let Some(i) = &r.inertia {
                if i.len() != 6 {
                    return self.ctx.err(
                        p.span(),
                        format!("'inertia' needs 6 numbers (Ixx, Iyy, Izz, Ixy, Iyz, Ixz) in {place}"),
                    );
                }
                self.ctx.finite(p.span(), "'inertia'", i)?;
                inertia.copy_from_slice(i);
            }
            self.refer(g, p.span(), place);
            self.spec.point_masses.push(PointMassSpec {
                group: g.clone(),
                mass: m,
                inertia,
            });
        }
        for s in &raw.spring {
            let r = s.get_ref();
            let a = self.ctx.need(&r.a, s.span(), "a", "[[spring]]")?;
            let place = format!("spring '{a}'");
            let k = self.ctx.need(&r.k, s.span(), "k", &place)?;
            if k.len() != 6 {
                return self.ctx.err(
                    s.span(),
                    format!("'k' needs 6 stiffnesses (kx, ky, kz, krx, kry, krz) in {place}"),
                );
            }
            self.ctx.finite(s.span(), "'k'", k)?;
            if k.iter().any(|&v| v < 0.0) {
                return self
                    .ctx
                    .err(s.span(), format!("'k' must be non-negative, got {k:?} in {place}"));
            }
            if r.b.as_ref() == Some(a) {
                return self.ctx.err(
                    s.span(),
                    format!("'b' is '{a}', the group of 'a': a spring joins two points (leave 'b' out for one to the ground) in {place}"),
                );
            }
            self.refer(a, s.span(), place.clone());
            if let Some(b) = &r.b {
                self.refer(b, s.span(), place);
            }
            let mut kk = [0.0; 6];
            kk.copy_from_slice(k);
            self.spec.springs.push(SpringSpec {
                a: a.clone(),
                b: r.b.clone(),
                k: kk,
            });
        }
        Ok(())
    }

    /// `[[displace]]` tables: prescribed motion of groups.
    fn displacements(&mut self, raw: &[Spanned<RawDisplace>]) -> Result<()> {
        for d in raw {
            let r = d.get_ref();
            let g = self.ctx.need(&r.group, d.span(), "group", "[[displace]]")?;
            let vals = [r.ux, r.uy, r.uz, r.rx, r.ry, r.rz];
            if vals.iter().all(Option::is_none) {
                return self.ctx.err(
                    d.span(),
                    format!("displace '{g}' prescribes nothing (give ux, uy, uz, rx, ry or rz)"),
                );
            }
            let given: Vec<f64> = vals.iter().flatten().copied().collect();
            self.ctx.finite(d.span(), &format!("displace '{g}'"), &given)?;
            self.refer(g, d.span(), format!("displace '{g}'"));
            self.spec.prescribed.push((g.clone(), vals));
        }
        Ok(())
    }

    /// One `[[load]]`: a force or a pressure on a group, or gravity on the whole model.
    fn load(&mut self, l: &Spanned<RawLoad>) -> Result<Load> {
        let r = l.get_ref();
        let n = r.force.is_some() as u8 + r.pressure.is_some() as u8 + r.gravity.is_some() as u8;
        if n != 1 {
            return self.ctx.err(
                l.span(),
                "a [[load]] needs exactly one of 'force', 'pressure' or 'gravity'",
            );
        }
        if let Some(g) = &r.gravity {
            if r.group.is_some() {
                return self
                    .ctx
                    .err(l.span(), "a 'gravity' load acts on the whole model: remove 'group'");
            }
            return Ok(Load::Acceleration(self.ctx.vec3(l.span(), "'gravity'", g)?));
        }
        let g = self.ctx.need(&r.group, l.span(), "group", "[[load]]")?;
        self.refer(g, l.span(), format!("load on '{g}'"));
        if let Some(f) = &r.force {
            Ok(Load::Force {
                group: g.clone(),
                force: self.ctx.vec3(l.span(), "'force'", f)?,
            })
        } else {
            let p = r.pressure.unwrap_or(0.0);
            self.ctx.finite(l.span(), "'pressure'", &[p])?;
            Ok(Load::Pressure { group: g.clone(), p })
        }
    }

    /// `[[load]]` (one case) or `[[load_case]]` tables; a static analysis is asked by
    /// `[static]`, by loads or by prescribed motion (an unloaded case then).
    fn load_cases(&mut self, raw: &RawScene) -> Result<Option<Vec<Vec<Load>>>> {
        if !raw.load.is_empty() && !raw.load_case.is_empty() {
            return self.ctx.err(
                raw.load_case[0].span(),
                "give either [[load]] (one load case) or [[load_case]] tables, not both",
            );
        }
        let mut cases = Vec::new();
        if !raw.load.is_empty() {
            let c = raw.load.iter().map(|l| self.load(l)).collect::<Result<Vec<_>>>()?;
            cases.push(c);
        }
        for (i, lc) in raw.load_case.iter().enumerate() {
            // Names are for the reader of the file: two cases with one name would be confused.
            if let Some(name) = &lc.get_ref().name
                && let Some(j) = raw.load_case[..i]
                    .iter()
                    .position(|o| o.get_ref().name.as_ref() == Some(name))
            {
                return self.ctx.err(
                    lc.span(),
                    format!(
                        "load case name '{name}' is given to cases {} and {}: give each its own",
                        j + 1,
                        i + 1
                    ),
                );
            }
            let c = lc
                .get_ref()
                .load
                .iter()
                .map(|l| self.load(l))
                .collect::<Result<Vec<_>>>()?;
            cases.push(c);
        }
        if raw.statics.is_none() && cases.is_empty() && self.spec.prescribed.is_empty() {
            return Ok(None);
        }
        if cases.is_empty() {
            cases.push(Vec::new());
        }
        Ok(Some(cases))
    }

    /// `[harmonic]`: forces, frequencies, damping, method, modes and probes.
    fn harmonic(
        &mut self,
        raw: &Option<Spanned<RawHarmonic>>,
    ) -> Result<Option<crate::app::harmonic::HarmonicRequest>> {
        let Some(h) = raw else {
            return Ok(None);
        };
        let r = h.get_ref();
        let sp = h.span();
        let e = |msg: String| self.ctx.error(sp.clone(), msg);
        if r.force.is_empty() {
            return self
                .ctx
                .err(sp, "[harmonic] needs 'force = [\"GROUP=FX,FY,FZ[@PHASE_DEG]\", ...]'");
        }
        let mut forces = Vec::new();
        for f in &r.force {
            let gf = crate::analysis::harmonic::GroupForce::parse("'force'", f).map_err(|x| e(x.to_string()))?;
            forces.push(gf);
        }
        let freqs_hz = self.harmonic_frequencies(r, sp.clone())?;
        let damping = self.harmonic_damping(r, sp.clone())?;
        let method = crate::app::harmonic::Method::parse(r.method.as_deref().unwrap_or("modal"))
            .map_err(|x| e(x.to_string().replace("--method", "'method'")))?;
        let modes = match r.modes {
            Some(n) if n < 1 => return self.ctx.err(sp, format!("'modes' must be at least 1, got {n}")),
            Some(n) => Some(n as usize),
            None => None,
        };
        for gf in &forces {
            self.refer(&gf.group, sp.clone(), format!("harmonic force on '{}'", gf.group));
        }
        for g in &r.probe {
            self.refer(g, sp.clone(), format!("harmonic probe '{g}'"));
        }
        Ok(Some(crate::app::harmonic::HarmonicRequest {
            forces,
            freqs_hz,
            damping,
            method,
            modes,
            probes: r.probe.clone(),
        }))
    }

    /// `freq_hz = F` or `sweep_hz = [F0, F1, N]`.
    fn harmonic_frequencies(&self, r: &RawHarmonic, sp: Span) -> Result<Vec<f64>> {
        match (r.freq_hz, &r.sweep_hz) {
            (Some(_), Some(_)) => self.ctx.err(sp, "[harmonic] takes 'freq_hz' or 'sweep_hz', not both"),
            (Some(f), None) => {
                if !(f.is_finite() && f >= 0.0) {
                    return self
                        .ctx
                        .err(sp, format!("'freq_hz' must be a finite frequency ≥ 0, got {f}"));
                }
                Ok(vec![f])
            }
            (None, Some(v)) => {
                if v.len() != 3 || v[2].fract() != 0.0 || v[2] < 0.0 {
                    return self.ctx.err(
                        sp,
                        format!("'sweep_hz' must be [F0, F1, N] with N a whole number, got {v:?}"),
                    );
                }
                crate::app::harmonic::sweep_frequencies(v[0], v[1], v[2] as usize)
                    .map_err(|x| self.ctx.error(sp, x.to_string().replace("--sweep", "'sweep_hz'")))
            }
            (None, None) => self
                .ctx
                .err(sp, "[harmonic] needs 'freq_hz' or 'sweep_hz = [F0, F1, N]'"),
        }
    }

    /// `damping = ZETA` or `rayleigh = [ALPHA, BETA]`, validated.
    fn harmonic_damping(&self, r: &RawHarmonic, sp: Span) -> Result<crate::analysis::harmonic::Damping> {
        use crate::analysis::harmonic::Damping;
        let damping = match (r.damping, &r.rayleigh) {
            (Some(_), Some(_)) => {
                return self.ctx.err(sp, "[harmonic] takes 'damping' or 'rayleigh', not both");
            }
            (Some(z), None) => Damping::Ratio(z),
            (None, Some(v)) if v.len() == 2 => Damping::Rayleigh {
                alpha: v[0],
                beta: v[1],
            },
            (None, Some(v)) => {
                return self.ctx.err(sp, format!("'rayleigh' must be [ALPHA, BETA], got {v:?}"));
            }
            (None, None) => {
                return self.ctx.err(
                    sp,
                    "[harmonic] needs 'damping' (modal ratio, e.g. 0.02) or 'rayleigh = [ALPHA, BETA]'",
                );
            }
        };
        damping.validate().map_err(|x| {
            self.ctx.error(
                sp,
                x.to_string()
                    .replace("--damping", "'damping'")
                    .replace("--rayleigh", "'rayleigh'"),
            )
        })?;
        Ok(damping)
    }

    /// `[modal]`: the target (modes or band), shift, mass lumping (into the spec), block, and
    /// the engine (`Some(ranks)` for SLEPc).
    #[allow(clippy::type_complexity)]
    fn modal(
        &mut self,
        raw: &Option<Spanned<RawModal>>,
    ) -> Result<(Option<(ModalTarget, Option<f64>, usize)>, Option<usize>)> {
        let Some(m) = raw else {
            return Ok((None, None));
        };
        let ctx = &self.ctx;
        let r = m.get_ref();
        let target = match (r.modes, &r.band) {
            (Some(_), Some(_)) => {
                return ctx.err(m.span(), "[modal] takes either 'modes' or 'band', not both");
            }
            (_, Some(b)) => {
                if b.len() != 2 || b.iter().any(|x| !x.is_finite()) || b[0] >= b[1] {
                    return ctx.err(
                        m.span(),
                        format!("'band' must be [f_lo, f_hi] with f_lo < f_hi, got {b:?}"),
                    );
                }
                ModalTarget::Band(b[0], b[1])
            }
            (Some(n), None) => {
                if n < 1 {
                    return ctx.err(m.span(), format!("'modes' must be at least 1, got {n}"));
                }
                ModalTarget::Modes(n as usize)
            }
            (None, None) => ModalTarget::Modes(12),
        };
        if let Some(s) = r.shift_hz {
            ctx.finite(m.span(), "'shift_hz'", &[s])?;
        }
        // As `modes --band/--shift` check them, but named by this file's keys.
        let far = r
            .band
            .iter()
            .flatten()
            .chain(&r.shift_hz)
            .find(|&&f| !crate::analysis::modal::usable_hz(f));
        if let Some(f) = far {
            let key = if r.shift_hz == Some(*f) { "shift_hz" } else { "band" };
            return ctx.err(
                m.span(),
                format!(
                    "'{key}': {} Hz is not a usable frequency ((2πf)² overflows double precision)",
                    crate::io::fmt_plain(*f)
                ),
            );
        }
        if let Some(mass) = &r.mass {
            self.spec.lumping = MassLumping::parse(mass).map_err(|e| ctx.error(m.span(), e))?;
        }
        let block = r.block.unwrap_or(6);
        if block < 1 {
            return ctx.err(m.span(), format!("'block' must be at least 1, got {block}"));
        }
        let slepc_ranks = match (r.engine.as_deref(), r.ranks) {
            (None | Some("native"), None) => None,
            (None | Some("native"), Some(_)) => {
                return ctx.err(m.span(), "'ranks' applies to engine = \"slepc\"");
            }
            (Some("slepc"), ranks) => {
                let n = ranks.unwrap_or(1);
                if n < 1 {
                    return ctx.err(m.span(), format!("'ranks' must be at least 1, got {n}"));
                }
                Some(n as usize)
            }
            (Some(e), _) => {
                return ctx.err(
                    m.span(),
                    format!("'engine' must be \"native\" or \"slepc\", got \"{e}\""),
                );
            }
        };
        Ok((Some((target, r.shift_hz, block as usize)), slepc_ranks))
    }

    /// A 1-based load case number (`[[load]]` is case 1, `[[load_case]]` tables are numbered in
    /// file order) checked against the `n_cases` cases of the scene; 0-based.
    fn case_number(&self, n: Option<i64>, sp: Span, what: &str, n_cases: usize) -> Result<Option<usize>> {
        let Some(n) = n else {
            return Ok(None);
        };
        if n_cases == 0 {
            return self.ctx.err(
                sp,
                format!("{what} names load case {n}, but the scene has no [[load]] or [[load_case]]"),
            );
        }
        if n < 1 || n as usize > n_cases {
            return self.ctx.err(
                sp,
                format!("{what} must be a load case number from 1 to {n_cases}, got {n}"),
            );
        }
        Ok(Some(n as usize - 1))
    }

    /// `[buckling]`: the load case (`case`, default 1) and the number of load factors (`modes`,
    /// default 4); (case 0-based, modes).
    fn buckling(&self, raw: &Option<Spanned<RawBuckling>>, n_cases: usize) -> Result<Option<(usize, usize)>> {
        let Some(b) = raw else {
            return Ok(None);
        };
        let r = b.get_ref();
        let case = self
            .case_number(Some(r.case.unwrap_or(1)), b.span(), "[buckling] 'case'", n_cases)?
            .unwrap_or(0);
        let modes = match r.modes {
            Some(n) if n < 1 => return self.ctx.err(b.span(), format!("'modes' must be at least 1, got {n}")),
            Some(n) => n as usize,
            None => 4,
        };
        Ok(Some((case, modes)))
    }
}
