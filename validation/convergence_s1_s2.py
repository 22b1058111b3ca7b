#!/usr/bin/env python3
"""Convergence of the first elastic frequency (mode 7) of the free-free plates S1 and S2.

S1: 300 x 300 x 20 mm steel plate, published 725.37 Hz (SolidWorks, probably nu = 0.28).
S2: 900 x 400 x 116 mm steel plate, published 722.01 Hz.

For tet4 and tet10 the meshes are unstructured gmsh meshes (meshes/make_meshes.py's tet_box,
written to validation/out/, not committed); for hex8 and hex20 the structured box meshes come
from vibrofem's own generator (``box:`` meshes), so no file is needed. Each row solves the
lowest 7 modes with the vibrofem Python package (``pip install ./python``) and records f7, DOFs,
wall time and the peak memory of the process.

    validation/.venv/bin/python validation/convergence_s1_s2.py [--quick] [--nu 0.3]

Prints markdown tables (one per plate) with the error against the published value and against
the finest quadratic result (an estimate of the discretisation error).
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import vibrofem as vf

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = os.path.join(HERE, "out")
sys.path.insert(0, os.path.join(ROOT, "meshes"))

PLATES = {
    "S1": {"dims": (0.3, 0.3, 0.02), "published": 725.37,
           "tet_h": [0.03, 0.02, 0.015, 0.01, 0.0075],
           "hex": [(10, 10, 2), (20, 20, 4), (30, 30, 6), (45, 45, 9)]},
    "S2": {"dims": (0.9, 0.4, 0.116), "published": 722.01,
           "tet_h": [0.06, 0.04, 0.03, 0.02],
           "hex": [(18, 8, 2), (27, 12, 3), (36, 16, 4), (54, 24, 6)]},
}


def run(mesh: str, nu: float) -> dict:
    modes = vf.Model(vf.read_mesh(mesh), material=(2.1e11, nu, 7850)).modes(7)
    if not (modes.complete and modes.accurate):
        raise RuntimeError(f"{mesh}: the modal solution failed its verification: {modes.notes}")
    return modes.report


def tet_meshes(name: str, dims, hs) -> list[tuple[str, str, float]]:
    import make_meshes  # gmsh Python API; only needed for the tet rows
    os.makedirs(OUT, exist_ok=True)
    rows = []
    for h in hs:
        base = f"conv_{name.lower()}"
        hmm = "h" + f"{h * 1000:.6g}".replace(".", "p")
        paths = {k: os.path.join(OUT, f"{base}_{k}_{hmm}.msh") for k in ("tet4", "tet10")}
        if not all(os.path.exists(p) for p in paths.values()):
            make_meshes.tet_box(base, dims, h, OUT)
        rows += [("tet4", paths["tet4"], h), ("tet10", paths["tet10"], h)]
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--nu", type=float, default=0.3)
    ap.add_argument("--quick", action="store_true", help="skip the finest level of each family")
    ap.add_argument("--plates", default="S1,S2")
    ap.add_argument("--json-out", default=os.path.join(OUT, "convergence_s1_s2.json"))
    args = ap.parse_args(argv)
    all_rows = {}
    for name in args.plates.split(","):
        pl = PLATES[name]
        hs = pl["tet_h"][:-1] if args.quick else pl["tet_h"]
        divs = pl["hex"][:-1] if args.quick else pl["hex"]
        cases = [(k, path, f"h = {h * 1000:g} mm") for k, path, h in tet_meshes(name, pl["dims"], hs)]
        lx, ly, lz = pl["dims"]
        for kind in ("hex8", "hex20"):
            for d in divs:
                cases.append((kind, f"box:{lx},{ly},{lz}:{d[0]},{d[1]},{d[2]}:{kind}", f"{d[0]}x{d[1]}x{d[2]}"))
        rows = []
        for kind, mesh, label in cases:
            r = run(mesh, args.nu)
            rows.append({"element": kind, "mesh": label, "dofs": r["dofs"], "f7": r["frequencies_hz"][6],
                         "time_s": r["timings_s"]["total"], "peak_mb": (r["peak_memory_bytes"] or 0) / 2**20,
                         "complete": r["complete"]})
            print(f"# {name} {kind} {label}: f7 = {rows[-1]['f7']:.4f} Hz, {r['dofs']} dofs, "
                  f"{rows[-1]['time_s']:.2f} s", file=sys.stderr)
        ref = min((x for x in rows if x["element"] in ("tet10", "hex20")), key=lambda x: -x["dofs"])["f7"]
        all_rows[name] = {"published": pl["published"], "finest_quadratic": ref, "rows": rows}
        print(f"\n### {name}: {' x '.join(f'{d * 1000:g}' for d in pl['dims'])} mm, nu = {args.nu}, "
              f"published {pl['published']} Hz\n")
        print("| element | mesh | DOFs | f7 [Hz] | vs published | vs finest quadratic | time [s] | peak [MiB] |")
        print("|---|---|---:|---:|---:|---:|---:|---:|")
        for x in rows:
            print(f"| {x['element']} | {x['mesh']} | {x['dofs']} | {x['f7']:.3f} | "
                  f"{(x['f7'] / pl['published'] - 1) * 100:+.2f} % | {(x['f7'] / ref - 1) * 100:+.3f} % | "
                  f"{x['time_s']:.2f} | {x['peak_mb']:.0f} |")
    os.makedirs(os.path.dirname(args.json_out), exist_ok=True)
    with open(args.json_out, "w") as fh:
        json.dump({"nu": args.nu, "plates": all_rows}, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
