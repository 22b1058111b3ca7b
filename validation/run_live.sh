#!/usr/bin/env bash
# Live validation of vibrofem against scikit-fem (what CI runs after `cargo test`):
#   1. resolve the Python interpreter (validation/python.sh; runs validation/setup.sh if needed);
#   2. run the convention self-tests (skfem_modes.py --selftest, ~10 s), then recompute every
#      scikit-fem reference from the committed meshes into a temporary folder
#      and check it equals the committed validation/reference/*.json (elastic frequencies to
#      1e-9 relative, same dofs, mass), and the harmonic references (skfem_harmonic.py, complex
#      displacements to 1e-9 of the largest) -- the committed references are never overwritten;
#   3. install the Python package (pip install ./python) and run validation/compare.py with it
#      (every case to 1e-6 relative), then the package's tests (python/tests, pytest).
#
#   bash validation/run_live.sh
#   SKIP_REGEN=1 bash validation/run_live.sh         # step 3 only (skips step 2)
#   VIBROFEM_REQUIRE_SLEPC=1 bash validation/run_live.sh   # (CI) the package's SLEPc test may not skip
# Extra arguments are passed to compare.py (e.g. --cases s1_plate --verbose).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

PY="$(bash validation/python.sh)"   # the one interpreter resolver (sets up the tools if missing)

if [ "${SKIP_REGEN:-0}" != 1 ]; then
    TMP="$(mktemp -d)"
    trap 'rm -rf "$TMP"' EXIT
    echo "== scikit-fem convention self-tests"
    "$PY" validation/skfem_modes.py --selftest
    echo "== regenerating scikit-fem references into $TMP"
    "$PY" validation/skfem_modes.py --out "$TMP" --check validation/reference
    echo "== regenerating the scikit-fem harmonic references (direct complex solves)"
    "$PY" validation/skfem_harmonic.py --out "$TMP" --check validation/reference
fi

echo "== installing the Python package (pip install ./python)"
"$PY" -m pip install --disable-pip-version-check -q ./python
echo "== comparing the vibrofem package with the references"
"$PY" validation/compare.py "$@"
echo "== Python package tests (pytest python/tests)"
"$PY" -m pytest -q python/tests
