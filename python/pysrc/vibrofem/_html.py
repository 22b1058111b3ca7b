"""Notebook display (``_repr_html_``): compact tables of a mesh, modes, a static or harmonic
result and an application report."""

from __future__ import annotations

from html import escape
from typing import Any, Iterable, List, Sequence

import numpy as np

_STYLE = "border-collapse:collapse;font-size:90%"
_OK = '<span style="color:#1a7f37">&#10003; {}</span>'
_BAD = '<span style="color:#cf222e">&#10007; {}</span>'


def _g(x: Any, digits: int = 5) -> str:
    try:
        return f"{float(x):.{digits}g}"
    except (TypeError, ValueError):
        return escape(str(x))


def _table(head: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    h = "".join(f"<th style='text-align:left;padding:0 .6em'>{escape(str(c))}</th>" for c in head)
    body = "".join(
        "<tr>" + "".join(f"<td style='padding:0 .6em'>{c}</td>" for c in r) + "</tr>" for r in rows
    )
    return f"<table style='{_STYLE}'><tr>{h}</tr>{body}</table>"


def _verdict(ok: bool, what: str) -> str:
    return (_OK if ok else _BAD).format(escape(what))


def _box(title: str, parts: List[str]) -> str:
    return f"<div><b>{escape(title)}</b>" + "".join(f"<div style='margin-top:.3em'>{p}</div>" for p in parts) + "</div>"


def mesh_html(mesh: Any) -> str:
    kinds = ", ".join(f"{n} {escape(k)}" for k, n in mesh.cell_kinds.items())
    groups = _table(
        ["group", "dim", "tag", "cells", "nodes"],
        [[escape(n), g["dim"], g["tag"], g["cells"], g["nodes"]] for n, g in mesh.groups.items()],
    )
    lo, hi = np.min(mesh.nodes, axis=0), np.max(mesh.nodes, axis=0)
    size = " × ".join(_g(d, 4) for d in hi - lo)
    return _box(
        f"vibrofem Mesh {mesh.source}",
        [f"{len(mesh.nodes)} nodes; cells: {kinds}; extent {size} m", groups],
    )


def modes_html(modes: Any) -> str:
    r = modes.report
    rows = []
    for i, f in enumerate(modes.frequencies_hz):
        rows.append([i + 1, _g(f, 6), escape(modes.kinds[i]), f"{modes.residuals[i]:.1e}", f"{modes.backward_errors[i]:.1e}"])
    head = f"{r.get('dofs', modes.vectors.shape[0])} DOFs, mass {_g(r.get('mass_kg', float('nan')), 6)} kg"
    verdicts = _verdict(bool(modes.complete), "complete (Sturm count)") + " &nbsp; " + _verdict(
        bool(modes.accurate), "accurate (backward errors ≤ 1e-10)"
    )
    return _box(
        f"vibrofem Modes ({len(modes.frequencies_hz)})",
        [head, verdicts, _table(["mode", "f (Hz)", "kind", "residual", "backward error"], rows)],
    )


def static_html(st: Any) -> str:
    r = st.report
    u = np.linalg.norm(np.asarray(st.displacement)[:, :3], axis=1)
    case = r["cases"][0] if r.get("cases") else {}
    rows = [[escape(g), *(_g(x) for x in v["force"])] for g, v in st.reactions.items()]
    parts = [
        f"{r.get('dofs', '?')} DOFs; max |u| {_g(u.max() if len(u) else 0.0)} m; "
        f"max von Mises {_g(np.max(st.von_mises) if len(st.von_mises) else 0.0)} Pa; "
        f"equilibrium error {_g(case.get('equilibrium_error', float('nan')), 2)}",
        _table(["reaction at", "Fx (N)", "Fy (N)", "Fz (N)"], rows),
    ]
    if st.stiffness:
        parts.append(_table(["coupled group", "stiffness (N/m)"], [[escape(g), _g(k)] for g, k in st.stiffness.items()]))
    return _box("vibrofem Static", parts)


def harmonic_html(h: Any) -> str:
    r = h.report
    rows = []
    for p in r.get("points", []):
        groups = "; ".join(f"{escape(g['group'])} {_g(g['peak_m'], 4)} m" for g in p.get("groups", []))
        rows.append([_g(p["freq_hz"], 6), _g(p["max_peak_m"], 4), groups])
    head = (
        f"{r.get('dofs', '?')} DOFs; method {escape(str(r.get('method', '?')))}; damping "
        f"{escape(str(r.get('damping', '?')))}; {r.get('modes_used', 0)} modes superposed"
    )
    return _box(
        f"vibrofem Harmonic ({len(h.frequencies_hz)} frequencies)",
        [head, _table(["f (Hz)", "max peak (m)", "groups' peak"], rows)],
    )


def app_html(a: Any) -> str:
    checks = a.data.get("checks") if isinstance(a.data, dict) else None
    parts = [f"report: <a href='{escape(a.html.as_uri())}'>{escape(str(a.html))}</a>"]
    if a.failure:
        parts.append(_verdict(False, a.failure))
    if isinstance(checks, dict):  # the design's {id: {name, value, limit, margin, ok}}
        checks = [dict(c, id=k) for k, c in checks.items() if isinstance(c, dict)]
    if isinstance(checks, list) and checks and all(isinstance(c, dict) for c in checks):
        rows = []
        for c in checks:
            rows.append([_verdict(bool(c.get("ok")), str(c.get("name", c.get("id", "")))), _g(c.get("value", "")), _g(c.get("limit", ""))])
        parts.append(_table(["check", "value", "limit"], rows))
    return _box(f"vibrofem report in {a.out}", parts)
