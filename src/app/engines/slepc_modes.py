"""SLEPc engine of vibrofem: run under mpirun by `vibrofem modes --engine slepc` (or by hand on
a cluster, see the README's cluster recipe) on a folder written by `vibrofem export`.

    mpirun -n N python3 slepc_modes.py DIR

Reads DIR/K.petsc, DIR/M.petsc and DIR/params.json; solves K x = λ M x with Krylov–Schur,
shift-and-invert about σ with a MUMPS LDLᵀ factorisation, and counts the eigenvalues below the
ends of the range found from the inertia of MUMPS factorisations of K − s M (Sturm counts).
The pairs kept (the nev nearest σ, or the band) are refined by one inverse iteration with a
Rayleigh–Ritz step. Rank 0 writes DIR/lambda.bin (f64, little-endian), DIR/vectors.bin (n × kept,
column after column) and DIR/slepc.json (counts, timings, versions). vibrofem then recomputes the residuals
with its own K and M.
"""
import json
import os
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
# Inertia of a MUMPS factorisation on several ranks needs the root's Schur part on one process.
opts["mat_mumps_icntl_13"] = 1
# ...and null-pivot detection on, to report the zero count along with the negative one.
opts["mat_mumps_icntl_24"] = 1
timings = {}
t = time.perf_counter()


def load(name):
    v = PETSc.Viewer().createBinary(os.path.join(wd, name), "r", comm=comm)
    a = PETSc.Mat().create(comm=comm)
    a.setType(PETSc.Mat.Type.AIJ)
    a.load(v)
    v.destroy()
    a.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    a.setOption(PETSc.Mat.Option.SPD, False)
    return a


K = load("K.petsc")
M = load("M.petsc")
n = K.getSize()[0]
timings["load"] = time.perf_counter() - t


def factor_pc(A):
    pc = PETSc.PC().create(comm=comm)
    pc.setOperators(A)
    pc.setType(PETSc.PC.Type.CHOLESKY)
    pc.setFactorSolverType("mumps")
    pc.setUp()
    return pc


def negative_count(s):
    """Eigenvalues below s: negative pivots of an LDLᵀ of K − s M (Sylvester)."""
    A = K.duplicate(copy=True)
    A.axpy(-s, M, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
    pc = factor_pc(A)
    neg, zero, pos = pc.getFactorMatrix().getInertia()
    pc.destroy()
    A.destroy()
    return int(neg), int(zero)


t = time.perf_counter()
eps = SLEPc.EPS().create(comm=comm)
eps.setOperators(K, M)
eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
st = eps.getST()
st.setType(SLEPc.ST.Type.SINVERT)
ksp = st.getKSP()
ksp.setType(PETSc.KSP.Type.PREONLY)
pc = ksp.getPC()
pc.setType(PETSc.PC.Type.CHOLESKY)
pc.setFactorSolverType("mumps")
sigma = float(p["sigma"])
band = p.get("band")
if band is not None:
    # Spectrum slicing: every eigenvalue in [lo, hi], counted by SLEPc's own inertias.
    eps.setWhichEigenpairs(SLEPc.EPS.Which.ALL)
    eps.setInterval(float(band[0]), float(band[1]))
else:
    eps.setTarget(sigma)
    st.setShift(sigma)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    # More pairs than wanted: Krylov–Schur's outermost converged pairs are the least accurate
    # (18 wanted of 18 asked came back with backward errors of 7e-9 on the S2 plate, and inverse
    # iteration gains only (λ_nev − σ)/(λ_next − σ) per step); with half as many again the wanted
    # ones are interior and one refinement brings them to rounding.
    eps.setDimensions(int(p["nev"]) + max(6, int(p["nev"]) // 2))
# ‖Kx − λMx‖ / ((‖K‖ + |λ|‖M‖)‖x‖): the backward error vibrofem accepts at 1e-10.
eps.setConvergenceTest(SLEPc.EPS.Conv.NORM)
eps.setTolerances(float(p.get("tol", 1e-12)), int(p.get("max_it", 1000)))
eps.setFromOptions()
eps.solve()
timings["solve"] = time.perf_counter() - t
nconv = eps.getConverged()
its = eps.getIterationNumber()

t = time.perf_counter()
lam_all = np.array([eps.getEigenvalue(i).real for i in range(nconv)])
nev = int(p.get("nev", 0))
if band is not None:
    lo, hi = float(band[0]), float(band[1])
    want = [i for i in range(nconv) if lo <= lam_all[i] <= hi]
else:
    want = list(np.argsort(np.abs(lam_all - sigma), kind="stable")[:nev])
# Every converged pair joins the refinement (up to twice the wanted count plus ten): the
# neighbours above the last wanted mode would otherwise stay mixed into it.
guard = [i for i in np.argsort(np.abs(lam_all - sigma), kind="stable") if i not in want]
basis = sorted(want + guard[: max(0, min(len(guard), len(want) + 10))], key=lambda i: lam_all[i])


def rayleigh_ritz(X):
    """Ritz values (ascending) and coefficients of span(X) for K, M."""
    m = len(X)
    KY = [K.createVecRight() for _ in range(m)]
    MY = [K.createVecRight() for _ in range(m)]
    for j in range(m):
        K.mult(X[j], KY[j])
        M.mult(X[j], MY[j])
    Kr = np.array([[X[i].dot(KY[j]) for j in range(m)] for i in range(m)])
    Mr = np.array([[X[i].dot(MY[j]) for j in range(m)] for i in range(m)])
    Kr, Mr = 0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T)
    # Scale to unit diagonal of Mr, then Mr = L Lᵀ, C = L⁻¹ Kr L⁻ᵀ, C W = W θ, Z = L⁻ᵀ W.
    d = 1.0 / np.sqrt(np.diag(Mr))
    Li = np.linalg.inv(np.linalg.cholesky(Mr * np.outer(d, d)))
    C = Li @ (Kr * np.outer(d, d)) @ Li.T
    theta, W = np.linalg.eigh(0.5 * (C + C.T))
    return theta, (Li.T @ W) * d[:, None]


def combine(X, z):
    x = K.createVecRight()
    x.set(0.0)
    x.maxpy(list(z), X)
    return x


# Inverse iteration with the shift factor SLEPc already holds, then Rayleigh–Ritz on the result
# (as vibrofem's native solver does): Krylov–Schur's residual estimates are optimistic for the
# outermost pairs. Repeated (at most three times) until every wanted pair's backward error
# ‖Kx − λMx‖ / ((‖K‖∞ + |λ|‖M‖∞)‖x‖) is at rounding level, one solve per pair each time.
normK, normM = K.norm(PETSc.NormType.INFINITY), M.norm(PETSc.NormType.INFINITY)
X = []
for i in basis:
    x = K.createVecRight()
    eps.getEigenvector(i, x)
    X.append(x)
refinements = 0
for _ in range(3):
    Y = []
    for x in X:
        y = K.createVecRight()
        st.apply(x, y)
        Y.append(y)
    refinements += 1
    theta, Z = rayleigh_ritz(Y)
    X = [combine(Y, Z[:, j]) for j in range(len(Y))]
    if band is None:
        sel = np.sort(np.argsort(np.abs(theta - sigma), kind="stable")[:nev])
    else:
        sel = np.nonzero((theta >= lo) & (theta <= hi))[0]
    r = K.createVecRight()
    worst = 0.0
    for j in sel:
        K.mult(X[j], r)
        mx = K.createVecRight()
        M.mult(X[j], mx)
        r.axpy(-theta[j], mx)
        worst = max(worst, r.norm() / ((normK + abs(theta[j]) * normM) * X[j].norm()))
    if worst <= 1e-14:
        break
timings["refinements"] = refinements
timings["refine"] = time.perf_counter() - t

# Sturm points around what was found (the same rule as vibrofem's native check).
t = time.perf_counter()
lam_sorted = np.sort(lam_all)
if band is not None:
    lower_pt = lo if lo > 0 else min(sigma, lo - abs(lo) * 1e-9 - 1e-9)
    upper_pt = hi
else:
    lam = theta[sel]
    lam_min = lam[0] if len(lam) else sigma
    lam_max = lam[-1] if len(lam) else sigma
    scale = max(abs(lam_max), abs(sigma))
    step = 1e-4 * scale
    # Below the spectrum (σ < 0), values within 1e-6 |σ| of 0 are the rigid-body modes'
    # rounding (±1e-4 rad²/s² on a steel bar, σ = −2e5): one root, never split by the point (a
    # point between two of them counted 0 of 3 on a free box asked for 2 modes).
    zero = 1e-6 * abs(sigma) if sigma < 0 else 0.0
    above = lam_sorted[(lam_sorted > lam_max + 1e-9 * scale) & (lam_sorted > zero)]
    if len(above):
        step = min(step, 0.5 * (above[0] - lam_max))
    upper_pt = lam_max + max(step, 1e-9 * scale)
    lower_pt = sigma if lam_min >= sigma else lam_min - max(abs(lam_min), abs(sigma)) * 1e-6
    # Every refined pair between the points is returned (vibrofem verifies them all and keeps
    # the asked ones): the count covers them too. The rest of a repeated root at the cut (a
    # square bar's double bending root) or of the rigid-body modes when fewer were asked lies
    # there, and a job holding only the asked pairs was counted short ("8 counted, 7 found").
    inside = [j for j in range(len(theta)) if lower_pt < theta[j] < upper_pt]
    sel = np.array(sorted(set(int(j) for j in sel) | set(inside)), dtype=int)
timings["points"] = time.perf_counter() - t
lam = theta[sel]
Xk = [X[j] for j in sel]
m = len(lam)

t = time.perf_counter()
xr = K.createVecRight()
scatter, x0 = PETSc.Scatter.toZero(xr)
vecs = []
for j in range(m):
    Xk[j].copy(xr)
    scatter.scatter(xr, x0, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
    if rank == 0:
        vecs.append(x0.getArray().copy())
timings["gather"] = time.perf_counter() - t

# Sturm counts at the points.
t = time.perf_counter()
lower_count, lower_zero = negative_count(lower_pt)
upper_count, upper_zero = negative_count(upper_pt)
timings["sturm"] = time.perf_counter() - t + timings.pop("points")

if rank == 0:
    lam.astype("<f8").tofile(os.path.join(wd, "lambda.bin"))
    np.asarray(vecs, dtype="<f8").reshape(-1).tofile(os.path.join(wd, "vectors.bin"))
    with open(os.path.join(wd, "slepc.json"), "w") as f:
        json.dump(
            {
                "n": n,
                "nconv": m,
                "converged": nconv,
                "iterations": its,
                "ranks": comm.getSize(),
                "sigma": sigma,
                "lower": [lower_pt, lower_count],
                "upper": [upper_pt, upper_count],
                "zero_pivots": [lower_zero, upper_zero],
                "timings_s": timings,
                "slepc": "%d.%d.%d" % SLEPc.Sys.getVersion()[:3],
                "petsc": "%d.%d.%d" % PETSc.Sys.getVersion()[:3],
            },
            f,
        )
