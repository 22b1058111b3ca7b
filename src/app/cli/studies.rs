//! Scene runs, batches, sweeps, convergence studies and merges of batch shards.

use super::{check_outputs, emit};
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
    #[arg(long, default_value_t = 1)]
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
            .map(|f| format!("{f:.4} Hz"))
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
    #[arg(long, default_value_t = 1)]
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
        study.solid_size = h;
    }
    if let Some(f) = a.min_f1 {
        study.constraints.min_f1_hz = f;
    }
    if let Some(m) = a.max_mass {
        study.constraints.max_mass_kg = m;
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
    Ok(0)
}

#[derive(clap::Args)]
pub struct ConvergeArgs {
    /// Built-in case (s1, s3, s5, s7, tiny) or a scene file with a box:, helix: or sandwich:paper
    /// generator.
    case: String,
    /// Folder for converge.md, converge.json and converge.svg.
    #[arg(short, long, default_value = "vibrofem-converge")]
    out: PathBuf,
    /// Refinement levels of a scene (each halves the element size).
    #[arg(long, default_value_t = 3)]
    levels: usize,
}

pub fn converge_cmd(a: &ConvergeArgs) -> Result<i32> {
    use crate::app::studies::converge;
    let case = if std::path::Path::new(&a.case).is_file() {
        converge::from_scene(std::path::Path::new(&a.case), a.levels)?
    } else {
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
    outln!(
        "{} cases ({} failed) merged from {} folders into {}",
        s.rows.len(),
        s.failed,
        a.dirs.len(),
        a.out.join("summary.csv").display()
    );
    Ok(0)
}
