#!/bin/bash
# Install CalculiX (Debian's calculix-ccx) for validation/ccx_buckling.py and the
# buckling_calculix_same_mesh test; a no-op when ccx is already on PATH.
set -e
if command -v ccx >/dev/null 2>&1; then
    echo "CalculiX: $(command -v ccx)"
    exit 0
fi
exec bash "$(dirname "$0")/setup_peers.sh" --calculix
