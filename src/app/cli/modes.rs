//! `vibrofem modes`: natural frequencies and mode shapes of a mesh.

use super::{check_outputs, emit, ordering, parse_bytes};
use crate::analysis::modal::{ModalOptions, ModalTarget};
use crate::analysis::statics::Load;
use crate::app::cli::args::{LoadArgs, ModelArgs, length_scale};
use crate::app::engines::{Engine, SlepcOptions};
use crate::io;
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
    // The engine switch: native, SLEPc under mpirun, or the import of a SLEPc job.
    let engine = Engine::parse(
        &a.engine,
        SlepcOptions {
            ranks: a.ranks,
            workdir: a.slepc_dir.clone(),
            import: a.slepc_import.clone(),
            ..Default::default()
        },
    )?;
    check_outputs(
        &[("--vtu", a.vtu.as_deref()), ("--msh-out", a.msh_out.as_deref())],
        None,
        &[("input mesh", std::path::Path::new(&a.mesh))],
    )?;
    let t = std::time::Instant::now();
    let mesh = crate::input::source::load(&a.mesh, length_scale(&a.model.length_unit)?)?;
    let read_time = t.elapsed().as_secs_f64();
    let run = match &loads {
        Some(l) => {
            if !matches!(engine, Engine::Native) {
                return Err(Error::option(
                    "--prestress",
                    "prestressed modes are solved by --engine native only",
                ));
            }
            crate::analysis::prestress::run_prestressed_modes(&mesh, &a.mesh, &opts, l, read_time)?.modal
        }
        None => engine.solve_mesh(&mesh, &a.mesh, &opts, read_time)?,
    };
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&run.report).map_err(|e| Error::output("JSON", e))?
        );
    } else {
        out!("{}", crate::app::report::modal_table(&run.report));
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
