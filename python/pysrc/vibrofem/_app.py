"""The application's reports as Python data: the design chain and the machines of the registry.

Each function runs as its command does with ``--out DIR --json`` (the same checks, the same report
files and plots written into ``out``) and returns an :class:`AppReport`: ``data`` is the document
``--json`` prints, parsed; the paths point at the written report.
"""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Union

from . import _core

PathArg = Union[str, bytes, "os.PathLike[str]", "os.PathLike[bytes]"]


@dataclass
class AppReport:
    """What :func:`design`, :func:`crank_drive`, :func:`autobalancer` and :func:`balancer_data`
    return."""

    #: The ``--json`` document, parsed.
    data: Dict[str, Any]
    #: The folder the report was written into.
    out: Path
    #: ``out/report.html``, ``report.md``, ``report.json``.
    html: Path
    markdown: Path
    json: Path
    #: Every file written into ``out`` (report, plots, mode shapes), sorted.
    files: List[Path]
    #: Why the machine's main result failed (the command line's exit code 2), else None.
    failure: Optional[str] = None
    #: :func:`design` only: the lightest passing variant's document, when the design failed a
    #: check and its ``[search]`` found one (report in ``out/passing-variant``).
    passing_variant: Optional[Dict[str, Any]] = field(default=None, repr=False)

    def _repr_html_(self) -> str:
        from ._html import app_html

        return app_html(self)


def _out_dir(out: Optional[PathArg], prefix: str) -> str:
    if out is None:
        return tempfile.mkdtemp(prefix=f"vibrofem-{prefix}-")
    if isinstance(out, (str, bytes, os.PathLike)):
        return os.fsdecode(os.fspath(out))
    raise TypeError(f"out: expected a path (str, bytes or os.PathLike), got {type(out).__name__}")


def _in_path(path: Optional[PathArg], what: str) -> Optional[str]:
    if path is None:
        return None
    if isinstance(path, (str, bytes, os.PathLike)):
        return os.fsdecode(os.fspath(path))
    raise TypeError(f"{what}: expected a path (str, bytes or os.PathLike), got {type(path).__name__}")


def _report(doc: str, out: str, failure: Optional[str] = None, variant: Optional[str] = None) -> AppReport:
    o = Path(out)
    return AppReport(
        data=json.loads(doc),
        out=o,
        html=o / "report.html",
        markdown=o / "report.md",
        json=o / "report.json",
        files=sorted(p for p in o.rglob("*") if p.is_file()),
        failure=failure,
        passing_variant=None if variant is None else json.loads(variant),
    )


def design(path: Optional[PathArg] = None, out: Optional[PathArg] = None, yes: bool = False) -> AppReport:
    """The vibratory-table design chain (``vibrofem design``) on a design TOML ``path`` (None: the
    paper's built-in 100 Hz table). The report goes to ``out`` (None: a new temporary folder);
    ``yes=True`` allows models over 300 000 DOFs (refused otherwise, with the estimate)."""
    o = _out_dir(out, "design")
    doc, variant = _core.run_design(_in_path(path, "design"), o, yes)
    return _report(doc, o, variant=variant)


def _machine(command: str, path: Optional[PathArg], out: Optional[PathArg]) -> AppReport:
    o = _out_dir(out, command)
    doc, failure = _core.run_machine(command, _in_path(path, command), o)
    return _report(doc, o, failure=failure)


def crank_drive(path: Optional[PathArg] = None, out: Optional[PathArg] = None) -> AppReport:
    """The crank drive of a roller-forming machine (``vibrofem crank-drive``) on a case TOML
    ``path`` (None: the built-in case); the report goes to ``out`` (None: a temporary folder).
    A steady run that stalls is returned with ``failure`` saying where and why."""
    return _machine("crank-drive", path, out)


def autobalancer(path: Optional[PathArg] = None, out: Optional[PathArg] = None) -> AppReport:
    """The ball autobalancer of a grinder (``vibrofem autobalancer``) on a case TOML ``path``
    (None: the built-in case); the report goes to ``out`` (None: a temporary folder)."""
    return _machine("autobalancer", path, out)


def balancer_data(path: Optional[PathArg] = None, out: Optional[PathArg] = None) -> AppReport:
    """The reduction of autobalancer test-stand data (``vibrofem balancer-data``) on a data file
    ``path`` (None: the built-in data); the report goes to ``out`` (None: a temporary folder)."""
    return _machine("balancer-data", path, out)
