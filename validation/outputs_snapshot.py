#!/usr/bin/env python3
"""Snapshot the JSON outputs of the main commands, and compare two snapshots.

A refactoring must not change what the commands compute. This script runs a fixed list of
commands (the design chain, modes on committed meshes, static, harmonic, scenes, the three
machines, a convergence study) with a given `vibrofem` binary and keeps each `--json` output;
`compare` walks two snapshots and reports every number that differs by more than a relative
1e-12 (timings, memory and paths aside), every key present in one and not the other, and every
differing string.

    python3 validation/outputs_snapshot.py take  target/release/vibrofem /tmp/before
    python3 validation/outputs_snapshot.py take  target/release/vibrofem /tmp/after
    python3 validation/outputs_snapshot.py compare /tmp/before /tmp/after

Exit code of `compare`: 0 when the snapshots agree, 1 otherwise.
"""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
M = os.path.join(ROOT, "meshes")
S = os.path.join(ROOT, "scenes")

# name -> arguments (the output folder, where a command needs one, is appended as `-o DIR`).
CASES = {
    "design": (["design", "--json"], True),
    "modes_hex20": (["modes", f"{M}/s1_plate_hex20_10x10x2.msh", "--modes", "12", "--json"], False),
    "modes_tet10": (["modes", f"{M}/s1_plate_tet10_h30.msh", "--modes", "10", "--json"], False),
    "modes_leaf_clamped": (
        ["modes", f"{M}/s3_leaf_hex20_10x6x1.msh", "--fix", "clamp_fixed", "--modes", "6", "--json"],
        False,
    ),
    "static_leaf": (
        [
            "static", f"{M}/s3_leaf_hex20_10x6x1.msh", "--fix", "clamp_fixed", "--couple",
            "clamp_guided:guided=z", "--force", "clamp_guided=0,0,100", "--json",
        ],
        False,
    ),
    "harmonic_box": (
        [
            "harmonic", "box:0.5,0.05,0.02:20,2,2:hex20", "--fix", "xmin", "--force", "xmax=0,0,10",
            "--sweep", "40", "100", "13", "--rayleigh", "1,1e-5", "--method", "both", "--modes", "30",
            "--json",
        ],
        False,
    ),
    "mesh_info": (["mesh-info", f"{M}/s2_plate_tet10_h40.msh", "--json"], False),
    "scene_s3_stiffness": (["run", f"{S}/s3_leaf_stiffness.toml", "--json"], True),
    "scene_s3_harmonic": (["run", f"{S}/s3_leaf_harmonic.toml", "--json"], True),
    "scene_s1_shell": (["run", f"{S}/s1_plate_shell.toml", "--json"], True),
    "crank_drive": (["crank-drive", "--json"], True),
    "autobalancer": (["autobalancer", "--json"], True),
    "balancer_data": (["balancer-data", "--json"], True),
}

# Keys whose values are measurements of the run, not results.
SKIP = ("time", "timing", "memory", "elapsed", "path", "outputs", "wrote", "threads", "rss", "gflops")


def take(binary, out):
    os.makedirs(out, exist_ok=True)
    failed = []
    for name, (args, needs_dir) in CASES.items():
        cmd = [binary, *args]
        with tempfile.TemporaryDirectory() as d:
            if needs_dir:
                cmd += ["-o", os.path.join(d, "out")]
            p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
        rec = {"exit": p.returncode}
        try:
            rec["json"] = json.loads(p.stdout)
        except ValueError:
            rec["stdout"] = p.stdout[-2000:]
            rec["stderr"] = p.stderr[-2000:]
            failed.append(name)
        with open(os.path.join(out, name + ".json"), "w") as f:
            json.dump(rec, f, indent=1, sort_keys=True)
        print(f"{name}: exit {p.returncode}", flush=True)
    if failed:
        print("no JSON from:", ", ".join(failed))


def skipped(key):
    k = key.lower()
    return any(s in k for s in SKIP)


def walk(a, b, path, diffs):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if skipped(k):
                continue
            if k not in a or k not in b:
                diffs.append(f"{path}/{k}: only in {'after' if k not in a else 'before'}")
                continue
            walk(a[k], b[k], f"{path}/{k}", diffs)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            diffs.append(f"{path}: length {len(a)} vs {len(b)}")
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, f"{path}[{i}]", diffs)
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        scale = max(abs(a), abs(b), 1e-300)
        if abs(a - b) > 1e-12 * scale:
            diffs.append(f"{path}: {a!r} vs {b!r} (rel {abs(a - b) / scale:.2e})")
    elif a != b:
        diffs.append(f"{path}: {str(a)[:80]!r} vs {str(b)[:80]!r}")


def compare(before, after):
    bad = 0
    for name in CASES:
        pa, pb = (os.path.join(d, name + ".json") for d in (before, after))
        if not (os.path.exists(pa) and os.path.exists(pb)):
            print(f"{name}: missing in one snapshot")
            bad += 1
            continue
        with open(pa) as f:
            a = json.load(f)
        with open(pb) as f:
            b = json.load(f)
        diffs = []
        walk(a, b, "", diffs)
        print(f"{name}: {'same' if not diffs else f'{len(diffs)} differences'}")
        for d in diffs[:20]:
            print("   ", d)
        bad += bool(diffs)
    return 1 if bad else 0


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "take":
        take(os.path.abspath(sys.argv[2]), sys.argv[3])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        sys.exit(compare(sys.argv[2], sys.argv[3]))
    else:
        sys.exit(__doc__)
