"""A gmsh part's modes shown with PyVista, off screen.

A steel bracket (a 200 × 120 × 10 mm plate with a hole) is meshed with gmsh's Python API in
second-order tetrahedra, clamped along one short edge, and its first elastic modes are drawn as
the mesh warped by each mode shape (PyVista renders off screen: EGL or OSMesa, no display needed).
Writes modes_gmsh_pyvista.png.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import gmsh
import numpy as np
import pyvista as pv

import vibrofem as vf
from _common import out_dir


def bracket(path: Path, size: float = 0.015) -> None:
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("bracket")
        occ = gmsh.model.occ
        plate = occ.addBox(0, 0, 0, 0.2, 0.12, 0.01)
        hole = occ.addCylinder(0.13, 0.06, 0, 0, 0, 0.01, 0.03)
        occ.cut([(3, plate)], [(3, hole)])
        occ.synchronize()
        vol = gmsh.model.getEntities(3)
        gmsh.model.addPhysicalGroup(3, [v[1] for v in vol], name="body")
        # The face at x = 0: the clamped edge.
        faces = gmsh.model.getEntitiesInBoundingBox(-1e-6, -1e-6, -1e-6, 1e-6, 0.12 + 1e-6, 0.01 + 1e-6, 2)
        gmsh.model.addPhysicalGroup(2, [f[1] for f in faces], name="clamp")
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def main() -> None:
    out = out_dir()
    with tempfile.TemporaryDirectory() as tmp:
        msh = Path(tmp) / "bracket.msh"
        bracket(msh)
        mesh = vf.read_mesh(msh)
    model = vf.Model(mesh, material=(2.1e11, 0.3, 7850.0), fix=["clamp"])
    modes = model.modes(4)
    assert modes.complete and modes.accurate, modes.notes
    print("frequencies (Hz):", np.round(modes.frequencies_hz, 2))
    grid = modes.to_pyvista()
    size = float(np.ptp(mesh.nodes, axis=0).max())
    pl = pv.Plotter(off_screen=True, shape=(2, 2), window_size=[1000, 760])
    for j in range(4):
        pl.subplot(j // 2, j % 2)
        u = modes.shapes[:, :3, j]
        factor = 0.15 * size / float(np.abs(u).max())
        warped = grid.warp_by_vector(f"mode_{j + 1}", factor=factor)
        warped["|u|"] = np.linalg.norm(u, axis=1)
        pl.add_mesh(warped, scalars="|u|", cmap="viridis", show_scalar_bar=False, show_edges=False)
        pl.add_mesh(grid, color="lightgrey", opacity=0.25)
        pl.add_text(f"mode {j + 1}: {modes.frequencies_hz[j]:.1f} Hz", font_size=11)
        pl.camera_position = "iso"
    png = out / "modes_gmsh_pyvista.png"
    pl.screenshot(str(png))
    pl.close()
    print("wrote", png)


if __name__ == "__main__":
    main()
