#!/usr/bin/env bash
# Live validation of vibrofem against scikit-fem (what CI runs after `cargo test`):
#   1. resolve the Python interpreter (validation/python.sh; runs validation/setup.sh if needed);
#   2. run the convention self-tests (skfem_modes.py --selftest, ~10 s), then recompute every
#      scikit-fem reference from the committed meshes into a temporary folder
#      and check it equals the committed validation/reference/*.json (elastic frequencies to
#      1e-9 relative, same dofs, mass), and the harmonic references (skfem_harmonic.py, complex
#      displacements to 1e-9 of the largest) -- the committed references are never overwritten;
#   3. build the package's wheel once (pip wheel ./python), install it into validation/.venv and
#      into a fresh venv (the wheel its only install there; the third-party packages come from
#      validation/.venv through a .pth line, as a full install of them takes minutes); with that
#      fresh venv: validation/compare.py (every case to 1e-6 relative), the package's tests
#      (python/tests, pytest), mypy --strict on the examples and tests, and every example
#      (python/examples/run_all.py: each writes its picture).
#
#   bash validation/run_live.sh
#   SKIP_REGEN=1 bash validation/run_live.sh         # step 3 only (skips step 2)
#   VIBROFEM_REQUIRE_SLEPC=1 bash validation/run_live.sh   # (CI) the package's SLEPc test may not skip
#   VIBROFEM_REQUIRE_BROWSER=1 …                           # (CI) nor may the report's browser test
# Extra arguments are passed to compare.py (e.g. --cases s1_plate --verbose).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

PY="$(bash validation/python.sh)"   # the one interpreter resolver (sets up the tools if missing)
# The package's tests and examples need more than python.sh checks for (an older venv may lack them).
if ! "$PY" -c "import meshio, pyvista, matplotlib, mypy, websocket, maturin" >/dev/null 2>&1; then
    bash validation/setup.sh >&2
fi
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
step() { echo "== [${SECONDS} s] $*"; }   # each step with the time since the start

if [ "${SKIP_REGEN:-0}" != 1 ]; then
    TMP="$WORK/references"
    mkdir -p "$TMP"
    step "scikit-fem convention self-tests"
    "$PY" validation/skfem_modes.py --selftest
    step "regenerating scikit-fem references into $TMP"
    "$PY" validation/skfem_modes.py --out "$TMP" --check validation/reference
    step "regenerating the scikit-fem harmonic references (direct complex solves)"
    "$PY" validation/skfem_harmonic.py --out "$TMP" --check validation/reference
fi

step "building the wheel (pip wheel ./python; abi3, CPython >= 3.9)"
"$PY" -m pip wheel --disable-pip-version-check -q --no-deps -w "$WORK/wheels" ./python
WHEEL="$(ls "$WORK"/wheels/vibrofem-*.whl)"
echo "   $(basename "$WHEEL")"
"$PY" -m pip install --disable-pip-version-check -q --force-reinstall --no-deps "$WHEEL"
step "installing the wheel into a fresh venv"
"$PY" -m venv "$WORK/venv"
FRESH="$WORK/venv/bin/python"
"$FRESH" -c "import site, sys; print(sys.argv[1], file=open(site.getsitepackages()[0] + '/_validation_deps.pth', 'w'))" \
    "$("$PY" -c 'import site; print(site.getsitepackages()[0])')"
"$FRESH" -m pip install --disable-pip-version-check -q --force-reinstall --no-deps "$WHEEL"
"$FRESH" -m pip check
"$FRESH" -c "import sys, vibrofem; assert vibrofem.__file__.startswith(sys.prefix), vibrofem.__file__; \
print('   vibrofem', vibrofem.__version__, 'from', vibrofem.__file__)"
step "comparing the vibrofem package with the references"
"$FRESH" validation/compare.py "$@"
step "Python package tests (pytest python/tests; the browser test needs chromium: validation/setup_browser.sh)"
bash validation/setup_browser.sh >/dev/null || echo "   no chromium: the report's browser test will skip (fails with VIBROFEM_REQUIRE_BROWSER=1)"
"$FRESH" -m pytest -q python/tests
step "mypy --strict on the examples and tests (the package's stubs)"
"$FRESH" -m mypy --config-file python/mypy.ini --cache-dir "$WORK/mypy_cache" python/examples python/tests
step "examples (python/examples/run_all.py: each writes its picture)"
"$FRESH" python/examples/run_all.py "$WORK/pictures"
step "done"
