"""Notebook display: the compact HTML tables of a mesh, modes, a static and a harmonic result."""

from __future__ import annotations

import re
from html.parser import HTMLParser
from typing import List

import numpy as np

import vibrofem as vf


class Cells(HTMLParser):
    """The text of every table cell, in order; fails on unbalanced tags."""

    def __init__(self) -> None:
        super().__init__()
        self.cells: List[str] = []
        self.stack: List[str] = []
        self._in = False

    def handle_starttag(self, tag: str, attrs: object) -> None:
        self.stack.append(tag)
        if tag in ("td", "th"):
            self._in = True
            self.cells.append("")

    def handle_endtag(self, tag: str) -> None:
        assert self.stack and self.stack[-1] == tag, (self.stack, tag)
        self.stack.pop()
        if tag in ("td", "th"):
            self._in = False

    def handle_data(self, data: str) -> None:
        if self._in:
            self.cells[-1] += data


def cells(html: str) -> List[str]:
    p = Cells()
    p.feed(html)
    p.close()
    assert not p.stack, p.stack
    return [c.strip() for c in p.cells]


def test_tables_of_a_mesh_and_its_results() -> None:
    mesh = vf.read_mesh("box:0.3,0.05,0.02:12,2,2:hex20")
    h = mesh._repr_html_()
    assert "48 hex20" in h and f"{len(mesh.nodes)} nodes" in h
    c = cells(h)
    assert c[:5] == ["group", "dim", "tag", "cells", "nodes"] and "xmin" in c

    model = vf.Model(mesh, fix=["xmin"], couple={"xmax": "z"})
    modes = model.modes(3)
    h = modes._repr_html_()
    c = cells(h)
    assert c[:5] == ["mode", "f (Hz)", "kind", "residual", "backward error"]
    rows = [c[5 + 5 * i: 10 + 5 * i] for i in range(3)]
    for i, r in enumerate(rows):
        assert r[0] == str(i + 1) and float(r[1]) == float(f"{modes.frequencies_hz[i]:.6g}") and r[2] == modes.kinds[i]
        assert float(r[3]) == float(f"{modes.residuals[i]:.1e}")
    assert f"{modes.report['dofs']} DOFs" in h and "complete" in h and "accurate" in h
    assert re.search(r"mass [0-9.]+ kg", h)
    assert "&#10003;" in h and "&#10007;" not in h  # both verdicts passed

    st = model.static(force={"xmax": (0, 0, 1000)})
    c = cells(st._repr_html_())
    i = c.index("xmin")
    assert float(c[i + 3]) == float(f"{st.reactions['xmin']['force'][2]:.5g}")
    j = c.index("coupled group")
    assert c[j + 2] == "xmax" and float(c[j + 3]) == float(f"{st.stiffness['xmax']:.5g}")

    hr = model.harmonic(force={"xmax": (0, 0, 10)}, sweep=(20.0, 200.0, 3), damping=0.02)
    c = cells(hr._repr_html_())
    assert c[:3] == ["f (Hz)", "max peak (m)", "groups' peak"]
    assert [float(c[3 + 3 * i]) for i in range(3)] == list(np.round(hr.frequencies_hz, 6))
