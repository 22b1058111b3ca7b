"""Export K and M, solve them elsewhere, and run vibrofem's SLEPc engine.

The model's matrices go to a folder (PETSc binary, Matrix Market, dofs.csv, model.json); scipy
reads the Matrix Market files back and its ``eigsh`` finds the same frequencies as vibrofem's own
solver; then ``model.modes(engine="slepc", ranks=2)`` solves with SLEPc + MUMPS under mpirun. The
SLEPc part needs Debian's python3-slepc4py and openmpi-bin (bash validation/setup_slepc.sh): when
they are absent it is skipped, and the script says so. Writes export_slepc.png.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Dict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import numpy.typing as npt
import scipy.io
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import vibrofem as vf
from _common import out_dir


def slepc_available() -> bool:
    env = dict(os.environ)
    env.setdefault("PETSC_DIR", "/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real")
    env.setdefault("SLEPC_DIR", "/usr/lib/slepcdir/slepc3.18/x86_64-linux-gnu-real")
    if shutil.which("mpirun") is None or not os.path.exists("/usr/bin/python3"):
        return False
    probe = subprocess.run(["/usr/bin/python3", "-c", "import slepc4py"], env=env, capture_output=True)
    return probe.returncode == 0


def main() -> None:
    out = out_dir()
    mesh = vf.read_mesh("box:0.4,0.1,0.02:16,4,2:hex20")
    model = vf.Model(mesh, fix=["xmin"])
    native = model.modes(6)
    results: Dict[str, npt.NDArray[np.float64]] = {"vibrofem (native)": native.frequencies_hz}
    with tempfile.TemporaryDirectory() as tmp:
        files = model.export(tmp)
        print("exported:", ", ".join(sorted(Path(f).name for f in files)))
        K = sp.csr_array(scipy.io.mmread(str(Path(tmp) / "K.mtx")))
        M = sp.csr_array(scipy.io.mmread(str(Path(tmp) / "M.mtx")))
    # Matrix Market keeps one triangle of a symmetric matrix: mmread gives back both.
    lam = spla.eigsh(K.tocsc(), k=6, M=M.tocsc(), sigma=0.0, which="LM", return_eigenvectors=False)
    results["scipy eigsh on the export"] = np.sqrt(np.sort(lam)) / (2 * np.pi)
    if slepc_available():
        slepc = model.modes(6, engine="slepc", ranks=2)
        assert slepc.complete and slepc.accurate, slepc.notes
        results["SLEPc, 2 MPI ranks"] = slepc.frequencies_hz
    else:
        print("SLEPc part skipped: python3-slepc4py or openmpi-bin not installed (bash validation/setup_slepc.sh)")
    ref = results["vibrofem (native)"]
    for name, f in results.items():
        print(f"{name:28s}", np.round(f, 3), f"max rel. diff {np.max(np.abs(f - ref) / ref):.1e}")
    fig, ax = plt.subplots(figsize=(8, 3.8))
    w = 0.8 / len(results)
    for i, (name, f) in enumerate(results.items()):
        ax.bar(np.arange(1, 7) + (i - (len(results) - 1) / 2) * w, f, width=w, label=name)
    ax.set_xlabel("mode")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title("one model, three solvers" if len(results) == 3 else "one model, two solvers (SLEPc absent)")
    ax.legend()
    fig.tight_layout()
    png = out / "export_slepc.png"
    fig.savefig(png, dpi=110)
    print("wrote", png)


if __name__ == "__main__":
    main()
