//! Parametric studies of the sandwich work table (`vibrofem sweep`).
//!
//! A study is either a scene whose mesh is `generator = "sandwich:paper[,SIZE]"` (its material is
//! used) or a study file (TOML, see `docs/sweeps.md`):
//!
//! ```toml
//! [study]
//! version = 1
//! name = "S7 work table"
//! formulation = "shell"          # or "solid" (hex20, `solid_size`)
//! [material]                     # optional, default steel
//! young = 2.1e11
//! poisson = 0.3
//! density = 7850.0
//! [table]                        # TableSpec fields; omitted fields take the S7 reconstruction
//! top_thickness = 0.025
//! n_long_webs = 3
//! [sweep]                        # ranges, as on the command line
//! "table.top_thickness" = "0.015:0.025:0.005"
//! "table.n_trans_webs" = [0, 2, 4]
//! [constraints]
//! min_f1_hz = 300.0
//! max_mass_kg = 165.0
//! [check]                        # re-run the best designs finer and as hex20 solids
//! designs = 3
//! ```
//!
//! Every combination is validated ([`SandwichParams::validate`]) before any meshing; an error names
//! the key and value. Each design is analysed free–free; its first elastic frequency and its real
//! steel mass ([`SandwichParams::mass`]) are tabulated, the Pareto front (lighter and stiffer) is
//! marked and plotted.

use super::scene::{MeshSource, Scene};
use crate::analysis::modal::{ModalOptions, ModalTarget, run_modal};
use crate::app::toml_file;
use crate::input::source::SandwichSpec;
use crate::material::Material;
use crate::mesh::CellKind;
use crate::mesh::parametric::{MAX_TABLE_DIVISIONS, SandwichParams, sandwich_table, sandwich_table_solid};
use crate::model::{ModelSpec, ShellPart};
use crate::section::ShellSection;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A bad value of a table key (`table.top_thickness`): a field of [`TableSpec`].
fn bad_key(key: &str, msg: String) -> Error {
    Error::param(key, msg)
}

/// The table of a study: [`SandwichParams`] with the webs given by count and span (evenly spaced,
/// centred), so that web counts can be swept.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TableSpec {
    /// Length along x (m).
    pub length: f64,
    /// Top plate width (m).
    pub top_width: f64,
    /// Top plate thickness (m).
    pub top_thickness: f64,
    /// Bottom plate width (m).
    pub bottom_width: f64,
    /// Bottom plate thickness (m).
    pub bottom_thickness: f64,
    /// Clear web height between the plates (m).
    pub web_height: f64,
    /// Number of longitudinal webs (along x), evenly spaced over `long_web_span`.
    pub n_long_webs: usize,
    /// Distance between the outermost longitudinal webs (m); one web sits at y = 0.
    pub long_web_span: f64,
    /// Longitudinal web thickness (m).
    pub long_web_thickness: f64,
    /// Number of transverse webs (diaphragms, along y), evenly spaced over `trans_web_span`.
    pub n_trans_webs: usize,
    /// Distance between the outermost transverse webs (m); one web sits at x = 0.
    pub trans_web_span: f64,
    /// Transverse web thickness (m).
    pub trans_web_thickness: f64,
    /// Shell element size (m).
    pub elem_size: f64,
}

impl Default for TableSpec {
    /// The S7 reconstruction ([`SandwichParams::paper`]); transverse webs, when counted, span
    /// 1100 mm (end diaphragms 50 mm in from the plate ends).
    fn default() -> Self {
        let p = SandwichParams::paper();
        TableSpec {
            length: p.length,
            top_width: p.top_width,
            top_thickness: p.top_thickness,
            bottom_width: p.bottom_width,
            bottom_thickness: p.bottom_thickness,
            web_height: p.web_height,
            n_long_webs: 3,
            long_web_span: 0.3,
            long_web_thickness: p.long_web_thickness,
            n_trans_webs: 0,
            trans_web_span: 1.1,
            trans_web_thickness: p.trans_web_thickness,
            elem_size: p.elem_size,
        }
    }
}

/// Webs of one direction at most (a web per element of a 4 m table at 2 mm is 2 000).
const MAX_WEBS: f64 = 2000.0;

/// The keys a sweep may set (`table.<key>`); `web_thickness` sets both web thicknesses.
pub const KEYS: &[&str] = &[
    "length",
    "top_width",
    "top_thickness",
    "bottom_width",
    "bottom_thickness",
    "web_height",
    "n_long_webs",
    "long_web_span",
    "long_web_thickness",
    "n_trans_webs",
    "trans_web_span",
    "trans_web_thickness",
    "web_thickness",
    "elem_size",
];

impl TableSpec {
    /// Set one parameter by key (`table.top_thickness` or `top_thickness`). Counts must be
    /// non-negative integers.
    pub fn set(&mut self, key: &str, v: f64) -> Result<()> {
        let k = key.strip_prefix("table.").unwrap_or(key);
        let count = |v: f64| -> Result<usize> {
            if !(v.is_finite() && v >= 0.0 && v.fract() == 0.0) {
                Err(bad_key(
                    key,
                    format!("{key} = {v}: a web count must be a non-negative integer"),
                ))
            } else if v > MAX_WEBS {
                Err(bad_key(key, format!("{key} = {v}: at most {MAX_WEBS} webs")))
            } else {
                Ok(v as usize)
            }
        };
        match k {
            "length" => self.length = v,
            "top_width" => self.top_width = v,
            "top_thickness" => self.top_thickness = v,
            "bottom_width" => self.bottom_width = v,
            "bottom_thickness" => self.bottom_thickness = v,
            "web_height" => self.web_height = v,
            "n_long_webs" => self.n_long_webs = count(v)?,
            "long_web_span" => self.long_web_span = v,
            "long_web_thickness" => self.long_web_thickness = v,
            "n_trans_webs" => self.n_trans_webs = count(v)?,
            "trans_web_span" => self.trans_web_span = v,
            "trans_web_thickness" => self.trans_web_thickness = v,
            "web_thickness" => {
                self.long_web_thickness = v;
                self.trans_web_thickness = v;
            }
            "elem_size" => self.elem_size = v,
            _ => {
                return Err(bad_key(
                    key,
                    format!(
                        "unknown sweep key '{key}' (keys: {})",
                        KEYS.iter().map(|k| format!("table.{k}")).collect::<Vec<_>>().join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The [`SandwichParams`] (quad4 shells), validated.
    pub fn params(&self) -> Result<SandwichParams> {
        let (hl, ht) = (0.5 * self.long_web_span, 0.5 * self.trans_web_span);
        let p = SandwichParams {
            length: self.length,
            top_width: self.top_width,
            top_thickness: self.top_thickness,
            bottom_width: self.bottom_width,
            bottom_thickness: self.bottom_thickness,
            web_height: self.web_height,
            long_webs: SandwichParams::evenly_spaced(self.n_long_webs, -hl, hl),
            long_web_thickness: self.long_web_thickness,
            trans_webs: SandwichParams::evenly_spaced(self.n_trans_webs, -ht, ht),
            trans_web_thickness: self.trans_web_thickness,
            elem_size: self.elem_size,
            shell_kind: CellKind::Quad4,
        };
        if self.n_long_webs > 1 && (self.long_web_span.is_nan() || self.long_web_span <= 0.0) {
            return Err(bad_key(
                "table.long_web_span",
                format!("long_web_span = {} must be positive", self.long_web_span),
            ));
        }
        if self.n_trans_webs > 1 && (self.trans_web_span.is_nan() || self.trans_web_span <= 0.0) {
            return Err(bad_key(
                "table.trans_web_span",
                format!("trans_web_span = {} must be positive", self.trans_web_span),
            ));
        }
        p.validate()?;
        if let Some((side, v)) = p.oversized_side(self.elem_size) {
            return Err(bad_key(
                &format!("table.{side}"),
                format!(
                    "table.{side} = {v} m is {:.3e} elements of table.elem_size = {} m, more than \
                     {MAX_TABLE_DIVISIONS} along one side (a table of metres, or a coarser element size)",
                    v / self.elem_size,
                    self.elem_size
                ),
            ));
        }
        Ok(p)
    }
}

/// The form a swept value takes, for errors.
const RANGE_FORMS: &str = "expected a:b:step, v1,v2,… or a value";

/// Parse a range given on the command line (`--set KEY=RANGE`): [`values_of`].
pub fn parse_values(key: &str, s: &str) -> Result<Vec<f64>> {
    values_of(s).map_err(|why| Error::option("--set", format!("--set {key}={s}: {why}; {RANGE_FORMS}")))
}

/// Parse a range: `a:b:step` (inclusive of `b` within 1e-9 of a step), `v1,v2,…` or one value;
/// what is wrong otherwise.
fn values_of(s: &str) -> std::result::Result<Vec<f64>, &'static str> {
    let num = |t: &str| t.trim().parse::<f64>().ok().filter(|x| x.is_finite());
    if s.contains(':') {
        let p: Vec<&str> = s.split(':').collect();
        if p.len() != 3 {
            return Err("a range has three parts");
        }
        let (a, b, st) = match (num(p[0]), num(p[1]), num(p[2])) {
            (Some(a), Some(b), Some(c)) => (a, b, c),
            _ => return Err("not a number"),
        };
        if st <= 0.0 || b < a {
            return Err("the step must be positive and b ≥ a");
        }
        let n = ((b - a) / st + 1e-9).floor();
        if !(n <= 10_000.0) {
            return Err("more than 10 000 values");
        }
        // Round to 12 significant digits so that 0.015 + 2 × 0.0025 prints as 0.02.
        let r = |x: f64| format!("{x:.12e}").parse::<f64>().unwrap_or(x);
        return Ok((0..=n as usize).map(|i| r(a + st * i as f64)).collect());
    }
    let v: Option<Vec<f64>> = s.split(',').map(num).collect();
    match v {
        Some(v) if !v.is_empty() => Ok(v),
        _ => Err("not a number"),
    }
}

/// Parse `KEY=RANGE` (a `--set` argument).
pub fn parse_set(arg: &str) -> Result<(String, Vec<f64>)> {
    let (k, v) = arg
        .split_once('=')
        .ok_or_else(|| Error::option("--set", format!("--set '{arg}': expected KEY=a:b:step or KEY=v1,v2,…")))?;
    let k = k.trim().to_string();
    let mut probe = TableSpec::default();
    probe.set(&k, 1.0)?;
    Ok((k.clone(), parse_values(&k, v.trim())?))
}

/// Which model the sweep analyses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SweepFormulation {
    /// MITC4 mid-surface shells ([`sandwich_table`]); about 10 % soft in racking (formulations.md).
    Shell,
    /// Hex20 solids ([`sandwich_table_solid`]) of size `solid_size`.
    Solid,
}

/// Design constraints: a design is feasible when `f1 ≥ min_f1_hz` and `mass ≤ max_mass_kg`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Constraints {
    /// Lowest admissible first elastic frequency (Hz).
    pub min_f1_hz: f64,
    /// Highest admissible real steel mass (kg).
    pub max_mass_kg: f64,
}

impl Constraints {
    /// The field (`min_f1_hz`, `max_mass_kg`) whose value no design could be compared with, and
    /// why: not a number, or below zero (`max_mass_kg = inf` and `min_f1_hz = 0` set no limit).
    pub fn invalid(&self) -> Option<(&'static str, String)> {
        let bad = |v: f64| v.is_nan() || v < 0.0 || v == f64::NEG_INFINITY;
        if bad(self.min_f1_hz) || self.min_f1_hz.is_infinite() {
            return Some((
                "min_f1_hz",
                format!("{} Hz: must be a finite frequency ≥ 0", self.min_f1_hz),
            ));
        }
        if bad(self.max_mass_kg) {
            return Some((
                "max_mass_kg",
                format!("{} kg: must be a mass ≥ 0 (inf for no limit)", self.max_mass_kg),
            ));
        }
        None
    }
}

impl Default for Constraints {
    fn default() -> Self {
        Constraints {
            min_f1_hz: 300.0,
            max_mass_kg: 165.0,
        }
    }
}

/// Re-analysis of the best designs: shells refined by `shell_refine`, and hex20 solids of
/// `solid_size`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CheckSpec {
    /// How many designs to check (0: none).
    pub designs: usize,
    /// Shell element size divisor of the check.
    pub shell_refine: f64,
    /// Hex20 element size of the check (m).
    pub solid_size: f64,
}

impl Default for CheckSpec {
    fn default() -> Self {
        CheckSpec {
            designs: 0,
            shell_refine: 2.0,
            solid_size: 0.025,
        }
    }
}

/// A parametric study of the sandwich table.
#[derive(Clone, Debug, Serialize)]
pub struct Study {
    /// Name.
    pub name: String,
    /// Model of the sweep.
    pub formulation: SweepFormulation,
    /// Hex20 size for `formulation = "solid"` (m).
    pub solid_size: f64,
    /// Material (`[material]`, default steel).
    #[serde(skip)]
    pub material: Material,
    /// The base design.
    pub table: TableSpec,
    /// Swept keys and their values, in order (the first varies slowest).
    pub sweep: Vec<(String, Vec<f64>)>,
    /// Feasibility limits.
    pub constraints: Constraints,
    /// Check of the best designs.
    pub check: CheckSpec,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStudyFile {
    study: RawStudyHeader,
    material: Option<RawMaterial>,
    #[serde(default)]
    table: TableSpec,
    #[serde(default)]
    sweep: toml::Table,
    #[serde(default)]
    constraints: Constraints,
    #[serde(default)]
    check: CheckSpec,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStudyHeader {
    version: i64,
    name: Option<String>,
    formulation: Option<SweepFormulation>,
    solid_size: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    young: f64,
    poisson: f64,
    density: f64,
}

impl Study {
    /// Load a study file (`[study]` table) or a scene whose mesh is `sandwich:paper[,SIZE]`.
    pub fn load(path: &Path) -> Result<Study> {
        let text = toml_file::read(path)?;
        if text.lines().any(|l| l.trim() == "[study]") {
            Study::from_file(path, &text)
        } else {
            Study::from_scene(path, &text)
        }
    }

    /// A scene on `sandwich:paper[,SIZE]`: the paper's table at that size with the thicknesses
    /// of the scene's shell parts, the scene's material, nothing swept yet. What the sweep's
    /// free–free table cannot carry (a part of its own material or with an offset, supports,
    /// couplings, masses, springs, solid or beam parts) is refused, named, rather than dropped.
    fn from_scene(path: &Path, text: &str) -> Result<Study> {
        let scene = Scene::parse(path, text)?;
        let mut table = TableSpec::default();
        let refuse = |what: String| {
            Err(toml_file::file_error(
                path.display().to_string(),
                None,
                format!(
                    "{what}: a sweep of a scene analyses the free table in the scene's material, with its \
                     parts' thicknesses; write a study file ([study], docs/sweeps.md) for anything else"
                ),
            ))
        };
        for part in &scene.spec.shells {
            let t = part.section.thickness;
            match part.group.as_str() {
                "top_plate" => table.top_thickness = t,
                "bottom_plate" => table.bottom_thickness = t,
                "webs_long" => table.long_web_thickness = t,
                "webs_trans" => table.trans_web_thickness = t,
                g => return refuse(format!("part '{g}' is not a part of the sandwich table")),
            }
            if part.material.is_some_and(|m| m != scene.spec.material) {
                return refuse(format!("part '{}' has a material of its own", part.group));
            }
            if part.section.offset != 0.0 {
                return refuse(format!("part '{}' has an offset", part.group));
            }
        }
        let s = &scene.spec;
        let extra = [
            (!s.fixes.is_empty(), "supports"),
            (!s.couplings.is_empty(), "couplings"),
            (!s.prescribed.is_empty(), "prescribed motion"),
            (!s.point_masses.is_empty(), "point masses"),
            (!(s.springs.is_empty() && s.spring_matrices.is_empty()), "springs"),
            (
                !s.beams.is_empty() || s.solid_groups.as_ref().is_some_and(|g| !g.is_empty()),
                "solid or beam parts",
            ),
            (!s.group_materials.is_empty(), "materials of groups"),
        ];
        if let Some((_, what)) = extra.iter().find(|(has, _)| *has) {
            return refuse(format!("the scene has {what}"));
        }
        let generator = match &scene.mesh {
            MeshSource::Generator(g) if g.starts_with("sandwich:paper") => g,
            _ => {
                return Err(toml_file::file_error(
                    path.display().to_string(),
                    None,
                    "a sweep needs a study file ([study]) or a scene with generator = \"sandwich:paper[,SIZE]\"",
                ));
            }
        };
        match SandwichSpec::parse(generator) {
            Ok(Some(SandwichSpec { elem_size: Some(h) })) => table.elem_size = h,
            Ok(Some(SandwichSpec { elem_size: None })) => {}
            _ => {
                return Err(toml_file::key_error(
                    path,
                    text,
                    "mesh.generator",
                    format!("generator '{generator}': bad element size"),
                ));
            }
        }
        Ok(Study {
            name: scene.name.clone(),
            formulation: SweepFormulation::Shell,
            solid_size: 0.025,
            material: scene.spec.material,
            table,
            sweep: Vec::new(),
            constraints: Constraints::default(),
            check: CheckSpec::default(),
        })
    }

    /// A study file (`[study]`, `[material]`, `[table]`, `[sweep]`, `[constraints]`,
    /// `[check]`).
    fn from_file(path: &Path, text: &str) -> Result<Study> {
        let raw: RawStudyFile = toml_file::parse(path, text)?;
        toml_file::check_version(path, text, "[study]", raw.study.version)?;
        let material = match raw.material {
            None => Material::steel(),
            Some(m) => Material {
                young: m.young,
                poisson: m.poisson,
                density: m.density,
            },
        };
        let mut sweep = Vec::new();
        for (k, v) in &raw.sweep {
            let at = |msg: String| {
                let line = toml_file::line_of_table_key(text, "sweep", 0, k).key;
                toml_file::file_error(path.display().to_string(), line, msg)
            };
            let vals = match v {
                toml::Value::String(s) => {
                    values_of(s).map_err(|why| at(format!("[sweep] '{k}' = \"{s}\": {why}; {RANGE_FORMS}")))?
                }
                toml::Value::Array(a) => a
                    .iter()
                    .map(|x| x.as_float().or_else(|| x.as_integer().map(|i| i as f64)))
                    .collect::<Option<Vec<f64>>>()
                    .ok_or_else(|| at(format!("[sweep] '{k}': values must be numbers")))?,
                toml::Value::Float(f) => vec![*f],
                toml::Value::Integer(i) => vec![*i as f64],
                _ => return Err(at(format!("[sweep] '{k}': expected a range or a list"))),
            };
            TableSpec::default().set(k, 1.0).map_err(|e| at(strip(e)))?;
            sweep.push((k.clone(), vals));
        }
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let study = Study {
            name: raw.study.name.unwrap_or(stem),
            formulation: raw.study.formulation.unwrap_or(SweepFormulation::Shell),
            solid_size: raw.study.solid_size.unwrap_or(0.025),
            material,
            table: raw.table,
            sweep,
            constraints: raw.constraints,
            check: raw.check,
        };
        study.check_file(path, text)?;
        Ok(study)
    }

    /// The file's values checked as it is read, each error at its line and key: the material,
    /// the base `[table]`, each `[sweep]` value on it and the solid element sizes. (Found later,
    /// in a case or after the sweep, they named neither file nor key.)
    fn check_file(&self, path: &Path, text: &str) -> Result<()> {
        if let Some((field, msg)) = self.material.invalid() {
            return Err(toml_file::key_error(path, text, &format!("material.{field}"), msg));
        }
        if let Some((field, msg)) = self.constraints.invalid() {
            return Err(toml_file::key_error(path, text, &format!("constraints.{field}"), msg));
        }
        // A [sweep] entry is named as written there ("table.n_long_webs"), at its line.
        let located = |e: Error, section: &str| match toml_file::param_as_key(e, |n| {
            format!("table.{}", n.trim_start_matches("table."))
        }) {
            Ok((key, msg)) => {
                let line = match section {
                    "sweep" => self
                        .sweep
                        .iter()
                        .find(|(k, _)| format!("table.{}", k.trim_start_matches("table.")) == key)
                        .and_then(|(k, _)| toml_file::line_of_table_key(text, "sweep", 0, k).key),
                    _ => toml_file::line_of_key(text, &key),
                };
                Error::key(path.display().to_string(), line, key, msg)
            }
            Err(e) => toml_file::locate(path, text, e),
        };
        self.table.params().map_err(|e| located(e, "table"))?;
        self.check_values().map_err(|e| located(e, "sweep"))?;
        self.check_sizes().map_err(|e| {
            let key_of = |n: String| {
                if n == "solid_size" {
                    "study.solid_size".to_string()
                } else {
                    n
                }
            };
            match toml_file::param_as_key(e, key_of) {
                Ok((key, msg)) => toml_file::key_error(path, text, &key, msg),
                Err(e) => e,
            }
        })
    }

    /// The solid element sizes in use (the solid formulation's `solid_size`; `[check]
    /// solid_size` when designs are checked): positive, and at most [`MAX_TABLE_DIVISIONS`]
    /// elements along a side of the base table or of any swept value on it.
    fn check_sizes(&self) -> Result<()> {
        let mut sizes = Vec::new();
        if self.formulation == SweepFormulation::Solid {
            sizes.push(("solid_size", self.solid_size));
        }
        if self.check.designs > 0 {
            sizes.push(("check.solid_size", self.check.solid_size));
        }
        for &(key, h) in &sizes {
            if !(h.is_finite() && h > 0.0) {
                return Err(Error::param(key, format!("{key} = {h} must be positive")));
            }
        }
        let oversized = |t: &TableSpec| -> Result<()> {
            for &(key, h) in &sizes {
                if let Some((side, v)) = t.params()?.oversized_side(h) {
                    return Err(Error::param(
                        key,
                        format!(
                            "{key} = {h} m is {:.3e} elements along table.{side} = {v} m, more than \
                             {MAX_TABLE_DIVISIONS} (a coarser solid element size)",
                            v / h
                        ),
                    ));
                }
            }
            Ok(())
        };
        if sizes.is_empty() {
            return Ok(());
        }
        oversized(&self.table)?;
        self.each_swept_value(|_, _, t| oversized(t))
    }

    /// Replace or add swept keys (command-line `--set` wins over the file's `[sweep]`).
    pub fn set(&mut self, key: &str, values: Vec<f64>) {
        let norm = |k: &str| k.strip_prefix("table.").unwrap_or(k).to_string();
        if let Some(e) = self.sweep.iter_mut().find(|(k, _)| norm(k) == norm(key)) {
            e.1 = values;
        } else {
            self.sweep.push((key.to_string(), values));
        }
    }

    /// Each swept value on the base table, so that a message names the one bad key. A value
    /// out of range there may be in range beside another swept key's value (a web span with
    /// a wider plate): it is refused only when no combination of the sweep takes it (the
    /// combinations that do not are failed designs of the run, [`Study::designs`]).
    pub fn check_values(&self) -> Result<()> {
        let mut usable: Option<Vec<bool>> = None;
        for (j, (k, vals)) in self.sweep.iter().enumerate() {
            for &v in vals {
                let mut t = self.table.clone();
                t.set(k, v)?;
                let Err(e) = t.params() else {
                    continue;
                };
                let ok = match &usable {
                    Some(u) => u,
                    None => usable.insert(match self.count() {
                        Ok(n) => (0..n).map(|i| self.design(i).is_ok()).collect(),
                        Err(_) => Vec::new(),
                    }),
                };
                if !ok.iter().enumerate().any(|(i, &ok)| ok && self.values(i)[j] == v) {
                    return Err(bad_key(k, format!("{k} = {v}: {}", strip(e))));
                }
            }
        }
        Ok(())
    }

    /// `f(key, value, table)` for each swept value alone on the base table.
    fn each_swept_value(&self, mut f: impl FnMut(&str, f64, &TableSpec) -> Result<()>) -> Result<()> {
        for (k, vals) in &self.sweep {
            for &v in vals {
                let mut t = self.table.clone();
                t.set(k, v)?;
                f(k, v, &t)?;
            }
        }
        Ok(())
    }

    /// How many designs the study has, counted from the list lengths before any design is
    /// built: a key that lists no value, or more than [`MAX_DESIGNS`] combinations, is refused
    /// with the count (as the product of the lengths where it overflows).
    pub fn count(&self) -> Result<usize> {
        if let Some((k, _)) = self.sweep.iter().find(|(_, v)| v.is_empty()) {
            return Err(bad_key(
                k,
                format!("the sweep has 0 combinations ('{k}' lists no value)"),
            ));
        }
        let n = self.sweep.iter().try_fold(1usize, |n, (_, v)| n.checked_mul(v.len()));
        let shown = match n {
            Some(n) if n <= MAX_DESIGNS => return Ok(n),
            Some(n) => n.to_string(),
            None => {
                let lens: Vec<String> = self.sweep.iter().map(|(_, v)| v.len().to_string()).collect();
                lens.join(" × ")
            }
        };
        Err(Error::param(
            "sweep",
            format!("the sweep has {shown} combinations (at most 100 000)"),
        ))
    }

    /// The swept values of design `i` (0-based; the first key varies slowest).
    fn values(&self, i: usize) -> Vec<f64> {
        let mut rem = i;
        let mut vals = vec![0.0; self.sweep.len()];
        for (j, (_, v)) in self.sweep.iter().enumerate().rev() {
            vals[j] = v[rem % v.len()];
            rem /= v.len();
        }
        vals
    }

    /// Design `i` (0-based; the first key varies slowest): its values and validated parameters.
    pub fn design(&self, i: usize) -> Result<(Vec<f64>, TableSpec, SandwichParams)> {
        let vals = self.values(i);
        let mut t = self.table.clone();
        for ((k, _), v) in self.sweep.iter().zip(&vals) {
            t.set(k, *v)?;
        }
        let p = t.params().map_err(|e| {
            let what: Vec<String> = self
                .sweep
                .iter()
                .zip(&vals)
                .map(|((k, _), v)| format!("{k} = {v}"))
                .collect();
            Error::param("sweep", format!("{}: {}", what.join(", "), strip(e)))
        })?;
        Ok((vals, t, p))
    }

    /// Every combination (the first key varies slowest) as its values and validated parameters,
    /// or the reason the combination is no table (a failed design of the run, named by all its
    /// values). Nothing is meshed: a value no combination takes is reported with its key before
    /// any analysis ([`Study::check_values`]), and the combinations are counted
    /// ([`Study::count`]) before any is built.
    pub fn designs(&self) -> Result<Vec<Design>> {
        self.check_values()?;
        let n = self.count()?;
        Ok((0..n)
            .map(|i| match self.design(i) {
                Ok((vals, t, p)) => (vals, Ok((t, p))),
                Err(e) => (self.values(i), Err(strip(e))),
            })
            .collect())
    }
}

/// One combination of a study ([`Study::designs`]): its values, then its table and validated
/// parameters or why it is no table.
pub type Design = (Vec<f64>, std::result::Result<(TableSpec, SandwichParams), String>);

/// The most combinations a study may have ([`Study::count`]).
pub const MAX_DESIGNS: usize = 100_000;

/// The message of an error without its place (to be given another).
fn strip(e: Error) -> String {
    match e {
        Error::InvalidInput(s) | Error::Invalid { msg: s, .. } => s,
        e => e.to_string(),
    }
}

/// One analysed design.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SweepRow {
    /// 1-based case number.
    pub case: usize,
    /// Values of the swept keys, in the study's order.
    pub values: Vec<f64>,
    /// Real steel mass, [`SandwichParams::mass`] (kg).
    pub mass_kg: f64,
    /// Mass the analysed model carries (kg).
    pub model_mass_kg: f64,
    /// First and second elastic frequencies (Hz).
    pub f1_hz: f64,
    /// Second elastic frequency (Hz).
    pub f2_hz: f64,
    /// Free DOFs.
    pub dofs: usize,
    /// Wall time (s).
    pub time_s: f64,
    /// Meets the constraints.
    pub feasible: bool,
    /// On the Pareto front (no design is both lighter-or-equal and stiffer-or-equal, one strictly).
    pub pareto: bool,
}

/// Result of a modal run of one design.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct DesignResult {
    /// Mass of the model (kg).
    pub model_mass_kg: f64,
    /// First elastic frequency (Hz).
    pub f1_hz: f64,
    /// Second elastic frequency (Hz).
    pub f2_hz: f64,
    /// Free DOFs.
    pub dofs: usize,
    /// Wall time (s).
    pub time_s: f64,
}

/// Free–free modal analysis of one table: shells (`solid_size = None`) or hex20 solids of size h.
pub fn analyse(p: &SandwichParams, material: Material, solid_size: Option<f64>) -> Result<DesignResult> {
    analyse_modes(p, material, solid_size, 10).map(|(r, _, _)| r)
}

/// [`analyse`] with the `n_modes` lowest modes (rigid-body ones included) and the mesh, for
/// callers that look at the shapes (mode pairing in `converge`).
pub fn analyse_modes(
    p: &SandwichParams,
    material: Material,
    solid_size: Option<f64>,
    n_modes: usize,
) -> Result<(DesignResult, crate::analysis::modal::ModalRun, crate::mesh::Mesh)> {
    let t = Instant::now();
    let (mesh, spec) = match solid_size {
        None => {
            let mesh = sandwich_table(p)?;
            let shells = p
                .thicknesses()
                .into_iter()
                .map(|(g, t)| ShellPart {
                    group: g,
                    section: ShellSection::new(t),
                    material: None,
                })
                .collect();
            let spec = ModelSpec {
                material,
                shells,
                ..Default::default()
            };
            (mesh, spec)
        }
        Some(h) => {
            let mesh = sandwich_table_solid(p, h, CellKind::Hex20)?;
            let spec = ModelSpec {
                material,
                ..Default::default()
            };
            (mesh, spec)
        }
    };
    let run = run_modal(
        &mesh,
        "sandwich table",
        &ModalOptions {
            spec,
            target: ModalTarget::Modes(n_modes),
            ..Default::default()
        },
        0.0,
    )?;
    if !run.report.complete {
        return Err(Error::Verification(
            "sandwich table modal analysis: a mode was missed".into(),
        ));
    }
    if !run.report.accurate {
        // A design so thin or so small that its frequencies are rounding (negative ones among
        // them) must not enter the table, let alone its Pareto front.
        let why = run
            .report
            .notes
            .iter()
            .find(|n| n.contains("negative eigenvalues") || n.starts_with("accuracy not guaranteed"))
            .map_or(String::new(), |n| format!(": {n}"));
        return Err(Error::Verification(format!(
            "sandwich table modal analysis: accuracy not guaranteed{why}"
        )));
    }
    let el: Vec<f64> = run.report.elastic_frequencies();
    if el.is_empty() {
        return Err(Error::Verification(
            "sandwich table: no elastic mode among the lowest 10".into(),
        ));
    }
    let r = DesignResult {
        model_mass_kg: run.report.mass_kg,
        f1_hz: el[0],
        f2_hz: el.get(1).copied().unwrap_or(f64::NAN),
        dofs: run.report.dofs,
        time_s: t.elapsed().as_secs_f64(),
    };
    Ok((r, run, mesh))
}

/// Mark the Pareto front (minimum mass, maximum f1) of `rows`.
pub fn mark_pareto(rows: &mut [SweepRow]) {
    let pts: Vec<(f64, f64)> = rows.iter().map(|r| (r.mass_kg, r.f1_hz)).collect();
    for (i, r) in rows.iter_mut().enumerate() {
        let (m, f) = pts[i];
        r.pareto = !pts
            .iter()
            .enumerate()
            .any(|(j, &(mj, fj))| j != i && mj <= m && fj >= f && (mj < m || fj > f));
    }
}

/// A re-analysis of one of the best designs.
#[derive(Clone, Debug, Serialize)]
pub struct CheckRow {
    /// Case number of the sweep.
    pub case: usize,
    /// Real mass (kg).
    pub mass_kg: f64,
    /// f1 of the sweep's model (Hz).
    pub f1_sweep_hz: f64,
    /// f1 of the refined shell model (Hz).
    pub f1_shell_fine_hz: f64,
    /// Shell element size of the check (m).
    pub shell_size: f64,
    /// f1 of the hex20 solid (Hz).
    pub f1_solid_hz: f64,
    /// Hex20 size (m).
    pub solid_size: f64,
    /// Feasible by the solid model.
    pub feasible_solid: bool,
}

/// The outcome of a sweep.
#[derive(Clone, Debug, Serialize)]
pub struct SweepOutcome {
    /// The study.
    pub study: Study,
    /// One row per design, in case order.
    pub rows: Vec<SweepRow>,
    /// Checks of the best designs.
    pub checks: Vec<CheckRow>,
    /// Designs (and checks) whose analysis failed, in case order: the study goes on past them.
    pub failed: Vec<FailedCase>,
}

/// A design of a sweep whose analysis failed (or whose check did).
#[derive(Clone, Debug, Serialize)]
pub struct FailedCase {
    /// 1-based case number.
    pub case: usize,
    /// Values of the swept keys, in the study's order.
    pub values: Vec<f64>,
    /// `design` (the sweep's own analysis) or `check` (the re-run of a best design).
    pub stage: &'static str,
    /// Why, as the error reads.
    pub error: String,
}

/// Options of [`run_sweep`].
#[derive(Clone, Debug)]
pub struct SweepOptions {
    /// Output folder (`sweep.csv`, `sweep.json`, `pareto.svg`).
    pub out: Option<PathBuf>,
    /// Concurrent designs.
    pub jobs: usize,
    /// Print one line per design on stderr.
    pub progress: bool,
    /// Start a study larger than [`LARGE_SWEEP`] designs (`--yes`); without it such a study is
    /// refused with its size, before any analysis.
    pub yes: bool,
}

/// Studies with more designs than this start only when asked for explicitly (`--yes`): at a
/// second or more per design they run for a quarter of an hour or more.
pub const LARGE_SWEEP: usize = 1000;

/// Run a study: validate every combination, analyse each, mark feasibility and the Pareto front,
/// check the best designs (`[check] designs`), and write the outputs.
pub fn run_sweep(study: &Study, opts: &SweepOptions) -> Result<SweepOutcome> {
    use rayon::prelude::*;
    // Values and the count (in `designs`), then the sizes: all before any design is meshed.
    let designs = study.designs()?;
    let total = designs.len();
    study.check_sizes()?;
    let solid = (study.formulation == SweepFormulation::Solid).then_some(study.solid_size);
    if total > LARGE_SWEEP && !opts.yes {
        // The size of one design's model, from its mesh (no analysis).
        let Some(p) = designs
            .iter()
            .find_map(|(_, d)| d.as_ref().ok().map(|(_, p)| p.clone()))
        else {
            return Err(study
                .design(0)
                .err()
                .unwrap_or_else(|| Error::param("sweep", "no valid design")));
        };
        let dofs = match solid {
            None => 6 * sandwich_table(&p)?.n_nodes(),
            Some(h) => 3 * sandwich_table_solid(&p, h, CellKind::Hex20)?.n_nodes(),
        };
        return Err(Error::option(
            "--yes",
            format!(
                "the study has {total} designs (more than {LARGE_SWEEP}) of about {dofs} DOFs each (each a modal \
                 solve: from hundredths of a second at a few thousand DOFs to seconds at a hundred thousand): rerun \
                 with --yes to start it, or narrow the ranges (--set)"
            ),
        ));
    }
    let done = std::sync::atomic::AtomicUsize::new(0);
    let one = |(i, (vals, d)): (usize, &Design)| -> std::result::Result<SweepRow, FailedCase> {
        let r = match d {
            Ok((_, p)) => analyse(p, study.material, solid),
            Err(msg) => Err(Error::param("sweep", msg.clone())),
        };
        let p = d.as_ref().map_or(None, |(_, p)| Some(p));
        let k = done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
        let r = r.map_err(|e| {
            if opts.progress {
                eprintln!("[{k}/{total}] {}: failed: {e}", describe(study, vals));
            }
            FailedCase {
                case: i + 1,
                values: vals.clone(),
                stage: "design",
                error: e.to_string(),
            }
        })?;
        let Some(p) = p else {
            unreachable!("a combination that is no table failed above");
        };
        let mass = p.mass(study.material.density);
        if opts.progress {
            eprintln!(
                "[{k}/{total}] {}: {mass:.1} kg, f1 {:.1} Hz ({:.2} s)",
                describe(study, vals),
                r.f1_hz,
                r.time_s
            );
        }
        Ok(SweepRow {
            case: i + 1,
            values: vals.clone(),
            mass_kg: mass,
            model_mass_kg: r.model_mass_kg,
            f1_hz: r.f1_hz,
            f2_hz: r.f2_hz,
            dofs: r.dofs,
            time_s: r.time_s,
            feasible: r.f1_hz >= study.constraints.min_f1_hz && mass <= study.constraints.max_mass_kg,
            pareto: false,
        })
    };
    let jobs = opts.jobs.max(1);
    let results: Vec<std::result::Result<SweepRow, FailedCase>> = if jobs == 1 {
        designs.iter().enumerate().map(one).collect()
    } else {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(jobs)
            .build()
            .map_err(|e| Error::param("jobs", format!("sweep: cannot start {jobs} workers: {e}")))?;
        pool.install(|| designs.par_iter().enumerate().map(one).collect())
    };
    let (mut rows, mut failed) = (Vec::new(), Vec::new());
    for r in results {
        match r {
            Ok(row) => rows.push(row),
            Err(f) => failed.push(f),
        }
    }
    mark_pareto(&mut rows);
    let mut checks = Vec::new();
    if study.check.designs > 0 {
        for r in best(&rows, study.check.designs) {
            let Ok((_, p)) = &designs[r.case - 1].1 else {
                continue;
            };
            match check_design(study, p, r) {
                Ok(c) => {
                    if opts.progress {
                        eprintln!(
                            "check case {}: shell {} m {:.1} Hz, hex20 {} m {:.1} Hz",
                            c.case, c.shell_size, c.f1_shell_fine_hz, c.solid_size, c.f1_solid_hz
                        );
                    }
                    checks.push(c);
                }
                Err(e) => {
                    if opts.progress {
                        eprintln!("check case {}: failed: {e}", r.case);
                    }
                    failed.push(FailedCase {
                        case: r.case,
                        values: r.values.clone(),
                        stage: "check",
                        error: e.to_string(),
                    });
                }
            }
        }
    }
    let outcome = SweepOutcome {
        study: study.clone(),
        rows,
        checks,
        failed,
    };
    if let Some(dir) = &opts.out {
        write_outputs(&outcome, dir)?;
    }
    Ok(outcome)
}

/// The check of one of the best designs: a finer shell mesh and the hex20 solid.
fn check_design(study: &Study, p: &SandwichParams, r: &SweepRow) -> Result<CheckRow> {
    let mut fine = p.clone();
    fine.elem_size = p.elem_size / study.check.shell_refine.max(1.0);
    let s = analyse(&fine, study.material, None)?;
    let so = analyse(p, study.material, Some(study.check.solid_size))?;
    Ok(CheckRow {
        case: r.case,
        mass_kg: r.mass_kg,
        f1_sweep_hz: r.f1_hz,
        f1_shell_fine_hz: s.f1_hz,
        shell_size: fine.elem_size,
        f1_solid_hz: so.f1_hz,
        solid_size: study.check.solid_size,
        feasible_solid: so.f1_hz >= study.constraints.min_f1_hz && r.mass_kg <= study.constraints.max_mass_kg,
    })
}

/// The `n` best designs: feasible ones by descending f1 (then ascending mass), else the Pareto
/// designs within the mass limit by descending f1, else the lightest Pareto designs.
pub fn best(rows: &[SweepRow], n: usize) -> Vec<&SweepRow> {
    let mut feas: Vec<&SweepRow> = rows.iter().filter(|r| r.feasible).collect();
    if feas.is_empty() {
        feas = rows.iter().filter(|r| r.pareto).collect();
    }
    feas.sort_by(|a, b| b.f1_hz.total_cmp(&a.f1_hz).then(a.mass_kg.total_cmp(&b.mass_kg)));
    feas.truncate(n);
    feas
}

fn describe(study: &Study, vals: &[f64]) -> String {
    study
        .sweep
        .iter()
        .zip(vals)
        .map(|((k, _), v)| format!("{k}={}", crate::io::fmt_plain(*v)))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The result table as text; feasible designs are marked `*`, Pareto designs `P`.
pub fn table_text(o: &SweepOutcome) -> String {
    let c = &o.study.constraints;
    let mut s = format!(
        "study {} ({} model); * = f1 ≥ {} Hz and mass ≤ {} kg, P = Pareto front\n",
        o.study.name,
        match o.study.formulation {
            SweepFormulation::Shell => "MITC4 mid-surface shell",
            SweepFormulation::Solid => "hex20 solid",
        },
        c.min_f1_hz,
        c.max_mass_kg
    );
    s.push_str(&format!("{:>5} ", "case"));
    for (k, _) in &o.study.sweep {
        s.push_str(&format!("{:>w$} ", k, w = k.len().max(8)));
    }
    s.push_str(&format!(
        "{:>9} {:>9} {:>9} {:>8} {:>7}  \n",
        "mass kg", "f1 Hz", "f2 Hz", "dofs", "time s"
    ));
    for r in &o.rows {
        s.push_str(&format!("{:>5} ", r.case));
        for ((k, _), v) in o.study.sweep.iter().zip(&r.values) {
            s.push_str(&format!("{:>w$} ", v, w = k.len().max(8)));
        }
        s.push_str(&format!(
            "{:>9.2} {:>9.1} {:>9.1} {:>8} {:>7.2} {}{}\n",
            r.mass_kg,
            r.f1_hz,
            r.f2_hz,
            r.dofs,
            r.time_s,
            if r.feasible { "*" } else { " " },
            if r.pareto { "P" } else { " " }
        ));
    }
    let nf = o.rows.iter().filter(|r| r.feasible).count();
    s.push_str(&format!("{nf} of {} designs meet the constraints\n", o.rows.len()));
    if !o.failed.is_empty() {
        s.push_str(&format!("{} failed (the study went on past them):\n", o.failed.len()));
        for f in &o.failed {
            let what = if f.stage == "check" { "check of case" } else { "case" };
            s.push_str(&format!(
                "  {what} {} ({}): {}\n",
                f.case,
                describe(&o.study, &f.values),
                f.error
            ));
        }
    }
    if !o.checks.is_empty() {
        s.push_str(
            "check of the best designs:\n  case   mass kg   f1 sweep   f1 shell fine   f1 hex20   feasible (hex20)\n",
        );
        for c in &o.checks {
            s.push_str(&format!(
                "  {:>4} {:>9.2} {:>10.1} {:>10.1} ({:.4}) {:>8.1} ({:.4}) {}\n",
                c.case,
                c.mass_kg,
                c.f1_sweep_hz,
                c.f1_shell_fine_hz,
                c.shell_size,
                c.f1_solid_hz,
                c.solid_size,
                if c.feasible_solid { "yes" } else { "no" }
            ));
        }
    }
    s
}

/// The rows as CSV, in case order:
/// `case,<keys…>,mass_kg,model_mass_kg,f1_hz,f2_hz,dofs,time_s,feasible,pareto,error`; a design
/// whose analysis failed has its values, empty results and the error.
pub fn sweep_csv(o: &SweepOutcome) -> String {
    let mut s = String::from("case");
    for (k, _) in &o.study.sweep {
        s.push_str(&format!(",{k}"));
    }
    s.push_str(",mass_kg,model_mass_kg,f1_hz,f2_hz,dofs,time_s,feasible,pareto,error\n");
    let failed = o.failed.iter().filter(|f| f.stage == "design");
    let mut lines: Vec<(usize, String)> = o
        .rows
        .iter()
        .map(|r| {
            let res = format!(
                ",{:.6},{:.6},{:.6},{:.6},{},{:.3},{},{},",
                r.mass_kg, r.model_mass_kg, r.f1_hz, r.f2_hz, r.dofs, r.time_s, r.feasible, r.pareto
            );
            (r.case, csv_values(&r.values) + &res)
        })
        .chain(failed.map(|f| {
            let err = format!(",,,,,,,false,false,{}", super::batch::csv_field(&f.error));
            (f.case, csv_values(&f.values) + &err)
        }))
        .collect();
    lines.sort_by_key(|l| l.0);
    for (case, l) in lines {
        s.push_str(&format!("{case}{l}\n"));
    }
    s
}

fn csv_values(v: &[f64]) -> String {
    v.iter().map(|v| format!(",{}", crate::io::fmt_plain(*v))).collect()
}

/// Write `sweep.csv`, `sweep.json` and `pareto.svg` to `dir` (created).
pub fn write_outputs(o: &SweepOutcome, dir: &Path) -> Result<()> {
    crate::io::create_dir(dir)?;
    let p = dir.join("sweep.csv");
    std::fs::write(&p, sweep_csv(o)).map_err(|e| Error::io(&p, e))?;
    let p = dir.join("sweep.json");
    let text = serde_json::to_string_pretty(o).map_err(|e| Error::output("JSON", e))?;
    std::fs::write(&p, text).map_err(|e| Error::io(&p, e))?;
    write_pareto_svg(o, &dir.join("pareto.svg"))
}

fn perr<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| Error::io(path, std::io::Error::other(format!("plotting failed: {e}")))
}

fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for x in v.filter(|x| x.is_finite()) {
        lo = lo.min(x);
        hi = hi.max(x);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(hi.abs() * 0.02).max(1e-9);
    (lo - pad, hi + pad)
}

/// SVG of mass against first elastic frequency: every design, the Pareto front as a line, the
/// feasible region's limits dashed.
pub fn write_pareto_svg(o: &SweepOutcome, path: &Path) -> Result<()> {
    use plotters::prelude::*;
    let c = o.study.constraints;
    let (x0, x1) = range(o.rows.iter().map(|r| r.mass_kg).chain([c.max_mass_kg]));
    let (y0, y1) = range(o.rows.iter().map(|r| r.f1_hz).chain([c.min_f1_hz]));
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(perr(path))?;
    let mut ch = ChartBuilder::on(&root)
        .caption(
            format!("{}: mass against first elastic frequency", o.study.name),
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(perr(path))?;
    ch.configure_mesh()
        .x_desc("mass, kg")
        .y_desc("first elastic frequency, Hz")
        .draw()
        .map_err(perr(path))?;
    let grey = RGBColor(150, 150, 150);
    ch.draw_series(DashedLineSeries::new(
        [(c.max_mass_kg, y0), (c.max_mass_kg, y1)],
        6,
        4,
        grey.stroke_width(1),
    ))
    .map_err(perr(path))?;
    ch.draw_series(DashedLineSeries::new(
        [(x0, c.min_f1_hz), (x1, c.min_f1_hz)],
        6,
        4,
        grey.stroke_width(1),
    ))
    .map_err(perr(path))?
    .label("constraints")
    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(1)));
    let blue = RGBColor(31, 119, 180);
    let red = RGBColor(214, 39, 40);
    let green = RGBColor(44, 160, 44);
    ch.draw_series(
        o.rows
            .iter()
            .filter(|r| !r.feasible)
            .map(|r| Circle::new((r.mass_kg, r.f1_hz), 3, blue.filled())),
    )
    .map_err(perr(path))?
    .label("design")
    .legend(move |(x, y)| Circle::new((x + 10, y), 3, blue.filled()));
    ch.draw_series(
        o.rows
            .iter()
            .filter(|r| r.feasible)
            .map(|r| Circle::new((r.mass_kg, r.f1_hz), 4, green.filled())),
    )
    .map_err(perr(path))?
    .label("meets the constraints")
    .legend(move |(x, y)| Circle::new((x + 10, y), 4, green.filled()));
    let mut front: Vec<(f64, f64)> = o
        .rows
        .iter()
        .filter(|r| r.pareto)
        .map(|r| (r.mass_kg, r.f1_hz))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    ch.draw_series(LineSeries::new(front.clone(), red.stroke_width(2)))
        .map_err(perr(path))?
        .label("Pareto front")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], red.stroke_width(2)));
    ch.draw_series(front.iter().map(|&p| Circle::new(p, 5, red.stroke_width(2))))
        .map_err(perr(path))?;
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(perr(path))?;
    root.present().map_err(perr(path))?;
    Ok(())
}
