"""The report page in a real browser: a freshly generated quick report's index.html, opened in
headless Chromium (Debian's `chromium` package; `.ci/run` installs it).

Checks: no console errors or failed loads, every figure (an <img> of figures/*.svg) decoded and
shown at a nonzero size within the page, Table III and one cell table per experiment present and
filled, nothing wider than the window. A pipeline with variants: the comparison page and a
variant's page at 1300 px, where the fit table and its caption must fit, and the variant's page
names the pipeline and the variant and links back. The comparison pages (the fixture's and the
committed reports/paper/index.html) open with the answer and the forest plot, both on the first
screen at 1300 × 900. Full-page screenshots are written to
target/report-screenshot.png (and -comparison, -variant) for a human to look at.

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
  title: document.title,
  images: [...document.images].map(i => {
    const r = i.getBoundingClientRect();
    return {src: i.getAttribute('src'), complete: i.complete, naturalWidth: i.naturalWidth,
            width: r.width, height: r.height, right: r.right, bottom: r.bottom};
  }),
  answer: (() => {
    const a = document.getElementById('answer');
    return a && {top: a.getBoundingClientRect().top, text: a.querySelector('p').textContent};
  })(),
  tables: [...document.querySelectorAll('table')].map(t => ({
    rows: t.tBodies.length ? [...t.tBodies].reduce((n, b) => n + b.rows.length, 0) : t.rows.length - 1,
    width: t.getBoundingClientRect().width, right: t.getBoundingClientRect().right})),
  captions: [...document.querySelectorAll('p.caption, caption')].map(c => c.getBoundingClientRect().right),
  overflowing: [...document.querySelectorAll('.scroll')].filter(d => d.scrollWidth > d.clientWidth + 1)
    .map(d => d.previousElementSibling?.textContent + ': ' + d.scrollWidth + ' px'),
  links: [...document.querySelectorAll('a')].map(a => a.getAttribute('href')),
  h3: document.querySelectorAll('h3').length,
  width: document.documentElement.scrollWidth,
  height: document.documentElement.scrollHeight,
})"""


def chromium_or_skip() -> str:
    exe = find_chromium()
    if exe is None:
        message = "Chromium not found (apt-get install chromium, or set $CHROMIUM)"
        if os.environ.get("CI") == "true":
            pytest.fail(message + "; CI must run this test", pytrace=False)
        pytest.skip(message)
    return exe


def render(exe: str, page_path: Path, width: int, shot_name: str) -> tuple[dict, list[dict], Path]:
    """Open `page_path` at `width` px; return the probe, the browser's events and the screenshot."""
    with tempfile.TemporaryDirectory(prefix="qsweep-chromium-") as profile:
        browser = Browser(exe, Path(profile))
        try:
            browser.open_page()
            browser.send("Emulation.setDeviceMetricsOverride",
                         {"width": width, "height": 900, "deviceScaleFactor": 1, "mobile": False})
            events: list[dict] = []
            browser.send("Page.navigate", {"url": page_path.as_uri()})
            browser.wait_for("Page.loadEventFired", events)
            page = json.loads(browser.send(
                "Runtime.evaluate", {"expression": PROBE, "returnByValue": True})["result"]["value"])
            # The whole page in one picture (up to Chromium's texture limit): a viewport as tall as it.
            browser.send("Emulation.setDeviceMetricsOverride",
                         {"width": width, "height": min(page["height"], 16000), "deviceScaleFactor": 1,
                          "mobile": False})
            shot = browser.send("Page.captureScreenshot", {"format": "png"})
            browser.drain(events)
        finally:
            browser.close()
    screenshot = target_dir() / shot_name
    screenshot.parent.mkdir(parents=True, exist_ok=True)
    screenshot.write_bytes(base64.b64decode(shot["data"]))
    return page, events, screenshot


def shapes(svg: Path) -> int:
    """Rectangles, paths and texts drawn by an SVG figure (it must show a heatmap or curves)."""
    import xml.etree.ElementTree as ET

    root = ET.parse(svg).getroot()
    return sum(1 for e in root.iter() if e.tag.rsplit("}", 1)[-1] in ("rect", "path", "polyline", "text"))


def check_fits(page: dict, width: int, screenshot: Path) -> None:
    assert page["width"] <= width, f"the page scrolls sideways at {width} px (screenshot: {screenshot})"
    assert page["overflowing"] == [], f"tables wider than the page at {width} px (they scroll sideways)"
    for t in page["tables"]:
        assert t["right"] <= width, f"a table overflows a {width} px window: {t}"
    for right in page["captions"]:
        assert right <= width, f"a caption overflows a {width} px window: {right}"
    for img in page["images"]:
        assert img["complete"] and img["naturalWidth"] > 0, f"image not decoded: {img}"
        assert img["width"] > 100 and img["height"] > 100, f"figure too small: {img}"
        assert img["right"] <= width, f"figure wider than the page: {img}"


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
    exe = chromium_or_skip()
    cells = pq.read_table(quick_report / "cells.parquet", columns=["system", "experiment"]).to_pylist()
    experiments = {(c["system"], c["experiment"]) for c in cells}
    systems = {c["system"] for c in cells}

    page, events, screenshot = render(exe, quick_report / "index.html", 1200, "report-screenshot.png")
    assert errors_in(events) == [], f"console errors (screenshot: {screenshot})"
    assert page["title"] == "qsweep report: quick"
    # Heatmaps and learning curves: every figure once, as a file the page links.
    assert sorted(i["src"] for i in page["images"]) == sorted(
        f"figures/{s}{k}.svg" for s in systems for k in ("", "-curves")
    )
    for img in page["images"]:
        assert shapes(quick_report / img["src"]) > 50, f"figure has no heatmap: {img}"
    check_fits(page, 1200, screenshot)
    # Table III and its uncertainty (the same rows), then one cell table per experiment; none empty.
    assert page["h3"] == len(experiments)
    assert len(page["tables"]) == 2 + len(experiments), page["tables"]
    assert page["tables"][0]["rows"] == 2 * len(experiments), "Table III: one row per experiment and algorithm"
    assert page["tables"][1]["rows"] == 2 * len(experiments), "its uncertainty: the same rows"
    assert all(t["rows"] > 0 and t["width"] > 0 for t in page["tables"]), page["tables"]


def check_opening(page: dict, screenshot: Path) -> None:
    """The comparison page opens with the answer and the forest plot, both on the first screen
    (900 px high)."""
    answer = page["answer"]
    assert answer and "Table III rows replicate" in answer["text"], answer
    forest = [i for i in page["images"] if i["src"] == "figures/forest.svg"]
    assert len(forest) == 1, page["images"]
    assert answer["top"] < 900 and forest[0]["bottom"] <= 900, \
        f"the answer and the forest plot are not on the first screen: {forest} (screenshot: {screenshot})"


def test_paper_comparison_opens_with_the_answer_on_the_first_screen() -> None:
    """The committed reports/paper/index.html at 1300 × 900: the answer and its figure first."""
    exe = chromium_or_skip()
    page, events, screenshot = render(exe, REPO_ROOT / "reports/paper/index.html", 1300,
                                      "report-screenshot-paper.png")
    assert errors_in(events) == [], f"console errors (screenshot: {screenshot})"
    check_opening(page, screenshot)
    assert page["answer"]["text"].startswith("Under the best-ranked declared variant, "), page["answer"]


@pytest.fixture(scope="module")
def variants_report(qsweep_bin: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("browser-variants")
    # Titles as long as paper.yaml's, which made the fit table overflow.
    text = (REPO_ROOT / "tests/fixtures/pipelines/variants.yaml").read_text()
    for short in ["The pipeline as written", "Crisp learning rate 0.05", "Episodes cut at 200 steps"]:
        assert short in text
        text = text.replace(short, f"{short}, with Gymnasium TimeLimits CartPole-v0 200, MountainCar-v0 200, random starts")
    pipeline = tmp / "variants.yaml"
    pipeline.write_text(text)
    out = subprocess.run(
        [str(qsweep_bin), "run", str(pipeline), "--quiet",
         "--cache", str(tmp / "cache"), "--out", str(tmp / "report")],
        capture_output=True, text=True, timeout=1200,
    )
    assert out.returncode == 0, out.stderr
    return tmp / "report"


def test_comparison_and_variant_pages_fit_a_1300_px_window(variants_report: Path) -> None:
    """Regression: the comparison page's fit table and its caption overflowed a 1300-px window, and
    a variant's page was titled by the pipeline alone, never naming its variant."""
    exe = chromium_or_skip()
    page, events, screenshot = render(exe, variants_report / "index.html", 1300,
                                      "report-screenshot-comparison.png")
    assert errors_in(events) == [], f"console errors (screenshot: {screenshot})"
    assert page["title"] == "qsweep variants: variants"
    assert page["tables"] and page["tables"][0]["rows"] == 3, "the fit table: one row per variant"
    assert len(page["captions"]) >= 1, "the fit table's caption"
    check_fits(page, 1300, screenshot)
    for v in ["as-written", "fast-crisp", "short-episodes"]:
        assert f"{v}/index.html" in page["links"], v
    check_opening(page, screenshot)

    page, events, screenshot = render(exe, variants_report / "fast-crisp" / "index.html", 1300,
                                      "report-screenshot-variant.png")
    assert errors_in(events) == [], f"console errors (screenshot: {screenshot})"
    assert page["title"] == "qsweep report: variants / fast-crisp"
    assert "../index.html" in page["links"], "a variant's page links back to the comparison"
    assert page["images"], "the variant's figures"
    check_fits(page, 1300, screenshot)
