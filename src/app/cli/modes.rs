//! `vibrofem modes`: natural frequencies and mode shapes of a mesh.

use super::{check_outputs, emit, ordering, parse_bytes};
use crate::analysis::modal::{ModalOptions, ModalTarget};
use crate::analysis::statics::Load;
use crate::app::cli::args::{LoadArgs, ModelArgs, length_scale};
use crate::app::engines::{Engine, LowMemOptions, SlepcOptions, Solver, lowmem};
use crate::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct ModesArgs {
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
    /// Prestressed modes: solve the static case of --force, --pressure, --gravity and
    /// --displace first and find the modes of the preloaded structure, (K + K_σ)x = λMx, with
    /// K_σ the geometric stiffness of its stresses.
    #[arg(long)]
    prestress: bool,
    #[command(flatten)]
    loads: LoadArgs,
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
    /// The memory the run may use (e.g. 8G, 500M): a factorisation that needs more is refused
    /// (--solver direct) or replaced by the low-memory iterative path (--solver auto).
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
    /// Solver: direct (a factorisation; refused when it does not fit the memory), iterative
    /// (the low-memory SLEPc path, multigrid-preconditioned, under mpirun) or auto (direct
    /// unless its estimate exceeds --max-memory or the memory available, then iterative).
    #[arg(long, default_value = "auto")]
    solver: String,
    /// MPI ranks of --engine slepc and of the iterative solver.
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

/// The static loads of `--prestress` (adding its prescribed displacements to `spec`); load
/// options without `--prestress` are an error.
fn prestress_loads(a: &ModesArgs, spec: &mut crate::model::ModelSpec) -> Result<Option<Vec<Load>>> {
    if a.prestress {
        return Ok(Some(a.loads.apply(spec)?));
    }
    let l = &a.loads;
    let given = [
        ("--force", !l.force.is_empty()),
        ("--pressure", !l.pressure.is_empty()),
        ("--gravity", l.gravity.is_some()),
        ("--displace", !l.displace.is_empty()),
    ];
    match given.iter().find(|(_, g)| *g) {
        Some((name, _)) => Err(Error::option(
            *name,
            "a static load applies to modes with --prestress (the preload of prestressed modes)",
        )),
        None => Ok(None),
    }
}

pub fn run(a: &ModesArgs) -> Result<i32> {
    let mut spec = a.model.spec()?;
    let loads = prestress_loads(a, &mut spec)?;
    let target = match (&a.band, a.modes) {
        (Some(b), _) => ModalTarget::Band(b[0], b[1]),
        (None, Some(n)) if n > 0 => ModalTarget::Modes(n),
        (None, Some(_)) => return Err(Error::option("--modes", "--modes must be at least 1")),
        (None, None) => ModalTarget::Modes(12),
    };
    let ordering = ordering(&a.ordering)?;
    if a.block == 0 {
        return Err(Error::option("--block", "--block must be at least 1"));
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
    // The engine switch: native, SLEPc under mpirun, or the import of a SLEPc job; and the
    // solver: direct, the low-memory iterative path, or the choice between them by memory.
    let solver = Solver::parse(&a.solver)?;
    let slepc_opts = SlepcOptions {
        ranks: a.ranks,
        workdir: a.slepc_dir.clone(),
        import: a.slepc_import.clone(),
        ..Default::default()
    };
    let lm = LowMemOptions {
        slepc: slepc_opts.clone(),
        method: None,
        max_memory: opts.max_memory,
    };
    // --ranks and --slepc-dir serve the iterative solver too.
    let engine = match (solver, a.engine.as_str()) {
        (Solver::Iterative, "native") => Engine::Native,
        _ => Engine::parse(&a.engine, slepc_opts)?,
    };
    check_outputs(
        &[("--vtu", a.vtu.as_deref()), ("--msh-out", a.msh_out.as_deref())],
        None,
        &[("input mesh", std::path::Path::new(&a.mesh))],
    )?;
    let t = std::time::Instant::now();
    let mesh = crate::input::source::load(&a.mesh, length_scale(&a.model.length_unit)?)?;
    let read_time = t.elapsed().as_secs_f64();
    let (run, iterative) = match &loads {
        Some(l) => {
            if !matches!(engine, Engine::Native) {
                return Err(Error::option(
                    "--prestress",
                    "prestressed modes are solved by --engine native only",
                ));
            }
            if solver == Solver::Iterative {
                return Err(Error::option(
                    "--prestress",
                    "prestressed modes are solved by --solver direct only",
                ));
            }
            let run = crate::analysis::prestress::run_prestressed_modes(&mesh, &a.mesh, &opts, l, read_time)?;
            (run.modal, None)
        }
        None => lowmem::solve_mesh(&engine, solver, (&mesh, &a.mesh), &opts, read_time, &lm)?,
    };
    match (&iterative, a.json) {
        (None, true) => outln!(
            "{}",
            serde_json::to_string_pretty(&run.report).map_err(|e| Error::output("JSON", e))?
        ),
        (Some(info), true) => {
            // The same document with the solver's name, its reasons and its memory by phase.
            let mut v = serde_json::to_value(&run.report).map_err(|e| Error::output("JSON", e))?;
            v["solver"] = serde_json::to_value(info).map_err(|e| Error::output("JSON", e))?;
            outln!(
                "{}",
                serde_json::to_string_pretty(&v).map_err(|e| Error::output("JSON", e))?
            );
        }
        (None, false) => out!("{}", crate::app::report::modal_table(&run.report)),
        (Some(info), false) => out!("{}", lowmem::table(&run, info)),
    }
    // The VTU draws the model's cells (a shell model on a box's bricks draws its shells),
    // and the shells' and beams' rotations beside the translations.
    for p in crate::app::output::write_shapes(
        &mesh,
        run.model.as_deref(),
        (&run.shapes, run.vectors.as_ref()),
        ("frequencies_hz", &run.report.frequencies_hz),
        a.vtu.as_deref(),
        a.msh_out.as_deref(),
    )? {
        eprintln!("wrote {}", p.display());
    }
    for n in &run.report.notes {
        eprintln!("note: {n}");
    }
    if let Some(why) = iterative.as_ref().and_then(|i| i.sturm_not_verified.as_ref()) {
        // The modes are verified accurate; whether one was missed is not known.
        eprintln!("warning: Sturm count not verified: {why}");
    } else if !run.report.complete {
        eprintln!("error: the Sturm-sequence check shows missed modes (see 'complete' above)");
        return Ok(2);
    }
    if !run.report.accurate {
        eprintln!("error: accuracy not guaranteed (the notes above say why)");
        return Ok(2);
    }
    Ok(0)
}
