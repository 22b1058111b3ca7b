#!/usr/bin/env bash
# Print the Python interpreter every validation step uses (one resolver for run_live.sh, .ci/run
# and the scripts): validation/.venv/bin/python when it has the tools, else python3 when it has
# them, else set them up with validation/setup.sh and resolve again.
#
#   PY="$(bash validation/python.sh)"
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
has_tools() { "$1" -c "import gmsh, skfem, numpy, scipy, pytest" >/dev/null 2>&1; }
for attempt in 1 2; do
    if [ -x "$HERE/.venv/bin/python" ] && has_tools "$HERE/.venv/bin/python"; then
        echo "$HERE/.venv/bin/python"
        exit 0
    fi
    if has_tools "${PYTHON:-python3}"; then
        command -v "${PYTHON:-python3}"
        exit 0
    fi
    [ "$attempt" = 1 ] && bash "$HERE/setup.sh" >&2
done
echo "validation/python.sh: no Python with gmsh, scikit-fem, numpy and scipy after setup.sh" >&2
exit 1
