//! Speed–accuracy studies (`vibrofem converge`): a case re-run over mesh refinements and
//! formulations, with value, estimated error, DOFs, wall time and peak memory per run, and the
//! cheapest run within 1 %, 0.1 % and 0.01 %.
//!
//! Built-in cases ([`builtin`]): `s1` (free plate, first elastic frequency: tet4, tet10, hex8,
//! hex20 boxes and MITC4 shells on the box's bottom face), `s3` (leaf spring stiffness: hex8,
//! hex20, tet4, tet10 boxes), `s5` (coil stiffness: line2 and line3 beam helices), `s7` (sandwich
//! table, first elastic frequency: MITC4 mid-surface shells and hex20 solids). A scene whose mesh
//! is a `box:`, `helix:` or `sandwich:paper` generator is refined by halving its element size
//! ([`from_scene`]).
//!
//! The reference is a documented converged value where one exists (S1: docs/validation.md's hex20
//! 45×45×9; S7: the finest graded hex20 of docs/formulations.md), else the Richardson
//! extrapolation of the reference formulation's last three levels (each halving the element size)
//! when they converge monotonically at an order ≥ 1.5, else its finest level.

use super::geo::Gmsh;
use super::scene::{MeshSource, Scene};
use crate::analysis::modal::ModalTarget;
use crate::analysis::statics::Load;
use crate::app::toml_file;
use crate::input::source::{BoxSpec, HelixSpec, SandwichSpec};
use crate::mesh::parametric::SandwichParams;
use crate::mesh::{CellKind, Mesh};
use crate::model::ModelSpec;
use crate::{Error, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// How one run of a case is made.
#[derive(Clone, Debug)]
pub enum Runner {
    /// A scene; the value is its first elastic frequency (modal) or its stiffness (static).
    Scene(Box<Scene>),
    /// The S7 table as MITC4 mid-surface shells of this size (m); value: first elastic frequency.
    TableShell(f64),
    /// The S7 table as hex20 solids of this size (m); value: first elastic frequency.
    TableSolid(f64),
}

/// One run of a convergence study.
#[derive(Clone, Debug)]
pub struct LevelSpec {
    /// Formulation name (`hex20`, `shell`, `line3`, …).
    pub formulation: String,
    /// Mesh label (divisions or element size).
    pub mesh: String,
    /// How to run it.
    pub runner: Runner,
}

/// A convergence study: its runs and which formulation is the reference.
#[derive(Clone, Debug)]
pub struct Case {
    /// Name.
    pub name: String,
    /// What is measured (`first elastic frequency`, `stiffness`).
    pub quantity: String,
    /// Its unit.
    pub unit: String,
    /// The runs, grouped by formulation, coarse to fine.
    pub levels: Vec<LevelSpec>,
    /// The formulation whose finest levels give the reference.
    pub reference: String,
    /// A documented converged value and its source, used as the reference instead.
    pub known: Option<(f64, String)>,
}

/// The result of one run.
#[derive(Clone, Debug, Serialize)]
pub struct LevelResult {
    /// Formulation.
    pub formulation: String,
    /// Mesh label.
    pub mesh: String,
    /// Value.
    pub value: f64,
    /// Relative error against the reference.
    pub error: f64,
    /// Free DOFs.
    pub dofs: usize,
    /// Wall time, s.
    pub time_s: f64,
    /// Peak resident memory of the run (bytes), where the OS reports it.
    pub peak_memory_bytes: Option<u64>,
    /// When MAC pairing with the finest level's mode chose another than this level's first
    /// elastic mode: which one (1-based among the elastic modes) and the MAC.
    pub paired: Option<(usize, f64)>,
}

/// Elastic modes of one level for MAC pairing: frequencies and shapes at the mesh nodes.
#[derive(Clone, Debug, Default)]
pub struct LevelModes {
    /// Node coordinates.
    pub points: Vec<[f64; 3]>,
    /// Elastic frequencies, ascending (Hz).
    pub freqs: Vec<f64>,
    /// Their shapes, 3 per node.
    pub shapes: Vec<Vec<f64>>,
}

/// Extra elastic modes computed per level so that a mode that moves up in the order with
/// refinement can still be found.
const PAIRING_EXTRA: usize = 5;

/// Modal assurance criterion of two shapes sampled at the same points.
pub fn mac(a: &[f64], b: &[f64]) -> f64 {
    let ab: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let aa: f64 = a.iter().map(|x| x * x).sum();
    let bb: f64 = b.iter().map(|x| x * x).sum();
    if aa > 0.0 && bb > 0.0 { ab * ab / (aa * bb) } else { 0.0 }
}

/// For each of `samples`, the index of the nearest of `points` (brute force; exact on nested
/// refinements, where every coarse node is a fine node).
fn nearest(samples: &[[f64; 3]], points: &[[f64; 3]]) -> Vec<usize> {
    samples
        .iter()
        .map(|s| {
            let d = |p: &[f64; 3]| (p[0] - s[0]).powi(2) + (p[1] - s[1]).powi(2) + (p[2] - s[2]).powi(2);
            (0..points.len())
                .min_by(|&i, &j| d(&points[i]).total_cmp(&d(&points[j])))
                .unwrap_or(0)
        })
        .collect()
}

/// A shape sampled at the given node indices (3 components each).
fn sample(shape: &[f64], at: &[usize]) -> Vec<f64> {
    at.iter()
        .flat_map(|&a| shape.get(3 * a..3 * a + 3).unwrap_or(&[0.0; 3]).to_vec())
        .collect()
}

/// Pair each level's modes with the finest level's first elastic mode by MAC: the shapes are
/// sampled at the coarsest level's nodes (the nearest node of each level; box and helix
/// refinements are nested, so these are the same points), and the level's mode with the
/// largest MAC is taken. Returns, per level, `(index among its elastic modes, MAC)`, or `None`
/// where a level has no shapes.
pub fn pair_by_mac(levels: &[Option<LevelModes>]) -> Vec<Option<(usize, f64)>> {
    pair_mode_by_mac(levels, 0)
}

/// [`pair_by_mac`] for the finest level's elastic mode `mode` (0-based) instead of its first.
pub fn pair_mode_by_mac(levels: &[Option<LevelModes>], mode: usize) -> Vec<Option<(usize, f64)>> {
    let Some(finest) = levels.iter().rev().flatten().next() else {
        return vec![None; levels.len()];
    };
    let coarsest = levels.iter().flatten().min_by_key(|l| l.points.len()).unwrap_or(finest);
    let Some(target) = finest.shapes.get(mode) else {
        return vec![None; levels.len()];
    };
    let target = sample(target, &nearest(&coarsest.points, &finest.points));
    levels
        .iter()
        .map(|l| {
            let l = l.as_ref()?;
            let at = nearest(&coarsest.points, &l.points);
            l.shapes
                .iter()
                .enumerate()
                .map(|(i, s)| (i, mac(&sample(s, &at), &target)))
                .max_by(|a, b| a.1.total_cmp(&b.1))
        })
        .collect()
}

/// A finished convergence study.
#[derive(Clone, Debug, Serialize)]
pub struct Convergence {
    /// Case name.
    pub name: String,
    /// Quantity measured.
    pub quantity: String,
    /// Unit.
    pub unit: String,
    /// Reference value.
    pub reference: f64,
    /// How the reference was obtained.
    pub reference_kind: String,
    /// One row per run.
    pub rows: Vec<LevelResult>,
    /// Per tolerance (0.01, 0.001, 0.0001): index into `rows` of the cheapest run within it.
    pub cheapest: Vec<(f64, Option<usize>)>,
}

/// A built-in case's scene: its body (parts, supports, loads, analysis) on a generated mesh.
fn builtin_scene(name: &str, mesh: &str, body: &str) -> Result<Runner> {
    let text = format!("[scene]\nversion = 1\nname = \"{name}\"\n\n[mesh]\ngenerator = \"{mesh}\"\n\n{body}");
    Ok(Runner::Scene(Box::new(Scene::parse(
        Path::new("converge.toml"),
        &text,
    )?)))
}

const S1_SOLID: &str = "[[part]]\ngroup = \"volume\"\nformulation = \"solid\"\n\n[modal]\nmodes = 7\n";
const S1_SHELL: &str = "[[part]]\ngroup = \"zmin\"\nformulation = \"shell\"\nthickness = 0.02\noffset = 0.01\n\n\
                        [modal]\nmodes = 7\n";
const S3_BODY: &str = "[[part]]\ngroup = \"volume\"\nformulation = \"solid\"\n\n[[fix]]\ngroup = \"xmin\"\n\
                       dofs = [\"ux\", \"uy\", \"uz\"]\n\n[[couple]]\ngroup = \"xmax\"\nguided = \"z\"\n\n[[load]]\n\
                       group = \"xmax\"\nforce = [0.0, 0.0, 1000.0]\n";
const S5_BODY: &str = "[[material]]\nname = \"spring steel\"\nyoung = 2.002e11\npoisson = 0.3\ndensity = 7850.0\n\n\
                       [[part]]\ngroup = \"wire\"\nformulation = \"beam\"\nsection = \"circle:0.006\"\n\
                       orientation = \"radial:0,0,0,0,0,1\"\n\n[[fix]]\ngroup = \"end_bottom\"\ndofs = [\"all\"]\n\n\
                       [[couple]]\ngroup = \"end_top\"\nguided = \"z\"\n\n[[load]]\ngroup = \"end_top\"\n\
                       force = [0.0, 0.0, -600.0]\n";

/// Box levels of a built-in case: per formulation (its name, cell kind and the divisions of
/// each level, coarse to fine), the scene `body` on a `box:` of `size`.
fn box_levels(
    name: &str,
    size: [f64; 3],
    body: &str,
    forms: &[(&str, CellKind, &[[usize; 3]])],
) -> Result<Vec<LevelSpec>> {
    let mut levels = Vec::new();
    for &(form, kind, divs) in forms {
        for &d in divs {
            let spec = BoxSpec {
                size,
                divisions: d,
                kind,
            };
            levels.push(LevelSpec {
                formulation: form.to_string(),
                mesh: format!("{}×{}×{}", d[0], d[1], d[2]),
                runner: builtin_scene(name, &spec.to_string(), body)?,
            });
        }
    }
    Ok(levels)
}

/// A case measuring the first elastic frequency (Hz).
fn frequency_case(name: &str, levels: Vec<LevelSpec>, reference: &str, known: Option<(f64, &str)>) -> Case {
    Case {
        name: name.into(),
        quantity: "first elastic frequency".into(),
        unit: "Hz".into(),
        levels,
        reference: reference.into(),
        known: known.map(|(v, s)| (v, s.to_string())),
    }
}

/// A case measuring a stiffness (N/m).
fn stiffness_case(name: &str, levels: Vec<LevelSpec>, reference: &str) -> Case {
    Case {
        name: name.into(),
        quantity: "stiffness".into(),
        unit: "N/m".into(),
        levels,
        reference: reference.into(),
        known: None,
    }
}

/// The built-in cases: `s1`, `s3`, `s5`, `s7`, and `tiny` (a fast S1 variant for tests).
pub fn builtin(name: &str) -> Result<Case> {
    use CellKind::{Hex8, Hex20, Line2, Line3, Tet4, Tet10};
    let s1 = [0.3, 0.3, 0.02];
    match name {
        "s1" => {
            let levels = box_levels(
                name,
                s1,
                S1_SOLID,
                &[
                    ("tet4", Tet4, &[[6, 6, 1], [12, 12, 2], [24, 24, 4]]),
                    ("tet10", Tet10, &[[4, 4, 1], [8, 8, 2], [16, 16, 4]]),
                    ("hex8", Hex8, &[[6, 6, 1], [12, 12, 2], [24, 24, 4]]),
                    ("hex20", Hex20, &[[4, 4, 1], [8, 8, 2], [16, 16, 4]]),
                ],
            )?
            .into_iter()
            .chain(box_levels(
                name,
                s1,
                S1_SHELL,
                &[("shell", Hex8, &[[10, 10, 1], [20, 20, 1], [40, 40, 1]])],
            )?)
            .collect();
            Ok(frequency_case(
                "S1 free plate 300 × 300 × 20 mm",
                levels,
                "hex20",
                Some((720.432, "hex20 45×45×9, 244 812 DOFs, README")),
            ))
        }
        "tiny" => {
            let levels = box_levels(
                name,
                s1,
                S1_SOLID,
                &[("hex20", Hex20, &[[2, 2, 1], [4, 4, 1], [8, 8, 1]])],
            )?
            .into_iter()
            .chain(box_levels(
                name,
                s1,
                S1_SHELL,
                &[("shell", Hex8, &[[8, 8, 1], [16, 16, 1]])],
            )?)
            .collect();
            Ok(frequency_case("tiny S1 plate", levels, "hex20", None))
        }
        "s3" => {
            let levels = box_levels(
                name,
                [0.169, 0.146, 0.009],
                S3_BODY,
                &[
                    ("tet4", Tet4, &[[8, 6, 1], [16, 12, 2], [32, 24, 4]]),
                    ("tet10", Tet10, &[[4, 3, 1], [8, 6, 2], [16, 12, 4]]),
                    ("hex8", Hex8, &[[8, 6, 1], [16, 12, 2], [32, 24, 4]]),
                    ("hex20", Hex20, &[[4, 3, 1], [8, 6, 2], [16, 12, 4]]),
                ],
            )?;
            Ok(stiffness_case("S3 leaf spring 169 × 146 × 9 mm", levels, "hex20"))
        }
        "s5" => {
            let mut levels = Vec::new();
            for (kind, per_turn) in [(Line2, [6, 12, 24, 48, 96]), (Line3, [3, 6, 12, 24, 48])] {
                for n in per_turn {
                    let spec = HelixSpec {
                        diameter: 0.032,
                        pitch: 0.01,
                        turns: 6.0,
                        per_turn: n,
                        kind: Some(kind),
                    };
                    levels.push(LevelSpec {
                        formulation: kind.name().to_string(),
                        mesh: format!("{n}/turn"),
                        runner: builtin_scene(name, &spec.to_string(), S5_BODY)?,
                    });
                }
            }
            Ok(stiffness_case("S5 coil, beam helix", levels, "line3"))
        }
        "s7" => {
            let level = |form: &str, h: f64, runner: Runner| LevelSpec {
                formulation: form.into(),
                mesh: format!("{} mm", h * 1e3),
                runner,
            };
            let sizes = [0.1, 0.05, 0.025];
            let levels = (sizes.iter().map(|&h| level("shell", h, Runner::TableShell(h))))
                .chain(sizes.iter().map(|&h| level("hex20", h, Runner::TableSolid(h))))
                .collect();
            Ok(frequency_case(
                "S7 sandwich table (reconstruction)",
                levels,
                "hex20",
                Some((164.5, "graded hex20 50/12.5/6.25 mm, 69 177 DOFs, docs/formulations.md")),
            ))
        }
        _ => Err(Error::param(
            "case",
            format!("converge: unknown case '{name}' (s1, s3, s5, s7, tiny, or a scene file)"),
        )),
    }
}

/// Most refinement levels of a scene study.
pub const MAX_LEVELS: usize = 6;

/// A mesh generator a scene study can refine: the source grammar's specs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Refinable {
    /// `box:`: divisions doubled per level (a single hex8 layer through the thickness stays one
    /// when the box carries shells on its faces).
    Box(BoxSpec),
    /// `helix:`: elements per turn doubled per level.
    Helix(HelixSpec),
    /// `sandwich:paper[,SIZE]`: element size halved per level (default size 0.025).
    Sandwich(SandwichSpec),
}

impl Refinable {
    /// The generator of `spec`, if it is one that can be refined (`None`: another generator
    /// or a malformed spec).
    pub fn parse(spec: &str) -> Option<Refinable> {
        if let Ok(Some(b)) = BoxSpec::parse(spec) {
            return Some(Refinable::Box(b));
        }
        if let Ok(Some(h)) = HelixSpec::parse(spec) {
            return Some(Refinable::Helix(h));
        }
        match SandwichSpec::parse(spec) {
            Ok(Some(s)) => Some(Refinable::Sandwich(s)),
            _ => None,
        }
    }

    /// The generator spec of refinement level `k` (0: as given, each level halves the element
    /// size). `shells`: the mesh carries shell parts, so a one-cell-thick hex8 box is a surface
    /// to mesh on and keeps its one layer (a solid box is refined through its thickness too: a
    /// solid plate of one hex8 layer kept one and converged to a locked +1.4 %).
    pub fn level(&self, k: u32, shells: bool) -> String {
        let f = 1usize << k;
        match *self {
            Refinable::Box(mut b) => {
                let [nx, ny, nz] = b.divisions;
                let nz = if shells && nz == 1 && b.kind == CellKind::Hex8 {
                    1
                } else {
                    nz * f
                };
                b.divisions = [nx * f, ny * f, nz];
                b.to_string()
            }
            Refinable::Helix(mut h) => {
                h.per_turn *= f;
                h.to_string()
            }
            Refinable::Sandwich(s) => SandwichSpec {
                elem_size: Some(s.elem_size.unwrap_or(0.025) / f as f64),
            }
            .to_string(),
        }
    }
}

/// A scene refined `levels` times by halving its element size: `box:` divisions doubled,
/// `helix:` elements per turn doubled, `sandwich:paper,SIZE` size halved ([`Refinable`]). One
/// formulation (the scene's); the reference is its own finest levels.
pub fn from_scene(path: &Path, levels: usize) -> Result<Case> {
    if levels < 2 {
        return Err(Error::option(
            "--levels",
            format!(
                "converge: --levels {levels}: at least 2 (the finest level is the reference; with one level there is \
                 nothing to measure against it)"
            ),
        ));
    }
    if levels > MAX_LEVELS {
        return Err(Error::option(
            "--levels",
            format!(
                "converge: --levels {levels}: at most {MAX_LEVELS} (each level halves the element size, so a 3D mesh \
                 grows 8× per level; level {MAX_LEVELS} already has 32 768× the cells of the first)"
            ),
        ));
    }
    let text = toml_file::read(path)?;
    let scene = Scene::parse(path, &text)?;
    let refinable = match &scene.mesh {
        MeshSource::Generator(g) => Refinable::parse(g).ok_or_else(|| {
            toml_file::key_error(
                path,
                &text,
                "mesh.generator",
                format!("converge: cannot refine generator '{g}'"),
            )
        })?,
        _ => {
            let at = toml_file::line_of_table_key(&text, "mesh", 0, "file");
            return Err(Error::key(
                path.display().to_string(),
                at.key.or(at.header),
                "mesh",
                "converge: only scenes with a box:, helix: or sandwich:paper generator can be refined",
            ));
        }
    };
    let form = scene
        .parts
        .first()
        .map(|(_, f)| format!("{f:?}").to_lowercase())
        .unwrap_or_else(|| "model".into());
    let levels = (0..levels as u32)
        .map(|k| {
            let spec = refinable.level(k, !scene.spec.shells.is_empty());
            let mut s = scene.clone();
            s.mesh = MeshSource::Generator(spec.clone());
            LevelSpec {
                formulation: form.clone(),
                mesh: spec,
                runner: Runner::Scene(Box::new(s)),
            }
        })
        .collect();
    let quantity = if scene.modal.is_some() {
        ("first elastic frequency", "Hz")
    } else {
        ("stiffness", "N/m")
    };
    Ok(Case {
        name: scene.name.clone(),
        quantity: quantity.0.into(),
        unit: quantity.1.into(),
        levels,
        reference: form,
        known: None,
    })
}

/// Reset the kernel's peak-RSS counter of this process (Linux ≥ 4.0), so that the next reading
/// is the peak of the next run.
fn reset_peak_memory() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Run one level: (value, dofs, wall time, peak memory).
pub fn run_level(l: &LevelSpec) -> Result<(f64, usize, f64, Option<u64>)> {
    run_level_modes(l).map(|(v, d, t, m, _)| (v, d, t, m))
}

/// [`run_level`] with the level's elastic modes (scenes with a modal analysis, which then
/// compute [`PAIRING_EXTRA`] more modes than asked).
pub fn run_level_modes(l: &LevelSpec) -> Result<(f64, usize, f64, Option<u64>, Option<LevelModes>)> {
    let reset = reset_peak_memory();
    let t = Instant::now();
    let mut modes = None;
    let (value, dofs) = match &l.runner {
        Runner::Scene(scene) => {
            let mut scene = (**scene).clone();
            if let Some((ModalTarget::Modes(n), None, _)) = &mut scene.modal {
                *n += PAIRING_EXTRA;
            }
            let r = scene.run(None)?;
            if let (Some(m), Some(s)) = (&r.modal, &r.mode_shapes) {
                let elastic: Vec<usize> = (0..m.modes.len()).filter(|&i| m.modes[i].kind == "elastic").collect();
                modes = Some(LevelModes {
                    points: s.points.clone(),
                    freqs: elastic.iter().map(|&i| m.modes[i].frequency_hz).collect(),
                    shapes: elastic.iter().filter_map(|&i| s.shapes.get(i).cloned()).collect(),
                });
            }
            if let Some(m) = &r.modal {
                if !(m.complete && m.accurate) {
                    return Err(Error::Verification(format!("{}: modal check failed", l.mesh)));
                }
                let f = m
                    .elastic_frequencies()
                    .first()
                    .copied()
                    .ok_or_else(|| Error::Verification(format!("{}: no elastic mode", l.mesh)))?;
                (f, m.dofs)
            } else {
                let k = r
                    .stiffness()
                    .ok_or_else(|| Error::param("case", format!("{}: the scene gives no stiffness", l.mesh)))?;
                (k, r.statics.as_ref().map(|s| s.dofs).unwrap_or(0))
            }
        }
        Runner::TableShell(h) | Runner::TableSolid(h) => {
            let mut p = SandwichParams::paper();
            let solid = matches!(l.runner, Runner::TableSolid(_));
            if !solid {
                p.elem_size = *h;
            }
            let (r, run, mesh) = super::sweep::analyse_modes(
                &p,
                crate::material::Material::steel(),
                solid.then_some(*h),
                10 + PAIRING_EXTRA,
            )?;
            let elastic: Vec<usize> = (0..run.report.modes.len())
                .filter(|&i| run.report.modes[i].kind == "elastic")
                .collect();
            modes = Some(LevelModes {
                points: mesh.nodes.clone(),
                freqs: elastic.iter().map(|&i| run.report.modes[i].frequency_hz).collect(),
                shapes: elastic.iter().filter_map(|&i| run.shapes.get(i).cloned()).collect(),
            });
            (r.f1_hz, r.dofs)
        }
    };
    let time = t.elapsed().as_secs_f64();
    let mem = if reset {
        crate::analysis::modal::peak_memory()
    } else {
        None
    };
    Ok((value, dofs, time, mem, modes))
}

/// Richardson extrapolation of three values at h, h/2, h/4: `Some((limit, order))` when the
/// differences shrink monotonically at an observed order of at least 1.5 (a lower order means the
/// levels are not in the asymptotic range, and the extrapolation is not trusted).
pub fn richardson(v: [f64; 3]) -> Option<(f64, f64)> {
    let (d1, d2) = (v[1] - v[0], v[2] - v[1]);
    if d1 * d2 <= 0.0 || d2.abs() * 2f64.powf(1.5) > d1.abs() {
        return None;
    }
    let q = d1 / d2;
    Some((v[2] + d2 / (q - 1.0), q.log2()))
}

/// Run every level of a case (`progress` gets one line per run), estimate the errors and pick the
/// cheapest runs within 1 %, 0.1 % and 0.01 %.
pub fn run_case(case: &Case, progress: &dyn Fn(&str)) -> Result<Convergence> {
    let mut raw = Vec::new();
    let mut level_modes = Vec::new();
    for l in &case.levels {
        let (value, dofs, time_s, mem, modes) =
            run_level_modes(l).map_err(|e| e.with_prefix(&format!("{} {}", l.formulation, l.mesh)))?;
        level_modes.push(modes);
        progress(&format!(
            "{} {}: {value:.6e} {} ({dofs} DOFs, {time_s:.2} s)",
            l.formulation, l.mesh, case.unit
        ));
        raw.push(LevelResult {
            formulation: l.formulation.clone(),
            mesh: l.mesh.clone(),
            value,
            error: 0.0,
            dofs,
            time_s,
            peak_memory_bytes: mem,
            paired: None,
        });
    }
    // Pair modes across the levels of each formulation by MAC (modes reorder with refinement:
    // in-plane and bending modes swap), and track the pair's frequency.
    let mut forms: Vec<&str> = raw.iter().map(|r| r.formulation.as_str()).collect();
    forms.dedup();
    let forms: Vec<String> = forms.into_iter().map(str::to_string).collect();
    for f in forms {
        let idx: Vec<usize> = (0..raw.len()).filter(|&i| raw[i].formulation == f).collect();
        let lm: Vec<Option<LevelModes>> = idx.iter().map(|&i| level_modes[i].clone()).collect();
        for (&i, p) in idx.iter().zip(pair_by_mac(&lm)) {
            if let (Some((k, m)), Some(l)) = (p, &level_modes[i]) {
                if k > 0 {
                    raw[i].value = l.freqs[k];
                    raw[i].paired = Some((k + 1, m));
                }
            }
        }
    }
    let refs: Vec<f64> = raw
        .iter()
        .filter(|r| r.formulation == case.reference)
        .map(|r| r.value)
        .collect();
    let finest = *refs.last().ok_or_else(|| {
        Error::param(
            "case",
            format!("converge: no run of the reference formulation '{}'", case.reference),
        )
    })?;
    let (reference, kind, finest_is_ref) = match (&case.known, refs.len()) {
        (Some((v, src)), _) => (*v, format!("documented converged value ({src})"), false),
        (None, n) if n >= 3 => match richardson([refs[n - 3], refs[n - 2], refs[n - 1]]) {
            Some((v, p)) => (
                v,
                format!(
                    "Richardson extrapolation of the last three {} levels (order {p:.2})",
                    case.reference
                ),
                false,
            ),
            None => (
                finest,
                format!(
                    "finest {} level (its levels are not in the asymptotic range)",
                    case.reference
                ),
                true,
            ),
        },
        _ => (finest, format!("finest {} level", case.reference), true),
    };
    let ref_idx = raw.iter().rposition(|r| r.formulation == case.reference);
    for r in raw.iter_mut() {
        r.error = (r.value - reference) / reference;
    }
    let cheapest = [1e-2, 1e-3, 1e-4]
        .iter()
        .map(|&tol| {
            let best = raw
                .iter()
                .enumerate()
                .filter(|(i, r)| r.error.abs() <= tol && !(finest_is_ref && Some(*i) == ref_idx))
                .min_by(|a, b| a.1.time_s.total_cmp(&b.1.time_s))
                .map(|(i, _)| i);
            (tol, best)
        })
        .collect();
    Ok(Convergence {
        name: case.name.clone(),
        quantity: case.quantity.clone(),
        unit: case.unit.clone(),
        reference,
        reference_kind: kind,
        rows: raw,
        cheapest,
    })
}

fn pct(tol: f64) -> String {
    format!("{} %", tol * 100.0)
}

/// The study as a markdown table plus the cheapest formulation per tolerance.
pub fn table_markdown(c: &Convergence) -> String {
    let mut s = format!(
        "{}: {} [{}]; reference {:.6e} ({})\n\n",
        c.name, c.quantity, c.unit, c.reference, c.reference_kind
    );
    s.push_str("| formulation | mesh | DOFs | value | error | time [s] | peak memory [MiB] |\n");
    s.push_str("|---|---|---:|---:|---:|---:|---:|\n");
    for r in &c.rows {
        s.push_str(&format!(
            "| {} | {} | {} | {:.6e} | {:+.3} % | {:.4} | {} |\n",
            r.formulation,
            r.mesh,
            r.dofs,
            r.value,
            r.error * 100.0,
            r.time_s,
            r.peak_memory_bytes
                .map(|b| format!("{:.0}", b as f64 / 1048576.0))
                .unwrap_or_else(|| "–".into())
        ));
    }
    s.push('\n');
    for r in c.rows.iter().filter(|r| r.paired.is_some()) {
        let (k, m) = r.paired.unwrap_or_default();
        s.push_str(&format!(
            "- {} {}: the value is elastic mode {k}, paired by MAC ({m:.3}) with the finest level's first \
             elastic mode (the modes reorder with refinement)\n",
            r.formulation, r.mesh
        ));
    }
    for (tol, i) in &c.cheapest {
        match i {
            Some(i) => {
                let r = &c.rows[*i];
                s.push_str(&format!(
                    "- cheapest within {}: {} {} ({:+.3} %, {:.3} s, {} DOFs)\n",
                    pct(*tol),
                    r.formulation,
                    r.mesh,
                    r.error * 100.0,
                    r.time_s,
                    r.dofs
                ));
            }
            // The finest level, when it is the reference itself, is not a candidate.
            None if c.reference_kind.starts_with("finest") => s.push_str(&format!(
                "- cheapest within {}: none of the coarser levels (the finest is the reference; refine further to \
                 find one)\n",
                pct(*tol)
            )),
            None => s.push_str(&format!("- cheapest within {}: none of the runs\n", pct(*tol))),
        }
    }
    s
}

/// The cheapest formulation within `tol` (0.01 = 1 %), if any.
pub fn cheapest_within(c: &Convergence, tol: f64) -> Option<&LevelResult> {
    c.cheapest
        .iter()
        .find(|(t, _)| (*t - tol).abs() < 1e-12)
        .and_then(|(_, i)| i.map(|i| &c.rows[i]))
}

/// Write `converge.md`, `converge.json` and `converge.svg` (|error| against time, log–log, one
/// line per formulation) to `dir` (created).
pub fn write_outputs(c: &Convergence, dir: &Path) -> Result<()> {
    crate::io::create_dir(dir)?;
    let p = dir.join("converge.md");
    std::fs::write(&p, table_markdown(c)).map_err(|e| Error::io(&p, e))?;
    let p = dir.join("converge.json");
    let text = serde_json::to_string_pretty(c).map_err(|e| Error::output("JSON", e))?;
    std::fs::write(&p, text).map_err(|e| Error::io(&p, e))?;
    write_svg(c, &dir.join("converge.svg"))
}

fn write_svg(c: &Convergence, path: &Path) -> Result<()> {
    use plotters::prelude::*;
    let perr = |e: &dyn std::fmt::Display| Error::io(path, std::io::Error::other(format!("plotting failed: {e}")));
    let pts: Vec<(f64, f64)> = c
        .rows
        .iter()
        .map(|r| (r.time_s.max(1e-4), r.error.abs()))
        .filter(|p| p.1 > 0.0 && p.1.is_finite())
        .collect();
    let (tx0, tx1) = pts
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (ey0, ey1) = pts
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let (tx0, tx1) = if pts.is_empty() {
        (1e-3, 1.0)
    } else {
        (tx0 / 2.0, tx1 * 2.0)
    };
    let (ey0, ey1) = if pts.is_empty() {
        (1e-6, 1.0)
    } else {
        ((ey0 / 3.0).min(5e-5), (ey1 * 3.0).max(2e-2))
    };
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| perr(&e))?;
    let mut ch = ChartBuilder::on(&root)
        .caption(format!("{}: error against wall time", c.name), ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((tx0..tx1).log_scale(), (ey0..ey1).log_scale())
        .map_err(|e| perr(&e))?;
    ch.configure_mesh()
        .x_desc("wall time, s")
        .y_desc(format!("|relative error| of the {}", c.quantity))
        .draw()
        .map_err(|e| perr(&e))?;
    let mut forms: Vec<&str> = Vec::new();
    for r in &c.rows {
        if !forms.contains(&r.formulation.as_str()) {
            forms.push(&r.formulation);
        }
    }
    for (k, f) in forms.iter().enumerate() {
        let col = Palette99::pick(k).to_rgba();
        let line: Vec<(f64, f64)> = c
            .rows
            .iter()
            .filter(|r| r.formulation == *f && r.error != 0.0 && r.error.is_finite())
            .map(|r| (r.time_s.max(1e-4), r.error.abs()))
            .collect();
        ch.draw_series(LineSeries::new(line.clone(), col.stroke_width(2)))
            .map_err(|e| perr(&e))?
            .label(f.to_string())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2)));
        ch.draw_series(line.iter().map(|&p| Circle::new(p, 4, col.filled())))
            .map_err(|e| perr(&e))?;
    }
    for tol in [1e-2, 1e-3, 1e-4] {
        ch.draw_series(DashedLineSeries::new(
            [(tx0, tol), (tx1, tol)],
            5,
            5,
            RGBColor(160, 160, 160).stroke_width(1),
        ))
        .map_err(|e| perr(&e))?;
    }
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| perr(&e))?;
    root.present().map_err(|e| perr(&e))?;
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Studies on the user's own part: a gmsh geometry meshed at several sizes and orders, or a set
// of meshes the user made.
// ---------------------------------------------------------------------------------------------

/// Where the levels of a study on the user's part come from.
#[derive(Clone, Debug)]
pub enum UserLevels {
    /// A gmsh geometry meshed by `gmsh` at each size (the geometry's units) and order, into
    /// `work`, each within `timeout`.
    Geo {
        /// The `.geo` file.
        geo: PathBuf,
        /// Element sizes (Mesh.MeshSizeMax), geometry units.
        sizes: Vec<f64>,
        /// Element orders (1: tet4/hex8, 2: tet10/hex20).
        orders: Vec<usize>,
        /// How gmsh runs.
        gmsh: Gmsh,
        /// Time limit of one mesh generation.
        timeout: Duration,
        /// Folder for the meshes.
        work: PathBuf,
    },
    /// Meshes of one part made by the user (their sizes: the mean edge length).
    Meshes(Vec<PathBuf>),
}

/// A speed–accuracy study on the user's part.
#[derive(Clone, Debug)]
pub struct UserStudy {
    /// Name (the geometry's or the pattern's).
    pub name: String,
    /// The levels.
    pub levels: UserLevels,
    /// The model built on every level.
    pub spec: ModelSpec,
    /// Loads of one static case; with them the study measures a stiffness (or, without a guided
    /// coupling, the largest displacement).
    pub loads: Option<Vec<Load>>,
    /// Metres per mesh unit.
    pub length_scale: f64,
    /// Name of the mesh unit (for sizes).
    pub length_unit: String,
    /// Elastic frequencies measured (the lowest ones).
    pub frequencies: usize,
    /// Relative tolerance of the cheapest run.
    pub tolerance: f64,
}

/// One level of a study on the user's part.
#[derive(Clone, Debug, Serialize)]
pub struct UserRow {
    /// Formulation: the volume cell kind(s) of the mesh (`tet10`, `hex20`, `hex8+wedge6`).
    pub formulation: String,
    /// Element size asked of gmsh (geometry units), or the mean edge length of a user's mesh.
    pub size: f64,
    /// Mean edge length of the volume cells (corner to corner, geometry units): the h of the
    /// extrapolation.
    pub mean_edge: f64,
    /// The mesh file.
    pub mesh: String,
    /// Free DOFs (of the modal model; of the static model without frequencies).
    pub dofs: usize,
    /// Mesh generation wall time (s), for meshes made here.
    pub mesh_time_s: Option<f64>,
    /// Analysis wall time (s): reading the mesh, model, solution(s).
    pub time_s: f64,
    /// Peak resident memory of the analysis (bytes), where the OS reports it.
    pub peak_memory_bytes: Option<u64>,
    /// Value per quantity.
    pub values: Vec<f64>,
    /// Relative error per quantity against its best estimate.
    pub errors: Vec<f64>,
    /// Per frequency quantity: the elastic mode (1-based) of this level paired by MAC with the
    /// finest level's, and the MAC, where it is not the same index.
    pub paired: Vec<Option<(usize, f64)>>,
}

/// The Richardson extrapolation of one formulation's levels for one quantity.
#[derive(Clone, Debug, Serialize)]
pub struct Fit {
    /// Formulation.
    pub formulation: String,
    /// Levels of this formulation.
    pub levels: usize,
    /// Value of its finest level.
    pub finest: f64,
    /// Richardson-extrapolated value from its three finest levels.
    pub extrapolated: Option<f64>,
    /// Observed order of convergence p (error ∝ hᵖ).
    pub order: Option<f64>,
    /// Estimated relative error of the finest level: |finest − extrapolated| / |extrapolated|.
    pub error_estimate: Option<f64>,
}

/// One quantity of a study on the user's part.
#[derive(Clone, Debug, Serialize)]
pub struct UserQuantity {
    /// Name (`elastic frequency 1`, `stiffness`, `largest displacement`).
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Per formulation.
    pub fits: Vec<Fit>,
    /// Best estimate of the converged value: the extrapolation with the smallest error estimate.
    pub estimate: f64,
    /// Which formulation's extrapolation it is.
    pub estimate_from: String,
    /// Index into the rows of the cheapest (analysis time) within the tolerance.
    pub cheapest: Option<usize>,
}

/// A finished study on the user's part.
#[derive(Clone, Debug, Serialize)]
pub struct UserConvergence {
    /// Name.
    pub name: String,
    /// Relative tolerance.
    pub tolerance: f64,
    /// Unit of the sizes.
    pub length_unit: String,
    /// The levels that ran, by formulation, coarse to fine.
    pub rows: Vec<UserRow>,
    /// Per quantity.
    pub quantities: Vec<UserQuantity>,
    /// Index into the rows of the cheapest within the tolerance for every quantity.
    pub cheapest: Option<usize>,
    /// Levels that could not be meshed, with the reason.
    pub failed: Vec<String>,
}

/// Corner edges of the volume cells (gmsh node order).
fn corner_edges(kind: CellKind) -> &'static [[usize; 2]] {
    match kind.linear() {
        CellKind::Tet4 => &[[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]],
        CellKind::Hex8 => &[
            [0, 1],
            [1, 2],
            [2, 3],
            [3, 0],
            [4, 5],
            [5, 6],
            [6, 7],
            [7, 4],
            [0, 4],
            [1, 5],
            [2, 6],
            [3, 7],
        ],
        CellKind::Wedge6 => &[[0, 1], [1, 2], [2, 0], [3, 4], [4, 5], [5, 3], [0, 3], [1, 4], [2, 5]],
        _ => &[],
    }
}

/// Mean corner-to-corner edge length of the volume cells (each cell's edges counted once per
/// cell), in the mesh's coordinates; `None` without volume cells.
pub fn mean_edge_length(mesh: &Mesh) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for b in mesh.blocks.iter().filter(|b| b.kind.dim() == 3) {
        let edges = corner_edges(b.kind);
        for c in 0..b.len() {
            let cell = b.cell(c);
            for e in edges {
                let (p, q) = (mesh.nodes[cell[e[0]] as usize], mesh.nodes[cell[e[1]] as usize]);
                sum += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
                n += 1;
            }
        }
    }
    (n > 0).then(|| sum / n as f64)
}

/// The formulation of a mesh: its volume cell kinds joined by `+`; `None` without volume cells.
pub fn volume_formulation(mesh: &Mesh) -> Option<String> {
    let kinds: Vec<&str> = mesh
        .blocks
        .iter()
        .filter(|b| b.kind.dim() == 3 && !b.is_empty())
        .map(|b| b.kind.name())
        .collect();
    (!kinds.is_empty()).then(|| kinds.join("+"))
}

/// Richardson extrapolation of three levels at sizes `h` (decreasing) with values `v`, for any
/// size ratios: the order p solves (v₁ − v₀)/(v₂ − v₁) = (h₀ᵖ − h₁ᵖ)/(h₁ᵖ − h₂ᵖ) (bisection,
/// 0.05 ≤ p ≤ 20), and v = v∞ + C hᵖ through the two finest levels gives v∞. `None` when the
/// differences do not shrink monotonically, or the order is outside that range.
pub fn richardson_sizes(h: [f64; 3], v: [f64; 3]) -> Option<(f64, f64)> {
    let (d1, d2) = (v[1] - v[0], v[2] - v[1]);
    if !(h[0] > h[1] && h[1] > h[2] && h[2] > 0.0) || d1 * d2 <= 0.0 || d2.abs() >= d1.abs() {
        return None;
    }
    let q = d1 / d2;
    let g = |p: f64| (h[0].powf(p) - h[1].powf(p)) / (h[1].powf(p) - h[2].powf(p));
    let (mut lo, mut hi) = (0.05, 20.0);
    if !(g(lo) <= q && q <= g(hi)) {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < q {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let p = 0.5 * (lo + hi);
    let c = d2 / (h[2].powf(p) - h[1].powf(p));
    Some((v[2] - c * h[2].powf(p), p))
}

/// Refuse levels that do not converge monotonically: the successive changes of the value must
/// keep their sign and shrink. `levels`: (size label, value), coarse to fine.
pub fn check_monotone(formulation: &str, quantity: &str, unit: &str, levels: &[(String, f64)]) -> Result<()> {
    for i in 2..levels.len() {
        let d1 = levels[i - 1].1 - levels[i - 2].1;
        let d2 = levels[i].1 - levels[i - 1].1;
        if d1 * d2 <= 0.0 || d2.abs() >= d1.abs() {
            let all: Vec<String> = levels.iter().map(|(s, v)| format!("{s}: {v:.6e}")).collect();
            return Err(Error::Verification(format!(
                "converge: {formulation}, {quantity} [{unit}]: the levels do not converge monotonically at {} (change \
                 {d2:+.4e} after {d1:+.4e}; the changes must keep their sign and shrink); levels {}. No \
                 extrapolation is trusted: use smaller sizes (or drop the coarsest), or check the mesh",
                levels[i].0,
                all.join(", ")
            )));
        }
    }
    Ok(())
}

/// A mesh of the study, before its analysis.
struct Pending {
    /// Size asked of gmsh (`None`: a user's mesh).
    size: Option<f64>,
    path: PathBuf,
    mesh_time: Option<f64>,
    /// gmsh's warnings, shown if the mesh turns out unusable.
    warnings: String,
    /// How messages name the level (`size 20 (order 2)`, the file name).
    label: String,
}

/// Mesh every (order, size) of a geometry (or list a user's meshes): the meshes made, and the
/// levels that failed, each naming its size and carrying gmsh's message.
fn mesh_levels(levels: &UserLevels, progress: &dyn Fn(&str)) -> Result<(Vec<Pending>, Vec<String>)> {
    let (geo, sizes, orders, gmsh, timeout, work) = match levels {
        UserLevels::Meshes(paths) => {
            let p = paths
                .iter()
                .map(|p| Pending {
                    size: None,
                    path: p.clone(),
                    mesh_time: None,
                    warnings: String::new(),
                    label: p.display().to_string(),
                })
                .collect();
            return Ok((p, Vec::new()));
        }
        UserLevels::Geo {
            geo,
            sizes,
            orders,
            gmsh,
            timeout,
            work,
        } => (geo, sizes, orders, gmsh, timeout, work),
    };
    crate::io::create_dir(work)?;
    let stem = geo
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (mut made, mut failed) = (Vec::new(), Vec::new());
    for &order in orders {
        for &size in sizes {
            let label = format!("size {size} (order {order})");
            let path = work.join(format!("{stem}_o{order}_h{}.msh", format!("{size}").replace('.', "p")));
            progress(&format!(
                "meshing {} at {label} with the {}",
                geo.display(),
                gmsh.describe()
            ));
            let t = Instant::now();
            match gmsh.mesh(geo, size, order, &path, *timeout) {
                Ok(warnings) => made.push(Pending {
                    size: Some(size),
                    path,
                    mesh_time: Some(t.elapsed().as_secs_f64()),
                    warnings,
                    label,
                }),
                Err(e) => {
                    progress(&format!("error: {label}: {e}"));
                    failed.push(format!("{label}: {e}"));
                }
            }
        }
    }
    Ok((made, failed))
}

/// What one level's analysis gives: elastic frequencies (with shapes for pairing), the static
/// quantity (value, and whether it is a stiffness), the DOFs.
struct LevelOutcome {
    freqs: Vec<f64>,
    modes: Option<LevelModes>,
    statics: Option<(f64, bool)>,
    dofs: usize,
}

/// Analyse one mesh of the study: the modal run (if frequencies are measured: the lowest
/// 6 + N + [`PAIRING_EXTRA`] modes, verified) and the static case (if loads are given).
fn analyse_user_level(study: &UserStudy, mesh: &Mesh, source: &str) -> Result<LevelOutcome> {
    use crate::analysis::modal::ModalOptions;
    let mut out = LevelOutcome {
        freqs: Vec::new(),
        modes: None,
        statics: None,
        dofs: 0,
    };
    if study.frequencies > 0 {
        let opts = ModalOptions {
            spec: study.spec.clone(),
            target: ModalTarget::Modes(6 + study.frequencies + PAIRING_EXTRA),
            ..Default::default()
        };
        let run = crate::app::engines::Engine::Native.solve_mesh(mesh, source, &opts, 0.0)?;
        let r = &run.report;
        if !(r.complete && r.accurate) {
            return Err(Error::Verification(format!(
                "{source}: the modal solution failed its Sturm-sequence or residual check"
            )));
        }
        let elastic: Vec<usize> = (0..r.modes.len()).filter(|&i| r.modes[i].kind == "elastic").collect();
        out.freqs = elastic.iter().map(|&i| r.modes[i].frequency_hz).collect();
        if out.freqs.len() < study.frequencies {
            return Err(Error::Verification(format!(
                "{source}: {} elastic modes found, {} asked (--frequencies)",
                out.freqs.len(),
                study.frequencies
            )));
        }
        out.modes = Some(LevelModes {
            points: mesh.nodes.clone(),
            freqs: out.freqs.clone(),
            shapes: elastic.iter().filter_map(|&i| run.shapes.get(i).cloned()).collect(),
        });
        out.dofs = r.dofs;
    }
    if let Some(loads) = &study.loads {
        let opts = crate::analysis::statics::StaticOptions {
            spec: study.spec.clone(),
            cases: vec![loads.clone()],
        };
        let run = crate::analysis::statics::run_static(mesh, source, &opts)?;
        let case = run
            .cases
            .first()
            .ok_or_else(|| Error::Verification(format!("{source}: the static solution gave no load case")))?;
        out.statics = Some(match case.references.iter().find_map(|r| r.stiffness) {
            Some(k) => (k, true),
            None => (case.max_displacement.0, false),
        });
        if out.dofs == 0 {
            out.dofs = run.dofs;
        }
    }
    Ok(out)
}

/// Analyse every mesh made: the rows (values filled later), their modes and static kind.
fn analyse_levels(
    study: &UserStudy,
    pending: Vec<Pending>,
    failed: &mut Vec<String>,
    progress: &dyn Fn(&str),
) -> Result<(Vec<UserRow>, Vec<LevelOutcome>)> {
    let (mut rows, mut outcomes) = (Vec::new(), Vec::new());
    for p in pending {
        let source = p.path.display().to_string();
        let reset = reset_peak_memory();
        let t = Instant::now();
        let why = if p.warnings.is_empty() {
            String::new()
        } else {
            format!(" (gmsh: {})", p.warnings)
        };
        // A mesh gmsh wrote without volume cells (an open surface loop: gmsh only warns) is a
        // failed level like a gmsh error; a user's mesh that cannot be read is an input error.
        let mesh = match crate::input::source::load(&source, study.length_scale) {
            Ok(m) => Some(m),
            Err(e) if p.size.is_some() => {
                let msg = format!(
                    "{}: no volume cells in gmsh's mesh: {e}{why}; a closed surface loop and, if the geometry has \
                     physical groups, a Physical Volume are needed",
                    p.label
                );
                progress(&format!("error: {msg}"));
                failed.push(msg);
                None
            }
            Err(e) => return Err(e),
        };
        let Some(mesh) = mesh else { continue };
        let (Some(form), Some(edge)) = (volume_formulation(&mesh), mean_edge_length(&mesh)) else {
            let msg = format!(
                "{}: the mesh has no volume cells{why}; a closed surface loop and, if the geometry has physical \
                 groups, a Physical Volume are needed",
                p.label
            );
            if p.size.is_none() {
                return Err(Error::InvalidInput(format!("converge: {msg}")));
            }
            progress(&format!("error: {msg}"));
            failed.push(msg);
            continue;
        };
        let edge = edge / study.length_scale;
        progress(&format!(
            "solving {} ({form}, mean edge {edge:.4} {}, {} nodes)",
            p.label,
            study.length_unit,
            mesh.n_nodes()
        ));
        let o =
            analyse_user_level(study, &mesh, &source).map_err(|e| e.with_prefix(&format!("converge: {}", p.label)))?;
        let time_s = t.elapsed().as_secs_f64();
        let mem = if reset {
            crate::analysis::modal::peak_memory()
        } else {
            None
        };
        let shown: Vec<String> = o
            .freqs
            .iter()
            .take(study.frequencies)
            .map(|f| format!("{f:.4} Hz"))
            .collect();
        progress(&format!(
            "{} {form}: {}{} ({} DOFs, {time_s:.2} s)",
            p.label,
            shown.join(", "),
            o.statics.map(|(v, _)| format!(" {v:.6e}")).unwrap_or_default(),
            o.dofs
        ));
        rows.push(UserRow {
            formulation: form,
            size: p.size.unwrap_or(edge),
            mean_edge: edge,
            mesh: source,
            dofs: o.dofs,
            mesh_time_s: p.mesh_time,
            time_s,
            peak_memory_bytes: mem,
            values: Vec::new(),
            errors: Vec::new(),
            paired: Vec::new(),
        });
        outcomes.push(o);
    }
    Ok((rows, outcomes))
}

/// The rows grouped by formulation (first appearance), each group coarse to fine (largest size
/// first): indices into the rows.
fn groups(rows: &[UserRow]) -> Vec<(String, Vec<usize>)> {
    let mut g: Vec<(String, Vec<usize>)> = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        match g.iter_mut().find(|(f, _)| *f == r.formulation) {
            Some((_, v)) => v.push(i),
            None => g.push((r.formulation.clone(), vec![i])),
        }
    }
    for (_, v) in &mut g {
        v.sort_by(|&a, &b| rows[b].size.total_cmp(&rows[a].size));
    }
    g
}

/// Fill each row's values: frequency j is the level's elastic mode paired by MAC with the
/// finest level's mode j of the same formulation; the static quantity follows.
fn fill_values(study: &UserStudy, rows: &mut [UserRow], outcomes: &[LevelOutcome]) {
    for (_, idx) in groups(rows) {
        let lm: Vec<Option<LevelModes>> = idx.iter().map(|&i| outcomes[i].modes.clone()).collect();
        for &i in &idx {
            rows[i].values = outcomes[i].freqs.iter().take(study.frequencies).copied().collect();
            rows[i].paired = vec![None; study.frequencies];
        }
        for j in 0..study.frequencies {
            for (&i, p) in idx.iter().zip(pair_mode_by_mac(&lm, j)) {
                if let Some((k, m)) = p {
                    if k != j {
                        rows[i].values[j] = outcomes[i].freqs[k];
                        rows[i].paired[j] = Some((k + 1, m));
                    }
                }
            }
        }
        for &i in &idx {
            if let Some((v, _)) = outcomes[i].statics {
                rows[i].values.push(v);
            }
        }
    }
}

/// The fit of one formulation's levels (coarse to fine) for quantity `q`, refusing levels that
/// do not converge monotonically.
fn fit(rows: &[UserRow], form: &str, idx: &[usize], q: usize, name: &str, unit: &str, size_unit: &str) -> Result<Fit> {
    let levels: Vec<(String, f64)> = idx
        .iter()
        .map(|&i| {
            (
                format!("size {} {size_unit}", crate::io::fmt_short(rows[i].size, 6)),
                rows[i].values[q],
            )
        })
        .collect();
    check_monotone(form, name, unit, &levels)?;
    let n = idx.len();
    let finest = rows[idx[n - 1]].values[q];
    let rich = (n >= 3)
        .then(|| {
            let at = |k: usize| &rows[idx[n - 3 + k]];
            richardson_sizes(
                [at(0).mean_edge, at(1).mean_edge, at(2).mean_edge],
                [at(0).values[q], at(1).values[q], at(2).values[q]],
            )
        })
        .flatten();
    Ok(Fit {
        formulation: form.to_string(),
        levels: n,
        finest,
        extrapolated: rich.map(|r| r.0),
        order: rich.map(|r| r.1),
        error_estimate: rich.map(|(v, _)| ((finest - v) / v).abs()),
    })
}

/// Run a study on the user's part: mesh (a failed size is reported and the others go on), solve,
/// refuse levels that do not converge monotonically, extrapolate each formulation's three
/// finest levels, and pick the cheapest run within the tolerance.
pub fn run_user(study: &UserStudy, progress: &dyn Fn(&str)) -> Result<UserConvergence> {
    let (pending, mut failed) = mesh_levels(&study.levels, progress)?;
    let (rows, outcomes) = analyse_levels(study, pending, &mut failed, progress)?;
    // Rows by formulation, coarse to fine.
    let order: Vec<usize> = groups(&rows).into_iter().flat_map(|(_, v)| v).collect();
    let mut slots: Vec<Option<(UserRow, LevelOutcome)>> = rows.into_iter().zip(outcomes).map(Some).collect();
    let (mut rows, outcomes): (Vec<UserRow>, Vec<LevelOutcome>) = order.iter().filter_map(|&i| slots[i].take()).unzip();
    let cannot = |why: String| {
        let f = if failed.is_empty() {
            String::new()
        } else {
            format!("; failed levels: {}", failed.join("; "))
        };
        if failed.is_empty() {
            Error::param("sizes", format!("converge: {why}"))
        } else {
            Error::Engine {
                engine: "gmsh".into(),
                msg: format!("converge: {why}{f}"),
            }
        }
    };
    if rows.is_empty() {
        return Err(cannot("no level could be meshed".into()));
    }
    fill_values(study, &mut rows, &outcomes);
    let mut names: Vec<(String, String)> = (1..=study.frequencies)
        .map(|j| (format!("elastic frequency {j}"), "Hz".to_string()))
        .collect();
    if let Some(o) = outcomes.first().and_then(|o| o.statics) {
        names.push(if o.1 {
            ("stiffness".into(), "N/m".into())
        } else {
            ("largest displacement".into(), "m".into())
        });
    }
    let groups = groups(&rows);
    let mut quantities = Vec::new();
    for (q, (name, unit)) in names.iter().enumerate() {
        let fits = groups
            .iter()
            .map(|(f, idx)| fit(&rows, f, idx, q, name, unit, &study.length_unit))
            .collect::<Result<Vec<Fit>>>()?;
        let best = fits
            .iter()
            .filter(|f| f.extrapolated.is_some())
            .min_by(|a, b| {
                a.error_estimate
                    .unwrap_or(1.0)
                    .total_cmp(&b.error_estimate.unwrap_or(1.0))
            })
            .ok_or_else(|| {
                let have: Vec<String> = groups.iter().map(|(f, i)| format!("{f}: {} levels", i.len())).collect();
                cannot(format!(
                    "{name}: Richardson extrapolation needs three levels of one formulation with decreasing mean \
                     edge length and an observed order between 0.05 and 20 ({})",
                    have.join(", ")
                ))
            })?;
        let (estimate, from) = (best.extrapolated.unwrap_or(best.finest), best.formulation.clone());
        for r in rows.iter_mut() {
            r.errors.push((r.values[q] - estimate) / estimate);
        }
        let cheapest = (0..rows.len())
            .filter(|&i| rows[i].errors[q].abs() <= study.tolerance)
            .min_by(|&a, &b| rows[a].time_s.total_cmp(&rows[b].time_s));
        quantities.push(UserQuantity {
            name: name.clone(),
            unit: unit.clone(),
            fits,
            estimate,
            estimate_from: from,
            cheapest,
        });
    }
    let cheapest = (0..rows.len())
        .filter(|&i| rows[i].errors.iter().all(|e| e.abs() <= study.tolerance))
        .min_by(|&a, &b| rows[a].time_s.total_cmp(&rows[b].time_s));
    Ok(UserConvergence {
        name: study.name.clone(),
        tolerance: study.tolerance,
        length_unit: study.length_unit.clone(),
        rows,
        quantities,
        cheapest,
        failed,
    })
}

/// The study on the user's part as markdown: per quantity the levels, the extrapolation of each
/// formulation and the cheapest run within the tolerance.
pub fn user_markdown(c: &UserConvergence) -> String {
    let u = &c.length_unit;
    let mut s = format!(
        "{}: {} levels; sizes in {u}; tolerance {}\n",
        c.name,
        c.rows.len(),
        pct(c.tolerance)
    );
    for (q, qu) in c.quantities.iter().enumerate() {
        s.push_str(&format!(
            "\n## {} [{}]\n\nbest estimate {:.6e} {} (Richardson extrapolation of {})\n\n",
            qu.name, qu.unit, qu.estimate, qu.unit, qu.estimate_from
        ));
        s.push_str(&format!(
            "| formulation | size [{u}] | mean edge [{u}] | DOFs | value | error | mesh [s] | solve [s] |\n"
        ));
        s.push_str("|---|---:|---:|---:|---:|---:|---:|---:|\n");
        for r in &c.rows {
            s.push_str(&format!(
                "| {} | {} | {:.4} | {} | {:.6e}{} | {:+.3} % | {} | {:.3} |\n",
                r.formulation,
                crate::io::fmt_short(r.size, 6),
                r.mean_edge,
                r.dofs,
                r.values[q],
                match r.paired.get(q).copied().flatten() {
                    Some((k, m)) => format!(" (mode {k}, MAC {m:.2})"),
                    None => String::new(),
                },
                r.errors[q] * 100.0,
                r.mesh_time_s.map(|t| format!("{t:.2}")).unwrap_or_else(|| "–".into()),
                r.time_s
            ));
        }
        s.push_str(
            "\n| formulation | levels | finest | Richardson | observed order | error estimate of the finest |\n",
        );
        s.push_str("|---|---:|---:|---:|---:|---:|\n");
        for f in &qu.fits {
            let o = |v: Option<f64>, k: &dyn Fn(f64) -> String| v.map(k).unwrap_or_else(|| "–".into());
            s.push_str(&format!(
                "| {} | {} | {:.6e} | {} | {} | {} |\n",
                f.formulation,
                f.levels,
                f.finest,
                o(f.extrapolated, &|v| format!("{v:.6e}")),
                o(f.order, &|p| format!("{p:.2}")),
                o(f.error_estimate, &|e| format!("{:.3} %", e * 100.0)),
            ));
        }
        s.push_str(&format!(
            "\n- cheapest within {}: {}\n",
            pct(c.tolerance),
            row_text(c, qu.cheapest, q)
        ));
    }
    if c.quantities.len() > 1 {
        s.push_str(&format!(
            "\ncheapest within {} for every quantity: {}\n",
            pct(c.tolerance),
            row_text(c, c.cheapest, 0)
        ));
    }
    for f in &c.failed {
        s.push_str(&format!("\nfailed: {f}\n"));
    }
    s
}

/// One row named for the cheapest line.
fn row_text(c: &UserConvergence, i: Option<usize>, q: usize) -> String {
    match i {
        Some(i) => {
            let r = &c.rows[i];
            format!(
                "{} at size {} {} ({:+.3} %, {:.3} s, {} DOFs)",
                r.formulation,
                r.size,
                c.length_unit,
                r.errors[q] * 100.0,
                r.time_s,
                r.dofs
            )
        }
        None => "none of the runs".into(),
    }
}

/// Write `converge.md`, `converge.json` and the plots of |error| against analysis time
/// (`converge.svg` for the first quantity, `converge_2.svg`, … for the others) to `dir`.
pub fn write_user_outputs(c: &UserConvergence, dir: &Path) -> Result<Vec<PathBuf>> {
    crate::io::create_dir(dir)?;
    let mut written = Vec::new();
    let p = dir.join("converge.md");
    std::fs::write(&p, user_markdown(c)).map_err(|e| Error::io(&p, e))?;
    written.push(p);
    let p = dir.join("converge.json");
    let text = serde_json::to_string_pretty(c).map_err(|e| Error::output("JSON", e))?;
    std::fs::write(&p, text).map_err(|e| Error::io(&p, e))?;
    written.push(p);
    for (q, qu) in c.quantities.iter().enumerate() {
        let view = Convergence {
            name: format!("{}, {}", c.name, qu.name),
            quantity: qu.name.clone(),
            unit: qu.unit.clone(),
            reference: qu.estimate,
            reference_kind: format!("Richardson extrapolation of {}", qu.estimate_from),
            rows: c
                .rows
                .iter()
                .map(|r| LevelResult {
                    formulation: r.formulation.clone(),
                    mesh: crate::io::fmt_short(r.size, 6),
                    value: r.values[q],
                    error: r.errors[q],
                    dofs: r.dofs,
                    time_s: r.time_s,
                    peak_memory_bytes: r.peak_memory_bytes,
                    paired: r.paired.get(q).copied().flatten(),
                })
                .collect(),
            cheapest: vec![(c.tolerance, qu.cheapest)],
        };
        let p = if q == 0 {
            dir.join("converge.svg")
        } else {
            dir.join(format!("converge_{}.svg", q + 1))
        };
        write_svg(&view, &p)?;
        written.push(p);
    }
    Ok(written)
}
