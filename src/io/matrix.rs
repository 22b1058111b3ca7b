//! Sparse matrices and DOF maps for other solvers: PETSc binary, Matrix Market, CSV.
//!
//! K and M are written over the free DOFs (equation numbers, the rows of [`crate::dof::DofMap`])
//! with both triangles in PETSc's AIJ binary format (what `MatLoad` reads on any number of MPI
//! ranks) and with the lower triangle in Matrix Market's `symmetric` coordinate format (what
//! `scipy.io.mmread` reads). Values are written so that they read back exactly.

use crate::dof::{COMPONENT_NAMES, DofMap};
use crate::linalg::sparse::SymMatrix;
use crate::{Error, Result};
use std::io::{BufWriter, Write};
use std::path::Path;

/// PETSc's class id of a matrix in its binary format (`MAT_FILE_CLASSID`).
pub const PETSC_MAT_CLASSID: i32 = 1211216;

fn create(path: &Path) -> Result<BufWriter<std::fs::File>> {
    let f = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    Ok(BufWriter::with_capacity(1 << 20, f))
}

fn int32(what: &str, path: &Path, v: usize) -> Result<[u8; 4]> {
    i32::try_from(v).map(i32::to_be_bytes).map_err(|_| {
        Error::InvalidInput(format!(
            "{}: {what} {v} exceeds PETSc's 32-bit indices (use a PETSc built with 64-bit indices and Matrix Market)",
            path.display()
        ))
    })
}

/// Write a symmetric matrix (both triangles) in PETSc's binary AIJ format: big-endian header
/// `[classid, rows, cols, nnz]`, the row lengths, the column indices and the values (f64).
/// Rows of a symmetric matrix are its columns, so the CSC arrays are written as they are.
pub fn write_petsc(path: &Path, a: &SymMatrix) -> Result<()> {
    let p = &a.pattern;
    let mut w = create(path)?;
    let io = |e| Error::io(path, e);
    let mut head = Vec::with_capacity(16);
    head.extend_from_slice(&PETSC_MAT_CLASSID.to_be_bytes());
    head.extend_from_slice(&int32("dimension", path, p.n)?);
    head.extend_from_slice(&int32("dimension", path, p.n)?);
    head.extend_from_slice(&int32("entry count", path, p.nnz())?);
    w.write_all(&head).map_err(io)?;
    for j in 0..p.n {
        w.write_all(&int32("row length", path, p.col_ptr[j + 1] - p.col_ptr[j])?)
            .map_err(io)?;
    }
    for &i in &p.row_idx {
        w.write_all(&int32("index", path, i as usize)?).map_err(io)?;
    }
    for v in &a.values {
        w.write_all(&v.to_be_bytes()).map_err(io)?;
    }
    w.flush().map_err(io)
}

/// Write the lower triangle of a symmetric matrix as Matrix Market `coordinate real symmetric`
/// (1-based indices; values in the shortest form that reads back exactly).
pub fn write_matrix_market(path: &Path, a: &SymMatrix, comment: &str) -> Result<()> {
    let p = &a.pattern;
    let mut w = create(path)?;
    let io = |e| Error::io(path, e);
    let lower: usize = (0..p.n)
        .map(|j| {
            p.row_idx[p.col_ptr[j]..p.col_ptr[j + 1]]
                .iter()
                .filter(|&&i| i as usize >= j)
                .count()
        })
        .sum();
    writeln!(w, "%%MatrixMarket matrix coordinate real symmetric").map_err(io)?;
    for line in comment.lines() {
        writeln!(w, "% {line}").map_err(io)?;
    }
    writeln!(w, "{} {} {}", p.n, p.n, lower).map_err(io)?;
    for j in 0..p.n {
        for q in p.col_ptr[j]..p.col_ptr[j + 1] {
            let i = p.row_idx[q] as usize;
            if i >= j {
                writeln!(w, "{} {} {:e}", i + 1, j + 1, a.values[q]).map_err(io)?;
            }
        }
    }
    w.flush().map_err(io)
}

/// Write the DOF map as CSV: `equation,node,node_tag,component,x,y,z` for each free DOF
/// (equation and node 0-based; `node_tag` is the mesh file's tag, empty for the reference
/// nodes of couplings, which follow the mesh nodes; coordinates in m).
pub fn write_dof_map(path: &Path, dofs: &DofMap, nodes: &[[f64; 3]], node_tags: &[u64]) -> Result<()> {
    let mut w = create(path)?;
    let io = |e| Error::io(path, e);
    writeln!(w, "equation,node,node_tag,component,x,y,z").map_err(io)?;
    for eq in 0..dofs.n_free {
        let (node, c) = dofs.node_comp_of(eq);
        let tag = node_tags.get(node).map(|t| t.to_string()).unwrap_or_default();
        let x = nodes[node];
        writeln!(
            w,
            "{eq},{node},{tag},{},{},{},{}",
            COMPONENT_NAMES[c],
            super::fmt_f64(x[0]),
            super::fmt_f64(x[1]),
            super::fmt_f64(x[2])
        )
        .map_err(io)?;
    }
    w.flush().map_err(io)
}

/// Read a file of little-endian f64 values (what numpy's `tofile` writes on x86 and ARM).
pub fn read_f64_le(path: &Path) -> Result<Vec<f64>> {
    let b = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if b.len() % 8 != 0 {
        return Err(Error::param(
            "path",
            format!(
                "{}: {} bytes is not a whole number of f64 values",
                path.display(),
                b.len()
            ),
        ));
    }
    Ok(b.chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect())
}
