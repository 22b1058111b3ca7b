//! What every command writes: standard output through one checked writer, and output files
//! refused before any work when they collide with each other or with an input.

use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// Write to stdout. A closed pipe (`vibrofem … | head`) ends the program quietly with 141, as
/// a Unix tool killed by SIGPIPE; any other failure (a full disk) is an [`Error::Output`].
pub fn emit(s: &str) -> Result<()> {
    use std::io::Write;
    let mut o = std::io::stdout().lock();
    o.write_all(s.as_bytes()).and_then(|()| o.flush()).map_err(|e| {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(141);
        }
        Error::output("standard output", e)
    })
}

/// The extension of the format an output option writes (`--vtu` a VTU file), if it has one.
fn format_extension(option: &str) -> Option<&'static str> {
    match option {
        "--vtu" => Some("vtu"),
        "--msh-out" => Some("msh"),
        "--plot" => Some("svg"),
        _ => None,
    }
}

/// Refuse, before any work (named, exit 1): an output file whose name ends otherwise than its
/// format (`--vtu x.msh`), two outputs that are the same file, an output (file
/// or folder) that is one of the inputs, and outputs that cannot be written. `files` and `dir`
/// pair each output with the option that names it, `inputs` each input with what it is (`input
/// mesh`, `scene file`); an input that is no existing file or folder (a generator such as
/// `box:…`) is skipped. Paths are compared canonically (symbolic links, `..`, hard links); a
/// file that does not exist yet by its folder's canonical path and its name.
pub fn check_outputs(
    files: &[(&str, Option<&Path>)],
    dir: Option<(&str, &Path)>,
    inputs: &[(&str, &Path)],
) -> Result<()> {
    let outs: Vec<(&str, &Path, PathBuf)> = files
        .iter()
        .filter_map(|&(o, p)| p.map(|p| (o, p, canonical(p))))
        .chain(dir.map(|(o, p)| (o, p, canonical(p))))
        .collect();
    for (i, (oi, pi, ci)) in outs.iter().enumerate() {
        for (oj, _, cj) in &outs[..i] {
            if same_file(ci, cj) {
                return Err(Error::option(
                    *oi,
                    format!(
                        "{oj} and {oi} name the same file '{}': one would overwrite the other; give each output its \
                         own",
                        pi.display()
                    ),
                ));
            }
        }
        for (what, input) in inputs {
            if input.exists() && same_file(ci, &canonical(input)) {
                return Err(Error::option(
                    *oi,
                    format!(
                        "{oi} '{}' is the {what} ('{}'): writing it would overwrite the input; give another path",
                        pi.display(),
                        input.display()
                    ),
                ));
            }
        }
    }
    // A file's format follows its option, whatever its name: a VTU file named `.msh` opens in
    // neither ParaView nor gmsh by its name, so the name must say the format. A device or a
    // pipe (`/dev/stdout`) has no name to say it; a folder gets its own error below.
    for &(o, p) in files {
        if let (Some(p), Some(ext)) = (p.filter(|p| !p.exists() || p.is_file()), format_extension(o)) {
            let given = p.extension().and_then(|e| e.to_str()).unwrap_or("");
            if !given.eq_ignore_ascii_case(ext) {
                return Err(Error::option(
                    o,
                    format!(
                        "{o} writes a .{ext} file, but '{}' {}: name it ….{ext}",
                        p.display(),
                        if given.is_empty() {
                            "has no extension".to_string()
                        } else {
                            format!("ends in '.{given}'")
                        }
                    ),
                ));
            }
        }
    }
    for f in files.iter().filter_map(|f| f.1) {
        crate::io::check_writable_file(f)?;
    }
    if let Some((_, d)) = dir {
        crate::io::check_writable_dir(d)?;
    }
    Ok(())
}

/// `p` made absolute with its longest existing ancestor canonicalised (symbolic links resolved)
/// and the rest appended with `.` and `..` applied.
fn canonical(p: &Path) -> PathBuf {
    use std::path::Component;
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let comps: Vec<Component> = abs.components().collect();
    for k in (1..=comps.len()).rev() {
        let head: PathBuf = comps[..k].iter().collect();
        if let Ok(mut out) = std::fs::canonicalize(&head) {
            for c in &comps[k..] {
                match c {
                    Component::ParentDir => {
                        out.pop();
                    }
                    Component::CurDir => {}
                    c => out.push(c.as_os_str()),
                }
            }
            return out;
        }
    }
    abs
}

/// Two canonical paths naming one file: equal, or (Unix) the same device and inode.
fn same_file(a: &Path, b: &Path) -> bool {
    if a == b {
        return true;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
    }
    false
}

/// Mode or buckling shapes (`shapes`, with their `vectors` over the free DOFs) as VTU and/or
/// gmsh files ([`crate::io::write_mode_shapes`]) drawn on the solved `model`'s cells, with the
/// shells' and beams' rotations beside the translations; without a model, on the mesh's cells of
/// its highest dimension and translations only. Returns the files written.
pub fn write_shapes(
    mesh: &crate::mesh::Mesh,
    model: Option<&crate::model::Model>,
    (shapes, vectors): (&[Vec<f64>], faer::MatRef<'_, f64>),
    values: (&str, &[f64]),
    vtu: Option<&Path>,
    msh: Option<&Path>,
) -> Result<Vec<PathBuf>> {
    if vtu.is_none() && msh.is_none() {
        return Ok(vec![]);
    }
    let cells = model.map(|m| m.cell_blocks());
    let rotations = model.map_or(vec![], |m| m.node_rotations(vectors, shapes));
    crate::io::write_mode_shapes(mesh, cells.as_deref(), shapes, &rotations, values, vtu, msh)
}
