"""Shared setup for the Python cross-checks of qsweep (Python only checks; the product is Rust)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
SCRIPTS_DIR = REPO_ROOT / "scripts"
if str(SCRIPTS_DIR) not in sys.path:
    sys.path.insert(0, str(SCRIPTS_DIR))


def _candidates() -> list[Path]:
    exe = "qsweep.exe" if os.name == "nt" else "qsweep"
    target_dirs = []
    if os.environ.get("CARGO_TARGET_DIR"):
        target_dirs.append(Path(os.environ["CARGO_TARGET_DIR"]))
    target_dirs.append(REPO_ROOT / "target")
    out = []
    for t in target_dirs:
        if not t.is_absolute():
            t = REPO_ROOT / t
        out += [t / "release" / exe, t / "debug" / exe]
    return out


def find_qsweep_bin() -> Path:
    """`$QSWEEP_BIN` if set, else the newer of target/release/qsweep and target/debug/qsweep.

    Fails the test (never skips) when no binary is found."""
    env = os.environ.get("QSWEEP_BIN")
    if env:
        p = Path(env)
        tried = [p] if p.is_absolute() else [Path.cwd() / p, REPO_ROOT / p]
        for c in tried:
            if c.is_file():
                return c
        pytest.fail(
            f"QSWEEP_BIN={env!r} does not name an existing file (tried: "
            + ", ".join(map(str, tried))
            + "). Run `cargo build --release` first, or point QSWEEP_BIN at the qsweep binary.",
            pytrace=False,
        )
    tried = _candidates()
    found = [c for c in tried if c.is_file()]
    if found:
        # The most recently built one: `cargo test` refreshes debug, `cargo build --release` release.
        return max(found, key=lambda c: c.stat().st_mtime)
    pytest.fail(
        "qsweep binary not found (tried: "
        + ", ".join(map(str, tried))
        + "). Run `cargo build --release` first, or set QSWEEP_BIN to the qsweep binary.",
        pytrace=False,
    )


@pytest.fixture(scope="session")
def qsweep_bin() -> Path:
    return find_qsweep_bin()
