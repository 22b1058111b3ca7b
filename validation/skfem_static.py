#!/usr/bin/env python3
"""scikit-fem reference solutions of linear statics on vibrofem's committed gmsh meshes.

Produces one ``validation/reference/static_<case>.json`` per case (schema below): displacements
of every node, reactions per constrained group and nodal stresses of K u = f, computed by
scikit-fem on *exactly the same mesh and element* vibrofem reads, so that vibrofem's static
solver must agree to rounding (displacements to ~1e-8 relative to the largest one).

Run from anywhere (paths are resolved against the crate root)::

    validation/.venv/bin/python validation/skfem_static.py                  # all cases
    validation/.venv/bin/python validation/skfem_static.py --cases guided   # names containing 'guided'
    validation/.venv/bin/python validation/skfem_static.py --out /tmp/ref --check validation/reference
    validation/.venv/bin/python validation/skfem_static.py --list

The discrete problem is made identical to an isoparametric code reading the gmsh file as in
``skfem_modes.py`` (whose mesh reading, element table, corner-order permutation and DOF/node
bijection check are imported from it): tet10 -> ElementTetP2, hex20 -> ElementHexS2 on the corner
mesh, intorder 4 (exact on affine cells).

Cases
    * ``s3_leaf_hex20_*_traction``: the S3 leaf (l x b x h = 169 x 146 x 9 mm, x along the length,
      z through the thickness) clamped at ``clamp_fixed`` (all three components of every node),
      a uniform traction t_z = Fz / (b h) on the ``clamp_guided`` face with Fz = 1000 N, assembled
      as the consistent load f_a = int_face N_a t dA, and the guided end otherwise free (a
      cantilever). Tip results: mean, min and max u_z over the ``clamp_guided`` nodes.
    * ``s3_leaf_*_guided``: the same leaf clamped at ``clamp_fixed``, and on ``clamp_guided`` the
      prescribed u = (0, 0, 0.46e-3) m at every node: the guided end translates rigidly along z
      without rotating and without in-plane motion. This is exactly what a rigid coupling of that
      face to a reference node guided along z imposes, so Fz / Delta is the S3 guided stiffness,
      and 1000 N / k is the deflection under the published P = 1000 N. Reaction: the z-sum of
      K u - f over the ``clamp_guided`` nodes.
    * ``cantilever_hex20_40x2x2_tip``: the 0.2 x 0.01 x 0.01 m bar of ``cantilever_hex20_40x2x2.msh``
      clamped at ``xmin`` with a uniform traction totalling Fz = 100 N on ``xmax``.

Nodal stresses (``stress`` block) are computed the way vibrofem's ``post::stress::nodal_stress``
does (direct nodal evaluation, simple average): in every cell, the displacement gradient of the
P2 / S2 field is evaluated at the cell's own nodes (a skfem Basis whose "quadrature points" are the
reference DOF locations of the element), giving the cell's stress D eps at each of its nodes;
the tensors are averaged over the cells sharing each node. von Mises is taken of the averaged
tensor; ``von_mises_max_unaveraged`` is the largest cell value at the node. Points are matched to
gmsh nodes by coordinates (KD-tree), so no node-order convention is involved.

JSON schema (one file per case)::

    {"case", "mesh" (relative to the crate root), "length_unit": "m", "element", "skfem_element",
     "material": {"young", "poisson", "density"},
     "bcs": [{"group", "type": "fixed"|"displacement"|"traction", ...}],
     "n_nodes", "dofs_total", "dofs_constrained",
     "node_tags": [...file order...], "node_order": "file order of $Nodes (= vibrofem's dense index)",
     "displacement": [[ux, uy, uz], ...per node, in node_tags order...],
     "applied_force": [Fx, Fy, Fz] (sum of the load vector),
     "reactions": {group: [Rx, Ry, Rz]} (sum over the group's nodes of K u - f),
     "equilibrium": |sum of reactions + applied| / max(|applied|, |reaction of each group|),
     "solve_rel_residual", "results": {...key numbers...},
     "stress": {"method", "voigt_order", "nodal": [[sxx, syy, szz, syz, sxz, sxy], ...],
                "von_mises": [...], "von_mises_max_unaveraged": [...],
                "max_von_mises": {"value", "node_tag", "coords"},
                "max_von_mises_per_group": {group: {...}}, "probes": [...]},
     "analytic": {...}, "published": {...}, "note", "versions"}
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
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree

from skfem import Basis, FacetBasis, LinearForm, condense
from skfem import ElementVector
from skfem.models.elasticity import lame_parameters, linear_elasticity

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from skfem_modes import (ROOT, SKFEM_ELEMENTS, STEEL, _tol, check_dofs_match_nodes,  # noqa: E402
                         read_gmsh, skfem_mesh, versions)

REF_DIR = os.path.join(HERE, "reference")

LEAF = {"l": 0.169, "b": 0.146, "h": 0.009}
DELTA = 0.46e-3           # S3 imposed deflection (m)
P_LEAF = 1000.0           # S3 test force (N)
CANT = {"l": 0.2, "b": 0.01, "h": 0.01}
P_CANT = 100.0
SHEAR_K = 5.0 / 6.0       # Timoshenko shear coefficient of a rectangle


@dataclass
class Case:
    case: str
    mesh: str                                  # relative to the crate root
    fixed: list                                # groups with all components fixed
    traction: dict = field(default_factory=dict)   # group -> total force [Fx, Fy, Fz] (uniform traction)
    displacement: dict = field(default_factory=dict)  # group -> prescribed [ux, uy, uz] at every node
    material: dict = field(default_factory=lambda: dict(STEEL))
    tip_group: str | None = None
    probes: list = field(default_factory=list)  # points (m): the nearest node is reported
    extra: dict = field(default_factory=dict)


def leaf_analytic(mat: dict) -> dict:
    """Beam formulas for the S3 leaf: fixed-guided and cantilever, E and plane-strain E/(1-nu^2)."""
    e, nu = mat["young"], mat["poisson"]
    l, b, h = LEAF["l"], LEAF["b"], LEAF["h"]
    i = b * h ** 3 / 12
    g = e / (2 * (1 + nu))
    shear = l / (SHEAR_K * g * b * h)          # Timoshenko shear compliance per unit force
    out = {}
    for tag, ee in (("E", e), ("E_plane_strain", e / (1 - nu ** 2))):
        out[f"guided_k_{tag}"] = 12 * ee * i / l ** 3                     # = E b h^3 / l^3
        out[f"guided_deflection_1000N_{tag}"] = P_LEAF * l ** 3 / (12 * ee * i)
        out[f"guided_sigma_max_at_delta_{tag}"] = 3 * ee * h * DELTA / l ** 2
        out[f"cantilever_deflection_1000N_{tag}"] = P_LEAF * l ** 3 / (3 * ee * i)
    out["timoshenko_shear_deflection_1000N"] = P_LEAF * shear
    out["formulas"] = ("guided k = 12 E I / l^3 = E b h^3 / l^3, sigma = 3 E h Delta / l^2; cantilever "
                       "P l^3 / (3 E I); shear term P l / (kappa G b h), kappa = 5/6")
    return out


def cantilever_analytic(mat: dict) -> dict:
    e, nu = mat["young"], mat["poisson"]
    l, b, h = CANT["l"], CANT["b"], CANT["h"]
    i = b * h ** 3 / 12
    g = e / (2 * (1 + nu))
    eb = P_CANT * l ** 3 / (3 * e * i)
    return {"euler_bernoulli_tip_deflection": eb,
            "timoshenko_tip_deflection": eb + P_CANT * l / (SHEAR_K * g * b * h),
            "root_sigma_xx_beam": P_CANT * l * (h / 2) / i,
            "formulas": "P l^3 / (3 E I) (+ P l / (kappa G A), kappa = 5/6); sigma = P l (h/2) / I"}


def all_cases() -> list[Case]:
    m = "meshes/"
    l, b, h = LEAF["l"], LEAF["b"], LEAF["h"]
    leaf_probes = [[0.0, b / 2, h], [0.0, 0.0, h], [l / 2, b / 2, h], [l / 4, b / 2, h], [l, b / 2, 0.0],
                   [l, b / 2, h]]
    published = {"deflection_1000N_m": 1.937e-4, "stiffness_N_per_m": P_LEAF / 1.937e-4,
                 "von_mises_max_at_0p46mm_Pa": 83.22e6, "allowable_Pa": 170e6,
                 "source": "docs/spec/scenes.md S3; docs/spec/paper.md sections 13-14 (SolidWorks FE)"}
    tz = [0.0, 0.0, P_LEAF]
    cases = []
    for mesh in ("s3_leaf_hex20_10x6x1", "s3_leaf_hex20_20x12x2"):
        cases.append(Case(f"{mesh}_traction", m + mesh + ".msh", fixed=["clamp_fixed"],
                          traction={"clamp_guided": tz}, tip_group="clamp_guided", probes=leaf_probes,
                          extra={"analytic": leaf_analytic(STEEL),
                                 "note": "cantilever: uniform traction on the free end face, no guide"}))
    for mesh in ("s3_leaf_hex20_10x6x1", "s3_leaf_hex20_20x12x2", "s3_leaf_tet10_h9"):
        cases.append(Case(f"{mesh}_guided", m + mesh + ".msh", fixed=["clamp_fixed"],
                          displacement={"clamp_guided": [0.0, 0.0, DELTA]}, tip_group="clamp_guided",
                          probes=leaf_probes,
                          extra={"analytic": leaf_analytic(STEEL), "published": published,
                                 "note": "fixed-guided: u = (0, 0, Delta) at every clamp_guided node "
                                         "(rigid, non-rotating guided end)"}))
    cases.append(Case("cantilever_hex20_40x2x2_tip", m + "cantilever_hex20_40x2x2.msh", fixed=["xmin"],
                      traction={"xmax": [0.0, 0.0, P_CANT]}, tip_group="xmax",
                      probes=[[0.0, 0.005, 0.01], [0.1, 0.005, 0.01], [0.2, 0.005, 0.005]],
                      extra={"analytic": cantilever_analytic(STEEL)}))
    return cases


# --------------------------------------------------------------------------------------------
# mesh bookkeeping: node tags in file order, groups as skfem dofs / facets
# --------------------------------------------------------------------------------------------

def file_node_tags(path: str) -> np.ndarray:
    """Node tags in the order of the file's $Nodes section (MSH 4.1 ASCII)."""
    tags = []
    with open(path) as fh:
        for line in fh:
            if line.startswith("$Nodes"):
                break
        _, _, _, _ = map(int, fh.readline().split())
        while True:
            head = fh.readline()
            if head.startswith("$EndNodes"):
                break
            _, _, parametric, n = map(int, head.split())
            if parametric:
                raise ValueError(f"{path}: parametric nodes not supported here")
            tags.extend(int(fh.readline()) for _ in range(n))
            for _ in range(n):
                fh.readline()
    return np.array(tags, dtype=np.int64)


def node_table(path: str):
    """(tags in file order, coordinates in file order) via gmsh (the model must be open)."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    coords = coords.reshape(-1, 3)
    order = {int(t): i for i, t in enumerate(tags)}
    ftags = file_node_tags(path)
    if len(ftags) != len(tags):
        raise AssertionError(f"{path}: {len(ftags)} nodes in the file, gmsh has {len(tags)}")
    return ftags, coords[[order[int(t)] for t in ftags]]


def group_dofs(basis, pts: np.ndarray, tol: float) -> np.ndarray:
    """skfem dofs (x, y, z interleaved per node) at the given node coordinates, shape (k, 3)."""
    locs = basis.doflocs.T
    tree = cKDTree(locs)
    hits = tree.query_ball_point(pts, r=tol)
    out = np.zeros((len(pts), 3), dtype=np.int64)
    for i, h in enumerate(hits):
        if len(h) != 3:
            raise AssertionError(f"node {pts[i]}: {len(h)} dofs")
        h = sorted(h)
        out[i] = h
    return out


def group_facets(mesh, pts: np.ndarray, tol: float) -> np.ndarray:
    """Boundary facets of the corner mesh whose vertices all belong to the group's nodes."""
    tree = cKDTree(pts)
    bf = mesh.boundary_facets()
    verts = mesh.p[:, mesh.facets[:, bf]]                  # (3, nv, nf)
    d, _ = tree.query(verts.reshape(3, -1).T)
    inside = (d <= tol).reshape(verts.shape[1], -1).all(axis=0)
    return bf[inside]


# --------------------------------------------------------------------------------------------
# one case
# --------------------------------------------------------------------------------------------

def nodal_stress(basis, u: np.ndarray, elem_cls, mat: dict, node_xyz: np.ndarray, tol: float):
    """Direct nodal evaluation in each cell, averaged: (stress (n, 6), vm (n,), vm_max (n,), count)."""
    x_ref = elem_cls().doflocs.T                            # (3, nloc): the reference node positions
    w = np.ones(x_ref.shape[1])
    nb = Basis(basis.mesh, basis.elem, quadrature=(x_ref, w))
    grad = nb.interpolate(u).grad                           # (3, 3, nel, nloc): du_i/dx_j
    xs = nb.mapping.F(x_ref)                                # (3, nel, nloc)
    lam, mu = lame_parameters(mat["young"], mat["poisson"])
    eps = 0.5 * (grad + grad.transpose(1, 0, 2, 3))
    tr = eps[0, 0] + eps[1, 1] + eps[2, 2]
    sig = 2 * mu * eps
    for i in range(3):
        sig[i, i] += lam * tr
    voigt = np.stack([sig[0, 0], sig[1, 1], sig[2, 2], sig[1, 2], sig[0, 2], sig[0, 1]], axis=-1)
    voigt = voigt.reshape(-1, 6)                            # (nel * nloc, 6)
    pts = xs.reshape(3, -1).T
    dist, idx = cKDTree(node_xyz).query(pts)
    if dist.max() > tol:
        raise AssertionError(f"cell node positions do not match gmsh nodes (max dist {dist.max():.2e})")
    n = len(node_xyz)
    total = np.zeros((n, 6))
    np.add.at(total, idx, voigt)
    count = np.bincount(idx, minlength=n)
    avg = total / np.maximum(count, 1)[:, None]
    vm_cell = von_mises(voigt)
    vm_max = np.zeros(n)
    np.maximum.at(vm_max, idx, vm_cell)
    return avg, von_mises(avg), vm_max, count


def von_mises(s: np.ndarray) -> np.ndarray:
    return np.sqrt(0.5 * ((s[:, 0] - s[:, 1]) ** 2 + (s[:, 1] - s[:, 2]) ** 2 + (s[:, 2] - s[:, 0]) ** 2)
                   + 3 * (s[:, 3] ** 2 + s[:, 4] ** 2 + s[:, 5] ** 2))


def solve(K, f, D, x):
    """Solve K u = f with u[D] = x[D]; returns (u, relative residual of the free equations)."""
    free = np.setdiff1d(np.arange(K.shape[0]), D)
    Kff = K[free][:, free].tocsc()
    rhs = f[free] - K[free][:, D] @ x[D]
    lu = spla.splu(Kff, permc_spec="MMD_AT_PLUS_A")
    uf = lu.solve(rhs)
    for _ in range(2):                                      # iterative refinement
        uf += lu.solve(rhs - Kff @ uf)
    res = float(np.linalg.norm(Kff @ uf - rhs) / np.linalg.norm(rhs))
    u = x.copy()
    u[free] = uf
    return u, res


def _lists(a: np.ndarray):
    """Nested lists of floats (full precision: stresses are differences of displacements, and
    rounding u to 13 digits already moves the recomputed stresses by ~1e-9)."""
    return np.asarray(a, dtype=float).tolist()


def run_case(c: Case, verbose: bool = True) -> dict:
    t0 = time.perf_counter()
    path = os.path.normpath(os.path.join(ROOT, c.mesh))
    g = read_gmsh(path)
    ftags, fxyz = node_table(path)                          # gmsh is still open on this file
    mesh = skfem_mesh(g)
    elem_cls, intorder = SKFEM_ELEMENTS[g.kind]
    basis = Basis(mesh, ElementVector(elem_cls()), intorder=intorder)
    check_dofs_match_nodes(basis, g)
    tol = _tol(g.xyz)
    if len(fxyz) != len(g.xyz):
        raise AssertionError(f"{c.mesh}: {len(fxyz)} nodes in the file but {len(g.xyz)} used by cells")
    lame = lame_parameters(c.material["young"], c.material["poisson"])
    K = linear_elasticity(*lame).assemble(basis).tocsr()
    ndof = K.shape[0]
    # dofs of every file node, in file order (n, 3)
    node_dofs = group_dofs(basis, fxyz, tol)

    f = np.zeros(ndof)
    x = np.zeros(ndof)
    constrained = []
    bcs = []
    for name in c.fixed:
        _, pts = g.groups[name]
        d = group_dofs(basis, pts, tol)
        constrained.append(d.ravel())
        bcs.append({"group": name, "type": "fixed", "components": [0, 1, 2], "nodes": len(pts)})
    for name, val in c.displacement.items():
        _, pts = g.groups[name]
        d = group_dofs(basis, pts, tol)
        for i in range(3):
            x[d[:, i]] = val[i]
        constrained.append(d.ravel())
        bcs.append({"group": name, "type": "displacement", "value": val, "nodes": len(pts),
                    "description": "u prescribed at every node of the group"})
    for name, force in c.traction.items():
        _, pts = g.groups[name]
        facets = group_facets(mesh, pts, tol)
        fb = FacetBasis(mesh, basis.elem, facets=facets, intorder=intorder)
        area = float(np.sum(fb.dx))
        t = np.array(force) / area

        @LinearForm
        def load(v, w):
            return t[0] * v[0] + t[1] * v[1] + t[2] * v[2]

        fg = load.assemble(fb)
        f += fg
        bcs.append({"group": name, "type": "traction", "total_force": force, "area_m2": area,
                    "traction_Pa": t.tolist(), "facets": int(len(facets)),
                    "description": "uniform traction, consistent load f_a = int N_a t dA"})
    D = np.unique(np.concatenate(constrained))
    u, res = solve(K, f, D, x)
    r = K @ u - f                                           # reactions (zero off the constrained dofs)
    reactions = {}
    for name in list(c.fixed) + list(c.displacement):
        _, pts = g.groups[name]
        d = group_dofs(basis, pts, tol)
        reactions[name] = [float(r[d[:, i]].sum()) for i in range(3)]
    applied = [float(f[node_dofs[:, i]].sum()) for i in range(3)]
    total_r = np.sum([reactions[k] for k in reactions], axis=0)
    scale = max([np.linalg.norm(applied)] + [np.linalg.norm(v) for v in reactions.values()] + [1e-300])
    equilibrium = float(np.linalg.norm(total_r + np.array(applied)) / scale)
    free_r = np.delete(r, D)
    if free_r.size and np.abs(free_r).max() > 1e-8 * max(np.abs(r).max(), 1e-300):
        raise AssertionError(f"{c.case}: residual force off the constraints {np.abs(free_r).max():.2e}")

    disp = u[node_dofs]                                     # (n, 3) in file order
    stress, vm, vm_max, count = nodal_stress(basis, u, elem_cls, c.material, fxyz, tol)
    if count.min() == 0:
        raise AssertionError(f"{c.case}: nodes without a cell")

    def at(i: int) -> dict:
        return {"value": float(vm[i]), "node_tag": int(ftags[i]), "coords": fxyz[i].tolist()}

    tree = cKDTree(fxyz)
    per_group = {}
    group_stats = {}
    for name, (_, pts) in g.groups.items():
        _, idx = tree.query(pts)
        i = idx[np.argmax(vm[idx])]
        per_group[name] = at(i) | {"von_mises_max_unaveraged": float(vm_max[idx].max())}
        group_stats[name] = idx
    probes = []
    for p in c.probes:
        _, i = tree.query(p)
        probes.append({"point": p, "node_tag": int(ftags[i]), "coords": fxyz[i].tolist(),
                       "displacement": disp[i].tolist(), "stress": stress[i].tolist(),
                       "von_mises": float(vm[i]), "von_mises_max_unaveraged": float(vm_max[i])})
    results = {"max_displacement_magnitude": float(np.linalg.norm(disp, axis=1).max())}
    if c.tip_group:
        idx = group_stats[c.tip_group]
        uz = disp[idx, 2]
        results.update({"tip_group": c.tip_group, "tip_uz_mean": float(uz.mean()),
                        "tip_uz_min": float(uz.min()), "tip_uz_max": float(uz.max())})
        if c.traction:
            fz = c.traction[c.tip_group][2]
            results["stiffness_force_over_mean_uz"] = fz / float(uz.mean())
    for name, val in c.displacement.items():
        if val[2] != 0:
            k = reactions[name][2] / val[2]
            results.update({"guided_reaction_Fz": reactions[name][2], "guided_stiffness_k": k,
                            "guided_deflection_at_1000N": P_LEAF / k,
                            "force_for_delta": reactions[name][2]})
    results["max_von_mises"] = at(int(np.argmax(vm)))
    results["max_von_mises_unaveraged"] = float(vm_max.max())

    out = {
        "case": c.case, "mesh": c.mesh, "length_unit": "m", "element": g.kind,
        "skfem_element": elem_cls.__name__, "material": c.material, "bcs": bcs,
        "n_nodes": int(len(ftags)), "dofs_total": int(ndof), "dofs_constrained": int(len(D)),
        "node_order": "file order of $Nodes (= vibrofem's dense node index); node_tags gives the tags",
        "applied_force": applied, "reactions": reactions, "equilibrium": equilibrium,
        "solve_rel_residual": res,
        "solve_accuracy": "SuperLU (MMD on A+A^T) + 2 steps of iterative refinement; other orderings "
                          "(COLAMD, natural) agree to <= 4e-10 of max |u| on these cases",
        "results": results,
        "node_tags": ftags.tolist(),
        "displacement": _lists(disp),
        "stress": {
            "method": "direct evaluation of D sym(grad u) at each cell's own nodes, simple average "
                      "over the cells sharing the node (as vibrofem post::stress::nodal_stress); "
                      "von Mises of the averaged tensor",
            "voigt_order": "xx, yy, zz, yz, xz, xy (Pa)",
            "max_von_mises_per_group": per_group, "probes": probes,
            "nodal": _lists(stress), "von_mises": _lists(vm), "von_mises_max_unaveraged": _lists(vm_max),
        },
        "versions": versions(),
    }
    out.update(c.extra)
    if verbose:
        msg = f"{c.case:34s} dofs {ndof:6d}  res {res:.1e}  eq {equilibrium:.1e}"
        if "tip_uz_mean" in results:
            msg += f"  tip uz mean {results['tip_uz_mean']:.6e}"
        if "guided_reaction_Fz" in results:
            msg += (f"  Fz {results['guided_reaction_Fz']:.2f} N  k {results['guided_stiffness_k']:.5e}"
                    f"  d(1000N) {results['guided_deflection_at_1000N']:.5e}")
        msg += f"  vm max {results['max_von_mises']['value'] / 1e6:.3f} MPa"
        msg += f" ({time.perf_counter() - t0:.1f}s)"
        print(msg, flush=True)
    return out


# --------------------------------------------------------------------------------------------
# output and comparison
# --------------------------------------------------------------------------------------------

def _fmt(v):
    """Compact JSON: scalars at full precision, arrays of numbers on one line each."""
    return json.dumps(v, separators=(",", ":"))


def write_json(obj: dict, path: str) -> None:
    """One key per line; the long per-node lists one row per line (diffable, not huge)."""
    def dump(o, indent):
        pad = " " * indent
        if isinstance(o, dict):
            items = [f'{pad} {json.dumps(k)}: {dump(v, indent + 1).lstrip()}' for k, v in o.items()]
            return pad + "{\n" + ",\n".join(items) + "\n" + pad + "}"
        if isinstance(o, list) and o and isinstance(o[0], list):
            rows = [pad + " " + _fmt(r) for r in o]
            return pad + "[\n" + ",\n".join(rows) + "\n" + pad + "]"
        return pad + _fmt(o)
    with open(path, "w") as fh:
        fh.write(dump(obj, 0))
        fh.write("\n")


def compare_refs(new: dict, old: dict, rel: float = 1e-9) -> list:
    errs = []
    for key in ("element", "n_nodes", "dofs_total", "dofs_constrained", "node_tags"):
        if new.get(key) != old.get(key):
            errs.append(f"{key} differs")
    a, b = np.array(new["displacement"]), np.array(old["displacement"])
    if a.shape != b.shape or np.abs(a - b).max() > rel * np.abs(b).max():
        errs.append("displacement differs")
    a, b = np.array(new["stress"]["von_mises"]), np.array(old["stress"]["von_mises"])
    if a.shape != b.shape or np.abs(a - b).max() > 1e-7 * np.abs(b).max():
        errs.append("von Mises differs")
    for g, r in old["reactions"].items():
        if np.abs(np.array(new["reactions"][g]) - r).max() > rel * max(np.abs(r).max(), 1.0):
            errs.append(f"reaction {g} differs")
    return errs


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=REF_DIR, help="output folder (default validation/reference)")
    ap.add_argument("--cases", action="append", default=[], help="substring of case names (repeatable)")
    ap.add_argument("--check", metavar="REFDIR", help="compare with static_*.json in REFDIR")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    args = ap.parse_args(argv)
    cases = [c for c in all_cases() if not args.cases or any(s in c.case for s in args.cases)]
    if args.list:
        for c in cases:
            print(f"static_{c.case:34s} {c.mesh}  fixed={c.fixed} traction={c.traction} "
                  f"displacement={c.displacement}")
        return 0
    os.makedirs(args.out, exist_ok=True)
    bad = 0
    for c in cases:
        res = run_case(c)
        name = f"static_{c.case}.json"
        write_json(res, os.path.join(args.out, name))
        if args.check:
            with open(os.path.join(args.check, name)) as fh:
                errs = compare_refs(res, json.load(fh))
            for e in errs:
                print(f"  MISMATCH {c.case}: {e}")
            bad += bool(errs)
    if args.check:
        print(f"references: {len(cases) - bad} passed, {bad} failed")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
