#!/usr/bin/env python3
"""Backward errors of the low-memory path's pairs, recomputed from the matrices on disk with the
direct path's definition (src/linalg/eigen.rs, `backward_errors`):

    η = ‖Kx − λMx‖ / (‖|K||x|‖ + |λ| ‖|M||x|‖)      (|K|: K with its entries' magnitudes)

    /usr/bin/python3 validation/lowmem_check.py DIR

DIR holds K.petsc, M.petsc (PETSc binary AIJ, as `vibrofem export` writes them) and the engine's
lambda.bin, vectors.bin. Reads the matrices by memory map in row chunks (numpy only, no PETSc), so
it checks a 1M-DOF run in about 1 GiB. Prints one JSON line: the largest η, every η, and the
M-orthonormality error max|XᵀMX − I|.
"""
import json
import os
import sys

import numpy as np

CHUNK = 1 << 20  # nonzeros per chunk


def petsc_aij(path: str):
    """(row pointer, column indices, values) of a PETSc binary AIJ matrix, memory-mapped."""
    head = np.fromfile(path, dtype=">i4", count=4)
    if head[0] != 1211216:
        raise SystemExit(f"{path}: not a PETSc binary matrix (class id {head[0]})")
    n, nnz = int(head[1]), int(head[3])
    lens = np.fromfile(path, dtype=">i4", count=n, offset=16)
    ptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(lens, out=ptr[1:])
    cols = np.memmap(path, dtype=">i4", mode="r", offset=16 + 4 * n, shape=(nnz,))
    vals = np.memmap(path, dtype=">f8", mode="r", offset=16 + 4 * n + 4 * nnz, shape=(nnz,))
    return ptr, cols, vals


def products(path: str, X: np.ndarray):
    """A·X and |A|·|X| for the matrix in `path`, by row chunks."""
    ptr, cols, vals = petsc_aij(path)
    n = len(ptr) - 1
    AX, AbsX = np.zeros_like(X), np.zeros_like(X)
    absX = np.abs(X)
    r0 = 0
    while r0 < n:
        r1 = int(np.searchsorted(ptr, ptr[r0] + CHUNK, side="right")) - 1
        r1 = min(max(r1, r0 + 1), n)
        a, b = ptr[r0], ptr[r1]
        c = np.asarray(cols[a:b], dtype=np.int64)
        v = np.asarray(vals[a:b], dtype=np.float64)
        starts = (ptr[r0:r1] - a).astype(np.int64)
        nonempty = ptr[r0 + 1:r1 + 1] > ptr[r0:r1]
        rows = np.arange(r0, r1)[nonempty]
        if len(rows):
            AX[rows] = np.add.reduceat(v[:, None] * X[c], starts[nonempty], axis=0)
            AbsX[rows] = np.add.reduceat(np.abs(v)[:, None] * absX[c], starts[nonempty], axis=0)
        r0 = r1
    return AX, AbsX


def check(wd: str) -> dict:
    lam = np.fromfile(os.path.join(wd, "lambda.bin"), dtype="<f8")
    m = len(lam)
    X = np.fromfile(os.path.join(wd, "vectors.bin"), dtype="<f8").reshape(m, -1).T.copy()
    KX, KabsX = products(os.path.join(wd, "K.petsc"), X)
    MX, MabsX = products(os.path.join(wd, "M.petsc"), X)
    r = np.linalg.norm(KX - MX * lam, axis=0)
    eta = r / (np.linalg.norm(KabsX, axis=0) + np.abs(lam) * np.linalg.norm(MabsX, axis=0))
    G = X.T @ MX
    d = 1.0 / np.sqrt(np.diag(G))
    orth = float(np.max(np.abs(G * np.outer(d, d) - np.eye(m))))
    return {"max_backward_error": float(eta.max()), "backward_errors": eta.tolist(), "m_orthonormality": orth}


if __name__ == "__main__":
    print(json.dumps(check(sys.argv[1])))
