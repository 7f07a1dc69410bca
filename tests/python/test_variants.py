"""Cross-checks of a pipeline with variants (tests/fixtures/pipelines/variants.yaml).

The binary runs the fixture into a temporary cache and report folder. Checks: the combined
cells.parquet / trials.parquet carry a `variant` column that pandas, polars and DuckDB read alike;
each variant's rows equal that variant's own report; a trial shared by two variants appears under
both; variants.csv is recomputed from each variant's table3.csv with the documented rules.
"""

from __future__ import annotations

import math
import subprocess
from pathlib import Path

import duckdb
import pandas as pd
import polars as pl
import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
VARIANTS = ["as-written", "fast-crisp", "short-episodes"]


@pytest.fixture(scope="module")
def report(qsweep_bin: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("variants")
    out = tmp / "report"
    subprocess.run(
        [
            str(qsweep_bin),
            "run",
            str(REPO_ROOT / "tests/fixtures/pipelines/variants.yaml"),
            "--cache",
            str(tmp / "cache"),
            "--out",
            str(out),
            "--quiet",
        ],
        check=True,
    )
    return out


def test_variant_column_reads_alike_in_pandas_polars_and_duckdb(report: Path) -> None:
    for name in ["cells.parquet", "trials.parquet"]:
        path = report / name
        pd_counts = pd.read_parquet(path, dtype_backend="pyarrow").groupby("variant").size().to_dict()
        pl_counts = dict(pl.read_parquet(path).group_by("variant").len().iter_rows())
        db_counts = dict(duckdb.sql(f"select variant, count(*) from '{path}' group by 1").fetchall())
        assert pd_counts == pl_counts == db_counts
        assert sorted(pd_counts) == VARIANTS
    cells = pd.read_parquet(report / "cells.parquet")
    assert (cells.groupby("variant").size() == 12).all(), "12 cells per variant"
    assert list(cells.columns[:2]) == ["variant", "system"]


def test_each_variants_rows_equal_its_own_report(report: Path) -> None:
    cells = pd.read_parquet(report / "cells.parquet")
    trials = pd.read_parquet(report / "trials.parquet")
    for v in VARIANTS:
        own = pd.read_parquet(report / v / "cells.parquet")
        mine = cells[cells["variant"] == v].drop(columns="variant").reset_index(drop=True)
        pd.testing.assert_frame_equal(mine, own.drop(columns="variant"), check_exact=True)
        own_t = pd.read_parquet(report / v / "trials.parquet")
        assert sorted(trials[trials["variant"] == v]["key"]) == sorted(own_t["key"])


def test_shared_trials_appear_under_each_variant_that_plans_them(report: Path) -> None:
    trials = pd.read_parquet(report / "trials.parquet")
    keys = {v: set(trials[trials["variant"] == v]["key"]) for v in VARIANTS}
    # fast-crisp changes only the crisp learning rate: the fuzzy experiment's 8 trials are shared.
    assert len(keys["as-written"] & keys["fast-crisp"]) == 8
    # short-episodes changes every trial.
    assert not keys["short-episodes"] & (keys["as-written"] | keys["fast-crisp"])
    assert trials.drop_duplicates("key").shape[0] == 24 + 16 + 24


def _verdict(r: pd.Series) -> str:
    se = math.sqrt(r["paper_std"] ** 2 / 10 + r["std"] ** 2 / r["n"])
    if abs(r["mean"] - r["paper_mean"]) <= 2 * se:
        return "replicates"
    if 0.5 <= r["mean"] / r["paper_mean"] <= 2:
        return "within 2x"
    return "no"
