"""Low-memory engine of vibrofem: run under mpirun by `vibrofem modes --solver iterative` on a
folder it wrote (K.petsc, M.petsc, R.bin, params.json).

    mpirun -n N python3 slepc_lowmem.py DIR

The lowest modes of K x = λ M x without an in-core factorisation of K (docs/lowmem.md).

1. The rigid-body motions R (n × 6, from the node coordinates, written by vibrofem in R.bin) are
   tried on K by Rayleigh–Ritz: the combinations K annihilates (a free body: six; a body on
   partial supports: fewer) are eigenpairs at λ ≈ 0, returned as such and deflated.
2. A = K − σM with σ < 0 below the spectrum (SPD; in K's storage, no copy; eigenvalues λ − σ).
   The iterative methods precondition it with PETSc's smoothed-aggregation multigrid (GAMG),
   R as its near-null space and the nodes' block size 3; one hierarchy serves the whole run.
3. The remaining modes by `method` (params.json): "lobpcg" (block LOBPCG here, one multigrid
   cycle per vector and iteration, A and M applied once per new vector: lobpcg()),
   "slepc-lobpcg" (SLEPc's LOBPCG, the same preconditioner; ~3.5× slower, kept for comparison),
   "ks-cg" (SLEPc's Krylov–Schur, shift-and-invert whose inverse is CG + GAMG to `inner_rtol`)
   or "ks-mumps" (Krylov–Schur, shift-and-invert with MUMPS's out-of-core LDLᵀ of A, whose
   inertia also checks that σ is below the spectrum).
4. Refinement: block inverse iteration (A⁻¹M by the same inverse) with Rayleigh–Ritz until
   every kept pair's backward error is below `refine_tol`.
5. Completeness: MUMPS's inertia of K − sM above the last mode (out-of-core factor, ICNTL(22))
   when `sturm_budget` bytes are given; otherwise the count is skipped and slepc.json says why.

Every failure (no convergence, a mode at λ ≈ 0 that is not deflated, a refinement that does not
reach its bar, a shift that is not below the spectrum) writes {"error": …} to slepc.json and
exits with status 3: never a silent unconverged answer. Rank 0 writes lambda.bin, vectors.bin
and slepc.json in the layout of slepc_modes.py, with the peak resident memory after each phase.
"""
import ctypes
import json
import os
import resource
import sys
import time

import numpy as np
import slepc4py

slepc4py.init(sys.argv[:1])
from petsc4py import PETSc  # noqa: E402
from slepc4py import SLEPc  # noqa: E402

WD = sys.argv[1]
COMM = PETSc.COMM_WORLD
RANK = COMM.getRank()
with open(os.path.join(WD, "params.json")) as _f:
    P = json.load(_f)
OPTS = PETSc.Options()
for _k, _v in P.get("petsc_options", {}).items():
    OPTS[_k] = _v
PETSc.Log.begin()
TIMINGS: dict = {}
MEMORY: dict = {}
EVENTS = ("MatMult", "PCApply", "KSPSolve", "PCSetUp", "MatSolve", "MatCholFctrNum")


def peak_mb() -> float:
    """Peak resident memory of this rank so far, summed over ranks (MiB)."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    if COMM.getSize() == 1:
        return own
    # The sum over ranks through a PETSc vector (one entry per rank): no mpi4py needed.
    v = PETSc.Vec().createMPI((1, PETSc.DECIDE), comm=COMM)
    v.setValue(RANK, own)
    v.assemble()
    total = v.sum()
    v.destroy()
    return total


def trim() -> None:
    """Give the C heap's freed memory back to the system (glibc's malloc_trim): numpy's and
    PETSc's temporaries otherwise stay resident after they are freed."""
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


_LAST = [time.perf_counter()]


def progress(msg: str, every: float = 10.0) -> None:
    """A line `progress: msg` on rank 0's stderr (vibrofem shows it with the elapsed time), at
    most one per `every` seconds: long runs report, short ones stay quiet."""
    now = time.perf_counter()
    if RANK == 0 and now - _LAST[0] >= every:
        _LAST[0] = now
        print("progress: " + msg, file=sys.stderr, flush=True)


def mark(phase: str, t0: float) -> None:
    trim()
    TIMINGS[phase] = time.perf_counter() - t0
    MEMORY[phase] = peak_mb()
    progress(f"low-memory path: {phase} done in {TIMINGS[phase]:.1f} s (peak {MEMORY[phase]:.0f} MiB)")


def counts() -> dict:
    """How many times each PETSc operation ran so far (operator and preconditioner applications)."""
    return {e: PETSc.Log.Event(e).getPerfInfo()["count"] for e in EVENTS}


def fail(msg: str) -> None:
    if RANK == 0:
        with open(os.path.join(WD, "slepc.json"), "w") as fh:
            json.dump({"error": msg, "timings_s": TIMINGS, "memory_mib": MEMORY, "counts": counts()}, fh)
    PETSc.Sys.Print("error: " + msg, comm=COMM)
    sys.exit(3)


def load(name: str, mat_type=None, rows=None):
    """The matrix in file `name` (PETSc binary), its local rows `rows` (lo, hi) if given."""
    v = PETSc.Viewer().createBinary(os.path.join(WD, name), "r", comm=COMM)
    a = PETSc.Mat().create(comm=COMM)
    if rows is not None:
        n = int(np.fromfile(os.path.join(WD, name), dtype=">i4", count=2)[1])
        a.setSizes(((rows[1] - rows[0], n), (rows[1] - rows[0], n)), bsize=int(P.get("block_size", 1)))
    a.setType(mat_type or P.get("mat_type", "aij"))  # "sbaij": the upper triangle only (GAMG needs aij)
    a.load(v)
    v.destroy()
    a.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    return a


def products(A, X):
    out = []
    for x in X:
        y = A.createVecLeft()
        A.mult(x, y)
        out.append(y)
    return out


def combine(X, z):
    x = X[0].duplicate()
    x.set(0.0)
    x.maxpy(list(z), X)
    return x


def ritz(GA, GM):
    """Ritz values (ascending) and GM-orthonormal coefficients of the pencil (GA, GM)."""
    d = 1.0 / np.sqrt(np.diag(GM))
    Li = np.linalg.inv(np.linalg.cholesky(0.5 * (GM + GM.T) * np.outer(d, d)))
    H = Li @ (0.5 * (GA + GA.T) * np.outer(d, d)) @ Li.T
    theta, V = np.linalg.eigh(0.5 * (H + H.T))
    return theta, (Li.T @ V) * d[:, None]


def rayleigh_ritz(K, M, X):
    """Ritz values (ascending) and coefficients of span(X) for K, M."""
    KX, MX = products(K, X), products(M, X)
    Kr = np.array([[x.dot(y) for y in KX] for x in X])
    Mr = np.array([[x.dot(y) for y in MX] for x in X])
    for v in KX + MX:
        v.destroy()
    return ritz(Kr, Mr)


class Pencil:
    """K (then A = K − σM in the same storage), M, their norms, and the backward error of a pair."""

    def __init__(self) -> None:
        bs = int(P.get("block_size", 1))
        if bs > 1:
            OPTS["matload_block_size"] = bs
        self.bs = bs
        # M without the explicit zeros of K's pattern (a solid's mass: a third of the entries),
        # read first so that its temporaries are gone before K takes its place.
        self.subset = bool(P.get("compact_m", True)) and P.get("mat_type", "aij") == "aij"
        if self.subset:
            self.M = load_compact("M.petsc", bs)
            self.K = load("K.petsc", rows=self.M.getOwnershipRange())
        else:
            self.K = load("K.petsc")
            self.M = load("M.petsc")
        self.n = self.K.getSize()[0]
        # The diagonals of K and M (before any shift) scale the backward error (backward()).
        self.dK, self.dM = self.K.getDiagonal(), self.M.getDiagonal()
        self.dK.abs()
        self.dM.abs()
        self.sigma = 0.0  # the shift already applied to K's storage
        self.mg = None  # (P, PᵀAP) of the P1 coarse level, when there is one

    def backward(self, x, lam: float) -> float:
        """‖Kx − λMx‖ / (‖D_K x‖ + |λ|‖D_M x‖) (D: the diagonal), whatever shift K's storage holds.
        An upper bound of vibrofem's backward error ‖Kx − λMx‖ / (‖|K||x|‖ + |λ|‖|M||x|‖): |K||x| ≥
        D_K|x| entry by entry. (A bound by ‖K‖∞‖x‖ instead is not one: on a beam's rotations and
        translations it was 77 times below vibrofem's.)"""
        r = self.K.createVecLeft()
        self.K.mult(x, r)
        mx = self.M.createVecLeft()
        self.M.mult(x, mx)
        r.axpy(-(lam - self.sigma), mx)
        dx = x.copy()
        dx.pointwiseMult(self.dK, x)
        den = dx.norm()
        dx.pointwiseMult(self.dM, x)
        den += abs(lam) * dx.norm()
        eta = r.norm() / max(den, 1e-300)
        for v in (r, mx, dx):
            v.destroy()
        return eta

    def shift(self, s: float) -> None:
        """Make K's storage hold K − sM."""
        pattern = PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN if self.subset else \
            PETSc.Mat.Structure.SAME_NONZERO_PATTERN
        self.K.axpy(-(s - self.sigma), self.M, structure=pattern)
        self.sigma = s

    def compact(self) -> None:
        """K's storage (A = K − σM) read again in params' `k_type` ("baij": 3 × 3 blocks, a third
        less memory than aij and faster products) once the multigrid no longer needs it in aij:
        only with the P1 two-level multigrid (its fine level needs products and the diagonal;
        GAMG on A needs aij). Read again rather than converted: PETSc 3.18's MatConvert of K
        after the P1 level's MatPtAP crashed (SEGV)."""
        kt = P.get("k_type", "baij" if self.mg is not None and self.bs > 1 else None)
        if kt:
            self.reread(kt)

    def reread(self, kt: str) -> None:
        """K's storage read again in type `kt` ("aij", "baij"), the current shift applied again."""
        if self.K.getType() in (kt, "seq" + kt, "mpi" + kt):
            return
        rows, s = self.K.getOwnershipRange(), self.sigma
        self.K.destroy()
        trim()
        self.K = load("K.petsc", kt, rows=rows)
        self.sigma = 0.0
        # M (aij) into K: entry by entry when the types differ; every entry is in K's pattern.
        self.shift(s)


def load_compact(name: str, bs: int):
    """The matrix in file `name` (PETSc binary AIJ) without its explicit zeros, in AIJ with PETSc's
    row distribution in blocks of `bs`, read row chunk by row chunk (no full-pattern copy is ever held). A solid's
    consistent mass matrix couples only equal components: written in K's pattern, two thirds of
    its entries are zeros."""
    path = os.path.join(WD, name)
    head = np.fromfile(path, dtype=">i4", count=4)
    if head[0] != 1211216:
        raise ValueError(f"{path}: not a PETSc binary matrix")
    nrows, ncols, nz = int(head[1]), int(head[2]), int(head[3])
    layout = PETSc.Vec().createMPI((PETSc.DECIDE, nrows), bsize=bs, comm=COMM)
    lo, hi = layout.getOwnershipRange()
    layout.destroy()
    with open(path, "rb") as fh:
        fh.seek(16)
        start = np.zeros(nrows + 1, dtype=np.int64)
        np.cumsum(np.fromfile(fh, dtype=">i4", count=nrows), out=start[1:])
        indptr = [np.zeros(1, dtype=np.int64)]
        idx, data = [], []
        chunk = 65536
        for r0 in range(lo, hi, chunk):  # read, not mapped: mapped file pages would count as resident
            r1 = min(hi, r0 + chunk)
            a, b = int(start[r0]), int(start[r1])
            fh.seek(16 + 4 * nrows + 4 * a)
            c = np.fromfile(fh, dtype=">i4", count=b - a).astype(np.int64)
            fh.seek(16 + 4 * nrows + 4 * nz + 8 * a)
            v = np.fromfile(fh, dtype=">f8", count=b - a).astype(np.float64)
            row = np.repeat(np.arange(r0, r1), np.diff(start[r0:r1 + 1]))
            keep = (v != 0.0) | (c == row)
            idx.append(c[keep].astype(PETSc.IntType))
            data.append(v[keep])
            counts = np.bincount(row[keep] - r0, minlength=r1 - r0)
            indptr.append(indptr[-1][-1] + np.cumsum(counts))
    del start
    ia = np.concatenate(indptr).astype(PETSc.IntType)
    ja = np.concatenate(idx) if idx else np.zeros(0, dtype=PETSc.IntType)
    del idx
    va = np.concatenate(data) if data else np.zeros(0)
    del data, indptr
    m = PETSc.Mat().createAIJ(((hi - lo, nrows), (hi - lo, ncols)), csr=(ia, ja, va), comm=COMM)
    m.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    del ia, ja, va
    trim()
    return m


def rigid_pairs(pen: Pencil):
    """The rigid-body motions K annihilates: Ritz pairs of span(R) with a backward error at rounding."""
    nr_all = int(P.get("rigid", 0))
    if not nr_all:
        return [], [], []
    lo, hi = pen.K.getOwnershipRange()
    raw = np.memmap(os.path.join(WD, "R.bin"), dtype="<f8", mode="r", shape=(nr_all, pen.n))
    R = []
    for j in range(nr_all):
        v = pen.K.createVecRight()
        v.setArray(np.array(raw[j, lo:hi]))
        if v.norm() > 0.0:  # a zero row (a motion the caller left out) is not a motion
            R.append(v)
    del raw
    if not R:
        return [], [], []
    theta, Z = rayleigh_ritz(pen.K, pen.M, R)
    lam, vecs = [], []
    for j in range(len(R)):
        x = combine(R, Z[:, j])
        if pen.backward(x, theta[j]) <= 1e-11:
            lam.append(theta[j])
            vecs.append(x)
    return R, lam, vecs


def orthonormal(vs):
    """Copies of `vs` orthonormalised (GAMG wants an orthonormal near-null space basis)."""
    out = [v.copy() for v in vs]
    for i in range(len(out)):
        for j in range(i):
            out[i].axpy(-out[j].dot(out[i]), out[j])
        out[i].normalize()
    return out


def vertex_interpolation(pen: Pencil):
    """The quadratic mesh's linear space inside its own: P (n × n_c) from the vertex DOFs, 1 at a
    vertex DOF, the linear shape functions' values at the others (1/2 from each end of an edge,
    1/4 from each corner of a hex27 face, 1/8 at its centre). parents.bin and parent_weights.bin:
    n rows of params' parents_width int64 and f64, the equations a DOF is interpolated from and
    their weights (its own alone, weight 1, at a vertex DOF; −1 for a fixed corner or an unused
    entry). Exact for linear fields on straight cells, the rigid-body motions among them; so PᵀAP
    is the linear elements' stiffness of the same mesh (shifted), seven to eight times smaller
    than A. None without parents.bin."""
    path = os.path.join(WD, "parents.bin")
    if not os.path.exists(path) or P.get("coarse", "p1") != "p1":
        return None
    n = pen.n
    width = int(P.get("parents_width", 2))
    par = np.fromfile(path, dtype="<i8").reshape(n, width)
    wts = np.fromfile(os.path.join(WD, "parent_weights.bin"), dtype="<f8").reshape(n, width)
    vertex = par[:, 0] == np.arange(n)
    cmap = np.cumsum(vertex) - 1
    lo, hi = pen.K.getOwnershipRange()
    pl, wl, isv = par[lo:hi], wts[lo:hi], vertex[lo:hi]
    # A vertex row: (its own coarse column, 1); any other: (each free parent's column, weight).
    ref = (pl >= 0) & ~isv[:, None]
    bad = (ref & ~vertex[np.maximum(pl, 0)]).any(axis=1)
    if bad.any():
        raise ValueError(f"parents.bin: equation {lo + int(np.argmax(bad))} is interpolated from a DOF that is not "
                         "a vertex DOF")
    cols = np.where(ref, cmap[np.maximum(pl, 0)], -1)
    vals = np.where(ref, wl, 0.0)
    cols[isv, 0] = cmap[lo:hi][isv]
    vals[isv, 0] = 1.0
    keep = cols >= 0
    ptr = np.concatenate([[0], np.cumsum(keep.sum(axis=1))])
    nc_local = int(isv.sum())
    pi = PETSc.Mat().createAIJ(((hi - lo, n), (nc_local, int(vertex.sum()))),
                               csr=(ptr.astype(PETSc.IntType), cols[keep].astype(PETSc.IntType), vals[keep]),
                               comm=COMM)
    if pen.bs > 1:
        pi.setBlockSizes(pen.bs, pen.bs)
    return pi, vertex[lo:hi]


def multigrid(pen: Pencil, R) -> None:
    """The preconditioner's pieces (params: gamg_threshold, near_null_space, coarse): GAMG on A
    with R as near-null space; or, for a quadratic solid mesh (parents.bin), a two-level cycle whose fine
    level is Chebyshev/Jacobi on A and whose coarse level is GAMG on the P1 operator PᵀAP."""
    near = orthonormal(R) if R and P.get("near_null_space", True) else []
    vi = vertex_interpolation(pen)
    pen.mg = None
    # The inverse's KSP is the spectral transformation's: its options take the prefix "st_".
    gamg = "st_"
    if vi is None:
        if near:
            pen.K.setNearNullSpace(PETSc.NullSpace().create(vectors=near, comm=COMM))
    else:
        pi, keep = vi
        product = pen.K.ptap(pi)
        ac = product.duplicate(copy=True)  # without the product's reference to K (freed below)
        product.destroy()
        ac.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        if near:
            cn = []
            for v in near:
                c = ac.createVecRight()
                c.setArray(v.getArray()[keep])
                cn.append(c)
            ac.setNearNullSpace(PETSc.NullSpace().create(vectors=orthonormal(cn), comm=COMM))
            for v in near + cn:  # the coarse null space holds its own copies
                v.destroy()
        pen.mg = (pi, ac)
        gamg = "st_mg_coarse_"
        fine = {"ksp_type": "chebyshev", "pc_type": "jacobi", "ksp_max_it": int(P.get("smooth_its", 1)),
                "ksp_chebyshev_esteig": "0,0.1,0,1.1"}
        for k, v in fine.items():
            if not OPTS.hasName("st_mg_levels_" + k):
                OPTS["st_mg_levels_" + k] = v
    defaults = {
        "pc_gamg_threshold": P.get("gamg_threshold", 0.01),
        "pc_gamg_square_graph": 1,
        "mg_levels_ksp_type": "chebyshev",
        "mg_levels_pc_type": "jacobi",
        "mg_levels_ksp_max_it": 2,
    }
    for k, v in defaults.items():
        if not OPTS.hasName(gamg + k):
            OPTS[gamg + k] = v


def precondition(pc, pen: Pencil, info=None) -> None:
    """Make `pc` the preconditioner multigrid() prepared; info's `coarse` says which ("p1": the
    two-level cycle on the mesh's linear elements, "gamg": GAMG on A)."""
    if info is not None:
        info["coarse"] = "gamg" if pen.mg is None else "p1"
    if pen.mg is None:
        pc.setType(PETSc.PC.Type.GAMG)
        return
    pi, ac = pen.mg
    pc.setType(PETSc.PC.Type.MG)
    pc.setMGLevels(2)
    pc.setMGType(PETSc.PC.MGType.MULTIPLICATIVE)
    pc.setMGInterpolation(1, pi)
    coarse = pc.getMGCoarseSolve()
    coarse.setType(PETSc.KSP.Type.PREONLY)
    coarse.setOperators(ac)
    coarse.getPC().setType(PETSc.PC.Type.GAMG)


def mumps_factor(pc, ooc_mb: int) -> None:
    """Make `pc` an out-of-core MUMPS LDLᵀ (ICNTL(22) = 1, files in params' ooc_dir or DIR) with
    its working memory capped at `ooc_mb` MB per rank (ICNTL(23); 0: MUMPS's estimate)."""
    os.environ.setdefault("MUMPS_OOC_TMPDIR", P.get("ooc_dir", WD))
    pc.setType(PETSc.PC.Type.CHOLESKY)
    pc.setFactorSolverType("mumps")
    pc.setFactorSetUpSolverType()
    F = pc.getFactorMatrix()
    for key, val in ((13, 1), (24, 1), (22, 1), (23, ooc_mb)):
        F.setMumpsIcntl(key, val)


def default_block(want_el: int) -> int:
    """The block (and SLEPc's nev) for `want_el` elastic modes: wanted + max(4, wanted/3), as the
    driver's `default_block`."""
    return want_el + max(4, want_el // 3)


def lobpcg_block(want_el: int) -> int:
    """LOBPCG's block: params' `lobpcg_block` (default: default_block()), cut to
    `lobpcg_block_max` (the largest the driver's memory budget allows) but never below the
    wanted modes + `lobpcg_min_extra` (1)."""
    block = int(P.get("lobpcg_block", default_block(want_el)))
    if "lobpcg_block_max" in P:
        block = min(block, max(want_el + int(P.get("lobpcg_min_extra", 1)), int(P["lobpcg_block_max"])))
    return max(block, 1)


def eigensolve(pen: Pencil, rigid_vecs, want_el: int):
    """Step 3: the elastic pairs of A (values λ − σ), ascending, and the inner KSP for step 4."""
    method = P.get("method", "lobpcg")
    if method == "lobpcg":
        return lobpcg(pen, rigid_vecs, want_el)
    A, M = pen.K, pen.M
    eps = SLEPc.EPS().create(comm=COMM)
    eps.setOperators(A, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    if rigid_vecs:
        eps.setDeflationSpace(rigid_vecs)
    st = eps.getST()
    ksp = st.getKSP()
    nev = default_block(want_el)
    info: dict = {}
    eps.setDimensions(nev)
    if method == "slepc-lobpcg":
        eps.setType(SLEPc.EPS.Type.LOBPCG)
        eps.setWhichEigenpairs(SLEPc.EPS.Which.SMALLEST_REAL)
        st.setType(SLEPc.ST.Type.PRECOND)
        ksp.setType(PETSc.KSP.Type.PREONLY)
        precondition(ksp.getPC(), pen, info)
        # Stop when the wanted pairs converge; the extra vectors only widen the block.
        block = lobpcg_block(want_el)
        eps.setDimensions(want_el, 3 * block)  # LOBPCG holds X, W, P: ncv = 3 × block
        eps.setLOBPCGBlockSize(block)
        # Locking converged pairs made SLEPc 3.18's LOBPCG stagnate at 1e-9–3e-8 on the clustered
        # pairs at the block's end (120k plate, the 1983-DOF box); without it the box converges.
        eps.setLOBPCGLocking(False)
        tol = float(P.get("eig_tol", 1e-11))
        info["lobpcg_block"] = block
    elif method in ("ks-cg", "ks-mumps"):
        eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
        eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
        eps.setTarget(0.0)
        st.setType(SLEPc.ST.Type.SINVERT)
        if method == "ks-cg":
            ksp.setType(PETSc.KSP.Type.CG)
            precondition(ksp.getPC(), pen, info)
            ksp.setTolerances(rtol=float(P.get("inner_rtol", 1e-9)), atol=0.0, max_it=int(P.get("ksp_max_it", 1000)))
            tol = float(P.get("eig_tol", 1e-8))
        else:
            ksp.setType(PETSc.KSP.Type.PREONLY)
            ksp.setOperators(A)
            mumps_factor(ksp.getPC(), int(P.get("ooc_mb", 0)))
            tol = float(P.get("eig_tol", 1e-12))
    else:
        fail(f"params.json: method {method!r} is not one of lobpcg, slepc-lobpcg, ks-cg, ks-mumps")
    st.setShift(0.0)
    eps.setConvergenceTest(SLEPc.EPS.Conv.NORM)
    eps.setTolerances(tol, int(P.get("max_it", 300)))
    eps.setFromOptions()
    info.update({"method": method, "eig_tol": tol})
    if method == "ks-mumps":
        try:
            ksp.setUp()
        except PETSc.Error:
            pass
        F = ksp.getPC().getFactorMatrix()
        if F.getMumpsInfog(1) < 0:
            fail(f"ks-mumps: MUMPS's out-of-core LDLᵀ of K − σM failed (INFOG(1) = {F.getMumpsInfog(1)}, "
                 f"INFOG(2) = {F.getMumpsInfog(2)}; estimated {F.getMumpsInfog(26)} MB out of core)")
        neg, zero, _ = F.getInertia()
        info["factor_inertia_negative"] = int(neg) + int(zero)
        info["factor_mb"] = [F.getMumpsInfog(26), F.getMumpsInfog(16)]
        info["factor_entries"] = F.getMumpsInfog(29)
        if neg + zero:
            fail(f"ks-mumps: K − σM has {neg} negative and {zero} zero pivots at σ = {pen.sigma:.6e}: the shift "
                 "is not below the spectrum (K is not positive semidefinite)")
    if want_el:
        eps.solve()
    nconv = eps.getConverged() if want_el else 0
    info["iterations"] = eps.getIterationNumber() if want_el else 0
    reason = eps.getConvergedReason() if want_el else 0
    if want_el and nconv < want_el:
        fail(f"{method}: {nconv} of {want_el} elastic modes converged in {info['iterations']} iterations "
             f"(reason {reason}): the preconditioned iteration stalled; solve with --solver direct")
    X, theta = [], []
    for i in range(nconv):
        x = A.createVecRight()
        eps.getEigenvector(i, x)
        X.append(x)
        theta.append(eps.getEigenvalue(i).real)
    order = np.argsort(theta, kind="stable")
    info["converged"] = nconv
    # eps stays alive until the refinement is done: destroying it resets the inverse's KSP.
    return [X[i] for i in order], np.array(theta)[order], ksp, info, eps


# The refinement's bar on backward() (an upper bound of vibrofem's backward error, whose bar is 1e-10).
REFINE_TOL = 5e-11
CHUNK = 16384  # rows per slice of the block operations (their temporaries: m × CHUNK numbers)


class Blocks:
    """Blocks of vectors stored by rows ((rows, n_local) arrays: row j is a vector's local part), the
    operators applied to them through PETSc vectors wrapping the rows (no copies), and their
    inner products summed over the ranks."""

    def __init__(self, pen: Pencil) -> None:
        lo, hi = pen.K.getOwnershipRange()
        self.nl = hi - lo
        self.chunks = [slice(s, min(self.nl, s + CHUNK)) for s in range(0, self.nl, CHUNK)]
        self.vin, self.vout = pen.K.createVecRight(), pen.K.createVecLeft()
        self.tmp = pen.K.createVecRight()
        self.mpi = COMM.tompi4py() if COMM.getSize() > 1 else None

    def allsum(self, g):
        if self.mpi is not None:
            from mpi4py import MPI
            self.mpi.Allreduce(MPI.IN_PLACE, g, op=MPI.SUM)
        return g

    def apply(self, op, src, dst, rows: int) -> None:
        """dst[j] = op(src[j]) for j < rows (op(x, y): a PETSc product or solve)."""
        for j in range(rows):
            self.vin.placeArray(src[j])
            self.vout.placeArray(dst[j])
            op(self.vin, self.vout)
            self.vout.resetArray()
            self.vin.resetArray()

    def project(self, B, rows: int, U, MU, urows: int) -> None:
        """B[:rows] made M-orthogonal to U[:urows] (M-orthonormal, MU = M·U)."""
        if not rows or not urows:
            return
        C = self.allsum(MU[:urows] @ B[:rows].T)
        for c in self.chunks:
            B[:rows, c] -= C.T @ U[:urows, c]

    def combine(self, srcs, C, dsts) -> None:
        """Rows of Cᵀ·S written into dsts (list of (array, rows)), S the rows of srcs (list of
        (array, rows)) stacked; slice by slice, so a destination may be a source."""
        for c in self.chunks:
            S = np.vstack([a[:r, c] for a, r in srcs])
            out = C.T @ S
            i = 0
            for a, r in dsts:
                a[:r, c] = out[i:i + r]
                i += r

    def grams(self, parts):
        """SᵀAS and SᵀMS of S = the rows of parts (list of (X, AX, MX, rows)) stacked."""
        m = sum(p[3] for p in parts)
        GA, GM = np.zeros((m, m)), np.zeros((m, m))
        for c in self.chunks:
            S = np.vstack([p[0][:p[3], c] for p in parts])
            GA += S @ np.vstack([p[1][:p[3], c] for p in parts]).T
            GM += S @ np.vstack([p[2][:p[3], c] for p in parts]).T
        return self.allsum(GA), self.allsum(GM)

    def svqb(self, G, tau: float):
        """T with Tᵀ G T = I on the directions of G (a Gram matrix) above tau relative (SVQB)."""
        dg = np.diag(G).copy()
        ok = dg > 0.0
        d = np.where(ok, 1.0 / np.sqrt(np.where(ok, dg, 1.0)), 0.0)
        e, Q = np.linalg.eigh(0.5 * (G + G.T) * np.outer(d, d))
        keep = e > tau * max(e.max(initial=0.0), 1e-300)
        return (d[:, None] * Q[:, keep]) / np.sqrt(e[keep])


def lobpcg(pen: Pencil, rigid_vecs, want_el: int):
    """Step 3, method "lobpcg": the lowest pairs of A = K − σM by block LOBPCG (Knyazev 2001) with
    the basis selection of Hetmaniuk & Lehoucq (2006): X the Ritz vectors, W the preconditioned
    residuals of the pairs not yet converged (one multigrid cycle each) made M-orthogonal to the
    rigid-body pairs, X and P and orthonormal among themselves, P the previous step's direction
    M-orthonormal and M-orthogonal to X. A·X, M·X, A·P, M·P are updated with X and P (no products
    on them): an iteration applies A and M once to each vector of W, where SLEPc's LOBPCG
    applies them to its whole basis (three blocks) again for the Rayleigh–Ritz (docs/lowmem.md).
    Memory: nine blocks of n numbers (X, W, P and their products with A and M)."""
    A, M, sigma = pen.K, pen.M, pen.sigma
    bl = Blocks(pen)
    ksp = PETSc.KSP().create(comm=COMM)
    ksp.setOptionsPrefix("st_")  # the prefix of the multigrid's options (multigrid())
    ksp.setOperators(A)
    ksp.setType(PETSc.KSP.Type.PREONLY)
    info: dict = {}
    precondition(ksp.getPC(), pen, info)
    ksp.setFromOptions()
    ksp.setUp()
    k = lobpcg_block(want_el)
    # The bar: half the refinement's, so that no refinement is needed (the backward errors are
    # those of the updated A·X, M·X: at 120k they equal the recomputed ones to 1e-8 relative).
    tol = float(P.get("eig_tol", 0.5 * float(P.get("refine_tol", REFINE_TOL))))
    max_it = int(P.get("max_it", 300))
    info.update({"method": "lobpcg", "eig_tol": tol, "lobpcg_block": k})
    nl = bl.nl
    dk, dm = pen.dK.getArray(readonly=True), pen.dM.getArray(readonly=True)
    ny = len(rigid_vecs)
    Y = np.array([v.getArray() for v in rigid_vecs]).reshape(ny, nl)
    MY = np.empty_like(Y)
    bl.apply(M.mult, Y, MY, ny)
    X, AX, MX, W, AW, MW, Pd, AP, MP = (np.empty((k, nl)) for _ in range(9))
    X[:] = np.random.default_rng(20261127 + RANK).standard_normal((k, nl))
    for _ in range(2):
        bl.project(X, k, Y, MY, ny)
    bl.apply(A.mult, X, AX, k)
    bl.apply(M.mult, X, MX, k)
    theta, Z = ritz(*bl.grams([(X, AX, MX, k)]))
    for a in ((X, k), (AX, k), (MX, k)):
        bl.combine([a], Z, [a])
    conv = np.zeros(k, dtype=bool)
    npr, it = 0, 0
    eta, history = np.ones(k), []
    while True:
        sq = np.zeros((3, k))  # ‖r‖², ‖D_K x‖², ‖D_M x‖² (the backward error of Pencil.backward)
        for c in bl.chunks:
            R = AX[:, c] - theta[:, None] * MX[:, c]
            sq[0] += np.einsum("ij,ij->i", R, R)
            R = X[:, c] * dk[c]
            sq[1] += np.einsum("ij,ij->i", R, R)
            R = X[:, c] * dm[c]
            sq[2] += np.einsum("ij,ij->i", R, R)
        sq = np.sqrt(bl.allsum(sq))
        eta = sq[0] / np.maximum(sq[1] + np.abs(theta + sigma) * sq[2], 1e-300)
        conv |= eta <= tol
        history.append(float(eta[:want_el].max(initial=0.0)))
        progress(f"LOBPCG iteration {it}: {int(conv[:want_el].sum())} of {want_el} modes converged, largest backward "
                 f"error {history[-1]:.1e} (bar {tol:.1e})")
        if conv[:want_el].all() or it >= max_it:
            break
        it += 1
        act = np.flatnonzero(~conv)
        na = len(act)
        for j, col in enumerate(act):  # W: the preconditioned residuals
            bl.tmp.setArray(AX[col] - theta[col] * MX[col])
            bl.vout.placeArray(W[j])
            ksp.solve(bl.tmp, bl.vout)
            bl.vout.resetArray()
        for _ in range(2):
            bl.project(W, na, Y, MY, ny)
            bl.project(W, na, X, MX, k)
            bl.project(W, na, Pd, MP, npr)
        for _ in range(2):  # orthonormal (Euclidean: no products yet), vanished directions dropped
            T = bl.svqb(bl.allsum(W[:na] @ W[:na].T), 1e-14)
            bl.combine([(W, na)], T, [(W, T.shape[1])])
            na = T.shape[1]
        bl.apply(A.mult, W, AW, na)
        bl.apply(M.mult, W, MW, na)
        parts = [(X, AX, MX, k), (W, AW, MW, na), (Pd, AP, MP, npr)]
        try:
            GA, GM = bl.grams(parts)
            th, Z = ritz(GA, GM)
        except np.linalg.LinAlgError:  # a basis that lost its independence: restart without P
            parts = parts[:2]
            GA, GM = bl.grams(parts)
            th, Z = ritz(GA, GM)
        theta, Zk, Zr = th[:k], Z[:, :k], Z[:, k:]
        # P: the step of the new X, [0; Zw; Zp] of the active pairs, made GM-orthogonal to Zk and
        # orthonormal. Z is GM-orthonormal, so its part orthogonal to Zk is Zr·Q with
        # Q = Zrᵀ·GM·[0; Zw; Zp]; directions below 1e-8 (relative, squared) are dropped: they would
        # magnify rounding in A·P and M·P.
        Yc = Zk[:, act].copy()
        Yc[:k] = 0.0
        Q = Zr.T @ (GM @ Yc)
        C = np.hstack([Zk, Zr @ (Q @ bl.svqb(Q.T @ Q, 1e-8))])
        pn = C.shape[1] - k
        for j in range(3):
            bl.combine([(p[j], p[3]) for p in parts], C, [((X, AX, MX)[j], k), ((Pd, AP, MP)[j], pn)])
        npr = pn
    info["iterations"] = it
    info["converged"] = int(conv.sum())
    info["eta"] = [float(e) for e in eta]
    info["eta_history"] = history
    if not conv[:want_el].all():
        fail(f"lobpcg: {int(conv[:want_el].sum())} of {want_el} elastic modes converged in {it} iterations (largest "
             f"backward error {eta[:want_el].max():.1e}, bar {tol:.1e}): the preconditioned iteration stalled (a mechanism, "
             "a zero-energy motion that is not a rigid-body motion, is a common cause); solve with --solver direct")
    out = []
    for j in range(k):
        x = A.createVecRight()
        x.setArray(X[j])
        out.append(x)
    del X, AX, MX, W, AW, MW, Pd, AP, MP, Y, MY
    trim()
    return out, np.array(theta), ksp, info, None


def m_orthonormal(M, V, MV, Y):
    """Y made M-orthogonal to V (M-orthonormal, MV = M·V) and M-orthonormal itself (Gram–Schmidt
    twice); vectors that vanish relative to their start are dropped. Returns (Y, M·Y)."""
    out, Mout = [], []
    for y in Y:
        y0 = y.norm()
        for _ in range(2):
            for b, mb in zip(V + out, MV + Mout):
                y.axpy(-mb.dot(y), b)
        my = products(M, [y])[0]
        nrm = np.sqrt(max(my.dot(y), 0.0))
        if y.norm() > 1e-10 * y0 and nrm > 0.0:
            y.scale(1.0 / nrm)
            my.scale(1.0 / nrm)
            out.append(y)
            Mout.append(my)
    return out, Mout


def refine(pen: Pencil, ksp, X, theta, want_el: int, rigid_vecs):
    """Step 4: Rayleigh–Ritz on span(X, A⁻¹MX), the correction M-orthogonal to the rigid-body pairs
    (A⁻¹ magnifies them by (λ − σ)/(−σ)) and to X, until the kept pairs' backward errors are at most
    refine_tol (the inner solve to refine_rtol, with the multigrid or factor of step 3). Two blocks
    per round: a block Lanczos step, much faster than plain block inverse iteration for the pairs
    at the block's end."""
    Mr = products(pen.M, rigid_vecs)
    tol = float(P.get("refine_tol", REFINE_TOL))

    def errors(th, XX):
        return [pen.backward(XX[j], th[j] + pen.sigma) for j in range(min(want_el, len(XX)))]

    if X:  # M-orthonormal Ritz vectors of the eigensolver's span (the rounds below rely on it)
        theta, Z = rayleigh_ritz(pen.K, pen.M, X)
        X = [combine(X, Z[:, j]) for j in range(len(X))]
    err = errors(theta, X)
    history = [max(err, default=0.0)]
    rounds, its = 0, 0
    if ksp.getType() == PETSc.KSP.Type.PREONLY and ksp.getPC().getType() != PETSc.PC.Type.CHOLESKY:
        ksp.setType(PETSc.KSP.Type.CG)
    ksp.setTolerances(rtol=float(P.get("refine_rtol", 1e-8)), atol=0.0, max_it=int(P.get("ksp_max_it", 1000)))
    for _ in range(int(P.get("max_refine", 10))):
        if history[-1] <= tol or (len(history) > 2 and history[-1] > 0.5 * history[-2]):
            break  # reached, or stalled (the inner solves' accuracy limits it)
        MX = products(pen.M, X)
        Y = []
        for mx in MX:
            y = mx.duplicate()
            ksp.solve(mx, y)
            its += ksp.getIterationNumber()
            Y.append(y)
        Y, MY = m_orthonormal(pen.M, rigid_vecs + X, Mr + MX, Y)
        for v in MY:
            v.destroy()
        rounds += 1
        B = X + Y
        th, Z = rayleigh_ritz(pen.K, pen.M, B)
        X = [combine(B, Z[:, j]) for j in range(len(X))]
        for v in B + MX:
            v.destroy()
        if hasattr(PETSc, "garbage_cleanup"):
            PETSc.garbage_cleanup(COMM)
        theta = th[:len(X)]
        err = errors(theta, X)
        history.append(max(err, default=0.0))
    if history[-1] > tol:
        fail(f"refinement: largest backward error {history[-1]:.2e} above {tol:.0e} after {rounds} rounds "
             f"(history {', '.join('%.1e' % h for h in history)}): the modes are not accurate; solve with "
             "--solver direct")
    return X, theta, err, {"refinements": rounds, "refine_ksp_iterations": its, "refine_history": history}


def sturm_upper(pen: Pencil, lam_max: float, above) -> dict:
    """Step 5: the number of eigenvalues below a point just above the last mode, from MUMPS's
    inertia of K − sM out of core, within the memory budget (params' sturm_budget bytes)."""
    # The scale as the direct path's (eigen.rs, check_points): |σ| when every mode returned is
    # at λ = 0, where a point 1e-4 rad²/s² above the rigid-body modes lay inside their
    # rounding and counted 4 of 6 (a steel bar, σ = −2.07e5).
    scale = max(abs(lam_max), abs(pen.sigma))
    step = 1e-4 * scale
    if len(above):
        step = min(step, 0.5 * (above[0] - lam_max))
    upper_pt = lam_max + max(step, 1e-9 * scale)
    sturm: dict = {"lower": [pen.sigma, 0]}
    budget_mb = int(float(P.get("sturm_budget", 0)) / 2**20 / COMM.getSize())
    if budget_mb <= 0:
        sturm["sturm_skipped"] = "no memory was left in the budget for a factorisation"
        return sturm
    # MUMPS copies K − sM (12 bytes an entry at the least) and analyses it before ICNTL(23) caps
    # anything, and K is read again in aij for it: with less than that left, an attempt only
    # overshoots the budget before failing (1M on 2 ranks under 4G: 3.32 → 3.95 GiB for a count
    # MUMPS then refused).
    need_mb = int(12 * pen.K.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_used"] / 2**20 / COMM.getSize()) + 1
    if budget_mb < need_mb:
        sturm["sturm_skipped"] = (
            f"MUMPS's copy of K − sM alone needs about {need_mb} MB per rank, and {budget_mb} MB per rank "
            "were left in the memory budget")
        return sturm
    pen.reread("aij")  # MUMPS's Cholesky takes aij or sbaij, not baij
    pen.shift(upper_pt)
    pc = PETSc.PC().create(comm=COMM)
    pc.setOperators(pen.K)
    mumps_factor(pc, budget_mb)
    F = pc.getFactorMatrix()
    try:
        pc.setUp()
        err = F.getMumpsInfog(1)
    except PETSc.Error:
        err = F.getMumpsInfog(1) or -1
    if err < 0:
        sturm["sturm_skipped"] = (
            f"MUMPS's out-of-core factorisation of K − sM needs more than the {budget_mb} MB per rank left in "
            f"the memory budget (INFOG(1) = {err}; estimated {F.getMumpsInfog(26)} MB out of core, "
            f"{F.getMumpsInfog(16)} MB in core)")
    else:
        neg, zero, _ = F.getInertia()
        sturm["upper"] = [upper_pt, int(neg)]
        sturm["zero_pivots"] = [0, int(zero)]
        sturm["sturm_mb"] = [F.getMumpsInfog(26), F.getMumpsInfog(16)]
    pc.destroy()
    return sturm


SAME_ROOT = 1e-8


def with_multiplet(theta, want_el: int, sigma: float) -> int:
    """`want_el` extended over the rest of a repeated root at the cut (Ritz values within SAME_ROOT
    of the scale of the last wanted one): a Sturm point just above the last wanted mode would
    count its partner, which was not returned (a square bar's double bending root: 8 counted, 7
    returned). The partners are refined and returned with the wanted pairs; vibrofem reports
    the modes asked for, checked against the count with all of them."""
    if want_el == 0:
        return 0
    scale = max(abs(theta[want_el - 1] + sigma), abs(sigma))
    while want_el < len(theta) and theta[want_el] - theta[want_el - 1] <= SAME_ROOT * scale:
        want_el += 1
    return want_el


def gather(X):
    """The vectors on rank 0 (numpy arrays; empty list elsewhere)."""
    xr = X[0].duplicate() if X else None
    out = []
    if xr is None:
        return out
    scatter, x0 = PETSc.Scatter.toZero(xr)
    for x in X:
        x.copy(xr)
        scatter.scatter(xr, x0, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
        if RANK == 0:
            out.append(x0.getArray().copy())
    return out


def elastic_pairs(pen: Pencil, rigid_vecs, want_el: int, nr: int):
    """Steps 3–4: the elastic pairs (values λ − σ, ascending; the wanted ones and a repeated
    root's partners refined), their backward errors, what the solve reports and the number
    refined."""
    sigma = pen.sigma
    t = time.perf_counter()
    try:
        X, theta, ksp, info, eps = eigensolve(pen, rigid_vecs, want_el)
    except (PETSc.Error, np.linalg.LinAlgError) as e:
        # LOBPCG's Rayleigh-Ritz breaks down (LAPACK sygvd) on a basis that holds zero-energy
        # motions the deflation does not: a mechanism is the usual cause, named as such.
        fail(f"the eigensolver ({P.get('method', 'lobpcg')}) broke down ({getattr(e, 'ierr', e)}) with {nr} "
             "rigid-body motions deflated: the model likely has a mechanism (a zero-energy motion that is not a "
             "rigid-body motion: unconnected parts, a free hinge), which the multigrid's near-null space does not "
             "hold. Solve with --solver direct, which finds and reports zero-energy modes, or constrain the "
             "mechanism")
    mark("solve", t)
    info["solve_counts"] = counts()
    # A mode at λ ≈ 0 left after the deflation: a mechanism, or rigid-body motions not given.
    if len(theta) and theta[0] + sigma <= 1e-9 * (-sigma) / 1e-7:
        fail(f"a mode at λ = {theta[0] + sigma:.3e} rad²/s² with {nr} rigid-body motions deflated: the model has a "
             "mechanism (a zero-energy motion that is not a rigid-body motion) or its rigid-body motions were not "
             "given (R.bin); the multigrid's near-null space does not hold it. Solve with --solver direct, or "
             "constrain the mechanism")
    want_el = with_multiplet(theta, want_el, sigma)
    t = time.perf_counter()
    X, theta, err, rinfo = refine(pen, ksp, X, theta, want_el, rigid_vecs)
    info.update(rinfo)
    if eps is not None:
        eps.destroy()
    ksp.destroy()
    mark("refine", t)
    return X, theta, err, info, want_el


def main() -> None:
    t = time.perf_counter()
    pen = Pencil()
    mark("load", t)
    t = time.perf_counter()
    R, rigid_lam, rigid_vecs = rigid_pairs(pen)
    mark("rigid", t)
    sigma = float(P["sigma"])
    if not sigma < 0.0:
        fail(f"params.json: sigma = {sigma} is not negative; the iterative solver needs a shift below the spectrum")
    t = time.perf_counter()
    pen.shift(sigma)
    multigrid(pen, R)
    for r in R:  # the rigid-body pairs (rigid_vecs) are kept; R itself is no longer needed
        r.destroy()
    pen.compact()
    mark("shift", t)
    nr, nev = len(rigid_lam), int(P["nev"])
    want_el = max(0, nev - nr)
    t = time.perf_counter()
    if pen.n <= nr:
        # Every degree of freedom is a rigid-body motion (a whole free body coupled to one
        # reference node, K = 0): the rigid-body pairs are the whole spectrum, nothing is left to
        # iterate for (the iteration on the empty complement returns rounding, once taken for a
        # mechanism).
        X, theta, err = [], np.zeros(0), []
        info = {"converged": 0, "iterations": 0, "refinements": 0}
        mark("solve", t)
        info["solve_counts"] = counts()
    else:
        X, theta, err, info, want_el = elastic_pairs(pen, rigid_vecs, want_el, nr)
    lam = np.concatenate([np.array(rigid_lam), theta[:want_el] + sigma])
    back = [pen.backward(x, lr) for x, lr in zip(rigid_vecs, rigid_lam)] + list(err)
    t = time.perf_counter()
    vecs = gather(rigid_vecs + X[:want_el])
    mark("gather", t)
    t = time.perf_counter()
    sturm = sturm_upper(pen, float(lam[-1]) if len(lam) else 0.0, theta[want_el:] + sigma)
    mark("sturm", t)
    if RANK == 0:
        lam.astype("<f8").tofile(os.path.join(WD, "lambda.bin"))
        np.asarray(vecs, dtype="<f8").reshape(-1).tofile(os.path.join(WD, "vectors.bin"))
        out = {
            "n": pen.n, "nconv": len(lam), "converged": info["converged"] + nr, "iterations": info["iterations"],
            "ranks": COMM.getSize(), "sigma": sigma, "rigid": nr, "block_size": pen.bs,
            "backward_errors": back, "max_backward_error": max(back, default=0.0),
            "timings_s": TIMINGS, "memory_mib": MEMORY, "counts": counts(),
            "slepc": "%d.%d.%d" % SLEPc.Sys.getVersion()[:3], "petsc": "%d.%d.%d" % PETSc.Sys.getVersion()[:3],
        }
        out.update(info)
        out.update(sturm)
        with open(os.path.join(WD, "slepc.json"), "w") as fh:
            json.dump(out, fh)


if __name__ == "__main__":  # imported by validation/lowmem_gamg.py to measure the phases alone
    try:
        main()
    except PETSc.Error as e:  # a PETSc failure (memory, a breakdown): an error, never a silent answer
        fail(f"PETSc error {e.ierr} after the {list(TIMINGS)[-1] if TIMINGS else 'start'} phase: {e}")
    except (np.linalg.LinAlgError, ValueError, OSError) as e:
        fail(f"{type(e).__name__} after the {list(TIMINGS)[-1] if TIMINGS else 'start'} phase: {e}")
