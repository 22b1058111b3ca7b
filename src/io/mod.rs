//! Readers and writers: gmsh MSH (4.1 and 2.2, ASCII and binary), VTU, JSON.
//!
//! vibrofem keeps gmsh's node ordering internally; writers that need another convention
//! (VTK) permute at output, with the permutation tables kept next to the writer
//! ([`vtk::gmsh_to_vtk`]).

pub mod gmsh;
pub mod matrix;
pub mod msh_out;
pub mod vtk;

/// A float in the shortest form that reads back exactly: plain decimals for ordinary
/// magnitudes, exponent form for very small or large ones (Rust's plain form of `1e-300`
/// would have 300 zeros).
pub(crate) fn fmt_f64(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (1e-4..1e15).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `x` with `sig` significant digits in plain or exponent form, whichever reads better
/// (`184.2`, `4.99e6`, `0.000977`).
pub fn fmt_sig(x: f64, sig: usize) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor() as i32;
    if (-4..6).contains(&e) {
        let decimals = (sig as i32 - 1 - e).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.prec$e}", prec = sig.saturating_sub(1))
    }
}

/// A byte count in GiB with three significant digits, and in MiB or KiB as well when below a
/// GiB (so a small limit never prints as "0.00 GiB").
pub fn fmt_bytes(b: u64) -> String {
    let gib = b as f64 / 1073741824.0;
    if b >= 1 << 30 {
        format!("{} GiB", fmt_sig(gib, 3))
    } else if b >= 1 << 20 {
        format!("{} GiB ({} MiB)", fmt_sig(gib, 3), fmt_sig(b as f64 / 1048576.0, 3))
    } else {
        format!("{} GiB ({} KiB)", fmt_sig(gib, 3), fmt_sig(b as f64 / 1024.0, 3))
    }
}

/// Write mode shapes (3 translation components per node, node-major, one vector per mode) as
/// VTU point fields `mode_N` (ParaView) and/or gmsh `$NodeData` views named `mode N (f Hz)`.
/// `None` skips a format. Returns the files written.
pub fn write_mode_shapes(
    mesh: &crate::mesh::Mesh,
    shapes: &[Vec<f64>],
    frequencies_hz: &[f64],
    vtu: Option<&std::path::Path>,
    msh: Option<&std::path::Path>,
) -> crate::Result<Vec<std::path::PathBuf>> {
    let mut written = Vec::new();
    if let Some(p) = vtu {
        let fields: Vec<vtk::PointField> = shapes
            .iter()
            .enumerate()
            .map(|(i, s)| vtk::PointField::mode(i + 1, s))
            .collect();
        vtk::write_vtu(p, mesh, &fields)?;
        written.push(p.to_path_buf());
    }
    if let Some(p) = msh {
        let views: Vec<msh_out::NodeView> = shapes
            .iter()
            .zip(frequencies_hz)
            .enumerate()
            .map(|(i, (s, &f))| msh_out::NodeView {
                name: format!("mode {} ({} Hz)", i + 1, fmt_sig(f, 6)),
                step: i,
                time: f,
                n_comp: 3,
                data: s,
            })
            .collect();
        msh_out::write_msh_views(p, mesh, &views)?;
        written.push(p.to_path_buf());
    }
    Ok(written)
}
