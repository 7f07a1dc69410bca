"""Cross-checks of a qsweep report directory with pandas, polars and DuckDB.

The report is the one `qsweep run pipelines/quick.yaml` writes, made here with the binary into a
temporary cache and report folder; set `$QSWEEP_REPORT_DIR` to check an existing report instead
(e.g. `reports/paper`, relative paths from the repository root).

Checks: both Parquet files load in all three libraries with the documented types and the same
row counts; every cell's n, successes, mean and std (ddof = 1) recomputed from trials.parquet match
cells.parquet; `episodes_counted` follows the censoring rule; table3.csv rows are the best cells.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
from pathlib import Path

import duckdb
import pandas as pd
import polars as pl
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
REPORT_DIR = Path()  # set by the `report_dir` fixture before any test runs
CACHE_DIR = Path()  # the cache the report was written from (likewise)


@pytest.fixture(scope="module", autouse=True)
def report_dir(qsweep_bin: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    global REPORT_DIR, CACHE_DIR
    given = os.environ.get("QSWEEP_REPORT_DIR")
    if given:
        d = Path(given)
        REPORT_DIR = d if d.is_absolute() else REPO_ROOT / d
        CACHE_DIR = Path(os.environ.get("QSWEEP_CACHE", REPO_ROOT / "cache"))
        assert (REPORT_DIR / "cells.parquet").is_file(), f"no report at {REPORT_DIR}"
        return REPORT_DIR
    tmp = tmp_path_factory.mktemp("quick")
    out = subprocess.run(
        [str(qsweep_bin), "run", str(REPO_ROOT / "pipelines" / "quick.yaml"), "--json",
         "--cache", str(tmp / "cache"), "--out", str(tmp / "report")],
        capture_output=True, text=True, timeout=1200,
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["failed"] == 0
    REPORT_DIR = tmp / "report"
    CACHE_DIR = tmp / "cache"
    return REPORT_DIR

CELL_KEY = ["system", "experiment", "algorithm", "axis1_value", "axis2_value"]

IDENTITY = {
    "system": pa.string(),
    "system_title": pa.string(),
    "experiment": pa.string(),
    "experiment_title": pa.string(),
    "repr": pa.string(),
    "algorithm": pa.string(),
    "label": pa.string(),
    "axis1_label": pa.string(),
    "axis1_value": pa.float64(),
    "axis2_label": pa.string(),
    "axis2_value": pa.float64(),
    "x": pa.uint32(),
    "x_dot": pa.uint32(),
    "theta": pa.uint32(),
    "theta_dot": pa.uint32(),
    "actions": pa.uint32(),
    "max_episodes": pa.uint32(),
}
CELLS = IDENTITY | {
    "planned": pa.int64(),
    "n": pa.int64(),
    "successes": pa.int64(),
    "all_converged": pa.bool_(),
    "best": pa.bool_(),
    **{c: pa.float64() for c in ["mean", "std", "min", "median", "max", "iqm", "ci_lo", "ci_hi"]},
}
TRIALS = IDENTITY | {
    "seed": pa.uint64(),
    "key": pa.string(),
    "converged": pa.bool_(),
    "episodes_to_goal": pa.uint32(),
    "episodes": pa.uint32(),
    "episodes_counted": pa.uint32(),
    "total_steps": pa.uint64(),
    "stop": pa.string(),
    "failure": pa.string(),
    "episode_lengths": pa.list_(pa.uint32()),
    **{c: pa.float64() for c in ["epsilon", "gamma", "alpha", "lambda", "seconds", "cpu_seconds"]},
}


@pytest.fixture(scope="module")
def cells(report_dir: Path) -> pd.DataFrame:
    return pd.read_parquet(REPORT_DIR / "cells.parquet")


@pytest.fixture(scope="module")
def trials(report_dir: Path) -> pd.DataFrame:
    return pd.read_parquet(REPORT_DIR / "trials.parquet")


@pytest.mark.parametrize("name,expected", [("cells", CELLS), ("trials", TRIALS)])
def test_schema_is_as_documented(name: str, expected: dict) -> None:
    schema = pq.read_schema(REPORT_DIR / f"{name}.parquet")
    got = {f.name: f.type for f in schema}
    assert list(got) == list(expected), f"{name}.parquet columns"
    for col, typ in expected.items():
        # Compare list types by their value type (the item field's name is not part of the contract).
        if pa.types.is_list(typ):
            assert pa.types.is_list(got[col]) and got[col].value_type == typ.value_type, col
        else:
            assert got[col] == typ, f"{name}.{col}: {got[col]} != {typ}"


def test_pandas_polars_duckdb_agree_on_rows_and_types(cells: pd.DataFrame, trials: pd.DataFrame) -> None:
    pl_cells = pl.read_parquet(REPORT_DIR / "cells.parquet")
    pl_trials = pl.read_parquet(REPORT_DIR / "trials.parquet")
    con = duckdb.connect()
    db_cells = con.execute(f"SELECT count(*) FROM '{REPORT_DIR / 'cells.parquet'}'").fetchone()[0]
    db_trials = con.execute(f"SELECT count(*) FROM '{REPORT_DIR / 'trials.parquet'}'").fetchone()[0]
    assert len(cells) == pl_cells.height == db_cells > 0
    assert len(trials) == pl_trials.height == db_trials
    assert len(trials) == cells["n"].sum()

    assert pl_cells.schema["mean"] == pl.Float64
    assert pl_cells.schema["x"] == pl.UInt32
    assert pl_cells.schema["best"] == pl.Boolean
    assert pl_trials.schema["episode_lengths"] == pl.List(pl.UInt32)
    assert pl_trials.schema["seed"] == pl.UInt64
    assert pl_trials.schema["system"] == pl.String

    described = con.execute(f"DESCRIBE SELECT * FROM '{REPORT_DIR / 'trials.parquet'}'").fetchall()
    types = {r[0]: r[1] for r in described}
    assert types["episode_lengths"] == "UINTEGER[]"
    assert types["seed"] == "UBIGINT"
    assert types["total_steps"] == "UBIGINT"
    assert types["converged"] == "BOOLEAN"
    assert types["key"] == "VARCHAR"

    assert pd.api.types.is_float_dtype(cells["mean"])
    assert pd.api.types.is_bool_dtype(trials["converged"])
    assert pd.api.types.is_string_dtype(trials["system"]), trials["system"].dtype

    # Every trial's episode list has one entry per episode run.
    assert (pl_trials["episode_lengths"].list.len() == pl_trials["episodes"].cast(pl.UInt32)).all()
    assert trials["key"].str.fullmatch(r"[0-9a-f]{64}").all()


def test_pyarrow_backed_pandas_keeps_the_stored_types() -> None:
    """The guide's idiom (docs/reading-results.md): `dtype_backend="pyarrow"` keeps uint64 and the nullable uint32."""
    t = pd.read_parquet(REPORT_DIR / "trials.parquet", dtype_backend="pyarrow")
    assert t["total_steps"].dtype == pd.ArrowDtype(pa.uint64())
    assert t["seed"].dtype == pd.ArrowDtype(pa.uint64())
    assert t["episodes_to_goal"].dtype == pd.ArrowDtype(pa.uint32())
    assert (t["episodes_to_goal"].isna() == ~t["converged"].astype(bool)).all()
    # A trial shared by two cells (Experiments 1 and 2 share configurations) is repeated per cell:
    # the rows outnumber the distinct trials, and each distinct trial is one row of the cache.
    distinct = t["key"].nunique()
    assert len(t) > distinct, "quick.yaml's experiments share cells, so some trials repeat"
    cache = pd.read_parquet(CACHE_DIR, columns=["key"])
    assert cache["key"].isin(set(t["key"])).sum() == distinct


def test_episodes_counted_is_goal_or_cap(trials: pd.DataFrame) -> None:
    conv = trials[trials["converged"]]
    assert (conv["episodes_counted"] == conv["episodes_to_goal"]).all()
    assert (conv["stop"] == "goal").all()
    fail = trials[~trials["converged"]]
    assert fail["episodes_to_goal"].isna().all()
    assert (fail["episodes_counted"] == fail["max_episodes"]).all()


def test_cell_statistics_match_trials(cells: pd.DataFrame, trials: pd.DataFrame) -> None:
    g = trials.groupby(CELL_KEY, dropna=False)
    recomputed = pd.DataFrame(
        {
            "n_re": g.size(),
            "successes_re": g["converged"].sum(),
            "mean_re": g["episodes_counted"].mean(),
            "std_re": g["episodes_counted"].std(ddof=1),
        }
    ).reset_index()
    merged = cells.merge(recomputed, on=CELL_KEY, how="left")
    present = merged[merged["n"] > 0]
    assert len(present) == len(recomputed), "every trial group is a cell"
    assert (present["n"] == present["n_re"]).all()
    assert (present["successes"] == present["successes_re"]).all()
    assert ((present["mean"] - present["mean_re"]).abs() < 1e-9).all()
    both = present[present["n"] > 1]
    assert ((both["std"] - both["std_re"]).abs() < 1e-9).all()
    assert present[present["n"] == 1]["std"].isna().all()
    # Order statistics are consistent.
    assert (present["min"] <= present["median"]).all() and (present["median"] <= present["max"]).all()
    assert (present["ci_lo"] <= present["ci_hi"]).all()
    empty = merged[merged["n"] == 0]
    assert empty["mean"].isna().all()

    # DuckDB, straight from the file, agrees.
    rows = duckdb.connect().execute(
        f"""SELECT system, experiment, algorithm, axis1_value, axis2_value,
                   avg(episodes_counted) AS m, stddev_samp(episodes_counted) AS s, count(*) AS n
            FROM '{REPORT_DIR / 'trials.parquet'}' GROUP BY ALL"""
    ).fetchdf()
    chk = cells.merge(rows, on=CELL_KEY)
    assert len(chk) == len(recomputed)
    assert ((chk["mean"] - chk["m"]).abs() < 1e-9).all()
    assert (chk["n_x"] == chk["n_y"]).all()


def test_table3_rows_are_the_best_cells(cells: pd.DataFrame) -> None:
    t3 = pd.read_csv(REPORT_DIR / "table3.csv", dtype={"experiment": str})
    best = cells[cells["best"]]
    pairs = cells.groupby(["system", "experiment", "algorithm"]).ngroups
    assert len(t3) == pairs, "one Table III row per system, experiment and algorithm"
    assert len(best) <= pairs
    for _, row in t3.iterrows():
        match = best[
            (best["system_title"] == row["system"])
            & (best["experiment"] == row["experiment"])
            & (best["label"] == row["algorithm"])
        ]
        if row["n"] == 0:
            assert match.empty and math.isnan(row["mean"])
            continue
        assert len(match) == 1, f"best cell of {row['system']} {row['experiment']} {row['algorithm']}"
        b = match.iloc[0]
        assert b["mean"] == pytest.approx(row["mean"], abs=1e-12)
        if b["n"] > 1:
            assert b["std"] == pytest.approx(row["std"], abs=1e-12)
        for col in ["x", "x_dot", "theta", "theta_dot", "actions", "n", "successes"]:
            want = b[col]
            got = row[col]
            if pd.isna(want):
                assert pd.isna(got), col
            else:
                assert int(got) == int(want), col
        # The rule: among fully converged cells of this experiment and algorithm, none has a lower mean.
        group = cells[
            (cells["system"] == b["system"]) & (cells["experiment"] == b["experiment"]) & (cells["algorithm"] == b["algorithm"])
        ]
        full = group[group["all_converged"]]
        if b["all_converged"]:
            assert (full["mean"] >= b["mean"]).all()
        else:
            assert full.empty
            assert b["successes"] == group["successes"].max()
