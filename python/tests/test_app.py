"""The application's reports from Python (vf.design, vf.crank_drive, vf.autobalancer,
vf.balancer_data): the same document as the command line's ``--json`` (the binary, when built, is
the reference), the report files written where asked, errors with the command line's messages."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path
from typing import Any, Callable, Optional

import pytest

import vibrofem as vf

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BINARY = os.path.join(ROOT, "target", "release", "vibrofem")


def strip(d: Any) -> Any:
    """Without what differs from run to run: timings, peak memory, the output paths."""
    if isinstance(d, dict):
        return {k: strip(v) for k, v in d.items() if not k.startswith("tim") and "memory" not in k and k not in ("outputs", "files")}
    if isinstance(d, list):
        return [strip(v) for v in d]
    return d


def cli_json(command: str, out: Path, path: Optional[str] = None) -> Any:
    if not os.access(BINARY, os.X_OK):
        pytest.skip("target/release/vibrofem not built (cargo build --release)")
    args = [BINARY, command] + ([path] if path else []) + ["--out", str(out), "--json"]
    r = subprocess.run(args, capture_output=True, text=True, cwd=ROOT)
    assert r.returncode in (0, 2), r.stderr
    return json.loads(r.stdout)


def test_design_returns_the_cli_document_and_the_report(design_report: vf.AppReport, tmp_path: Path) -> None:
    r = design_report
    assert r.html.is_file() and r.markdown.is_file() and r.json.is_file()
    assert json.loads(r.json.read_text()) == r.data
    assert any(p.suffix == ".svg" for p in r.files)
    assert isinstance(r.data["checks"], dict) and r.data["checks"]
    html = r._repr_html_()
    assert "report.html" in html and "work-table first elastic mode" in html
    if r.passing_variant is not None:
        assert (r.out / "passing-variant" / "report.html").is_file()


def test_design_file_returns_the_cli_document(tmp_path: Path) -> None:
    # The same document as `vibrofem design FILE --json`, on the built-in design without its
    # envelope (the envelope runs some forty chains, minutes on 2 cores: the built-in run of the
    # fixture above carries it, and the Rust tests check the envelope against single runs).
    toml = tmp_path / "no_envelope.toml"
    toml.write_text("version = 1\n[envelope]\nenabled = false\n")
    r = vf.design(toml, out=tmp_path / "py")
    assert "envelope" not in r.data and r.data["checks"]
    assert strip(r.data) == strip(cli_json("design", tmp_path / "cli", str(toml)))


@pytest.mark.parametrize(
    "fn, command",
    [(vf.crank_drive, "crank-drive"), (vf.autobalancer, "autobalancer"), (vf.balancer_data, "balancer-data")],
)
def test_machines_return_the_cli_document(fn: Callable[..., vf.AppReport], command: str, tmp_path: Path) -> None:
    r = fn(out=tmp_path / "py")
    assert r.out == tmp_path / "py" and r.html.is_file()
    assert json.loads(r.json.read_text()) == r.data
    assert strip(r.data) == strip(cli_json(command, tmp_path / "cli"))


def test_a_temporary_folder_by_default_and_errors_named() -> None:
    r = vf.crank_drive()
    assert r.out.is_dir() and r.out.name.startswith("vibrofem-crank-drive-") and r.html.is_file()
    case = os.path.join(ROOT, "scenes", "machines", "crank_two_carts.toml")
    assert strip(vf.crank_drive(case).data)["name"] == strip(r.data)["name"]
    with pytest.raises(vf.InputError, match="nope.toml"):
        vf.autobalancer(os.path.join(ROOT, "nope.toml"))
    with pytest.raises(vf.InputError, match="out"):
        vf.crank_drive(case, out=case)
    with pytest.raises(TypeError, match="out"):
        vf.crank_drive(out=3.5)  # type: ignore[arg-type]
