#!/usr/bin/env bash
# Install the peer solvers validation/bench_peers.py compares against: CalculiX (Debian's
# calculix-ccx: SPOOLES + ARPACK) and SLEPc + MUMPS (validation/setup_slepc.sh).
#
#   bash validation/setup_peers.sh                 # both; idempotent; as root with apt-get
#   bash validation/setup_peers.sh --calculix      # CalculiX only
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
want_ccx=0 want_slepc=0
[ "$#" = 0 ] && want_ccx=1 && want_slepc=1
for a in "$@"; do
    case "$a" in
        --calculix) want_ccx=1 ;;
        --slepc) want_slepc=1 ;;
        *) echo "setup_peers.sh: unknown option $a" >&2; exit 2 ;;
    esac
done
# apt_install PKG WHAT: install a Debian package as root; 1 when this user cannot.
apt_install() {
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "setup_peers.sh: installing $1 ($2)" >&2
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$1" >/dev/null
    else
        return 1
    fi
}
if [ "$want_ccx" = 1 ] && ! command -v ccx >/dev/null 2>&1; then
    if ! apt_install calculix-ccx "CalculiX"; then
        echo "setup_peers.sh: install Debian's calculix-ccx (as root: apt-get install calculix-ccx)" >&2
        exit 1
    fi
fi
[ "$want_ccx" = 1 ] && echo "CalculiX: $(command -v ccx)"
[ "$want_slepc" = 1 ] && bash "$HERE/setup_slepc.sh"
# An optimised BLAS under both peers (MUMPS's dense kernels, ARPACK's): Debian's packages link
# libblas.so.3, which is the reference BLAS unless OpenBLAS is installed beside it (it then takes
# the alternative). Without it SLEPc + MUMPS's eigen solve at 119k DOFs takes 38 s instead of
# ~16 s: a comparison against an untuned installation.
if ! dpkg -s libopenblas0-pthread >/dev/null 2>&1; then
    if ! apt_install libopenblas0-pthread "the BLAS of the peers"; then
        echo "setup_peers.sh: the peers will run on the reference BLAS (as root: apt-get install libopenblas0-pthread)" >&2
    fi
fi
echo "BLAS of the peers: $(readlink -f /usr/lib/x86_64-linux-gnu/libblas.so.3 2>/dev/null || echo unknown)"
exit 0
