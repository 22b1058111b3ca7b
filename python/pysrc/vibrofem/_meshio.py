"""Conversions between vibrofem meshes and results and meshio / PyVista.

vibrofem keeps gmsh's node order inside a cell; meshio (and VTK, hence PyVista) use VTK's, which
differs for tet10, hex20, hex27 and wedge15. The permutations below are those of gmsh's and VTK's
node-ordering documentation (the same as meshio's own gmsh reader uses; python/tests/test_meshio.py
checks a converted mesh against meshio reading the same .msh file).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    import meshio
    import pyvista

    from . import Mesh

#: vibrofem cell kind → meshio cell type.
KIND_TO_MESHIO: Dict[str, str] = {
    "point1": "vertex",
    "line2": "line",
    "line3": "line3",
    "tri3": "triangle",
    "tri6": "triangle6",
    "quad4": "quad",
    "quad8": "quad8",
    "quad9": "quad9",
    "tet4": "tetra",
    "tet10": "tetra10",
    "hex8": "hexahedron",
    "hex20": "hexahedron20",
    "hex27": "hexahedron27",
    "wedge6": "wedge",
    "wedge15": "wedge15",
}
MESHIO_TO_KIND: Dict[str, str] = {v: k for k, v in KIND_TO_MESHIO.items()}

# meshio_cell = gmsh_cell[:, GMSH_TO_VTK[kind]] (kinds not listed share the order).
GMSH_TO_VTK: Dict[str, List[int]] = {
    "tet10": [0, 1, 2, 3, 4, 5, 6, 7, 9, 8],
    "hex20": [0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15],
    "hex27": [0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15, 22, 23, 21, 24, 20, 25, 26],
    "wedge15": [0, 1, 2, 3, 4, 5, 6, 9, 7, 12, 14, 13, 8, 10, 11],
}
VTK_TO_GMSH: Dict[str, List[int]] = {k: [int(i) for i in np.argsort(p)] for k, p in GMSH_TO_VTK.items()}

_SCALE = {"m": 1.0, "cm": 0.01, "mm": 0.001}


def _require_meshio() -> Any:
    try:
        import meshio
        import meshio._mesh
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("to_meshio()/from_meshio() need meshio: pip install meshio") from e
    # meshio 5.3.5 lacks wedge15 in its table of cell dimensions, so it can neither build nor
    # read a mesh with them (its issues #1247 and #1505; its VTK/VTU writers know the type).
    meshio._mesh.topological_dimension.setdefault("wedge15", 3)
    return meshio


def mesh_to_meshio(mesh: "Mesh") -> "meshio.Mesh":
    """The mesh as a ``meshio.Mesh``: one cell block per kind (VTK node order), the groups as
    ``cell_sets`` and as gmsh's ``gmsh:physical`` cell data with ``field_data`` {name: [tag, dim]}
    (so ``meshio.write("x.msh", m, file_format="gmsh22")`` keeps them; for ``.msh`` meshio
    otherwise picks ANSYS, and its MSH 4.1 writer asks for ``gmsh:dim_tags``)."""
    meshio = _require_meshio()
    kinds = list(mesh.cell_kinds)
    cells = []
    for kind in kinds:
        conn = np.array(mesh.cells(kind), dtype=np.int64)
        if kind in GMSH_TO_VTK:
            conn = conn[:, GMSH_TO_VTK[kind]]
        cells.append((KIND_TO_MESHIO[kind], conn))
    physical = [np.zeros(mesh.cell_kinds[k], dtype=np.int64) for k in kinds]
    cell_sets: Dict[str, List[np.ndarray]] = {}
    field_data: Dict[str, np.ndarray] = {}
    for name, dim, tag, parts in mesh._core.group_cells:
        per_block = [np.zeros(0, dtype=np.int64) for _ in kinds]
        for kind, idx in parts:
            b = kinds.index(kind)
            per_block[b] = np.asarray(idx, dtype=np.int64)
            physical[b][per_block[b]] = tag
        key = name if name not in cell_sets else f"{name}:{dim}"
        cell_sets[key] = per_block
        field_data[key] = np.array([tag, dim])
    return meshio.Mesh(
        np.array(mesh.nodes, dtype=float),  # the caller's own (writeable) copy
        cells,
        # No geometrical entities: each group's tag stands for its entity (meshio's gmsh writer
        # wants both).
        cell_data={"gmsh:physical": physical, "gmsh:geometrical": [p.copy() for p in physical]},
        cell_sets=cell_sets,
        field_data=field_data,
    )


def _meshio_blocks(m: "meshio.Mesh") -> Tuple[List[Tuple[str, np.ndarray]], List[Tuple[int, int]]]:
    """meshio's cell blocks merged per vibrofem kind (gmsh node order); for each meshio block,
    (vibrofem block, offset of its first cell there)."""
    order: List[str] = []
    parts: Dict[str, List[np.ndarray]] = {}
    where: List[Tuple[int, int]] = []
    for i, block in enumerate(m.cells):
        kind = MESHIO_TO_KIND.get(block.type)
        if kind is None:
            known = ", ".join(sorted(MESHIO_TO_KIND))
            raise _input_error(f"meshio cell block {i}: cell type '{block.type}' is not one vibrofem reads ({known})")
        conn = np.asarray(block.data, dtype=np.int64).reshape(len(block.data), -1)
        if kind in VTK_TO_GMSH:
            conn = conn[:, VTK_TO_GMSH[kind]]
        if kind not in parts:
            order.append(kind)
            parts[kind] = []
        offset = sum(len(p) for p in parts[kind])
        parts[kind].append(conn)
        where.append((order.index(kind), offset))
    return [(k, np.concatenate(parts[k], axis=0)) for k in order], where


def _dim_of(kind: str) -> int:
    if kind == "point1":
        return 0
    if kind.startswith("line"):
        return 1
    if kind.startswith(("tri", "quad")):
        return 2
    return 3


GroupSpec = Tuple[str, int, int, List[Tuple[int, List[int]]]]


def _groups_from_sets(m: "meshio.Mesh", blocks: Sequence[Tuple[str, np.ndarray]], where: Sequence[Tuple[int, int]]) -> List[GroupSpec]:
    groups: List[GroupSpec] = []
    sets = {k: v for k, v in m.cell_sets.items() if not k.startswith("gmsh:")}
    for n, (name, per_block) in enumerate(sets.items()):
        by_block: Dict[int, List[int]] = {}
        for i, idx in enumerate(per_block):
            if idx is None or len(idx) == 0:
                continue
            if i >= len(where):
                raise _input_error(f"cell set '{name}': {len(per_block)} parts for {len(m.cells)} cell blocks")
            b, off = where[i]
            by_block.setdefault(b, []).extend(int(off + j) for j in np.asarray(idx).ravel())
        dims = {_dim_of(blocks[b][0]) for b in by_block}
        if len(dims) > 1:
            raise _input_error(f"cell set '{name}' mixes cells of dimensions {sorted(dims)}: give one dimension per group")
        fd = m.field_data.get(name)
        tag = int(fd[0]) if fd is not None and len(fd) >= 1 else n + 1
        dim = dims.pop() if dims else (int(fd[1]) if fd is not None and len(fd) >= 2 else 3)
        groups.append((str(name), dim, tag, sorted(by_block.items())))
    return groups


def _groups_from_physical(m: "meshio.Mesh", blocks: Sequence[Tuple[str, np.ndarray]], where: Sequence[Tuple[int, int]]) -> List[GroupSpec]:
    names = {(int(v[0]), int(v[1])): k for k, v in m.field_data.items() if len(v) >= 2}
    found: Dict[Tuple[int, int], Dict[int, List[int]]] = {}
    for i, tags in enumerate(m.cell_data["gmsh:physical"]):
        b, off = where[i]
        dim = _dim_of(blocks[b][0])
        for j, t in enumerate(np.asarray(tags).ravel()):
            if int(t) > 0:
                found.setdefault((int(t), dim), {}).setdefault(b, []).append(off + j)
    return [(names.get(key, f"{key[1]}:{key[0]}"), key[1], key[0], sorted(v.items())) for key, v in sorted(found.items(), key=lambda kv: (kv[0][1], kv[0][0]))]


def _input_error(msg: str) -> Exception:
    from . import InputError

    return InputError(msg)


def mesh_from_meshio(m: "meshio.Mesh", length_unit: str = "m", source: Optional[str] = None) -> "Mesh":
    """A vibrofem mesh from a ``meshio.Mesh``: cell blocks merged per kind, groups from its
    ``cell_sets`` (any but meshio's ``gmsh:*`` sets) or, without those, from the
    ``gmsh:physical`` cell data, named by ``field_data`` (``"dim:tag"`` when unnamed, as
    :func:`read_mesh` names them). Coordinates are scaled from ``length_unit`` to metres."""
    from . import Mesh, _core

    if is_pyvista(m):
        m = from_pyvista(m)
    if not (hasattr(m, "points") and hasattr(m, "cells") and hasattr(m, "cell_sets")):
        raise TypeError(f"from_meshio: expected a meshio.Mesh (or a PyVista grid), got {type(m).__name__}")
    if length_unit not in _SCALE:
        raise _input_error(f"unknown unit '{length_unit}' (m, cm or mm)")
    pts = np.asarray(m.points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3):
        raise _input_error(f"meshio points: expected n × 2 or n × 3 coordinates, got shape {pts.shape}")
    if pts.shape[1] == 2:
        pts = np.column_stack([pts, np.zeros(len(pts))])
    pts = np.ascontiguousarray(pts * _SCALE[length_unit])
    blocks, where = _meshio_blocks(m)
    has_sets = any(not k.startswith("gmsh:") for k in m.cell_sets)
    if has_sets:
        groups = _groups_from_sets(m, blocks, where)
    elif "gmsh:physical" in m.cell_data:
        groups = _groups_from_physical(m, blocks, where)
    else:
        groups = []
    core = _core.mesh_from_arrays(
        pts,
        [(k, np.ascontiguousarray(c)) for k, c in blocks],
        groups,
        source or "<meshio>",
    )
    return Mesh(core)


def is_pyvista(obj: Any) -> bool:
    """Whether ``obj`` is a PyVista dataset (which has ``points`` and ``cells`` too, with other
    meanings than meshio's)."""
    return type(obj).__module__.split(".")[0] == "pyvista"


def from_pyvista(grid: Any) -> "meshio.Mesh":
    """A PyVista grid as a meshio mesh (``pyvista.to_meshio``; its cell data, such as
    ``gmsh:physical``, comes along, so groups do where the grid carries them)."""
    import pyvista

    if not hasattr(grid, "celltypes"):
        grid = grid.cast_to_unstructured_grid()
    return pyvista.to_meshio(grid)


#: meshio cell type → VTK cell type id.
VTK_TYPE: Dict[str, int] = {
    "vertex": 1,
    "line": 3,
    "triangle": 5,
    "quad": 9,
    "tetra": 10,
    "hexahedron": 12,
    "wedge": 13,
    "line3": 21,
    "triangle6": 22,
    "quad8": 23,
    "tetra10": 24,
    "hexahedron20": 25,
    "wedge15": 26,
    "quad9": 28,
    "hexahedron27": 29,
}


def to_pyvista(m: "meshio.Mesh") -> "pyvista.UnstructuredGrid":
    """A meshio mesh of vibrofem's as a PyVista grid, coordinates kept in double precision
    (``pyvista.from_meshio`` would store them as float32); point data and field data copied."""
    try:
        import pyvista
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("to_pyvista() needs PyVista: pip install pyvista") from e
    cells = []
    types = []
    for b in m.cells:
        conn = np.asarray(b.data, dtype=np.int64)
        k = conn.shape[1]
        cells.append(np.column_stack([np.full(len(conn), k, dtype=np.int64), conn]).ravel())
        types.append(np.full(len(conn), VTK_TYPE[b.type], dtype=np.uint8))
    grid = pyvista.UnstructuredGrid(
        np.concatenate(cells) if cells else np.zeros(0, dtype=np.int64),
        np.concatenate(types) if types else np.zeros(0, dtype=np.uint8),
        np.asarray(m.points, dtype=np.float64),
    )
    for name, v in m.point_data.items():
        grid.point_data[name] = np.asarray(v)
    for name, v in m.field_data.items():
        grid.field_data[name] = np.asarray(v)
    return grid


def modes_to_meshio(modes: Any, mesh: "Mesh") -> "meshio.Mesh":
    m = mesh_to_meshio(mesh)
    k = modes.shapes.shape[2]
    for j in range(k):
        m.point_data[f"mode_{j + 1}"] = np.ascontiguousarray(modes.shapes[:, :3, j])
        rot = modes.shapes[:, 3:6, j]
        if np.any(rot != 0.0):
            m.point_data[f"mode_{j + 1}_rotation"] = np.ascontiguousarray(rot)
    m.field_data["frequencies_hz"] = np.asarray(modes.frequencies_hz, dtype=float)
    m.field_data["rigid"] = np.array([kind == "rigid" for kind in modes.kinds], dtype=np.int64)
    m.field_data["rel_residuals"] = np.asarray(modes.residuals, dtype=float)
    m.field_data["complete"] = np.array([int(modes.complete)])
    m.field_data["accurate"] = np.array([int(modes.accurate)])
    return m


def static_to_meshio(st: Any, mesh: "Mesh") -> "meshio.Mesh":
    m = mesh_to_meshio(mesh)
    u = np.asarray(st.displacement)
    m.point_data["displacement"] = np.ascontiguousarray(u[:, :3])
    if np.any(u[:, 3:6] != 0.0):
        m.point_data["rotation"] = np.ascontiguousarray(u[:, 3:6])
    m.point_data["von_mises"] = np.asarray(st.von_mises, dtype=float)
    for g, k in st.stiffness.items():
        m.field_data[f"stiffness:{g}"] = np.array([float(k)])
    return m


def harmonic_to_meshio(h: Any, mesh: "Mesh") -> "meshio.Mesh":
    m = mesh_to_meshio(mesh)
    u = np.asarray(h.displacement)
    for j in range(u.shape[0]):
        m.point_data[f"real_{j + 1}"] = np.ascontiguousarray(u[j].real)
        m.point_data[f"imag_{j + 1}"] = np.ascontiguousarray(u[j].imag)
        m.point_data[f"amplitude_{j + 1}"] = np.linalg.norm(np.abs(u[j]), axis=1)
    m.field_data["frequencies_hz"] = np.asarray(h.frequencies_hz, dtype=float)
    return m
