#!/usr/bin/env python3
"""scikit-fem reference eigenfrequencies on vibrofem's committed gmsh meshes.

Produces one ``validation/reference/<case>.json`` per case (schema below): the lowest natural
frequencies of linear elasticity with consistent mass, computed by scikit-fem on *exactly the same
mesh* vibrofem reads, so that vibrofem must agree to ~1e-6 relative.

Run from anywhere (paths are resolved against the crate root)::

    validation/.venv/bin/python validation/skfem_modes.py                 # all cases -> validation/reference/
    validation/.venv/bin/python validation/skfem_modes.py --cases cube    # cases whose name contains 'cube'
    validation/.venv/bin/python validation/skfem_modes.py --out /tmp/ref --check validation/reference
    validation/.venv/bin/python validation/skfem_modes.py --selftest      # ordering / completeness cross-checks
    validation/.venv/bin/python validation/skfem_modes.py --list

How the discrete problem is made identical to an isoparametric code reading the gmsh file:

* The mesh is read with gmsh's own API (MSH 4.1 and 2.2). scikit-fem's mesh is built from the
  CORNER nodes only (gmsh lists corners first in every cell); the higher-order space comes from the
  element: tet4 -> ElementTetP1, tet10 -> ElementTetP2, hex8 -> ElementHex1, hex20 -> ElementHexS2,
  hex27 -> ElementHex2, each wrapped in ElementVector. On straight-sided cells whose midside nodes
  sit at edge/face/cell midpoints (all our meshes) these spaces equal the isoparametric ones.
  This is *checked* for every case: the set of skfem DOF locations must equal the set of gmsh node
  coordinates used by the volume cells (a bijection, via a KD-tree), so the dof counts agree too.
* Hex corner order differs: gmsh numbers the corners (-1,-1,-1), (1,-1,-1), (1,1,-1), (-1,1,-1),
  then the same at z=+1; skfem's MeshHex expects (0,0,0), (0,0,1), (0,1,0), (1,0,0), (0,1,1),
  (1,0,1), (1,1,0), (1,1,1). Hence ``t_skfem = t_gmsh[[0, 4, 3, 1, 7, 5, 2, 6]]``. Checked by
  ``--selftest``: the gmsh-read structured hex meshes give the same frequencies as skfem's own
  ``MeshHex.init_tensor`` meshes, and every cell's volume is positive and sums to the box volume.
* Quadrature is exact for K and M on affine cells: intorder = 2p (skfem's intorder is the total
  degree for tets and the degree per direction for hexes, ceil((intorder+1)/2) Gauss points per
  direction): 2 for P1/Q1, 4 for P2/S2/Q2.
* Fixed groups clamp all three DOFs of every node of the group (corner and midside nodes): the
  group's node coordinates from gmsh are matched to skfem DOF locations.
* Eigen solve: ``scipy.sparse.linalg.eigsh(K, M=M, sigma, which='LM', tol=1e-12)`` in shift-invert
  mode with sigma = -(2 pi 10 Hz)^2, so free-free models (6 zero eigenvalues) are fine. The
  factorisation of K - sigma M is SuperLU with a symmetric (MMD on A+A^T) ordering. Four extra modes
  are computed and dropped. Each elastic mode is checked: ||Kx - lam Mx|| / ||Kx|| < 1e-8.
  Completeness is checked by a Sturm count: the inertia of K - s M (SuperLU, symmetric mode,
  no pivoting, so sign(diag U) = sign(D) of an LDL^T) at s in a gap above the recorded modes
  must equal the number of modes below s.

JSON schema (one file per case)::

    {"case", "mesh" (relative to the crate root), "length_unit" ("m"|"mm"), "element",
     "skfem_element", "material": {"young", "poisson", "density"}, "fixed_groups": [...],
     "n_rigid", "dofs" (free equations), "dofs_total" (3 x nodes), "mass_kg",
     "frequencies_hz": [...all computed, sorted, rigid ones included...],
     "max_rel_residual", "sturm": {"shift_hz", "count", "expected"}, "versions": {...},
     optional "analytic_f1_hz", "published_hz", "note"}
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field

import gmsh
import numpy as np
import scipy
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree

import skfem
from skfem import (Basis, BilinearForm, ElementHex1, ElementHex2, ElementHexS2, ElementTetP1,
                   ElementTetP2, ElementVector, MeshHex, MeshTet)
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)          # crate root
REF_DIR = os.path.join(HERE, "reference")

STEEL = {"young": 2.1e11, "poisson": 0.3, "density": 7850.0}
SHIFT_HZ = 10.0                       # sigma = -(2 pi SHIFT_HZ)^2
EXTRA_MODES = 4                       # computed beyond the recorded ones, for the Sturm gap
RESIDUAL_LIMIT = 1e-8

# gmsh element type -> (our name, number of corners)
GMSH_TYPES = {4: ("tet4", 4), 11: ("tet10", 4), 5: ("hex8", 8), 17: ("hex20", 8), 12: ("hex27", 8)}
SKFEM_ELEMENTS = {
    "tet4": (ElementTetP1, 2), "tet10": (ElementTetP2, 4),
    "hex8": (ElementHex1, 2), "hex20": (ElementHexS2, 4), "hex27": (ElementHex2, 4),
}
# skfem MeshHex vertex i sits at gmsh corner HEX_GMSH_TO_SKFEM[i]
HEX_GMSH_TO_SKFEM = [0, 4, 3, 1, 7, 5, 2, 6]


# --------------------------------------------------------------------------------------------
# cases
# --------------------------------------------------------------------------------------------

@dataclass
class Case:
    case: str
    mesh: str                          # relative to the crate root
    fixed_groups: list = field(default_factory=list)
    material: dict = field(default_factory=lambda: dict(STEEL))
    length_unit: str = "m"
    n_elastic: int | None = None       # default: 20 free-free, 12 with supports
    extra: dict = field(default_factory=dict)

    @property
    def n_modes(self) -> int:
        if self.n_elastic is not None:
            return self.n_elastic + (0 if self.fixed_groups else 6)
        return 26 if not self.fixed_groups else 12


def euler_bernoulli_hz(beta_l: float, length: float, b: float, h: float, mat: dict) -> float:
    """f = (beta L)^2 / (2 pi L^2) sqrt(E I / (rho A)) for a b x h rectangular section."""
    area, inertia = b * h, b * h ** 3 / 12.0
    return beta_l ** 2 / (2 * math.pi * length ** 2) * math.sqrt(
        mat["young"] * inertia / (mat["density"] * area))


def all_cases() -> list[Case]:
    m = "meshes/"
    cases = []
    for h in (30, 20, 15):
        for el in ("tet4", "tet10"):
            name = f"s1_plate_{el}_h{h}"
            cases.append(Case(name, m + name + ".msh", extra={"published_hz": 725.37}))
    cases.append(Case("s1_plate_tet10_h15_nu028", m + "s1_plate_tet10_h15.msh",
                      material={"young": 2.1e11, "poisson": 0.28, "density": 7850.0},
                      extra={"published_hz": 725.37,
                             "note": "nu = 0.28, the likely default of the published package"}))
    cases.append(Case("s1_plate_tet10_h30_mm", m + "s1_plate_tet10_h30_mm.msh", length_unit="mm",
                      extra={"note": "same mesh as s1_plate_tet10_h30, coordinates in mm"}))
    cases.append(Case("s1_plate_tet10_h30_msh22", m + "s1_plate_tet10_h30_msh22.msh",
                      extra={"note": "same mesh as s1_plate_tet10_h30, MSH 2.2 ASCII"}))
    for el in ("hex8", "hex20", "hex27"):
        for d in ("10x10x2", "20x20x4"):
            name = f"s1_plate_{el}_{d}"
            cases.append(Case(name, m + name + ".msh", extra={"published_hz": 725.37}))
    for name in ("s2_plate_tet10_h40", "s2_plate_hex20_27x12x3"):
        cases.append(Case(name, m + name + ".msh", extra={"published_hz": 722.01}))
    cases.append(Case("cube_hex20_4x4x4", m + "cube_hex20_4x4x4.msh",
                      extra={"note": "free cube 0.1 m: triple eigenvalues"}))
    cases.append(Case("bar_hex20_15x2x2", m + "bar_hex20_15x2x2.msh", extra={
        "note": "free bar 0.3 x 0.02 x 0.02 m along x: double eigenvalues; analytic = "
                "Euler-Bernoulli free-free beta L = 4.730041",
        "analytic_f1_hz": euler_bernoulli_hz(4.730041, 0.3, 0.02, 0.02, STEEL)}))
    cases.append(Case("cantilever_hex20_40x2x2", m + "cantilever_hex20_40x2x2.msh",
                      fixed_groups=["xmin"], extra={
        "note": "cantilever 0.2 x 0.01 x 0.01 m along x, xmin clamped; analytic = "
                "Euler-Bernoulli fixed-free beta L = 1.8751 (shear and the 3D clamp make FE lower/"
                "higher by a fraction of a percent)",
        "analytic_f1_hz": euler_bernoulli_hz(1.8751, 0.2, 0.01, 0.01, STEEL)}))
    cases.append(Case("external_beams_tet4", "../shared/meshes/external/beams.msh",
                      fixed_groups=["fixed"],
                      material={"young": 200e9, "poisson": 0.3, "density": 8050.0},
                      extra={"note": "scikit-fem's beams.msh (structural vibration example)"}))
    return cases


# --------------------------------------------------------------------------------------------
# mesh reading
# --------------------------------------------------------------------------------------------

@dataclass
class GmshMesh:
    kind: str                # tet4 | tet10 | hex8 | hex20 | hex27
    xyz: np.ndarray          # (n_used, 3) coordinates of the nodes used by the volume cells
    cells: np.ndarray        # (n_cells, nodes per cell), indices into xyz, gmsh node order
    groups: dict             # name -> (dim, array of node coordinates (k, 3))
    n_corners: int


def read_gmsh(path: str, scale: float = 1.0) -> GmshMesh:
    """Read a .msh with gmsh's API; coordinates multiplied by ``scale`` (e.g. 1e-3 for mm)."""
    if not gmsh.isInitialized():
        gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.clear()
    gmsh.open(path)
    tags, coords, _ = gmsh.model.mesh.getNodes()
    coords = coords.reshape(-1, 3) * scale
    index = {int(t): i for i, t in enumerate(tags)}
    types, _, enodes = gmsh.model.mesh.getElements(3)
    if len(types) != 1 or types[0] not in GMSH_TYPES:
        raise ValueError(f"{path}: expected one supported 3D cell type, got {list(types)}")
    kind, ncorner = GMSH_TYPES[int(types[0])]
    npe = gmsh.model.mesh.getElementProperties(int(types[0]))[3]
    conn = np.array([index[int(t)] for t in enodes[0]], dtype=np.int64).reshape(-1, npe)
    used, cells = np.unique(conn, return_inverse=True)
    groups = {}
    for dim, ptag in gmsh.model.getPhysicalGroups():
        name = gmsh.model.getPhysicalName(dim, ptag)
        gtags, _ = gmsh.model.mesh.getNodesForPhysicalGroup(dim, ptag)
        groups[name] = (dim, coords[[index[int(t)] for t in gtags]])
    return GmshMesh(kind, coords[used], cells.reshape(conn.shape), groups, ncorner)


def skfem_mesh(g: GmshMesh):
    """scikit-fem mesh on the corner nodes of ``g`` (hex corners permuted to skfem's order)."""
    corners = g.cells[:, :g.n_corners]
    used, t = np.unique(corners, return_inverse=True)
    t = t.reshape(corners.shape)
    p = g.xyz[used].T.copy()
    if g.kind.startswith("tet"):
        return MeshTet(p, t.T.copy())
    return MeshHex(p, t[:, HEX_GMSH_TO_SKFEM].T.copy())


# --------------------------------------------------------------------------------------------
# assembly, constraints, eigen solve
# --------------------------------------------------------------------------------------------

@BilinearForm
def _mass(u, v, w):
    return w.rho * dot(u, v)


def assemble(g: GmshMesh, material: dict):
    """Return (basis, K, M) with exact quadrature, after checking DOF locations == gmsh nodes."""
    mesh = skfem_mesh(g)
    elem_cls, intorder = SKFEM_ELEMENTS[g.kind]
    basis = Basis(mesh, ElementVector(elem_cls()), intorder=intorder)
    check_dofs_match_nodes(basis, g)
    K = linear_elasticity(*lame_parameters(material["young"], material["poisson"])).assemble(basis)
    M = _mass.assemble(basis, rho=material["density"])
    return basis, K.tocsr(), M.tocsr()


def _tol(xyz: np.ndarray) -> float:
    return 1e-9 * float(np.max(np.ptp(xyz, axis=0)))


def check_dofs_match_nodes(basis, g: GmshMesh) -> None:
    """The skfem scalar DOF locations must be exactly the gmsh volume nodes (a bijection)."""
    locs = basis.doflocs[:, 0::3].T          # ElementVector interleaves components
    if len(locs) != len(g.xyz):
        raise AssertionError(f"skfem has {len(locs)} scalar dofs, gmsh {len(g.xyz)} volume nodes")
    dist, idx = cKDTree(g.xyz).query(locs)
    if dist.max() > _tol(g.xyz) or len(np.unique(idx)) != len(idx):
        raise AssertionError(f"skfem DOF locations do not match gmsh nodes (max dist {dist.max()})")


def fixed_dofs(basis, g: GmshMesh, names: list) -> np.ndarray:
    """All DOFs (x, y, z) at every node of the named groups."""
    locs = basis.doflocs.T
    tree = cKDTree(locs)
    out = []
    for name in names:
        if name not in g.groups:
            raise KeyError(f"group '{name}' not in mesh (has {sorted(g.groups)})")
        _, pts = g.groups[name]
        hits = tree.query_ball_point(pts, r=_tol(g.xyz))
        n = sum(len(h) for h in hits)
        if n != 3 * len(pts):
            raise AssertionError(f"group '{name}': {len(pts)} nodes but {n} matching dofs")
        out.extend(i for h in hits for i in h)
    return np.unique(np.array(out, dtype=np.int64))


def factor(A):
    """SuperLU of a symmetric matrix with a symmetric ordering and no pivoting (LDL^T-like)."""
    return spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                     options={"SymmetricMode": True})


def count_below(K, M, s: float) -> int:
    """Sturm count: number of eigenvalues of (K, M) below s = negative pivots of K - s M."""
    lu = factor(K - s * M)
    if not np.array_equal(lu.perm_r, lu.perm_c):
        raise AssertionError("SuperLU pivoted off the diagonal: inertia not available")
    return int(np.sum(lu.U.diagonal() < 0))


def shift() -> float:
    """The shift sigma = -(2 pi SHIFT_HZ)^2 of the eigen solves."""
    return -(2 * math.pi * SHIFT_HZ) ** 2


def solve_modes(K, M, k: int, seed: int = 0, lu=None):
    """Lowest k eigenpairs by shift-invert Lanczos; returns (lam sorted, vectors).

    ``lu``: an existing ``factor(K - shift() * M)`` (else computed here).
    """
    sigma = shift()
    if lu is None:
        lu = factor(K - sigma * M)
    op = spla.LinearOperator(K.shape, matvec=lu.solve, dtype=float)
    v0 = np.random.default_rng(seed).standard_normal(K.shape[0])
    k = min(k, K.shape[0] - 1)
    lam, vec = spla.eigsh(K, k=k, M=M, sigma=sigma, which="LM", OPinv=op, tol=1e-12, v0=v0,
                          ncv=min(K.shape[0], max(2 * k + 1, 40)))
    # One step of subspace (inverse) iteration + Rayleigh-Ritz on the whole block: ARPACK's
    # vectors are accurate in the shift-inverted metric, but their tiny high-frequency error
    # shows up amplified in ||Kx - lam Mx|| (up to ~1e-8 relative); one more application of
    # (K - sigma M)^-1 M damps it and the projected problem keeps multiplets intact.
    y = lu.solve(np.asarray(M @ vec))
    y /= np.linalg.norm(y, axis=0)
    kp, mp = y.T @ (K @ y), y.T @ (M @ y)
    lam, z = scipy.linalg.eigh(0.5 * (kp + kp.T), 0.5 * (mp + mp.T))
    vec = y @ z
    order = np.argsort(lam)
    return lam[order], vec[:, order]


def to_hz(lam: np.ndarray) -> list:
    return [math.sqrt(max(x, 0.0)) / (2 * math.pi) for x in lam]


# --------------------------------------------------------------------------------------------
# one case
# --------------------------------------------------------------------------------------------

def versions() -> dict:
    return {"scikit-fem": skfem.__version__, "scipy": scipy.__version__,
            "numpy": np.__version__, "gmsh": gmsh.__version__}


def run_case(c: Case, verbose: bool = True) -> dict:
    t0 = time.perf_counter()
    scale = {"m": 1.0, "mm": 1e-3}[c.length_unit]
    g = read_gmsh(os.path.normpath(os.path.join(ROOT, c.mesh)), scale)
    basis, K, M = assemble(g, c.material)
    kind = g.kind
    ndof_total = K.shape[0]
    ex = np.zeros(ndof_total)
    ex[0::3] = 1.0
    mass = float(ex @ (M @ ex))
    t_asm = time.perf_counter()

    if c.fixed_groups:
        fixed = fixed_dofs(basis, g, c.fixed_groups)
        free = np.setdiff1d(np.arange(ndof_total), fixed)
        Kf, Mf = K[free][:, free].tocsc(), M[free][:, free].tocsc()
    else:
        free = np.arange(ndof_total)
        Kf, Mf = K.tocsc(), M.tocsc()
    del basis, K, M, g            # keep the peak memory down (the factor is the big one)
    n = c.n_modes
    lam_all, vec_all = solve_modes(Kf, Mf, n + EXTRA_MODES)
    lam, vec = lam_all[:n], vec_all[:, :n]
    t_eig = time.perf_counter()

    # rigid modes and residuals
    top = max(abs(lam_all[-1]), 1.0)
    rigid = np.abs(lam) < 1e-8 * top
    n_rigid = int(rigid.sum())
    expected_rigid = 0 if c.fixed_groups else 6
    if n_rigid != expected_rigid:
        raise AssertionError(f"{c.case}: {n_rigid} rigid modes, expected {expected_rigid}")
    kx = Kf @ vec
    res = np.linalg.norm(kx - (Mf @ vec) * lam, axis=0) / np.maximum(np.linalg.norm(kx, axis=0),
                                                                     1e-300)
    max_res = float(res[~rigid].max())
    if max_res > RESIDUAL_LIMIT:
        raise AssertionError(f"{c.case}: relative residual {max_res:.2e} > {RESIDUAL_LIMIT}")

    # Sturm check in the widest relative gap above the recorded modes (or the highest gap below)
    gaps = [(j, (lam_all[j] - lam_all[j - 1]) / lam_all[j]) for j in range(n, len(lam_all))
            if lam_all[j - 1] > 0]
    good = [(j, gap) for j, gap in gaps if gap > 1e-3]
    if not good:   # fall back to the last clear gap below the top recorded mode
        good = [(j, (lam_all[j] - lam_all[j - 1]) / lam_all[j]) for j in range(n - 1, 0, -1)
                if lam_all[j - 1] > 0 and (lam_all[j] - lam_all[j - 1]) / lam_all[j] > 1e-3][:1]
    j = good[0][0]
    s = 0.5 * (lam_all[j - 1] + lam_all[j])
    count = count_below(Kf, Mf, s)
    if count != j:
        raise AssertionError(f"{c.case}: Sturm count {count} below {to_hz([s])[0]:.3f} Hz, "
                             f"but {j} modes computed there: modes missed")
    t_end = time.perf_counter()

    out = {
        "case": c.case, "mesh": c.mesh, "length_unit": c.length_unit, "element": kind,
        "skfem_element": SKFEM_ELEMENTS[kind][0].__name__, "material": c.material,
        "fixed_groups": c.fixed_groups, "n_rigid": n_rigid, "dofs": int(len(free)),
        "dofs_total": int(ndof_total), "mass_kg": mass, "frequencies_hz": to_hz(lam),
        "max_rel_residual": max_res,
        "sturm": {"shift_hz": to_hz([s])[0], "count": count, "expected": int(j)},
        "versions": versions(),
    }
    out.update(c.extra)
    if verbose:
        f = out["frequencies_hz"]
        print(f"{c.case:30s} dofs {len(free):6d}  f[{n_rigid}] {f[n_rigid]:12.6f} Hz  "
              f"mass {mass:9.4f} kg  res {max_res:.1e}  sturm {count}/{j}  "
              f"asm {t_asm - t0:5.1f}s eig {t_eig - t_asm:5.1f}s check {t_end - t_eig:5.1f}s",
              flush=True)
    return out


def write_json(obj: dict, path: str) -> None:
    with open(path, "w") as fh:
        json.dump(obj, fh, indent=1)
        fh.write("\n")


# --------------------------------------------------------------------------------------------
# comparison of two reference sets, self-tests
# --------------------------------------------------------------------------------------------

def compare_refs(new: dict, old: dict, rel: float = 1e-9, rigid_rel: float = 1e-4) -> list:
    """Differences between two reference dicts for the same case (empty list if equal).

    Elastic frequencies must agree to ``rel``; rigid-mode frequencies are round-off noise and
    must only stay below max(1e-3 Hz, rigid_rel x first elastic frequency).
    """
    errs = []
    for key in ("element", "n_rigid", "dofs", "fixed_groups", "length_unit"):
        if new.get(key) != old.get(key):
            errs.append(f"{key}: {new.get(key)} != {old.get(key)}")
    if abs(new["mass_kg"] - old["mass_kg"]) > rel * abs(old["mass_kg"]):
        errs.append(f"mass {new['mass_kg']} != {old['mass_kg']}")
    fn, fo = new["frequencies_hz"], old["frequencies_hz"]
    if len(fn) != len(fo):
        errs.append(f"{len(fn)} frequencies != {len(fo)}")
    nr = old["n_rigid"]
    rigid_abs_hz = max(1e-3, rigid_rel * fo[nr]) if nr < len(fo) else 1e-3
    for i, (a, b) in enumerate(zip(fn, fo)):
        if i < nr:
            if a > rigid_abs_hz or b > rigid_abs_hz:
                errs.append(f"rigid mode {i}: {a} / {b} Hz")
        elif abs(a - b) > rel * abs(b):
            errs.append(f"mode {i}: {a!r} != {b!r} (rel {abs(a - b) / b:.1e})")
    return errs


def gmsh_isoparametric_km(path: str, material: dict):
    """Independent oracle: isoparametric K, M on the gmsh connectivity in gmsh's own node order,
    with gmsh's own shape functions and Gauss rules (``getBasisFunctions``), DOFs node-major.

    Used by ``--selftest`` to show that skfem's corner-mesh P2/S2/Q2 spaces are the same discrete
    problem as an isoparametric tet10/hex20/hex27 code reading the file.
    """
    if not gmsh.isInitialized():
        gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.clear()
    gmsh.open(path)
    tags, coords, _ = gmsh.model.mesh.getNodes()
    coords = coords.reshape(-1, 3)
    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    types, _, enodes = gmsh.model.mesh.getElements(3)
    etype = int(types[0])
    npe = gmsh.model.mesh.getElementProperties(etype)[3]
    conn = index[enodes[0].astype(np.int64)].reshape(-1, npe)
    rule = "Gauss5" if etype in (4, 11) else "Gauss4"    # exact for degree 4 (tets: positive weights)
    lc, w = gmsh.model.mesh.getIntegrationPoints(etype, rule)
    _, n, _ = gmsh.model.mesh.getBasisFunctions(etype, lc, "Lagrange")
    _, dn, _ = gmsh.model.mesh.getBasisFunctions(etype, lc, "GradLagrange")
    nq = len(w)
    n = np.asarray(n).reshape(nq, npe)
    dn = np.asarray(dn).reshape(nq, npe, 3)
    xe = coords[conn]                                     # (ne, npe, 3)
    jac = np.einsum("eai,qaj->eqij", xe, dn)              # dx_i / dxi_j
    det = np.linalg.det(jac)
    if not (np.all(det > 0) or np.all(det < 0)):
        raise AssertionError(f"{path}: cells of both orientations")
    grad = np.einsum("qaj,eqji->eqai", dn, np.linalg.inv(jac))   # dN_a / dx_i
    wdet = np.abs(det) * np.asarray(w)[None, :]
    lam, mu = lame_parameters(material["young"], material["poisson"])
    # K_(a,i),(b,j) = lam dNa_i dNb_j + mu (dNa_j dNb_i + delta_ij dNa.dNb)
    ke = (lam * np.einsum("eq,eqai,eqbj->eaibj", wdet, grad, grad)
          + mu * np.einsum("eq,eqaj,eqbi->eaibj", wdet, grad, grad)
          + mu * np.einsum("eq,eqak,eqbk,ij->eaibj", wdet, grad, grad, np.eye(3)))
    me = material["density"] * np.einsum("eq,qa,qb,ij->eaibj", wdet, n, n, np.eye(3))
    dofs = (3 * conn[:, :, None] + np.arange(3)[None, None, :]).reshape(len(conn), -1)
    rows = np.repeat(dofs, 3 * npe, axis=1).ravel()
    cols = np.tile(dofs, (1, 3 * npe)).ravel()
    ndof = 3 * len(coords)
    K = sp.coo_matrix((ke.reshape(len(conn), -1).ravel(), (rows, cols)), shape=(ndof, ndof)).tocsc()
    M = sp.coo_matrix((me.reshape(len(conn), -1).ravel(), (rows, cols)), shape=(ndof, ndof)).tocsc()
    return K, M


def selftest() -> int:
    """Cross-checks of the reading/ordering conventions; prints and returns the failure count."""
    fails = 0
    mat = STEEL
    # 1. structured hex meshes read from gmsh == skfem's own tensor meshes
    for kind in ("hex8", "hex20", "hex27"):
        g = read_gmsh(os.path.join(ROOT, f"meshes/s1_plate_{kind}_10x10x2.msh"))
        _, K, M = assemble(g, mat)
        lam_g, _ = solve_modes(K, M, 16)
        native = MeshHex.init_tensor(np.linspace(0, 0.3, 11), np.linspace(0, 0.3, 11),
                                     np.linspace(0, 0.02, 3))
        elem_cls, intorder = SKFEM_ELEMENTS[kind]
        nb = Basis(native, ElementVector(elem_cls()), intorder=intorder)
        Kn = linear_elasticity(*lame_parameters(mat["young"], mat["poisson"])).assemble(nb)
        Mn = _mass.assemble(nb, rho=mat["density"])
        lam_n, _ = solve_modes(Kn.tocsc(), Mn.tocsc(), 16)
        d = np.max(np.abs(lam_g[6:] - lam_n[6:]) / lam_n[6:])
        ok = d < 1e-10 and K.shape == Kn.shape
        fails += not ok
        print(f"selftest {kind}: gmsh-read vs MeshHex.init_tensor, max rel diff {d:.1e} "
              f"dofs {K.shape[0]}/{Kn.shape[0]} -> {'ok' if ok else 'FAIL'}")
        # every cell has the orientation of skfem's own meshes (skfem's reference hex is the
        # point reflection of [0,1]^3, so its detJ is negative on a right-handed mesh) and the
        # cell volumes sum to the box volume
        mesh = skfem_mesh(g)
        vb = Basis(mesh, ElementHex1(), intorder=2)
        detj = vb.mapping.detDF(vb.X)
        nb1 = Basis(native, ElementHex1(), intorder=2)
        sign = np.sign(nb1.mapping.detDF(nb1.X)).ravel()[0]
        same = bool(np.all(np.sign(detj) == sign))
        vol = float(np.sum(vb.dx))
        ok = same and abs(vol - 0.3 * 0.3 * 0.02) < 1e-14
        fails += not ok
        print(f"selftest {kind}: detJ sign as in skfem's own mesh everywhere: {same}, "
              f"volume {vol:.15g} -> {'ok' if ok else 'FAIL'}")
    # 2. a wrong hex corner order must be detected (the permutation is not a no-op)
    g = read_gmsh(os.path.join(ROOT, "meshes/s1_plate_hex8_10x10x2.msh"))
    corners = g.cells[:, :8]
    used, t = np.unique(corners, return_inverse=True)
    bad = MeshHex(g.xyz[used].T.copy(), t.reshape(corners.shape).T.copy())   # gmsh order as-is
    vb = Basis(bad, ElementHex1(), intorder=2)
    dj = vb.mapping.detDF(vb.X)
    ok = abs(float(np.sum(vb.dx)) - 0.3 * 0.3 * 0.02) > 1e-6 or len(np.unique(np.sign(dj))) > 1
    fails += not ok
    print(f"selftest: unpermuted gmsh hex order is detectably wrong -> {'ok' if ok else 'FAIL'}")
    # 3. dense generalized eigensolver on the small cube: eigsh found every triple root
    g = read_gmsh(os.path.join(ROOT, "meshes/cube_hex20_4x4x4.msh"))
    _, K, M = assemble(g, mat)
    lam_s, _ = solve_modes(K.tocsc(), M.tocsc(), 26)
    lam_d = scipy.linalg.eigh(K.toarray(), M.toarray(), eigvals_only=True, subset_by_index=[0, 25])
    d = np.max(np.abs(lam_s[6:] - lam_d[6:]) / lam_d[6:])
    ok = d < 1e-10
    fails += not ok
    print(f"selftest cube: eigsh vs dense eigh (26 modes) max rel diff {d:.1e} -> "
          f"{'ok' if ok else 'FAIL'}")
    # 4. Sturm count agrees with the dense spectrum
    s = 0.5 * (lam_d[10] + lam_d[11]) if lam_d[11] > lam_d[10] * (1 + 1e-6) else None
    if s is not None:
        c = count_below(K, M, s)
        want = int(np.sum(scipy.linalg.eigh(K.toarray(), M.toarray(), eigvals_only=True) < s))
        ok = c == want
        fails += not ok
        print(f"selftest cube: Sturm count {c}, dense count {want} -> {'ok' if ok else 'FAIL'}")
    # 5. independent isoparametric oracle in gmsh's node order == skfem on the corner mesh
    for name in ("s1_plate_tet4_h30", "s1_plate_tet10_h30", "s1_plate_hex8_10x10x2",
                 "s1_plate_hex20_10x10x2", "s1_plate_hex27_10x10x2", "cube_hex20_4x4x4"):
        path = os.path.join(ROOT, "meshes", name + ".msh")
        Ki, Mi = gmsh_isoparametric_km(path, mat)
        lam_i, _ = solve_modes(Ki, Mi, 16)
        g = read_gmsh(path)
        _, K, M = assemble(g, mat)
        lam_s, _ = solve_modes(K.tocsc(), M.tocsc(), 16)
        d = np.max(np.abs(lam_i[6:] - lam_s[6:]) / lam_s[6:])
        ok = d < 1e-10 and Ki.shape == K.shape
        fails += not ok
        print(f"selftest {name}: gmsh-order isoparametric oracle vs skfem, max rel diff {d:.1e}, "
              f"f7 {to_hz(lam_s[6:7])[0]:.6f} Hz -> {'ok' if ok else 'FAIL'}")
    print(f"selftest: {fails} failure(s)")
    return fails


# --------------------------------------------------------------------------------------------

def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=REF_DIR, help="output folder (default validation/reference)")
    ap.add_argument("--cases", action="append", default=[],
                    help="substring of case names to run (repeatable); default all")
    ap.add_argument("--check", metavar="REFDIR",
                    help="after computing, compare with the JSON files in REFDIR (1e-9 rel)")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    ap.add_argument("--selftest", action="store_true", help="run the convention cross-checks")
    args = ap.parse_args(argv)

    if args.selftest:
        return 1 if selftest() else 0
    cases = [c for c in all_cases() if not args.cases or any(s in c.case for s in args.cases)]
    if args.list:
        for c in cases:
            print(f"{c.case:30s} {c.mesh}  fixed={c.fixed_groups} modes={c.n_modes}")
        return 0
    os.makedirs(args.out, exist_ok=True)
    bad = 0
    for c in cases:
        res = run_case(c)
        write_json(res, os.path.join(args.out, c.case + ".json"))
        if args.check:
            with open(os.path.join(args.check, c.case + ".json")) as fh:
                errs = compare_refs(res, json.load(fh))
            for e in errs:
                print(f"  MISMATCH {c.case}: {e}")
            bad += bool(errs)
    if args.check:
        print(f"references: {len(cases) - bad} passed, {bad} failed")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
