"""The cache reads back as one table in pandas, polars and DuckDB (docs/reading-results.md's promise)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import duckdb
import pandas as pd
import polars as pl
import pyarrow as pa
import pytest

from conftest import REPO_ROOT

TINY = REPO_ROOT / "tests" / "fixtures" / "pipelines" / "tiny.yaml"
N_TRIALS = 56


@pytest.fixture(scope="module")
def cache(qsweep_bin: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("cache")
    out = subprocess.run(
        [str(qsweep_bin), "run", str(TINY), "--cache", str(d), "--json", "--no-report", "--batch-trials", "10"],
        check=True,
        capture_output=True,
        text=True,
    )
    summary = json.loads(out.stdout)
    assert summary["executed"] == N_TRIALS
    return d


def check(df: pd.DataFrame) -> None:
    assert len(df) == N_TRIALS
    assert df["key"].is_unique
    assert set(df["system"]) == {"ball-beam", "mountain-car"}
    assert set(df["algorithm"]) == {"q0", "q-lambda"}
    assert df["episodes"].dtype == "uint32"
    assert df["total_steps"].dtype == "uint64"
    assert df["converged"].dtype == bool
    # The list column holds every episode, and the totals agree with it.
    for _, row in df.iterrows():
        lengths = list(row["episode_lengths"])
        assert len(lengths) == row["episodes"]
        assert sum(lengths) == row["total_steps"]
        assert json.loads(row["config_json"])["actions"] == row["actions"]
        if row["converged"]:
            assert row["episodes_to_goal"] == row["episodes"]
        else:
            assert pd.isna(row["episodes_to_goal"])


def test_pandas_reads_the_cache_directory(cache: Path) -> None:
    check(pd.read_parquet(cache))


def test_pyarrow_backed_pandas_keeps_the_stored_types(cache: Path) -> None:
    """The guide's idiom (docs/reading-results.md): `dtype_backend="pyarrow"` keeps uint64 and the nullable uint32 (the
    same types as trials.parquet) instead of float64 with NaN."""
    df = pd.read_parquet(cache, dtype_backend="pyarrow")
    assert len(df) == N_TRIALS
    assert df["total_steps"].dtype == pd.ArrowDtype(pa.uint64())
    assert df["seed"].dtype == pd.ArrowDtype(pa.uint64())
    assert df["episodes_to_goal"].dtype == pd.ArrowDtype(pa.uint32())
    assert (df["episodes_to_goal"].isna() == ~df["converged"].astype(bool)).all()


def test_polars_reads_the_segment_glob(cache: Path) -> None:
    df = pl.read_parquet(str(cache / "seg-*.parquet"))
    assert df.schema["resolution"] == pl.List(pl.UInt32)
    assert df.schema["episodes_to_goal"] == pl.UInt32
    check(df.to_pandas())


def test_duckdb_reads_the_segment_glob(cache: Path) -> None:
    con = duckdb.connect()
    glob = str(cache / "seg-*.parquet")
    n, systems = con.execute(
        f"select count(*), count(distinct system) from read_parquet('{glob}')"
    ).fetchone()
    assert (n, systems) == (N_TRIALS, 2)
    per_cell = con.execute(
        f"select system, repr, algorithm, resolution, actions, count(*) as n "
        f"from read_parquet('{glob}') group by all"
    ).fetchall()
    assert len(per_cell) == N_TRIALS // 2
    assert all(row[-1] == 2 for row in per_cell)


def test_a_cache_mixing_segments_from_before_cpu_seconds_reads_with_the_readme_idioms(
    qsweep_bin: Path, tmp_path: Path
) -> None:
    """Segments written before qsweep recorded `cpu_seconds` lack the column; a cache holding both
    kinds reads with the guide's idioms (polars `concat(..., how="diagonal_relaxed")`, DuckDB
    `union_by_name`), old rows null, and `qsweep gc` rewrites every segment in the current schema."""
    import shutil

    d = tmp_path / "cache"
    subprocess.run([str(qsweep_bin), "run", str(TINY), "--cache", str(d), "--no-report", "--quiet",
                    "--set", "seeds=1"], check=True)
    shutil.copy(REPO_ROOT / "tests/fixtures/cache/seg-previous-layout.parquet", d / "seg-0-previous.parquet")
    new = pl.read_parquet(sorted(set(d.glob("seg-*.parquet")) - {d / "seg-0-previous.parquet"}))
    assert new["cpu_seconds"].null_count() == 0
    assert (new["cpu_seconds"] > 0).all() and (new["cpu_seconds"] <= new["seconds"] * 1.5 + 0.05).all()
    df = pl.concat([pl.read_parquet(f) for f in sorted(d.glob("seg-*.parquet"))], how="diagonal_relaxed")
    old_rows = 30
    assert df["cpu_seconds"].null_count() == old_rows
    rows, with_cpu = duckdb.sql(
        f"select count(*), count(cpu_seconds) from read_parquet('{d}/seg-*.parquet', union_by_name=true)"
    ).fetchall()[0]
    assert with_cpu == len(new) and rows == len(df)
    subprocess.run([str(qsweep_bin), "gc", "--cache", str(d)], check=True, capture_output=True)
    after = pl.read_parquet(d / "seg-*.parquet")  # one schema again: no option needed
    assert "cpu_seconds" in after.columns
    assert after["key"].n_unique() == after.height
