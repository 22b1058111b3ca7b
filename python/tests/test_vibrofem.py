"""Tests of the vibrofem Python package (run by .ci/run through validation/run_live.sh):

    validation/.venv/bin/python -m pytest -q python/tests

The references are independent: scikit-fem's K and M on the same tet10 mesh (assembled by
validation/skfem_modes.py's conventions), scipy's eigsh on vibrofem's own matrices, scipy's
Matrix Market reader, hand formulas of the leaf spring, and the command line's JSON.
"""

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any, Tuple

import numpy as np
import numpy.typing as npt
import pytest
import scipy.io
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree

import vibrofem as vf

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "validation"))

STEEL = {"young": 2.1e11, "poisson": 0.3, "density": 7850.0}
TET10 = os.path.join(ROOT, "meshes", "s1_plate_tet10_h30.msh")


Plate = Tuple[vf.Mesh, vf.Model, sp.csr_array, sp.csr_array]


@pytest.fixture(scope="module")
def plate() -> Plate:
    mesh = vf.read_mesh(TET10)
    model = vf.Model(mesh, material=(STEEL["young"], STEEL["poisson"], STEEL["density"]))
    K, M = model.assemble()
    return mesh, model, K, M


def skfem_permutation(mesh: vf.Mesh, dofs: vf.Dofs, basis: Any) -> npt.NDArray[np.int64]:
    """skfem DOF of each vibrofem free DOF: same node (by position) and component."""
    locs = basis.doflocs[:, 0::3].T  # ElementVector interleaves the three components
    dist_, k = cKDTree(locs).query(mesh.nodes[dofs.node])
    dist = np.asarray(dist_)
    scale = np.ptp(mesh.nodes, axis=0).max()
    assert dist.max() <= 1e-9 * scale, f"a vibrofem node has no skfem DOF ({dist.max():.2e} m away)"
    perm = 3 * k + dofs.component
    assert len(np.unique(perm)) == len(perm) == basis.N
    return perm


def test_assemble_equals_scikit_fem_entry_by_entry(plate: Plate) -> None:
    import skfem_modes

    mesh, model, K, M = plate
    g = skfem_modes.read_gmsh(TET10)
    basis, Ks, Ms = skfem_modes.assemble(g, STEEL)
    perm = skfem_permutation(mesh, model.dofs, basis)
    for name, A, B in (("K", K, Ks), ("M", M, Ms)):
        Bp = B[perm][:, perm].tocsr()
        D = (A - Bp).tocoo()
        # Entry by entry, relative to the largest entry: each entry is a sum of element
        # contributions of that magnitude, so rounding differences between two exact quadratures
        # are a few ulps of it (an entry that cancels to ~0 cannot be compared to itself).
        scale = abs(Bp).max()
        worst = abs(D.data).max() / scale if D.nnz else 0.0
        assert worst <= 1e-12, f"{name}: max |vibrofem − scikit-fem| = {worst:.2e} × max entry"
        # And the same sparsity wherever scikit-fem has a non-negligible entry.
        big = abs(Bp) > 1e-12 * scale
        assert (abs(A)[big] > 0).all(), f"{name}: vibrofem lacks entries scikit-fem has"
    assert abs(K - K.T).max() == 0.0 and abs(M - M.T).max() == 0.0


def test_modes_equal_eigsh_on_the_same_matrices(plate: Plate) -> None:
    _, model, K, M = plate
    modes = model.modes(12)
    assert modes.complete and modes.accurate, modes.notes
    # Free-free: shift-invert below the rigid-body modes, as validation/skfem_modes.py does.
    sigma = -(2 * np.pi * 10.0) ** 2
    lam, _ = spla.eigsh(K.tocsc(), k=12, M=M.tocsc(), sigma=sigma, which="LM", tol=1e-12)
    f = np.sqrt(np.abs(np.sort(lam))) / (2 * np.pi)
    # Rigid-body modes are round-off on either side of 0 (a few mHz); elastic modes of the same
    # matrices must agree to the eigen solvers' accuracy (both verified to ~1e-12 residuals).
    assert modes.kinds[:6] == ["rigid"] * 6
    assert np.all(np.abs(modes.frequencies_hz[:6]) < 1e-2) and np.all(f[:6] < 1e-2)
    rel = np.abs(modes.frequencies_hz[6:] - f[6:]) / f[6:]
    assert rel.max() <= 1e-9, rel
    # Shapes: M-orthonormal vectors over the free DOFs, and the node × component view agrees.
    X = modes.vectors
    G = X.T @ (M @ X)
    assert np.abs(G - np.eye(12)).max() < 1e-8
    d = model.dofs
    assert np.allclose(modes.shapes[d.node, d.component, :], X, rtol=0, atol=1e-14)
    assert modes.participation.shape == (12, 6) and modes.effective_mass.shape == (12, 6)


def test_export_round_trips(plate: Plate, tmp_path: Path) -> None:
    _, model, K, M = plate
    files = model.export(tmp_path)
    assert {os.path.basename(f) for f in files} >= {"K.mtx", "M.mtx", "K.petsc", "M.petsc", "dofs.csv", "model.json"}
    for name, A in (("K", K), ("M", M)):
        # Matrix Market: the values are written in their shortest exact form, so equality is exact.
        B = sp.csr_matrix(scipy.io.mmread(str(tmp_path / f"{name}.mtx")))
        assert abs(B - A).max() == 0.0
        # PETSc binary (big-endian AIJ: classid, rows, cols, nnz, row lengths, columns, values).
        raw = open(tmp_path / f"{name}.petsc", "rb").read()
        head = np.frombuffer(raw[:16], dtype=">i4")
        assert head[0] == 1211216 and head[1] == head[2] == A.shape[0]
        n, nnz = int(head[1]), int(head[3])
        lens = np.frombuffer(raw[16:16 + 4 * n], dtype=">i4")
        cols = np.frombuffer(raw[16 + 4 * n:16 + 4 * (n + nnz)], dtype=">i4")
        vals = np.frombuffer(raw[16 + 4 * (n + nnz):], dtype=">f8")
        P = sp.csr_matrix((vals, cols, np.concatenate([[0], np.cumsum(lens)])), shape=(n, n))
        assert abs(P - A).max() == 0.0
    summary = json.load(open(tmp_path / "model.json"))
    assert summary["dofs"] == K.shape[0] and summary["nnz"] == K.nnz
    rows = open(tmp_path / "dofs.csv").read().splitlines()
    assert rows[0] == "equation,node,node_tag,component,x,y,z" and len(rows) == K.shape[0] + 1


def test_leaf_spring_stiffness_between_beam_and_plate_theory() -> None:
    # S3 leaf 169 × 146 × 9 mm, clamped at x = 0, the far face guided along z: a fixed-guided
    # strip lies between beam theory (k = E b h³/l³) and plate theory (E/(1 − ν²)).
    E, nu, l, b, h = 2.1e11, 0.3, 0.169, 0.146, 0.009
    mesh = vf.read_mesh(f"box:{l},{b},{h}:24,8,2:hex20")
    leaf = vf.Model(mesh, fix=["xmin"], couple={"xmax": "z"})
    st = leaf.static(force={"xmax": (0, 0, 1000)})
    k = st.stiffness["xmax"]
    kb = E * b * h**3 / l**3
    assert kb < k < kb / (1 - nu**2), k
    # Equilibrium: the clamp's reaction balances the applied force.
    assert st.reactions["xmin"]["force"][2] == pytest.approx(-1000.0, rel=1e-9)
    assert st.displacement.shape == (len(mesh.nodes), 6) and st.von_mises.max() > 0


def test_run_scene_returns_the_cli_report(tmp_path: Path) -> None:
    scene = os.path.join(ROOT, "scenes", "s3_leaf_stiffness.toml")
    r = vf.run_scene(scene)
    binary = os.path.join(ROOT, "target", "release", "vibrofem")
    if not os.access(binary, os.X_OK):
        pytest.skip("target/release/vibrofem not built (cargo build --release)")
    out = subprocess.run([binary, "run", scene, "--json", "-o", str(tmp_path)], capture_output=True,
                         text=True, cwd=ROOT, check=True).stdout
    cli = json.loads(out)

    def strip(d: Any) -> Any:  # timings and peak memory differ from run to run
        if isinstance(d, dict):
            return {k: strip(v) for k, v in d.items() if not k.startswith("tim") and "memory" not in k and k != "outputs"}
        if isinstance(d, list):
            return [strip(v) for v in d]
        return d

    assert strip(r) == strip(cli)


def test_errors_raise_with_the_command_line_messages(tmp_path: Path) -> None:
    with pytest.raises(vf.InputError, match="nope.msh"):
        vf.read_mesh(str(tmp_path / "nope.msh"))
    mesh = vf.read_mesh("box:0.1,0.1,0.1:2,2,2:hex8")
    with pytest.raises(vf.InputError, match=r"unknown group 'base' \(the mesh has: .*xmin"):
        vf.Model(mesh, fix=["base"]).assemble()
    with pytest.raises(vf.InputError, match="invalid material .*three comma-separated numbers"):
        vf.Model(mesh, material=(2.1e11, 0.3))
    with pytest.raises(vf.InputError, match="unknown unit"):
        vf.read_mesh("box:0.1,0.1,0.1:2,2,2:hex8", length_unit="inch")
    with pytest.raises(vf.VibrofemError):
        vf.Model(mesh).modes(n=0)


def test_length_unit_and_groups() -> None:
    mm = vf.read_mesh(os.path.join(ROOT, "meshes", "s1_plate_tet10_h30_mm.msh"), length_unit="mm")
    m = vf.read_mesh(TET10)
    assert np.allclose(np.ptp(mm.nodes, axis=0), np.ptp(m.nodes, axis=0), rtol=1e-12)
    assert mm.cell_kinds.get("tet10", 0) == m.cell_kinds["tet10"]
    c = m.cells("tet10")
    assert c.shape == (m.cell_kinds["tet10"], 10) and c.max() < len(m.nodes)
    # A plate of 300 × 300 × 20 mm of steel: 14.13 kg.
    assert vf.Model(m).mass == pytest.approx(0.3 * 0.3 * 0.02 * 7850, rel=1e-9)


def slepc_available() -> bool:
    import shutil

    env = dict(os.environ)
    env.setdefault("PETSC_DIR", "/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real")
    env.setdefault("SLEPC_DIR", "/usr/lib/slepcdir/slepc3.18/x86_64-linux-gnu-real")
    ok = subprocess.run(["/usr/bin/python3", "-c", "import slepc4py"], env=env, capture_output=True).returncode == 0
    return ok and shutil.which("mpirun") is not None


def test_slepc_engine_equals_the_native_solver(plate: Plate) -> None:
    # CI installs SLEPc (validation/setup_slepc.sh) and sets VIBROFEM_REQUIRE_SLEPC=1, so this
    # cannot pass by skipping there.
    if not slepc_available():
        if os.environ.get("VIBROFEM_REQUIRE_SLEPC") == "1":
            pytest.fail("SLEPc engine required but python3-slepc4py/openmpi-bin are missing")
        pytest.skip("SLEPc not installed (bash validation/setup_slepc.sh)")
    _, model, _, _ = plate
    native = model.modes(10)
    slepc = model.modes(10, engine="slepc", ranks=2)
    assert slepc.complete and slepc.accurate, slepc.notes
    assert any("SLEPc" in n for n in slepc.notes)
    # Both verified to backward errors ≤ 1e-10 on the same K and M.
    rel = np.abs(slepc.frequencies_hz[6:] - native.frequencies_hz[6:]) / native.frequencies_hz[6:]
    assert rel.max() <= 1e-8, rel


def test_harmonic_equals_a_scipy_complex_solve_on_the_same_matrices() -> None:
    """model.harmonic against scipy's direct complex solve of ((1 + iωβ)K − (ω² − iωα)M) u = F on
    the matrices model.assemble() returns: the force acts on the reference node of a guided
    coupling, so F is one unit entry and the coupled face moves with that node. Both methods of
    the package (direct, and modal superposition of 40 modes with the static correction) must
    agree with scipy: direct to 1e-9 (two LU solves of one system), modal to 1e-4 (40 modes plus a
    static correction leave terms of order ω²/λ of the omitted modes: 5e-5 at 650 Hz here)."""

    mesh = vf.read_mesh("box:0.3,0.05,0.02:12,2,2:hex20")
    model = vf.Model(mesh, fix=["xmin"], couple={"xmax": "z"})
    K, M = model.assemble()
    d = model.dofs
    ref = [i for i in range(K.shape[0]) if d.node[i] >= len(mesh.nodes) and d.component[i] == 2]
    assert len(ref) == 1
    F = np.zeros(K.shape[0], dtype=complex)
    F[ref[0]] = 100.0
    tip = int(mesh.group_nodes("xmax")[0])
    alpha, beta = 2.0, 1e-5
    freqs = [20.0, 180.0, 650.0]
    for method, tol in (("direct", 1e-9), ("modal", 1e-4)):
        h = model.harmonic(force={"xmax": (0, 0, 100)}, sweep=(20.0, 650.0, 2), rayleigh=(alpha, beta),
                           method=method, modes=40 if method == "modal" else None)
        h1 = model.harmonic(force={"xmax": (0, 0, 100)}, freq=180.0, rayleigh=(alpha, beta), method=method,
                            modes=40 if method == "modal" else None)
        got = [h.displacement[0, tip, 2], h1.displacement[0, tip, 2], h.displacement[1, tip, 2]]
        for f, g in zip(freqs, got):
            w = 2 * np.pi * f
            A = ((1 + 1j * w * beta) * K - (w * w - 1j * w * alpha) * M).tocsc()
            u = spla.spsolve(A, F)
            want = u[ref[0]]
            assert abs(g - want) <= tol * abs(want), (method, f, g, want)
    with pytest.raises(vf.InputError, match="damping"):
        model.harmonic(force={"xmax": (0, 0, 1)}, freq=50.0)
