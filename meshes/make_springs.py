#!/usr/bin/env python3
"""Generate the committed spring meshes of vibrofem: the S3 leaf spring and the S5 coil spring.

Run from anywhere, with the validation venv (``bash validation/setup.sh``)::

    validation/.venv/bin/python meshes/make_springs.py              # all spring meshes into meshes/
    validation/.venv/bin/python meshes/make_springs.py --only s5    # names containing 's5'
    validation/.venv/bin/python meshes/make_springs.py --list
    validation/.venv/bin/python meshes/make_springs.py --outdir /tmp/m   # e.g. to diff against meshes/

Every file is MSH 4.1 ASCII, coordinates in METRES, with named physical groups. The options are
those of ``make_meshes.py`` (one thread, fixed algorithms), so the output is deterministic for a
given gmsh version (4.15.2 here): re-running the script rewrites the files byte for byte.

S3 leaf spring (docs/spec/scenes.md S3; docs/spec/paper.md sections 12-14)
    Free length l = 169 mm along x, width b = 146 mm along y, thickness h = 9 mm along z; the box
    [0, l] x [0, b] x [0, h]. Only the free length between the clamping bars is modelled: the two
    end faces are the clamp faces (the parts of the leaf inside the clamps, and the clamp contact
    patches, are not modelled).
    Groups: volume ``leaf``; surfaces ``clamp_fixed`` (x = 0, the clamped end), ``clamp_guided``
    (x = l, the guided end that translates along z without rotating), ``top`` (z = h) and
    ``bottom`` (z = 0).
    * ``s3_leaf_hex20_NXxNYxNZ``: structured (transfinite + recombine), incomplete second order
      (serendipity hex20, ``Mesh.SecondOrderIncomplete=1``), NX x NY x NZ cells.
    * ``s3_leaf_tet10_hH``: unstructured tet10, characteristic length H mm.
    All geometry is straight, and the midside nodes sit exactly at the edge midpoints
    (``Mesh.SecondOrderLinear=1``), so scikit-fem's P2 / serendipity spaces on the corner mesh are
    the same discrete problem (see validation/skfem_static.py).

S5 coil spring (docs/spec/scenes.md S5; docs/spec/paper.md section 16)
    Wire d = 6 mm, mean coil diameter D = 32 mm, 6 active turns, pitch p = 10 mm, helix axis z.
    The centre line is the helix (R cos t, R sin t, p t / 2 pi), t in [0, 12 pi], R = D/2: from
    (R, 0, 0) to (R, 0, 0.06). It is an OCC spline interpolating 48 points per turn (its length
    differs from the exact helix by < 1e-7 relative), and the wire is a circular disk of diameter
    d swept along it (``occ.addPipe``, Frenet trihedron). Only the active turns are modelled, with
    plain cut ends (no closed or ground end coils).
    Groups: volume ``wire``; surfaces ``end_bottom`` (the disk at z = 0), ``end_top`` (the disk at
    z = 0.06) and ``surface`` (the lateral surface).
    * ``s5_coil_tet10_hH``: unstructured tet10, characteristic length H mm (2.5 and 2 mm: 2.4
      and 3 cells across the wire). The midside nodes are placed ON the curved geometry
      (``Mesh.SecondOrderLinear=0``), because straight tet edges on a 3 mm wire radius lose
      several percent of the cross-section area, and the torsional stiffness goes as d^4.
      Curving makes a few cells near the surface nearly or completely inside out; those cells'
      midside nodes are moved back towards the straight edge midpoints, a quarter of the way per
      pass, until every cell's quality min det J / det J(straight cell) over its nodes and the
      degree-2 and degree-4 rule points is >= 0.1 (``_untangle_curved_tets``; gmsh's own
      high-order optimiser also repairs them, but its output changes from run to run). The
      script then checks that det J > 0 at the nodes and rule points of every cell: vibrofem
      integrates K and M at those points and recovers stresses at the nodes.
    The script prints the wire length and volume from the OCC geometry and from the mesh, against
    the helix formula L = n sqrt((pi D)^2 + p^2) and V = pi d^2 / 4 L, and the mass at 7850 kg/m^3.
"""

from __future__ import annotations

import argparse
import math
import os
import sys

import gmsh
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from make_meshes import _count, _init, _write  # noqa: E402  (same options as the other meshes)

# S3 leaf (m)
LEAF_L, LEAF_B, LEAF_H = 0.169, 0.146, 0.009
# S5 coil (m)
WIRE_D, COIL_D, TURNS, PITCH = 0.006, 0.032, 6, 0.010
SPLINE_POINTS_PER_TURN = 48
STEEL_DENSITY = 7850.0


# --------------------------------------------------------------------------------------------
# S3 leaf
# --------------------------------------------------------------------------------------------

def _leaf_geometry() -> int:
    """OCC box of the leaf with its named groups; returns the volume tag."""
    dims = (LEAF_L, LEAF_B, LEAF_H)
    vol = gmsh.model.occ.addBox(0.0, 0.0, 0.0, *dims)
    gmsh.model.occ.synchronize()
    wanted = {"clamp_fixed": (0, 0.0), "clamp_guided": (0, LEAF_L),
              "bottom": (2, 0.0), "top": (2, LEAF_H)}
    found = {}
    for _, s in gmsh.model.getEntities(2):
        c = gmsh.model.occ.getCenterOfMass(2, s)
        for name, (axis, value) in wanted.items():
            if abs(c[axis] - value) < 1e-9:
                found[name] = s
    assert sorted(found) == sorted(wanted), found
    for name in ("clamp_fixed", "clamp_guided", "top", "bottom"):
        tag = gmsh.model.addPhysicalGroup(2, [found[name]])
        gmsh.model.setPhysicalName(2, tag, name)
    tag = gmsh.model.addPhysicalGroup(3, [vol])
    gmsh.model.setPhysicalName(3, tag, "leaf")
    return vol


def leaf_hex20(divs, outdir: str) -> dict:
    """Structured hex20 leaf with ``divs`` = (nx, ny, nz) cells."""
    _init()
    vol = _leaf_geometry()
    dims = (LEAF_L, LEAF_B, LEAF_H)
    for _, cv in gmsh.model.getEntities(1):
        ends = gmsh.model.getBoundary([(1, cv)], oriented=False)
        p0, p1 = (gmsh.model.getValue(0, t, []) for _, t in ends)
        ext = [abs(p1[i] - p0[i]) for i in range(3)]
        axis = max(range(3), key=lambda i: ext[i])
        assert sum(e > 1e-9 * max(dims) for e in ext) == 1, ext
        gmsh.model.mesh.setTransfiniteCurve(cv, divs[axis] + 1)
    for _, s in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(s)
        gmsh.model.mesh.setRecombine(2, s)
    gmsh.model.mesh.setTransfiniteVolume(vol)
    gmsh.model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1)
    gmsh.model.mesh.setOrder(2)
    name = f"s3_leaf_hex20_{divs[0]}x{divs[1]}x{divs[2]}"
    path = _write(name, outdir)
    _count(name, path)
    _check_jacobians(name)
    gmsh.finalize()
    return {name: path}


def leaf_tet10(h: float, outdir: str) -> dict:
    """Unstructured tet10 leaf with characteristic length ``h`` (m)."""
    _init()
    _leaf_geometry()
    gmsh.option.setNumber("Mesh.MeshSizeMin", h)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.model.mesh.setOrder(2)
    name = "s3_leaf_tet10_h" + f"{h * 1000:.6g}".replace(".", "p")
    path = _write(name, outdir)
    _count(name, path)
    _check_jacobians(name)
    gmsh.finalize()
    return {name: path}


# --------------------------------------------------------------------------------------------
# S5 coil
# --------------------------------------------------------------------------------------------

def helix_length() -> float:
    """Exact length of the helix centre line: n sqrt((pi D)^2 + p^2)."""
    return TURNS * math.hypot(math.pi * COIL_D, PITCH)


def _coil_geometry() -> tuple[int, float]:
    """OCC swept wire with its named groups; returns (volume tag, centre-line length)."""
    r = COIL_D / 2
    occ = gmsh.model.occ
    n = TURNS * SPLINE_POINTS_PER_TURN
    pts = []
    for i in range(n + 1):
        t = 2 * math.pi * TURNS * i / n
        pts.append(occ.addPoint(r * math.cos(t), r * math.sin(t), PITCH * t / (2 * math.pi)))
    spine = occ.addSpline(pts)
    wire = occ.addWire([spine])
    # the disk at the start, normal to the helix tangent (0, R, p / 2 pi), x axis radial
    tangent = (0.0, r, PITCH / (2 * math.pi))
    disk = occ.addDisk(r, 0.0, 0.0, WIRE_D / 2, WIRE_D / 2, zAxis=list(tangent), xAxis=[1.0, 0.0, 0.0])
    out = occ.addPipe([(2, disk)], wire, "Frenet")
    occ.synchronize()
    vols = [t for d, t in out if d == 3]
    assert len(vols) == 1, out
    vol = vols[0]
    length = occ.getMass(1, spine)
    # remove the construction points, the spine and the profile from the model
    occ.remove([(2, disk)], recursive=True)
    occ.remove([(1, spine)], recursive=True)
    occ.remove([(0, p) for p in pts])
    occ.synchronize()
    faces = [t for _, t in gmsh.model.getBoundary([(3, vol)], oriented=False)]
    ends = {}
    lateral = []
    area_disk = math.pi * WIRE_D ** 2 / 4
    for s in faces:
        c = occ.getCenterOfMass(2, s)
        a = occ.getMass(2, s)
        if abs(a - area_disk) < 1e-3 * area_disk and abs(math.hypot(c[0], c[1]) - r) < 1e-6:
            at = {"end_bottom": 0.0, "end_top": TURNS * PITCH}
            key = next((k for k, z in at.items() if abs(c[2] - z) < 1e-6), None)
            assert key is not None, (s, c)
            ends[key] = s
        else:
            lateral.append(s)
    assert sorted(ends) == ["end_bottom", "end_top"], (ends, faces)
    for name in ("end_bottom", "end_top"):
        tag = gmsh.model.addPhysicalGroup(2, [ends[name]])
        gmsh.model.setPhysicalName(2, tag, name)
    tag = gmsh.model.addPhysicalGroup(2, lateral)
    gmsh.model.setPhysicalName(2, tag, "surface")
    tag = gmsh.model.addPhysicalGroup(3, [vol])
    gmsh.model.setPhysicalName(3, tag, "wire")
    return vol, length


def name_of_h(h: float) -> str:
    return "s5_coil_tet10_h" + f"{h * 1000:.6g}".replace(".", "p")


# Reference tet10 in gmsh's order: corners, then edges 0-1, 1-2, 2-0, 0-3, 2-3, 1-3.
TET10_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (2, 3), (1, 3))
Q_MIN = 0.1
STEP = 0.25


def _tet10_quality(conn: np.ndarray, xyz: np.ndarray, dn: np.ndarray) -> np.ndarray:
    """Per cell, min over the sample points of det J / det J of the straight (corner) tet."""
    x = xyz[conn]                                          # (ne, 10, 3)
    jac = np.einsum("eai,paj->epij", x, dn)
    det = np.linalg.det(jac)
    c = x[:, :4]
    lin = np.einsum("ei,ei->e", c[:, 1] - c[:, 0], np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 0]))
    return det.min(axis=1) / lin


def _untangle_curved_tets(name: str) -> None:
    """Make every curved tet10 valid, deterministically.

    Putting the midside nodes of boundary edges on the curved surface can turn a cell nearly or
    completely inside out near a corner (its det J at some node <= 0). For each cell whose
    quality q = min det J / det J(straight cell), over its nodes and the degree-2/4 rule points,
    is below Q_MIN, its midside nodes are moved a fraction STEP of the way back towards the
    straight edge midpoints; repeated until no cell is below Q_MIN. (gmsh's own high-order
    optimiser also repairs such cells, but its result differs from run to run.)
    """
    etype = 11
    etags, enodes = gmsh.model.mesh.getElementsByType(etype)
    ntags, coords, _ = gmsh.model.mesh.getNodes()
    index = np.zeros(int(ntags.max()) + 1, dtype=np.int64)
    index[ntags.astype(np.int64)] = np.arange(len(ntags))
    xyz = coords.reshape(-1, 3).copy()
    conn = index[enodes.astype(np.int64)].reshape(-1, 10)
    pts = list(gmsh.model.mesh.getElementProperties(etype)[4])
    for rule in ("Gauss2", "Gauss4"):
        pts += list(gmsh.model.mesh.getIntegrationPoints(etype, rule)[0])
    _, dn, _ = gmsh.model.mesh.getBasisFunctions(etype, pts, "GradLagrange")
    dn = np.asarray(dn).reshape(len(pts) // 3, 10, 3)
    moved = set()
    q0 = _tet10_quality(conn, xyz, dn)
    for it in range(20):
        q = _tet10_quality(conn, xyz, dn)
        bad = np.nonzero(q < Q_MIN)[0]
        if len(bad) == 0:
            break
        todo = {}
        for e in bad:
            for k, (a, b) in enumerate(TET10_EDGES):
                m = conn[e, 4 + k]
                todo[m] = 0.5 * (xyz[conn[e, a]] + xyz[conn[e, b]])
        for m in sorted(todo):
            xyz[m] += STEP * (todo[m] - xyz[m])
            moved.add(m)
    else:
        raise AssertionError(f"{name}: curved cells still below quality {Q_MIN}")
    for m in sorted(moved):
        gmsh.model.mesh.setNode(int(ntags[m]), xyz[m].tolist(), [])
    print(f"{'':34s} curved cells with q < {Q_MIN}: {int(np.sum(q0 < Q_MIN))} ({int(np.sum(q0 <= 0))} "
          f"inverted) -> 0 after {it} pass(es); {len(moved)} midside nodes moved; "
          f"min q {q.min():.3f}", flush=True)


def coil_tet10(h: float, outdir: str) -> dict:
    """Unstructured tet10 coil spring with characteristic length ``h`` (m), curved midside nodes."""
    _init()
    vol, length = _coil_geometry()
    vol_occ = gmsh.model.occ.getMass(3, vol)
    gmsh.option.setNumber("Mesh.MeshSizeMin", h)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)      # midside nodes on the geometry
    gmsh.model.mesh.setOrder(2)
    _untangle_curved_tets(name_of_h(h))
    name = name_of_h(h)
    path = _write(name, outdir)
    _count(name, path)
    _check_jacobians(name)
    vol_mesh = _mesh_volume()
    exact_l = helix_length()
    exact_v = math.pi * WIRE_D ** 2 / 4 * exact_l
    print(f"{'':34s} wire length: spline {length:.7f} m, helix n*sqrt((pi D)^2+p^2) = {exact_l:.7f} m")
    print(f"{'':34s} volume: OCC {vol_occ:.6e} m^3, mesh (tet10) {vol_mesh:.6e} m^3 "
          f"({(vol_mesh / vol_occ - 1) * 100:+.3f} %), pi d^2/4 L = {exact_v:.6e} m^3")
    print(f"{'':34s} mass at {STEEL_DENSITY:.0f} kg/m^3: OCC {vol_occ * STEEL_DENSITY * 1e3:.2f} g, "
          f"mesh {vol_mesh * STEEL_DENSITY * 1e3:.2f} g", flush=True)
    gmsh.finalize()
    return {name: path}


# --------------------------------------------------------------------------------------------
# checks
# --------------------------------------------------------------------------------------------

def _volume_cells():
    types, _, _ = gmsh.model.mesh.getElements(3)
    assert len(types) == 1, types
    return int(types[0])


def _check_jacobians(name: str) -> None:
    """Every volume cell must have det J > 0 at its nodes and at the points of the degree-2 and
    degree-4 rules (vibrofem's stiffness and mass rules; stresses are recovered at the nodes)."""
    etype = _volume_cells()
    _, _, _, npe, local, _ = gmsh.model.mesh.getElementProperties(etype)
    worst = math.inf
    for label, pts in (("nodes", list(local)),
                       ("Gauss2", list(gmsh.model.mesh.getIntegrationPoints(etype, "Gauss2")[0])),
                       ("Gauss4", list(gmsh.model.mesh.getIntegrationPoints(etype, "Gauss4")[0]))):
        _, det, _ = gmsh.model.mesh.getJacobians(etype, pts)
        det = np.asarray(det)
        if det.min() <= 0:
            raise AssertionError(f"{name}: non-positive Jacobian determinant {det.min():.3e} "
                                 f"at the {label}")
        worst = min(worst, det.min() / np.median(det))
    print(f"{'':34s} min det J / median over nodes and rule points: {worst:.3f}", flush=True)


def _mesh_volume() -> float:
    """Volume of the mesh integrated with the degree-4 rule (isoparametric cells)."""
    etype = _volume_cells()
    lc, w = gmsh.model.mesh.getIntegrationPoints(etype, "Gauss4")
    _, det, _ = gmsh.model.mesh.getJacobians(etype, lc)
    w = np.asarray(w)                     # gmsh's weights include the reference cell's measure
    det = np.asarray(det).reshape(-1, len(w))
    return float(np.sum(np.abs(det) @ w))


# --------------------------------------------------------------------------------------------

def jobs():
    """(name, callable(outdir)) for every committed spring mesh."""
    out = []
    for divs in ((10, 6, 1), (20, 12, 2), (40, 24, 4)):
        out.append((f"s3_leaf_hex20_{divs[0]}x{divs[1]}x{divs[2]}", lambda d, v=divs: leaf_hex20(v, d)))
    for h in (0.009, 0.006):
        out.append((f"s3_leaf_tet10_h{round(h * 1000)}", lambda d, h=h: leaf_tet10(h, d)))
    for h in (0.0025, 0.002):
        out.append((name_of_h(h), lambda d, h=h: coil_tet10(h, d)))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--outdir", default=HERE, help="output folder (default: meshes/)")
    ap.add_argument("--only", action="append", default=[], help="substring of a mesh name (repeatable)")
    ap.add_argument("--list", action="store_true", help="list the mesh names and exit")
    args = ap.parse_args(argv)
    os.makedirs(args.outdir, exist_ok=True)
    print(f"gmsh {gmsh.__version__}")
    for name, job in jobs():
        if args.list:
            print(name)
            continue
        if args.only and not any(s in name for s in args.only):
            continue
        job(args.outdir)
    return 0


if __name__ == "__main__":
    sys.exit(main())
