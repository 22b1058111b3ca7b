"""Low-memory engine of vibrofem: run under mpirun by `vibrofem modes --solver iterative` on a
folder it wrote (K.petsc, M.petsc, R.bin, params.json).

    mpirun -n N python3 slepc_lowmem.py DIR

The lowest modes of K x = λ M x without a factorisation of K: memory grows with the matrices.

1. The rigid-body motions R (n × 6, from the node coordinates, written by vibrofem in R.bin) are
   tried on K by Rayleigh–Ritz: the combinations K annihilates (a free body: six; a body on
   partial supports: fewer) are eigenpairs at λ ≈ 0, returned as such and deflated.
2. A = K − σM with σ < 0 slightly below the spectrum (SPD: no copy of K, the eigenvalues move
   by σ), preconditioned by PETSc's smoothed-aggregation multigrid (GAMG) with R as its
   near-null space and the nodes' block size.
3. The remaining modes by SLEPc's `method` (params.json): "lobpcg" (LOBPCG, one multigrid cycle
   per vector and iteration) or "ks-cg" (Krylov–Schur, shift-and-invert with an inexact
   inverse: CG preconditioned by GAMG), deflated against the rigid-body pairs.
4. Block inverse iteration (CG + GAMG to 1e-12) with Rayleigh–Ritz until every kept pair's
   backward error is at rounding level.
5. Completeness: MUMPS's inertia of K − sM above the last mode (out-of-core factor, ICNTL(22))
   only when MUMPS's own estimate of its memory fits `sturm_budget` bytes; otherwise the count
   is skipped and slepc.json says why (vibrofem then reports the modes as not verified complete).

A mode at λ ≈ 0 that is not a rigid-body motion (a mechanism) stops the run with an error: the
multigrid's near-null space does not hold it and its iteration would not be trustworthy.
Rank 0 writes lambda.bin, vectors.bin and slepc.json as slepc_modes.py does.
"""
import json
import os
import resource
import sys
import time

import numpy as np
import petsc4py
import slepc4py

slepc4py.init(sys.argv[:1])
from petsc4py import PETSc  # noqa: E402
from slepc4py import SLEPc  # noqa: E402

wd = sys.argv[1]
comm = PETSc.COMM_WORLD
rank = comm.getRank()
with open(os.path.join(wd, "params.json")) as f:
    p = json.load(f)
opts = PETSc.Options()
timings = {}
memory = {}


def peak_mb():
    """Peak resident memory of this rank so far, summed over ranks (MiB)."""
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return comm.tompi4py().allreduce(own) if comm.getSize() > 1 else own


def mark(phase, t0):
    timings[phase] = time.perf_counter() - t0
    memory[phase] = peak_mb()


def fail(msg):
    if rank == 0:
        with open(os.path.join(wd, "slepc.json"), "w") as fh:
            json.dump({"error": msg}, fh)
    PETSc.Sys.Print("error: " + msg, comm=comm)
    sys.exit(3)


t = time.perf_counter()
bs = int(p.get("block_size", 1))
if bs > 1:
    opts["matload_block_size"] = bs


def load(name):
    v = PETSc.Viewer().createBinary(os.path.join(wd, name), "r", comm=comm)
    a = PETSc.Mat().create(comm=comm)
    a.setType(PETSc.Mat.Type.AIJ)
    a.load(v)
    v.destroy()
    a.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    return a


K = load("K.petsc")
M = load("M.petsc")
n = K.getSize()[0]
lo_r, hi_r = K.getOwnershipRange()
nr_all = int(p.get("rigid", 0))
Rraw = np.memmap(os.path.join(wd, "R.bin"), dtype="<f8", mode="r", shape=(nr_all, n)) if nr_all else None
R = []
for j in range(nr_all):
    v = K.createVecRight()
    v.setArray(np.array(Rraw[j, lo_r:hi_r]))
    R.append(v)
del Rraw
normK, normM = K.norm(PETSc.NormType.INFINITY), M.norm(PETSc.NormType.INFINITY)
mark("load", t)


def gram(X, Y):
    return np.array([[x.dot(y) for y in Y] for x in X])


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


def rayleigh_ritz(X, KX=None, MX=None):
    """Ritz values (ascending) and coefficients of span(X) for K, M."""
    KX = KX if KX is not None else products(K, X)
    MX = MX if MX is not None else products(M, X)
    Kr, Mr = gram(X, KX), gram(X, MX)
    Kr, Mr = 0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T)
    d = 1.0 / np.sqrt(np.diag(Mr))
    Li = np.linalg.inv(np.linalg.cholesky(Mr * np.outer(d, d)))
    C = Li @ (Kr * np.outer(d, d)) @ Li.T
    theta, W = np.linalg.eigh(0.5 * (C + C.T))
    return theta, (Li.T @ W) * d[:, None]


def backward(x, lam):
    r = K.createVecLeft()
    K.mult(x, r)
    mx = M.createVecLeft()
    M.mult(x, mx)
    r.axpy(-lam, mx)
    return r.norm() / ((normK + abs(lam) * normM) * x.norm())


# 1. The rigid-body motions K annihilates: Ritz pairs of span(R) with a backward error at rounding.
t = time.perf_counter()
rigid_lam, rigid_vecs = [], []
if R:
    theta, Z = rayleigh_ritz(R)
    for j in range(len(R)):
        x = combine(R, Z[:, j])
        if backward(x, theta[j]) <= 1e-11:
            rigid_lam.append(theta[j])
            rigid_vecs.append(x)
mark("rigid", t)

# 2. A = K − σM (in place: K's storage, eigenvalues λ − σ), its multigrid preconditioner.
sigma = float(p["sigma"])
if not sigma < 0.0:
    fail(f"the iterative solver needs a shift below the spectrum (sigma = {sigma} is not negative)")
t = time.perf_counter()
K.axpy(-sigma, M, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
A = K
if R:
    near = [r.copy() for r in R]
    # GAMG wants an orthonormal basis.
    for i in range(len(near)):
        for j in range(i):
            near[i].axpy(-near[j].dot(near[i]), near[j])
        near[i].normalize()
    A.setNearNullSpace(PETSc.NullSpace().create(vectors=near, comm=comm))
opts["pc_gamg_threshold"] = p.get("gamg_threshold", 0.01)
opts["pc_gamg_square_graph"] = 1
opts["mg_levels_ksp_type"] = "chebyshev"
opts["mg_levels_pc_type"] = "jacobi"
opts["mg_levels_ksp_max_it"] = 2


def gamg_ksp(rtol, prefix):
    ksp = PETSc.KSP().create(comm=comm)
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(A)
    ksp.setType(PETSc.KSP.Type.CG)
    ksp.getPC().setType(PETSc.PC.Type.GAMG)
    ksp.setTolerances(rtol=rtol, atol=0.0, max_it=int(p.get("ksp_max_it", 2000)))
    ksp.setFromOptions()
    return ksp


# Normalise the backward errors after the shift: the residual is that of K (Ax − θMx = Kx − λMx).
normK = max(normK, 1e-300)
mark("shift", t)

# 3. The elastic modes, deflated against the rigid-body pairs.
method = p.get("method", "lobpcg")
nr = len(rigid_lam)
nev = int(p["nev"])
want_el = max(0, nev - nr)
extra = max(4, want_el // 3)
t = time.perf_counter()
eps = SLEPc.EPS().create(comm=comm)
eps.setOperators(A, M)
eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
if rigid_vecs:
    eps.setDeflationSpace(rigid_vecs)
st = eps.getST()
inner_its = [0]
if method == "lobpcg":
    eps.setType(SLEPc.EPS.Type.LOBPCG)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.SMALLEST_REAL)
    st.setType(SLEPc.ST.Type.PRECOND)
    st.setShift(0.0)
    sksp = st.getKSP()
    sksp.setType(PETSc.KSP.Type.PREONLY)
    sksp.getPC().setType(PETSc.PC.Type.GAMG)
    eps.setDimensions(want_el + extra)
    eps.setLOBPCGBlockSize(want_el + extra)
    tol = float(p.get("eig_tol", 1e-9))
else:
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTarget(0.0)
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(0.0)
    sksp = st.getKSP()
    sksp.setType(PETSc.KSP.Type.CG)
    sksp.getPC().setType(PETSc.PC.Type.GAMG)
    sksp.setTolerances(rtol=float(p.get("inner_rtol", 1e-10)), atol=0.0, max_it=2000)
    eps.setDimensions(want_el + extra)
    tol = float(p.get("eig_tol", 1e-10))
eps.setConvergenceTest(SLEPc.EPS.Conv.NORM)
eps.setTolerances(tol, int(p.get("max_it", 2000)))
eps.setFromOptions()
if want_el:
    eps.solve()
    nconv = eps.getConverged()
    its = eps.getIterationNumber()
else:
    nconv, its = 0, 0
mark("solve", t)
reason = eps.getConvergedReason() if want_el else 0
if want_el and nconv < want_el:
    fail(
        f"{method}: {nconv} of {want_el} elastic modes converged in {its} iterations (reason {reason}): "
        "the multigrid-preconditioned iteration stalled; solve with --solver direct"
    )

# 4. Refinement: block inverse iteration with Rayleigh–Ritz (every converged pair takes part).
t = time.perf_counter()
X, theta = [], []
for i in range(nconv):
    x = A.createVecRight()
    eps.getEigenvector(i, x)
    X.append(x)
    theta.append(eps.getEigenvalue(i).real)
order = np.argsort(theta, kind="stable")
X = [X[i] for i in order]
theta = np.array(theta)[order]
scale = -sigma / 1e-7
if nconv and theta[0] + sigma <= 1e-9 * scale:
    fail(
        f"a mode at λ = {theta[0] + sigma:.3e} rad²/s², {nr} rigid-body motions deflated: the model has a "
        "mechanism (a zero-energy motion that is not a rigid-body motion), which the multigrid's near-null "
        "space does not hold; solve with --solver direct, or constrain the mechanism"
    )
eps.destroy()
refinements, solves = 0, 0
rksp = None


def kept_worst(th, XX):
    return max((backward(XX[j], th[j] + sigma) for j in range(min(want_el, len(XX)))), default=0.0)


worst = kept_worst(theta, X)
for _ in range(int(p.get("max_refine", 4))):
    if worst <= float(p.get("refine_tol", 1e-13)) or not X:
        break
    if rksp is None:
        rksp = gamg_ksp(1e-12, "refine_")
    Y = []
    for x in X:
        y = x.duplicate()
        mx = x.duplicate()
        M.mult(x, mx)
        rksp.solve(mx, y)
        solves += rksp.getIterationNumber()
        Y.append(y)
    refinements += 1
    # A's Ritz values: K now holds A.
    th, Z = rayleigh_ritz(Y)
    X = [combine(Y, Z[:, j]) for j in range(len(Y))]
    theta = th
    worst = kept_worst(theta, X)
lam = np.concatenate([np.array(rigid_lam), theta[:want_el] + sigma])
Xk = rigid_vecs + X[:want_el]
m = len(lam)
mark("refine", t)

t = time.perf_counter()
xr = A.createVecRight()
scatter, x0 = PETSc.Scatter.toZero(xr)
vecs = []
for j in range(m):
    Xk[j].copy(xr)
    scatter.scatter(xr, x0, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
    if rank == 0:
        vecs.append(x0.getArray().copy())
mark("gather", t)

# 5. Sturm count above the last mode with an out-of-core MUMPS factorisation, if it fits.
t = time.perf_counter()
lam_max = float(lam[-1]) if m else 0.0
above = theta[want_el:] + sigma if nconv > want_el else np.array([])
step = 1e-4 * max(abs(lam_max), 1.0)
if len(above):
    step = min(step, 0.5 * (above[0] - lam_max))
upper_pt = lam_max + max(step, 1e-9 * abs(lam_max))
# Below σ < 0 no eigenvalue: K is positive semidefinite (elastic elements, no prestress), so
# K − σM is positive definite.
lower_pt = sigma
sturm = {"lower": [lower_pt, 0]}
budget_mb = int(float(p.get("sturm_budget", 0)) / 2**20 / comm.getSize())
if budget_mb <= 0:
    sturm["sturm_skipped"] = "no memory was left in the budget for a factorisation"
else:
    # K − s·M = A − (s − σ)M in A's storage (A is not needed any more); MUMPS out of core
    # (ICNTL(22)) with its working memory capped at the budget (ICNTL(23), MB per rank): a
    # factorisation that needs more stops at the analysis and the count is skipped.
    A.axpy(-(upper_pt - sigma), M, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
    os.environ.setdefault("MUMPS_OOC_TMPDIR", wd)
    pc = PETSc.PC().create(comm=comm)
    pc.setOperators(A)
    pc.setType(PETSc.PC.Type.CHOLESKY)
    pc.setFactorSolverType("mumps")
    pc.setFactorSetUpSolverType()
    F = pc.getFactorMatrix()
    for key, val in ((13, 1), (24, 1), (22, 1), (23, budget_mb)):
        F.setMumpsIcntl(key, val)
    try:
        pc.setUp()
        err = F.getMumpsInfog(1)
    except PETSc.Error:
        err = F.getMumpsInfog(1) or -1
    if err < 0:
        sturm["sturm_skipped"] = (
            f"MUMPS's out-of-core factorisation of K − sM needs more than the {budget_mb} MB per rank left in "
            f"the memory budget (INFOG(1) = {err}; estimated {F.getMumpsInfog(26)} MB out of core, "
            f"{F.getMumpsInfog(16)} MB in core)"
        )
    else:
        neg, zero, pos = F.getInertia()
        sturm["upper"] = [upper_pt, int(neg)]
        sturm["zero_pivots"] = [0, int(zero)]
        sturm["sturm_mb"] = [F.getMumpsInfog(26), F.getMumpsInfog(16)]
    pc.destroy()
mark("sturm", t)

if rank == 0:
    lam.astype("<f8").tofile(os.path.join(wd, "lambda.bin"))
    np.asarray(vecs, dtype="<f8").reshape(-1).tofile(os.path.join(wd, "vectors.bin"))
    info = {
        "n": n,
        "nconv": m,
        "converged": nconv + nr,
        "iterations": its,
        "ranks": comm.getSize(),
        "sigma": sigma,
        "method": method,
        "rigid": nr,
        "refinements": refinements,
        "refine_cg_iterations": solves,
        "block_size": bs,
        "timings_s": timings,
        "memory_mib": memory,
        "slepc": "%d.%d.%d" % SLEPc.Sys.getVersion()[:3],
        "petsc": "%d.%d.%d" % PETSc.Sys.getVersion()[:3],
    }
    info.update(sturm)
    with open(os.path.join(wd, "slepc.json"), "w") as fh:
        json.dump(info, fh)
