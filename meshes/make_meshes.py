#!/usr/bin/env python3
"""Generate the committed gmsh test meshes of vibrofem (``meshes/*.msh``).

Run from the crate root, with the validation venv (``bash validation/setup.sh``)::

    validation/.venv/bin/python meshes/make_meshes.py            # all meshes into meshes/
    validation/.venv/bin/python meshes/make_meshes.py --only s1_plate_hex20
    validation/.venv/bin/python meshes/make_meshes.py --list

Every mesh is a box ``[0, a] x [0, b] x [0, c]`` (origin at a corner), written as MSH 4.1 ASCII
(``Mesh.MshFileVersion=4.1``, ``Mesh.Binary=0``) unless the file name ends in ``_msh22`` (MSH 2.2
ASCII). Physical groups carry names: the volume group ``body`` and the six faces ``xmin``,
``xmax``, ``ymin``, ``ymax``, ``zmin``, ``zmax`` (surface groups; their elements are tri3/tri6 or
quad4/quad8/quad9 matching the volume cells). Coordinates are metres unless the name ends in ``_mm``.

Second-order nodes are in gmsh's own order (nothing is reordered) and lie exactly at the
edge/face/cell midpoints (``Mesh.SecondOrderLinear=1``; all geometry is straight-sided), so the
isoparametric tet10/hex20/hex27 spaces equal scikit-fem's P2/serendipity/Q2 spaces on the corner mesh.

Cases (see validation/skfem_modes.py for the reference results computed on them):

* S1 plate 0.3 x 0.3 x 0.02 m: ``s1_plate_tet4_hH`` / ``s1_plate_tet10_hH`` for H = 30, 20, 15 mm
  (characteristic length; the tet10 mesh is the tet4 mesh with midside nodes added), and structured
  ``s1_plate_{hex8,hex20,hex27}_{10x10x2,20x20x4}`` (transfinite + recombine; hex20 is
  ``Mesh.SecondOrderIncomplete=1``).
* S1 plate in millimetres: ``s1_plate_tet10_h30_mm`` (the h30 tet10 mesh, coordinates x1000), and
  the same h30 tet10 mesh again in MSH 2.2: ``s1_plate_tet10_h30_msh22``.
* S2 plate 0.9 x 0.4 x 0.116 m: ``s2_plate_tet10_h40`` and ``s2_plate_hex20_27x12x3``.
* ``cube_hex20_4x4x4``: free cube 0.1 m (triple eigenvalues).
* ``bar_hex20_15x2x2``: square bar 0.3 x 0.02 x 0.02 m, length along x (double eigenvalues).
* ``cantilever_hex20_40x2x2``: 0.2 x 0.01 x 0.01 m, length along x; clamp group ``xmin``.

Meshing is deterministic for a given gmsh version (one thread, fixed options); the committed
references in validation/reference were computed on the committed files, so re-running this
script is only needed to add or change meshes.
"""

from __future__ import annotations

import argparse
import os
import sys

import gmsh

HERE = os.path.dirname(os.path.abspath(__file__))

FACE_NAMES = ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")

S1 = (0.3, 0.3, 0.02)
S2 = (0.9, 0.4, 0.116)


def _init() -> None:
    if gmsh.isInitialized():
        gmsh.finalize()
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.option.setNumber("Mesh.SaveParametric", 0)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 1)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 6)      # Frontal-Delaunay 2D
    gmsh.option.setNumber("Mesh.Algorithm3D", 1)    # Delaunay 3D
    gmsh.model.add("box")


def _box_with_groups(dims: tuple[float, float, float]) -> int:
    """Add an OCC box at the origin and its named physical groups; return the volume tag."""
    a, b, c = dims
    vol = gmsh.model.occ.addBox(0.0, 0.0, 0.0, a, b, c)
    gmsh.model.occ.synchronize()
    found = {}
    for _, s in gmsh.model.getEntities(2):
        centre = gmsh.model.occ.getCenterOfMass(2, s)
        for axis, name in enumerate("xyz"):
            for side, value in (("min", 0.0), ("max", dims[axis])):
                if abs(centre[axis] - value) < 1e-9 * max(dims):
                    found[name + side] = s
    assert sorted(found) == sorted(FACE_NAMES), found
    for name in FACE_NAMES:
        tag = gmsh.model.addPhysicalGroup(2, [found[name]])
        gmsh.model.setPhysicalName(2, tag, name)
    tag = gmsh.model.addPhysicalGroup(3, [vol])
    gmsh.model.setPhysicalName(3, tag, "body")
    return vol


def _write(name: str, outdir: str, version: float = 4.1) -> str:
    path = os.path.join(outdir, name + ".msh")
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.write(path)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    return path


def _count(name: str, path: str) -> None:
    tags, _, _ = gmsh.model.mesh.getNodes()
    types, etags, _ = gmsh.model.mesh.getElements(3)
    ne = sum(len(t) for t in etags)
    kinds = [gmsh.model.mesh.getElementProperties(t)[0] for t in types]
    size = os.path.getsize(path) / 1e6
    print(f"{name:34s} nodes {len(tags):7d}  dofs {3 * len(tags):7d}  cells {ne:7d} "
          f"{'/'.join(kinds):14s} {size:6.2f} MB", flush=True)


def tet_box(base: str, dims, h: float, outdir: str, orders=(1, 2), extra_tet10=()) -> dict:
    """Unstructured tetrahedral mesh of a box with characteristic length ``h`` (metres).

    Writes ``{base}_tet4_h{H}`` (if 1 in orders) and ``{base}_tet10_h{H}`` (if 2 in orders), H = h
    in mm; the tet10 mesh is the same tet4 mesh elevated to order 2. ``extra_tet10`` may hold
    ``"mm"`` (coordinates x1000, suffix ``_mm``) and ``"msh22"`` (MSH 2.2 copy, suffix ``_msh22``).
    Returns {name: path}.
    """
    _init()
    _box_with_groups(dims)
    gmsh.option.setNumber("Mesh.MeshSizeMin", h)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.model.mesh.generate(3)
    written = {}
    hmm = "h" + f"{h * 1000:.6g}".replace(".", "p")   # h in mm: h30, h28p2
    if 1 in orders:
        name = f"{base}_tet4_{hmm}"
        written[name] = _write(name, outdir)
        _count(name, written[name])
    if 2 in orders:
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
        gmsh.model.mesh.setOrder(2)
        name = f"{base}_tet10_{hmm}"
        written[name] = _write(name, outdir)
        _count(name, written[name])
        if "msh22" in extra_tet10:
            n22 = name + "_msh22"
            written[n22] = _write(n22, outdir, version=2.2)
            _count(n22, written[n22])
        if "mm" in extra_tet10:
            gmsh.model.mesh.affineTransform([1000.0, 0, 0, 0, 0, 1000.0, 0, 0, 0, 0, 1000.0, 0])
            nmm = name + "_mm"
            written[nmm] = _write(nmm, outdir)
            _count(nmm, written[nmm])
    gmsh.finalize()
    return written


def hex_box(base: str, dims, divs, kind: str, outdir: str) -> dict:
    """Structured hexahedral mesh (transfinite + recombine) of a box, ``divs`` cells per axis.

    kind is ``hex8``, ``hex20`` (incomplete second order) or ``hex27``. Writes
    ``{base}_{kind}_{nx}x{ny}x{nz}``.
    """
    _init()
    vol = _box_with_groups(dims)
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
    if kind in ("hex20", "hex27"):
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1 if kind == "hex20" else 0)
        gmsh.model.mesh.setOrder(2)
    name = f"{base}_{kind}_{divs[0]}x{divs[1]}x{divs[2]}"
    path = _write(name, outdir)
    _count(name, path)
    gmsh.finalize()
    return {name: path}


def jobs():
    """(name prefix, callable(outdir)) for every committed mesh family."""
    out = []
    for h, extra in ((0.030, ("mm", "msh22")), (0.020, ()), (0.015, ())):
        out.append((f"s1_plate_tet_h{round(h * 1000)}",
                    lambda d, h=h, extra=extra: tet_box("s1_plate", S1, h, d, extra_tet10=extra)))
    for kind in ("hex8", "hex20", "hex27"):
        for divs in ((10, 10, 2), (20, 20, 4)):
            out.append((f"s1_plate_{kind}_{divs[0]}x{divs[1]}x{divs[2]}",
                        lambda d, k=kind, v=divs: hex_box("s1_plate", S1, v, k, d)))
    out.append(("s2_plate_tet10_h40", lambda d: tet_box("s2_plate", S2, 0.040, d, orders=(2,))))
    out.append(("s2_plate_hex20_27x12x3", lambda d: hex_box("s2_plate", S2, (27, 12, 3), "hex20", d)))
    out.append(("cube_hex20_4x4x4", lambda d: hex_box("cube", (0.1, 0.1, 0.1), (4, 4, 4), "hex20", d)))
    out.append(("bar_hex20_15x2x2", lambda d: hex_box("bar", (0.3, 0.02, 0.02), (15, 2, 2), "hex20", d)))
    out.append(("cantilever_hex20_40x2x2",
                lambda d: hex_box("cantilever", (0.2, 0.01, 0.01), (40, 2, 2), "hex20", d)))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--outdir", default=HERE, help="output folder (default: meshes/)")
    ap.add_argument("--only", action="append", default=[],
                    help="substring of a job name to run (repeatable)")
    ap.add_argument("--list", action="store_true", help="list job names and exit")
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
