//! `vibrofem export`: K, M and the DOF map for other solvers, and the SLEPc job.

use super::emit;
use crate::analysis::modal::ModalTarget;
use crate::app::cli::args::{ModelArgs, length_scale};
use crate::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct ExportArgs {
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

pub fn export_cmd(a: &ExportArgs) -> Result<i32> {
    use crate::app::engines::export;
    let formats = export::Formats::parse(&a.format)?;
    // The SLEPc job beside the PETSc matrices, its numbers checked before any work (whatever
    // the format: a bad value is not passed over silently).
    let target = match &a.band {
        Some(b) => ModalTarget::Band(b[0], b[1]),
        None => ModalTarget::Modes(a.modes),
    };
    let params = crate::analysis::modal::ModalParams {
        target,
        shift_hz: a.shift,
        ..Default::default()
    };
    crate::analysis::modal::check_params(&params)?;
    if formats == export::Formats::MatrixMarket {
        if let Some(o) = [("--band", a.band.is_some()), ("--shift", a.shift.is_some())]
            .iter()
            .find(|o| o.1)
        {
            return Err(Error::option(
                o.0,
                format!(
                    "{} sets the SLEPc job written beside the PETSc matrices; --format mtx writes none \
                     (give --format petsc or both)",
                    o.0
                ),
            ));
        }
    }
    let job = (formats != export::Formats::MatrixMarket).then_some(params);
    let spec = a.model.spec()?;
    super::check_outputs(
        &[],
        Some(("--out", &a.out)),
        &[("input mesh", std::path::Path::new(&a.mesh))],
    )?;
    let mesh = crate::input::source::load(&a.mesh, length_scale(&a.model.length_unit)?)?;
    let model = crate::model::Model::build(&mesh, &spec, &a.mesh)?;
    let sys = crate::system::System::assemble_only(model, &a.mesh)?;
    let (summary, files) = export::export(&sys, &a.out, formats, job.as_ref())?;
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
            crate::io::fmt_sig(summary.mass_kg, 4)
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
