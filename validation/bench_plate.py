#!/usr/bin/env python3
"""End-to-end benchmark on the S2 plate (0.9 x 0.4 x 0.116 m, tet10, free-free): scikit-fem vs vibrofem.

For each size it generates (once) the gmsh mesh ``validation/out/bench_s2_plate_tet10_h<H>.msh``
(not committed), then runs, each in its own process, on the same mesh and asking for the
12 lowest elastic modes (18 with the 6 rigid ones):

* scikit-fem: read (gmsh API) -> assemble K and M (ElementTetP2, exact quadrature) -> factor
  K - sigma M (SuperLU, MMD(A+A^T) ordering) -> eigsh shift-invert + one Rayleigh-Ritz
  refinement -> verify residuals; timed per phase inside the worker;
* vibrofem: ``vibrofem modes MESH --modes 18 --json --material 2.1e11,0.3,7850`` with its own
  ``timings_s``, ``peak_memory_bytes`` and ``factor_flops``.

Wall time and peak memory of each process come from ``/usr/bin/time -v`` if present (Debian
package ``time``), else from ``getrusage(RUSAGE_CHILDREN)`` of a wrapper process. Frequency
agreement = max relative difference over the 12 elastic modes. Writes a markdown table to stdout
and everything to ``validation/out/bench.json``.

Mesh sizes (gmsh 4.15.2, characteristic length h, tet10 = the tet4 mesh with midside nodes):

    label   h [mm]   nodes    dofs
    50k     27.8     17 101    51 303
    200k    16.7     65 008   195 024
    500k    12.1    166 011   498 033

Usage (from the crate root, after ``bash validation/setup.sh`` and ``cargo build --release``)::

    validation/.venv/bin/python validation/bench_plate.py                    # 50k,200k,500k
    validation/.venv/bin/python validation/bench_plate.py --sizes 50k --skip-vibrofem
    validation/.venv/bin/python validation/bench_plate.py --sizes 50k,200k --skip-skfem-above 100000

scikit-fem's run grows fast in 3D (peak 1.5 GB and ~25 s of CPU at 50k dofs; the SuperLU factor
dominates above that), so
by default it is skipped above 250 000 dofs (``--skip-skfem-above``; 0 = never skip).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = os.path.join(HERE, "out")
SIZES = {"50k": 0.0278, "200k": 0.0167, "500k": 0.0121}
S2 = (0.9, 0.4, 0.116)
STEEL = (2.1e11, 0.3, 7850.0)


# --------------------------------------------------------------------------------------------
# scikit-fem worker (runs in its own process)
# --------------------------------------------------------------------------------------------

def worker(mesh: str, n_modes: int, result: str) -> int:
    """Solve with scikit-fem, timing each phase; write a JSON result file."""
    t = {}
    t0 = time.perf_counter()
    sys.path.insert(0, HERE)
    import numpy as np
    import skfem_modes as S
    from skfem import Basis, ElementTetP2, ElementVector
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    tic = time.perf_counter()
    g = S.read_gmsh(mesh)
    m = S.skfem_mesh(g)
    t["read"] = time.perf_counter() - tic

    tic = time.perf_counter()
    assert g.kind == "tet10", g.kind
    basis = Basis(m, ElementVector(ElementTetP2()), intorder=4)
    K = linear_elasticity(*lame_parameters(STEEL[0], STEEL[1])).assemble(basis).tocsc()
    M = S._mass.assemble(basis, rho=STEEL[2]).tocsc()
    t["assemble"] = time.perf_counter() - tic
    S.check_dofs_match_nodes(basis, g)
    ex = np.zeros(K.shape[0])
    ex[0::3] = 1.0
    mass = float(ex @ (M @ ex))
    del basis, g, m

    tic = time.perf_counter()
    lu = S.factor(K - S.shift() * M)
    t["factor"] = time.perf_counter() - tic
    fill = int(lu.L.nnz + lu.U.nnz)

    tic = time.perf_counter()
    lam, vec = S.solve_modes(K, M, n_modes, lu=lu)
    t["solve"] = time.perf_counter() - tic

    tic = time.perf_counter()
    kx = K @ vec
    res = np.linalg.norm(kx - (M @ vec) * lam, axis=0) / np.linalg.norm(kx, axis=0)
    rigid = np.abs(lam) < 1e-8 * abs(lam[-1])
    t["verify"] = time.perf_counter() - tic
    t["total"] = time.perf_counter() - t0
    out = {"frequencies_hz": S.to_hz(lam), "n_rigid": int(rigid.sum()), "dofs": int(K.shape[0]),
           "mass_kg": mass, "complete": True, "timings_s": t,
           "max_rel_residual": float(res[~rigid].max()), "lu_nnz": fill,
           "peak_memory_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
           "versions": S.versions()}
    with open(result, "w") as fh:
        json.dump(out, fh, indent=1)
    return 0


# --------------------------------------------------------------------------------------------
# measuring a child process
# --------------------------------------------------------------------------------------------

def measure(cmd: list, timeout: float) -> dict:
    """Run cmd; return returncode, stdout, stderr, wall_s, peak_rss_bytes, method."""
    tic = time.perf_counter()
    if os.path.exists("/usr/bin/time"):
        with tempfile.NamedTemporaryFile("r", suffix=".time") as tf:
            p = subprocess.run(["/usr/bin/time", "-v", "-o", tf.name] + cmd, capture_output=True,
                               text=True, timeout=timeout, cwd=ROOT)
            report = open(tf.name).read()
        m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", report)
        rss = int(m.group(1)) * 1024 if m else None
        cpu = sum(float(x) for x in re.findall(r"(?:User|System) time \(seconds\): ([\d.]+)",
                                               report)) or None
        method = "/usr/bin/time -v"
    else:
        wrapper = ("import resource, subprocess, sys\n"
                   "rc = subprocess.call(sys.argv[1:])\n"
                   "r = resource.getrusage(resource.RUSAGE_CHILDREN)\n"
                   "sys.stderr.write('\\nPEAK_RSS_KB=%d CPU_S=%f\\n' % "
                   "(r.ru_maxrss, r.ru_utime + r.ru_stime))\n"
                   "sys.exit(rc)\n")
        p = subprocess.run([sys.executable, "-c", wrapper] + cmd, capture_output=True, text=True,
                           timeout=timeout, cwd=ROOT)
        m = re.search(r"PEAK_RSS_KB=(\d+) CPU_S=([\d.]+)", p.stderr)
        rss = int(m.group(1)) * 1024 if m else None
        cpu = float(m.group(2)) if m else None
        method = "getrusage(RUSAGE_CHILDREN)"
    return {"returncode": p.returncode, "stdout": p.stdout, "stderr": p.stderr,
            "wall_s": time.perf_counter() - tic, "cpu_s": cpu, "peak_rss_bytes": rss,
            "method": method}


def make_mesh(label: str, h: float) -> str:
    name = "bench_s2_plate_tet10_h" + f"{h * 1000:.6g}".replace(".", "p")
    path = os.path.join(OUT, name + ".msh")
    if not os.path.exists(path):
        sys.path.insert(0, os.path.join(ROOT, "meshes"))
        import make_meshes
        tmp = tempfile.mkdtemp(dir=OUT)
        with contextlib.redirect_stdout(sys.stderr):
            written = make_meshes.tet_box("bench_s2_plate", S2, h, tmp, orders=(2,))
        os.replace(written[name], path)
        shutil.rmtree(tmp)
    return path


def elastic_diff(a: list, b: list, nr: int) -> float:
    return max((abs(x - y) / y for x, y in zip(a[nr:], b[nr:])), default=float("nan"))


# --------------------------------------------------------------------------------------------

def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="50k,200k,500k", help=f"comma list of {list(SIZES)}")
    ap.add_argument("--modes", type=int, default=12, help="elastic modes (6 rigid are added)")
    ap.add_argument("--skip-skfem-above", type=int, default=250_000,
                    help="skip scikit-fem above this many dofs (0: never)")
    ap.add_argument("--skip-vibrofem", action="store_true")
    ap.add_argument("--vibrofem", default=os.path.join(ROOT, "target", "release", "vibrofem"))
    ap.add_argument("--timeout", type=float, default=3600.0, help="seconds per run")
    ap.add_argument("--worker", nargs=3, metavar=("MESH", "N", "RESULT"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        return worker(args.worker[0], int(args.worker[1]), args.worker[2])

    os.makedirs(OUT, exist_ok=True)
    n_total = args.modes + 6
    runs = []
    for label in args.sizes.split(","):
        label = label.strip()
        if label not in SIZES:
            ap.error(f"unknown size {label!r}; known: {', '.join(SIZES)}")
        h = SIZES[label]
        mesh = make_mesh(label, h)
        with open(mesh) as fh:   # node count from the $Nodes header (MSH 4.1: 2nd number)
            text = fh.read(1 << 16)
        nodes = int(text.split("$Nodes\n", 1)[1].split()[1])
        row = {"size": label, "h_mm": h * 1000, "mesh": os.path.relpath(mesh, ROOT),
               "dofs": 3 * nodes}
        print(f"# {label}: {row['mesh']} ({row['dofs']} dofs)", file=sys.stderr, flush=True)

        if args.skip_skfem_above and row["dofs"] > args.skip_skfem_above:
            row["skfem"] = {"skipped": f"dofs > {args.skip_skfem_above}"}
        else:
            with tempfile.NamedTemporaryFile(suffix=".json", dir=OUT) as tf:
                meas = measure([sys.executable, os.path.abspath(__file__), "--worker", mesh,
                                str(n_total), tf.name], args.timeout)
                res = json.load(open(tf.name)) if meas["returncode"] == 0 else None
            row["skfem"] = {"result": res, "wall_s": meas["wall_s"], "cpu_s": meas["cpu_s"],
                            "peak_rss_bytes": meas["peak_rss_bytes"], "method": meas["method"],
                            "returncode": meas["returncode"],
                            "stderr": meas["stderr"][-2000:] if meas["returncode"] else ""}

        if args.skip_vibrofem:
            row["vibrofem"] = {"skipped": "--skip-vibrofem"}
        elif not os.access(args.vibrofem, os.X_OK):
            row["vibrofem"] = {"skipped": f"{args.vibrofem} not built"}
        else:
            cmd = [args.vibrofem, "modes", mesh, "--modes", str(n_total), "--json",
                   "--material", ",".join(repr(float(x)) for x in STEEL)]
            meas = measure(cmd, args.timeout)
            res = None
            if meas["returncode"] == 0:
                try:
                    res = json.loads(meas["stdout"])
                except json.JSONDecodeError:
                    s, e = meas["stdout"].find("{"), meas["stdout"].rfind("}")
                    res = json.loads(meas["stdout"][s:e + 1])
            row["vibrofem"] = {"result": res, "wall_s": meas["wall_s"], "cpu_s": meas["cpu_s"],
                               "command": cmd,
                               "peak_rss_bytes": meas["peak_rss_bytes"], "method": meas["method"],
                               "returncode": meas["returncode"],
                               "stderr": meas["stderr"][-2000:] if meas["returncode"] else ""}

        a = (row["skfem"].get("result") or {}).get("frequencies_hz")
        b = (row["vibrofem"].get("result") or {}).get("frequencies_hz")
        if a and b:
            row["max_rel_diff_elastic"] = elastic_diff(sorted(b), a, 6)
        runs.append(row)

    report = {"case": "S2 plate 0.9 x 0.4 x 0.116 m, tet10, free-free, steel",
              "elastic_modes": args.modes, "machine": {
                  "cpus": os.cpu_count(), "platform": platform.platform(),
                  "python": platform.python_version(), "loadavg_at_end": os.getloadavg()},
              "runs": runs}
    with open(os.path.join(OUT, "bench.json"), "w") as fh:
        json.dump(report, fh, indent=1)

    def fmt(x, f="{:.2f}"):
        return "-" if x is None else f.format(x)

    print("| size | h mm | dofs | tool | read s | assemble s | factor s | solve s | total s "
          "| wall s | cpu s | peak RSS MB | f7 Hz | max rel diff | note |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for row in runs:
        for tool in ("skfem", "vibrofem"):
            r = row[tool]
            res = r.get("result") or {}
            tim = res.get("timings_s") or {}
            f = res.get("frequencies_hz")
            nr = res.get("n_rigid", 6)
            status = r.get("skipped") or ("" if res else f"failed (exit {r.get('returncode')})")
            rss = r.get("peak_rss_bytes")
            print(f"| {row['size']} | {row['h_mm']:.1f} | {row['dofs']} | {tool} "
                  f"| {fmt(tim.get('read'))} | {fmt(tim.get('assemble'))} "
                  f"| {fmt(tim.get('factor'))} | {fmt(tim.get('solve'))} "
                  f"| {fmt(tim.get('total'))} | {fmt(r.get('wall_s'))} | {fmt(r.get('cpu_s'))} "
                  f"| {fmt(rss / 1e6 if rss else None, '{:.0f}')} "
                  f"| {fmt(f[nr] if f and len(f) > nr else None, '{:.4f}')} "
                  f"| {fmt(row.get('max_rel_diff_elastic') if tool == 'vibrofem' else None, '{:.1e}')}"
                  f" | {status} |")
    print(f"\nJSON: {os.path.relpath(os.path.join(OUT, 'bench.json'), ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
