"""A program pipeline's rows read as a user reads them (docs/programs.md, typed rows): polars and
pandas load `trials.parquet` and the cache's `_programs/` folder with the declared types and no
JSON parsing, every cell's rows are there, and the metrics are the program's own numbers,
recomputed here by running the program by hand."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pandas as pd
import polars as pl

from conftest import REPO_ROOT


def test_program_rows_are_typed_for_polars_and_pandas(qsweep_bin, tmp_path):
    for f in ("sgd.py", "sgd.yaml"):
        (tmp_path / "examples" / "programs").mkdir(parents=True, exist_ok=True)
        shutil.copy(REPO_ROOT / "examples" / "programs" / f, tmp_path / "examples" / "programs" / f)
    run = subprocess.run(
        [str(qsweep_bin), "run", "examples/programs/sgd.yaml", "--cache", "cache", "--jobs", "2"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    t = pl.read_parquet(tmp_path / "reports" / "sgd" / "trials.parquet")
    assert t.height == 8  # 2 learning rates x 2 batch sizes x 2 seeds
    assert t.schema["lr"] == pl.Float64 and t.schema["batch"] == pl.Int64
    assert t.schema["loss"] == pl.Float64 and t.schema["steps"] == pl.Int64
    assert t.schema["seed"] == pl.UInt64 and set(t["status"]) == {"ok"}
    assert sorted(t.select("lr", "batch").unique().rows()) == [(0.1, 8), (0.1, 64), (0.3, 8), (0.3, 64)]
    # The cache's folder holds the same rows, and reading the cache folder as engine rows does not
    # pick them up (the leading underscore).
    cached = pl.read_parquet(tmp_path / "cache" / "_programs" / "*" / "seg-*.parquet")
    assert sorted(cached["key"]) == sorted(t["key"])
    # pandas too, with the same dtypes.
    p = pd.read_parquet(tmp_path / "reports" / "sgd" / "trials.parquet")
    assert str(p["steps"].dtype) == "int64" and str(p["loss"].dtype) == "float64"
    # Each row holds what the program prints for its params and seed.
    for row in t.iter_rows(named=True):
        config = {"lr": row["lr"], "batch": row["batch"], "seed": row["seed"]}
        out = subprocess.run(
            [sys.executable, "examples/programs/sgd.py"],
            cwd=tmp_path,
            input=json.dumps(config),
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip().splitlines()[-1]
        assert json.loads(out) == {"loss": row["loss"], "steps": row["steps"]}


NOISY = """import json, random, sys
c = json.load(sys.stdin)
r = random.Random(c["seed"])
score = c["scale"] * (10.0 * c["bins"] + 100.0 * c["alpha"]) + r.gauss(0.0, 3.0)
curve = [score / (k + 1) + r.random() for k in range(5 + c["seed"] % 3)]
print(json.dumps({"score": score, "steps": int(score) // 2, "ok": score > 40.0, "curve": curve}))
"""

NOISY_YAML = """name: noisy
seeds: 6
program:
  command: [{python}, noisy.py]
  inputs: [noisy.py]
  metrics: {{ score: float, steps: int, ok: bool, curve: list<float> }}
  objective: {{ metric: score, goal: minimize }}
params: {{ bins: 4, alpha: 0.1, scale: 1.0 }}
experiments:
  - {{ id: grid, title: "<b>&x", vary: {{ bins: [2, 4, 6], alpha: [0.1, 0.3] }} }}
  - {{ id: line, vary: {{ bins: [1, 3, 5, 7] }} }}
variants:
  - {{ id: wide, set: {{ params.scale: 2.0 }} }}
"""


def test_program_report_cells_recomputed_from_trials_parquet(qsweep_bin, tmp_path):
    """Every cell of cells.parquet (n, mean, std, the 95 % bootstrap interval) and every
    experiment's best cell, recomputed from trials.parquet with pandas and scipy, not qsweep."""
    import numpy as np
    from scipy import stats

    (tmp_path / "noisy.py").write_text(NOISY)
    (tmp_path / "noisy.yaml").write_text(NOISY_YAML.format(python=sys.executable))
    run = subprocess.run(
        [str(qsweep_bin), "run", "noisy.yaml", "--cache", "cache", "--jobs", "2"],
        cwd=tmp_path, capture_output=True, text=True, timeout=300,
    )
    assert run.returncode == 0, run.stderr
    rep = tmp_path / "reports" / "noisy"
    trials = pd.read_parquet(rep / "trials.parquet")
    cells = pd.read_parquet(rep / "cells.parquet")
    metrics = ["score", "steps", "ok"]
    # 3 x 2 + 4 cells of the one variant (a pipeline with variants runs its variants), one row per
    # scalar metric; the list metric has none.
    assert len(cells) == 10 * len(metrics) and set(cells["metric"]) == set(metrics)
    keys = ["variant", "experiment", "bins", "alpha"]
    for (variant, exp, bins, alpha), g in trials.groupby(keys, dropna=False):
        mine = cells[(cells["experiment"] == exp) & (cells["bins"] == bins) & (cells["alpha"] == alpha)
                     & (cells["variant"].fillna("") == ("" if pd.isna(variant) else variant))]
        for m in metrics:
            row = mine[mine["metric"] == m]
            assert len(row) == 1, (variant, exp, bins, alpha, m)
            row = row.iloc[0]
            x = g[m].astype(float).to_numpy()
            assert row["n"] == len(x) == 6 and row["planned"] == 6 and row["failed"] == 0
            assert abs(row["mean"] - x.mean()) <= 1e-9 * max(1.0, abs(x.mean()))
            assert abs(row["std"] - x.std(ddof=1)) <= 1e-9 * max(1.0, x.std(ddof=1))
            # Percentile bootstrap of the mean: scipy's resamples are not ours, so the two ends
            # agree within a share of the standard error, not to the bit.
            se = x.std(ddof=1) / np.sqrt(len(x))
            if se == 0:
                assert row["ci_lo"] == row["ci_hi"] == x.mean()
                continue
            ref = stats.bootstrap((x,), np.mean, method="percentile", n_resamples=20000,
                                  random_state=np.random.default_rng(1)).confidence_interval
            assert abs(row["ci_lo"] - ref.low) <= 0.3 * se, (m, row["ci_lo"], ref.low, se)
            assert abs(row["ci_hi"] - ref.high) <= 0.3 * se, (m, row["ci_hi"], ref.high, se)
    # The best cell of each experiment: the lowest mean score (the objective), the first of equals.
    score = cells[cells["metric"] == "score"]
    for _, g in score.groupby(["variant", "experiment"], dropna=False):
        assert g["best"].sum() == 1
        assert g.loc[g["best"], "mean"].iloc[0] == g["mean"].min()
    # The pages name every file, and a user's text is escaped, never markup.
    html = (rep / "index.html").read_text()
    assert "<b>&x" not in html and "&lt;b&gt;&amp;x" in html
    for f in ["figures/wide--grid.svg", "figures/wide--line.svg", "figures/wide--grid--curve.svg"]:
        assert (rep / f).is_file() and f in html and f in (rep / "README.md").read_text(), f
