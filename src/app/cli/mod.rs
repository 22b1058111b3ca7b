//! The command line: clap's definitions and a dispatcher over the commands, one file each
//! (`modes`, `statics` with `mesh-info`, `harmonic`, `export`, `design`, `studies` for scenes,
//! batches, sweeps, convergence and merges); the machines' commands live with the machines.
//! `src/main.rs` only calls [`main`].
//!
//! Exit codes: 0 success, 1 input error, 2 numerical failure (no convergence, a missed mode,
//! accuracy not guaranteed), 3 batch with failed cases, 4 a result could not be written, 5 an
//! external engine is missing or failed, 141 standard output closed ([`crate::Error::exit_code`]).

use crate::linalg::ordering::Ordering;
use crate::{Error, Result};
use clap::{Parser, Subcommand};

use std::process::ExitCode;

pub(crate) use crate::app::output::{check_outputs, emit};

macro_rules! out {
    ($($t:tt)*) => { emit(&format!($($t)*))? };
}

macro_rules! outln {
    ($($t:tt)*) => { emit(&format!("{}\n", format_args!($($t)*)))? };
}

pub mod args;
mod buckling;
mod design;
mod export;
mod harmonic;
mod modes;
mod statics;
mod studies;

pub use args::*;
use buckling::BucklingArgs;
use design::DesignArgs;
use export::ExportArgs;
use harmonic::HarmonicArgs;
use modes::ModesArgs;
use statics::{MeshInfoArgs, StaticArgs};
use studies::{BatchArgs, ConvergeArgs, MergeArgs, RunArgs, SweepArgs};

/// The command line: global options and one subcommand.
#[derive(Parser)]
#[command(
    name = "vibrofem",
    version,
    about = "Finite-element modal and stiffness analysis for vibrating machines"
)]
pub struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
    /// Worker threads (default: all cores).
    #[arg(long, global = true)]
    threads: Option<usize>,
    /// Progress and timing messages on stderr (-v: phases, -vv: details).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
}

/// The subcommands.
#[derive(Subcommand)]
pub enum Cmd {
    /// The vibratory-table design chain (FE parts → two-mass model → checks); built-in paper
    /// design when no file is given.
    Design(DesignArgs),
    /// Natural frequencies and mode shapes of a solid mesh (gmsh MSH 2.2 or 4.1).
    Modes(ModesArgs),
    /// Linear buckling: the lowest positive load factors of a static load case and their shapes.
    Buckling(BucklingArgs),
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
    /// The machines of the registry (`crank-drive`, `autobalancer`, `balancer-data`), one
    /// subcommand each.
    #[command(flatten)]
    Machine(crate::app::machines::MachineCommand),
}

pub(crate) fn parse_bytes(s: &str) -> Result<u64> {
    let t = s.trim();
    let (num, mult) = match t.chars().last() {
        Some('G' | 'g') => (&t[..t.len() - 1], 1u64 << 30),
        Some('M' | 'm') => (&t[..t.len() - 1], 1u64 << 20),
        Some('K' | 'k') => (&t[..t.len() - 1], 1u64 << 10),
        _ => (t, 1),
    };
    let v: f64 = num.parse().map_err(|_| {
        Error::option(
            "--max-memory",
            format!("--max-memory: cannot read '{s}' (e.g. 8G, 500M)"),
        )
    })?;
    if !(v > 0.0) {
        return Err(Error::option(
            "--max-memory",
            format!("--max-memory must be positive, got '{s}'"),
        ));
    }
    Ok((v * mult as f64) as u64)
}

/// The fill-reducing ordering named by `--ordering`.
fn ordering(s: &str) -> Result<Ordering> {
    match s {
        "metis" => Ok(Ordering::Metis),
        "amd" => Ok(Ordering::Amd),
        o => Err(Error::option(
            "--ordering",
            format!("--ordering: unknown '{o}' (use metis or amd)"),
        )),
    }
}

/// Parse the command line, run the command, map its result to the documented exit code.
pub fn main() -> ExitCode {
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
        Cmd::Modes(a) => modes::run(a),
        Cmd::Buckling(a) => buckling::run(a),
        Cmd::Design(a) => design::design_cmd(a),
        Cmd::Static(a) => statics::static_cmd(a),
        Cmd::MeshInfo(a) => statics::mesh_info(a),
        Cmd::Export(a) => export::export_cmd(a),
        Cmd::Harmonic(a) => harmonic::harmonic_cmd(a),
        Cmd::Run(a) => studies::run_cmd(a),
        Cmd::Batch(a) => studies::batch_cmd(a),
        Cmd::Sweep(a) => studies::sweep_cmd(a),
        Cmd::Converge(a) => studies::converge_cmd(a),
        Cmd::Merge(a) => studies::merge_cmd(a),
        Cmd::Machine(m) => m.run(),
    };
    match r {
        Ok(code) => ExitCode::from(code as u8),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
