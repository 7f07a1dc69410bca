"""Every Python snippet of README.md and the guide (docs/**/*.md) runs, in the test venv.

The ```python blocks of one file run in order in one namespace (a later block may use an earlier
block's imports), in a scratch directory that looks like a checkout after
`qsweep run pipelines/paper.yaml`: `cache/` is the committed cache (linked, read only) and
`reports/paper/trials.parquet` is the combined trial table of a small pipeline with variants
(tests/fixtures/pipelines/variants.yaml), run by the binary, so the snippets meet the same columns
and types as on the paper's report without its 45 MB. A failing snippet fails naming FILE:LINE.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import traceback
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
FENCE = re.compile(r"^(\s*)```python\s*$")


def python_blocks(path: Path) -> list[tuple[int, str]]:
    """(first line, code) of each ```python block of `path`, its list-item indentation removed."""
    blocks, lines = [], path.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if m:
            indent, start, body = len(m.group(1)), i + 2, []
            i += 1
            while i < len(lines) and lines[i].strip() != "```":
                body.append(lines[i][indent:] if lines[i][:indent].isspace() else lines[i])
                i += 1
            blocks.append((start, "\n".join(body) + "\n"))
        i += 1
    return blocks


def documents() -> list[Path]:
    docs = [REPO_ROOT / "README.md", *sorted((REPO_ROOT / "docs").rglob("*.md"))]
    return [d for d in docs if python_blocks(d)]


@pytest.fixture(scope="module")
def checkout(qsweep_bin: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("docs")
    (root / "cache").symlink_to(REPO_ROOT / "cache")
    subprocess.run(
        [
            str(qsweep_bin),
            "run",
            str(REPO_ROOT / "tests/fixtures/pipelines/variants.yaml"),
            "--cache",
            str(root / "scratch-cache"),
            "--out",
            str(root / "reports" / "paper"),
            "--quiet",
        ],
        check=True,
    )
    # A small program pipeline named as docs/programs.md's, for its snippet on reports/my-sweep.
    (root / "fake_agent.py").write_text(
        "import json, sys\n"
        "c = json.load(sys.stdin)\n"
        "episodes = 50 + 10 * c['bins'] + (c['seed'] * 7) % 13 - int(100 * c['alpha'])\n"
        "print(json.dumps({'episodes': episodes, 'solved': episodes < 100}))\n"
    )
    (root / "my-sweep.yaml").write_text(
        "name: my-sweep\n"
        "seeds: 3\n"
        "program:\n"
        f"  command: [{sys.executable}, fake_agent.py]\n"
        "  metrics: { episodes: int, solved: bool }\n"
        "params: { bins: 6, alpha: 0.1 }\n"
        "experiments:\n"
        "  - { id: bins-alpha, vary: { bins: [2, 4, 6], alpha: [0.1, 0.2] } }\n"
    )
    subprocess.run(
        [str(qsweep_bin), "run", "my-sweep.yaml", "--cache", "scratch-cache", "--quiet"],
        cwd=root,
        check=True,
    )
    assert (root / "reports/my-sweep/trials.parquet").is_file()
    return root


def test_the_guide_has_python_snippets() -> None:
    assert sum(len(python_blocks(d)) for d in documents()) >= 4


@pytest.mark.parametrize("doc", documents(), ids=lambda p: str(p.relative_to(REPO_ROOT)))
def test_every_python_snippet_runs(doc: Path, checkout: Path) -> None:
    namespace: dict = {"__name__": "__doc_snippet__"}
    cwd = os.getcwd()
    os.chdir(checkout)
    try:
        for line, code in python_blocks(doc):
            where = f"{doc.relative_to(REPO_ROOT)}:{line}"
            try:
                exec(compile(code, where, "exec"), namespace)
            except Exception:  # noqa: BLE001 - any failure of a snippet is the test's failure
                pytest.fail(f"{where}: the snippet fails:\n{traceback.format_exc()}", pytrace=False)
    finally:
        os.chdir(cwd)
