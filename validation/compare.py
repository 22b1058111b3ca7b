#!/usr/bin/env python3
"""Compare vibrofem against the committed scikit-fem references.

For every ``validation/reference/*.json`` this solves, with the vibrofem Python package
(``pip install ./python``)::

    mesh = vf.read_mesh(MESH, length_unit=UNIT)
    modes = vf.Model(mesh, material=(E, NU, RHO), fix=[GROUP, ...]).modes(N)

with N = the number of reference frequencies (rigid modes included), or with ``--cli BINARY`` runs
``BINARY modes MESH --modes N --json --material E,NU,RHO [--fix GROUP ...] [--length-unit mm]``
and parses the JSON it prints, and checks the report against the reference:

* the command exits 0 and reports ``"complete": true``;
* ``n_rigid`` equals the reference; each rigid-mode frequency is below
  max(``--rigid-tol-hz`` (default 1e-3 Hz), ``--rigid-rel`` (default 1e-4) x the first elastic
  frequency) in absolute value. Rigid modes are round-off: sqrt(eps * lambda_max) gives a few mHz
  on our meshes (scikit-fem itself reports up to 3e-3 Hz), more on fine meshes, hence the relative
  part (lambda_rigid < 1e-8 lambda_first);
* every elastic frequency agrees to ``--rel-tol`` (default 1e-6) relative. The CLI may return more
  modes than asked (if it counts elastic modes only); the first N are compared;
* ``mass_kg`` agrees to 1e-8 relative; ``dofs`` equals the reference's free (``dofs``) or total
  (``dofs_total``) DOF count.

Usage::

    validation/.venv/bin/python validation/compare.py
    validation/.venv/bin/python validation/compare.py --cases s1_plate_tet10 --verbose
    python3 validation/compare.py --cli target/release/vibrofem --json-out validation/out/compare.json

Prints one line per case, then ``N passed, N failed``; exits 1 if any case fails, 2 on bad usage.
Report contract used (the package's ``Modes.report`` is the CLI's JSON; extra keys are ignored)::

    {"frequencies_hz": [...], "n_rigid": 6, "dofs": N, "mass_kg": m, "complete": true,
     "timings_s": {"read", "assemble", "factor", "solve", "verify", "total"},
     "peak_memory_bytes": N, "factor_flops": N}
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def cli_command(binary: str, ref: dict, n_modes: int) -> list:
    mat = ref["material"]
    cmd = [binary, "modes", ref["mesh"], "--modes", str(n_modes), "--json",
           "--material", f"{float(mat['young'])!r},{float(mat['poisson'])!r},"
                         f"{float(mat['density'])!r}"]
    for group in ref.get("fixed_groups", []):
        cmd += ["--fix", group]
    if ref.get("length_unit", "m") != "m":
        cmd += ["--length-unit", ref["length_unit"]]
    return cmd


def package_run(ref: dict, n_modes: int) -> dict:
    import vibrofem as vf
    mat = ref["material"]
    mesh = vf.read_mesh(os.path.join(ROOT, ref["mesh"]), length_unit=ref.get("length_unit", "m"))
    model = vf.Model(mesh, material=(mat["young"], mat["poisson"], mat["density"]),
                     fix=ref.get("fixed_groups", []))
    return model.modes(n_modes).report


def parse_json_output(text: str) -> dict:
    """The CLI's stdout JSON (tolerates stray lines around one JSON object)."""
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        start, end = text.find("{"), text.rfind("}")
        if start < 0 or end <= start:
            raise
        return json.loads(text[start:end + 1])


def check(ref: dict, out: dict, rel_tol: float, rigid_tol_hz: float,
          rigid_rel: float) -> tuple[list, float]:
    """Return (list of problems, max relative error of the elastic modes)."""
    errs = []
    if out.get("complete") is not True:
        errs.append(f"complete = {out.get('complete')!r}")
    f_ref, f_cli = ref["frequencies_hz"], out.get("frequencies_hz", [])
    if not isinstance(f_cli, list):
        return [f"frequencies_hz is {type(f_cli).__name__}"], float("nan")
    nr = ref["n_rigid"]
    if out.get("n_rigid") != nr:
        errs.append(f"n_rigid {out.get('n_rigid')} != {nr}")
    if len(f_cli) < len(f_ref):
        errs.append(f"{len(f_cli)} frequencies returned, {len(f_ref)} expected")
    worst = 0.0
    if nr < len(f_ref):
        rigid_tol_hz = max(rigid_tol_hz, rigid_rel * f_ref[nr])
    for i, (a, b) in enumerate(zip(sorted(f_cli), f_ref)):
        if i < nr:
            if abs(a) > rigid_tol_hz:
                errs.append(f"rigid mode {i + 1}: {a:.3e} Hz > {rigid_tol_hz:g} Hz")
            continue
        rel = abs(a - b) / abs(b)
        worst = max(worst, rel)
        if rel > rel_tol:
            errs.append(f"mode {i + 1}: {a:.9f} Hz vs reference {b:.9f} Hz (rel {rel:.2e})")
    mass = out.get("mass_kg")
    if not isinstance(mass, (int, float)) or abs(mass - ref["mass_kg"]) > 1e-8 * ref["mass_kg"]:
        errs.append(f"mass_kg {mass!r} != {ref['mass_kg']!r}")
    if out.get("dofs") not in (ref["dofs"], ref.get("dofs_total", ref["dofs"])):
        errs.append(f"dofs {out.get('dofs')!r} not in ({ref['dofs']}, {ref.get('dofs_total')})")
    return errs, worst


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cli", metavar="BINARY",
                    help="run this vibrofem executable instead of the Python package")
    ap.add_argument("--ref-dir", default=os.path.join(HERE, "reference"))
    ap.add_argument("--cases", action="append", default=[],
                    help="substring of case names to run (repeatable); default all")
    ap.add_argument("--rel-tol", type=float, default=1e-6)
    ap.add_argument("--rigid-tol-hz", type=float, default=1e-3)
    ap.add_argument("--rigid-rel", type=float, default=1e-4,
                    help="rigid modes may reach this fraction of the first elastic frequency")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds per case")
    ap.add_argument("--json-out", help="write per-case results (incl. CLI timings) here")
    ap.add_argument("--verbose", "-v", action="store_true", help="print commands and stderr")
    args = ap.parse_args(argv)

    binary = os.path.abspath(args.cli) if args.cli else None
    if binary and not os.access(binary, os.X_OK):
        print(f"compare.py: {args.cli} is not an executable", file=sys.stderr)
        return 2
    if not binary:
        try:
            import vibrofem  # noqa: F401
        except ImportError:
            print("compare.py: the vibrofem package is not installed (pip install ./python), "
                  "or give --cli target/release/vibrofem", file=sys.stderr)
            return 2
    refs = []
    for path in sorted(glob.glob(os.path.join(args.ref_dir, "*.json"))):
        with open(path) as fh:
            ref = json.load(fh)
        if os.path.basename(path).startswith(("static_", "harmonic_")) or "mesh" not in ref \
                or "frequencies_hz" not in ref:
            continue  # not a modal reference (e.g. the two-mass dynamics references)
        if not args.cases or any(s in ref["case"] for s in args.cases):
            refs.append(ref)
    if not refs:
        print(f"compare.py: no reference cases in {args.ref_dir}", file=sys.stderr)
        return 2

    passed, failed, results = 0, 0, []
    print(f"{'case':32s} {'dofs':>7s} {'f_first_elastic':>16s} {'max rel err':>11s} "
          f"{'run s':>7s} {'wall s':>7s}  status")
    for ref in refs:
        n_modes = len(ref["frequencies_hz"])
        cmd = cli_command(binary, ref, n_modes) if binary else ["package", ref["mesh"], str(n_modes)]
        if args.verbose:
            print("  $ " + " ".join(cmd))
        t0 = time.perf_counter()
        errs, worst, out = [], float("nan"), {}
        try:
            if binary:
                proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True,
                                      timeout=args.timeout)
                if proc.returncode != 0:
                    errs.append(f"exit code {proc.returncode}: {proc.stderr.strip()[-500:]}")
                else:
                    out = parse_json_output(proc.stdout)
                if args.verbose and proc.stderr.strip():
                    print("  stderr: " + proc.stderr.strip()[-2000:].replace("\n", "\n          "))
            else:
                out = package_run(ref, n_modes)
            if out:
                errs, worst = check(ref, out, args.rel_tol, args.rigid_tol_hz,
                                    args.rigid_rel)
        except subprocess.TimeoutExpired:
            errs.append(f"timed out after {args.timeout:g} s")
        except (json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
            errs.append(f"bad JSON output: {exc}")
        except Exception as exc:  # the package's VibrofemError and its subclasses
            errs.append(f"{type(exc).__name__}: {exc}")
        wall = time.perf_counter() - t0
        cli_total = (out.get("timings_s") or {}).get("total", float("nan")) \
            if isinstance(out, dict) else float("nan")
        nr = ref["n_rigid"]
        f1 = ref["frequencies_hz"][nr]
        status = "ok" if not errs else "FAIL"
        passed += not errs
        failed += bool(errs)
        print(f"{ref['case']:32s} {ref['dofs']:7d} {f1:16.6f} {worst:11.2e} "
              f"{cli_total:7.2f} {wall:7.2f}  {status}", flush=True)
        for e in errs[:10]:
            print(f"    {e}")
        if len(errs) > 10:
            print(f"    ... {len(errs) - 10} more")
        results.append({"case": ref["case"], "ok": not errs, "errors": errs,
                        "max_rel_err": worst, "wall_s": wall, "command": cmd,
                        "timings_s": out.get("timings_s") if isinstance(out, dict) else None,
                        "peak_memory_bytes": out.get("peak_memory_bytes")
                        if isinstance(out, dict) else None})
    if args.json_out:
        os.makedirs(os.path.dirname(os.path.abspath(args.json_out)), exist_ok=True)
        with open(args.json_out, "w") as fh:
            json.dump(results, fh, indent=1)
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
