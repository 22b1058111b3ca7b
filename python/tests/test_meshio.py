"""Meshes and results handed to meshio and PyVista, and meshio meshes given to ``vf.Model``.

The reference for the node order inside quadratic cells is independent of vibrofem: meshio's own
gmsh reader on the same .msh file (gmsh's order permuted to VTK's by meshio), and VTK's cell volumes
(a quadratic cell read in a wrong node order has a wrong volume).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Dict, List

import numpy as np
import numpy.typing as npt
import pytest

import vibrofem as vf

meshio = pytest.importorskip("meshio")

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FILES = [
    "s1_plate_tet10_h30.msh",
    "s1_plate_hex20_10x10x2.msh",
    "s1_plate_hex27_10x10x2.msh",
    "s1_plate_tet10_h30_msh22.msh",
]


def cells_by_type(m: Any) -> Dict[str, npt.NDArray[np.float64]]:
    """{meshio type: the cells' node coordinates, c × k × 3, rows sorted}: blocks of one type
    merged, comparable between meshes whose node numbering differs."""
    out: Dict[str, List[npt.NDArray[np.float64]]] = {}
    for b in m.cells:
        out.setdefault(b.type, []).append(np.asarray(m.points)[np.asarray(b.data)])
    res = {}
    for t, parts in out.items():
        x = np.concatenate(parts, axis=0)
        flat = np.round(x.reshape(len(x), -1), 12)
        res[t] = x[np.lexsort(flat.T[::-1])]
    return res


def set_centroids(m: Any, name: str) -> npt.NDArray[np.float64]:
    """Sorted centroids of the cells of a cell set."""
    cs = []
    for b, idx in zip(m.cells, m.cell_sets[name]):
        if idx is not None and len(idx):
            cs.append(np.asarray(m.points)[np.asarray(b.data)[np.asarray(idx)]].mean(axis=1))
    c = np.round(np.concatenate(cs, axis=0), 12)
    return np.asarray(c[np.lexsort(c.T[::-1])], dtype=np.float64)


@pytest.mark.parametrize("name", FILES)
def test_to_meshio_equals_meshios_own_gmsh_reader(name: str) -> None:
    path = os.path.join(ROOT, "meshes", name)
    ours = vf.read_mesh(path).to_meshio()
    ref = meshio.read(path)
    a, b = cells_by_type(ours), cells_by_type(ref)
    assert sorted(a) == sorted(b)
    for t in a:
        # The same cells with the same node order (coordinates of each cell's nodes, in order).
        assert a[t].shape == b[t].shape, t
        assert np.array_equal(a[t], b[t]), t
    # Groups: meshio's MSH 4.1 reader gives cell sets, its MSH 2.2 reader only field_data.
    assert {g: list(v) for g, v in ours.field_data.items()} == {g: list(v) for g, v in ref.field_data.items()}
    groups = [k for k in ref.cell_sets if not k.startswith("gmsh:")]
    for g in groups:
        assert np.array_equal(set_centroids(ours, g), set_centroids(ref, g)), g


@pytest.mark.parametrize(
    "spec, volume",
    [
        ("box:0.3,0.05,0.02:6,2,2:hex20", 0.3 * 0.05 * 0.02),
        ("box:0.3,0.05,0.02:6,2,2:hex27", 0.3 * 0.05 * 0.02),
        ("box:0.3,0.05,0.02:6,2,2:tet10", 0.3 * 0.05 * 0.02),
        ("box:0.3,0.05,0.02:6,2,2:wedge15", 0.3 * 0.05 * 0.02),
    ],
)
def test_pyvista_cell_volumes_add_up_to_the_box(spec: str, volume: float) -> None:
    pv = pytest.importorskip("pyvista")
    try:
        mesh = vf.read_mesh(spec)
    except vf.InputError:
        pytest.skip(f"the generator makes no {spec.rsplit(':', 1)[1]}")
    grid = mesh.to_pyvista()
    solid = grid.extract_cells_by_type([pv.CellType.QUADRATIC_HEXAHEDRON, pv.CellType.TRIQUADRATIC_HEXAHEDRON,
                                        pv.CellType.QUADRATIC_TETRA, pv.CellType.QUADRATIC_WEDGE])
    sizes = solid.compute_cell_sizes(length=False, area=False, volume=True)
    v = np.asarray(sizes.cell_data["Volume"])
    # A quadratic cell whose nodes are in a wrong order has mid-edge nodes in the wrong places:
    # its VTK volume is no longer its share of the box (the box's cells are straight-sided). Given
    # in gmsh's order, the hex20 box's VTK volume sums to −0.27 × the box; VTK's cell-size filter
    # itself is within 4e-8 of the exact volume here, hence 1e-6.
    assert len(v) == sum(n for k, n in mesh.cell_kinds.items() if k[-2:] in ("10", "20", "27", "15"))
    assert np.all(v > 0)
    assert v.sum() == pytest.approx(volume, rel=1e-6)


@pytest.mark.parametrize("name", FILES)
def test_a_meshio_mesh_makes_the_same_model(name: str) -> None:
    path = os.path.join(ROOT, "meshes", name)
    direct = vf.read_mesh(path)
    via = vf.from_meshio(meshio.read(path))
    # meshio numbers the nodes as the file does; the cells, groups and matrices must agree.
    a, b = cells_by_type(via.to_meshio()), cells_by_type(direct.to_meshio())
    assert sorted(a) == sorted(b) and all(np.array_equal(a[t], b[t]) for t in a)
    assert {g: (d["dim"], d["cells"], d["nodes"]) for g, d in via.groups.items()} == {
        g: (d["dim"], d["cells"], d["nodes"]) for g, d in direct.groups.items()
    }
    kw: Dict[str, Any] = dict(material=(2.1e11, 0.3, 7850.0))
    m1, m2 = vf.Model(direct, **kw), vf.Model(meshio.read(path), **kw)
    assert m1.mass == pytest.approx(m2.mass, rel=1e-13)
    f1 = m1.modes(8).frequencies_hz
    f2 = m2.modes(8).frequencies_hz
    assert np.allclose(f1[6:], f2[6:], rtol=1e-10), (f1, f2)


def test_round_trip_through_meshio_is_exact() -> None:
    mesh = vf.read_mesh(os.path.join(ROOT, "meshes", "s1_plate_hex20_10x10x2.msh"))
    back = vf.from_meshio(mesh.to_meshio())
    assert np.array_equal(back.nodes, mesh.nodes)
    assert back.cell_kinds == mesh.cell_kinds
    for k in mesh.cell_kinds:
        assert np.array_equal(back.cells(k), mesh.cells(k)), k
    assert back.groups == mesh.groups
    for g in mesh.groups:
        assert np.array_equal(back.group_nodes(g), mesh.group_nodes(g))


def test_groups_come_back_from_gmsh_physical_cell_data(tmp_path: Path) -> None:
    """Files that keep no cell sets, only cell data: meshio's MSH 2.2 (groups named by its
    field_data) and VTU (no field_data read back: unnamed groups are "dim:tag", as read_mesh
    names them)."""
    mesh = vf.read_mesh("box:0.3,0.05,0.02:6,2,2:hex20")
    m = mesh.to_meshio()
    m.cell_sets = {}
    meshio.write(tmp_path / "bar.msh", m, file_format="gmsh22", binary=False)
    meshio.write(tmp_path / "bar.vtu", m)
    ref = vf.Model(mesh, fix=["xmin"])
    K2, M2 = ref.assemble()
    xmin = mesh.groups["xmin"]
    for f, name in (("bar.msh", "xmin"), ("bar.vtu", f"{xmin['dim']}:{xmin['tag']}")):
        back = meshio.read(tmp_path / f)
        assert not [k for k in back.cell_sets if not k.startswith("gmsh:")]
        model = vf.Model(back, fix=[name])
        assert model.mesh.group_nodes(name).tolist() == mesh.group_nodes("xmin").tolist(), f
        K1, M1 = model.assemble()
        assert abs(K1 - K2).max() == 0.0 and abs(M1 - M2).max() == 0.0, f


def test_results_as_point_arrays() -> None:
    mesh = vf.read_mesh("box:0.3,0.05,0.02:12,2,2:hex20")
    model = vf.Model(mesh, fix=["xmin"], couple={"xmax": "z"})
    modes = model.modes(4)
    m = modes.to_meshio()
    for j in range(4):
        assert np.array_equal(m.point_data[f"mode_{j + 1}"], modes.shapes[:, :3, j])
    assert np.array_equal(m.field_data["frequencies_hz"], modes.frequencies_hz)
    assert m.field_data["complete"][0] == 1 and m.field_data["accurate"][0] == 1
    st = model.static(force={"xmax": (0, 0, 1000)})
    ms = st.to_meshio()
    assert np.array_equal(ms.point_data["displacement"], st.displacement[:, :3])
    assert np.array_equal(ms.point_data["von_mises"], st.von_mises)
    assert ms.field_data["stiffness:xmax"][0] == st.stiffness["xmax"]
    h = model.harmonic(force={"xmax": (0, 0, 10)}, sweep=(20.0, 200.0, 3), damping=0.02)
    mh = h.to_meshio()
    assert np.array_equal(mh.point_data["real_2"], h.displacement[1].real)
    assert np.array_equal(mh.field_data["frequencies_hz"], h.frequencies_hz)
    pv = pytest.importorskip("pyvista")
    grid = modes.to_pyvista()
    assert isinstance(grid, pv.UnstructuredGrid) and grid.n_points == len(mesh.nodes)
    warped = grid.warp_by_vector("mode_1", factor=0.01)
    assert np.allclose(warped.points, grid.points + 0.01 * modes.shapes[:, :3, 0])


def test_bad_meshio_meshes_are_refused_with_the_place() -> None:
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=float)
    with pytest.raises(vf.InputError, match="pyramid"):
        vf.from_meshio(meshio.Mesh(pts, [("pyramid", np.array([[0, 1, 4, 2, 3]]))]))
    with pytest.raises(vf.InputError, match="node index 9"):
        vf.from_meshio(meshio.Mesh(pts, [("tetra", np.array([[0, 1, 2, 9]]))]))
    with pytest.raises(vf.InputError, match="'mixed'.*dimensions"):
        vf.from_meshio(meshio.Mesh(pts, [("tetra", np.array([[0, 1, 2, 3]])), ("triangle", np.array([[0, 1, 2]]))],
                                   cell_sets={"mixed": [np.array([0]), np.array([0])]}))
    with pytest.raises(TypeError, match="Model"):
        vf.Model(42)


def test_from_arrays_makes_a_tet() -> None:
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    mesh = vf.Mesh.from_arrays(pts, {"tet4": [[0, 1, 2, 3]], "tri3": [[0, 1, 2]]}, groups={"base": {"tri3": [0]}})
    assert mesh.groups["base"] == {"dim": 2, "tag": 1, "cells": 1, "nodes": 3}
    # A unit right tetrahedron: volume 1/6.
    assert vf.Model(mesh, material=(1.0, 0.3, 6.0)).mass == pytest.approx(1.0, rel=1e-14)
    with pytest.raises(vf.InputError, match="group 'base'"):
        vf.Mesh.from_arrays(pts, {"tet4": [[0, 1, 2, 3]]}, groups={"base": {"tri3": [0]}})
    with pytest.raises(vf.InputError, match="tet4 cells have 4 nodes"):
        vf.Mesh.from_arrays(pts, {"tet4": [[0, 1, 2]]})


def test_a_pyvista_grid_makes_the_same_model() -> None:
    # A PyVista grid has points and cells too (other meanings): it was taken for a meshio mesh
    # and failed with an AttributeError. It goes through pyvista.to_meshio now.
    pytest.importorskip("pyvista")
    mesh = vf.read_mesh("box:0.3,0.05,0.02:6,2,2:hex20")
    kw: Dict[str, Any] = dict(material=(2.1e11, 0.3, 7850.0))
    direct, via = vf.Model(mesh, **kw), vf.Model(mesh.to_pyvista(), **kw)
    assert via.mass == pytest.approx(direct.mass, rel=1e-13)
    f1, f2 = direct.modes(8).frequencies_hz, via.modes(8).frequencies_hz
    assert np.allclose(f1[6:], f2[6:], rtol=1e-10), (f1, f2)
    for bad in (5, None):
        with pytest.raises(TypeError, match="meshio"):
            vf.from_meshio(bad)


def test_from_arrays_refuses_what_it_cannot_read_exactly() -> None:
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    # Non-integer indices were cast (0.5 → 0) without a word.
    with pytest.raises(vf.InputError, match="whole numbers"):
        vf.Mesh.from_arrays(pts, {"tet4": [[0.5, 1, 2, 3]]})
    with pytest.raises(vf.InputError, match="whole numbers"):
        vf.Mesh.from_arrays(pts, {"tet4": [[0, 1, 2, 3]], "tri3": [[0, 1, 2]]}, groups={"b": {"tri3": [0.7]}})
    # Whole floats are indices.
    assert vf.Mesh.from_arrays(pts, {"tet4": np.array([[0.0, 1.0, 2.0, 3.0]])}).cell_kinds == {"tet4": 1}
    with pytest.raises(vf.InputError, match="n × 3"):
        vf.Mesh.from_arrays(pts.ravel(), {"tet4": [[0, 1, 2, 3]]})
    with pytest.raises(vf.InputError, match="groups must be a dict"):
        vf.Mesh.from_arrays(pts, {"tet4": [[0, 1, 2, 3]]}, groups=[0])  # type: ignore[arg-type]
    with pytest.raises(vf.InputError, match="out of range"):
        vf.Mesh.from_arrays(pts, {"tet4": np.array([[0, 1, 2, 2**63]], dtype=np.uint64)})
