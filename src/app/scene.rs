//! Scene files: one analysis described in TOML, and batch runs of a scene over many meshes.
//!
//! A scene names its mesh (a gmsh file relative to the scene, or a built-in generator), the
//! materials, the formulation of each group it includes (the rest of the mesh is ignored, with a
//! note), supports, couplings, point masses, springs, prescribed displacements, load cases and the
//! analyses to run (`[modal]`, `[static]`). The format is strict: `[scene] version = 1` is required
//! and unknown keys are errors; every error names the file and line. See `docs/scenes.md`.
//!
//! - [`Scene::load`] parses and validates a file; [`Scene::run`] runs it; [`run`] does both.
//! - [`run_batch`] runs a template scene over the meshes matched by a glob, in parallel, with
//!   resume, shards and a CSV/JSON summary.

use crate::analysis::modal::{ModalReport, ModalTarget};
use crate::analysis::statics::Load;
use crate::app::report::StaticReport;
use crate::dof::parse_components;
use crate::element::MassLumping;
use crate::material::Material;
use crate::mesh::Mesh;
use crate::model::{CouplingSpec, ModelSpec, PointMassSpec, ShellPart, SpringSpec};
use crate::section::ShellSection;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;
use toml::Spanned;

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
// Validated scene.

/// Where the mesh of a scene comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshSource {
    /// A gmsh file (already resolved against the scene's folder).
    File(PathBuf),
    /// A generator spec (the grammar of [`crate::input::source`]: `box:`, `helix:`,
    /// `sandwich:`, `ibeam-line:`, `ibeam-shell:`, `ibeam-solid:`).
    Generator(String),
    /// No mesh given (a batch template: the batch supplies the file).
    Missing,
}

/// The formulation of one part.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Formulation {
    /// Volume cells as solid elements.
    Solid,
    /// Surface cells as MITC shells.
    Shell,
    /// Line cells as Timoshenko beams.
    Beam,
}

/// A group reference of the scene, kept with its line for messages after the mesh is read.
#[derive(Clone, Debug)]
struct GroupRef {
    group: String,
    line: usize,
    what: String,
    /// Cell dimension the group must have (parts only).
    needs_dim: Option<(usize, Formulation)>,
}

/// A parsed and validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// Its `name` (default: the file stem).
    pub name: String,
    /// The mesh.
    pub mesh: MeshSource,
    /// Length unit of the mesh coordinates, as a factor to metres.
    pub length_scale: f64,
    /// The model (materials, parts, supports, couplings, masses, springs, prescribed motion).
    pub spec: ModelSpec,
    /// The parts: group and formulation, in file order.
    pub parts: Vec<(String, Formulation)>,
    /// The modal analysis, if asked: target, shift (Hz), Lanczos block.
    pub modal: Option<(ModalTarget, Option<f64>, usize)>,
    /// The static load cases, if a static analysis is asked.
    pub static_cases: Option<Vec<Vec<Load>>>,
    /// The harmonic analysis, if asked (`[harmonic]`).
    pub harmonic: Option<crate::app::harmonic::HarmonicRequest>,
    /// Write VTU files of the results.
    pub vtu: bool,
    /// Write gmsh `.msh` files with result views.
    pub msh: bool,
    /// `[modal] engine = "slepc"`: solve with SLEPc on this many MPI ranks (`ranks`, default 1);
    /// `None`: the native solver.
    pub slepc_ranks: Option<usize>,
    groups: Vec<GroupRef>,
}

/// The results of one scene run (`summary.json` of `vibrofem run`).
#[derive(Clone, Debug, Serialize)]
pub struct SceneReport {
    /// Scene file.
    pub scene: String,
    /// Scene name.
    pub name: String,
    /// Mesh file or generator.
    pub mesh: String,
    /// Nodes of the mesh.
    pub nodes: usize,
    /// Parts: group and formulation.
    pub parts: Vec<(String, Formulation)>,
    /// Cells of the mesh not in any part (ignored).
    pub ignored_cells: usize,
    /// Modal report, if asked.
    pub modal: Option<ModalReport>,
    /// Static report, if asked.
    #[serde(rename = "static")]
    pub statics: Option<StaticReport>,
    /// Harmonic report, if asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub harmonic: Option<crate::app::harmonic::HarmonicReport>,
    /// Files written.
    pub outputs: Vec<String>,
    /// Notes (ignored cells, model notes).
    pub notes: Vec<String>,
    /// Wall time of the whole scene, s.
    pub time_s: f64,
    /// Mode shapes of the modal analysis at the mesh nodes (3 per node, one per mode of
    /// `modal`), for callers that compare shapes (`converge`); not serialised.
    #[serde(skip)]
    pub mode_shapes: Option<ModeShapes>,
}

/// Mode shapes at mesh nodes.
#[derive(Clone, Debug, Default)]
pub struct ModeShapes {
    /// Node coordinates (m).
    pub points: Vec<[f64; 3]>,
    /// Per mode, 3 displacement components per node.
    pub shapes: Vec<Vec<f64>>,
}

impl SceneReport {
    /// The modal solution (if any) passed its Sturm and residual checks.
    pub fn verified(&self) -> bool {
        self.modal.as_ref().is_none_or(|m| m.complete && m.accurate)
    }

    /// Human-readable tables (the same as `vibrofem modes` and `vibrofem static`).
    pub fn text(&self) -> String {
        let mut s = format!("scene    {} ({})\n", self.name, self.scene);
        if let Some(m) = &self.modal {
            s.push_str(&crate::app::report::modal_table(m));
        }
        if let Some(st) = &self.statics {
            if self.modal.is_some() {
                s.push('\n');
            }
            s.push_str(&crate::app::report::static_text(st));
        }
        if let Some(h) = &self.harmonic {
            s.push('\n');
            s.push_str(&crate::app::harmonic::text(h));
        }
        s
    }

    /// Stiffness along the guided axis of the first reference node with one, load case 1.
    pub fn stiffness(&self) -> Option<f64> {
        let st = self.statics.as_ref()?;
        st.cases.first()?.references.iter().find_map(|r| r.stiffness)
    }

    /// Largest averaged von Mises stress over the model, load case 1 (Pa).
    pub fn max_von_mises(&self) -> Option<f64> {
        let st = self.statics.as_ref()?;
        st.stress
            .first()?
            .von_mises
            .iter()
            .find(|g| g.group == "(all)")
            .map(|g| g.value)
    }

    /// Largest displacement, load case 1 (m).
    pub fn max_displacement(&self) -> Option<f64> {
        Some(self.statics.as_ref()?.cases.first()?.max_displacement.0)
    }
}

/// Context for messages: the file and the line of a span.
struct Ctx<'a> {
    file: String,
    text: &'a str,
}

impl Ctx<'_> {
    fn line(&self, offset: usize) -> usize {
        self.text[..offset.min(self.text.len())].matches('\n').count() + 1
    }
    fn err<T>(&self, span: std::ops::Range<usize>, msg: impl std::fmt::Display) -> Result<T> {
        Err(self.error(self.line(span.start), msg))
    }
    fn error(&self, line: usize, msg: impl std::fmt::Display) -> Error {
        Error::Input {
            file: self.file.clone(),
            line: Some(line),
            key: None,
            msg: msg.to_string(),
        }
    }
    fn need<'v, T>(&self, v: &'v Option<T>, span: std::ops::Range<usize>, key: &str, place: &str) -> Result<&'v T> {
        match v {
            Some(x) => Ok(x),
            None => self.err(span, format!("missing '{key}' key in {place}")),
        }
    }
}

fn finite(ctx: &Ctx, span: std::ops::Range<usize>, what: &str, v: &[f64]) -> Result<()> {
    if let Some(x) = v.iter().find(|x| !x.is_finite()) {
        return ctx.err(span, format!("{what}: {x} is not finite"));
    }
    Ok(())
}

fn vec3(ctx: &Ctx, span: std::ops::Range<usize>, what: &str, v: &[f64]) -> Result<[f64; 3]> {
    if v.len() != 3 {
        return ctx.err(span, format!("{what} needs 3 numbers, got {}", v.len()));
    }
    finite(ctx, span, what, v)?;
    Ok([v[0], v[1], v[2]])
}

fn unit_scale(u: &str) -> Option<f64> {
    match u {
        "m" => Some(1.0),
        "cm" => Some(1e-2),
        "mm" => Some(1e-3),
        _ => None,
    }
}

impl Scene {
    /// Read and validate a scene file. Errors name the file, line and key.
    pub fn load(path: &Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Scene::parse(path, &text)
    }

    /// Parse scene text; `path` names the file in messages and anchors relative mesh paths.
    pub fn parse(path: &Path, text: &str) -> Result<Scene> {
        let ctx = Ctx {
            file: path.display().to_string(),
            text,
        };
        let raw: RawScene = toml::from_str(text).map_err(|e| {
            let msg = e.message().trim().to_string();
            match e.span() {
                Some(s) => ctx.error(ctx.line(s.start), msg),
                None => Error::InvalidInput(format!("{}: {msg}", ctx.file)),
            }
        })?;
        let header = raw
            .scene
            .as_ref()
            .ok_or_else(|| Error::InvalidInput(format!("{}: missing [scene] table (with version = 1)", ctx.file)))?;
        let version = *ctx.need(&header.get_ref().version, header.span(), "version", "[scene]")?;
        if version != 1 {
            return ctx.err(
                header.span(),
                format!("unsupported scene version {version} (this vibrofem reads version 1)"),
            );
        }
        let name = header.get_ref().name.clone().unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();

        // Mesh.
        let (mesh, length_scale) = match &raw.mesh {
            None => (MeshSource::Missing, 1.0),
            Some(m) => {
                let r = m.get_ref();
                let src = match (&r.file, &r.generator) {
                    (Some(_), Some(_)) => {
                        return ctx.err(m.span(), "[mesh] takes either 'file' or 'generator', not both");
                    }
                    (Some(f), None) => MeshSource::File(base.join(f)),
                    (None, Some(g)) => MeshSource::Generator(g.clone()),
                    (None, None) => MeshSource::Missing,
                };
                let scale = match &r.length_unit {
                    None => 1.0,
                    Some(u) => unit_scale(u).ok_or_else(|| {
                        ctx.error(
                            ctx.line(m.span().start),
                            format!("unknown 'length_unit' '{u}' in [mesh] (use m, cm or mm)"),
                        )
                    })?,
                };
                (src, scale)
            }
        };
        let hex8 = match raw
            .mesh
            .as_ref()
            .and_then(|m| m.get_ref().hex8.as_ref().map(|h| (m, h)))
        {
            None => Default::default(),
            Some((m, h)) => crate::element::incompatible::Hex8Formulation::parse(h)
                .map_err(|e| ctx.error(ctx.line(m.span().start), format!("[mesh] 'hex8': {e}")))?,
        };

        // Materials.
        let mut materials: Vec<(String, Material)> = Vec::new();
        for m in &raw.material {
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
        let find_material = |n: &Option<String>, span: std::ops::Range<usize>, place: &str| -> Result<Material> {
            match n {
                None => Ok(materials.first().map(|m| m.1).unwrap_or_else(Material::steel)),
                Some(n) => match materials.iter().find(|m| m.0 == *n) {
                    Some(m) => Ok(m.1),
                    None if n == "steel" => Ok(Material::steel()),
                    None => {
                        let known: Vec<&str> = materials.iter().map(|m| m.0.as_str()).collect();
                        ctx.err(
                            span,
                            format!(
                                "unknown material '{n}' in {place} (defined: {}; 'steel' is built in)",
                                if known.is_empty() {
                                    "none".to_string()
                                } else {
                                    known.join(", ")
                                }
                            ),
                        )
                    }
                },
            }
        };

        let mut spec = ModelSpec::default();
        spec.hex8 = hex8;
        let mut groups = Vec::new();
        let mut parts = Vec::new();
        let mut solid_groups = Vec::new();
        let mut default_material = None;
        if raw.part.is_empty() {
            return Err(Error::InvalidInput(format!(
                "{}: no [[part]]: a scene includes only the groups it names (e.g. group = \"body\", formulation = \"solid\")",
                ctx.file
            )));
        }
        for p in &raw.part {
            let r = p.get_ref();
            let sp = p.span();
            let group = ctx.need(&r.group, sp.clone(), "group", "[[part]]")?.clone();
            let place = format!("part '{group}'");
            let form = match ctx.need(&r.formulation, sp.clone(), "formulation", &place)?.as_str() {
                "solid" => Formulation::Solid,
                "shell" => Formulation::Shell,
                "beam" => Formulation::Beam,
                f => {
                    return ctx.err(
                        sp,
                        format!("unknown formulation '{f}' in {place} (use solid, shell or beam)"),
                    );
                }
            };
            if parts.iter().any(|(g, _)| *g == group) {
                return ctx.err(sp, format!("group '{group}' is named by two parts"));
            }
            let mat = find_material(&r.material, sp.clone(), &place)?;
            let not_for = |key: &str, present: bool| -> Result<()> {
                if present {
                    let f = match form {
                        Formulation::Solid => "solid",
                        Formulation::Shell => "shell",
                        Formulation::Beam => "beam",
                    };
                    return ctx.err(sp.clone(), format!("'{key}' does not apply to a {f} part ({place})"));
                }
                Ok(())
            };
            match form {
                Formulation::Solid => {
                    not_for("thickness", r.thickness.is_some())?;
                    not_for("offset", r.offset.is_some())?;
                    not_for("section", r.section.is_some())?;
                    not_for("orientation", r.orientation.is_some())?;
                    if default_material.is_none() {
                        default_material = Some(mat);
                    }
                    spec.group_materials.push((group.clone(), mat));
                    solid_groups.push(group.clone());
                }
                Formulation::Shell => {
                    not_for("section", r.section.is_some())?;
                    not_for("orientation", r.orientation.is_some())?;
                    let t = *ctx.need(&r.thickness, sp.clone(), "thickness", &place)?;
                    if !(t.is_finite() && t > 0.0) {
                        return ctx.err(sp, format!("'thickness' must be positive, got {t} in {place}"));
                    }
                    let mut section = ShellSection::new(t);
                    if let Some(o) = r.offset {
                        finite(&ctx, sp.clone(), "'offset'", &[o])?;
                        section = section.with_offset(o);
                    }
                    spec.shells.push(ShellPart {
                        group: group.clone(),
                        section,
                        material: Some(mat),
                    });
                }
                Formulation::Beam => {
                    not_for("thickness", r.thickness.is_some())?;
                    not_for("offset", r.offset.is_some())?;
                    let sec = ctx.need(&r.section, sp.clone(), "section", &place)?;
                    let orientation = match ctx.need(&r.orientation, sp.clone(), "orientation", &place)? {
                        RawOrientation::Vector(v) => {
                            let v = vec3(&ctx, sp.clone(), "'orientation'", v)?;
                            if v.iter().all(|x| *x == 0.0) {
                                return ctx.err(sp, format!("{place}: orientation must be a non-zero vector x,y,z"));
                            }
                            crate::model::Orientation::Vector(v)
                        }
                        RawOrientation::Text(s) => crate::input::options::parse_orientation(s)
                            .map_err(|e| ctx.error(ctx.line(sp.start), format!("{place}: {e}")))?,
                    };
                    let section = crate::input::options::parse_section(sec)
                        .map_err(|e| ctx.error(ctx.line(sp.start), format!("{place}: {e}")))?;
                    let mut b = crate::model::BeamPart {
                        group: group.clone(),
                        section,
                        orientation,
                        material: None,
                    };
                    if let Err(e) = b.section.validate(&place) {
                        return ctx.err(sp, e);
                    }
                    b.material = Some(mat);
                    spec.beams.push(b);
                }
            }
            let dim = match form {
                Formulation::Solid => 3,
                Formulation::Shell => 2,
                Formulation::Beam => 1,
            };
            groups.push(GroupRef {
                group: group.clone(),
                line: ctx.line(sp.start),
                what: place,
                needs_dim: Some((dim, form)),
            });
            parts.push((group, form));
        }
        spec.material =
            default_material.unwrap_or_else(|| materials.first().map(|m| m.1).unwrap_or_else(Material::steel));
        if !solid_groups.is_empty() {
            spec.solid_groups = Some(solid_groups);
        }
        let mut refer = |g: &str, sp: std::ops::Range<usize>, what: String| {
            groups.push(GroupRef {
                group: g.to_string(),
                line: ctx.line(sp.start),
                what,
                needs_dim: None,
            })
        };

        for f in &raw.fix {
            let r = f.get_ref();
            let g = ctx.need(&r.group, f.span(), "group", "[[fix]]")?;
            let comps = r
                .dofs
                .clone()
                .unwrap_or_else(|| vec!["ux".into(), "uy".into(), "uz".into()]);
            let joined = comps.join(",");
            let mask = parse_components(&joined).ok_or_else(|| {
                ctx.error(
                    ctx.line(f.span().start),
                    format!("unknown 'dofs' {comps:?} in fix '{g}' (use ux, uy, uz, rx, ry, rz or all)"),
                )
            })?;
            refer(g, f.span(), format!("fix '{g}'"));
            spec.fixes.push((g.clone(), mask));
        }
        for c in &raw.couple {
            let r = c.get_ref();
            let g = ctx.need(&r.group, c.span(), "group", "[[couple]]")?;
            let guided = match r.guided.as_deref() {
                None => None,
                Some("x") => Some(0),
                Some("y") => Some(1),
                Some("z") => Some(2),
                Some(a) => {
                    return ctx.err(
                        c.span(),
                        format!("'guided' must be x, y or z, got '{a}' in couple '{g}'"),
                    );
                }
            };
            let reference = match &r.reference {
                None => None,
                Some(v) => Some(vec3(&ctx, c.span(), "'reference'", v)?),
            };
            refer(g, c.span(), format!("couple '{g}'"));
            spec.couplings.push(CouplingSpec {
                group: g.clone(),
                guided,
                reference,
            });
        }
        for p in &raw.point_mass {
            let r = p.get_ref();
            let g = ctx.need(&r.group, p.span(), "group", "[[point_mass]]")?;
            let place = format!("point_mass '{g}'");
            let m = *ctx.need(&r.mass, p.span(), "mass", &place)?;
            if !(m.is_finite() && m >= 0.0) {
                return ctx.err(p.span(), format!("'mass' must be non-negative, got {m} in {place}"));
            }
            let mut inertia = [0.0; 6];
            if let Some(i) = &r.inertia {
                if i.len() != 6 {
                    return ctx.err(
                        p.span(),
                        format!("'inertia' needs 6 numbers (Ixx, Iyy, Izz, Ixy, Iyz, Ixz) in {place}"),
                    );
                }
                finite(&ctx, p.span(), "'inertia'", i)?;
                inertia.copy_from_slice(i);
            }
            refer(g, p.span(), place);
            spec.point_masses.push(PointMassSpec {
                group: g.clone(),
                mass: m,
                inertia,
            });
        }
        for s in &raw.spring {
            let r = s.get_ref();
            let a = ctx.need(&r.a, s.span(), "a", "[[spring]]")?;
            let place = format!("spring '{a}'");
            let k = ctx.need(&r.k, s.span(), "k", &place)?;
            if k.len() != 6 {
                return ctx.err(
                    s.span(),
                    format!("'k' needs 6 stiffnesses (kx, ky, kz, krx, kry, krz) in {place}"),
                );
            }
            finite(&ctx, s.span(), "'k'", k)?;
            refer(a, s.span(), place.clone());
            if let Some(b) = &r.b {
                refer(b, s.span(), place);
            }
            let mut kk = [0.0; 6];
            kk.copy_from_slice(k);
            spec.springs.push(SpringSpec {
                a: a.clone(),
                b: r.b.clone(),
                k: kk,
            });
        }
        for d in &raw.displace {
            let r = d.get_ref();
            let g = ctx.need(&r.group, d.span(), "group", "[[displace]]")?;
            let vals = [r.ux, r.uy, r.uz, r.rx, r.ry, r.rz];
            if vals.iter().all(Option::is_none) {
                return ctx.err(
                    d.span(),
                    format!("displace '{g}' prescribes nothing (give ux, uy, uz, rx, ry or rz)"),
                );
            }
            let given: Vec<f64> = vals.iter().flatten().copied().collect();
            finite(&ctx, d.span(), &format!("displace '{g}'"), &given)?;
            refer(g, d.span(), format!("displace '{g}'"));
            spec.prescribed.push((g.clone(), vals));
        }

        let load = |l: &Spanned<RawLoad>, refer: &mut dyn FnMut(&str, std::ops::Range<usize>, String)| {
            let r = l.get_ref();
            let n = r.force.is_some() as u8 + r.pressure.is_some() as u8 + r.gravity.is_some() as u8;
            if n != 1 {
                return ctx.err(
                    l.span(),
                    "a [[load]] needs exactly one of 'force', 'pressure' or 'gravity'",
                );
            }
            if let Some(g) = &r.gravity {
                if r.group.is_some() {
                    return ctx.err(l.span(), "a 'gravity' load acts on the whole model: remove 'group'");
                }
                return Ok(Load::Acceleration(vec3(&ctx, l.span(), "'gravity'", g)?));
            }
            let g = ctx.need(&r.group, l.span(), "group", "[[load]]")?;
            refer(g, l.span(), format!("load on '{g}'"));
            if let Some(f) = &r.force {
                Ok(Load::Force {
                    group: g.clone(),
                    force: vec3(&ctx, l.span(), "'force'", f)?,
                })
            } else {
                let p = r.pressure.unwrap_or(0.0);
                finite(&ctx, l.span(), "'pressure'", &[p])?;
                Ok(Load::Pressure { group: g.clone(), p })
            }
        };
        if !raw.load.is_empty() && !raw.load_case.is_empty() {
            return ctx.err(
                raw.load_case[0].span(),
                "give either [[load]] (one load case) or [[load_case]] tables, not both",
            );
        }
        let mut cases = Vec::new();
        if !raw.load.is_empty() {
            let mut c = Vec::new();
            for l in &raw.load {
                c.push(load(l, &mut refer)?);
            }
            cases.push(c);
        }
        for lc in &raw.load_case {
            let _ = &lc.get_ref().name;
            let mut c = Vec::new();
            for l in &lc.get_ref().load {
                c.push(load(l, &mut refer)?);
            }
            cases.push(c);
        }
        let static_cases = if raw.statics.is_some() || !cases.is_empty() || !spec.prescribed.is_empty() {
            if cases.is_empty() {
                cases.push(Vec::new());
            }
            Some(cases)
        } else {
            None
        };

        let harmonic = match &raw.harmonic {
            None => None,
            Some(h) => {
                let r = h.get_ref();
                let e = |msg: String| ctx.error(ctx.line(h.span().start), msg);
                if r.force.is_empty() {
                    return ctx.err(
                        h.span(),
                        "[harmonic] needs 'force = [\"GROUP=FX,FY,FZ[@PHASE_DEG]\", ...]'",
                    );
                }
                let mut forces = Vec::new();
                for f in &r.force {
                    let gf =
                        crate::analysis::harmonic::GroupForce::parse("'force'", f).map_err(|x| e(x.to_string()))?;
                    refer(&gf.group, h.span(), format!("harmonic force on '{}'", gf.group));
                    forces.push(gf);
                }
                for g in &r.probe {
                    refer(g, h.span(), format!("harmonic probe '{g}'"));
                }
                let freqs_hz = match (r.freq_hz, &r.sweep_hz) {
                    (Some(_), Some(_)) => {
                        return ctx.err(h.span(), "[harmonic] takes 'freq_hz' or 'sweep_hz', not both");
                    }
                    (Some(f), None) => {
                        if !(f.is_finite() && f >= 0.0) {
                            return ctx.err(h.span(), format!("'freq_hz' must be a finite frequency ≥ 0, got {f}"));
                        }
                        vec![f]
                    }
                    (None, Some(v)) => {
                        if v.len() != 3 || v[2].fract() != 0.0 || v[2] < 0.0 {
                            return ctx.err(
                                h.span(),
                                format!("'sweep_hz' must be [F0, F1, N] with N a whole number, got {v:?}"),
                            );
                        }
                        crate::app::harmonic::sweep_frequencies(v[0], v[1], v[2] as usize)
                            .map_err(|x| e(x.to_string().replace("--sweep", "'sweep_hz'")))?
                    }
                    (None, None) => return ctx.err(h.span(), "[harmonic] needs 'freq_hz' or 'sweep_hz = [F0, F1, N]'"),
                };
                let damping = match (r.damping, &r.rayleigh) {
                    (Some(_), Some(_)) => {
                        return ctx.err(h.span(), "[harmonic] takes 'damping' or 'rayleigh', not both");
                    }
                    (Some(z), None) => crate::analysis::harmonic::Damping::Ratio(z),
                    (None, Some(v)) if v.len() == 2 => crate::analysis::harmonic::Damping::Rayleigh {
                        alpha: v[0],
                        beta: v[1],
                    },
                    (None, Some(v)) => {
                        return ctx.err(h.span(), format!("'rayleigh' must be [ALPHA, BETA], got {v:?}"));
                    }
                    (None, None) => {
                        return ctx.err(
                            h.span(),
                            "[harmonic] needs 'damping' (modal ratio, e.g. 0.02) or 'rayleigh = [ALPHA, BETA]'",
                        );
                    }
                };
                damping.validate().map_err(|x| {
                    e(x.to_string()
                        .replace("--damping", "'damping'")
                        .replace("--rayleigh", "'rayleigh'"))
                })?;
                let method = crate::app::harmonic::Method::parse(r.method.as_deref().unwrap_or("modal"))
                    .map_err(|x| e(x.to_string().replace("--method", "'method'")))?;
                let modes = match r.modes {
                    Some(n) if n < 1 => return ctx.err(h.span(), format!("'modes' must be at least 1, got {n}")),
                    Some(n) => Some(n as usize),
                    None => None,
                };
                Some(crate::app::harmonic::HarmonicRequest {
                    forces,
                    freqs_hz,
                    damping,
                    method,
                    modes,
                    probes: r.probe.clone(),
                })
            }
        };

        let mut slepc_ranks = None;
        let modal = match &raw.modal {
            None => None,
            Some(m) => {
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
                    finite(&ctx, m.span(), "'shift_hz'", &[s])?;
                }
                if let Some(mass) = &r.mass {
                    spec.lumping = MassLumping::parse(mass).map_err(|e| ctx.error(ctx.line(m.span().start), e))?;
                }
                let block = r.block.unwrap_or(6);
                if block < 1 {
                    return ctx.err(m.span(), format!("'block' must be at least 1, got {block}"));
                }
                slepc_ranks = match (r.engine.as_deref(), r.ranks) {
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
                Some((target, r.shift_hz, block as usize))
            }
        };
        if modal.is_none() && static_cases.is_none() && harmonic.is_none() {
            return Err(Error::InvalidInput(format!(
                "{}: the scene asks for no analysis: add [modal], [harmonic], or [static] / [[load]] / [[displace]]",
                ctx.file
            )));
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
            spec,
            parts,
            modal,
            static_cases,
            harmonic,
            vtu,
            msh,
            slepc_ranks,
            groups,
        })
    }

    /// The mesh as text for reports: the file path or the generator spec.
    pub fn mesh_name(&self) -> String {
        match &self.mesh {
            MeshSource::File(p) => p.display().to_string(),
            MeshSource::Generator(g) => g.clone(),
            MeshSource::Missing => "(none)".into(),
        }
    }

    /// Read or generate the mesh.
    pub fn load_mesh(&self) -> Result<Mesh> {
        match &self.mesh {
            MeshSource::File(p) => crate::io::gmsh::read(p, self.length_scale),
            MeshSource::Generator(g) => generate(g, self.length_scale).map_err(|e| match e {
                Error::InvalidInput(m) => Error::InvalidInput(format!("{}: [mesh] {m}", self.path.display())),
                e => e,
            }),
            MeshSource::Missing => Err(Error::InvalidInput(format!(
                "{}: no mesh: give [mesh] file = \"...\" or generator = \"...\"",
                self.path.display()
            ))),
        }
    }

    /// Check the scene's group names and part formulations against the mesh; errors name the
    /// scene's line. Returns the number of ignored cells and a note about them.
    pub fn check_groups(&self, mesh: &Mesh) -> Result<(usize, Option<String>)> {
        let file = self.path.display();
        for g in &self.groups {
            let grp = mesh
                .group(&g.group)
                .map_err(|e| Error::InvalidInput(format!("{file}, line {}: {} names an {e}", g.line, g.what)))?;
            if let Some((dim, form)) = g.needs_dim {
                let ok = grp.cells.iter().any(|c| {
                    let k = mesh.blocks[c.block as usize].kind;
                    match form {
                        Formulation::Solid => k.dim() == 3,
                        Formulation::Shell => crate::element::shell::supports(k),
                        Formulation::Beam => crate::element::beam::supports(k),
                    }
                });
                if !ok {
                    let dims: Vec<String> = {
                        let mut d: Vec<u8> = grp
                            .cells
                            .iter()
                            .map(|c| mesh.blocks[c.block as usize].kind.dim() as u8)
                            .collect();
                        d.sort_unstable();
                        d.dedup();
                        d.iter().map(|x| format!("{x}D")).collect()
                    };
                    let need = match dim {
                        3 => "volume cells (tet, hex, wedge)",
                        2 => "surface cells (tri3, quad4)",
                        _ => "line cells (line2, line3)",
                    };
                    return Err(Error::InvalidInput(format!(
                        "{file}, line {}: {} is a {} part but group '{}' has no {need} (it has {} cells)",
                        g.line,
                        g.what,
                        match form {
                            Formulation::Solid => "solid",
                            Formulation::Shell => "shell",
                            Formulation::Beam => "beam",
                        },
                        g.group,
                        if dims.is_empty() {
                            "no".to_string()
                        } else {
                            dims.join(", ")
                        }
                    )));
                }
            }
        }
        // Cells of the part dimensions not in any part.
        let mut used: Vec<Vec<bool>> = mesh.blocks.iter().map(|b| vec![false; b.len()]).collect();
        let mut dims_in_use = [false; 4];
        for (g, f) in &self.parts {
            let d = match f {
                Formulation::Solid => 3,
                Formulation::Shell => 2,
                Formulation::Beam => 1,
            };
            dims_in_use[d] = true;
            if let Ok(grp) = mesh.group(g) {
                for c in &grp.cells {
                    used[c.block as usize][c.index as usize] = true;
                }
            }
        }
        let mut ignored = 0;
        let mut total = 0;
        for (bi, b) in mesh.blocks.iter().enumerate() {
            let d = b.kind.dim();
            // Volume cells always count; surface and line cells only where parts of that
            // dimension exist (otherwise they are boundary faces and edges).
            if d == 3 || (d >= 1 && dims_in_use[d]) {
                total += b.len();
                ignored += used[bi].iter().filter(|u| !**u).count();
            }
        }
        let note = (ignored > 0)
            .then(|| format!("{ignored} of {total} cells are in no [[part]] of the scene and were ignored"));
        Ok((ignored, note))
    }

    /// Run the scene's analyses. With `out = Some((dir, prefix))` the result files asked for in
    /// `[output]` are written to `dir/<prefix>modes.vtu`, `dir/<prefix>static.vtu` (and `.msh`).
    pub fn run(&self, out: Option<(&Path, &str)>) -> Result<SceneReport> {
        let t0 = Instant::now();
        let mesh = self.load_mesh()?;
        let read_time = t0.elapsed().as_secs_f64();
        log::info!("scene {}: mesh read in {read_time:.3} s", self.name);
        let (ignored_cells, note) = self.check_groups(&mesh)?;
        let mut notes: Vec<String> = note.into_iter().collect();
        let source = self.mesh_name();
        let mut outputs = Vec::new();
        // One model and one system serve both analyses: assembled and ordered once.
        let t_model = Instant::now();
        let model = crate::model::Model::build(&mesh, &self.spec, &source)?;
        let t_model = t_model.elapsed().as_secs_f64();
        let sys = if self.slepc_ranks.is_some() && self.static_cases.is_none() && self.harmonic.is_none() {
            // SLEPc factorises on its ranks: no ordering or memory check for this machine.
            crate::system::System::assemble_only(model, &source)?
        } else {
            crate::system::System::build(
                model,
                &crate::system::SystemOptions {
                    mass: self.modal.is_some() || self.harmonic.is_some(),
                    ..Default::default()
                },
                &source,
            )?
        };
        let mut mode_shapes = None;
        let modal = match &self.modal {
            None => None,
            Some((target, shift_hz, block)) => {
                let params = crate::analysis::modal::ModalParams {
                    target: *target,
                    shift_hz: *shift_hz,
                    block: *block,
                    ..Default::default()
                };
                let mut run = match self.slepc_ranks {
                    None => crate::analysis::modal::solve(&sys, &params)?,
                    Some(ranks) => crate::app::slepc::solve(
                        &sys,
                        &params,
                        &crate::app::slepc::SlepcOptions {
                            ranks,
                            ..Default::default()
                        },
                    )?,
                };
                let tm = &mut run.report.timings_s;
                tm.read = read_time;
                tm.assemble += t_model;
                tm.total += read_time + t_model;
                log::info!(
                    "scene {}: modal: assemble {:.3} s, factor {:.3} s, eigen {:.3} s",
                    self.name,
                    run.report.timings_s.assemble,
                    run.report.timings_s.factor,
                    run.report.timings_s.solve
                );
                if let Some((dir, prefix)) = out {
                    let vtu = self.vtu.then(|| dir.join(format!("{prefix}modes.vtu")));
                    let msh = self.msh.then(|| dir.join(format!("{prefix}modes.msh")));
                    for p in crate::io::write_mode_shapes(
                        &mesh,
                        &run.shapes,
                        &run.report.frequencies_hz,
                        vtu.as_deref(),
                        msh.as_deref(),
                    )? {
                        outputs.push(p.display().to_string());
                    }
                }
                notes.extend(run.report.notes.iter().cloned());
                mode_shapes = Some(ModeShapes {
                    points: mesh.nodes.clone(),
                    shapes: std::mem::take(&mut run.shapes),
                });
                Some(run.report)
            }
        };
        let statics = match &self.static_cases {
            None => None,
            Some(cases) => {
                let mut run = crate::analysis::statics::solve(&sys, &mesh, cases)?;
                if modal.is_none() {
                    run.timings.assemble += t_model;
                }
                let t = run.timings;
                log::info!(
                    "scene {}: static: assemble {:.3} s, factor {:.3} s, solve {:.3} s",
                    self.name,
                    t.assemble,
                    t.factor,
                    t.solve
                );
                let rep = crate::app::report::static_report(&mesh, &source, &run)?;
                if let Some((dir, prefix)) = out {
                    let vtu = self.vtu.then(|| dir.join(format!("{prefix}static.vtu")));
                    let msh = self.msh.then(|| dir.join(format!("{prefix}static.msh")));
                    if vtu.is_some() || msh.is_some() {
                        crate::app::report::write_static_fields(&mesh, &run, vtu.as_deref(), msh.as_deref())?;
                        outputs.extend(vtu.iter().chain(msh.iter()).map(|p| p.display().to_string()));
                    }
                }
                if modal.is_none() {
                    notes.extend(rep.notes.iter().cloned());
                }
                Some(rep)
            }
        };
        let harmonic = match &self.harmonic {
            None => None,
            Some(req) => {
                let run = crate::app::harmonic::run_with(&sys, &mesh, req, crate::app::harmonic::Fields::Peak)?;
                if let Some((dir, prefix)) = out {
                    let k = crate::app::harmonic::peak_index(&run.report);
                    let vtu = self.vtu.then(|| dir.join(format!("{prefix}harmonic.vtu")));
                    let msh = self.msh.then(|| dir.join(format!("{prefix}harmonic.msh")));
                    if vtu.is_some() || msh.is_some() {
                        crate::app::harmonic::write_fields(&mesh, &run, k, vtu.as_deref(), msh.as_deref())?;
                        outputs.extend(vtu.iter().chain(msh.iter()).map(|p| p.display().to_string()));
                    }
                    if run.report.points.len() > 1 {
                        let svg = dir.join(format!("{prefix}frf.svg"));
                        crate::app::harmonic::write_frf_svg(&svg, &run.report)?;
                        outputs.push(svg.display().to_string());
                    }
                }
                notes.extend(run.report.notes.iter().cloned());
                Some(run.report)
            }
        };
        notes.dedup();
        Ok(SceneReport {
            scene: self.path.display().to_string(),
            name: self.name.clone(),
            mesh: source,
            nodes: mesh.n_nodes(),
            parts: self.parts.clone(),
            ignored_cells,
            modal,
            statics,
            harmonic,
            outputs,
            notes,
            time_s: t0.elapsed().as_secs_f64(),
            mode_shapes,
        })
    }
}

/// Read and run a scene file (no result files written).
pub fn run(path: &Path) -> Result<SceneReport> {
    Scene::load(path)?.run(None)
}

/// A mesh from a generator spec (any of [`crate::input::source::GENERATORS`]); a spec that is
/// not a generator is an error (a scene names files with `file =`).
pub fn generate(spec: &str, length_scale: f64) -> Result<Mesh> {
    if !crate::input::source::is_generator(spec) {
        return Err(Error::InvalidInput(format!(
            "unknown generator '{spec}' ({})",
            crate::input::source::GENERATORS
        )));
    }
    crate::input::source::load(spec, length_scale)
}

// ---------------------------------------------------------------------------------------------
// Batch runs.

/// Does `name` match the glob `pat` (`*` any run of characters, `?` one character)?
pub fn glob_match(pat: &str, name: &str) -> bool {
    let p: Vec<char> = pat.chars().collect();
    let n: Vec<char> = name.chars().collect();
    let (mut pi, mut ni) = (0, 0);
    let (mut star, mut mark) = (None, 0);
    while ni < n.len() {
        if pi < p.len() && (p[pi] == '?' || p[pi] == n[ni]) {
            pi += 1;
            ni += 1;
        } else if pi < p.len() && p[pi] == '*' {
            star = Some(pi);
            mark = ni;
            pi += 1;
        } else if let Some(s) = star {
            pi = s + 1;
            mark += 1;
            ni = mark;
        } else {
            return false;
        }
    }
    while pi < p.len() && p[pi] == '*' {
        pi += 1;
    }
    pi == p.len()
}

/// The files matching a glob whose wildcards (`*`, `?`) are in the file name only, sorted.
pub fn glob_files(pattern: &str) -> Result<Vec<PathBuf>> {
    let path = Path::new(pattern);
    let name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .ok_or_else(|| Error::InvalidInput(format!("batch: '{pattern}' names no file")))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if dir.to_string_lossy().contains(['*', '?']) {
        return Err(Error::InvalidInput(format!(
            "batch: '{pattern}': wildcards are allowed in the file name only"
        )));
    }
    let rd = std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, e))?;
    let mut out = Vec::new();
    for e in rd.flatten() {
        let f = e.file_name().to_string_lossy().into_owned();
        if glob_match(&name, &f) && e.path().is_file() {
            out.push(if path.parent().is_some_and(|d| !d.as_os_str().is_empty()) {
                dir.join(&f)
            } else {
                PathBuf::from(&f)
            });
        }
    }
    out.sort();
    Ok(out)
}

/// Parse `I/N` (1-based shard `I` of `N`).
pub fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let bad = || Error::InvalidInput(format!("--shard '{s}': expected I/N with 1 ≤ I ≤ N, e.g. 2/8"));
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let i: usize = i.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if n == 0 || i == 0 || i > n {
        return Err(bad());
    }
    Ok((i, n))
}

/// Shard `i` of `n` (1-based) of a sorted list: every n-th file starting at the i-th.
pub fn shard<T: Clone>(items: &[T], i: usize, n: usize) -> Vec<T> {
    items
        .iter()
        .enumerate()
        .filter(|(k, _)| k % n == i - 1)
        .map(|(_, x)| x.clone())
        .collect()
}

/// Options of a batch run.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    /// Glob of mesh files (wildcards in the file name).
    pub pattern: String,
    /// The template scene; each mesh replaces its `[mesh]`.
    pub template: PathBuf,
    /// Output folder (per-case `<stem>.json`, `summary.csv`, `summary.json`).
    pub out: PathBuf,
    /// Concurrent cases at most (further capped by memory).
    pub jobs: usize,
    /// Rerun cases whose result file exists.
    pub force: bool,
    /// Only shard `(i, n)` of the sorted file list.
    pub shard: Option<(usize, usize)>,
    /// Show a progress bar (a terminal); otherwise one line per case on stderr.
    pub progress_bar: bool,
}

/// One row of the batch summary.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BatchRow {
    /// Mesh file.
    pub file: String,
    /// `ok`, `failed`, `unverified` (modal check failed) or `resumed` (result file existed).
    pub status: String,
    /// Error message of a failed case.
    pub error: Option<String>,
    /// Free DOFs.
    pub dofs: Option<usize>,
    /// Model mass (modal runs), kg.
    pub mass_kg: Option<f64>,
    /// Frequencies, Hz.
    pub frequencies_hz: Vec<f64>,
    /// First elastic (non-rigid-body) frequency, Hz.
    pub first_elastic_hz: Option<f64>,
    /// Stiffness along the first guided axis, load case 1 (N/m).
    pub stiffness: Option<f64>,
    /// Largest displacement, load case 1 (m).
    pub max_displacement: Option<f64>,
    /// Largest von Mises stress, load case 1 (Pa).
    pub max_von_mises: Option<f64>,
    /// Wall time, s.
    pub time_s: f64,
}

impl BatchRow {
    fn failed(file: &str, error: String, time_s: f64) -> BatchRow {
        BatchRow {
            file: file.to_string(),
            status: "failed".into(),
            error: Some(error),
            dofs: None,
            mass_kg: None,
            frequencies_hz: vec![],
            first_elastic_hz: None,
            stiffness: None,
            max_displacement: None,
            max_von_mises: None,
            time_s,
        }
    }

    fn from_report(file: &str, r: &SceneReport) -> BatchRow {
        BatchRow {
            file: file.to_string(),
            status: if r.verified() { "ok" } else { "unverified" }.into(),
            error: (!r.verified()).then(|| "the modal solution failed its Sturm or residual check".to_string()),
            dofs: r.modal.as_ref().map(|m| m.dofs).or(r.statics.as_ref().map(|s| s.dofs)),
            mass_kg: r.modal.as_ref().map(|m| m.mass_kg),
            frequencies_hz: r.modal.as_ref().map(|m| m.frequencies_hz.clone()).unwrap_or_default(),
            first_elastic_hz: r.modal.as_ref().and_then(|m| m.elastic_frequencies().first().copied()),
            stiffness: r.stiffness(),
            max_displacement: r.max_displacement(),
            max_von_mises: r.max_von_mises(),
            time_s: r.time_s,
        }
    }

    /// The case did not produce results.
    pub fn is_failure(&self) -> bool {
        self.status == "failed" || self.status == "unverified"
    }
}

/// The outcome of a batch.
#[derive(Clone, Debug, Serialize)]
pub struct BatchSummary {
    /// One row per mesh, in sorted file order.
    pub rows: Vec<BatchRow>,
    /// Cases that failed.
    pub failed: usize,
    /// Cases taken from existing result files.
    pub resumed: usize,
    /// Concurrent cases allowed.
    pub jobs: usize,
}

/// Memory available to new processes (bytes), from /proc/meminfo.
fn available_memory() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    let l = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
    Some(l.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
}

/// Rough peak memory of one case from its mesh file size: 64 MiB + 150 × the file size (an
/// ASCII tet10 mesh of 55 k DOFs, 3 MB, peaks near 440 MiB).
pub fn estimate_case_memory(file: &Path) -> u64 {
    let size = std::fs::metadata(file).map(|m| m.len()).unwrap_or(0);
    (64 << 20) + 150 * size
}

/// A counting budget of bytes shared by the workers.
struct MemoryBudget {
    limit: u64,
    used: std::sync::Mutex<u64>,
    freed: std::sync::Condvar,
}

impl MemoryBudget {
    fn acquire(&self, want: u64) -> u64 {
        let want = want.min(self.limit);
        let mut used = self.used.lock().unwrap_or_else(|e| e.into_inner());
        while *used > 0 && *used + want > self.limit {
            used = self.freed.wait(used).unwrap_or_else(|e| e.into_inner());
        }
        *used += want;
        want
    }
    fn release(&self, got: u64) {
        let mut used = self.used.lock().unwrap_or_else(|e| e.into_inner());
        *used = used.saturating_sub(got);
        self.freed.notify_all();
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\"").replace('\n', " "))
    } else {
        s.to_string()
    }
}

/// The summary as CSV: `file,status,error,dofs,mass_kg,stiffness_n_per_m,max_displacement_m,
/// max_von_mises_pa,time_s,f1_hz,…` (as many frequency columns as the longest row).
pub fn summary_csv(rows: &[BatchRow]) -> String {
    let nf = rows.iter().map(|r| r.frequencies_hz.len()).max().unwrap_or(0);
    let mut s =
        String::from("file,status,error,dofs,mass_kg,stiffness_n_per_m,max_displacement_m,max_von_mises_pa,time_s");
    for i in 1..=nf {
        s.push_str(&format!(",f{i}_hz"));
    }
    s.push('\n');
    let opt = |v: Option<f64>| v.map(|x| format!("{x:.9e}")).unwrap_or_default();
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{},{:.3}",
            csv_field(&r.file),
            r.status,
            csv_field(r.error.as_deref().unwrap_or("")),
            r.dofs.map(|d| d.to_string()).unwrap_or_default(),
            opt(r.mass_kg),
            opt(r.stiffness),
            opt(r.max_displacement),
            opt(r.max_von_mises),
            r.time_s
        ));
        for i in 0..nf {
            s.push(',');
            if let Some(f) = r.frequencies_hz.get(i) {
                s.push_str(&format!("{f:.9e}"));
            }
        }
        s.push('\n');
    }
    s
}

/// FNV-1a, 64 bits: a stable content hash (the same on every machine and Rust version).
fn fnv1a(h: u64, bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .fold(h, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

/// What a batch result was computed from: the mesh's full path, and a hash of the mesh bytes,
/// the template scene's text and the program version. A result file is resumed only when both
/// match, so an edited template or mesh, or another mesh of the same name, is rerun.
fn case_key(template_text: &[u8], file: &Path) -> serde_json::Value {
    let path = std::fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf());
    let mut h = fnv1a(0xcbf2_9ce4_8422_2325, env!("CARGO_PKG_VERSION").as_bytes());
    h = fnv1a(h, &(template_text.len() as u64).to_le_bytes());
    h = fnv1a(h, template_text);
    match std::fs::read(file) {
        Ok(bytes) => h = fnv1a(h, &bytes),
        // Unreadable: a key that matches nothing (the run reports the error).
        Err(_) => h = fnv1a(h, b"\0unreadable"),
    }
    serde_json::json!({ "path": path.display().to_string(), "hash": format!("{h:016x}") })
}

/// Result-file names of the cases: the file stem, or the whole file name where two meshes of
/// the batch share a stem (`m.msh` and `m.msh2`), so no case overwrites or resumes another.
fn case_names(files: &[PathBuf]) -> Vec<String> {
    let stem = |f: &PathBuf| {
        f.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let stems: Vec<String> = files.iter().map(stem).collect();
    files
        .iter()
        .zip(&stems)
        .map(|(f, s)| {
            if stems.iter().filter(|t| *t == s).count() > 1 {
                f.file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_else(|| s.clone())
            } else {
                s.clone()
            }
        })
        .collect()
}

fn run_case(template: &Scene, template_text: &[u8], file: &Path, stem: &str, out: &Path, force: bool) -> BatchRow {
    let name = file.display().to_string();
    let result = out.join(format!("{stem}.json"));
    let key = case_key(template_text, file);
    if !force && result.is_file() {
        let doc = std::fs::read_to_string(&result)
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok());
        let row = doc
            .as_ref()
            .filter(|d| d.get("key") == Some(&key))
            .and_then(|v| serde_json::from_value::<BatchRow>(v.get("row")?.clone()).ok());
        if let Some(mut row) = row {
            row.status = "resumed".into();
            return row;
        }
        if doc.is_some() {
            eprintln!(
                "note: {}: computed from another mesh, template or version; rerunning {name}",
                result.display()
            );
        }
    }
    let t = Instant::now();
    let mut scene = template.clone();
    scene.mesh = MeshSource::File(file.to_path_buf());
    let prefix = format!("{stem}_");
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| scene.run(Some((out, &prefix)))));
    match r {
        Ok(Ok(rep)) => {
            let row = BatchRow::from_report(&name, &rep);
            if !row.is_failure() {
                let doc = serde_json::json!({ "key": key, "row": row, "report": rep });
                if let Ok(text) = serde_json::to_string_pretty(&doc) {
                    let tmp = out.join(format!("{stem}.json.part"));
                    if std::fs::write(&tmp, text).is_ok() {
                        let _ = std::fs::rename(&tmp, &result);
                    }
                }
            }
            row
        }
        Ok(Err(e)) => BatchRow::failed(&name, e.to_string(), t.elapsed().as_secs_f64()),
        Err(p) => {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "unknown panic".into());
            BatchRow::failed(&name, format!("internal error: {msg}"), t.elapsed().as_secs_f64())
        }
    }
}

/// Run a template scene over the meshes matched by a glob. Failing cases are reported in their
/// row and skipped; the summary is written to `out/summary.csv` and `out/summary.json`.
pub fn run_batch(opts: &BatchOptions) -> Result<BatchSummary> {
    use rayon::prelude::*;
    let template = Scene::load(&opts.template)?;
    let template_text = std::fs::read(&opts.template).map_err(|e| Error::io(&opts.template, e))?;
    let mut files = glob_files(&opts.pattern)?;
    if files.is_empty() {
        return Err(Error::InvalidInput(format!(
            "batch: no file matches '{}'",
            opts.pattern
        )));
    }
    if let Some((i, n)) = opts.shard {
        files = shard(&files, i, n);
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    // More workers than cases, or far more than cores, only cost threads and memory.
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let cap = (4 * cores).min(files.len()).max(1);
    let jobs = opts.jobs.clamp(1, cap);
    if opts.jobs > cap {
        eprintln!(
            "note: --jobs {} capped at {cap} ({} cases, {cores} cores)",
            opts.jobs,
            files.len()
        );
    }
    let budget = MemoryBudget {
        limit: available_memory().map(|m| m / 10 * 7).unwrap_or(4 << 30).max(256 << 20),
        used: std::sync::Mutex::new(0),
        freed: std::sync::Condvar::new(),
    };
    let bar = if opts.progress_bar {
        let b = indicatif::ProgressBar::new(files.len() as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} {elapsed} {msg}") {
            b.set_style(style);
        }
        Some(b)
    } else {
        None
    };
    let done = std::sync::atomic::AtomicUsize::new(0);
    let total = files.len();
    let names = case_names(&files);
    let cases: Vec<(&PathBuf, &String)> = files.iter().zip(&names).collect();
    let one = |&(f, stem): &(&PathBuf, &String)| -> BatchRow {
        let got = budget.acquire(estimate_case_memory(f));
        let row = run_case(&template, &template_text, f, stem, &opts.out, opts.force);
        budget.release(got);
        let k = done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
        let line = format!(
            "[{k}/{total}] {} {}{}",
            row.file,
            row.status,
            row.error.as_ref().map(|e| format!(": {e}")).unwrap_or_default()
        );
        match &bar {
            Some(b) => {
                b.set_message(line);
                b.inc(1);
            }
            None => eprintln!("{line}"),
        }
        row
    };
    let rows: Vec<BatchRow> = if jobs == 1 {
        cases.iter().map(one).collect()
    } else {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(jobs)
            .build()
            .map_err(|e| Error::InvalidInput(format!("batch: cannot start {jobs} workers: {e}")))?;
        pool.install(|| cases.par_iter().map(one).collect())
    };
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let summary = BatchSummary {
        failed: rows.iter().filter(|r| r.is_failure()).count(),
        resumed: rows.iter().filter(|r| r.status == "resumed").count(),
        rows,
        jobs,
    };
    let csv = opts.out.join("summary.csv");
    std::fs::write(&csv, summary_csv(&summary.rows)).map_err(|e| Error::io(&csv, e))?;
    let js = opts.out.join("summary.json");
    let text = serde_json::to_string_pretty(&summary).map_err(|e| Error::output("summary.json", e))?;
    std::fs::write(&js, text).map_err(|e| Error::io(&js, e))?;
    Ok(summary)
}
