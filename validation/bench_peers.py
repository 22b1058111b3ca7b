#!/usr/bin/env python3
"""Side-by-side benchmark of vibrofem against CalculiX, SLEPc + MUMPS and scikit-fem.

The S2 plate (0.9 x 0.4 x 0.116 m, steel, free-free) meshed by gmsh with tet10 at several sizes;
every tool computes the 18 lowest modes (6 rigid + 12 elastic) of the same mesh, each run in its
own process, timed as a whole with ``/usr/bin/time -v`` (wall time, peak RSS of the largest
process of the run):

* vibrofem: ``vibrofem modes MESH --modes 18 --json`` (read to report, verified: residuals,
  M-orthonormality, Sturm count); its own phase timings come from the JSON;
* SLEPc 3.18 Krylov-Schur with a MUMPS LDL^T (Debian's python3-slepc4py, 1 MPI rank), driven by
  ``vibrofem modes MESH --engine slepc``: the figure compared is SLEPc's own eigen solve (PETSc
  load of K, M and EPSSolve, including MUMPS's factorisation), from the JSON phase ``solve``;
* CalculiX 2.20 (Debian's calculix-ccx: SPOOLES + ARPACK, shift 1): ``ccx`` on an input deck
  written here from the same mesh (C3D10, ``*FREQUENCY`` 18), whole process;
* scikit-fem (``bench_plate.py``'s worker: assemble, SuperLU shift-invert, eigsh), whole process.

Sizes (label: h in mm): 20k: 40, 65k: 25, 120k: 20.3, 300k: 14.9, 1M: 9.4 (vibrofem alone at
1M). Runs under ``--repeat-below`` seconds are repeated (``--repeat``, default 3) and the
median is reported; ``--rounds N`` runs every tool N times instead, in rounds (each tool once
per round, the order rotated), and adds each peer's time over vibrofem's round by round (median
and range): on a shared machine a slow spell then falls on all the tools alike. ``--lowmem`` compares the in-core and the low-memory paths instead (time
per mode, memory per DOF; live up to ``--lowmem-live-up-to`` DOFs, from the runs logged in
``validation/lowmem_results.json`` above). Writes ``validation/out/bench_peers.json``, a log-log plot of wall time and
peak memory against DOFs (``validation/out/bench_peers.svg``, copied to ``docs/bench_peers.svg``
with ``--readme``), and the markdown table; with ``--readme`` (or ``--docs``) the table replaces
the block between ``<!-- bench_peers:begin -->`` and ``<!-- bench_peers:end -->`` in
docs/performance.md (*Against other solvers*; the README keeps a hand-written summary).

Usage (crate root, after ``cargo build --release``; installs CalculiX and SLEPc through
``validation/setup_peers.sh`` when missing)::

    validation/.venv/bin/python validation/bench_peers.py --quick          # 20k, all tools, 1 run
    validation/.venv/bin/python validation/bench_peers.py --sizes 20k,65k,120k --tools vibrofem,slepc
    validation/.venv/bin/python validation/bench_peers.py --sizes 120k --tools vibrofem,slepc,calculix --rounds 3
    validation/.venv/bin/python validation/bench_peers.py --readme          # everything (hours)
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = os.path.join(HERE, "out")
sys.path.insert(0, HERE)
import bench_plate as BP  # noqa: E402  (measure, make_mesh, the scikit-fem worker)

SIZES = {"20k": 0.040, "65k": 0.025, "120k": 0.0203, "300k": 0.0149, "1M": 0.0094}
TOOLS = ("vibrofem", "slepc", "calculix", "skfem")
STEEL = BP.STEEL
N_MODES = 18


def dofs_of(mesh: str) -> int:
    with open(mesh) as fh:  # MSH 4.1: the $Nodes header's second number is the node count
        text = fh.read(1 << 16)
    return 3 * int(text.split("$Nodes\n", 1)[1].split()[1])


def write_ccx_deck(mesh: str, path: str) -> None:
    """CalculiX input deck of the tet10 mesh: nodes, C3D10 cells (gmsh's last two midside nodes
    swapped into Abaqus order), steel, one *FREQUENCY step for N_MODES modes."""
    import gmsh
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.open(mesh)
    tags, coords, _ = gmsh.model.mesh.getNodes()
    etags, enodes = gmsh.model.mesh.getElementsByType(11)  # tet10
    gmsh.finalize()
    with open(path, "w") as fh:
        fh.write("*NODE, NSET=NALL\n")
        for i, t in enumerate(tags):
            x, y, z = (float(c) for c in coords[3 * i:3 * i + 3])
            fh.write(f"{int(t)},{x!r},{y!r},{z!r}\n")
        fh.write("*ELEMENT, TYPE=C3D10, ELSET=EALL\n")
        for i, t in enumerate(etags):
            n = [int(x) for x in enodes[10 * i:10 * i + 10]]
            n[8], n[9] = n[9], n[8]
            fh.write(f"{int(t)}," + ",".join(map(str, n[:8])) + ",\n" + ",".join(map(str, n[8:])) + "\n")
        e, nu, rho = STEEL
        fh.write(f"*MATERIAL, NAME=STEEL\n*ELASTIC\n{e!r},{nu!r}\n*DENSITY\n{rho!r}\n")
        fh.write("*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n")
        fh.write(f"*STEP\n*FREQUENCY, SOLVER=SPOOLES\n{N_MODES}\n*END STEP\n")


def ccx_frequencies(dat: str) -> list:
    """Frequencies (cycles/time) from the eigenvalue table of a CalculiX .dat file."""
    out = []
    with open(dat) as fh:
        text = fh.read()
    block = text.split("E I G E N V A L U E   O U T P U T", 1)[-1]
    for line in block.splitlines():
        m = re.match(r"\s*(\d+)\s+([-+\d.Ee]+)\s+([-+\d.Ee]+)\s+([-+\d.Ee]+)\s+([-+\d.Ee]+)\s*$", line)
        if m:
            out.append(float(m.group(4)))
        elif out and line.strip() and not line.strip()[0].isdigit():
            break
    return out


def vibrofem_json(stdout: str):
    try:
        return json.loads(stdout)
    except json.JSONDecodeError:
        s, e = stdout.find("{"), stdout.rfind("}")
        return json.loads(stdout[s:e + 1]) if s >= 0 else None


def run_tool(tool: str, mesh: str, args) -> dict:
    """One run of `tool` on `mesh`: wall s, compared s, peak bytes, frequencies, details."""
    if tool in ("vibrofem", "slepc"):
        cmd = [args.vibrofem, "modes", mesh, "--modes", str(N_MODES), "--json",
               "--material", ",".join(repr(float(x)) for x in STEEL)]
        if tool == "slepc":
            cmd += ["--engine", "slepc"]
        m = BP.measure(cmd, args.timeout)
        # Exit 2 is a run whose verification failed: its report (and timing) still counts.
        res = vibrofem_json(m["stdout"]) if m["returncode"] in (0, 2) else None
        if not res:
            return {"failed": f"exit {m['returncode']}: {m['stderr'][-500:]}"}
        tim = res["timings_s"]
        ok = bool(res.get("complete")) and bool(res.get("accurate"))
        return {"wall_s": m["wall_s"], "cpu_s": m["cpu_s"], "peak_bytes": m["peak_rss_bytes"],
                # vibrofem: the whole run; SLEPc: its eigen solve (load + EPSSolve with MUMPS).
                "compared_s": m["wall_s"] if tool == "vibrofem" else tim.get("solve"),
                "frequencies_hz": res["frequencies_hz"], "verified": ok,
                "timings_s": tim, "memory_bytes": res.get("memory_bytes"),
                "factor_gflops": res.get("factor_gflops"), "factorizations": res.get("factorizations"),
                "operator_applications": res.get("operator_applications"), "floor": res.get("floor")}
    if tool == "calculix":
        ccx = shutil.which("ccx") or shutil.which("ccx2.20")
        if not ccx:
            return {"failed": "ccx not found (validation/setup_peers.sh installs calculix-ccx)"}
        deck = os.path.splitext(mesh)[0] + "_ccx.inp"
        if not os.path.exists(deck):
            write_ccx_deck(mesh, deck)
        work = tempfile.mkdtemp(dir=OUT)
        try:
            shutil.copy(deck, os.path.join(work, "plate.inp"))
            env = dict(os.environ, OMP_NUM_THREADS=str(os.cpu_count()),
                       CCX_NPROC_EQUATION_SOLVER=str(os.cpu_count()))
            cwd = os.getcwd()
            os.chdir(work)
            try:
                m = measure_in(work, [ccx, "-i", "plate"], args.timeout, env)
            finally:
                os.chdir(cwd)
            f = ccx_frequencies(os.path.join(work, "plate.dat")) if m["returncode"] == 0 else []
        finally:
            shutil.rmtree(work, ignore_errors=True)
        if not f:
            return {"failed": f"exit {m['returncode']}: {m['stderr'][-500:]}"}
        return {"wall_s": m["wall_s"], "cpu_s": m["cpu_s"], "peak_bytes": m["peak_rss_bytes"],
                "compared_s": m["wall_s"], "frequencies_hz": f}
    if tool == "skfem":
        with tempfile.NamedTemporaryFile(suffix=".json", dir=OUT) as tf:
            m = BP.measure([sys.executable, os.path.join(HERE, "bench_plate.py"), "--worker", mesh,
                            str(N_MODES), tf.name], args.timeout)
            res = json.load(open(tf.name)) if m["returncode"] == 0 else None
        if not res:
            return {"failed": f"exit {m['returncode']}: {m['stderr'][-500:]}"}
        return {"wall_s": m["wall_s"], "cpu_s": m["cpu_s"], "peak_bytes": m["peak_rss_bytes"],
                "compared_s": m["wall_s"], "frequencies_hz": res.get("frequencies_hz"),
                "timings_s": res.get("timings_s")}
    raise ValueError(tool)


def measure_in(cwd: str, cmd: list, timeout: float, env: dict) -> dict:
    """bench_plate.measure with a working directory and environment (CalculiX writes beside
    its input)."""
    import time
    tic = time.perf_counter()
    with tempfile.NamedTemporaryFile("r", suffix=".time") as tf:
        p = subprocess.run(["/usr/bin/time", "-v", "-o", tf.name] + cmd, capture_output=True,
                           text=True, timeout=timeout, cwd=cwd, env=env)
        report = open(tf.name).read()
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", report)
    cpu = sum(float(x) for x in re.findall(r"(?:User|System) time \(seconds\): ([\d.]+)", report))
    return {"returncode": p.returncode, "stdout": p.stdout, "stderr": p.stderr,
            "wall_s": time.perf_counter() - tic, "cpu_s": cpu or None,
            "peak_rss_bytes": int(m.group(1)) * 1024 if m else None}


def aggregate(runs: list) -> dict:
    """Medians (and ranges) of the timed figures of `runs`; the rest from the median run."""
    good = [r for r in runs if "failed" not in r]
    if not good:
        return runs[0]
    out = dict(sorted(good, key=lambda r: r["wall_s"])[len(good) // 2])
    for key in ("wall_s", "compared_s", "peak_bytes", "cpu_s"):
        vals = [r[key] for r in good if r.get(key) is not None]
        if vals:
            out[key] = statistics.median(vals)
            out[key + "_range"] = [min(vals), max(vals)]
    out["runs"] = len(good)
    return out


def median_run(tool: str, mesh: str, args) -> dict:
    """Median of `--repeat` runs when one takes under `--repeat-below` seconds."""
    runs = [run_tool(tool, mesh, args)]
    if "failed" not in runs[0] and runs[0]["wall_s"] < args.repeat_below:
        runs += [run_tool(tool, mesh, args) for _ in range(args.repeat - 1)]
    return aggregate(runs)


def rounds_run(tools: list, mesh: str, args) -> tuple[dict, dict]:
    """`--rounds` rounds, each running every tool once (the order rotated from round to round),
    so that a slow spell of a shared machine falls on all the tools alike. Returns the medians
    per tool and, per peer, the ratio of its compared time to vibrofem's in the same round
    (median and range over the rounds)."""
    runs = {t: [] for t in tools}
    for k in range(args.rounds):
        order = tools[k % len(tools):] + tools[:k % len(tools)]
        for tool in order:
            r = run_tool(tool, mesh, args)
            runs[tool].append(r)
            print(f"#   round {k + 1}/{args.rounds} {tool}: " + (r.get("failed") or
                  f"{r['wall_s']:.2f} s wall, compared {r.get('compared_s') or 0:.2f} s"),
                  file=sys.stderr, flush=True)
    ratios = {}
    if "vibrofem" in tools:
        for peer in tools:
            if peer == "vibrofem":
                continue
            q = [p["compared_s"] / v["compared_s"] for v, p in zip(runs["vibrofem"], runs[peer])
                 if "failed" not in v and "failed" not in p and v.get("compared_s") and p.get("compared_s")]
            if q:
                ratios[peer] = {"median": statistics.median(q), "range": [min(q), max(q)], "rounds": len(q)}
    return {t: aggregate(rs) for t, rs in runs.items()}, ratios


def ratio_lines(rows: list) -> str:
    """The round-by-round ratios of `--rounds`, one line per size."""
    lines = []
    for row in rows:
        rat = row.get("ratios")
        if rat:
            parts = [f"{peer} {q['median']:.2f}× ({q['range'][0]:.2f}–{q['range'][1]:.2f}, {q['rounds']} rounds)"
                     for peer, q in rat.items()]
            lines.append(f"- {format(row['dofs'], ',').replace(',', ' ')} DOFs: " + ", ".join(parts))
    if not lines:
        return ""
    return ("Compared time of each peer over vibrofem's, run by run in the same round (median, range):\n\n"
            + "\n".join(lines))


def dgemm_gflops() -> float | None:
    """This machine's DGEMM rate (numpy's BLAS, 2000 x 2000, best of 3), GFLOP/s."""
    try:
        import time

        import numpy as np
        a = np.random.default_rng(1).random((2000, 2000))
        best = float("inf")
        for _ in range(3):
            t = time.perf_counter()
            a @ a
            best = min(best, time.perf_counter() - t)
        return 2 * 2000 ** 3 / best / 1e9
    except Exception:  # noqa: BLE001 - the rate is informative only
        return None


def table(rows: list, dgemm) -> str:
    def f(x, fmt="{:.2f}"):
        return "–" if x is None else fmt.format(x)

    lines = ["| DOFs | tool | runs | wall [s] | compared [s] | peak RSS [MiB] | factor GFLOP/s "
             "| max rel. diff (elastic) | note |", "|---:|---|---:|---:|---:|---:|---:|---:|---|"]
    for row in rows:
        ref = (row["tools"].get("vibrofem") or {}).get("frequencies_hz")
        for tool in TOOLS:
            r = row["tools"].get(tool)
            if r is None:
                continue
            if "failed" in r or "skipped" in r:
                lines.append(f"| {row['dofs']:,} | {tool} | 0 | – | – | – | – | – | "
                             f"{(r.get('failed') or r.get('skipped'))[:80]} |".replace(",", " "))
                continue
            diff = None
            fr = r.get("frequencies_hz")
            if ref and fr and tool != "vibrofem" and len(fr) >= N_MODES:
                diff = max(abs(a - b) / b for a, b in zip(sorted(fr)[6:N_MODES], sorted(ref)[6:N_MODES]))
            note = {True: "verified", False: "verification failed"}.get(r.get("verified"), "")
            lines.append(
                f"| {format(row['dofs'], ',').replace(',', ' ')} | {tool} | {r.get('runs', 1)} | {f(r['wall_s'])} | {f(r.get('compared_s'))} "
                f"| {f(r['peak_bytes'] / 2 ** 20 if r.get('peak_bytes') else None, '{:.0f}')} "
                f"| {f(r.get('factor_gflops'), '{:.1f}')} | {f(diff, '{:.1e}')} | {note} |")
    lines.append("")
    lines.append(f"DGEMM on this machine (numpy, 2000², best of 3): {f(dgemm, '{:.1f}')} GFLOP/s. "
                 "'compared': vibrofem's whole run, SLEPc's eigen solve alone (load + EPSSolve with "
                 "MUMPS), the whole process for CalculiX and scikit-fem. The peers' BLAS: "
                 f"{os.path.realpath('/usr/lib/x86_64-linux-gnu/libblas.so.3')}.")
    return "\n".join(lines)


def floor_table(rows: list) -> str:
    """vibrofem's phases against their floors (the `floor` of `modes --json`, from the median
    run): factorisation flops at the DGEMM rate it measured, the block solves' bytes of factor
    read at the read bandwidth it measured over the factor, operator applications per mode."""
    lines = ["| DOFs | factorise: floor / measured [s] (× floor) | block solves: passes, GB, floor / measured [s] "
             "(× floor) | applications per mode | DGEMM GFLOP/s, read GB/s | rest of the run [s] |",
             "|---:|---|---|---:|---|---|"]
    for row in rows:
        fl = (row["tools"].get("vibrofem") or {}).get("floor")
        if not fl:
            continue
        f, s, a, o = fl["factorisation"], fl["block_solves"], fl["applications"], fl["other_s"]
        lines.append(
            f"| {format(row['dofs'], ',').replace(',', ' ')} "
            f"| {f['floor_s']:.2f} / {f['measured_s']:.2f} ({f['ratio']:.2f}) "
            f"| {fl['solve_passes']}, {s['work'] / 1e9:.1f}, {s['floor_s']:.2f} / {s['measured_s']:.2f} ({s['ratio']:.2f}) "
            f"| {a['per_mode']:.2f} ({a['applications']} for {a['modes']}) "
            f"| {fl['dgemm_gflops']:.1f}, {fl['read_gbs']:.1f} "
            f"| assemble+order {o['assemble_and_order']:.2f}, coarse+pack {o['coarse_estimate_and_packing']:.2f}, "
            f"iteration besides solves {o['iteration_besides_solves']:.2f}, verify+post {o['verify_and_post']:.2f} |")
    if len(lines) == 2:
        return ""
    return "vibrofem against its floor (docs/solver-floor.md):\n\n" + "\n".join(lines)


def plot(rows: list, path: str, tools=TOOLS, titles=("time (compared figure)", "peak memory")) -> bool:
    """Log-log plot of the compared time and the peak memory against DOFs, one line per tool,
    written as SVG by hand (no plotting package needed). False when there is nothing to plot."""
    import math
    colors = {"vibrofem": "#1f77b4", "slepc": "#ff7f0e", "calculix": "#2ca02c", "skfem": "#d62728",
              "in-core": "#1f77b4", "low-memory": "#d62728"}
    series = {}
    for tool in tools:
        pts = [(row["dofs"], row["tools"][tool]) for row in rows
               if tool in row["tools"] and "wall_s" in row["tools"][tool]]
        if pts:
            series[tool] = [(d, r.get("compared_s") or r["wall_s"], (r.get("peak_bytes") or 0) / 2 ** 20)
                            for d, r in pts]
    if not series:
        return False
    W, H, L, R, T, B = 460, 340, 64, 16, 34, 48  # one panel: size and margins (px)

    def decades(vals):
        lo = math.floor(math.log10(min(vals)))
        hi = math.ceil(math.log10(max(vals)))
        return lo, max(hi, lo + 1)

    def panel(x0, title, ylabel, k):
        xs = [p[0] for s in series.values() for p in s]
        ys = [p[k] for s in series.values() for p in s if p[k] > 0]
        (xl, xh), (yl, yh) = decades(xs), decades(ys)
        px = lambda x: x0 + L + (math.log10(x) - xl) / (xh - xl) * (W - L - R)
        py = lambda y: T + (yh - math.log10(y)) / (yh - yl) * (H - T - B)
        out = [f'<text x="{x0 + W / 2}" y="20" text-anchor="middle" font-size="14">{title}</text>',
               f'<rect x="{x0 + L}" y="{T}" width="{W - L - R}" height="{H - T - B}" fill="none" stroke="#444"/>']
        for e in range(xl, xh + 1):
            x = px(10 ** e)
            out.append(f'<line x1="{x:.1f}" y1="{T}" x2="{x:.1f}" y2="{H - B}" stroke="#ddd"/>')
            out.append(f'<text x="{x:.1f}" y="{H - B + 16}" text-anchor="middle" font-size="11">1e{e}</text>')
        for e in range(yl, yh + 1):
            y = py(10 ** e)
            out.append(f'<line x1="{x0 + L}" y1="{y:.1f}" x2="{x0 + W - R}" y2="{y:.1f}" stroke="#ddd"/>')
            out.append(f'<text x="{x0 + L - 6}" y="{y + 4:.1f}" text-anchor="end" font-size="11">1e{e}</text>')
        out.append(f'<text x="{x0 + L + (W - L - R) / 2}" y="{H - 10}" text-anchor="middle" font-size="12">DOFs</text>')
        out.append(f'<text x="{x0 + 14}" y="{T + (H - T - B) / 2}" font-size="12" text-anchor="middle" '
                   f'transform="rotate(-90 {x0 + 14} {T + (H - T - B) / 2})">{ylabel}</text>')
        for i, (tool, pts) in enumerate(series.items()):
            c = colors.get(tool, "#000")
            xy = [(px(p[0]), py(p[k])) for p in pts if p[k] > 0]
            if len(xy) > 1:
                out.append(f'<polyline fill="none" stroke="{c}" stroke-width="2" points="'
                           + " ".join(f"{x:.1f},{y:.1f}" for x, y in xy) + '"/>')
            out += [f'<circle cx="{x:.1f}" cy="{y:.1f}" r="3.5" fill="{c}"/>' for x, y in xy]
            out.append(f'<text x="{x0 + L + 8}" y="{T + 16 + 15 * i}" font-size="12" fill="{c}">{tool}</text>')
        return out

    body = panel(0, titles[0], "time [s]", 1) + panel(W, titles[1], "peak RSS [MiB]", 2)
    with open(path, "w") as fh:
        fh.write(f'<svg xmlns="http://www.w3.org/2000/svg" width="{2 * W}" height="{H}" '
                 f'font-family="sans-serif">\n<rect width="100%" height="100%" fill="white"/>\n'
                 + "\n".join(body) + "\n</svg>\n")
    return True


DOCS_PAGE = os.path.join("docs", "performance.md")
LOWMEM_LOG = os.path.join(HERE, "lowmem_results.json")
PATHS = ("in-core", "low-memory")


def lowmem_live(mesh: str, path: str, args) -> dict:
    """One run of `vibrofem modes MESH --modes 18 --solver direct|iterative --json` with the process
    tree's resident memory summed (validation/lowmem_run.py's poller: vibrofem and its MPI rank)."""
    import lowmem_run as LR
    cmd = [args.vibrofem, "modes", mesh, "--modes", str(N_MODES), "--json", "--solver",
           "direct" if path == "in-core" else "iterative",
           "--material", ",".join(repr(float(x)) for x in STEEL)]
    load = os.getloadavg()[0]
    r = LR.run_polled(cmd, kill_above=args.lowmem_kill_above * 2 ** 30)
    out = {"wall_s": r["wall_s"], "peak_bytes": r["tree_peak_bytes"], "ranks": 1, "loadavg": load,
           "source": "live run"}
    if r["returncode"]:
        out["failed"] = r["stderr"][-500:]
    return out


def lowmem_table(rows: list) -> str:
    """In-core against low-memory: wall time, time per elastic mode, peak memory, memory per DOF."""
    lines = ["| DOFs | path | wall [s] | s per mode | peak [MiB] | bytes per DOF | load | source |",
             "|---:|---|---:|---:|---:|---:|---:|---|"]
    for row in rows:
        for path in PATHS:
            r = row["tools"].get(path)
            if not r or "wall_s" not in r:
                why = (r or {}).get("failed") or (r or {}).get("skipped") or "not run"
                lines.append(f"| {row['dofs']:,} | {path} | – | – | – | – | – | {why} |")
                continue
            peak = r.get("peak_bytes") or 0
            load = "–" if r.get("loadavg") is None else f"{r['loadavg']:.1f}"
            lines.append(f"| {row['dofs']:,} | {path} | {r['wall_s']:.0f} | {r['wall_s'] / (N_MODES - 6):.1f} | "
                         f"{peak / 2 ** 20:,.0f} | {peak / row['dofs']:,.0f} | {load} | {r.get('source', '')} |")
    return "\n".join(lines)


def lowmem_main(args) -> int:
    """--lowmem: the in-core and the low-memory paths side by side (12 elastic modes, free-free),
    live for the sizes up to --lowmem-live-up-to DOFs, from validation/lowmem_results.json (runs
    logged by hand with /usr/bin/time -v and a process-tree sampler, docs/lowmem.md) above."""
    with open(LOWMEM_LOG) as fh:
        logged = json.load(fh)["runs"]
    rows = []
    for label in [x.strip() for x in args.sizes.split(",") if x.strip()]:
        if label not in SIZES and label != "3M":
            raise SystemExit(f"unknown size {label!r}; known: {', '.join(SIZES)}, 3M")
        row = {"size": label, "tools": {}}
        for path in PATHS:
            log = [r for r in logged if r["size"] == label and r["path"] == path]
            if log:
                row["dofs"] = log[-1]["dofs"]
                row["tools"][path] = log[-1]
        if label in SIZES and row.get("dofs", 0) <= args.lowmem_live_up_to:
            mesh = BP.make_mesh(label, SIZES[label])
            row["dofs"] = dofs_of(mesh)
            if row["dofs"] <= args.lowmem_live_up_to:
                for path in PATHS:
                    row["tools"][path] = lowmem_live(os.path.abspath(mesh), path, args)
        if "dofs" in row:
            rows.append(row)
    text = lowmem_table(rows)
    os.makedirs(OUT, exist_ok=True)
    with open(os.path.join(OUT, "bench_lowmem.json"), "w") as fh:
        json.dump({"rows": rows, "loadavg_at_end": os.getloadavg()}, fh, indent=1)
    svg = os.path.join(OUT, "bench_lowmem.svg")
    if plot(rows, svg, PATHS, ("wall time, 18 modes", "peak memory (process tree)")):
        text += "\n\n![in-core and low-memory: time and memory against DOFs](bench_lowmem.svg)"
    print(text)
    return 0


def update_readme(text: str) -> None:
    """Writes the table between the bench_peers markers of docs/performance.md."""
    path = os.path.join(ROOT, DOCS_PAGE)
    with open(path) as fh:
        readme = fh.read()
    begin, end = "<!-- bench_peers:begin -->", "<!-- bench_peers:end -->"
    if begin not in readme or end not in readme:
        raise SystemExit(f"{DOCS_PAGE} has no bench_peers markers")
    head, rest = readme.split(begin, 1)
    _, tail = rest.split(end, 1)
    with open(path, "w") as fh:
        fh.write(head + begin + "\n" + text + "\n" + end + tail)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="20k,65k,120k,300k,1M", help=f"comma list of {list(SIZES)}")
    ap.add_argument("--tools", default=",".join(TOOLS), help=f"comma list of {list(TOOLS)}")
    ap.add_argument("--quick", action="store_true", help="20k only, one run each")
    ap.add_argument("--repeat", type=int, default=3, help="runs for the median")
    ap.add_argument("--repeat-below", type=float, default=60.0, help="repeat runs shorter than this (s)")
    ap.add_argument("--rounds", type=int, default=0,
                    help="interleave: N rounds of every tool once, medians of all and per-round ratios "
                         "(replaces --repeat)")
    ap.add_argument("--peers-up-to", type=int, default=400_000,
                    help="run the other tools only up to this many DOFs (vibrofem alone above)")
    ap.add_argument("--skfem-up-to", type=int, default=150_000, help="scikit-fem only up to this many DOFs")
    ap.add_argument("--vibrofem", default=os.path.join(ROOT, "target", "release", "vibrofem"))
    ap.add_argument("--timeout", type=float, default=3600.0, help="seconds per run")
    ap.add_argument("--readme", "--docs", dest="readme", action="store_true",
                    help="write the table and the plot into docs/performance.md")
    ap.add_argument("--lowmem", action="store_true",
                    help="in-core against low-memory path (--solver direct|iterative): live up to "
                         "--lowmem-live-up-to DOFs, logged runs (validation/lowmem_results.json) above")
    ap.add_argument("--lowmem-live-up-to", type=int, default=200_000, help="DOFs run live with --lowmem")
    ap.add_argument("--lowmem-kill-above", type=float, default=20.0, help="GiB: kill a live --lowmem run above")
    args = ap.parse_args(argv)
    if args.lowmem:
        return lowmem_main(args)
    if args.quick:
        args.sizes, args.repeat = "20k", 1
    tools = [t.strip() for t in args.tools.split(",") if t.strip()]
    for t in tools:
        if t not in TOOLS:
            ap.error(f"unknown tool {t!r}")
    if ("calculix" in tools and not (shutil.which("ccx") or shutil.which("ccx2.20"))) or "slepc" in tools:
        subprocess.run(["bash", os.path.join(HERE, "setup_peers.sh")] +
                       (["--calculix"] if "calculix" in tools else []) +
                       (["--slepc"] if "slepc" in tools else []), check=False)
    os.makedirs(OUT, exist_ok=True)
    rows = []
    for label in args.sizes.split(","):
        label = label.strip()
        if label not in SIZES:
            ap.error(f"unknown size {label!r}; known: {', '.join(SIZES)}")
        mesh = BP.make_mesh(label, SIZES[label])
        row = {"size": label, "h_mm": SIZES[label] * 1000, "mesh": os.path.relpath(mesh, ROOT),
               "dofs": dofs_of(mesh), "tools": {}}
        print(f"# {label}: {row['mesh']} ({row['dofs']} DOFs)", file=sys.stderr, flush=True)
        live = []
        for tool in tools:
            if tool != "vibrofem" and row["dofs"] > args.peers_up_to:
                row["tools"][tool] = {"skipped": f"DOFs > {args.peers_up_to}"}
            elif tool == "skfem" and row["dofs"] > args.skfem_up_to:
                row["tools"][tool] = {"skipped": f"DOFs > {args.skfem_up_to}"}
            else:
                live.append(tool)
        if args.rounds > 0:
            medians, row["ratios"] = rounds_run(live, os.path.abspath(mesh), args)
            row["tools"].update(medians)
        for tool in live:
            if args.rounds <= 0:
                row["tools"][tool] = median_run(tool, os.path.abspath(mesh), args)
            r = row["tools"][tool]
            print(f"#   {tool}: " + (r.get("failed") or f"{r['wall_s']:.2f} s wall, "
                  f"{(r.get('peak_bytes') or 0) / 2 ** 20:.0f} MiB"), file=sys.stderr, flush=True)
        rows.append(row)
    dgemm = dgemm_gflops()
    report = {"case": "S2 plate 0.9 x 0.4 x 0.116 m, tet10, free-free, steel, 18 modes",
              "machine": {"cpus": os.cpu_count(), "platform": platform.platform(),
                          "loadavg_at_end": os.getloadavg(), "dgemm_gflops": dgemm,
                          "peer_blas": os.path.realpath("/usr/lib/x86_64-linux-gnu/libblas.so.3")},
              "rows": rows}
    with open(os.path.join(OUT, "bench_peers.json"), "w") as fh:
        json.dump(report, fh, indent=1)
    text = table(rows, dgemm)
    ratios = ratio_lines(rows)
    if ratios:
        text += "\n\n" + ratios
    floors = floor_table(rows)
    if floors:
        text += "\n\n" + floors
    svg = os.path.join(OUT, "bench_peers.svg")
    if plot(rows, svg):
        # The link is relative to docs/performance.md, where --readme writes the table.
        text += "\n\n![time and peak memory against DOFs](bench_peers.svg)"
    print(text)
    if args.readme:
        if os.path.exists(svg):
            shutil.copy(svg, os.path.join(ROOT, "docs", "bench_peers.svg"))
        update_readme(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
