//! The chain's figures and mode shapes, written into the report's folder: the amplitude–
//! frequency curves, the start-up transient, the magnet force, the work table's modes (VTU,
//! MSH and a plan view of the first elastic one) and the 3D machine's response.

use super::file::Design;
use super::machine::{MachineResult, write_amplitude_svg, write_amplitude_vtu};
use crate::analysis::modal::ModalRun;
use crate::app::dynamics::electromagnet::RectifiedDrive;
use crate::app::dynamics::plot::{write_electromagnet_svg, write_frequency_response_svg, write_transient_svg};
use crate::app::dynamics::transient::Transient;
use crate::app::dynamics::two_mass::TwoMass;
use crate::mesh::Mesh;
use crate::{Error, Result};
use std::path::Path;

/// The figures the report shows, with their captions (file names relative to the folder). The
/// two-mass curves, the start-up and the magnet force are the paper's chain on this design's
/// masses (the paper's rectified force law, the leaves tuned on the two-mass model), to compare
/// with the paper's figures; a design's own law and 3D machine are in its tables, and the
/// captions say which is which (a flux-law design's plots showed 1256 N and X1 = 0.1757 mm
/// beside its report's 1480 N and 0.1580 mm, without a word).
pub const FIGURES: [(&str, &str); 5] = [
    (
        "work_surface_amplitude.svg",
        "Work-surface vertical amplitude at the excitation (3D machine)",
    ),
    (
        "amplitude_frequency.svg",
        "Amplitude–frequency and phase curves with the operating point: the paper's chain on this design's \
         masses (its rectified force law, leaves tuned on the two-mass model), as in the paper's figures",
    ),
    (
        "transient.svg",
        "Start-up transient: the paper's chain on this design's masses (its rectified force law); this design's \
         own start-up is in the start-up rows above",
    ),
    (
        "electromagnet.svg",
        "Electromagnet force and its harmonics: the paper's rectified law (this design's law is drive.force_law)",
    ),
    ("table_mode7.svg", "Work-table mode 7"),
];

/// Write every figure and mode-shape file of a run into `dir` (created if missing).
#[allow(clippy::too_many_arguments)]
pub fn write_all(
    dir: &Path,
    d: &Design,
    model: &TwoMass,
    drive: &RectifiedDrive,
    tr: &Transient,
    table_run: &ModalRun,
    table_mesh: &Mesh,
    mach: &MachineResult,
) -> Result<()> {
    crate::io::create_dir(dir)?;
    write_frequency_response_svg(
        dir.join("amplitude_frequency.svg"),
        model,
        1.0,
        2.0 * d.excitation_hz,
        4000,
        drive.harmonic_amplitude(),
        Some(d.excitation_hz),
    )?;
    write_transient_svg(dir.join("transient.svg"), tr, None)?;
    write_electromagnet_svg(dir.join("electromagnet.svg"), drive, 8, 2.0)?;
    crate::io::write_mode_shapes(
        table_mesh,
        None,
        &table_run.shapes,
        &[],
        ("frequencies_hz", &table_run.report.frequencies_hz),
        Some(&dir.join("table_modes.vtu")),
        Some(&dir.join("table_modes.msh")),
    )?;
    write_amplitude_svg(&dir.join("work_surface_amplitude.svg"), mach, d.excitation_hz)?;
    write_amplitude_vtu(&dir.join("machine_response.vtu"), mach)?;
    if let Some(k) = table_run.report.modes.iter().position(|m| m.kind == "elastic") {
        write_mode_svg(
            &dir.join("table_mode7.svg"),
            table_mesh,
            &table_run.shapes[k],
            table_run.report.frequencies_hz[k],
        )?;
    }
    Ok(())
}

/// A plan view of a mode shape: the top-plate nodes coloured by the vertical displacement.
fn write_mode_svg(path: &Path, mesh: &Mesh, shape: &[f64], f: f64) -> Result<()> {
    use plotters::prelude::*;
    let top = mesh.group("top_plate")?;
    let nodes = mesh.group_nodes(top);
    let (lo, hi) = mesh.bounding_box();
    let umax = nodes
        .iter()
        .map(|&a| shape[3 * a as usize + 2].abs())
        .fold(0.0f64, f64::max)
        .max(1e-300);
    let root = SVGBackend::new(path, (900, 520)).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| Error::output(path.display(), format!("plotting failed: {e}"));
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("work table, first elastic mode: {f:.2} Hz (top plate, vertical displacement)"),
            ("sans-serif", 18),
        )
        .margin(15)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(lo[0]..hi[0], lo[1]..hi[1])
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("x [m]")
        .y_desc("y [m]")
        .draw()
        .map_err(|e| err(&e))?;
    chart
        .draw_series(nodes.iter().map(|&a| {
            let x = mesh.nodes[a as usize];
            let v = shape[3 * a as usize + 2] / umax;
            let c = if v >= 0.0 {
                RGBColor(255, (255.0 * (1.0 - v)) as u8, (255.0 * (1.0 - v)) as u8)
            } else {
                RGBColor((255.0 * (1.0 + v)) as u8, (255.0 * (1.0 + v)) as u8, 255)
            };
            Circle::new((x[0], x[1]), 4, c.filled())
        }))
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
