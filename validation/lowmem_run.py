#!/usr/bin/env python3
"""Drive the low-memory modal path (src/app/engines/slepc_lowmem.py) on a mesh and compare it
with vibrofem's direct path.

    /usr/bin/python3 validation/lowmem_run.py MESH [--modes 18] [--method lobpcg|slepc-lobpcg|ks-cg|ks-mumps]
        [--ranks 1] [--sturm-budget BYTES] [--param KEY=JSON ...] [--direct] [--check]
        [--kill-above GIB] [--vibrofem target/release/vibrofem] [--workdir DIR]

1. ``vibrofem export MESH`` writes K and M (PETSc binary) and dofs.csv (equation, node,
   component, coordinates) into a work folder;
2. the six rigid-body motions of the free DOFs are written to R.bin (6 rows of n f64) from the
   coordinates in dofs.csv (translations; rotations about the centroid);
3. ``mpirun -n RANKS python3 slepc_lowmem.py DIR`` runs while a poller sums the resident memory of
   the whole process tree every 0.2 s (mpirun, its ranks);
   and kills it when that sum passes ``--kill-above`` GiB (default 10);
4. with ``--check``, validation/lowmem_check.py recomputes every pair's backward error with the
   direct path's definition from K.petsc and M.petsc (numpy, row chunks), in its own process;
5. with ``--direct``, ``vibrofem modes MESH --json`` gives the reference frequencies and the
   largest relative difference of the elastic ones is printed.

Prints one JSON document: the job's slepc.json, the tree's peak memory, wall times, and the
comparison. Solids only (three translations per node). Debian's python3-slepc4py and openmpi-bin
(``bash validation/setup_slepc.sh``).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SCRIPT = os.path.join(ROOT, "src", "app", "engines", "slepc_lowmem.py")
ENV = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
           PETSC_DIR=os.environ.get("PETSC_DIR", "/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real"),
           SLEPC_DIR=os.environ.get("SLEPC_DIR", "/usr/lib/slepcdir/slepc3.18/x86_64-linux-gnu-real"))


def tree_rss(root: int) -> int:
    """Resident bytes of `root` and every descendant (from /proc)."""
    parent, rss = {}, {}
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat") as fh:
                st = fh.read().rsplit(")", 1)[1].split()
            parent[int(d)] = int(st[1])
            rss[int(d)] = int(st[21]) * os.sysconf("SC_PAGE_SIZE")
        except (OSError, IndexError, ValueError):
            continue
    total, todo = 0, [root]
    while todo:
        p = todo.pop()
        total += rss.get(p, 0)
        todo += [c for c, pp in parent.items() if pp == p]
    return total


def run_polled(cmd: list, cwd=None, kill_above: float = 10 * 2**30) -> dict:
    """Run `cmd`, polling its process tree's resident memory; wall time and the tree's peak. The
    tree is killed when its resident memory passes `kill_above` bytes (a watchdog for big runs)."""
    t = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=cwd, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    peak = [0]

    def poll():
        while proc.poll() is None:
            peak[0] = max(peak[0], tree_rss(proc.pid))
            if peak[0] > kill_above:
                os.killpg(proc.pid, 9)
                sys.stderr.write(f"lowmem_run: process tree above {kill_above / 2**30:.1f} GiB, killed\n")
                return
            time.sleep(0.2)

    th = threading.Thread(target=poll)
    th.start()
    out, err = proc.communicate()
    th.join()
    return {"returncode": proc.returncode, "wall_s": time.perf_counter() - t, "tree_peak_bytes": peak[0],
            "stdout": out, "stderr": err}


def rigid_modes(dofs_csv: str) -> np.ndarray:
    """The six rigid-body motions on the free DOFs (rows), from dofs.csv's coordinates."""
    comp = {"ux": 0, "uy": 1, "uz": 2}
    c, x = [], []
    with open(dofs_csv) as fh:
        next(fh)
        for line in fh:
            f = line.rstrip("\n").split(",")
            if f[3] not in comp:
                raise SystemExit(f"{dofs_csv}: component {f[3]}: the low-memory path takes solids only")
            c.append(comp[f[3]])
            x.append((float(f[4]), float(f[5]), float(f[6])))
    c, x = np.array(c), np.array(x)
    x -= x.mean(axis=0)
    n = len(c)
    R = np.zeros((6, n))
    R[c, np.arange(n)] = 1.0
    for a in range(3):
        e = np.zeros(3)
        e[a] = 1.0
        u = np.cross(e, x)  # rotation about axis a through the centroid
        R[3 + a] = u[np.arange(n), c]
    return R


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("mesh")
    ap.add_argument("--modes", type=int, default=18)
    ap.add_argument("--method", default="ks-cg", choices=["lobpcg", "slepc-lobpcg", "ks-cg", "ks-mumps"])
    ap.add_argument("--param", action="append", default=[], metavar="KEY=JSON",
                    help="extra params.json key (e.g. inner_rtol=1e-9, petsc_options={\"eps_monitor\":\"\"})")
    ap.add_argument("--check", action="store_true", help="recompute the backward errors (validation/lowmem_check.py)")
    ap.add_argument("--kill-above", type=float, default=10.0, help="GiB: kill the process tree above this")
    ap.add_argument("--ranks", type=int, default=1)
    ap.add_argument("--sturm-budget", type=float, default=0.0, help="bytes for MUMPS's out-of-core Sturm count")
    ap.add_argument("--material", default="2.1e11,0.3,7850")
    ap.add_argument("--direct", action="store_true", help="compare with vibrofem modes (in core)")
    ap.add_argument("--vibrofem", default=os.path.join(ROOT, "target", "release", "vibrofem"))
    ap.add_argument("--workdir", default=None)
    a = ap.parse_args(argv)
    wd = a.workdir or tempfile.mkdtemp(prefix="vibrofem-lowmem-")
    os.makedirs(wd, exist_ok=True)
    res = {"mesh": a.mesh, "method": a.method, "ranks": a.ranks, "loadavg_at_start": os.getloadavg()}
    ex = run_polled([a.vibrofem, "export", a.mesh, "--material", a.material, "--out", wd])
    if ex["returncode"]:
        raise SystemExit(ex["stderr"])
    res["export"] = {"wall_s": ex["wall_s"], "tree_peak_bytes": ex["tree_peak_bytes"]}
    for f in ("K.mtx", "M.mtx"):  # not needed here; they take disk only
        if os.path.exists(os.path.join(wd, f)):
            os.remove(os.path.join(wd, f))
    R = rigid_modes(os.path.join(wd, "dofs.csv"))
    R.astype("<f8").tofile(os.path.join(wd, "R.bin"))
    with open(os.path.join(wd, "params.json")) as fh:
        p = json.load(fh)
    p.update({"nev": a.modes, "rigid": 6, "block_size": 3, "method": a.method, "sturm_budget": a.sturm_budget})
    for kv in a.param:
        k, v = kv.split("=", 1)
        p[k] = json.loads(v)
    with open(os.path.join(wd, "params.json"), "w") as fh:
        json.dump(p, fh)
    del R
    mpi = ["mpirun", "--allow-run-as-root"] if os.geteuid() == 0 else ["mpirun"]
    res["loadavg_before_engine"] = os.getloadavg()
    run = run_polled(["/usr/bin/time", "-v"] + mpi + ["-n", str(a.ranks), "/usr/bin/python3", SCRIPT, wd],
                     kill_above=a.kill_above * 2**30)
    res["loadavg_after_engine"] = os.getloadavg()
    for line in run["stderr"].splitlines():
        if "Maximum resident set size" in line:
            res["time_v_max_rss_kib"] = int(line.split()[-1])  # the largest single process (GNU time)
    res["engine"] = {"wall_s": run["wall_s"], "tree_peak_bytes": run["tree_peak_bytes"],
                     "returncode": run["returncode"]}
    if run["returncode"]:
        res["engine"]["stderr"] = run["stderr"][-3000:]
    with open(os.path.join(wd, "slepc.json")) as fh:
        res["job"] = json.load(fh)
    if "error" not in res["job"]:
        lam = np.fromfile(os.path.join(wd, "lambda.bin"), dtype="<f8")
        res["frequencies_hz"] = list(np.sqrt(np.abs(lam)) / (2 * np.pi) * np.sign(lam))
        if a.check:
            c = run_polled(["/usr/bin/python3", os.path.join(HERE, "lowmem_check.py"), wd])
            res["check"] = json.loads(c["stdout"]) if c["returncode"] == 0 else {"error": c["stderr"][-2000:]}
            res["check"]["tree_peak_bytes"] = c["tree_peak_bytes"]
    if a.direct and "frequencies_hz" in res:
        d = run_polled(["/usr/bin/time", "-v", a.vibrofem, "modes", a.mesh, "--modes", str(a.modes), "--json",
                        "--material", a.material])
        rep = json.loads(d["stdout"])
        f_d = np.array(rep["frequencies_hz"])
        f_i = np.array(res["frequencies_hz"])
        nr = rep.get("n_rigid", 6)
        res["direct"] = {"wall_s": d["wall_s"], "tree_peak_bytes": d["tree_peak_bytes"],
                         "frequencies_hz": list(f_d), "max_backward_error": rep.get("max_backward_error")}
        res["max_rel_diff_elastic"] = float(np.max(np.abs(f_i[nr:] - f_d[nr:]) / f_d[nr:]))
        res["max_abs_diff_rigid_hz"] = float(np.max(np.abs(f_i[:nr] - f_d[:nr])))
    json.dump(res, sys.stdout, indent=1)
    print()
    return 0 if "error" not in res["job"] else 3


if __name__ == "__main__":
    sys.exit(main())
