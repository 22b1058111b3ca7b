#!/usr/bin/env bash
# Install the Python tools of vibrofem's validation and of its Python package's tests and examples
# (gmsh, scikit-fem, numpy, scipy, pytest, meshio, PyVista/VTK, matplotlib, mypy, websocket-client,
# maturin; pinned in validation/requirements.txt).
#
#   bash validation/setup.sh          # from anywhere; idempotent
#
# Preferred: a virtual environment validation/.venv (python3 -m venv). If venv is unavailable
# (Debian without python3-venv), falls back to `pip install --user` for python3 (adding
# --break-system-packages where the system Python is "externally managed").
# The gmsh wheel links against X11/OpenGL runtime libraries; if `import gmsh` fails and we are
# root with apt-get, the Debian packages providing them are installed.
# Scripts then run with validation/.venv/bin/python if it exists, else python3
# (see validation/run_live.sh).
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
PY="${PYTHON:-python3}"
REQ="$HERE/requirements.txt"

if [ -x "$HERE/.venv/bin/python" ] || "$PY" -m venv "$HERE/.venv" >/dev/null 2>&1; then
    PYBIN="$HERE/.venv/bin/python"
    "$PYBIN" -m pip install --disable-pip-version-check -q -r "$REQ"
else
    echo "setup.sh: python3 -m venv unavailable, installing with pip --user" >&2
    rm -rf "$HERE/.venv"
    PYBIN="$PY"
    "$PY" -m pip install --disable-pip-version-check -q --user -r "$REQ" \
        || "$PY" -m pip install --disable-pip-version-check -q --user --break-system-packages -r "$REQ"
fi

if ! "$PYBIN" -c "import gmsh" >/dev/null 2>&1; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "setup.sh: installing the runtime libraries of the gmsh wheel" >&2
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
            libglu1-mesa libgl1 libxcursor1 libxft2 libxinerama1 libxrender1 libgomp1 >/dev/null
    fi
fi
# PyVista (the examples) renders off screen through EGL (Mesa's llvmpipe on a machine without a GPU).
if ! "$PYBIN" -c "import vtkmodules.vtkRenderingOpenGL2" >/dev/null 2>&1 \
    || ! ldconfig -p 2>/dev/null | grep -q "libEGL.so.1"; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "setup.sh: installing the EGL/Mesa libraries of off-screen rendering" >&2
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
            libegl1 libegl-mesa0 libgl1-mesa-dri libgl1 >/dev/null
    fi
fi
"$PYBIN" -c "import gmsh, skfem, numpy, scipy; print('validation python:', '$PYBIN', \
'gmsh', gmsh.__version__, 'scikit-fem', skfem.__version__, 'numpy', numpy.__version__, \
'scipy', scipy.__version__)"
