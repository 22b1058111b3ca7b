"""Open a report.html in headless Chromium through the DevTools protocol and say what a reader sees.

Used by python/tests/test_report_browser.py and python/examples/refresh_pictures.py. Needs Debian's
``chromium`` (bash validation/setup_browser.sh) and ``websocket-client`` (validation/requirements.txt).
The browser only ever talks to this process over the loopback interface and reads a local file.
"""

from __future__ import annotations

import base64
import json
import shutil
import subprocess
import tempfile
import threading
import time
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional

#: What the page is asked once it has loaded: the figures with their size and how many of their
#: shapes have a nonzero box, the renderer's "figure … not found" notes, the tables' order.
_PROBE = r"""
(() => {
  const figs = [...document.querySelectorAll('figure')].map(f => {
    const s = f.querySelector('svg');
    const r = (s || f).getBoundingClientRect();
    let drawn = 0;
    if (s) for (const e of s.querySelectorAll('path,line,polyline,polygon,rect,circle,ellipse,text')) {
      try { const b = e.getBBox(); if (b.width > 0 || b.height > 0) drawn++; } catch (err) {}
    }
    return {id: f.id, svg: !!s, width: r.width, height: r.height, drawn: drawn};
  });
  const missing = [...document.querySelectorAll('p.fail')].map(p => p.textContent);
  const tables = [...document.querySelectorAll('table')].map(t => t.className);
  const checks = document.querySelector('table.checks');
  const firstFig = document.querySelector('figure');
  const checksFirst = !!checks && (!firstFig ||
      !!(checks.compareDocumentPosition(firstFig) & Node.DOCUMENT_POSITION_FOLLOWING));
  return JSON.stringify({title: document.title, figures: figs, missing: missing, tables: tables,
                         checks_before_figures: checksFirst,
                         checks_rows: checks ? checks.rows.length - 1 : 0});
})()
"""


@dataclass
class Page:
    """What the browser showed."""

    title: str
    figures: List[Dict[str, Any]]
    missing: List[str]
    tables: List[str]
    checks_before_figures: bool
    checks_rows: int
    #: Console errors, uncaught exceptions and failed loads (Log/Runtime events of level error).
    errors: List[str] = field(default_factory=list)
    screenshot: Optional[bytes] = None

    def problems(self) -> List[str]:
        """Why the page is not as a reader should see it (empty: it is)."""
        out = [f"console: {e}" for e in self.errors]
        out += [f"missing: {m}" for m in self.missing]
        if not self.figures:
            out.append("no figure in the report")
        for f in self.figures:
            if not f["svg"]:
                out.append(f"figure {f['id']!r} has no drawing")
            elif f["width"] <= 0 or f["height"] <= 0:
                out.append(f"figure {f['id']!r} renders at {f['width']} × {f['height']} px")
            elif f["drawn"] == 0:
                out.append(f"figure {f['id']!r} draws nothing")
        if not self.tables or self.tables[0] != "checks":
            out.append(f"the first table is {self.tables[:1]}, not the check table")
        if not self.checks_before_figures:
            out.append("the check table comes after a figure")
        return out


def find_chromium() -> Optional[str]:
    for name in ("chromium", "chromium-browser"):
        p = shutil.which(name)
        if p:
            return p
    return None


class _Cdp:
    """A DevTools session on one page: numbered commands, events kept in arrival order."""

    def __init__(self, url: str) -> None:
        import websocket  # websocket-client

        self.ws = websocket.create_connection(url, timeout=60, suppress_origin=True)
        self.next_id = 0
        self.events: List[Dict[str, Any]] = []

    def call(self, method: str, **params: Any) -> Dict[str, Any]:
        self.next_id += 1
        mid = self.next_id
        self.ws.send(json.dumps({"id": mid, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == mid:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return dict(msg.get("result", {}))
            if "method" in msg:
                self.events.append(msg)

    def wait_for(self, method: str, timeout: float) -> None:
        end = time.monotonic() + timeout
        while not any(e["method"] == method for e in self.events):
            if time.monotonic() > end:
                raise TimeoutError(f"no {method} within {timeout} s")
            msg = json.loads(self.ws.recv())
            if "method" in msg:
                self.events.append(msg)

    def close(self) -> None:
        self.ws.close()


def _devtools_port(proc: "subprocess.Popen[str]", timeout: float) -> int:
    """The port Chromium chose (--remote-debugging-port=0), from its 'DevTools listening' line."""
    found: List[int] = []
    lines: List[str] = []

    def read() -> None:
        assert proc.stderr is not None
        for line in proc.stderr:
            lines.append(line)
            if "DevTools listening on ws://" in line and not found:
                found.append(int(line.split("ws://", 1)[1].split("/", 1)[0].rsplit(":", 1)[1]))

    threading.Thread(target=read, daemon=True).start()
    end = time.monotonic() + timeout
    while not found:
        if proc.poll() is not None or time.monotonic() > end:
            raise RuntimeError("chromium did not start its DevTools server:\n" + "".join(lines[-20:]))
        time.sleep(0.05)
    return found[0]


def open_report(html: Path, width: int = 1100, height: int = 1400, screenshot: bool = False) -> Page:
    """Load ``html`` in headless Chromium and probe it (and take a PNG of the first screen)."""
    browser = find_chromium()
    if browser is None:
        raise FileNotFoundError("chromium not installed (bash validation/setup_browser.sh)")
    profile = tempfile.mkdtemp(prefix="vibrofem-chromium-")
    cmd = [
        browser,
        "--headless",
        "--no-sandbox",  # CI runs as root
        "--disable-gpu",
        "--no-first-run",
        "--hide-scrollbars",
        "--remote-debugging-address=127.0.0.1",
        "--remote-debugging-port=0",
        f"--user-data-dir={profile}",
        f"--window-size={width},{height}",
        "about:blank",
    ]
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        port = _devtools_port(proc, 60.0)
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=30) as r:
            targets = json.load(r)
        page = next(t for t in targets if t.get("type") == "page")
        cdp = _Cdp(page["webSocketDebuggerUrl"])
        try:
            for domain in ("Page", "Runtime", "Log"):
                cdp.call(f"{domain}.enable")
            cdp.call("Page.navigate", url=Path(html).resolve().as_uri())
            cdp.wait_for("Page.loadEventFired", 60.0)
            got = cdp.call("Runtime.evaluate", expression=_PROBE, returnByValue=True)
            probe = json.loads(got["result"]["value"])
            png = None
            if screenshot:
                shot = cdp.call("Page.captureScreenshot", format="png")
                png = base64.b64decode(shot["data"])
            errors = _errors(cdp.events)
        finally:
            cdp.close()
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        shutil.rmtree(profile, ignore_errors=True)
    return Page(errors=errors, screenshot=png, **probe)


def _errors(events: List[Dict[str, Any]]) -> List[str]:
    out = []
    for e in events:
        p = e.get("params", {})
        if e["method"] == "Runtime.exceptionThrown":
            d = p.get("exceptionDetails", {})
            out.append(str(d.get("exception", {}).get("description") or d.get("text")))
        elif e["method"] == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            out.append(" ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", [])))
        elif e["method"] == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
            ent = p["entry"]
            out.append(f"{ent.get('text')} {ent.get('url', '')}".strip())
    return out


if __name__ == "__main__":  # pragma: no cover - a manual check: python browser.py report.html
    import sys

    pg = open_report(Path(sys.argv[1]))
    print(json.dumps({k: v for k, v in pg.__dict__.items() if k != "screenshot"}, indent=1))
    print("problems:", pg.problems() or "none")
    sys.exit(1 if pg.problems() else 0)
