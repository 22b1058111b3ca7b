//! Readers and writers: gmsh MSH (4.1 and 2.2, ASCII and binary), VTU, JSON.
//!
//! vibrofem keeps gmsh's node ordering internally; writers that need another convention
//! (VTK) permute at output, with the permutation tables kept next to the writer
//! ([`vtk::gmsh_to_vtk`]).

pub mod gmsh;
pub mod matrix;
pub mod msh_out;
pub mod vtk;

pub use crate::util::fmt::{fmt_bytes, fmt_fixed, fmt_plain, fmt_short, fmt_sig};

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

/// Write mode shapes (3 translation components per node, node-major, one vector per mode) as
/// VTU point fields `mode_N` (ParaView) on the model's `cells` (the mesh's of its highest
/// dimension if `None`) and/or gmsh `$NodeData` views named `mode N (f Hz)`, each a view of
/// its own at time step 0. `rotations[i]`, where given, is mode i's nodal rotations (3 per
/// node, rad): `mode_N_rotation` and `mode N (f Hz) rotation`. `values` (named, e.g.
/// `frequencies_hz`, or a buckling run's `load_factors`) go into the VTU's field data and the
/// views' time values. `None` skips a format. Returns the files written.
pub fn write_mode_shapes(
    mesh: &crate::mesh::Mesh,
    cells: Option<&[crate::mesh::CellBlock]>,
    shapes: &[Vec<f64>],
    rotations: &[Option<Vec<f64>>],
    (values_name, values): (&str, &[f64]),
    vtu: Option<&std::path::Path>,
    msh: Option<&std::path::Path>,
) -> crate::Result<Vec<std::path::PathBuf>> {
    let mut written = Vec::new();
    if let Some(p) = vtu {
        let mut fields: Vec<vtk::PointField> = Vec::new();
        for (i, s) in shapes.iter().enumerate() {
            fields.push(vtk::PointField::mode(i + 1, s));
            if let Some(Some(r)) = rotations.get(i) {
                fields.push(vtk::PointField::new(format!("mode_{}_rotation", i + 1), 3, r));
            }
        }
        vtk::write_vtu_with(p, mesh, cells, &fields, &[(values_name, values)])?;
        written.push(p.to_path_buf());
    }
    if let Some(p) = msh {
        let mut views: Vec<msh_out::NodeView> = Vec::new();
        for (i, (s, &f)) in shapes.iter().zip(values).enumerate() {
            // A view of its own per mode, at step 0 (at step i it had i empty steps before
            // it, and gmsh showed the first, empty one).
            let name = format!("mode {} ({} Hz)", i + 1, fmt_sig(f, 6));
            let rotation = rotations.get(i).and_then(|r| r.as_deref());
            for (name, data) in [
                (name.clone(), Some(s.as_slice())),
                (format!("{name} rotation"), rotation),
            ] {
                if let Some(data) = data {
                    views.push(msh_out::NodeView {
                        name,
                        step: 0,
                        time: f,
                        n_comp: 3,
                        data,
                    });
                }
            }
        }
        msh_out::write_msh_views(p, mesh, &views)?;
        written.push(p.to_path_buf());
    }
    Ok(written)
}

/// Check, before a run, that `path` can be written as an output file: its folder exists (it
/// is created if missing) and a file can be created there. A file that did not exist is not
/// left behind. The error names the path ([`Error::Io`], exit 1), so a bad `--vtu` or `-o`
/// is reported in a second rather than after the whole analysis.
pub fn check_writable_file(path: &std::path::Path) -> crate::Result<()> {
    if path.is_dir() {
        return Err(crate::Error::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::IsADirectory,
                "is a folder, an output file was expected",
            ),
        ));
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        crate::io::create_dir(dir)?;
    }
    let existed = path.exists();
    std::fs::OpenOptions::new()
        .append(true)
        .create(true)
        .open(path)
        .map_err(|e| crate::Error::io(path, e))?;
    if !existed {
        let _ = std::fs::remove_file(path);
    }
    Ok(())
}

/// Create the folder `dir` and its parents (as `std::fs::create_dir_all`); where a path
/// component is a file, the error says which ("File exists" named neither the file nor why).
pub fn create_dir(dir: &std::path::Path) -> crate::Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| {
        match dir
            .ancestors()
            .find(|a| !a.as_os_str().is_empty() && a.exists() && !a.is_dir())
        {
            Some(file) => crate::Error::io(
                dir,
                std::io::Error::new(
                    e.kind(),
                    if file == dir {
                        "is a file, not a folder: a folder for the outputs was expected".to_string()
                    } else {
                        format!("'{}' in the path is a file, not a folder", file.display())
                    },
                ),
            ),
            None => crate::Error::io(dir, e),
        }
    })
}

/// Check, before a run, that `dir` can take output files: created if missing, and a probe
/// file written and removed in it. The error names the folder ([`Error::Io`], exit 1).
pub fn check_writable_dir(dir: &std::path::Path) -> crate::Result<()> {
    crate::io::create_dir(dir)?;
    let probe = dir.join(format!(".vibrofem-write-check-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(|e| crate::Error::io(dir, e))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}
