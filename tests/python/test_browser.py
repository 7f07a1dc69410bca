"""The report page in a real browser: a freshly generated quick report's index.html, opened in
headless Chromium (Debian's `chromium` package; `.ci/run` installs it).

Checks: no console errors or failed loads, every <img> decoded (naturalWidth > 0), every inline
<svg> figure present with a nonzero size, Table III and one cell table per experiment present and
filled. The full-page screenshot is written to target/report-screenshot.png for a human to look at.

Chromium is driven over the DevTools protocol through `--remote-debugging-pipe` (JSON messages
separated by NUL bytes on file descriptors 3 and 4), so no websocket client or open port is needed.
Without Chromium the test is skipped, except under CI=true, where it fails.
"""

from __future__ import annotations

import base64
import json
import os
import queue
import shutil
import subprocess
import tempfile
import threading
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
TIMEOUT = 180.0  # seconds for any one DevTools answer or the page load (CI machines are slow)

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--remote-debugging-pipe",
]


def find_chromium() -> str | None:
    env = os.environ.get("CHROMIUM")
    if env:
        return env
    for name in ["chromium", "chromium-browser", "google-chrome"]:
        found = shutil.which(name)
        if found:
            return found
    return "/usr/bin/chromium" if Path("/usr/bin/chromium").is_file() else None


def target_dir() -> Path:
    t = Path(os.environ.get("CARGO_TARGET_DIR", "target"))
    return t if t.is_absolute() else REPO_ROOT / t


class Browser:
    """Headless Chromium with one page, spoken to over the DevTools pipe."""

    def __init__(self, exe: str, profile: Path):
        # fd 3 (Chromium reads commands) is our stdin pipe, fd 4 (it writes answers) our stdout pipe.
        self.proc = subprocess.Popen(
            ["sh", "-c", 'exec "$0" "$@" 3<&0 4>&1 0</dev/null 1>&2', exe, *FLAGS,
             f"--user-data-dir={profile}", "about:blank"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        )
        self.next_id = 0
        self.answers: dict[int, dict] = {}
        self.events: queue.Queue[dict] = queue.Queue()
        self.cond = threading.Condition()
        self.stderr: list[bytes] = []
        threading.Thread(target=self._read, daemon=True).start()
        threading.Thread(target=lambda: self.stderr.extend(self.proc.stderr), daemon=True).start()
        self.session: str | None = None

    def _read(self) -> None:
        buf = b""
        while chunk := self.proc.stdout.read1(1 << 16):
            buf += chunk
            *messages, buf = buf.split(b"\0")
            for raw in messages:
                msg = json.loads(raw)
                if "id" in msg:
                    with self.cond:
                        self.answers[msg["id"]] = msg
                        self.cond.notify_all()
                else:
                    self.events.put(msg)
        with self.cond:
            self.cond.notify_all()

    def send(self, method: str, params: dict | None = None, session: bool = True) -> dict:
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session and self.session:
            msg["sessionId"] = self.session
        self.proc.stdin.write(json.dumps(msg).encode() + b"\0")
        self.proc.stdin.flush()
        deadline = time.monotonic() + TIMEOUT
        with self.cond:
            while self.next_id not in self.answers:
                left = deadline - time.monotonic()
                if left <= 0 or self.proc.poll() is not None:
                    raise AssertionError(f"no answer to {method} from Chromium: {self.log()}")
                self.cond.wait(left)
            answer = self.answers.pop(self.next_id)
        assert "error" not in answer, f"{method}: {answer['error']}"
        return answer["result"]

    def log(self) -> str:
        return b"".join(self.stderr).decode(errors="replace")[-3000:]

    def open_page(self) -> None:
        target = self.send("Target.createTarget", {"url": "about:blank"}, session=False)["targetId"]
        self.session = self.send(
            "Target.attachToTarget", {"targetId": target, "flatten": True}, session=False)["sessionId"]
        for domain in ["Page", "Runtime", "Log"]:
            self.send(f"{domain}.enable")

    def wait_for(self, method: str, seen: list[dict]) -> None:
        deadline = time.monotonic() + TIMEOUT
        while True:
            left = deadline - time.monotonic()
            assert left > 0, f"Chromium never sent {method}: {self.log()}"
            try:
                ev = self.events.get(timeout=left)
            except queue.Empty:
                continue
            seen.append(ev)
            if ev["method"] == method:
                return

    def drain(self, seen: list[dict]) -> None:
        while True:
            try:
                seen.append(self.events.get_nowait())
            except queue.Empty:
                return

    def close(self) -> None:
        try:
            self.send("Browser.close", session=False)
            self.proc.wait(timeout=10)
        except Exception:
            self.proc.kill()
            self.proc.wait()


def errors_in(events: list[dict]) -> list[str]:
    out = []
    for ev in events:
        p = ev.get("params", {})
        if ev["method"] == "Runtime.exceptionThrown":
            out.append(f"exception: {p['exceptionDetails'].get('text')}")
        elif ev["method"] == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            out.append("console.error: " + " ".join(str(a.get("value", a.get("description"))) for a in p["args"]))
        elif ev["method"] == "Log.entryAdded" and p["entry"]["level"] == "error":
            e = p["entry"]
            out.append(f"{e['source']}: {e['text']} {e.get('url', '')}")
    return out


# Everything the page shows, measured in the page itself.
PROBE = """JSON.stringify({
  images: [...document.images].map(i => ({src: i.getAttribute('src'), complete: i.complete,
                                          naturalWidth: i.naturalWidth, width: i.width})),
  svgs: [...document.querySelectorAll('figure > svg')].map(s => {
    const r = s.getBoundingClientRect();
    return {label: s.getAttribute('aria-label'), width: r.width, height: r.height,
            shapes: s.querySelectorAll('rect, polyline, text').length};
  }),
  tables: [...document.querySelectorAll('table')].map(t => ({
    rows: t.tBodies.length ? [...t.tBodies].reduce((n, b) => n + b.rows.length, 0) : t.rows.length - 1,
    width: t.getBoundingClientRect().width})),
  overflowing: [...document.querySelectorAll('.scroll')].filter(d => d.scrollWidth > d.clientWidth + 1)
    .map(d => d.previousElementSibling?.textContent + ': ' + d.scrollWidth + ' px'),
  h3: document.querySelectorAll('h3').length,
  width: document.documentElement.scrollWidth,
  height: document.documentElement.scrollHeight,
})"""


@pytest.fixture(scope="module")
def quick_report(qsweep_bin: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("browser")
    out = subprocess.run(
        [str(qsweep_bin), "run", str(REPO_ROOT / "pipelines" / "quick.yaml"), "--quiet",
         "--cache", str(tmp / "cache"), "--out", str(tmp / "report")],
        capture_output=True, text=True, timeout=1200,
    )
    assert out.returncode == 0, out.stderr
    return tmp / "report"


def test_report_page_renders_in_chromium(quick_report: Path) -> None:
    exe = find_chromium()
    if exe is None:
        message = "Chromium not found (apt-get install chromium, or set $CHROMIUM)"
        if os.environ.get("CI") == "true":
            pytest.fail(message + "; CI must run this test", pytrace=False)
        pytest.skip(message)

    cells = pq.read_table(quick_report / "cells.parquet", columns=["system", "experiment"]).to_pylist()
    experiments = {(c["system"], c["experiment"]) for c in cells}
    systems = {c["system"] for c in cells}

    with tempfile.TemporaryDirectory(prefix="qsweep-chromium-") as profile:
        browser = Browser(exe, Path(profile))
        try:
            browser.open_page()
            browser.send("Emulation.setDeviceMetricsOverride",
                         {"width": 1200, "height": 900, "deviceScaleFactor": 1, "mobile": False})
            events: list[dict] = []
            browser.send("Page.navigate", {"url": (quick_report / "index.html").as_uri()})
            browser.wait_for("Page.loadEventFired", events)
            page = json.loads(browser.send(
                "Runtime.evaluate", {"expression": PROBE, "returnByValue": True})["result"]["value"])
            # The whole page in one picture (up to Chromium's texture limit): a viewport as tall as it.
            browser.send("Emulation.setDeviceMetricsOverride",
                         {"width": 1200, "height": min(page["height"], 16000), "deviceScaleFactor": 1,
                          "mobile": False})
            shot = browser.send("Page.captureScreenshot", {"format": "png"})
            browser.drain(events)
        finally:
            browser.close()

    screenshot = target_dir() / "report-screenshot.png"
    screenshot.parent.mkdir(parents=True, exist_ok=True)
    screenshot.write_bytes(base64.b64decode(shot["data"]))

    assert errors_in(events) == [], f"console errors (screenshot: {screenshot})"
    for img in page["images"]:
        assert img["complete"] and img["naturalWidth"] > 0, f"image not decoded: {img}"
    assert len(page["svgs"]) == 2 * len(systems), page["svgs"]  # heatmaps and learning curves
    for svg in page["svgs"]:
        assert svg["width"] > 100 and svg["height"] > 100, f"figure too small: {svg}"
        assert svg["width"] <= 1200, f"figure wider than the page: {svg}"
        assert svg["shapes"] > 50, f"figure has no heatmap: {svg}"
    # Table III, then one cell table per experiment; none empty.
    assert page["h3"] == len(experiments)
    assert len(page["tables"]) == 1 + len(experiments), page["tables"]
    assert page["tables"][0]["rows"] == 2 * len(experiments), "Table III: one row per experiment and algorithm"
    assert all(t["rows"] > 0 and t["width"] > 0 for t in page["tables"]), page["tables"]
    assert page["width"] <= 1200, "the page scrolls sideways"
    assert page["overflowing"] == [], "tables wider than the page at 1200 px (they scroll sideways)"
