"""An exploratory search's comparison, recomputed in Python.

Two reports: the one `qsweep run tests/fixtures/pipelines/grid.yaml` writes (a 2 x 3 variant grid
beside `as-written`, one fit row, three held-out rows), and the committed
`pipelines/explore-ball-beam.yaml` search re-reported from the committed cache, both into
temporary folders;
set `$QSWEEP_EXPLORE_REPORT_DIR` and `$QSWEEP_EXPLORE_PIPELINE` to check another, e.g.
`reports/explore-ball-beam` and `pipelines/explore-ball-beam.yaml`.

From the combined `cells.parquet` (each variant's best cells) and the pipeline's `reference:` and
`exploratory:` blocks (read with PyYAML), the test recomputes, independently of qsweep's Rust:
every Table III row's verdict, each variant's tallies on the fit rows and on the held-out rows,
the ranking on the fit rows alone, and the held-out table of the chosen variant beside
`as-written`; then compares with `variants.csv` and `held_out.csv`.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
from pathlib import Path

import pandas as pd
import pytest
import yaml

REPO_ROOT = Path(__file__).resolve().parents[2]
FIXTURE = REPO_ROOT / "tests" / "fixtures" / "pipelines" / "grid.yaml"


@pytest.fixture(scope="module", params=["fixture", "explore-ball-beam"])
def search(request, qsweep_bin: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    given = os.environ.get("QSWEEP_EXPLORE_REPORT_DIR")
    if given:
        pipeline = Path(os.environ["QSWEEP_EXPLORE_PIPELINE"])
        d = Path(given)
        return (d if d.is_absolute() else REPO_ROOT / d), (pipeline if pipeline.is_absolute() else REPO_ROOT / pipeline)
    if request.param == "explore-ball-beam":
        # The committed search, re-reported from the committed cache (runs nothing).
        pipeline = REPO_ROOT / "pipelines" / "explore-ball-beam.yaml"
        tmp = tmp_path_factory.mktemp("explore-ball-beam")
        out = subprocess.run(
            [str(qsweep_bin), "report", str(pipeline), "--cache", str(REPO_ROOT / "cache"),
             "--out", str(tmp / "report"), "--formats", "csv,cells"],
            capture_output=True, text=True, timeout=600,
        )
        assert out.returncode == 0, out.stderr
        assert "42120 of 42120 planned trials present" in out.stdout, out.stdout
        return tmp / "report", pipeline
    tmp = tmp_path_factory.mktemp("explore")
    out = subprocess.run(
        [str(qsweep_bin), "run", str(FIXTURE), "--json", "--cache", str(tmp / "cache"),
         "--out", str(tmp / "report"), "--formats", "csv,cells"],
        capture_output=True, text=True, timeout=600,
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["executed"] == 112
    return tmp / "report", FIXTURE


def verdict(m: float, s: float | None, n: int, rm: float, rs: float) -> str:
    """The replication rule of REPLICATION.md, written again."""
    if s is not None and not math.isnan(s) and abs(m - rm) <= 2 * math.sqrt(rs * rs / 10 + s * s / n):
        return "replicates"
    if rm > 0 and 0.5 <= m / rm <= 2:
        return "within 2×"
    return "does not replicate"


def references(pipeline: Path) -> tuple[dict, list]:
    spec = yaml.safe_load(pipeline.read_text())
    refs = {}
    for system, sec in spec["systems"].items():
        for e in sec["experiments"]:
            for alg, r in (e.get("reference") or {}).items():
                refs[(system, str(e["id"]), alg)] = r
    return refs, spec["exploratory"]["fit_rows"]


def is_fit(row: tuple, fit_rows: list) -> bool:
    system, exp, alg = row
    return any(
        f["system"] == system and str(f.get("experiment", exp)) == exp and f.get("algorithm", alg) == alg
        for f in fit_rows
    )


def test_fit_and_held_out_scores_recomputed(search) -> None:
    d, pipeline = search
    refs, fit_rows = references(pipeline)
    cells = pd.read_parquet(d / "cells.parquet")
    best = cells[cells["best"]]
    tallies = {}
    rows_of = {}
    for variant in dict.fromkeys(cells["variant"]):
        t = {"fit": [0, 0, 0, 0, []], "held_out": [0, 0, 0, 0, []]}
        rows = {}
        for _, c in best[best["variant"] == variant].iterrows():
            key = (c["system"], str(c["experiment"]), c["algorithm"])
            if key not in refs:
                continue
            r = refs[key]
            v = verdict(c["mean"], c["std"], int(c["n"]), r["mean"], r["std"])
            cfg = [int(c[x]) for x in ["x", "x_dot", "theta", "theta_dot"] if not pd.isna(c[x])] + [int(c["actions"])]
            match = "resolution" in r and "actions" in r and cfg == r["resolution"] + [r["actions"]]
            part = t["fit" if is_fit(key, fit_rows) else "held_out"]
            part[0] += 1
            part[1] += v == "replicates"
            part[2] += v == "within 2×"
            part[3] += match
            part[4].append(math.log(c["mean"] / r["mean"]))
            rows[key] = (c["mean"], c["std"], int(c["n"]), v)
        tallies[variant] = t
        rows_of[variant] = rows
    got = pd.read_csv(d / "variants.csv")
    assert got["exploratory"].all()
    for _, g in got.iterrows():
        t = tallies[g["variant"]]
        for p in ("fit", "held_out"):
            rows, rep, w2, cfg, logs = t[p]
            assert (g[f"{p}_rows"], g[f"{p}_replicating"], g[f"{p}_within_2x"], g[f"{p}_config_match"]) == (rows, rep, w2, cfg), (g["variant"], p)
            assert math.isclose(g[f"{p}_geo_mean_ratio"], math.exp(sum(logs) / len(logs)), rel_tol=1e-12)
    # The ranking uses the fit rows only: replicating, within 2x, config matches, |ln geo mean|,
    # then the pipeline's order (listed variants first, then the grid in product order).
    order = list(dict.fromkeys(cells["variant"]))
    def key(v):
        rows, rep, w2, cfg, logs = tallies[v]["fit"]
        return (-rep, -w2, -cfg, abs(sum(logs) / len(logs)) if logs else math.inf, order.index(v))
    assert list(got["variant"]) == sorted(order, key=key)
    # The held-out table: the chosen variant beside as-written, row by row.
    held = pd.read_csv(d / "held_out.csv")
    chosen = got["variant"].iloc[0]
    assert len(held) == sum(1 for k in refs if not is_fit(k, fit_rows))
    for _, h in held.iterrows():
        k = next(k for k in rows_of[chosen] if k[1] == str(h["experiment"]) and k[2] == h["algorithm"]
                 and h["system"].lower().replace(" ", "-") == k[0])
        assert (h["chosen_n"], h["chosen_verdict"]) == (rows_of[chosen][k][2], rows_of[chosen][k][3])
        assert math.isclose(h["chosen_mean"], rows_of[chosen][k][0])
        assert (h["as_written_n"], h["as_written_verdict"]) == (rows_of["as-written"][k][2], rows_of["as-written"][k][3])
