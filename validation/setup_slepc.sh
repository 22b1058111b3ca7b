#!/usr/bin/env bash
# Install what `vibrofem modes --engine slepc` needs: SLEPc, PETSc and MUMPS with their Python
# bindings (Debian's python3-slepc4py, for /usr/bin/python3) and Open MPI's mpirun (openmpi-bin).
#
#   bash validation/setup_slepc.sh        # idempotent; as root with apt-get (CI, containers)
#
# The Debian build needs PETSC_DIR and SLEPC_DIR; vibrofem sets them to Debian's paths when they
# are unset (see src/app/engines/slepc.rs), and this script checks the import with them.
set -euo pipefail
export PETSC_DIR="${PETSC_DIR:-/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real}"
export SLEPC_DIR="${SLEPC_DIR:-/usr/lib/slepcdir/slepc3.18/x86_64-linux-gnu-real}"
ok() { /usr/bin/python3 -c "import numpy, petsc4py, slepc4py, mpi4py" >/dev/null 2>&1 && command -v mpirun >/dev/null 2>&1; }
if ! ok; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "setup_slepc.sh: installing python3-slepc4py python3-petsc4py python3-mpi4py python3-numpy openmpi-bin" >&2
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
            python3-slepc4py python3-petsc4py python3-mpi4py python3-numpy openmpi-bin >/dev/null
    else
        echo "setup_slepc.sh: install Debian's python3-slepc4py, python3-mpi4py and openmpi-bin (as root: apt-get install" \
             "python3-slepc4py python3-mpi4py openmpi-bin)" >&2
        exit 1
    fi
fi
/usr/bin/python3 -c "import slepc4py, petsc4py; print('SLEPc engine: slepc4py', slepc4py.__version__, 'petsc4py', petsc4py.__version__)"
mpirun --version | head -1
