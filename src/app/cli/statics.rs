//! `vibrofem static` and `vibrofem mesh-info`.

use super::{check_outputs, emit};
use crate::app::cli::args::{LoadArgs, ModelArgs, length_scale};
use crate::material::Material;
use crate::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct StaticArgs {
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

pub fn static_cmd(a: &StaticArgs) -> Result<i32> {
    let mut spec = a.model.spec()?;
    let loads = a.loads.apply(&mut spec)?;
    check_outputs(
        &[("--vtu", a.vtu.as_deref()), ("--msh-out", a.msh_out.as_deref())],
        None,
        &[("input mesh", std::path::Path::new(&a.mesh))],
    )?;
    let mesh = crate::input::source::load(&a.mesh, length_scale(&a.model.length_unit)?)?;
    let opts = crate::analysis::statics::StaticOptions {
        spec,
        cases: vec![loads],
    };
    let run = crate::analysis::statics::run_static(&mesh, &a.mesh, &opts)?;
    let stresses = crate::app::report::case_stresses(&mesh, &run)?;
    let report = crate::app::report::static_report(&mesh, &a.mesh, &run, &stresses)?;
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&report).map_err(|e| Error::output("JSON", e))?
        );
    } else {
        out!("{}", crate::app::report::static_text(&report));
    }
    if a.vtu.is_some() || a.msh_out.is_some() {
        crate::app::report::write_static_fields(&mesh, &run, &stresses, a.vtu.as_deref(), a.msh_out.as_deref())?;
    }
    // The model's notes and the stress recovery's (beams whose stresses are not recovered).
    for n in &report.notes {
        eprintln!("note: {n}");
    }
    Ok(0)
}

#[derive(clap::Args)]
pub struct MeshInfoArgs {
    /// gmsh mesh file, or a generated box `box:LX,LY,LZ:NX,NY,NZ:KIND`.
    mesh: String,
    /// Length unit of the mesh coordinates: m (default), cm or mm.
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

pub fn mesh_info(a: &MeshInfoArgs) -> Result<i32> {
    let mesh = crate::input::source::load(&a.mesh, length_scale(&a.length_unit)?)?;
    let mat = Material::parse(&a.material)?;
    mat.validate("--material")?;
    let mut info = crate::app::report::mesh_info(&mesh, &a.mesh, &mat)?;
    for n in &mesh.notes {
        eprintln!("note: {n}");
    }
    if a.shell.is_empty() && a.beam.is_empty() && !mesh.blocks.iter().any(|b| b.kind.dim() == 3) {
        eprintln!(
            "note: no volume elements: the volume and mass count solids only; give --shell GROUP=THICKNESS \
             or --beam for the surface and line parts"
        );
    }
    if !a.shell.is_empty() || !a.beam.is_empty() {
        // Volume and mass of the model the parts describe (shells t·A, beams A·L, solids).
        let opts = crate::input::options::ModelOptions {
            material: a.material.clone(),
            shell: a.shell.clone(),
            beam: a.beam.clone(),
            ..Default::default()
        };
        let model = crate::model::Model::build(&mesh, &opts.spec()?, &a.mesh)?;
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
        out!("{}", crate::app::report::mesh_info_text(&info));
    }
    Ok(0)
}
