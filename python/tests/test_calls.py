"""How the package is called: paths of every kind, arguments under the command line's rules,
Ctrl-C during a long computation, one model shared by threads (run by validation/run_live.sh
with the other package tests: ``python -m pytest -q python/tests``)."""

import os
import pathlib
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Callable

import numpy as np
import pytest

import vibrofem as vf

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TET10 = os.path.join(ROOT, "meshes", "s1_plate_tet10_h30.msh")
BAR = "box:0.3,0.05,0.02:12,2,2:hex20"


def test_paths_as_bytes_and_path_objects(tmp_path: pathlib.Path) -> None:
    for p in (os.fsencode(TET10), pathlib.Path(TET10)):
        mesh = vf.read_mesh(p)
        assert mesh.source == TET10, mesh.source
        assert mesh.cell_kinds["tet10"] > 0
    assert vf.Model(os.fsencode(TET10)).mesh.source == TET10
    assert vf.Model(pathlib.Path(TET10)).mesh.source == TET10
    with pytest.raises(TypeError, match="read_mesh"):
        vf.read_mesh(42)  # type: ignore[arg-type]
    model = vf.Model(vf.read_mesh(BAR), fix=["xmin"])
    files = model.export(os.fsencode(str(tmp_path / "k")), format="mtx")
    assert all(f.startswith(str(tmp_path / "k")) for f in files), files


def test_a_sweep_follows_the_command_lines_rules() -> None:
    model = vf.Model(vf.read_mesh(BAR), fix=["xmin"])
    force = {"xmax": (0, 0, 10)}
    # Reversed, as the command line refuses it.
    with pytest.raises(vf.InputError, match="F0 < F1"):
        model.harmonic(force=force, sweep=(600.0, 20.0, 5), damping=0.02)
    # More points than the command line's cap, refused before any work (a billion points would
    # not return at all).
    with pytest.raises(vf.InputError, match="sweep"):
        model.harmonic(force=force, sweep=(20.0, 600.0, 10**9), damping=0.02)
    with pytest.raises(vf.InputError, match="whole number"):
        model.harmonic(force=force, sweep=(20.0, 600.0, 2.5), damping=0.02)
    with pytest.raises(vf.InputError, match="at least 2"):
        model.harmonic(force=force, sweep=(20.0, 600.0, 1), damping=0.02)
    h = model.harmonic(force=force, sweep=(20.0, 600.0, 3.0), damping=0.02)
    assert np.allclose(h.frequencies_hz, [20.0, 310.0, 600.0])
    assert h.displacement.shape[0] == 3


def test_one_model_is_shared_by_threads() -> None:
    """Several threads on one model: one assembly, the same answers, no 'Already borrowed'."""
    model = vf.Model(vf.read_mesh(BAR), fix=["xmin"])
    ref = vf.Model(vf.read_mesh(BAR), fix=["xmin"]).modes(6).frequencies_hz

    def work(i: int) -> Any:
        if i % 3 == 0:
            return model.modes(6).frequencies_hz
        if i % 3 == 1:
            K, _ = model.assemble()
            return K.shape[0]
        return model.mass

    with ThreadPoolExecutor(6) as ex:
        out = list(ex.map(work, range(12)))
    for i, o in enumerate(out):
        if i % 3 == 0:
            assert np.allclose(o, ref, rtol=1e-12), (o, ref)
    assert len({o for i, o in enumerate(out) if i % 3 == 1}) == 1


CTRL_C = """
import sys, time
import vibrofem as vf
model = vf.Model(vf.read_mesh(sys.argv[1]), fix=["xmin"])
print("ready", flush=True)
t = time.perf_counter()
try:
    model.modes(30)
except KeyboardInterrupt:
    print("interrupted after %.3f s" % (time.perf_counter() - t), flush=True)
    sys.exit(3)
print("finished after %.3f s" % (time.perf_counter() - t), flush=True)
"""


def test_ctrl_c_stops_a_long_modal_analysis_at_once() -> None:
    """SIGINT during modes(): KeyboardInterrupt, never a PanicException (before, the signal waited
    for the solve to end and then surfaced as a Rust panic). How soon it comes is printed, not
    asserted (no timing in tests)."""
    big = "box:0.6,0.6,0.02:60,60,2:hex20"
    p = subprocess.Popen(
        [sys.executable, "-c", CTRL_C, big],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert p.stdout is not None
        assert p.stdout.readline().strip() == "ready"
        time.sleep(1.0)
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=300)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    assert "PanicException" not in err, err
    assert p.returncode == 3, (p.returncode, out, err)
    assert "interrupted" in out and "finished" not in out, out
    print(out.strip())


def test_values_of_the_wrong_length_or_kind_are_refused() -> None:
    model = vf.Model(vf.read_mesh(BAR), fix=["xmin"])
    # A fifth force value and a third Rayleigh coefficient were dropped without a word.
    with pytest.raises(vf.InputError, match="force for group 'xmax'"):
        model.harmonic(force={"xmax": (0, 0, 10, 90, 123)}, freq=100.0, damping=0.02)
    with pytest.raises(vf.InputError, match="rayleigh"):
        model.harmonic(force={"xmax": (0, 0, 10)}, freq=100.0, rayleigh=(1.0, 1e-5, 99.0))  # type: ignore[arg-type]
    with pytest.raises(vf.InputError, match="rayleigh"):
        model.harmonic(force={"xmax": (0, 0, 10)}, freq=100.0, rayleigh=1.0)  # type: ignore[arg-type]
    # {group: False} is "not fixed"; a number is not a component list (1 was taken as True).
    free = vf.Model(vf.read_mesh(BAR), fix={"xmin": False})
    assert free.modes(7).report["n_rigid"] == 6
    with pytest.raises(vf.InputError, match="fix: group 'xmin'"):
        vf.Model(vf.read_mesh(BAR), fix={"xmin": 1})  # type: ignore[dict-item]
    with pytest.raises(vf.InputError, match="couple: group 'xmax'"):
        vf.Model(vf.read_mesh(BAR), couple={"xmax": 1})
    with pytest.raises(vf.InputError, match="unknown component 'qq'"):
        model.dofs.index(0, "qq")
    with pytest.raises(vf.InputError, match="m, cm or mm"):
        vf.read_mesh(BAR, length_unit="inch")


def test_a_model_reads_a_millimetre_mesh_and_checks_its_groups_at_once() -> None:
    mm = os.path.join(ROOT, "meshes", "s1_plate_tet10_h30_mm.msh")
    # The same plate in metres and in millimetres: the same mass (it was 1e9 times too much,
    # with no way to give the unit to Model).
    assert vf.Model(mm, length_unit="mm").mass == pytest.approx(vf.Model(TET10).mass, rel=1e-12)
    with pytest.raises(vf.InputError, match="metres already"):
        vf.Model(vf.read_mesh(TET10), length_unit="mm")
    # An unknown group is refused by the constructor, not at the first analysis.
    with pytest.raises(vf.InputError, match="nope"):
        vf.Model(vf.read_mesh(BAR), fix=["nope"])


def test_modes_refuses_flags_for_counts_and_text_for_a_band() -> None:
    model = vf.Model(vf.read_mesh(BAR), fix=["xmin"])
    # True was taken as one mode; '0,500' was read as a tuple of five characters.
    with pytest.raises(vf.InputError, match="whole number"):
        model.modes(True)
    with pytest.raises(vf.InputError, match="band takes"):
        model.modes(band="0,500")  # type: ignore[arg-type]


def test_a_meshs_arrays_and_a_models_mesh_cannot_be_changed_unnoticed() -> None:
    # Each access hands out a fresh copy: a write to it changed nothing and said nothing.
    mesh = vf.read_mesh(BAR)
    for arr in (mesh.nodes, mesh.node_tags, mesh.cells("hex20"), mesh.cell_tags("hex20"),
                mesh.group_nodes("xmin")):
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 0
    model = vf.Model(mesh, fix=["xmin"])
    with pytest.raises(AttributeError):
        model.mesh = vf.read_mesh(TET10)  # type: ignore[misc]
    assert model.mesh is mesh
    # A changed copy makes a new mesh.
    pts = mesh.nodes.copy()
    pts[:, 0] *= 2.0
    longer = vf.Mesh.from_arrays(pts, {"hex20": mesh.cells("hex20")})
    assert np.ptp(longer.nodes[:, 0]) == pytest.approx(0.6)


def test_messages_name_python_keywords_not_command_line_options() -> None:
    model = vf.Model(vf.read_mesh(BAR), fix=["xmin"])
    with pytest.raises(vf.InputError) as e:
        model.modes(band=(0.0, 1e300))
    assert "band" in str(e.value) and "--" not in str(e.value), e.value
    with pytest.raises(vf.InputError) as e:
        model.modes(4, shift_hz=1e300)
    assert "shift_hz" in str(e.value) and "--shift" not in str(e.value), e.value


def test_more_messages_name_python_keywords_and_arguments() -> None:
    """Messages from the engine, method, sweep and format checks named the command line's
    options (``--engine``); negative counts were PyO3's ``OverflowError`` naming nothing."""
    model = vf.Model(vf.read_mesh(BAR), fix=["xmin"])
    calls: list[tuple[Callable[[], object], str]] = [
        (lambda: model.modes(4, engine="arpack"), "engine"),
        (lambda: model.harmonic({"xmax": (0, 0, 1)}, sweep=(100, 5, 10), damping=0.02), "sweep"),
        (lambda: model.harmonic({"xmax": (0, 0, 1)}, freq=50, damping=0.02, method="fast"), "method"),
    ]
    for call, word in calls:
        with pytest.raises(vf.InputError) as e:
            call()
        assert word in str(e.value) and "--" not in str(e.value), e.value
    counts: list[tuple[Callable[[], object], str]] = [
        (lambda: model.modes(-1), "n"),
        (lambda: model.modes(4, block=-1), "block"),
        (lambda: model.modes(2**70), "n"),
        (lambda: model.harmonic({"xmax": (0, 0, 1)}, freq=50, damping=0.02, modes=-1), "modes"),
        (lambda: model.buckling(force={"xmax": (-1, 0, 0)}, n=0), "n"),
    ]
    for call, what in counts:
        with pytest.raises(vf.InputError) as e:
            call()
        assert what in str(e.value) and "whole number" in str(e.value), e.value


def test_a_group_name_that_the_text_form_would_change_is_refused() -> None:
    """A force on a group named "zmax " (trailing space) went to the group "zmax": the dict's
    names travel as GROUP=VALUE text, which trims and splits them. Such names are refused."""
    base = vf.read_mesh("box:0.2,0.05,0.02:8,2,2:hex8")
    m = base.to_meshio()
    m.cell_sets = {("zmax " if k == "xmax" else k): v for k, v in m.cell_sets.items()}
    model = vf.Model(vf.from_meshio(m), fix=["xmin"])
    with pytest.raises(vf.InputError) as e:
        model.static(force={"zmax ": (0, 0, 100)})
    assert "'zmax '" in str(e.value) and "spaces" in str(e.value), e.value
    with pytest.raises(vf.InputError) as e:
        vf.Model(base, couple={"x:min": "z"})
    assert "':'" in str(e.value), e.value
    with pytest.raises(vf.InputError) as e:
        vf.Model(base, spring={"2:2": (1e5,) * 6})
    assert "spring" in str(e.value) and "':'" in str(e.value), e.value


def test_results_print_as_a_summary() -> None:
    """``print(modes)`` dumped the shapes array (5 kB for 4 modes)."""
    model = vf.Model(vf.read_mesh(BAR), fix=["xmin"])
    r = repr(model.modes(4))
    assert r.startswith("<vibrofem Modes: 4 modes") and "complete" in r and len(r) < 200, r
    s = repr(model.static(force={"xmax": (0, 0, 10)}))
    assert "max displacement" in s and "MPa" in s and len(s) < 200, s
    h = repr(model.harmonic({"xmax": (0, 0, 1)}, freq=50, damping=0.02))
    assert h.startswith("<vibrofem Harmonic: 50 Hz") and len(h) < 200, h
    empty = vf.Mesh.from_arrays(np.zeros((0, 3)), {})
    assert "no cells" in repr(empty), repr(empty)
