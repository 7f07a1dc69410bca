"""Cross-checks of a pipeline with variants (tests/fixtures/pipelines/variants.yaml).

The binary runs the fixture into a temporary cache and report folder. Checks: the combined
cells.parquet / trials.parquet carry a `variant` column that pandas, polars and DuckDB read alike;
each variant's rows equal that variant's own report; a trial shared by two variants appears under
both; variants.csv is recomputed from each variant's table3.csv with the documented rules (the old
rule's counts `within_2se` and `ratio_within_2x` recomputed from the means, those of the verdict
scale of issue #46 counted from table3.csv's `verdict`, which tests/python/test_verdicts.py checks).
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
        # The trial rows live once, in the combined file: a variant's rows are its cells' trials.
        assert not (report / v / "trials.parquet").exists()
        mine_t = trials[trials["variant"] == v]
        assert len(mine_t) == int(own["n"].sum())
        per_cell = mine_t.groupby(["experiment", "algorithm", "axis1_value", "axis2_value"], dropna=False).size()
        assert sorted(per_cell.tolist()) == sorted(own["n"].tolist())


def test_shared_trials_appear_under_each_variant_that_plans_them(report: Path) -> None:
    trials = pd.read_parquet(report / "trials.parquet")
    keys = {v: set(trials[trials["variant"] == v]["key"]) for v in VARIANTS}
    # fast-crisp changes only the crisp learning rate: the fuzzy experiment's 8 trials are shared.
    assert len(keys["as-written"] & keys["fast-crisp"]) == 8
    # short-episodes changes every trial.
    assert not keys["short-episodes"] & (keys["as-written"] | keys["fast-crisp"])
    assert trials.drop_duplicates("key").shape[0] == 24 + 16 + 24


SCALE = ["equivalent", "within-2x", "consistent-but-wide", "differs"]


def _verdict(r: pd.Series) -> str:
    """The old rule (table3.csv's `verdict_2se`)."""
    se = math.sqrt(r["paper_std"] ** 2 / 10 + r["std"] ** 2 / r["n"])
    if abs(r["mean"] - r["paper_mean"]) <= 2 * se:
        return "replicates"
    if 0.5 <= r["mean"] / r["paper_mean"] <= 2:
        return "within 2x"
    return "no"


def test_variants_csv_is_recomputed_from_each_variants_table3(report: Path) -> None:
    got = pd.read_csv(report / "variants.csv")
    assert sorted(got["variant"]) == sorted(VARIANTS)
    res_cols = ["x", "x_dot", "theta", "theta_dot"]
    expected = {}
    for v in VARIANTS:
        t3 = pd.read_csv(report / v / "table3.csv", dtype={"experiment": str})
        rows = t3[t3["paper_mean"].notna() & t3["mean"].notna()]
        verdicts = [_verdict(r) for _, r in rows.iterrows()]
        assert rows["verdict_2se"].tolist() == [{"within 2x": "within-2x"}.get(x, x) for x in verdicts], v
        scale = rows["verdict"].value_counts()
        scale = {k: int(scale.get(k, 0)) for k in SCALE}
        assert set(rows["verdict"]) <= set(SCALE) | {"undecided"}, v
        eq100 = int((rows["equivalent_n100"] == "yes").sum())
        config = 0
        for _, r in rows.iterrows():
            ours = [int(r[c]) for c in res_cols if pd.notna(r[c])] + [int(r["actions"])]
            paper = [int(r[f"paper_{c}"]) for c in res_cols + ["actions"] if pd.notna(r[f"paper_{c}"])]
            config += ours == paper
        order = ordered = 0
        for _, same in t3.groupby(["system", "experiment"]):
            if len(same) >= 2 and same["paper_mean"].notna().all() and same["mean"].notna().all():
                ordered += 1
                by_ours = same.sort_values("mean", kind="stable")["algorithm"].tolist()
                by_paper = same.sort_values("paper_mean", kind="stable")["algorithm"].tolist()
                order += by_ours == by_paper
        geo = math.exp(sum(math.log(m / p) for m, p in zip(rows["mean"], rows["paper_mean"])) / len(rows))
        expected[v] = (len(rows), verdicts.count("replicates"), verdicts.count("within 2x"), config, order, ordered, geo, scale, eq100)
    assert got.columns.tolist()[:19] == [
        "rank", "variant", "title", "rows", "replicating_n10", "equivalent_n10", "within_2x_n10",
        "consistent_but_wide_n10", "differs_n10", "replicating_n5", "replicating_n3", "within_2se",
        "ratio_within_2x", "config_match", "order_match", "order_experiments", "geo_mean_ratio",
        "equivalent_n100", "exploratory",
    ]
    for _, r in got.iterrows():
        n, se2, w2, config, order, ordered, geo, scale, eq100 = expected[r["variant"]]
        assert (r["rows"], r["within_2se"], r["ratio_within_2x"], r["config_match"]) == (n, se2, w2, config), r["variant"]
        assert [r[f"{k.replace('-', '_')}_n10"] for k in SCALE] == [scale[k] for k in SCALE], r["variant"]
        assert r["replicating_n10"] == scale["equivalent"] + scale["within-2x"], r["variant"]
        assert r["equivalent_n100"] == eq100, r["variant"]
        assert (r["order_match"], r["order_experiments"]) == (order, ordered), r["variant"]
        assert r["geo_mean_ratio"] == pytest.approx(geo, rel=1e-9), r["variant"]
    # Rows are in the stated fit order, ranked 1, 2, 3.
    assert got["rank"].tolist() == [1, 2, 3]
    keys = [
        (-r["within_2se"], -r["ratio_within_2x"], -r["config_match"], abs(math.log(r["geo_mean_ratio"])))
        for _, r in got.iterrows()
    ]
    assert keys == sorted(keys)
    html = (report / "index.html").read_text()
    for v in VARIANTS:
        assert f'href="{v}/index.html"' in html
    for v in VARIANTS[1:]:
        assert (report / "figures" / f"diff-{v}-mountain-car.svg").is_file()
        assert not (report / "figures" / f"diff-{v}-mountain-car.png").exists(), "no PNG by default"
        assert f'src="figures/diff-{v}-mountain-car.svg"' in html


def test_replication_summary_recomputes_the_variant_study(report: Path, capsys: pytest.CaptureFixture) -> None:
    """scripts/replication_summary.py's study part (REPLICATION.md's tallies) accepts the report:
    the tallies recomputed from each variant's table3.csv equal variants.csv, in the pre-registered
    order. (The conclusions part needs the paper's full grid and is not run on this fixture.)"""
    import replication_summary

    best = replication_summary.study(report)
    out = capsys.readouterr().out
    assert best == pd.read_csv(report / "variants.csv")["variant"][0]
    assert "Best fit under the pre-registered measure" in out
    for v in VARIANTS:
        assert f"`{v}`" in out


def test_python_and_rust_verdicts_agree_when_a_row_has_one_trial(qsweep_bin: Path, tmp_path: Path) -> None:
    """Regression: scripts/replication_summary.py called every n = 1 row "does not replicate"
    while qsweep (whose rule is the one definition) lets it be within 2x. With one seed every
    row has n = 1 and no std; the tallies recomputed in Python must equal variants.csv."""
    import replication_summary

    out = tmp_path / "report"
    subprocess.run(
        [str(qsweep_bin), "run", str(REPO_ROOT / "tests/fixtures/pipelines/variants.yaml"), "--cache",
         str(tmp_path / "cache"), "--out", str(out), "--quiet", "--set", "seeds=1"],
        check=True,
    )
    got = pd.read_csv(out / "variants.csv").set_index("variant")
    for v in VARIANTS:
        t3 = pd.read_csv(out / v / "table3.csv", dtype={"experiment": str})
        assert (t3["n"] == 1).all() and t3["std"].isna().all()
        t = replication_summary.tally(t3)
        cols = ["rows", "within_2se", "ratio_within_2x"]
        assert (t["rows"], t["within_2se"], t["ratio_within_2x"]) == tuple(got.loc[v, cols]), v
        # Without a std the verdict scale cannot decide: no row replicates.
        assert (t3[t3["paper_mean"].notna()]["verdict"] == "undecided").all(), v
        assert (got.loc[v, "replicating_n10"], got.loc[v, "replicating_n5"], got.loc[v, "replicating_n3"]) == (0, 0, 0), v
    row = pd.Series({"mean": 6.0, "std": float("nan"), "n": 1, "paper_mean": 6.0, "paper_std": 3.0})
    assert replication_summary.verdict(row) == "within 2×", "no std: not within 2 SE, but within 2x"
    assert replication_summary.verdict(pd.Series({**row, "mean": 13.0})) == "does not replicate"
