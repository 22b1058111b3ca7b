//! `vibrofem` command-line program. Exit codes: 0 success, 1 input error, 2 numerical failure
//! (no convergence, a missed mode, accuracy not guaranteed), 3 batch with failed cases.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use vibrofem::analysis::modal::{ModalOptions, ModalTarget, run_modal};
use vibrofem::app::cli::{LoadArgs, ModelArgs, length_scale};
use vibrofem::io;
use vibrofem::linalg::ordering::Ordering;
use vibrofem::material::Material;
use vibrofem::{Error, Result};

#[derive(Parser)]
#[command(
    name = "vibrofem",
    version,
    about = "Finite-element modal and stiffness analysis for vibrating machines"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
    /// Worker threads (default: all cores).
    #[arg(long, global = true)]
    threads: Option<usize>,
    /// Progress and timing messages on stderr (-v: phases, -vv: details).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
}

#[derive(Subcommand)]
enum Cmd {
    /// The vibratory-table design chain (FE parts → two-mass model → checks); built-in paper
    /// design when no file is given.
    Design(DesignArgs),
    /// Natural frequencies and mode shapes of a solid mesh (gmsh MSH 2.2 or 4.1).
    Modes(ModesArgs),
    /// Linear static analysis: displacements, reactions, stiffness and stresses.
    Static(StaticArgs),
    /// Steady-state response to harmonic forces at one frequency or over a sweep: modal
    /// superposition with static correction, or a direct complex solve.
    Harmonic(HarmonicArgs),
    /// Write K, M (PETSc binary and Matrix Market), the DOF map and a model summary for
    /// another solver (SLEPc, scipy).
    Export(ExportArgs),
    /// Groups, cell kinds and counts, bounding box, volume and mass of a mesh.
    MeshInfo(MeshInfoArgs),
    /// Run a scene file (TOML): the modal and/or static analyses it describes.
    Run(RunArgs),
    /// Run a template scene over every mesh matched by a glob, in parallel; exit 3 if some fail.
    Batch(BatchArgs),
    /// Parametric study of the sandwich work table: mass and first elastic frequency per design,
    /// CSV/JSON table and Pareto plot (docs/sweeps.md).
    Sweep(SweepArgs),
    /// Speed–accuracy study: a case over mesh refinements and formulations (s1, s3, s5, s7, or a
    /// scene with a generator).
    Converge(ConvergeArgs),
    /// Join the summaries of batch shard folders into one.
    Merge(MergeArgs),
    /// Crank–slider drives (roller-forming machine): reduced inertia, Kloss motor, motion
    /// non-uniformity; built-in paper drive when no file is given.
    CrankDrive(vibrofem::app::machines_cli::CrankDriveArgs),
    /// Ball autobalancer of a grinder on a rocker: criterion, speed sweep, run-up; built-in grinder
    /// when no file is given.
    Autobalancer(vibrofem::app::machines_cli::AutobalancerArgs),
    /// Autobalancer test-stand data reduction (correction cut, imbalance scatter, sensitivity,
    /// efficiency) from a CSV file; built-in example when no file is given.
    BalancerData(vibrofem::app::machines_cli::BalancerDataArgs),
}

#[derive(clap::Args)]
struct SweepArgs {
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

#[derive(clap::Args)]
struct HarmonicArgs {
    /// gmsh mesh file (MSH 2.2 or 4.1), or a generator (`box:`, `helix:`, `sandwich:`, `ibeam-*:`).
    mesh: String,
    #[command(flatten)]
    model: ModelArgs,
    /// Harmonic force on a group: `GROUP=FX,FY,FZ` amplitudes in N, optionally `@PHASE` in degrees;
    /// repeatable. Spread as a static force (coupled group: its reference node; surface: uniform
    /// traction; otherwise equally over the nodes).
    #[arg(
        long,
        value_name = "GROUP=FX,FY,FZ[@DEG]",
        allow_hyphen_values = true,
        required = true
    )]
    force: Vec<String>,
    /// One excitation frequency (Hz).
    #[arg(long, conflicts_with = "sweep", required_unless_present = "sweep")]
    freq: Option<f64>,
    /// A sweep: N frequencies from F0 to F1 Hz.
    #[arg(long, num_args = 3, value_names = ["F0", "F1", "N"])]
    sweep: Option<Vec<String>>,
    /// Modal damping ratio ζ (e.g. 0.02).
    #[arg(long, conflicts_with = "rayleigh")]
    damping: Option<f64>,
    /// Rayleigh damping C = αM + βK: `ALPHA,BETA` (1/s, s).
    #[arg(long, value_name = "ALPHA,BETA")]
    rayleigh: Option<String>,
    /// modal (superposition with static correction, default), direct (complex solve per
    /// frequency) or both (reports their difference).
    #[arg(long, default_value = "modal")]
    method: String,
    /// Modes superposed: the N lowest (default: every mode below 2 × the highest frequency).
    #[arg(long)]
    modes: Option<usize>,
    /// Groups to report and plot (repeatable; default: the loaded groups).
    #[arg(long)]
    probe: Vec<String>,
    /// Fill-reducing ordering: metis (default) or amd.
    #[arg(long, default_value = "metis")]
    ordering: String,
    /// Refuse models whose factorisation needs more memory than this (e.g. 8G, 500M).
    #[arg(long = "max-memory")]
    max_memory: Option<String>,
    /// Print the JSON report on stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// Write the response fields as VTU (ParaView); for a sweep, at the frequency of the largest
    /// response.
    #[arg(long)]
    vtu: Option<PathBuf>,
    /// The same as gmsh views.
    #[arg(long = "msh-out")]
    msh_out: Option<PathBuf>,
    /// FRF plot (SVG) of a sweep.
    #[arg(long)]
    plot: Option<PathBuf>,
}

#[derive(clap::Args)]
struct ConvergeArgs {
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

#[derive(clap::Args)]
struct MergeArgs {
    /// Batch output folders (each with summary.json).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Folder for the merged summary.csv and summary.json.
    #[arg(short, long)]
    out: PathBuf,
}

#[derive(clap::Args)]
struct RunArgs {
    /// Scene file (TOML, see docs/scenes.md).
    scene: PathBuf,
    /// Folder for summary.json and the result files asked for in [output].
    #[arg(short, long, default_value = "vibrofem-run")]
    out: PathBuf,
    /// Print the JSON summary on stdout instead of the tables.
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct BatchArgs {
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

#[derive(clap::Args)]
struct DesignArgs {
    /// Design file (TOML); default: the paper's 100 Hz table, built in.
    file: Option<PathBuf>,
    /// Folder for the report (report.md, report.json, SVG plots, mode shapes).
    #[arg(short, long, default_value = "vibrofem-design")]
    out: PathBuf,
    /// Print the JSON report on stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// Run a design whose models exceed 300 000 DOFs (refused otherwise, with the estimate).
    #[arg(long)]
    yes: bool,
}

#[derive(clap::Args)]
struct StaticArgs {
    /// gmsh mesh file (MSH 2.2 or 4.1), or a generated box `box:LX,LY,LZ:NX,NY,NZ:KIND`.
    mesh: String,
    #[command(flatten)]
    model: ModelArgs,
    #[command(flatten)]
    loads: LoadArgs,
    /// Print the JSON report on stdout instead of the text summary.
    #[arg(long)]
    json: bool,
    /// Write displacement and stress fields as a VTU file (ParaView).
    #[arg(long)]
    vtu: Option<PathBuf>,
    /// Write the mesh with displacement and stress views (gmsh).
    #[arg(long = "msh-out")]
    msh_out: Option<PathBuf>,
}

#[derive(clap::Args)]
struct ModesArgs {
    /// gmsh mesh file (MSH 2.2 or 4.1), or a generated box `box:LX,LY,LZ:NX,NY,NZ:KIND`.
    mesh: String,
    /// Number of modes (the lowest ones, rigid-body modes included; nearest the shift if --shift).
    #[arg(long, conflicts_with = "band")]
    modes: Option<usize>,
    /// All modes with frequency in [F_LO, F_HI] Hz.
    #[arg(long, num_args = 2, value_names = ["F_LO", "F_HI"], allow_negative_numbers = true)]
    band: Option<Vec<f64>>,
    #[command(flatten)]
    model: ModelArgs,
    /// Shift in Hz: find the modes nearest this frequency (negative: a negative λ shift).
    #[arg(long, allow_negative_numbers = true)]
    shift: Option<f64>,
    /// Lanczos block size (at least the largest multiplicity expected).
    #[arg(long, default_value_t = 6)]
    block: usize,
    /// Safety limit on the eigen iteration: operator applications (vectors) before giving up.
    #[arg(long = "max-applications", default_value_t = 20000)]
    max_applications: usize,
    /// Fill-reducing ordering: metis (default) or amd.
    #[arg(long, default_value = "metis")]
    ordering: String,
    /// Refuse models whose factorisation needs more memory than this (e.g. 8G, 500M).
    #[arg(long = "max-memory")]
    max_memory: Option<String>,
    /// Print the JSON report on stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// Write mode shapes as a VTU file (ParaView).
    #[arg(long)]
    vtu: Option<PathBuf>,
    /// Write the mesh with one $NodeData view per mode (gmsh).
    #[arg(long = "msh-out")]
    msh_out: Option<PathBuf>,
    /// Eigen solver: native (verified block Lanczos, default) or slepc (SLEPc Krylov–Schur with
    /// a MUMPS LDLᵀ under mpirun; Debian's python3-slepc4py and openmpi-bin).
    #[arg(long, default_value = "native")]
    engine: String,
    /// MPI ranks of --engine slepc.
    #[arg(long, default_value_t = 1)]
    ranks: usize,
    /// Keep the SLEPc work folder (matrices, script, eigenpairs) here instead of a temporary one.
    #[arg(long = "slepc-dir")]
    slepc_dir: Option<PathBuf>,
    /// Read the eigenpairs of a SLEPc job run elsewhere (a cluster) from this folder (written by
    /// `vibrofem export` with the same mesh and model options, then solved by its
    /// slepc_modes.py), verify and post-process them.
    #[arg(long = "slepc-import", conflicts_with = "slepc_dir")]
    slepc_import: Option<PathBuf>,
}

#[derive(clap::Args)]
struct ExportArgs {
    /// gmsh mesh file (MSH 2.2 or 4.1), or a generator (`box:`, `helix:`, `sandwich:`, `ibeam-*:`).
    mesh: String,
    #[command(flatten)]
    model: ModelArgs,
    /// Folder for K.petsc, M.petsc, K.mtx, M.mtx, dofs.csv and model.json.
    #[arg(short, long)]
    out: PathBuf,
    /// Matrix formats: petsc, mtx or both.
    #[arg(long, default_value = "both")]
    format: String,
    /// Print the summary (model.json) on stdout.
    #[arg(long)]
    json: bool,
    /// Modes of the SLEPc job written beside the PETSc matrices (params.json, slepc_modes.py).
    #[arg(long, default_value_t = 12, conflicts_with = "band")]
    modes: usize,
    /// The SLEPc job's band in Hz instead (all modes in [F_LO, F_HI]).
    #[arg(long, num_args = 2, value_names = ["F_LO", "F_HI"], allow_negative_numbers = true)]
    band: Option<Vec<f64>>,
    /// The SLEPc job's shift in Hz.
    #[arg(long, allow_negative_numbers = true)]
    shift: Option<f64>,
}

#[derive(clap::Args)]
struct MeshInfoArgs {
    /// gmsh mesh file, or a generated box `box:LX,LY,LZ:NX,NY,NZ:KIND`.
    mesh: String,
    /// Length unit of the mesh coordinates: m (default) or mm.
    #[arg(long = "length-unit", default_value = "m")]
    length_unit: String,
    /// Material for the mass: `steel` or `E,NU,RHO`.
    #[arg(long, default_value = "steel")]
    material: String,
    /// Shell part (as for `modes`): `GROUP=T[,OFFSET]`; volume and mass then count the model's
    /// shells, beams and solids instead of the volume cells alone.
    #[arg(long, value_name = "GROUP=T[,OFFSET]", allow_hyphen_values = true)]
    shell: Vec<String>,
    /// Beam part (as for `modes`): `GROUP=SECTION@ORIENT`.
    #[arg(long, value_name = "GROUP=SECTION@ORIENT", allow_hyphen_values = true)]
    beam: Vec<String>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// Write to stdout. A closed pipe (`vibrofem … | head`) ends the program quietly with 141, as
/// a Unix tool killed by SIGPIPE; any other failure (a full disk) is an [`Error::Output`].
fn emit(s: &str) -> Result<()> {
    use std::io::Write;
    let mut o = std::io::stdout().lock();
    o.write_all(s.as_bytes()).and_then(|()| o.flush()).map_err(|e| {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(141);
        }
        Error::output("standard output", e)
    })
}

macro_rules! out {
    ($($t:tt)*) => { emit(&format!($($t)*))? };
}

macro_rules! outln {
    ($($t:tt)*) => { emit(&format!("{}\n", format_args!($($t)*)))? };
}

/// Refuse, before any work, output files and folders that cannot be written (named, exit 1).
fn check_outputs(files: &[Option<&std::path::Path>], dir: Option<&std::path::Path>) -> Result<()> {
    for f in files.iter().flatten() {
        io::check_writable_file(f)?;
    }
    if let Some(d) = dir {
        io::check_writable_dir(d)?;
    }
    Ok(())
}

fn parse_bytes(s: &str) -> Result<u64> {
    let t = s.trim();
    let (num, mult) = match t.chars().last() {
        Some('G' | 'g') => (&t[..t.len() - 1], 1u64 << 30),
        Some('M' | 'm') => (&t[..t.len() - 1], 1u64 << 20),
        Some('K' | 'k') => (&t[..t.len() - 1], 1u64 << 10),
        _ => (t, 1),
    };
    let v: f64 = num
        .parse()
        .map_err(|_| Error::InvalidInput(format!("--max-memory: cannot read '{s}' (e.g. 8G, 500M)")))?;
    if !(v > 0.0) {
        return Err(Error::InvalidInput(format!("--max-memory must be positive, got '{s}'")));
    }
    Ok((v * mult as f64) as u64)
}

fn modes(a: &ModesArgs) -> Result<i32> {
    let spec = a.model.spec()?;
    let target = match (&a.band, a.modes) {
        (Some(b), _) => ModalTarget::Band(b[0], b[1]),
        (None, Some(n)) if n > 0 => ModalTarget::Modes(n),
        (None, Some(_)) => return Err(Error::InvalidInput("--modes must be at least 1".into())),
        (None, None) => ModalTarget::Modes(12),
    };
    let ordering = match a.ordering.as_str() {
        "metis" => Ordering::Metis,
        "amd" => Ordering::Amd,
        o => {
            return Err(Error::InvalidInput(format!(
                "--ordering: unknown '{o}' (use metis or amd)"
            )));
        }
    };
    if a.block == 0 {
        return Err(Error::InvalidInput("--block must be at least 1".into()));
    }
    let opts = ModalOptions {
        spec,
        target,
        shift_hz: a.shift,
        block: a.block,
        ordering,
        max_memory: a.max_memory.as_deref().map(parse_bytes).transpose()?,
        max_applications: a.max_applications,
    };
    check_outputs(&[a.vtu.as_deref(), a.msh_out.as_deref()], None)?;
    let t = std::time::Instant::now();
    let mesh = vibrofem::input::source::load(&a.mesh, length_scale(&a.model.length_unit)?)?;
    let read_time = t.elapsed().as_secs_f64();
    let source = a.mesh.clone();
    let engine = if a.slepc_import.is_some() {
        "slepc"
    } else {
        a.engine.as_str()
    };
    let run = match engine {
        "native" => {
            if a.ranks != 1 || a.slepc_dir.is_some() {
                return Err(Error::InvalidInput(
                    "--ranks and --slepc-dir apply to --engine slepc".into(),
                ));
            }
            run_modal(&mesh, &source, &opts, read_time)?
        }
        "slepc" => {
            let t = std::time::Instant::now();
            let model = vibrofem::model::Model::build(&mesh, &opts.spec, &source)?;
            let sys = vibrofem::system::System::assemble_only(model, &source)?;
            let t_model = t.elapsed().as_secs_f64() - sys.timings.assemble;
            let so = vibrofem::app::slepc::SlepcOptions {
                ranks: a.ranks,
                workdir: a.slepc_dir.clone(),
                import: a.slepc_import.clone(),
                ..Default::default()
            };
            let mut run = vibrofem::app::slepc::solve(&sys, &opts.params(), &so)?;
            run.report.timings_s.read = read_time;
            run.report.timings_s.assemble += t_model;
            run.report.timings_s.total += read_time + t_model;
            run
        }
        e => {
            return Err(Error::InvalidInput(format!("--engine '{e}': use native or slepc")));
        }
    };
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&run.report).map_err(|e| Error::output("JSON", e))?
        );
    } else {
        out!("{}", vibrofem::app::report::modal_table(&run.report));
    }
    for p in io::write_mode_shapes(
        &mesh,
        &run.shapes,
        &run.report.frequencies_hz,
        a.vtu.as_deref(),
        a.msh_out.as_deref(),
    )? {
        eprintln!("wrote {}", p.display());
    }
    for n in &run.report.notes {
        eprintln!("note: {n}");
    }
    if !run.report.complete {
        eprintln!("error: the Sturm-sequence check shows missed modes (see 'complete' above)");
        return Ok(2);
    }
    if !run.report.accurate {
        eprintln!("error: accuracy not guaranteed (residual or orthonormality above tolerance)");
        return Ok(2);
    }
    Ok(0)
}

fn design_cmd(a: &DesignArgs) -> Result<i32> {
    use std::io::IsTerminal;
    let d = match &a.file {
        Some(f) => vibrofem::app::design::Design::from_toml(f)?,
        None => vibrofem::app::design::Design::paper(),
    };
    if !a.yes {
        // A design file's sizes are all valid alone, yet a 5 mm element size or a 10 m plate
        // makes minutes of work: say so before starting.
        let dofs = vibrofem::app::design::estimate_dofs(&d)?;
        if dofs > vibrofem::app::design::LARGE_DESIGN_DOFS {
            return Err(Error::InvalidInput(format!(
                "the design's FE models have about {dofs} DOFs (more than {}): minutes to hours of work; \
                 rerun with --yes to start it, or coarsen the mesh sizes",
                vibrofem::app::design::LARGE_DESIGN_DOFS
            )));
        }
    }
    check_outputs(&[], Some(&a.out))?;
    let bar = if std::io::stderr().is_terminal() {
        let b = indicatif::ProgressBar::new_spinner();
        b.enable_steady_tick(std::time::Duration::from_millis(120));
        Some(b)
    } else {
        None
    };
    let t0 = std::time::Instant::now();
    let progress = |step: &str| match &bar {
        Some(b) => b.set_message(step.to_string()),
        None => eprintln!("[{:6.1} s] {step}", t0.elapsed().as_secs_f64()),
    };
    let r = vibrofem::app::design::run_design(&d, Some(&a.out), &progress);
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let r = r?;
    let json = serde_json::to_string_pretty(&r).map_err(|e| Error::output("JSON", e))?;
    std::fs::write(a.out.join("report.json"), &json).map_err(|e| Error::io(a.out.join("report.json"), e))?;
    std::fs::write(a.out.join("report.md"), vibrofem::app::design::report_markdown(&r))
        .map_err(|e| Error::io(a.out.join("report.md"), e))?;
    let html = a.out.join("report.html");
    std::fs::write(&html, vibrofem::app::design::report_html(&r, &a.out)).map_err(|e| Error::io(&html, e))?;
    if a.json {
        outln!("{json}");
    } else {
        out!("{}", vibrofem::app::design::verdict_text(&r));
        outln!(
            "
report: {}/report.md (plots and mode shapes beside it)",
            a.out.display()
        );
    }
    if d.search.enabled && r.checks.iter().any(|c| !c.ok) {
        // Issue 13 item 3: a failing design is followed by the lightest passing variant.
        let vdir = a.out.join("passing-variant");
        let bar = if std::io::stderr().is_terminal() {
            let b = indicatif::ProgressBar::new_spinner();
            b.enable_steady_tick(std::time::Duration::from_millis(120));
            Some(b)
        } else {
            None
        };
        let progress = |step: &str| match &bar {
            Some(b) => b.set_message(step.to_string()),
            None => eprintln!("[{:6.1} s] {step}", t0.elapsed().as_secs_f64()),
        };
        std::fs::create_dir_all(&vdir).map_err(|e| Error::io(&vdir, e))?;
        let o = vibrofem::app::design_search::search(&d, Some(&vdir), &progress);
        if let Some(b) = &bar {
            b.finish_and_clear();
        }
        let o = o?;
        let text = vibrofem::app::design_search::search_text(&d, &o);
        std::fs::write(a.out.join("search.txt"), &text).map_err(|e| Error::io(a.out.join("search.txt"), e))?;
        if !a.json {
            outln!("\n{text}");
        }
        if let Some((_, vr)) = &o.best {
            let vjson = serde_json::to_string_pretty(vr).map_err(|e| Error::output("JSON", e))?;
            std::fs::write(vdir.join("report.json"), &vjson).map_err(|e| Error::io(vdir.join("report.json"), e))?;
            std::fs::write(vdir.join("report.md"), vibrofem::app::design::report_markdown(vr))
                .map_err(|e| Error::io(vdir.join("report.md"), e))?;
            let vhtml = vdir.join("report.html");
            std::fs::write(&vhtml, vibrofem::app::design::report_html(vr, &vdir)).map_err(|e| Error::io(&vhtml, e))?;
            if !a.json {
                out!("{}", vibrofem::app::design::verdict_text(vr));
                outln!("\nreport of the passing variant: {}/report.md", vdir.display());
            }
        }
    }
    Ok(0)
}

fn static_cmd(a: &StaticArgs) -> Result<i32> {
    let mut spec = a.model.spec()?;
    let loads = a.loads.apply(&mut spec)?;
    check_outputs(&[a.vtu.as_deref(), a.msh_out.as_deref()], None)?;
    let mesh = vibrofem::input::source::load(&a.mesh, length_scale(&a.model.length_unit)?)?;
    let opts = vibrofem::analysis::statics::StaticOptions {
        spec,
        cases: vec![loads],
    };
    let run = vibrofem::analysis::statics::run_static(&mesh, &a.mesh, &opts)?;
    let report = vibrofem::app::report::static_report(&mesh, &a.mesh, &run)?;
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&report).map_err(|e| Error::output("JSON", e))?
        );
    } else {
        out!("{}", vibrofem::app::report::static_text(&report));
    }
    if a.vtu.is_some() || a.msh_out.is_some() {
        vibrofem::app::report::write_static_fields(&mesh, &run, a.vtu.as_deref(), a.msh_out.as_deref())?;
    }
    for n in &run.model.notes {
        eprintln!("note: {n}");
    }
    Ok(0)
}

fn harmonic_cmd(a: &HarmonicArgs) -> Result<i32> {
    use vibrofem::analysis::harmonic::{Damping, GroupForce};
    use vibrofem::app::harmonic as h;
    let spec = a.model.spec()?;
    let forces = a
        .force
        .iter()
        .map(|f| GroupForce::parse("--force", f))
        .collect::<Result<Vec<_>>>()?;
    let freqs = match (&a.freq, &a.sweep) {
        (Some(f), _) => vec![*f],
        (None, Some(s)) => {
            let num = |t: &str| -> Result<f64> {
                t.trim()
                    .parse()
                    .map_err(|_| Error::InvalidInput(format!("--sweep: cannot read '{t}' as a number")))
            };
            let n: usize = s[2]
                .trim()
                .parse()
                .map_err(|_| Error::InvalidInput(format!("--sweep: N '{}' must be a whole number ≥ 2", s[2])))?;
            h::sweep_frequencies(num(&s[0])?, num(&s[1])?, n)?
        }
        (None, None) => return Err(Error::InvalidInput("give --freq HZ or --sweep F0 F1 N".into())),
    };
    let damping = match (&a.damping, &a.rayleigh) {
        (Some(z), _) => Damping::Ratio(*z),
        (None, Some(r)) => {
            let v = vibrofem::input::options::numbers("--rayleigh", r, r)?;
            if v.len() != 2 {
                return Err(Error::InvalidInput(format!("--rayleigh '{r}': expected ALPHA,BETA")));
            }
            Damping::Rayleigh {
                alpha: v[0],
                beta: v[1],
            }
        }
        (None, None) => {
            return Err(Error::InvalidInput(
                "give --damping RATIO (e.g. 0.02) or --rayleigh ALPHA,BETA: an undamped response is infinite at \
                 resonance"
                    .into(),
            ));
        }
    };
    damping.validate()?;
    if a.plot.is_some() && freqs.len() < 2 {
        return Err(Error::InvalidInput("--plot draws an FRF: it needs --sweep".into()));
    }
    let req = h::HarmonicRequest {
        forces,
        freqs_hz: freqs,
        damping,
        method: h::Method::parse(&a.method)?,
        modes: a.modes,
        probes: a.probe.clone(),
    };
    check_outputs(&[a.vtu.as_deref(), a.msh_out.as_deref(), a.plot.as_deref()], None)?;
    let mesh = vibrofem::input::source::load(&a.mesh, length_scale(&a.model.length_unit)?)?;
    let model = vibrofem::model::Model::build(&mesh, &spec, &a.mesh)?;
    let opts = vibrofem::system::SystemOptions {
        ordering: match a.ordering.as_str() {
            "metis" => Ordering::Metis,
            "amd" => Ordering::Amd,
            o => {
                return Err(Error::InvalidInput(format!(
                    "--ordering: unknown '{o}' (use metis or amd)"
                )));
            }
        },
        max_memory: a.max_memory.as_deref().map(parse_bytes).transpose()?,
        mass: true,
    };
    let sys = vibrofem::system::System::build(model, &opts, &a.mesh)?;
    let run = h::run(&sys, &mesh, &req)?;
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&run.report).map_err(|e| Error::output("JSON", e))?
        );
    } else {
        out!("{}", h::text(&run.report));
    }
    if a.vtu.is_some() || a.msh_out.is_some() {
        let k = h::peak_index(&run.report);
        h::write_fields(&mesh, &run, k, a.vtu.as_deref(), a.msh_out.as_deref())?;
        if run.report.points.len() > 1 {
            eprintln!(
                "note: fields written at {} Hz, the frequency of the largest response",
                vibrofem::io::fmt_sig(run.report.points[k].freq_hz, 5)
            );
        }
    }
    if let Some(p) = &a.plot {
        h::write_frf_svg(p, &run.report)?;
    }
    for n in sys.model().notes.iter().chain(&run.report.notes) {
        eprintln!("note: {n}");
    }
    Ok(0)
}

fn export_cmd(a: &ExportArgs) -> Result<i32> {
    use vibrofem::app::export;
    let formats = export::Formats::parse(&a.format)?;
    let spec = a.model.spec()?;
    let mesh = vibrofem::input::source::load(&a.mesh, length_scale(&a.model.length_unit)?)?;
    let model = vibrofem::model::Model::build(&mesh, &spec, &a.mesh)?;
    let sys = vibrofem::system::System::assemble_only(model, &a.mesh)?;
    let (summary, mut files) = export::export(&sys, &a.out, formats)?;
    if formats != export::Formats::MatrixMarket {
        // The SLEPc job beside the PETSc matrices: `mpirun -n N python3 DIR/slepc_modes.py DIR`.
        let target = match (&a.band, a.modes) {
            (Some(b), _) => ModalTarget::Band(b[0], b[1]),
            (None, 0) => return Err(Error::InvalidInput("--modes must be at least 1".into())),
            (None, n) => ModalTarget::Modes(n),
        };
        let params = vibrofem::analysis::modal::ModalParams {
            target,
            shift_hz: a.shift,
            ..Default::default()
        };
        vibrofem::app::slepc::write_job(&sys, &params, &a.out, false)?;
        files.push(a.out.join("params.json"));
        files.push(a.out.join("slepc_modes.py"));
    }
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&summary).map_err(|e| Error::output("JSON", e))?
        );
    } else {
        outln!(
            "{}: {} free DOFs, {} entries in K and M, mass {} kg",
            a.mesh,
            summary.dofs,
            summary.nnz,
            vibrofem::io::fmt_sig(summary.mass_kg, 4)
        );
        for f in &files {
            outln!("wrote {}", f.display());
        }
    }
    for n in &summary.notes {
        eprintln!("note: {n}");
    }
    Ok(0)
}

fn mesh_info(a: &MeshInfoArgs) -> Result<i32> {
    let mesh = vibrofem::input::source::load(&a.mesh, length_scale(&a.length_unit)?)?;
    let mat = Material::parse(&a.material)?;
    mat.validate("--material")?;
    let mut info = vibrofem::app::report::mesh_info(&mesh, &a.mesh, &mat)?;
    for n in &mesh.notes {
        eprintln!("note: {n}");
    }
    if !a.shell.is_empty() || !a.beam.is_empty() {
        // Volume and mass of the model the parts describe (shells t·A, beams A·L, solids).
        let opts = vibrofem::input::options::ModelOptions {
            material: a.material.clone(),
            shell: a.shell.clone(),
            beam: a.beam.clone(),
            ..Default::default()
        };
        let model = vibrofem::model::Model::build(&mesh, &opts.spec()?, &a.mesh)?;
        let (volume, mass) = model.volume_and_mass()?;
        info.volume_m3 = volume;
        info.mass_kg = mass;
    }
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&info).map_err(|e| Error::output("JSON", e))?
        );
    } else {
        out!("{}", vibrofem::app::report::mesh_info_text(&info));
    }
    Ok(0)
}

fn run_cmd(a: &RunArgs) -> Result<i32> {
    let scene = vibrofem::app::scene::Scene::load(&a.scene)?;
    check_outputs(&[], Some(&a.out))?;
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

fn batch_cmd(a: &BatchArgs) -> Result<i32> {
    use std::io::IsTerminal;
    check_outputs(&[], Some(&a.out))?;
    let opts = vibrofem::app::scene::BatchOptions {
        pattern: a.pattern.clone(),
        template: a.scene.clone(),
        out: a.out.clone(),
        jobs: a.jobs,
        force: a.force,
        shard: a.shard.as_deref().map(vibrofem::app::scene::parse_shard).transpose()?,
        progress_bar: std::io::stderr().is_terminal(),
    };
    let s = vibrofem::app::scene::run_batch(&opts)?;
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

fn sweep_cmd(a: &SweepArgs) -> Result<i32> {
    use vibrofem::app::sweep;
    let mut study = sweep::Study::load(&a.study)?;
    for s in &a.set {
        let (k, v) = sweep::parse_set(s)?;
        study.set(&k, v);
    }
    match a.formulation.as_deref() {
        None => {}
        Some("shell") => study.formulation = sweep::SweepFormulation::Shell,
        Some("solid") => study.formulation = sweep::SweepFormulation::Solid,
        Some(f) => return Err(Error::InvalidInput(format!("--formulation '{f}': use shell or solid"))),
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
    check_outputs(&[], Some(&a.out))?;
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

fn converge_cmd(a: &ConvergeArgs) -> Result<i32> {
    use vibrofem::app::converge;
    let case = if std::path::Path::new(&a.case).is_file() {
        converge::from_scene(std::path::Path::new(&a.case), a.levels)?
    } else {
        converge::builtin(&a.case)?
    };
    check_outputs(&[], Some(&a.out))?;
    let c = converge::run_case(&case, &|l| eprintln!("{l}"))?;
    converge::write_outputs(&c, &a.out)?;
    out!("{}", converge::table_markdown(&c));
    outln!("outputs in {}", a.out.display());
    Ok(0)
}

fn merge_cmd(a: &MergeArgs) -> Result<i32> {
    check_outputs(&[], Some(&a.out))?;
    let s = vibrofem::app::sweep::merge(&a.dirs, Some(&a.out))?;
    outln!(
        "{} cases ({} failed) merged from {} folders into {}",
        s.rows.len(),
        s.failed,
        a.dirs.len(),
        a.out.join("summary.csv").display()
    );
    Ok(0)
}

fn main() -> ExitCode {
    // Usage errors exit 1 (input error), not clap's 2 (our numerical-failure code).
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { 1 } else { 0 });
        }
    };
    let level = match cli.verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or(level))
        .format_timestamp(None)
        .format_target(false)
        .init();
    if let Some(t) = cli.threads {
        // Far more threads than cores only costs memory (and rayon fails to spawn thousands).
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        let cap = 4 * cores;
        let t = if t > cap {
            eprintln!("note: --threads {t} capped to {cap} (4 × the {cores} available cores)");
            cap
        } else {
            t.max(1)
        };
        let _ = rayon::ThreadPoolBuilder::new().num_threads(t).build_global();
    }
    let r = match &cli.cmd {
        Cmd::Modes(a) => modes(a),
        Cmd::Design(a) => design_cmd(a),
        Cmd::Static(a) => static_cmd(a),
        Cmd::MeshInfo(a) => mesh_info(a),
        Cmd::Export(a) => export_cmd(a),
        Cmd::Harmonic(a) => harmonic_cmd(a),
        Cmd::Run(a) => run_cmd(a),
        Cmd::Batch(a) => batch_cmd(a),
        Cmd::Sweep(a) => sweep_cmd(a),
        Cmd::Converge(a) => converge_cmd(a),
        Cmd::Merge(a) => merge_cmd(a),
        Cmd::CrankDrive(a) => vibrofem::app::machines_cli::run_crank_drive(a),
        Cmd::Autobalancer(a) => vibrofem::app::machines_cli::run_autobalancer(a),
        Cmd::BalancerData(a) => vibrofem::app::machines_cli::run_balancer_data(a),
    };
    match r {
        Ok(code) => ExitCode::from(code as u8),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
