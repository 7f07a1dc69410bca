"""A raced report, read and re-derived in Python.

Two reports: the one `qsweep run tests/fixtures/pipelines/race.yaml` writes (3 seeds, then 2 more
per round up to 7), and the committed `pipelines/paper-race.yaml` race re-reported from the
committed cache, both into temporary folders. Set `$QSWEEP_RACE_REPORT_DIR` (with
`$QSWEEP_RACE`, e.g. `5,5,40,0.95` for seeds, batch, max_seeds, confidence) to check another
report, e.g. `reports/paper-race`.

Checks: `cells.parquet` loads with a bool `contender` in pandas, polars and DuckDB alike;
table3.csv's `contenders` counts them; and the race is replayed from `trials.parquet` with SciPy's
Welch test and a Holm step-down written here, round by round, giving the same contenders and the
same seeds per cell.
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import duckdb
import pandas as pd
import polars as pl
import pytest
from scipy import stats

# SciPy warns about a sample without spread (every trial of a cell counting the same); the test's
# own branch handles two such samples, and one such sample is an ordinary Welch case.
pytestmark = pytest.mark.filterwarnings("ignore:Precision loss occurred:RuntimeWarning")

REPO_ROOT = Path(__file__).resolve().parents[2]
HEATMAP = ["variant", "system", "experiment", "algorithm"]
CELL = ["axis1_value", "axis2_value"]


@pytest.fixture(scope="module", params=["fixture", "paper-race"])
def race(request, qsweep_bin: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, tuple[int, int, int, float]]:
    given = os.environ.get("QSWEEP_RACE_REPORT_DIR")
    if given:
        d = Path(given)
        seeds, batch, most, conf = os.environ.get("QSWEEP_RACE", "5,5,40,0.95").split(",")
        return (d if d.is_absolute() else REPO_ROOT / d), (int(seeds), int(batch), int(most), float(conf))
    if request.param == "paper-race":
        # The committed race, re-reported from the committed cache (runs nothing): every
        # decision of pipelines/paper-race.yaml replayed independently.
        tmp = tmp_path_factory.mktemp("paper-race")
        out = subprocess.run(
            [str(qsweep_bin), "report", str(REPO_ROOT / "pipelines" / "paper-race.yaml"),
             "--cache", str(REPO_ROOT / "cache"), "--out", str(tmp / "report"), "--formats", "csv,cells,trials"],
            capture_output=True, text=True, timeout=600,
        )
        assert out.returncode == 0, out.stderr
        assert "26365 of 26365 planned trials present" in out.stdout, out.stdout
        return tmp / "report", (5, 5, 40, 0.95)
    tmp = tmp_path_factory.mktemp("race")
    pipeline = REPO_ROOT / "tests" / "fixtures" / "pipelines" / "race.yaml"
    out = subprocess.run(
        [str(qsweep_bin), "run", str(pipeline), "--json", "--cache", str(tmp / "cache"),
         "--out", str(tmp / "report"), "--formats", "csv,cells,trials"],
        capture_output=True, text=True, timeout=600,
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["executed"] == 31
    return tmp / "report", (3, 2, 7, 0.95)


def test_contender_reads_the_same_in_pandas_polars_and_duckdb(race) -> None:
    d, _ = race
    # A nullable boolean (null outside races): Arrow-backed pandas keeps it boolean, nulls included.
    pdf = pd.read_parquet(d / "cells.parquet", dtype_backend="pyarrow")
    assert str(pdf["contender"].dtype) == "bool[pyarrow]", pdf["contender"].dtype
    pl_df = pl.read_parquet(d / "cells.parquet")
    assert pl_df.schema["contender"] == pl.Boolean
    con = duckdb.connect()
    n = con.execute(f"SELECT count(*) FROM '{d / 'cells.parquet'}' WHERE contender").fetchone()[0]
    assert n == int(pdf["contender"].fillna(False).sum()) == pl_df["contender"].sum()
    # Every cell of a raced heatmap says whether it is in the race; the best always is.
    assert pdf["contender"].notna().all()
    assert pdf.loc[pdf["best"], "contender"].all()


def test_table3_counts_the_contenders(race) -> None:
    d, _ = race
    cells = pd.read_parquet(d / "cells.parquet")
    if "variant" not in cells:
        cells["variant"] = ""
    t3 = pd.read_csv(d / "table3.csv")
    per = cells.groupby(["system_title", "experiment", "label"])["contender"].sum()
    for _, row in t3.iterrows():
        assert row["contenders"] == per[(row["system"], str(row["experiment"]), row["algorithm"])]


def holm(p: list[float], alpha: float) -> list[bool]:
    order = sorted(range(len(p)), key=lambda i: (p[i], i))
    out = [False] * len(p)
    for k, i in enumerate(order):
        if p[i] <= alpha / (len(p) - k):
            out[i] = True
        else:
            break
    return out


def welch_greater(a: list[float], b: list[float]) -> float:
    if pd.Series(a).std() == 0 and pd.Series(b).std() == 0:
        return 0.0 if sum(a) / len(a) > sum(b) / len(b) else 1.0
    return float(stats.ttest_ind(a, b, equal_var=False, alternative="greater").pvalue)


def best(samples: dict, order: list) -> object:
    """Table III's rule: lowest mean among fully converged cells, else most successes, then mean."""
    def key(c):
        v, ok = samples[c]
        full = ok == len(v)
        return (0 if full else 1, 0 if full else -ok, sum(v) / len(v), order.index(c))
    return min(samples, key=key)


def test_the_race_replays_from_the_trials(race) -> None:
    d, (first, batch, most, conf) = race
    cells = pd.read_parquet(d / "cells.parquet")
    trials = pd.read_parquet(d / "trials.parquet", columns=HEATMAP[1:] + CELL + ["seed", "episodes_counted", "converged"] + (["variant"] if "variant" in cells else []))
    for df in (cells, trials):
        if "variant" not in df:
            df["variant"] = ""
        df["axis2_value"] = df["axis2_value"].fillna(-1.0)
    checked = 0
    for heat, hc in cells.groupby(HEATMAP, sort=False):
        ht = trials.merge(hc[HEATMAP + CELL], on=HEATMAP + CELL)
        order = [tuple(r) for r in hc[CELL].itertuples(index=False)]
        by_cell = {c: g.sort_values("seed") for c, g in ht.groupby(CELL)}
        alive, n, seeds_of = list(order), first, {c: first for c in order}
        while True:
            samples = {c: (list(by_cell[c]["episodes_counted"][:n].astype(float)), int(by_cell[c]["converged"][:n].sum())) for c in alive}
            b = best(samples, order)
            tested = [c for c in alive if c != b]
            drop = holm([welch_greater(samples[c][0], samples[b][0]) for c in tested], 1 - conf)
            alive = [c for c in alive if c == b or not drop[tested.index(c)]]
            if len(alive) == 1 or n >= most:
                break
            n = min(n + batch, most)
            for c in alive:
                seeds_of[c] = n
        want = {c: (c in alive, seeds_of[c]) for c in order}
        got = {tuple(r[:2]): (bool(r[2]), int(r[3])) for r in hc[CELL + ["contender", "n"]].itertuples(index=False)}
        assert got == want, heat
        checked += 1
    assert checked >= 2
