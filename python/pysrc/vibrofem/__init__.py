"""vibrofem: finite-element modal and stiffness analysis for vibrating machines, from Python.

numpy and scipy native::

    import vibrofem as vf
    mesh = vf.read_mesh("plate.msh", length_unit="mm")     # or "box:0.3,0.3,0.02:10,10,2:hex20"
    model = vf.Model(mesh, material=(2.1e11, 0.3, 7850), fix=["clamp"])
    K, M = model.assemble()             # scipy.sparse.csr_array over the free DOFs
    model.dofs.node, model.dofs.component   # the node and component of each row
    modes = model.modes(12)             # .frequencies_hz, .shapes (n_nodes × 6 × k), .complete …
    st = model.static(force={"top": (0, 0, 1000)})   # .displacement, .reactions, .von_mises …
    vf.run_scene("scenes/s3_leaf_stiffness.toml")     # the scene report as a dict
    modes.to_meshio(), modes.to_pyvista()             # point arrays per mode, for meshio/PyVista
    vf.Model(meshio.read("part.vtu"), fix=["base"])   # a meshio mesh, its cell sets as groups
    vf.design().data["checks"]                        # the application's reports (vibrofem design)

Units are SI throughout (m, kg, s, N, Pa); a mesh drawn in millimetres is scaled on reading.
Model options take the command line's grammar as strings, or Python values:

============== ============================================ =====================================
keyword        Python value                                 command line
============== ============================================ =====================================
material       ``"steel"`` or ``(E, nu, rho)``              ``--material``
group_material ``{"web": (E, nu, rho)}``                    ``--group-material web=E,NU,RHO``
fix            ``["clamp"]``, ``{"base": "ux,uy"}``          ``--fix clamp``, ``--fix base:ux,uy``
couple         ``["top"]``, ``{"top": "z"}`` (guided along  ``--couple top``,
               z), ``{"top": "@0,0,0.06:guided=z"}``        ``--couple top:guided=z``
point_mass     ``{"top": 12.5}`` or ``{"top": (m, Ixx, …)}``  ``--point-mass top=12.5``
spring         ``{"a:b": (kx, ky, kz, krx, kry, krz)}``     ``--spring a:b=...``
shell          ``{"top": 0.02}`` or ``{"top": (t, offset)}`` ``--shell top=0.02``
beam           ``{"coil": "circle:0.006@radial:0,0,0,0,0,1"}`` ``--beam coil=…``
solid          ``["body"]``                                 ``--solid body``
mass           ``"consistent"`` or ``"lumped"``              ``--mass``
hex8           ``"standard"`` or ``"incompatible"``          ``--hex8``
length_unit    ``"m"``, ``"cm"``, ``"mm"`` (a path or a     ``--length-unit``
               meshio mesh given as ``mesh``)
============== ============================================ =====================================

Errors raise :class:`VibrofemError` subclasses (:class:`InputError`, :class:`NumericalError`,
:class:`OutputError`, :class:`EngineError`) carrying the command line's message.

Paths may be ``str``, ``bytes`` or :class:`os.PathLike` objects. Long computations run with the
interpreter released and stop at Ctrl-C (:class:`KeyboardInterrupt`; the computation already
started finishes in the background and its result is dropped). A :class:`Model` may be shared by
threads: its matrices are assembled once, by the first analysis that needs them.
"""

import json as _json
import operator as _operator
import os as _os
from dataclasses import dataclass as _dataclass, field as _field

import numpy as _np

from . import _core, _html, _meshio
from ._app import AppReport, autobalancer, balancer_data, crank_drive, design
from ._core import (  # noqa: F401
    EngineError,
    InputError,
    NumericalError,
    OutputError,
    VibrofemError,
    __version__,
)

__all__ = [
    "read_mesh",
    "from_meshio",
    "Mesh",
    "Model",
    "Dofs",
    "Modes",
    "Static",
    "Harmonic",
    "run_scene",
    "design",
    "crank_drive",
    "autobalancer",
    "balancer_data",
    "AppReport",
    "COMPONENTS",
    "VibrofemError",
    "InputError",
    "NumericalError",
    "OutputError",
    "EngineError",
]

#: DOF component names in component order (index 0..6).
COMPONENTS = tuple(_core.component_names())


def _num(x):
    return repr(float(x))


def _nums(v):
    if isinstance(v, (str, bytes)):
        return str(v)
    if _np.ndim(v) == 0:
        return _num(v)
    return ",".join(_num(a) for a in v)


def _material(m):
    return m if isinstance(m, str) else _nums(m)


def _group(opt, g, separators="="):
    """A dict key as a group name for the command line's ``GROUP=VALUE`` text: a string that
    reads back as itself. Surrounding spaces were trimmed there (a force on ``"zmax "`` went to
    ``"zmax"``) and a separator split the name, so such names are refused here."""
    if not isinstance(g, str):
        raise InputError(f"{opt}: group names are strings, got {g!r}")
    if g != g.strip() or not g:
        raise InputError(f"{opt}: group {g!r} is empty or has surrounding spaces, which {opt}= cannot pass on: "
                         "rename the group")
    bad = [c for c in separators if c in g]
    if bad:
        raise InputError(f"{opt}: group {g!r} contains {bad[0]!r}, which separates the parts of a {opt} entry: "
                         "rename the group")
    return g


def _group_values(d, opt):
    """{group: value} or [\"group=value\"] → list of 'group=value' strings."""
    if d is None:
        return []
    if isinstance(d, dict):
        # A spring joins two groups as A:B, so its group names cannot hold ':'.
        seps = "=:" if opt == "spring" else "="
        return [f"{_group(opt, g, seps)}={_nums(v)}" for g, v in d.items()]
    if isinstance(d, str):
        return [d]
    out = list(d)
    for s in out:
        if not isinstance(s, str):
            raise InputError(f"{opt}: give a dict {{group: value}} or strings 'GROUP=VALUE', got {s!r}")
    return out


def _group_entries(d, entry, opt):
    """``fix=``/``couple=`` as the command line's entries: a string or a list of them as they
    are, a dict {group: value} with ``True``/``None``/``""`` the bare group, ``False`` left out
    and any other value written by ``entry(group, value)``; the dict's group names must read
    back as themselves (no ``:`` or ``@``, which start a component list or a point)."""
    if d is None:
        return []
    if isinstance(d, str):
        return [d]
    if isinstance(d, dict):
        return [g if v is None or v is True or (isinstance(v, str) and v == "") else entry(g, v)
                for g, v in ((_group(opt, g, ":@"), v) for g, v in d.items()) if v is not False]
    return list(d)


def _fix_entry(g, c):
    if isinstance(c, str):
        return f"{g}:{c}"
    if _np.ndim(c) == 1 and all(isinstance(x, str) for x in c):
        return f"{g}:{','.join(c)}"
    raise InputError(f"fix: group '{g}': give True, components such as 'ux,uz' or ['ux', 'uz'], got {c!r}")


def _couple_entry(g, v):
    if isinstance(v, (bool, int, float)) and not isinstance(v, str):
        raise InputError(f"couple: group '{g}': give True, a guided axis 'x'/'y'/'z', '@X,Y,Z' or a point "
                         f"(x, y, z), got {v!r}")
    if v in ("x", "y", "z"):
        return f"{g}:guided={v}"
    if isinstance(v, str) and v.startswith(("@", ":")):
        return f"{g}{v}"
    if isinstance(v, str):
        return f"{g}:{v}"
    return f"{g}@{_nums(v)}"  # a point: the reference node's position


def _fixes(d):
    return _group_entries(d, _fix_entry, "fix")


def _couplings(d):
    return _group_entries(d, _couple_entry, "couple")


def _whole(what, v, least):
    """``v`` as a whole number ≥ ``least`` (a negative one was PyO3's ``OverflowError``, naming
    nothing); ``None`` as is."""
    if v is None:
        return None
    if isinstance(v, bool):
        raise InputError(f"{what} is a whole number, not {v}")
    try:
        v = _operator.index(v)
    except TypeError:
        raise InputError(f"{what} must be a whole number, got {v!r}") from None
    if v < least or v > 2**63 - 1:
        raise InputError(f"{what} must be a whole number ≥ {least}, got {v}")
    return v


def _path(p, what):
    """A path as text: ``str`` as is, ``bytes`` and path objects decoded as the OS does."""
    if isinstance(p, str):
        return p
    if isinstance(p, (bytes, _os.PathLike)):
        return _os.fsdecode(_os.fspath(p))
    raise TypeError(f"{what}: expected a path (str, bytes or os.PathLike), got {type(p).__name__}")


def _sweep(sweep):
    """(f0, f1, n) with n a whole number, as the command line's ``--sweep F0 F1 N``."""
    try:
        f0, f1, n = sweep
    except (TypeError, ValueError):
        raise InputError(f"sweep: give (f0, f1, n), got {sweep!r}") from None
    try:
        n = _operator.index(n)
    except TypeError:
        if not (isinstance(n, float) and n.is_integer()):
            raise InputError(f"sweep: N {n!r} must be a whole number ≥ 2") from None
        n = int(n)
    if n < 2:
        raise InputError(f"sweep: need at least 2 points, got {n}")
    return float(f0), float(f1), n


def _rayleigh(r):
    """(α, β) of C = αM + βK, exactly two numbers."""
    if isinstance(r, (str, bytes)) or _np.ndim(r) != 1 or len(r) != 2:
        raise InputError(f"rayleigh: give (alpha, beta) (1/s, s), got {r!r}")
    return float(r[0]), float(r[1])


def _indices(a, what):
    """An integer index array: integer dtypes as they are, floats only when whole."""
    a = _np.asarray(a)
    if a.size and a.dtype.kind not in "iu":
        if a.dtype.kind != "f" or not _np.all(_np.isfinite(a)) or not _np.all(a == _np.round(a)):
            raise InputError(f"{what}: indices must be whole numbers, got {a.ravel()[:4].tolist()}…")
    if a.size and a.dtype.kind == "u" and a.max() > _np.iinfo(_np.int64).max:
        raise InputError(f"{what}: index {int(a.max())} is out of range")
    return a.astype(_np.int64)


def _mesh_of(result):
    if result.mesh is None:
        raise ValueError("this result carries no mesh (it was not made by a Model)")
    return result.mesh


def _names(d):
    if d is None:
        return []
    if isinstance(d, str):
        return [d]
    return list(d)


def _frozen(a):
    """``a`` read-only: each call hands out a fresh copy of the mesh's arrays, so a write to
    one would change nothing and say nothing (:meth:`Mesh.from_arrays` makes a changed mesh)."""
    a.flags.writeable = False
    return a


class Mesh:
    """A mesh in metres: nodes, cells per kind, physical groups. Made by :func:`read_mesh`.
    Its arrays are read-only; :meth:`from_arrays` makes a mesh from changed copies."""

    def __init__(self, core):
        self._core = core

    @property
    def source(self):
        return self._core.source

    @property
    def nodes(self):
        """Node coordinates, m (n × 3 ndarray, read-only)."""
        return _frozen(self._core.nodes)

    @property
    def node_tags(self):
        """The file's tag of each node (read-only)."""
        return _frozen(self._core.node_tags)

    @property
    def groups(self):
        """{name: {"dim", "tag", "cells", "nodes"}} of the physical groups."""
        return {
            name: {"dim": dim, "tag": tag, "cells": nc, "nodes": nn}
            for name, dim, tag, nc, nn in self._core.group_list
        }

    @property
    def cell_kinds(self):
        """{kind: count} of the cells, e.g. {"tet10": 5120, "tri6": 640}."""
        return dict(self._core.cell_kinds)

    def cells(self, kind):
        """Connectivity of the cells of one kind (0-based node indices, gmsh order), c × k, read-only."""
        return _frozen(self._core.cells(kind))

    def cell_tags(self, kind):
        """The file's tag of each cell of one kind (read-only)."""
        return _frozen(self._core.cell_tags(kind))

    def group_nodes(self, name):
        """0-based indices of a group's nodes, sorted (read-only)."""
        return _frozen(self._core.group_nodes(name))

    def group_cells(self, name):
        """{kind: 0-based indices into :meth:`cells` of that kind} of a group's cells."""
        hits = [parts for g, _, _, parts in self._core.group_cells if g == name]
        if not hits:
            raise InputError(f"unknown group '{name}' (the mesh has: {', '.join(self.groups)})")
        out = {}
        for parts in hits:
            for kind, idx in parts:
                out[kind] = _np.asarray(idx, dtype=_np.int64)
        return out

    @classmethod
    def from_arrays(cls, points, cells, groups=None, source="<arrays>"):
        """A mesh from arrays in metres: ``points`` (n × 3), ``cells`` {kind: connectivity
        (c × k, 0-based, gmsh node order)}, ``groups`` {name: {kind: cell indices}} (each group
        of one dimension)."""
        if not isinstance(cells, dict):
            raise InputError(f"from_arrays: cells must be a dict {{kind: connectivity}}, got {type(cells).__name__}")
        if groups is not None and not isinstance(groups, dict):
            raise InputError(f"from_arrays: groups must be a dict {{name: {{kind: cell indices}}}}, got "
                             f"{type(groups).__name__}")
        kinds = list(cells)
        blocks = [(k, _np.ascontiguousarray(_indices(cells[k], f"from_arrays: {k} connectivity"))) for k in kinds]
        gs = []
        for tag, (name, parts) in enumerate((groups or {}).items(), start=1):
            if not isinstance(parts, dict):
                raise InputError(f"from_arrays: group '{name}': give {{kind: cell indices}}, got {parts!r}")
            ref = []
            dims = set()
            for kind, idx in parts.items():
                if kind not in kinds:
                    raise InputError(f"group '{name}': no {kind} cells in the mesh (it has: {', '.join(kinds)})")
                ref.append((kinds.index(kind), [int(i) for i in _indices(idx, f"from_arrays: group '{name}'").ravel()]))
                dims.add(_meshio._dim_of(kind))
            if len(dims) != 1:
                raise InputError(f"group '{name}': give cells of one dimension, got {sorted(dims) or 'none'}")
            gs.append((str(name), dims.pop(), tag, ref))
        pts = _np.ascontiguousarray(_np.asarray(points, dtype=float))
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise InputError(f"from_arrays: points must be n × 3 coordinates (m), got shape {pts.shape}")
        for k, c in blocks:
            if c.ndim != 2:
                raise InputError(f"from_arrays: {k} connectivity must be c × (nodes per cell), got shape {c.shape}")
        return cls(_core.mesh_from_arrays(pts, blocks, gs, source))

    def to_meshio(self):
        """The mesh as a ``meshio.Mesh`` (VTK node order; groups as ``cell_sets``, as
        ``gmsh:physical`` cell data and ``field_data`` {name: [tag, dim]})."""
        return _meshio.mesh_to_meshio(self)

    def to_pyvista(self):
        """The mesh as a ``pyvista.UnstructuredGrid`` (needs PyVista)."""
        return _meshio.to_pyvista(self.to_meshio())

    def _repr_html_(self):
        return _html.mesh_html(self)

    def __repr__(self):
        return repr(self._core)


def from_meshio(mesh, length_unit="m"):
    """A :class:`Mesh` from a ``meshio.Mesh`` (or a PyVista grid, through ``pyvista.to_meshio``):
    cell blocks merged per kind, groups from its ``cell_sets`` or else its ``gmsh:physical``
    cell data (named by ``field_data``); coordinates scaled from ``length_unit`` (m, cm, mm) to
    metres."""
    return _meshio.mesh_from_meshio(mesh, length_unit)


def read_mesh(source, length_unit="m"):
    """Read a gmsh mesh (MSH 2.2 or 4.1, ASCII or binary) or generate one
    (``box:LX,LY,LZ:NX,NY,NZ:KIND``, ``helix:…``, ``sandwich:paper[,SIZE]``, ``ibeam-*:…``),
    scaling coordinates from ``length_unit`` (m, cm, mm) to metres."""
    return Mesh(_core.read_mesh(_path(source, "read_mesh"), length_unit))


@_dataclass
class Dofs:
    """The free DOFs: row i of K and M is component ``component[i]`` of node ``node[i]``
    (0-based mesh node index; reference nodes of couplings follow the mesh nodes)."""

    node: _np.ndarray
    component: _np.ndarray
    n_mesh_nodes: int

    @property
    def names(self):
        return [COMPONENTS[c] for c in self.component]

    def index(self, node, component):
        """Row of a node's component (component as an index or a name such as "uz"), or -1."""
        if isinstance(component, str):
            if component not in COMPONENTS:
                raise InputError(f"Dofs.index: unknown component '{component}' (use {', '.join(COMPONENTS)})")
            component = COMPONENTS.index(component)
        hit = _np.nonzero((self.node == node) & (self.component == component))[0]
        return int(hit[0]) if len(hit) else -1

    def __len__(self):
        return len(self.node)


@_dataclass
class Modes:
    """A verified modal solution."""

    frequencies_hz: _np.ndarray
    eigenvalues: _np.ndarray
    #: Mode shapes at the mesh nodes: n_nodes × 6 (ux, uy, uz, rx, ry, rz) × k, M-normalised.
    shapes: _np.ndarray
    #: The same modes over the free DOFs (n_free × k), rows as in :attr:`Model.dofs`.
    vectors: _np.ndarray
    #: The Sturm count found every mode in the range.
    complete: bool
    #: Every backward error ≤ 1e-10, M-orthonormal, stable factorisations.
    accurate: bool
    #: Relative residuals ‖Kx − λMx‖/‖Kx‖ per mode.
    residuals: _np.ndarray
    #: Backward errors per mode (the acceptance test).
    backward_errors: _np.ndarray
    #: Participation factors per mode (k × 6: X, Y, Z, RX, RY, RZ).
    participation: _np.ndarray
    #: Effective masses per mode (k × 6, kg and kg·m²).
    effective_mass: _np.ndarray
    #: "rigid" or "elastic" per mode.
    kinds: list
    #: The whole report (what ``vibrofem modes --json`` prints).
    report: dict = _field(repr=False)
    #: The mesh the shapes live on.
    mesh: "Mesh | None" = _field(default=None, repr=False)

    @property
    def notes(self):
        return self.report.get("notes", [])

    def __repr__(self):
        f = self.frequencies_hz
        span = f"{f[0]:.6g}–{f[-1]:.6g} Hz" if len(f) else "none"
        return (f"<vibrofem Modes: {len(f)} modes, {span}, {'complete' if self.complete else 'INCOMPLETE'}, "
                f"{'accurate' if self.accurate else 'NOT ACCURATE'} (max residual {_np.max(self.residuals, initial=0):.2e})>")

    def to_meshio(self):
        """The mesh with a point array per mode (``mode_1`` … translations n × 3, and
        ``mode_1_rotation`` … where rotations are nonzero); ``field_data``: ``frequencies_hz``,
        ``rigid`` (1 per rigid mode), ``rel_residuals``, ``complete`` and ``accurate``."""
        return _meshio.modes_to_meshio(self, _mesh_of(self))

    def to_pyvista(self):
        """:meth:`to_meshio` as a ``pyvista.UnstructuredGrid`` (``grid.warp_by_vector("mode_7")``)."""
        return _meshio.to_pyvista(self.to_meshio())

    def _repr_html_(self):
        return _html.modes_html(self)


@_dataclass
class Static:
    """A linear static solution (one load case)."""

    #: Displacements at the mesh nodes, n_nodes × 6 (m, rad).
    displacement: _np.ndarray
    #: Nodal von Mises stress of the solid cells (Pa; 0 at nodes of no solid).
    von_mises: _np.ndarray
    #: {group: {"force": (Fx, Fy, Fz), "moment": (Mx, My, Mz)}} reaction resultants.
    reactions: dict
    #: {coupled group: stiffness along its guided axis, N/m} where defined.
    stiffness: dict
    #: The whole report (what ``vibrofem static --json`` prints).
    report: dict = _field(repr=False)
    #: The mesh the fields live on.
    mesh: "Mesh | None" = _field(default=None, repr=False)

    def __repr__(self):
        u = _np.linalg.norm(self.displacement[:, :3], axis=1) if len(self.displacement) else _np.zeros(1)
        return (f"<vibrofem Static: max displacement {u.max():.4g} m, max von Mises "
                f"{_np.max(self.von_mises, initial=0) / 1e6:.4g} MPa, {len(self.reactions)} support(s)>")

    def to_meshio(self):
        """The mesh with point arrays ``displacement`` (n × 3), ``rotation`` (where nonzero) and
        ``von_mises``; ``field_data`` ``stiffness:GROUP`` (N/m) per coupled group."""
        return _meshio.static_to_meshio(self, _mesh_of(self))

    def to_pyvista(self):
        return _meshio.to_pyvista(self.to_meshio())

    def _repr_html_(self):
        return _html.static_html(self)


class Model:
    """A mesh bound to materials, supports, couplings and parts (see the module's table of
    keywords). K and M are assembled once, on first use, and shared by every analysis."""

    def __init__(
        self,
        mesh,
        material="steel",
        group_material=None,
        fix=None,
        couple=None,
        point_mass=None,
        spring=None,
        mass="consistent",
        solid=None,
        shell=None,
        beam=None,
        hex8="standard",
        length_unit="m",
    ):
        if isinstance(mesh, (str, bytes, _os.PathLike)):
            mesh = read_mesh(mesh, length_unit)
        elif isinstance(mesh, Mesh) and length_unit != "m":
            raise InputError(f"Model: length_unit='{length_unit}' applies to a mesh read here (a path) or converted "
                             "(a meshio mesh); a Mesh is in metres already (read_mesh(path, length_unit) scales it)")
        elif not isinstance(mesh, Mesh) and hasattr(mesh, "points") and hasattr(mesh, "cells"):
            mesh = from_meshio(mesh, length_unit)  # a meshio.Mesh or a PyVista grid
        elif not isinstance(mesh, Mesh):
            raise TypeError(f"Model: expected a Mesh, a meshio.Mesh, a PyVista grid or a path, got {type(mesh).__name__}")
        self._mesh = mesh
        gm = group_material
        if isinstance(gm, dict):
            gm = [f"{_group('group_material', g)}={_material(m)}" for g, m in gm.items()]
        self._core = _core.Model(
            mesh._core,
            material=_material(material),
            group_material=_names(gm),
            fix=_fixes(fix),
            couple=_couplings(couple),
            point_mass=_group_values(point_mass, "point_mass"),
            spring=_group_values(spring, "spring"),
            mass=mass,
            solid=_names(solid),
            shell=_group_values(shell, "shell"),
            beam=_group_values(beam, "beam"),
            hex8=hex8,
        )
        self._kwargs = dict(
            material=material,
            group_material=group_material,
            fix=fix,
            couple=couple,
            point_mass=point_mass,
            spring=spring,
            mass=mass,
            solid=solid,
            shell=shell,
            beam=beam,
            hex8=hex8,
        )

    def assemble(self):
        """K and M over the free DOFs as ``scipy.sparse.csr_array`` (symmetric, both triangles
        stored; N/m and kg, N·m/rad and kg·m² on rotations). They used to be
        ``csr_matrix``: ``A * x`` is now element-wise, use ``A @ x``."""
        import scipy.sparse as sp

        (kd, ki, kp), (md, mi, mp), n = self._core.assemble()
        return (
            sp.csr_array((kd, ki, kp), shape=(n, n)),
            sp.csr_array((md, mi, mp), shape=(n, n)),
        )

    @property
    def dofs(self):
        """The node and component of each free DOF (:class:`Dofs`)."""
        node, comp = self._core.dof_table()
        n_mesh, _ = self._core.node_counts()
        return Dofs(node=node, component=comp, n_mesh_nodes=n_mesh)

    @property
    def volume(self):
        return self._core.summary()[0]

    @property
    def mass(self):
        """Total mass, kg (point masses included)."""
        return self._core.summary()[1]

    @property
    def notes(self):
        return self._core.summary()[2]

    def modes(self, n=None, band=None, shift_hz=None, block=6, engine="native", ranks=1, prestress=None):
        """The ``n`` lowest modes (12 by default; nearest ``shift_hz`` if given), or every mode
        with frequency in ``band = (f_lo, f_hi)`` Hz; verified (Sturm count, backward errors).
        ``engine="slepc"`` solves with SLEPc + MUMPS on ``ranks`` MPI ranks instead. A result
        that fails its verification is returned with ``complete``/``accurate`` False (the command
        line then exits 2); check them. ``prestress=dict(force=..., pressure=..., gravity=...,
        displace=...)`` (as :meth:`static`) gives the modes of the structure preloaded by that
        static case, (K + K_σ)x = λMx (native engine)."""
        n, block, ranks = _whole("modes: n", n, 1), _whole("modes: block", block, 1), _whole("modes: ranks", ranks, 1)
        if isinstance(band, (str, bytes)):
            raise InputError(f"modes: band takes (f_lo, f_hi) in Hz, got {band!r}")
        pre = None
        if prestress is not None:
            if not isinstance(prestress, dict):
                raise InputError("modes: prestress takes a dict of static loads, e.g. dict(force={'end': (0, 0, -1e3)})")
            unknown = set(prestress) - {"force", "pressure", "gravity", "displace"}
            if unknown:
                raise InputError(f"modes: prestress: unknown load(s) {sorted(unknown)} (force, pressure, gravity, displace)")
            pre = self._loads(**prestress)
        rep, lam, vec, shapes = self._core.modes(
            n=n, band=None if band is None else tuple(band), shift_hz=shift_hz, block=block, engine=engine, ranks=ranks,
            prestress=pre,
        )
        r = _json.loads(rep)
        rows = r["modes"]
        return Modes(
            frequencies_hz=_np.array(r["frequencies_hz"]),
            eigenvalues=_np.asarray(lam),
            shapes=shapes,
            vectors=vec,
            complete=bool(r["complete"]),
            accurate=bool(r["accurate"]),
            residuals=_np.array([m["rel_residual"] for m in rows]),
            backward_errors=_np.array([m["backward_error"] for m in rows]),
            participation=_np.array([m["participation"] for m in rows]).reshape(-1, 6),
            effective_mass=_np.array([m["effective_mass"] for m in rows]).reshape(-1, 6),
            kinds=[m["kind"] for m in rows],
            report=r,
            mesh=self.mesh,
        )

    def harmonic(self, force, freq=None, sweep=None, damping=None, rayleigh=None, method="modal", modes=None,
                 probe=None):
        """Steady-state response to harmonic forces (as ``vibrofem harmonic``):
        ``force={group: (Fx, Fy, Fz)}`` or ``(Fx, Fy, Fz, phase_deg)`` (N, total on the group);
        ``freq=Hz`` or ``sweep=(f0, f1, n)`` (n points from f0 to f1, 0 ≤ f0 < f1, as the command
        line's ``--sweep``, with its cap on n); ``damping=ζ`` (modal) or ``rayleigh=(α, β)``
        (C = αM + βK); ``method`` "modal" (superposition with static correction), "direct" or
        "both"; ``modes`` superposed (default: all below 2 × the highest frequency)."""
        forces = []
        if isinstance(force, dict):
            for g, v in force.items():
                if isinstance(v, (str, bytes)) or _np.ndim(v) != 1 or len(v) not in (3, 4):
                    raise InputError(
                        f"harmonic: force for group '{g}': give (Fx, Fy, Fz) or (Fx, Fy, Fz, phase_deg), got {v!r}")
                v = tuple(v)
                phase = v[3] if len(v) > 3 else 0.0
                forces.append(f"{_group('force', g)}={_nums(v[:3])}@{_num(phase)}")
        else:
            forces = _group_values(force, "force")
        if (freq is None) == (sweep is None):
            raise InputError("harmonic: give freq=Hz or sweep=(f0, f1, n), one of them")
        rep, freqs, re, im = self._core.harmonic(
            force=forces,
            freq=None if freq is None else float(freq),
            sweep=None if sweep is None else _sweep(sweep),
            damping=None if damping is None else float(damping),
            rayleigh=None if rayleigh is None else _rayleigh(rayleigh),
            method=method,
            modes=_whole("harmonic: modes", modes, 1),
            probe=[] if probe is None else _names(probe),
        )
        return Harmonic(frequencies_hz=freqs, displacement=re + 1j * im, report=_json.loads(rep), mesh=self.mesh)

    @staticmethod
    def _loads(force=None, pressure=None, gravity=None, displace=None):
        """One static load case in the command line's grammar: (force, pressure, gravity,
        displace)."""
        disp = []
        if isinstance(displace, dict):
            for g, v in displace.items():
                disp.append(f"{_group('displace', g)}=" + ",".join("-" if a is None else _num(a) for a in v))
        elif displace is not None:
            disp = _names(displace)
        return (
            _group_values(force, "force"),
            _group_values(pressure, "pressure"),
            None if gravity is None else _nums(gravity),
            disp,
        )

    def buckling(self, force=None, pressure=None, gravity=None, displace=None, n=4):
        """Linear buckling (as ``vibrofem buckling``): the ``n`` lowest positive load factors λ
        of (K + λK_σ)φ = 0 for the static case given as in :meth:`static`, verified (backward
        errors, Sturm count). Returns a namespace with ``load_factors`` (ascending; empty with
        ``no_buckling`` True when the load has no positive load factor, proved by a Sturm
        count), ``shapes`` (n_nodes × 3 × k, largest translation 1), ``complete``, ``accurate``
        and the JSON ``report``."""
        import types

        f, p, g, d = self._loads(force, pressure, gravity, displace)
        rep, lam, shapes = self._core.buckling(n=_whole("buckling: n", n, 1), force=f, pressure=p, gravity=g, displace=d)
        r = _json.loads(rep)
        return types.SimpleNamespace(
            load_factors=_np.asarray(lam),
            shapes=shapes,
            no_buckling=bool(r["no_buckling"]),
            complete=bool(r["complete"]),
            accurate=bool(r["accurate"]),
            report=r,
        )

    def static(self, force=None, pressure=None, gravity=None, displace=None):
        """Linear statics, one load case: ``force={group: (Fx, Fy, Fz)}`` (N; on a coupled group
        at its reference node, on a surface as a uniform traction), ``pressure={surface: p}``
        (Pa, into the solid), ``gravity=(gx, gy, gz)`` (m/s²), ``displace={group: (ux, uy, uz)}``
        (m; None leaves a component free)."""
        disp = []
        if isinstance(displace, dict):
            for g, v in displace.items():
                disp.append(f"{_group('displace', g)}=" + ",".join("-" if a is None else _num(a) for a in v))
        elif displace is not None:
            disp = _names(displace)
        rep, u, vm = self._core.static_analysis(
            force=_group_values(force, "force"),
            pressure=_group_values(pressure, "pressure"),
            gravity=None if gravity is None else _nums(gravity),
            displace=disp,
        )
        r = _json.loads(rep)
        case = r["cases"][0]
        reactions = {
            x["group"]: {"force": tuple(x["resultant"]["force"]), "moment": tuple(x["resultant"]["moment"])}
            for x in case["reactions"]
        }
        stiffness = {x["group"]: x["stiffness"] for x in case["references"] if x.get("stiffness") is not None}
        return Static(displacement=u, von_mises=vm, reactions=reactions, stiffness=stiffness, report=r,
                      mesh=self.mesh)

    def export(self, dir, format="both"):
        """Write K, M (PETSc binary, Matrix Market), dofs.csv and model.json into ``dir``."""
        return self._core.export(_path(dir, "export"), format)

    @property
    def mesh(self):
        """The model's mesh (read-only: K and M are built on it; a new mesh needs a new Model)."""
        return self._mesh

    def __repr__(self):
        return f"<vibrofem Model of {self.mesh.source!r}>"


@_dataclass
class Harmonic:
    """Steady-state harmonic response: u(t) = Re(û e^{iωt}).

    ``frequencies_hz`` (k,), ``displacement`` (k × n_nodes × 3, complex, m), and the report as a
    dict (per-group amplitude and phase per frequency, modes used, notes)."""

    frequencies_hz: _np.ndarray
    displacement: _np.ndarray
    report: dict = _field(repr=False)
    #: The mesh the displacements live on.
    mesh: "Mesh | None" = _field(default=None, repr=False)

    def __repr__(self):
        f = self.frequencies_hz
        span = f"{f[0]:.6g} Hz" if len(f) == 1 else f"{len(f)} frequencies, {f[0]:.6g}–{f[-1]:.6g} Hz"
        peak = _np.abs(self.displacement).max(initial=0)
        return f"<vibrofem Harmonic: {span}, largest amplitude {peak:.4g} m>"

    def to_meshio(self):
        """The mesh with point arrays per frequency: ``real_1``, ``imag_1`` (n × 3, m) and
        ``amplitude_1`` (|û|, n) …; ``field_data`` ``frequencies_hz``."""
        return _meshio.harmonic_to_meshio(self, _mesh_of(self))

    def to_pyvista(self):
        return _meshio.to_pyvista(self.to_meshio())

    def _repr_html_(self):
        return _html.harmonic_html(self)


def run_scene(path, out=None):
    """Run a scene file (TOML) and return its report (what ``vibrofem run --json`` prints) as a
    dict; ``out`` is the folder for the result files the scene asks for."""
    return _json.loads(_core.run_scene(_path(path, "run_scene"), None if out is None else _path(out, "run_scene")))
