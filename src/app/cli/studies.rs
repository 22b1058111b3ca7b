//! Scene runs, batches, sweeps, convergence studies and merges of batch shards.

use super::{check_outputs, emit};
use crate::app::cli::args::{LoadArgs, ModelArgs, length_scale};
use crate::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct RunArgs {
    /// Scene file (TOML, see docs/scenes.md).
    scene: PathBuf,
    /// Folder for summary.json and the result files asked for in [output].
    #[arg(short, long, default_value = "vibrofem-run")]
    out: PathBuf,
    /// Print the JSON summary on stdout instead of the tables.
    #[arg(long)]
    json: bool,
}

pub fn run_cmd(a: &RunArgs) -> Result<i32> {
    let scene = crate::app::studies::scene::Scene::load(&a.scene)?;
    check_outputs(&[], Some(("--out", &a.out)), &[("scene file", &a.scene)])?;
    let report = scene.run(Some((&a.out, "")))?;
    let json = serde_json::to_string_pretty(&report).map_err(|e| Error::output("JSON", e))?;
    let path = a.out.join("summary.json");
    std::fs::write(&path, &json).map_err(|e| Error::io(&path, e))?;
    if a.json {
        outln!("{json}");
    } else {
        out!("{}", report.text());
    }
    for n in &report.notes {
        eprintln!("note: {n}");
    }
    for o in &report.outputs {
        eprintln!("wrote {o}");
    }
    if !report.verified() {
        eprintln!("error: the modal solution failed its Sturm-sequence or residual check");
        return Ok(2);
    }
    Ok(0)
}

#[derive(clap::Args)]
pub struct BatchArgs {
    /// Glob of mesh files, wildcards (* and ?) in the file name only, e.g. 'meshes/s1_*.msh'.
    pattern: String,
    /// Template scene: each mesh replaces its [mesh].
    #[arg(long)]
    scene: PathBuf,
    /// Folder for per-case results (<stem>.json), summary.csv and summary.json.
    #[arg(short, long, default_value = "vibrofem-batch")]
    out: PathBuf,
    /// Cases run at once (capped further by available memory).
    #[arg(long, default_value_t = 1, value_parser = super::args::at_least_one)]
    jobs: usize,
    /// Rerun cases whose result file already exists.
    #[arg(long)]
    force: bool,
    /// Run only shard I of N of the sorted file list, e.g. 2/8.
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
}

pub fn batch_cmd(a: &BatchArgs) -> Result<i32> {
    use std::io::IsTerminal;
    check_outputs(&[], Some(("--out", &a.out)), &[("template scene", &a.scene)])?;
    let opts = crate::app::studies::batch::BatchOptions {
        pattern: a.pattern.clone(),
        template: a.scene.clone(),
        out: a.out.clone(),
        jobs: a.jobs,
        force: a.force,
        shard: a
            .shard
            .as_deref()
            .map(crate::app::studies::batch::parse_shard)
            .transpose()?,
        progress_bar: std::io::stderr().is_terminal(),
    };
    let s = crate::app::studies::batch::run_batch(&opts)?;
    outln!(
        "{:<48} {:>10} {:>8} {:>14} {:>9}",
        "file",
        "status",
        "dofs",
        "f elastic / k",
        "time [s]"
    );
    for r in &s.rows {
        let key = r
            .first_elastic_hz
            .map(|f| format!("{} Hz", crate::io::fmt_fixed(f, 4)))
            .or(r.stiffness.map(|k| format!("{k:.4e}")))
            .unwrap_or_default();
        outln!(
            "{:<48} {:>10} {:>8} {:>14} {:>9.2}",
            r.file,
            r.status,
            r.dofs.map(|d| d.to_string()).unwrap_or_default(),
            key,
            r.time_s
        );
        if let Some(e) = &r.error {
            outln!("    {e}");
        }
    }
    outln!(
        "{} cases: {} ok, {} resumed, {} failed; summary in {}",
        s.rows.len(),
        s.rows.len() - s.failed - s.resumed,
        s.resumed,
        s.failed,
        a.out.join("summary.csv").display()
    );
    Ok(if s.failed > 0 { 3 } else { 0 })
}

#[derive(clap::Args)]
pub struct SweepArgs {
    /// Study file ([study], see docs/sweeps.md) or a scene with generator = "sandwich:paper[,SIZE]".
    study: PathBuf,
    /// KEY=a:b:step or KEY=v1,v2,… (e.g. table.top_thickness=0.015:0.03:0.0025); repeatable.
    #[arg(long = "set", value_name = "KEY=RANGE")]
    set: Vec<String>,
    /// Folder for sweep.csv, sweep.json and pareto.svg.
    #[arg(short, long, default_value = "vibrofem-sweep")]
    out: PathBuf,
    /// Designs analysed at once.
    #[arg(long, default_value_t = 1, value_parser = super::args::at_least_one)]
    jobs: usize,
    /// Model: shell (MITC4 mid-surface) or solid (hex20 of --solid-size).
    #[arg(long)]
    formulation: Option<String>,
    /// Hex20 element size for --formulation solid (m).
    #[arg(long)]
    solid_size: Option<f64>,
    /// Lowest admissible first elastic frequency (Hz).
    #[arg(long)]
    min_f1: Option<f64>,
    /// Highest admissible mass (kg).
    #[arg(long)]
    max_mass: Option<f64>,
    /// Re-run the N best designs on a finer shell mesh and as hex20 solids.
    #[arg(long)]
    check: Option<usize>,
    /// Start a study of more than 1000 designs (refused otherwise, with its size).
    #[arg(long)]
    yes: bool,
}

pub fn sweep_cmd(a: &SweepArgs) -> Result<i32> {
    use crate::app::studies::sweep;
    let mut study = sweep::Study::load(&a.study)?;
    for s in &a.set {
        let (k, v) = sweep::parse_set(s)?;
        study.set(&k, v);
    }
    match a.formulation.as_deref() {
        None => {}
        Some("shell") => study.formulation = sweep::SweepFormulation::Shell,
        Some("solid") => study.formulation = sweep::SweepFormulation::Solid,
        Some(f) => {
            return Err(Error::option(
                "--formulation",
                format!("--formulation '{f}': use shell or solid"),
            ));
        }
    }
    if let Some(h) = a.solid_size {
        // It sizes the solid formulation's elements only (the check's hex20 size is the study
        // file's [check] solid_size): given for a shell sweep it would be dropped unseen.
        if study.formulation != sweep::SweepFormulation::Solid {
            return Err(Error::option(
                "--solid-size",
                "--solid-size sizes the hex20 elements of --formulation solid; this sweep is of shells (give \
                 --formulation solid, or the check's size as [check] solid_size in a study file)",
            ));
        }
        study.solid_size = h;
    }
    if let Some(f) = a.min_f1 {
        study.constraints.min_f1_hz = f;
    }
    if let Some(m) = a.max_mass {
        study.constraints.max_mass_kg = m;
    }
    if let Some((field, msg)) = study.constraints.invalid() {
        let option = if field == "min_f1_hz" { "--min-f1" } else { "--max-mass" };
        return Err(Error::option(option, format!("{option} {msg}")));
    }
    if let Some(n) = a.check {
        study.check.designs = n;
    }
    check_outputs(&[], Some(("--out", &a.out)), &[("study file", &a.study)])?;
    let o = sweep::run_sweep(
        &study,
        &sweep::SweepOptions {
            out: Some(a.out.clone()),
            jobs: a.jobs,
            progress: true,
            yes: a.yes,
        },
    )?;
    out!("{}", sweep::table_text(&o));
    outln!("outputs in {}", a.out.display());
    // As `batch`: 3 when some designs (or checks) failed and the others completed.
    Ok(if o.failed.is_empty() { 0 } else { 3 })
}

#[derive(clap::Args)]
pub struct ConvergeArgs {
    /// Built-in case (s1, s3, s5, s7, tiny), a scene file with a box:, helix: or sandwich:paper
    /// generator, a gmsh geometry PART.geo (meshed at each of --sizes and --orders), or a glob
    /// of meshes of one part, e.g. 'plate_h*.msh' (docs/converge.md).
    case: String,
    /// Folder for converge.md, converge.json and converge.svg (and the meshes of a .geo).
    #[arg(short, long, default_value = "vibrofem-converge")]
    out: PathBuf,
    /// Refinement levels of a scene (each halves the element size; default 3).
    #[arg(long, value_parser = super::args::at_least_one)]
    levels: Option<usize>,
    /// Element sizes of a .geo (gmsh's Mesh.MeshSizeMax, in the geometry's units), e.g. 20,10,5.
    #[arg(long, value_name = "H1,H2,…")]
    sizes: Option<String>,
    /// Element orders of a .geo: 1 (tet4, hex8 where the .geo recombines) and/or 2 (tet10, hex20).
    #[arg(long, value_name = "1,2")]
    orders: Option<String>,
    /// Tolerance of the cheapest run (relative to the best Richardson estimate), e.g. 1% or 0.01.
    #[arg(long)]
    tolerance: Option<String>,
    /// Elastic frequencies measured on a .geo or a set of meshes (the lowest ones).
    #[arg(long)]
    frequencies: Option<usize>,
    /// gmsh to run: the gmsh executable or a Python with the gmsh module (default: the variable
    /// VIBROFEM_GMSH, else gmsh on PATH, else python3/python on PATH with the gmsh module).
    #[arg(long)]
    gmsh: Option<PathBuf>,
    /// Time limit of one mesh generation, s.
    #[arg(long = "mesh-timeout", value_name = "SECONDS")]
    mesh_timeout: Option<f64>,
    /// Print the JSON of a .geo or mesh-set study on stdout instead of the tables.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    model: ModelArgs,
    #[command(flatten)]
    loads: LoadArgs,
}

/// Is the case a study on the user's part: a `.geo`, or a glob / `.msh` file?
fn user_case(case: &str) -> bool {
    let lower = case.to_lowercase();
    lower.ends_with(".geo") || lower.ends_with(".msh") || case.contains(['*', '?'])
}

/// The first option of a study on the user's part that was given to a built-in case or scene.
fn user_option_given(a: &ConvergeArgs) -> Option<&'static str> {
    let m = &a.model;
    let l = &a.loads;
    [
        ("--sizes", a.sizes.is_some()),
        ("--orders", a.orders.is_some()),
        ("--tolerance", a.tolerance.is_some()),
        ("--frequencies", a.frequencies.is_some()),
        ("--gmsh", a.gmsh.is_some()),
        ("--mesh-timeout", a.mesh_timeout.is_some()),
        ("--json", a.json),
        ("--material", m.material != "steel"),
        ("--group-material", !m.group_material.is_empty()),
        ("--fix", !m.fix.is_empty()),
        ("--couple", !m.couple.is_empty()),
        ("--point-mass", !m.point_mass.is_empty()),
        ("--spring", !m.spring.is_empty()),
        ("--mass", m.mass != "consistent"),
        ("--hex8", m.hex8 != "standard"),
        ("--solid", !m.solid.is_empty()),
        ("--shell", !m.shell.is_empty()),
        ("--beam", !m.beam.is_empty()),
        ("--length-unit", m.length_unit != "m"),
        ("--force", !l.force.is_empty()),
        ("--pressure", !l.pressure.is_empty()),
        ("--gravity", l.gravity.is_some()),
        ("--displace", !l.displace.is_empty()),
    ]
    .into_iter()
    .find(|(_, g)| *g)
    .map(|(n, _)| n)
}

pub fn converge_cmd(a: &ConvergeArgs) -> Result<i32> {
    use crate::app::studies::converge;
    if user_case(&a.case) {
        return converge_user_cmd(a);
    }
    if let Some(o) = user_option_given(a) {
        return Err(Error::option(
            o,
            format!(
                "{o} applies to a study on a .geo geometry or a set of .msh meshes, not to '{}'",
                a.case
            ),
        ));
    }
    let case = if std::path::Path::new(&a.case).is_file() {
        converge::from_scene(std::path::Path::new(&a.case), a.levels.unwrap_or(3))?
    } else {
        if a.levels.is_some() {
            return Err(levels_not_here(&a.case));
        }
        converge::builtin(&a.case)?
    };
    check_outputs(
        &[],
        Some(("--out", &a.out)),
        &[("case file", std::path::Path::new(&a.case))],
    )?;
    let c = converge::run_case(&case, &|l| eprintln!("{l}"))?;
    converge::write_outputs(&c, &a.out)?;
    out!("{}", converge::table_markdown(&c));
    outln!("outputs in {}", a.out.display());
    Ok(0)
}

/// A list `a,b,c` of positive numbers for `option`.
fn positive_list(option: &str, text: &str) -> Result<Vec<f64>> {
    let v = crate::app::cli::args::numbers(option, text, text)?;
    if v.is_empty() || v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return Err(Error::option(
            option,
            format!("{option} '{text}': expected positive numbers separated by commas, e.g. 20,10,5"),
        ));
    }
    Ok(v)
}

/// `1%`, `0.5 %` or `0.01`: a relative tolerance in (0, 1).
fn parse_tolerance(text: &str) -> Result<f64> {
    let t = text.trim();
    let v = match t.strip_suffix('%') {
        Some(p) => p.trim().parse::<f64>().map(|x| x / 100.0),
        None => t.parse::<f64>(),
    };
    match v {
        Ok(x) if x > 0.0 && x < 1.0 => Ok(x),
        _ => Err(Error::option(
            "--tolerance",
            format!("--tolerance '{text}': expected a relative tolerance such as 1% or 0.01 (between 0 and 1)"),
        )),
    }
}

/// `--levels` given where the study's levels are fixed (a built-in case, a .geo's --sizes, a set
/// of meshes): refused rather than ignored.
fn levels_not_here(case: &str) -> Error {
    Error::option(
        "--levels",
        format!(
            "--levels applies to a scene with a generator; '{case}' has its own levels (a built-in case's, a .geo's \
             --sizes, or the meshes matched)"
        ),
    )
}

/// `vibrofem converge PART.geo` and `vibrofem converge 'part_h*.msh'`.
fn converge_user_cmd(a: &ConvergeArgs) -> Result<i32> {
    if a.levels.is_some() {
        return Err(levels_not_here(&a.case));
    }
    use crate::app::studies::converge::{self, UserLevels, UserStudy};
    use crate::app::studies::geo::Gmsh;
    let path = std::path::Path::new(&a.case);
    let geo = a.case.to_lowercase().ends_with(".geo");
    let mut spec = a.model.spec()?;
    let loads = a.loads.apply(&mut spec)?;
    let has_loads = !loads.is_empty() || !a.loads.displace.is_empty();
    let frequencies = a.frequencies.unwrap_or(1);
    if frequencies == 0 && !has_loads {
        return Err(Error::option(
            "--frequencies",
            "--frequencies 0 leaves nothing to measure: give a load (--force with a --couple GROUP:guided=AXIS for \
             a stiffness)",
        ));
    }
    let tolerance = a.tolerance.as_deref().map(parse_tolerance).transpose()?.unwrap_or(0.01);
    let levels = if geo {
        if !path.is_file() {
            return Err(Error::io(
                path,
                std::io::Error::new(std::io::ErrorKind::NotFound, "no such geometry file"),
            ));
        }
        let sizes = positive_list(
            "--sizes",
            a.sizes
                .as_deref()
                .ok_or_else(|| Error::option("--sizes", "a .geo study needs --sizes, e.g. --sizes 20,10,5"))?,
        )?;
        let orders: Vec<usize> = positive_list("--orders", a.orders.as_deref().unwrap_or("1,2"))?
            .into_iter()
            .map(|o| match o {
                1.0 => Ok(1),
                2.0 => Ok(2),
                _ => Err(Error::option(
                    "--orders",
                    format!("--orders: order {o}: use 1 and/or 2"),
                )),
            })
            .collect::<Result<_>>()?;
        let timeout = a.mesh_timeout.unwrap_or(300.0);
        if !(timeout.is_finite() && timeout > 0.0) {
            return Err(Error::option(
                "--mesh-timeout",
                "--mesh-timeout must be a positive number of seconds",
            ));
        }
        check_outputs(&[], Some(("--out", &a.out)), &[("geometry", path)])?;
        UserLevels::Geo {
            geo: path.to_path_buf(),
            sizes,
            orders,
            gmsh: Gmsh::find(a.gmsh.as_deref())?,
            // Beyond 1e9 s (31 years) no limit in effect; Duration holds no more than ~1.8e19 s.
            timeout: std::time::Duration::from_secs_f64(timeout.min(1e9)),
            work: a.out.join("meshes"),
        }
    } else {
        if let Some(o) = [
            ("--sizes", a.sizes.is_some()),
            ("--orders", a.orders.is_some()),
            ("--gmsh", a.gmsh.is_some()),
        ]
        .iter()
        .find(|o| o.1)
        {
            return Err(Error::option(
                o.0,
                format!("{} applies to a .geo geometry; a set of meshes has its own sizes", o.0),
            ));
        }
        let files = crate::app::studies::batch::glob_files(&a.case)?;
        if files.is_empty() {
            return Err(Error::param(
                "pattern",
                format!("converge: no file matches '{}'", a.case),
            ));
        }
        let inputs: Vec<(&str, &std::path::Path)> = files.iter().map(|f| ("mesh", f.as_path())).collect();
        check_outputs(&[], Some(("--out", &a.out)), &inputs)?;
        UserLevels::Meshes(files)
    };
    let study = UserStudy {
        name: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| a.case.clone()),
        levels,
        spec,
        loads: has_loads.then_some(loads),
        length_scale: length_scale(&a.model.length_unit)?,
        length_unit: a.model.length_unit.clone(),
        frequencies,
        tolerance,
    };
    let c = converge::run_user(&study, &|l| eprintln!("{l}"))?;
    let written = converge::write_user_outputs(&c, &a.out)?;
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&c).map_err(|e| Error::output("JSON", e))?
        );
    } else {
        out!("{}", converge::user_markdown(&c));
        outln!("outputs in {}", a.out.display());
    }
    for p in written {
        eprintln!("wrote {}", p.display());
    }
    for f in &c.failed {
        eprintln!("warning: {f}");
    }
    Ok(0)
}

#[derive(clap::Args)]
pub struct MergeArgs {
    /// Batch output folders (each with summary.json).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Folder for the merged summary.csv and summary.json.
    #[arg(short, long)]
    out: PathBuf,
}

pub fn merge_cmd(a: &MergeArgs) -> Result<i32> {
    let inputs: Vec<(&str, &std::path::Path)> = a.dirs.iter().map(|d| ("batch folder merged", d.as_path())).collect();
    check_outputs(&[], Some(("--out", &a.out)), &inputs)?;
    let s = crate::app::studies::merge::merge(&a.dirs, Some(&a.out))?;
    let missing = crate::app::studies::merge::missing_shards(&s);
    if !missing.is_empty() {
        eprintln!(
            "note: shard(s) {} of the batch are not among the folders merged: the summary is incomplete",
            missing.join(", ")
        );
    }
    outln!(
        "{} cases ({} failed) merged from {} folders into {}",
        s.rows.len(),
        s.failed,
        a.dirs.len(),
        a.out.join("summary.csv").display()
    );
    Ok(0)
}
