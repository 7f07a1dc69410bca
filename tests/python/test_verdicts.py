"""An independent reviewer's recompute of the verdicts of issue #46 (docs/preregistration.md, last
section: "Verdicts that need closeness, the paper's unknown n, one row per contradiction").

Nothing here imports the project's scripts: the only inputs are `reports/paper/cells.parquet`
(every cell of every declared variant), the order and the `exploratory:` flags of `variants:` in
`pipelines/paper.yaml`, and the paper's Table III typed afresh below (itself checked against the
`paper_*` columns of `as-written/table3.csv`, so a typo shows). Statistics are SciPy's.

What is checked, each against what qsweep wrote:

- `table3.csv` of every declared variant: the new columns follow `paper_cell_equivalent_n100` in the
  declared order, and each is recomputed: the old rule (`verdict_2se`, `paper_cell_verdict_2se`,
  `cause_2se` with both rows of a contradictory pair `paper-inconsistent` and `learner`), the
  within-2x TOST's p for the best cell and the paper's cell (`tost2x_p_n10`,
  `paper_cell_tost2x_p_n10`), the verdict scale (`verdict`, `paper_cell_verdict`), the pairs
  (`contradictory_pair`), the designated row (`paper_inconsistent`), the `cause`, and the spread
  (`std_ratio` with its F interval, `spread_differs`), all at n_paper = 10, on the fresh-seed
  estimate where the cell has one;
- `verdicts_by_n.csv`: one line per variant of the pipeline, Table III row and n_paper in
  {3, 5, 10}; for every variant with cells in `cells.parquet` (today the declared ones) every
  verdict, pair flag, designation and cause recomputed at that n; for the others (the exploratory
  `*-failures` variants, which have neither cells nor a folder) the pair flags and the designation
  recomputed (they depend on the paper alone), the verdict recomputed from the estimate the line
  states (`mean`, `std`, `n`; for variants with cells that estimate is checked too) and the cause
  checked against the line's own verdicts; the closest variant per row and n (best verdict, then
  smallest |ln(m/M)|, then pipeline order): fully among variants with cells, and against the others
  as far as their lines allow;
- `cross_validation.csv`: leave-one-row-out over the declared variants with the fit measure of
  2026-11-30 (rows within 2 SE, rows within 2x by ratio, matching configurations, |ln geometric
  mean|, then pipeline order), the held-out row judged under the chosen variant;
- `variants.csv`: the old rule's counts under their new names (`within_2se`, `ratio_within_2x`), the
  new counts per variant (`replicating_n3/5/10` = equivalent + within-2x, `within_2x_n10`,
  `consistent_but_wide_n10`, `differs_n10`), and the declared variants' order by the fit measure.

Not recomputed: the permutation yardstick's exact numbers (its ChaCha8 stream is qsweep's own); its
unit tests check its behaviour (crates/qsweep-report/src/replication/stats/selection.rs).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "reports" / "paper"
PIPELINE = ROOT / "pipelines" / "paper.yaml"

RES = ["x", "x_dot", "theta", "theta_dot"]
ALPHA = 0.05
NS = (3, 5, 10)
HEADLINE_N = 10
EQUIV_MARGIN = (-0.20, 0.25)  # ours / paper in [0.80, 1.25]
TWOFOLD_MARGIN = (-0.50, 1.00)  # ours / paper in [0.5, 2]
SCALE = ["equivalent", "within-2x", "consistent-but-wide", "differs", "undecided"]  # closest first
REPLICATING = {"equivalent", "within-2x"}

NEW_TABLE3_COLUMNS = [
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
BY_N_COLUMNS = [
    "variant",
    "exploratory",
    "system",
    "experiment",
    "algorithm",
    "mean",
    "std",
    "n",
    "n_paper",
    "verdict",
    "paper_cell_verdict",
    "contradictory_pair",
    "paper_inconsistent",
    "cause",
    "closest_variant",
    "closest_exploratory",
    "closest_ratio",
    "closest_verdict",
]

# The paper's Table III, typed from its text: (system, experiment, algorithm, mean, std,
# (x, x_dot, theta, theta_dot, actions)); None where the variable is not in the model ("—").
_ = None
TABLE3 = [
    ("Ball-Beam", "1", "Q(0)-learning", 90.5, 25.8, (5, 3, _, _, 3)),
    ("Ball-Beam", "1", "Q(λ)-learning", 2.1, 1.1, (9, 3, _, _, 3)),
    ("Ball-Beam", "2", "Q(0)-learning", 43.2, 20.4, (3, 3, _, _, 3)),
    ("Ball-Beam", "2", "Q(λ)-learning", 2.3, 1.5, (7, 7, _, _, 2)),
    ("Ball-Beam", "3", "Fuzzy Q(0)-learning", 2.9, 1.1, (10, 3, _, _, 3)),
    ("Ball-Beam", "3", "Fuzzy Q(λ)-learning", 1.3, 0.6, (9, 6, _, _, 3)),
    ("Ball-Beam", "4", "Fuzzy Q(0)-learning", 2.55, 0.73, (3, 3, _, _, 2)),
    ("Ball-Beam", "4", "Fuzzy Q(λ)-learning", 1.59, 0.88, (10, 10, _, _, 3)),
    ("Cart-Pole", "1", "Q(0)-learning", 42.4, 13.8, (2, 2, 2, 2, 2)),
    ("Cart-Pole", "1", "Q(λ)-learning", 27.2, 6.3, (10, 2, 10, 2, 2)),
    ("Cart-Pole", "2", "Q(0)-learning", 42.4, 13.8, (2, 2, 2, 2, 2)),
    ("Cart-Pole", "2", "Q(λ)-learning", 41.4, 24.4, (2, 2, 2, 2, 2)),
    ("Cart-Pole", "3", "Fuzzy Q(0)-learning", 4.5, 2.1, (2, 2, 2, 2, 2)),
    ("Cart-Pole", "3", "Fuzzy Q(λ)-learning", 3.9, 1.5, (4, 2, 4, 2, 2)),
    ("Cart-Pole", "4", "Fuzzy Q(0)-learning", 4.54, 2.06, (2, 2, 2, 2, 2)),
    ("Cart-Pole", "4", "Fuzzy Q(λ)-learning", 4.57, 1.35, (2, 2, 2, 2, 2)),
    ("Mountain Car", "1", "Q(0)-learning", 121.6, 11.4, (2, 2, _, _, 3)),
    ("Mountain Car", "1", "Q(λ)-learning", 143.5, 4.3, (3, 9, _, _, 3)),
    ("Mountain Car", "2", "Q(0)-learning", 121.2, 8.6, (2, 2, _, _, 3)),
    ("Mountain Car", "2", "Q(λ)-learning", 162.0, 32.6, (6, 6, _, _, 2)),
    ("Mountain Car", "3", "Fuzzy Q(0)-learning", 125.9, 11.2, (4, 4, _, _, 3)),
    ("Mountain Car", "3", "Fuzzy Q(λ)-learning", 114.1, 3.5, (4, 4, _, _, 3)),
    ("Mountain Car", "4", "Fuzzy Q(0)-learning", 116.6, 2.9, (4, 4, _, _, 2)),
    ("Mountain Car", "4", "Fuzzy Q(λ)-learning", 114.1, 3.5, (4, 4, _, _, 3)),
]
ROWS = [r[:3] for r in TABLE3]
PUBLISHED = {r[:3]: r[3:] for r in TABLE3}  # key -> (M, S, config)


# ---------------------------------------------------------------------------------------------
# Inputs


def pipeline_variants() -> list[tuple[str, bool]]:
    """(id, exploratory) of `variants:` in pipelines/paper.yaml, in pipeline order."""
    text = PIPELINE.read_text(encoding="utf-8")
    out: list[list] = []
    for line in text[text.index("\nvariants:") :].splitlines():
        if m := re.match(r"\s*- id:\s*(\S+)\s*$", line):
            out.append([m.group(1), False])
        elif re.match(r"\s*exploratory:\s*true\s*$", line):
            out[-1][1] = True
    return [(a, b) for a, b in out]


VARIANTS = pipeline_variants()
ORDER = {v: i for i, (v, _) in enumerate(VARIANTS)}
EXPLORATORY = dict(VARIANTS)
DECLARED = [v for v, e in VARIANTS if not e]


@lru_cache(maxsize=1)
def cells() -> pd.DataFrame:
    return pd.read_parquet(PAPER / "cells.parquet")


@lru_cache(maxsize=None)
def has_cells(v: str) -> bool:
    """Whether `cells.parquet` holds the variant (today: the declared ones only)."""
    return v in set(cells()["variant"])


def read_csv(path: Path) -> pd.DataFrame:
    return pd.read_csv(path, dtype={"experiment": str})


def config_of(r) -> tuple:
    """A cell's (x, x_dot, theta, theta_dot, actions), None for a variable not in the model."""
    return tuple(None if pd.isna(r[c]) else int(r[c]) for c in RES + ["actions"])


@dataclass(frozen=True)
class Est:
    """The estimate a row is judged on: mean, sample std (NaN below two trials) and trials."""

    mean: float
    std: float
    n: int


def estimate(cell) -> Est:
    """Fresh-seed estimate where the cell has fresh trials, else the grid's seeds."""
    if cell["fresh_n"] > 0:
        return Est(float(cell["fresh_mean"]), float(cell["fresh_std"]), int(cell["fresh_n"]))
    return Est(float(cell["mean"]), float(cell["std"]), int(cell["n"]))


@lru_cache(maxsize=None)
def heatmap(v: str, key: tuple) -> pd.DataFrame:
    c = cells()
    system, exp, alg = key
    return c[(c.variant == v) & (c.system_title == system) & (c.experiment == exp) & (c.label == alg)]


@lru_cache(maxsize=None)
def best_cell(v: str, key: tuple) -> pd.Series:
    h = heatmap(v, key)
    b = h[h["best"]]
    assert len(b) == 1, (v, key, len(b))
    return b.iloc[0]


@lru_cache(maxsize=None)
def paper_cell(v: str, key: tuple) -> pd.Series | None:
    """Our cell at the paper's configuration, None when there is none with trials."""
    want = PUBLISHED[key][2]
    h = heatmap(v, key)
    hits = [r for _, r in h.iterrows() if config_of(r) == want]
    assert len(hits) <= 1
    if not hits or hits[0]["n"] < 1:
        return None
    return hits[0]


@lru_cache(maxsize=None)
def grid(key: tuple) -> frozenset:
    """The cells (configurations) of a row's heatmap, the same in every declared variant."""
    grids = {frozenset(config_of(r) for _, r in heatmap(v, key).iterrows()) for v in DECLARED}
    assert len(grids) == 1, key
    return grids.pop()


# ---------------------------------------------------------------------------------------------
# The rules


def has_spread(e: Est) -> bool:
    return e.n >= 2 and math.isfinite(e.std)


def tost_p(e: Est, M: float, S: float, n_paper: int, margin: tuple[float, float]) -> float:
    """TOST of m - M against (lo*M, hi*M): the larger one-sided Welch p; NaN when undecidable."""
    if not has_spread(e) or M <= 0:
        return math.nan
    lo, hi = margin
    if e.std == 0 and S == 0:  # no spread on either side: the point estimate decides, strictly
        return 0.0 if lo * M < e.mean - M < hi * M else 1.0
    p_lo = stats.ttest_ind_from_stats(
        e.mean, e.std, e.n, M * (1 + lo), S, n_paper, equal_var=False, alternative="greater"
    ).pvalue
    p_hi = stats.ttest_ind_from_stats(
        e.mean, e.std, e.n, M * (1 + hi), S, n_paper, equal_var=False, alternative="less"
    ).pvalue
    return float(max(p_lo, p_hi))


def within_2se(e: Est, M: float, S: float, n_paper: int) -> bool:
    return has_spread(e) and abs(e.mean - M) <= 2 * math.sqrt(S * S / n_paper + e.std * e.std / e.n)


def verdict(e: Est | None, M: float, S: float, n_paper: int) -> str | None:
    """The scale of 2026-12-05 (issue #46), first that applies; None without an estimate."""
    if e is None:
        return None
    if not has_spread(e) or M <= 0:
        return "undecided"
    if tost_p(e, M, S, n_paper, EQUIV_MARGIN) <= ALPHA:
        return "equivalent"
    if tost_p(e, M, S, n_paper, TWOFOLD_MARGIN) <= ALPHA:
        return "within-2x"
    if within_2se(e, M, S, n_paper):
        return "consistent-but-wide"
    return "differs"


def verdict_2se(e: Est | None, M: float, S: float) -> str | None:
    """The old rule (the fit measure's): within 2 SE at n_paper = 10, else 0.5 <= m/M <= 2."""
    if e is None:
        return None
    if within_2se(e, M, S, HEADLINE_N):
        return "replicates"
    if M > 0 and 0.5 <= e.mean / M <= 2:
        return "within-2x"
    return "no"


def cause(best: str, designated: bool, at_paper: str | None) -> str:
    if best in REPLICATING:
        return "replicates"
    if designated:
        return "paper-inconsistent"
    if at_paper is None:
        return "unexplained"
    return "argmin" if at_paper in REPLICATING else "differs-at-paper-config"


def cause_2se(best: str, in_pair: bool, at_paper: str | None) -> str:
    if best == "replicates":
        return "replicates"
    if in_pair:
        return "paper-inconsistent"
    if at_paper is None:
        return "unexplained"
    return "argmin" if at_paper == "replicates" else "learner"


@dataclass(frozen=True)
class Pair:
    a: tuple
    b: tuple
    equal: bool  # each configuration is a cell of the other's grid: equal means implied
    high: tuple | None  # the row whose value the grids say cannot be the higher one (None: equal)


def comparable_pairs() -> list[Pair]:
    out = []
    for i, a in enumerate(ROWS):
        for b in ROWS[i + 1 :]:
            if a[0] != b[0] or a[2] != b[2] or a[1] == b[1]:
                continue  # the label carries representation and algorithm
            a_in_b = PUBLISHED[a][2] in grid(b)
            b_in_a = PUBLISHED[b][2] in grid(a)
            if a_in_b and b_in_a:
                out.append(Pair(a, b, True, None))
            elif a_in_b:  # b's published value is the minimum of a grid holding a's configuration
                out.append(Pair(a, b, False, b))
            elif b_in_a:
                out.append(Pair(a, b, False, a))
    return out


def pair_p(p: Pair, n_paper: int) -> float:
    (ma, sa, _), (mb, sb, _) = PUBLISHED[p.a], PUBLISHED[p.b]
    return float(stats.ttest_ind_from_stats(ma, sa, n_paper, mb, sb, n_paper, equal_var=False).pvalue)


def contradictory(p: Pair, n_paper: int) -> bool:
    if pair_p(p, n_paper) >= ALPHA:
        return False
    if p.equal:
        return True
    low = p.b if p.high == p.a else p.a
    return PUBLISHED[p.high][0] > PUBLISHED[low][0]


def designated_row(p: Pair) -> tuple:
    """The row a contradictory pair marks `paper-inconsistent`."""
    if p.equal:
        return max(p.a, p.b, key=lambda k: int(k[1]))  # the later experiment's
    return p.high


@lru_cache(maxsize=None)
def in_contradictory_pair(n_paper: int) -> frozenset:
    return frozenset(k for p in comparable_pairs() if contradictory(p, n_paper) for k in (p.a, p.b))


@lru_cache(maxsize=None)
def designated(n_paper: int) -> frozenset:
    return frozenset(designated_row(p) for p in comparable_pairs() if contradictory(p, n_paper))


@dataclass(frozen=True)
class Judged:
    est: Est
    at_paper: Est | None
    verdict: str
    paper_cell_verdict: str | None
    cause: str
    config_match: bool


@lru_cache(maxsize=None)
def judged(v: str, key: tuple, n_paper: int) -> Judged:
    M, S, cfg = PUBLISHED[key]
    b = best_cell(v, key)
    e = estimate(b)
    pc = paper_cell(v, key)
    at = None if pc is None else estimate(pc)
    ver, pver = verdict(e, M, S, n_paper), verdict(at, M, S, n_paper)
    return Judged(e, at, ver, pver, cause(ver, key in designated(n_paper), pver), config_of(b) == cfg)


def ln_ratio(m: float, M: float) -> float:
    return abs(math.log(m / M)) if m > 0 and M > 0 else math.inf


def yes(flag: bool) -> str:
    return "yes" if flag else "no"


# The fit measure of 2026-11-30 (crates/qsweep-report/src/replication/compare/fit.rs `fit_order` uses the same keys): rows
# within 2 SE desc, rows within 2x by ratio (not within 2 SE) desc, matching configurations desc,
# |ln geometric mean of m/M| asc, then pipeline order. With the first key tied, counting the second
# key inclusively or exclusively ranks alike.
def fit_key(v: str, rows: list[tuple]) -> tuple:
    rep = w2 = cfg = 0
    logs = []
    for key in rows:
        M, S, _ = PUBLISHED[key]
        j = judged(v, key, HEADLINE_N)
        old = verdict_2se(j.est, M, S)
        rep += old == "replicates"
        w2 += old == "within-2x"
        cfg += j.config_match
        if j.est.mean > 0 and M > 0:
            logs.append(math.log(j.est.mean / M))
    off = abs(float(np.mean(logs))) if logs else math.inf
    return (-rep, -w2, -cfg, off, ORDER[v])


def close(a, b, rel: float = 1e-9, abs_: float = 1e-12) -> bool:
    if pd.isna(a) or pd.isna(b):
        return bool(pd.isna(a) and pd.isna(b))
    return math.isclose(float(a), float(b), rel_tol=rel, abs_tol=abs_)


def key_of(r) -> tuple:
    return (r["system"], str(r["experiment"]), r["algorithm"])


# ---------------------------------------------------------------------------------------------
# Tests


def test_typed_table3_matches_the_reports_paper_columns() -> None:
    for v in DECLARED:
        t3 = read_csv(PAPER / v / "table3.csv")
        assert [key_of(r) for _, r in t3.iterrows()] == ROWS, v
        for _, r in t3.iterrows():
            M, S, cfg = PUBLISHED[key_of(r)]
            assert (r["paper_mean"], r["paper_std"]) == (M, S), (v, key_of(r))
            got = tuple(None if pd.isna(r[f"paper_{c}"]) else int(r[f"paper_{c}"]) for c in RES + ["actions"])
            assert got == cfg, (v, key_of(r))


def test_pipeline_and_variants_csv_name_the_same_variants() -> None:
    vs = read_csv(PAPER / "variants.csv")
    assert sorted(vs["variant"]) == sorted(ORDER)
    for _, r in vs.iterrows():
        assert r["exploratory"] == yes(EXPLORATORY[r["variant"]]), r["variant"]
    assert set(DECLARED) <= set(cells()["variant"]) <= set(ORDER), "cells.parquet holds every declared variant"


def test_the_papers_pairs_and_contradictions_at_each_n() -> None:
    pairs = comparable_pairs()
    assert len(pairs) == 9
    # The reviewer's numbers quoted in the amendment: the Ball-Beam crisp Q(0) pair.
    bb = [p for p in pairs if p.a[0] == "Ball-Beam" and p.a[2] == "Q(0)-learning"]
    assert len(bb) == 1
    for n_paper, p in [(10, 2.8e-4), (5, 0.013), (3, 0.071)]:
        assert math.isclose(pair_p(bb[0], n_paper), p, rel_tol=0.05), n_paper
    assert designated_row(bb[0]) == ("Ball-Beam", "1", "Q(0)-learning"), "90.5 is Exp. 1's minimum"
    assert designated(10) == designated(5) == {("Ball-Beam", "1", "Q(0)-learning")}
    assert designated(3) == frozenset()


@pytest.mark.parametrize("v", DECLARED)
def test_table3_new_columns(v: str) -> None:
    t3 = read_csv(PAPER / v / "table3.csv")
    cols = t3.columns.tolist()
    assert cols[cols.index("paper_cell_equivalent_n100") + 1 :] == NEW_TABLE3_COLUMNS
    n = HEADLINE_N
    for _, r in t3.iterrows():
        key = key_of(r)
        where = (v, *key)
        M, S, _ = PUBLISHED[key]
        b = best_cell(v, key)
        assert config_of(b) == tuple(
            None if pd.isna(r[c]) else int(r[c]) for c in RES + ["actions"]
        ), where
        j = judged(v, key, n)
        e, at = j.est, j.at_paper
        # The old rule, kept for comparison.
        old, old_pc = verdict_2se(e, M, S), verdict_2se(at, M, S)
        assert r["verdict_2se"] == old, where
        if old_pc is None:
            assert pd.isna(r["paper_cell_verdict_2se"]), where
        else:
            assert r["paper_cell_verdict_2se"] == old_pc, where
        assert r["cause_2se"] == cause_2se(old, key in in_contradictory_pair(n), old_pc), where
        # Pairs and designation.
        assert r["contradictory_pair"] == yes(key in in_contradictory_pair(n)), where
        assert r["paper_inconsistent"] == yes(key in designated(n)), where
        # The within-2x TOST's p and the scale.
        assert close(r["tost2x_p_n10"], tost_p(e, M, S, n, TWOFOLD_MARGIN), 1e-6, 1e-12), where
        want_pc_p = math.nan if at is None else tost_p(at, M, S, n, TWOFOLD_MARGIN)
        assert close(r["paper_cell_tost2x_p_n10"], want_pc_p, 1e-6, 1e-12), where
        # The existing equivalence TOST, recomputed the same way: checks the machinery.
        assert close(r["tost_p_n10"], tost_p(e, M, S, n, EQUIV_MARGIN), 1e-6, 1e-12), where
        assert r["verdict"] == j.verdict, where
        if j.paper_cell_verdict is None:
            assert pd.isna(r["paper_cell_verdict"]), where
        else:
            assert r["paper_cell_verdict"] == j.paper_cell_verdict, where
        assert r["cause"] == j.cause, where
        # Spread: s / S with its 95 % F interval, n_paper = 10.
        if not has_spread(e) or S <= 0:
            for c in ["std_ratio", "std_ratio_lo", "std_ratio_hi", "spread_differs"]:
                assert pd.isna(r[c]), (where, c)
        else:
            r2 = (e.std / S) ** 2
            lo = math.sqrt(r2 / stats.f.ppf(0.975, e.n - 1, n - 1))
            hi = math.sqrt(r2 / stats.f.ppf(0.025, e.n - 1, n - 1))
            assert close(r["std_ratio"], e.std / S), where
            assert close(r["std_ratio_lo"], lo, 1e-6), where
            assert close(r["std_ratio_hi"], hi, 1e-6), where
            assert r["spread_differs"] == yes(lo > 1 or hi < 1), where


@pytest.fixture(scope="module")
def by_n() -> pd.DataFrame:
    return read_csv(PAPER / "verdicts_by_n.csv")


def test_verdicts_by_n_has_one_line_per_variant_row_and_n(by_n: pd.DataFrame) -> None:
    assert by_n.columns.tolist() == BY_N_COLUMNS
    got = sorted((r.variant, key_of(r), int(r.n_paper)) for _, r in by_n.iterrows())
    want = sorted((v, k, n) for v, _ in VARIANTS for k in ROWS for n in NS)
    assert got == want
    for _, r in by_n.iterrows():
        assert r["exploratory"] == yes(EXPLORATORY[r["variant"]]), r["variant"]


@pytest.mark.parametrize("n_paper", NS)
def test_verdicts_by_n_recomputed(by_n: pd.DataFrame, n_paper: int) -> None:
    lines = by_n[by_n["n_paper"] == n_paper]
    for _, r in lines.iterrows():
        v, key = r["variant"], key_of(r)
        where = (v, *key, n_paper)
        assert r["contradictory_pair"] == yes(key in in_contradictory_pair(n_paper)), where
        assert r["paper_inconsistent"] == yes(key in designated(n_paper)), where
        M, S, _ = PUBLISHED[key]
        line_est = Est(float(r["mean"]), float(r["std"]), int(r["n"]))
        if not has_cells(v):
            # An exploratory variant without cells: its verdict recomputed from the estimate the
            # line states, its cause from the line's verdicts.
            assert r["verdict"] == verdict(line_est, M, S, n_paper), where
            pc = None if pd.isna(r["paper_cell_verdict"]) else r["paper_cell_verdict"]
            assert pc is None or pc in SCALE, where
            assert r["cause"] == cause(r["verdict"], key in designated(n_paper), pc), where
            continue
        j = judged(v, key, n_paper)
        assert close(line_est.mean, j.est.mean) and close(line_est.std, j.est.std), where
        assert line_est.n == j.est.n, where
        assert r["verdict"] == j.verdict, where
        if j.paper_cell_verdict is None:
            assert pd.isna(r["paper_cell_verdict"]), where
        else:
            assert r["paper_cell_verdict"] == j.paper_cell_verdict, where
        assert r["cause"] == j.cause, where


@pytest.mark.parametrize("n_paper", NS)
def test_closest_variant_per_row(by_n: pd.DataFrame, n_paper: int) -> None:
    lines = by_n[by_n["n_paper"] == n_paper]
    for key in ROWS:
        M = PUBLISHED[key][0]
        mine = lines[lines.apply(key_of, axis=1) == key]
        named = mine[["closest_variant", "closest_exploratory", "closest_ratio", "closest_verdict"]]
        assert len(named.drop_duplicates()) == 1, (key, n_paper, "one closest variant per row and n")
        c = named.iloc[0]
        where = (*key, n_paper, c["closest_variant"])
        assert c["closest_variant"] in ORDER, where
        assert c["closest_exploratory"] == yes(EXPLORATORY[c["closest_variant"]]), where
        own = mine[mine["variant"] == c["closest_variant"]].iloc[0]
        assert c["closest_verdict"] == own["verdict"], where
        # Variants with cells, recomputed: (verdict rank, |ln m/M|, pipeline order).
        scored = {}
        for v in ORDER:
            if has_cells(v):
                j = judged(v, key, n_paper)
                scored[v] = (SCALE.index(j.verdict), ln_ratio(j.est.mean, M), ORDER[v])
        first = min(scored, key=scored.get)
        # Variants without cells (exploratory) can only be ranked by the verdicts they report.
        rest = mine[~mine["variant"].map(has_cells)]
        best_rest = min((SCALE.index(x) for x in rest["verdict"]), default=len(SCALE))
        if c["closest_variant"] in scored:
            assert c["closest_variant"] == first, where
            j = judged(first, key, n_paper)
            assert close(c["closest_ratio"], j.est.mean / M), where
            assert c["closest_verdict"] == j.verdict, where
            assert SCALE.index(c["closest_verdict"]) <= best_rest, where
        else:
            named_score = (
                SCALE.index(c["closest_verdict"]),
                ln_ratio(float(c["closest_ratio"]), 1.0),
                ORDER[c["closest_variant"]],
            )
            assert named_score < scored[first], where
            assert SCALE.index(c["closest_verdict"]) == best_rest, where


def test_leave_one_row_out() -> None:
    cv = read_csv(PAPER / "cross_validation.csv")
    assert cv.columns.tolist() == ["system", "experiment", "algorithm", "chosen_variant", "verdict", "verdict_2se"]
    assert [key_of(r) for _, r in cv.iterrows()] == ROWS
    for _, r in cv.iterrows():
        held = key_of(r)
        rest = [k for k in ROWS if k != held]
        chosen = min(DECLARED, key=lambda v: fit_key(v, rest))
        M, S, _ = PUBLISHED[held]
        j = judged(chosen, held, HEADLINE_N)
        assert r["chosen_variant"] == chosen, held
        assert r["verdict"] == j.verdict, held
        assert r["verdict_2se"] == verdict_2se(j.est, M, S), held


def test_variants_counts(by_n: pd.DataFrame) -> None:
    vs = read_csv(PAPER / "variants.csv")
    for c in ["within_2se", "ratio_within_2x", "replicating_n3", "replicating_n5", "replicating_n10",
              "within_2x_n10", "consistent_but_wide_n10", "differs_n10"]:
        assert c in vs.columns, c
    assert "replicating" not in vs.columns and "within_2x" not in vs.columns, "the old names are renamed"
    for _, r in vs.iterrows():
        v = r["variant"]
        mine = by_n[by_n["variant"] == v]
        for n_paper in NS:
            if not has_cells(v):
                verdicts = mine[mine["n_paper"] == n_paper]["verdict"].tolist()
            else:
                verdicts = [judged(v, k, n_paper).verdict for k in ROWS]
            assert r[f"replicating_n{n_paper}"] == sum(x in REPLICATING for x in verdicts), (v, n_paper)
            if n_paper == HEADLINE_N:
                assert r["within_2x_n10"] == verdicts.count("within-2x"), v
                assert r["consistent_but_wide_n10"] == verdicts.count("consistent-but-wide"), v
                assert r["differs_n10"] == verdicts.count("differs"), v
                if has_cells(v):
                    assert r["equivalent_n10"] == verdicts.count("equivalent"), v
        if has_cells(v):
            old = [verdict_2se(judged(v, k, HEADLINE_N).est, *PUBLISHED[k][:2]) for k in ROWS]
            assert r["within_2se"] == old.count("replicates"), v
            assert r["ratio_within_2x"] == old.count("within-2x"), v
    # The declared variants are still ranked by the fit measure on all rows.
    ranked = vs[vs["exploratory"] == "no"].sort_values("rank")["variant"].tolist()
    assert ranked == sorted(DECLARED, key=lambda v: fit_key(v, ROWS))
