#!/usr/bin/env python3
"""The low-memory engine's phases alone, for measuring memory and time option by option
(docs/lowmem.md, *1M*): load, rigid-body pairs, shift, the multigrid's set-up, then optionally
a CG solve and a few LOBPCG iterations, with the resident memory after each phase.

    /usr/bin/python3 validation/lowmem_gamg.py DIR [--cg] [--lobpcg N] [-petsc_option value ...]

DIR is a folder of the engine's protocol (K.petsc, M.petsc, R.bin, params.json; the keys of
params.json apply, e.g. ``mat_type_m``). PETSc options on the command line (``-pc_gamg_threshold
0.02``) override the script's GAMG defaults. Prints one line per phase: wall time, this process's
resident memory now and its peak (MiB); and one JSON line at the end. One rank (or mpirun -n N).
"""
import json
import os
import resource
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "src", "app", "engines"))
argv = sys.argv[1:]
want_cg = "--cg" in argv
n_lobpcg = int(argv[argv.index("--lobpcg") + 1]) if "--lobpcg" in argv else 0
petsc_args = [a for i, a in enumerate(argv[1:], 1)
              if a != "--cg" and a != "--lobpcg" and not (i > 1 and argv[i - 1] == "--lobpcg")]
sys.argv = [sys.argv[0], argv[0]]
import slepc_lowmem as S  # noqa: E402  (reads DIR/params.json)

PETSc, SLEPc = S.PETSc, S.SLEPc
for a in [a for a in petsc_args if "=" in a and not a.startswith("-")]:  # params.json keys: coarse="gamg"
    k, v = a.split("=", 1)
    S.P[k] = json.loads(v)
    petsc_args.remove(a)
for i, a in enumerate(petsc_args):
    if a.startswith("-"):
        val = petsc_args[i + 1] if i + 1 < len(petsc_args) and not petsc_args[i + 1].startswith("-") else ""
        S.OPTS[a[1:]] = val
OUT: dict = {"options": petsc_args, "loadavg_start": os.getloadavg()}


def rss_mib() -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return 0.0


def phase(name: str, t0: float) -> None:
    S.trim()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    OUT[name] = {"s": round(time.perf_counter() - t0, 2), "rss": round(rss_mib()), "peak": round(peak)}
    PETSc.Sys.Print(f"{name:8s} {OUT[name]['s']:8.2f} s  rss {OUT[name]['rss']:6d} MiB  peak {OUT[name]['peak']:6d} MiB "
                    f"load {os.getloadavg()[0]:.1f}", comm=S.COMM)
    sys.stdout.flush()


t = time.perf_counter()
pen = S.Pencil()
phase("load", t)
t = time.perf_counter()
R, rigid_lam, rigid_vecs = S.rigid_pairs(pen)
phase("rigid", t)
t = time.perf_counter()
pen.shift(float(S.P["sigma"]))
S.multigrid(pen, R)
pen.compact()
phase("shift", t)
t = time.perf_counter()
ksp = PETSc.KSP().create(comm=S.COMM)
ksp.setOptionsPrefix("st_")  # as the engine's inverse: its options are -st_...
ksp.setOperators(pen.K)
ksp.setType("cg")
S.precondition(ksp.getPC(), pen)
ksp.setTolerances(rtol=1e-8, atol=0.0, max_it=500)
ksp.setFromOptions()
ksp.setUp()
phase("gamg", t)
pc = ksp.getPC()
try:
    levels = pc.getMGLevels()
    sizes = []
    for lv in range(levels):
        op = pc.getMGSmoother(lv).getOperators()[0]
        info = op.getInfo()
        sizes.append([op.getSize()[0], int(info["nz_used"])])
    OUT["levels"] = sizes
    fine = sizes[-1][1]
    OUT["operator_complexity"] = round(sum(s[1] for s in sizes) / fine, 3)
    PETSc.Sys.Print(f"levels (n, nnz) {sizes} complexity {OUT['operator_complexity']}", comm=S.COMM)
    if pen.mg is not None:
        cpc = pc.getMGCoarseSolve().getPC()
        csz = []
        for lv in range(cpc.getMGLevels()):
            op = cpc.getMGSmoother(lv).getOperators()[0]
            csz.append([op.getSize()[0], int(op.getInfo()["nz_used"])])
        OUT["coarse_levels"] = csz
        OUT["operator_complexity"] = round((sum(c[1] for c in csz) + fine) / fine, 3)
        PETSc.Sys.Print(f"coarse GAMG levels {csz} complexity {OUT['operator_complexity']}", comm=S.COMM)
except PETSc.Error:
    pass
if want_cg:
    b = pen.K.createVecLeft()
    x = b.duplicate()
    b.setRandom()
    t = time.perf_counter()
    ksp.solve(b, x)
    OUT["cg_its"] = ksp.getIterationNumber()
    phase("cg", t)
    PETSc.Sys.Print(f"cg its {OUT['cg_its']} per it {OUT['cg']['s'] / max(1, OUT['cg_its']):.3f} s", comm=S.COMM)
    t = time.perf_counter()
    for _ in range(5):
        pen.K.mult(b, x)
    OUT["matvec_s"] = round((time.perf_counter() - t) / 5, 4)
ksp.destroy()
if n_lobpcg:
    S.P["max_it"] = n_lobpcg
    S.OPTS["eps_monitor"] = ""
    t = time.perf_counter()
    try:
        S.eigensolve(pen, rigid_vecs, int(S.P["nev"]) - len(rigid_lam))
    except SystemExit:
        pass  # fewer converged than wanted after n_lobpcg iterations: expected
    phase("lobpcg", t)
    OUT["lobpcg_per_it_s"] = round(OUT["lobpcg"]["s"] / n_lobpcg, 2)
OUT["loadavg_end"] = os.getloadavg()
PETSc.Sys.Print(json.dumps(OUT), comm=S.COMM)
