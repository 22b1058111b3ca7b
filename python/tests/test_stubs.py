"""The type stubs cover the public API: every name of ``vibrofem.__all__`` and every public member of
its classes is declared in ``__init__.pyi``, and the installed package ships the stubs and
``py.typed`` (PEP 561), so mypy uses them (validation/run_live.sh runs mypy --strict on the
examples and these tests)."""

from __future__ import annotations

import ast
import dataclasses
import inspect
from pathlib import Path
from typing import Dict, Set

import vibrofem as vf

PKG = Path(vf.__file__).parent


def stub_names() -> Dict[str, Set[str]]:
    """{top-level name: its members (for classes)} declared in the installed __init__.pyi."""
    tree = ast.parse((PKG / "__init__.pyi").read_text())
    out: Dict[str, Set[str]] = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            members: Set[str] = set()
            for b in node.body:
                if isinstance(b, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    members.add(b.name)
                elif isinstance(b, ast.AnnAssign) and isinstance(b.target, ast.Name):
                    members.add(b.target.id)
            out[node.name] = members
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            out[node.name] = set()
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            out[node.target.id] = set()
        elif isinstance(node, ast.Assign):
            for t in node.targets:
                if isinstance(t, ast.Name):
                    out[t.id] = set()
    return out


def public_members(cls: type) -> Set[str]:
    names = {n for n, _ in inspect.getmembers(cls) if not n.startswith("_") or n == "_repr_html_"}
    if dataclasses.is_dataclass(cls):
        names |= {f.name for f in dataclasses.fields(cls)}
    return names


def test_every_public_name_is_in_the_stubs() -> None:
    stubs = stub_names()
    public = list(vf.__all__) + ["__version__"]
    # The list of the public API, as a user sees it (a new name fails here until it is stubbed).
    assert sorted(vf.__all__) == sorted([
        "read_mesh", "from_meshio", "Mesh", "Model", "Dofs", "Modes", "Static", "Harmonic", "run_scene",
        "design", "crank_drive", "autobalancer", "balancer_data", "AppReport", "COMPONENTS",
        "VibrofemError", "InputError", "NumericalError", "OutputError", "EngineError",
    ])
    missing = [n for n in public if n not in stubs]
    assert not missing, f"not in __init__.pyi: {missing}"
    for name in vf.__all__:
        obj = getattr(vf, name)
        if inspect.isclass(obj) and not issubclass(obj, Exception):
            lack = sorted(public_members(obj) - stubs[name])
            assert not lack, f"{name}: members not in __init__.pyi: {lack}"
    # And nothing stubbed that the package lacks.
    for name, members in stubs.items():
        if name.startswith("_"):  # the stubs' own type aliases, __all__
            continue
        assert hasattr(vf, name), f"__init__.pyi declares {name}, the package has none"
        for m in {m for m in members if not m.startswith("_") or m == "_repr_html_"}:
            obj = getattr(vf, name)
            fields = {f.name for f in dataclasses.fields(obj)} if dataclasses.is_dataclass(obj) else set()
            assert hasattr(obj, m) or m in fields or m in getattr(obj, "__annotations__", {}), f"{name}.{m} stubbed, absent"


def test_the_package_ships_its_stubs() -> None:
    assert (PKG / "py.typed").is_file()
    assert (PKG / "__init__.pyi").is_file()


def test_assemble_returns_sparse_arrays() -> None:
    import scipy.sparse as sp

    K, M = vf.Model(vf.read_mesh("box:0.1,0.02,0.02:2,1,1:hex8"), fix=["xmin"]).assemble()
    assert isinstance(K, sp.csr_array) and isinstance(M, sp.csr_array)
    assert not isinstance(K, sp.spmatrix)
