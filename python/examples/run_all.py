"""Run every example and check it wrote its picture; with --refresh, into docs/img/gallery/ (the
pictures of docs/gallery.md), plus the screenshot of the built-in design's report.html in headless
Chromium (docs/img/report_design.png).

    python python/examples/run_all.py OUT_DIR       # CI: into a scratch folder
    python python/examples/run_all.py --refresh     # refresh the committed pictures
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
EXAMPLES = {
    "modes_gmsh_pyvista.py": "modes_gmsh_pyvista.png",
    "spring_stiffness.py": "spring_stiffness.png",
    "harmonic_frf.py": "harmonic_frf.png",
    "design_leaf_thickness.py": "design_leaf_thickness.png",
    "export_slepc.py": "export_slepc.png",
}


def report_screenshot(dest: Path) -> None:
    sys.path.insert(0, str(ROOT / "python" / "tests"))
    import browser

    import vibrofem as vf

    with tempfile.TemporaryDirectory() as tmp:
        r = vf.design(out=tmp)
        page = browser.open_report(r.html, width=1100, height=1400, screenshot=True)
    if page.problems():
        raise SystemExit(f"report.html: {page.problems()}")
    assert page.screenshot is not None
    dest.write_bytes(page.screenshot)
    print("wrote", dest)


def main() -> int:
    refresh = "--refresh" in sys.argv[1:]
    args = [a for a in sys.argv[1:] if a != "--refresh"]
    out = ROOT / "docs" / "img" / "gallery" if refresh else Path(args[0] if args else tempfile.mkdtemp())
    out.mkdir(parents=True, exist_ok=True)
    failed = []
    for script, picture in EXAMPLES.items():
        t = time.perf_counter()
        png = out / picture
        png.unlink(missing_ok=True)
        r = subprocess.run([sys.executable, str(HERE / script), str(out)], cwd=HERE, capture_output=True, text=True)
        ok = r.returncode == 0 and png.is_file() and png.stat().st_size > 1000
        print(f"{'ok  ' if ok else 'FAIL'} {script} ({time.perf_counter() - t:.1f} s)")
        for line in (r.stdout + r.stderr).strip().splitlines()[-6:]:
            print("     ", line)
        if not ok:
            failed.append(script)
    if refresh:
        report_screenshot(ROOT / "docs" / "img" / "report_design.png")
    print(f"{len(EXAMPLES) - len(failed)} passed, {len(failed)} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
