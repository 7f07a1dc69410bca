"""Independent checks of issue #40 on the committed paper report, in Python with pandas/SciPy:

- every declared variant's table3.csv has the `paper_cell_*` columns, and ours at the paper's
  configuration (mean, std, n, successes, fresh-seed estimate, ratio to the paper) is recomputed
  from that variant's rows of `cells.parquet` and the paper's values;
- the old rule's columns (issue #46 renamed them `verdict_2se`, `paper_cell_verdict_2se`,
  `cause_2se`) and `contradictory_pair` follow the rule pre-registered in docs/preregistration.md
  for issue #40, recomputed by scripts/replication_summary.py; `paper_inconsistent` marks the one
  row the contradictory pair costs (the scale's `verdict` and `cause`: tests/python/test_verdicts.py);
- consistency.csv lists exactly the comparable pairs recomputed from the paper's values and the
  grids (9 pairs, 1 contradictory: Ball-Beam crisp Q(0), Exp. 1 against Exp. 2, marking Exp. 1;
  still contradictory with the paper's means over 5 runs, not over 3);
- the comparison page opens with the best declared variant's tally of causes (the scale's `cause`).
"""

from __future__ import annotations

import math

import pandas as pd
import pytest
from scipy import stats

from conftest import REPO_ROOT

PAPER = REPO_ROOT / "reports" / "paper"
RES = ["x", "x_dot", "theta", "theta_dot"]
# The causes on the verdict scale (table3.csv's `cause`), in the order the comparison page tallies them.
CAUSES = ["replicates", "argmin", "paper-inconsistent", "differs-at-paper-config", "unexplained"]
# table3.csv's columns after the paper's cell's (issue #46).
TAIL = [
    "verdict_2se",
    "paper_cell_verdict_2se",
    "cause_2se",
    "contradictory_pair",
    "paper_inconsistent",
    "tost2x_p_n10",
    "paper_cell_tost2x_p_n10",
    "verdict",
    "paper_cell_verdict",
    "cause",
    "std_ratio",
    "std_ratio_lo",
    "std_ratio_hi",
    "spread_differs",
]


def _declared() -> list[str]:
    v = pd.read_csv(PAPER / "variants.csv")
    return v[v["exploratory"] == "no"]["variant"].tolist()


@pytest.fixture(scope="module")
def cells() -> pd.DataFrame:
    return pd.read_parquet(PAPER / "cells.parquet")


def _close(a: float, b: float) -> bool:
    return (pd.isna(a) and pd.isna(b)) or math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-12)


@pytest.mark.parametrize("v", _declared())
def test_paper_cell_columns_are_the_cell_at_the_papers_configuration(v: str, cells: pd.DataFrame) -> None:
    t3 = pd.read_csv(PAPER / v / "table3.csv", dtype={"experiment": str})
    cols = t3.columns.tolist()
    end = cols.index("equivalent_n100") + 1
    new = cols[end : cols.index(TAIL[0])]
    assert cols[cols.index(TAIL[0]) :] == TAIL
    best_cols = cols[cols.index("ci_lo") : end]
    assert new == ["paper_cell_mean", "paper_cell_std", "paper_cell_n", "paper_cell_successes"] + [
        f"paper_cell_{c}" for c in best_cols
    ]
    c = cells[cells.variant == v]
    for _, r in t3.iterrows():
        m = c[(c.system_title == r.system) & (c.experiment == r.experiment) & (c.label == r.algorithm)]
        for col in RES + ["actions"]:
            want = r[f"paper_{col}"]
            m = m[m[col].isna()] if pd.isna(want) else m[m[col] == want]
        assert len(m) == 1, (v, r.system, r.experiment, r.algorithm)
        m = m.iloc[0]
        for col in ["mean", "std", "n", "successes", "ci_lo", "ci_hi", "fresh_mean", "fresh_std", "fresh_ci_lo", "fresh_ci_hi"]:
            assert _close(r[f"paper_cell_{col}"], m[col]), (v, r.system, r.experiment, r.algorithm, col)
        assert int(r["paper_cell_fresh_n"]) == int(m["fresh_n"])
        est = m["fresh_mean"] if m["fresh_n"] > 0 else m["mean"]
        assert _close(r["paper_cell_ratio"], est / r["paper_mean"])
        if m["fresh_n"] > 0:
            assert (m["best"]), "only a heatmap's best cell has fresh seeds"


@pytest.mark.parametrize("v", _declared())
def test_old_rule_verdicts_and_causes_follow_the_preregistered_rule(v: str, cells: pd.DataFrame) -> None:
    """The old rule (issue #40), kept for comparison under the `_2se` names: within 2 SE, else
    within 2x, else no; causes with both rows of a contradictory pair paper-inconsistent."""
    import replication_summary as rs

    t3 = pd.read_csv(PAPER / v / "table3.csv", dtype={"experiment": str})
    c = cells[cells.variant == v]
    word = rs.WORD_2SE
    j = rs.judged(t3)
    at = rs.paper_cell(c, t3)
    for i, r in j.iterrows():
        assert t3.loc[i, "verdict_2se"] == word[rs.verdict(r)]
        pc = pd.Series({**r.to_dict(), "mean": at.loc[i, "mean"], "std": at.loc[i, "std"], "n": at.loc[i, "n"]})
        assert t3.loc[i, "paper_cell_verdict_2se"] == word[rs.verdict(pc)]
    assert t3["cause_2se"].tolist() == rs.causes(t3, c)
    pair = t3[t3["contradictory_pair"] == "yes"]
    assert (pair["system"] == "Ball-Beam").all() and set(pair["experiment"]) == {"1", "2"}
    assert set(pair["algorithm"]) == {"Q(0)-learning"} and len(pair) == 2
    assert (pair["cause_2se"].isin(["replicates", "paper-inconsistent"])).all()
    # A contradiction costs one row: Exp. 1's, whose grid holds Exp. 2's configuration and whose
    # published minimum (90.5) that cell undercuts (43.2).
    marked = t3[t3["paper_inconsistent"] == "yes"]
    assert [tuple(x) for x in marked[["system", "experiment", "algorithm"]].values] == [("Ball-Beam", "1", "Q(0)-learning")]
    assert set(t3["contradictory_pair"]) <= {"yes", "no"} and set(t3["paper_inconsistent"]) <= {"yes", "no"}


def test_consistency_lists_every_comparable_pair(cells: pd.DataFrame) -> None:
    import replication_summary as rs

    got = pd.read_csv(PAPER / "consistency.csv", dtype={"experiment_a": str, "experiment_b": str, "marked": str})
    v = _declared()[0]
    t3 = pd.read_csv(PAPER / v / "table3.csv", dtype={"experiment": str})
    want = rs.consistency(t3, cells[cells.variant == v])
    fewer = {n: rs.consistency(t3, cells[cells.variant == v], n) for n in (5, 3)}
    assert len(got) == len(want) == len(fewer[5]) == len(fewer[3]) == 9
    assert int((got["contradictory"] == "yes").sum()) == 1
    for k, ((_, g), w) in enumerate(zip(got.iterrows(), want)):
        assert (g.marked if pd.notna(g.marked) else "") == w["marked"], (k, g.marked, w["marked"])
        for n in (5, 3):
            assert (g[f"contradictory_n{n}"] == "yes") == fewer[n][k]["contradictory"], (k, n)
        a, b = w["row_a"], w["row_b"]
        assert (g.system, g.algorithm, g.experiment_a, g.experiment_b) == (a.system, a.algorithm, a.experiment, b.experiment)
        assert (g.mean_a, g.std_a, g.mean_b, g.std_b) == (a.paper_mean, a.paper_std, b.paper_mean, b.paper_std)
        assert math.isclose(g.p, w["p"], abs_tol=1e-6), (g.p, w["p"])
        if math.isfinite(w["t"]) and w["t"] != 0:
            assert math.isclose(g.t, w["t"], abs_tol=1e-3)
        assert (g.contradictory == "yes") == w["contradictory"]
    bad = got[got["contradictory"] == "yes"].iloc[0]
    assert (bad.system, bad.algorithm, bad.experiment_a, bad.experiment_b) == ("Ball-Beam", "Q(0)-learning", "1", "2")
    t, p = stats.ttest_ind_from_stats(43.2, 20.4, 10, 90.5, 25.8, 10, equal_var=False)
    assert math.isclose(bad.t, t, abs_tol=1e-3) and math.isclose(bad.p, p, abs_tol=1e-6)
    # It costs Exp. 1's row (a); with the paper's means over 5 runs it stays contradictory
    # (p = 0.013), over 3 it does not (p = 0.071). Only that pair is marked.
    assert bad.marked == "a"
    assert (bad.contradictory_n5, bad.contradictory_n3) == ("yes", "no")
    for n, col in [(5, "p_n5"), (3, "p_n3")]:
        _, p = stats.ttest_ind_from_stats(43.2, 20.4, n, 90.5, 25.8, n, equal_var=False)
        assert math.isclose(bad[col], p, abs_tol=1e-6), (n, bad[col], p)
    assert int(got["marked"].notna().sum()) == 1


def test_the_comparison_page_opens_with_the_best_variants_causes() -> None:
    best = _declared()[0]
    t3 = pd.read_csv(PAPER / best / "table3.csv")
    counts = ", ".join(f"{int((t3['cause'] == c).sum())} {c}" for c in CAUSES)
    html = (PAPER / "index.html").read_text()
    readme = (PAPER / "README.md").read_text()
    assert '<p id="causes">' in html and counts in html, counts
    assert counts in readme
    assert html.index('id="causes"') < html.index('id="fit"'), "near the top"
    notes = (PAPER / "REPLICATION.md").read_text()
    assert counts in notes, "REPLICATION.md states the tally of the best declared variant"
