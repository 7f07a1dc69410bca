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
