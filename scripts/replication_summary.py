#!/usr/bin/env python3
"""Numbers behind REPLICATION.md's verdicts, computed from a report's files.

Usage: .venv/bin/python scripts/replication_summary.py [reports/paper]

For a report of a pipeline with variants (reports/paper: one folder per variant of the paper,
variants.csv), prints Markdown: every variant's tally recomputed from its table3.csv (and checked
against variants.csv), the ranking by the pre-registered fit measure (docs/preregistration.md),
Table III under `as-written` and under the best-fitting variant side by side, then the paper's
conclusions re-checked under both. For a report without variants, the last part for that report.
Analysis only; qsweep itself is Rust. Every figure here can be recomputed with any tool.

Two rules are in play (docs/preregistration.md). The old one, two standard errors then within 2×
(`verdict` and `causes` here, table3.csv's `verdict_2se` and `cause_2se`), is recomputed here from
the means and stds. The verdict scale of issue #46 (table3.csv's `verdict`, `paper_cell_verdict`,
`cause`: equivalent / within-2x / consistent-but-wide / differs / undecided, a TOST at the paper's
n taken as 10) is read from table3.csv and tallied; tests/python/test_verdicts.py recomputes it.
Only `equivalent` and `within-2x` count as replicating.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pandas as pd

SYSTEMS = ["ball-beam", "cart-pole", "mountain-car"]
TITLE = {"ball-beam": "Ball-Beam", "cart-pole": "Cart-Pole", "mountain-car": "Mountain Car"}


def best(cells: pd.DataFrame) -> pd.DataFrame:
    return cells[cells["best"]].set_index(["system", "experiment", "algorithm"])


RES_COLS = ["x", "x_dot", "theta", "theta_dot"]
# The verdict scale (table3.csv's `verdict`) in variants.csv's order, with its column there.
SCALE = {
    "equivalent": "equivalent_n10",
    "within-2x": "within_2x_n10",
    "consistent-but-wide": "consistent_but_wide_n10",
    "differs": "differs_n10",
}
REPLICATING = ("equivalent", "within-2x")
# The causes on the verdict scale (table3.csv's `cause`), in the order the comparison page tallies them.
CAUSES = ["replicates", "argmin", "paper-inconsistent", "differs-at-paper-config", "unexplained"]
# The old cause rule's labels (`cause_2se`).
CAUSES_2SE = ["replicates", "argmin", "paper-inconsistent", "learner", "unexplained"]
# The old rule's verdicts as this script words them, and as table3.csv's `verdict_2se` does.
WORD_2SE = {"replicates": "replicates", "within 2×": "within-2x", "does not replicate": "no"}


def verdict(r: pd.Series) -> str:
    """The old rule (table3.csv's `verdict_2se`), recomputed independently of qsweep's
    (crates/qsweep-report/src/replication/stats/verdict.rs): two standard errors, else within 2x, else not. A row without std
    (one trial) cannot be within 2 SE but can be within 2x. "replicates" here means within 2 SE,
    which no longer counts as replicating in a headline (the verdict scale decides that)."""
    if pd.isna(r["mean"]):
        return "does not replicate"
    if pd.notna(r["std"]):
        se = math.sqrt(r["paper_std"] ** 2 / 10 + r["std"] ** 2 / r["n"])
        if abs(r["mean"] - r["paper_mean"]) <= 2 * se:
            return "replicates"
    if 0.5 <= r["mean"] / r["paper_mean"] <= 2:
        return "within 2×"
    return "does not replicate"


def configs(r: pd.Series) -> tuple[list[int], list[int]]:
    ours = [int(r[c]) for c in RES_COLS if pd.notna(r[c])] + [int(r["actions"])]
    paper = [int(r[f"paper_{c}"]) for c in RES_COLS + ["actions"] if pd.notna(r[f"paper_{c}"])]
    return ours, paper


def judged(t3: pd.DataFrame) -> pd.DataFrame:
    """Table III as its rows are judged: where a row's best cell was re-run on fresh seeds
    (`fresh_n` > 0, a pipeline with `fresh:`), their mean, std and n replace the selection's."""
    if "fresh_n" not in t3.columns:
        return t3
    t = t3.copy()
    fresh = t["fresh_n"] > 0
    for ours, theirs in [("mean", "fresh_mean"), ("std", "fresh_std"), ("n", "fresh_n")]:
        t[ours] = t[ours].astype(float)
        t.loc[fresh, ours] = t.loc[fresh, theirs]
    return t


def tally(t3: pd.DataFrame) -> dict:
    """One variant's fit, from its table3.csv, as variants.csv states it: the old rule's counts
    (`within_2se`, `ratio_within_2x`) recomputed, the verdict scale's counted from the `verdict`
    column (`replicating_n10`: equivalent or within-2x), the TOST at 100 runs from `equivalent_n100`."""
    t3 = judged(t3)
    rows = t3[t3["paper_mean"].notna() & t3["mean"].notna()]
    v = [verdict(r) for _, r in rows.iterrows()]
    scale = rows["verdict"].value_counts()
    config = sum(configs(r)[0] == configs(r)[1] for _, r in rows.iterrows())
    order = ordered = 0
    for _, same in rows.groupby(["system", "experiment"]):
        if len(same) >= 2:
            ordered += 1
            a = same.sort_values("mean", kind="stable")["algorithm"].tolist()
            b = same.sort_values("paper_mean", kind="stable")["algorithm"].tolist()
            order += a == b
    geo = math.exp(sum(math.log(r["mean"] / r["paper_mean"]) for _, r in rows.iterrows()) / len(rows))
    return {
        "rows": len(rows),
        "replicating_n10": int(sum(scale.get(k, 0) for k in REPLICATING)),
        **{col: int(scale.get(k, 0)) for k, col in SCALE.items()},
        "within_2se": v.count("replicates"),
        "ratio_within_2x": v.count("within 2×"),
        "config_match": config,
        "order_match": order,
        "order_experiments": ordered,
        "geo_mean_ratio": geo,
        "equivalent_n100": int((rows["equivalent_n100"] == "yes").sum()),
    }


def fit_key(t: dict) -> tuple:
    """The pre-registered order (unchanged by issue #46): rows within 2 SE, ratio within 2x (both
    the old rule), matching configurations, |ln g|."""
    return (-t["within_2se"], -t["ratio_within_2x"], -t["config_match"], abs(math.log(t["geo_mean_ratio"])))


def paper_cell(cells: pd.DataFrame, t3: pd.DataFrame) -> pd.DataFrame:
    """Per Table III row, our cell at the paper's stated configuration (one variant's cells, from
    cells.parquet), on its fresh-seed estimate where it has one: columns mean, std, n (NaN where
    the row has no such cell)."""
    out = []
    for _, r in t3.iterrows():
        c = cells[
            (cells.system_title == r.system) & (cells.experiment.astype(str) == str(r.experiment)) & (cells.label == r.algorithm)
        ]
        for col in RES_COLS + ["actions"]:
            want = r[f"paper_{col}"]
            c = c[c[col].isna()] if pd.isna(want) else c[c[col] == want]
        if len(c) != 1 or pd.isna(r["paper_actions"]) or c.iloc[0]["n"] == 0:
            out.append({"mean": math.nan, "std": math.nan, "n": 0})
            continue
        c = c.iloc[0]
        f = "fresh_" if c.get("fresh_n", 0) > 0 else ""
        out.append({"mean": c[f"{f}mean"], "std": c[f"{f}std"], "n": int(c[f"{f}n"])})
    return pd.DataFrame(out, index=t3.index)


def consistency(t3: pd.DataFrame, cells: pd.DataFrame, n: int = 10) -> list[dict]:
    """Every pair of Table III rows (same system, representation, algorithm; different experiments)
    where one row's published configuration is a cell of the other's grid, with the two-sided Welch
    test of the published means (`n` runs each: the paper never states it); contradictory when
    p < 0.05 and the difference goes the way the grids forbid (the grid's minimum above the
    contained row's value). `marked` ("a", "b"; "" for a consistent pair): the row a contradictory
    pair costs, the one whose published minimum is undercut by a cell of its own grid; where each
    configuration lies in the other's grid, the later experiment's (b)."""
    from scipy import stats

    def cfg(r: pd.Series) -> tuple | None:
        if pd.isna(r["paper_actions"]):
            return None
        return tuple(int(r[f"paper_{c}"]) for c in RES_COLS if pd.notna(r[f"paper_{c}"])) + (int(r["paper_actions"]),)

    def grid(r: pd.Series) -> set:
        c = cells[(cells.system_title == r.system) & (cells.experiment.astype(str) == str(r.experiment)) & (cells.label == r.algorithm)]
        return {tuple(int(x[k]) for k in RES_COLS if pd.notna(x[k])) + (int(x["actions"]),) for _, x in c.iterrows()}

    rows = [r for _, r in t3.iterrows() if pd.notna(r["paper_mean"])]
    grids = [grid(r) for r in rows]
    out = []
    for i, a in enumerate(rows):
        for j in range(i + 1, len(rows)):
            b = rows[j]
            if (a.system, a.algorithm) != (b.system, b.algorithm) or a.experiment == b.experiment:
                continue
            a_in_b, b_in_a = cfg(a) in grids[j], cfg(b) in grids[i]
            if not (a_in_b or b_in_a):
                continue
            t, p = stats.ttest_ind_from_stats(b.paper_mean, b.paper_std, n, a.paper_mean, a.paper_std, n, equal_var=False)
            forbidden = (a_in_b and b.paper_mean > a.paper_mean) or (b_in_a and a.paper_mean > b.paper_mean)
            bad = bool(p < 0.05 and forbidden)
            # Only a's grid holds b's configuration: a's published minimum is the one undercut.
            marked = ("a" if b_in_a and not a_in_b else "b") if bad else ""
            out.append({"a": i, "b": j, "row_a": a, "row_b": b, "t": float(t), "p": float(p), "contradictory": bad, "marked": marked})
    return out


def causes(t3: pd.DataFrame, cells: pd.DataFrame) -> list[str]:
    """Each Table III row's cause by the old rule (issue #40; table3.csv's `cause_2se`), recomputed
    from cells.parquet and the paper's values: replicates (within 2 SE), paper-inconsistent (both
    rows of a contradictory pair at 10 runs), argmin, learner, unexplained."""
    j = judged(t3)
    at = paper_cell(cells, t3)
    rows = [i for i, r in t3.iterrows() if pd.notna(r["paper_mean"])]
    bad = set()
    for p in consistency(t3, cells):
        if p["contradictory"]:
            bad |= {rows[p["a"]], rows[p["b"]]}
    out = []
    for i, r in j.iterrows():
        if pd.isna(r["paper_mean"]):
            out.append("")
            continue
        if verdict(r) == "replicates":
            out.append("replicates")
        elif i in bad:
            out.append("paper-inconsistent")
        elif at.loc[i, "n"] == 0:
            out.append("unexplained")
        else:
            pc = verdict(pd.Series({**r.to_dict(), "mean": at.loc[i, "mean"], "std": at.loc[i, "std"], "n": at.loc[i, "n"]}))
            out.append("argmin" if pc == "replicates" else "learner")
    return out


def cause_table(d: Path, v: str) -> None:
    """The per-row cause table of REPLICATION.md for variant `v`, and its tallies: the verdicts and
    causes of the verdict scale (table3.csv's `verdict`, `paper_cell_verdict`, `cause`) beside the
    old rule's (within 2 SE, recomputed; equal to `verdict_2se`, `paper_cell_verdict_2se`,
    `cause_2se`)."""
    cells = pd.read_parquet(d / "cells.parquet")
    cells = cells[cells.variant == v]
    t3 = pd.read_csv(d / v / "table3.csv", dtype={"experiment": str})
    j = judged(t3)
    at = paper_cell(cells, t3)
    why_2se = causes(t3, cells)
    # The declared variant whose best cell (judged estimate) comes closest to the paper, per row.
    listed = pd.read_csv(d / "variants.csv")
    others = {
        o: judged(pd.read_csv(d / o / "table3.csv", dtype={"experiment": str}))
        for o, x in zip(listed["variant"], listed["exploratory"].astype(str))
        if x == "no" and (d / o / "table3.csv").is_file()
    }
    text = lambda x: "" if pd.isna(x) else str(x)  # noqa: E731
    print(f"### Why each row does or does not replicate, under `{v}`\n")
    print(
        "| system | exp. | algorithm | paper | ours, best cell | verdict | within 2 SE (old rule) "
        "| ours at paper's config | verdict | within 2 SE (old rule) | cause | cause (old rule) "
        "| closest variant (ours/paper) |"
    )
    print("|---|---|---|---:|---:|---|---|---:|---|---|---|---|---|")
    for (i, r), c in zip(j.iterrows(), why_2se):
        pc = pd.Series({**r.to_dict(), "mean": at.loc[i, "mean"], "std": at.loc[i, "std"], "n": at.loc[i, "n"]})
        near = min(others, key=lambda o: (abs(math.log(others[o].loc[i, "mean"] / r.paper_mean)), o))
        ratio = others[near].loc[i, "mean"] / r.paper_mean
        print(
            f"| {r.system} | {r.experiment} | {r.algorithm} | {r.paper_mean:g} ± {r.paper_std:g} "
            f"| {r['mean']:.1f} ± {r['std']:.1f} | {text(t3.loc[i, 'verdict'])} | {verdict(r)} "
            f"| {pc['mean']:.1f} ± {pc['std']:.1f} | {text(t3.loc[i, 'paper_cell_verdict'])} | {verdict(pc)} "
            f"| {text(t3.loc[i, 'cause'])} | {c} | `{near}` ({ratio:.2f}) |"
        )
    tallied = {c: int((t3["cause"] == c).sum()) for c in CAUSES}
    print("\nTally: " + ", ".join(f"{n} {c}" for c, n in tallied.items()) + ".")
    tallied = {c: why_2se.count(c) for c in CAUSES_2SE}
    print("Old rule (within 2 SE; both rows of a contradictory pair paper-inconsistent): " + ", ".join(f"{n} {c}" for c, n in tallied.items()) + ".\n")
    print("### The paper against itself (pairs of Table III rows whose grids overlap)\n")
    print(
        "Contradictory: the paper's means taken over 10 runs each (over 5 and 3 in the last two columns); "
        "marked: the row the pair costs (a or b).\n"
    )
    print("| system | algorithm | exp. a | paper a | exp. b | paper b | Welch t (b − a) | p | contradictory | marked | n = 5 | n = 3 |")
    print("|---|---|---|---:|---|---:|---:|---:|---|---|---|---|")
    yes = lambda b: "yes" if b else "no"  # noqa: E731
    by_n = {n: consistency(t3, cells, n) for n in (10, 5, 3)}
    for p, p5, p3 in zip(by_n[10], by_n[5], by_n[3]):
        a, b = p["row_a"], p["row_b"]
        print(
            f"| {a.system} | {a.algorithm} | {a.experiment} | {a.paper_mean:g} ± {a.paper_std:g} | {b.experiment} "
            f"| {b.paper_mean:g} ± {b.paper_std:g} | {p['t']:.2f} | {p['p']:.2g} | {yes(p['contradictory'])} "
            f"| {p['marked']} | {yes(p5['contradictory'])} | {yes(p3['contradictory'])} |"
        )
    print()


def study(d: Path) -> str:
    """Print the variant study; return the id of the best-fitting declared variant. Exploratory
    variants have no folder of their own (their rows are in variants.csv only) and are skipped."""
    listed = pd.read_csv(d / "variants.csv")
    listed = listed[[(d / v / "table3.csv").is_file() for v in listed["variant"]]]
    ids = listed["variant"].tolist()
    tallies = {v: tally(pd.read_csv(d / v / "table3.csv", dtype={"experiment": str})) for v in ids}
    for _, r in listed.iterrows():
        t = tallies[r["variant"]]
        for k, want in t.items():
            got = r[k]
            ok = math.isclose(got, want, rel_tol=1e-9) if k == "geo_mean_ratio" else int(got) == want
            assert ok, f"variants.csv {r['variant']}.{k} = {got}, recomputed {want}"
    # variants.csv lists the declared variants first, each part in fit order.
    explo = dict(zip(listed["variant"], listed["exploratory"].astype(str) == "yes"))
    ranked = sorted(ids, key=lambda v: (explo[v], fit_key(tallies[v]), ids.index(v)))
    assert ranked == ids, f"variants.csv order {ids} differs from the recomputed ranking {ranked}"
    print("### Every variant's fit (variants.csv, recomputed from each variant's table3.csv)\n")
    print(
        "Replicate: equivalent or within 2× by TOST, the paper's means taken over 10 runs (the verdict "
        "scale). The ranking keeps the pre-registered fit measure: rows within 2 SE, then ratio within 2× "
        "(the old rule), configurations matching, |ln geo. mean|.\n"
    )
    print(
        "| rank | variant | replicate | equivalent | within 2× (TOST) | consistent but wide | differs "
        "| within 2 SE (old rule) | ratio within 2× (old rule) | neither (old rule) | configs match "
        "| Q(0)/Q(λ) order | geo. mean ours/paper |"
    )
    print("|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for i, v in enumerate(ranked, 1):
        t = tallies[v]
        rest = t["rows"] - t["within_2se"] - t["ratio_within_2x"]
        print(
            f"| {i} | `{v}` | {t['replicating_n10']} | {t['equivalent_n10']} | {t['within_2x_n10']} "
            f"| {t['consistent_but_wide_n10']} | {t['differs_n10']} | {t['within_2se']} | {t['ratio_within_2x']} "
            f"| {rest} | {t['config_match']} | {t['order_match']}/{t['order_experiments']} | {t['geo_mean_ratio']:.2f} |"
        )
    best = next(v for v in ranked if not explo[v])
    print(f"\nBest fit under the pre-registered measure: `{best}`.\n")
    side_by_side(d, "as-written", best)
    if (d / "cells.parquet").is_file() and "paper_cell_mean" in pd.read_csv(d / best / "table3.csv", nrows=0).columns:
        cause_table(d, best)
    return best


def scale_word(r: pd.Series) -> str:
    """A row's verdict on the scale of issue #46, as table3.csv's `verdict` states it ("" without)."""
    v = r.get("verdict")
    return "" if v is None or pd.isna(v) else str(v)


def side_by_side(d: Path, a: str, b: str) -> None:
    ta = pd.read_csv(d / a / "table3.csv", dtype={"experiment": str})
    tb = pd.read_csv(d / b / "table3.csv", dtype={"experiment": str})
    print(f"### Table III: paper, `{a}` and `{b}`\n")
    print(
        f"| system | exp. | algorithm | paper | paper config | `{a}` | verdict | within 2 SE (old rule) "
        f"| `{b}` | config | successes | verdict | within 2 SE (old rule) |"
    )
    print("|---|---|---|---:|---|---:|---|---|---:|---|---:|---|---|")
    for (_, x), (_, y) in zip(ta.iterrows(), tb.iterrows()):
        assert (x.system, x.experiment, x.algorithm) == (y.system, y.experiment, y.algorithm)
        ours_b, paper_cfg = configs(y)
        print(
            f"| {x.system} | {x.experiment} | {x.algorithm} | {x.paper_mean:g} ± {x.paper_std:g} | {paper_cfg} "
            f"| {x['mean']:.1f} ± {x['std']:.1f} | {scale_word(x)} | {verdict(x)} | {y['mean']:.1f} ± {y['std']:.1f} "
            f"| {ours_b} | {int(y.successes)}/{int(y.n)} | {scale_word(y)} | {verdict(y)} |"
        )
    print()


def main() -> None:
    d = Path(sys.argv[1] if len(sys.argv) > 1 else "reports/paper")
    if (d / "variants.csv").is_file():
        best = study(d)
        for v in dict.fromkeys(["as-written", best]):
            print(f"\n## Conclusions under `{v}`\n")
            conclusions(d / v)
    else:
        conclusions(d)


def conclusions(d: Path) -> None:
    cells = pd.read_parquet(d / "cells.parquet")
    b = best(cells)
    conv = cells.groupby(["system", "experiment", "algorithm"]).agg(
        cells=("n", "size"), full=("all_converged", "sum"), trials=("n", "sum"), ok=("successes", "sum")
    )

    print("### Table III side by side\n")
    print("Verdict: table3.csv's, on the pre-registered scale (docs/preregistration.md, issue #46):")
    print("*equivalent* or *within-2x* by TOST (the paper's means taken over 10 runs) replicate;")
    print("*consistent-but-wide*, *differs*, *undecided* do not. Within 2 SE (old rule): *replicates*")
    print("when the difference of the means is within two standard errors (√(s₁²/n₁ + s₂²/n₂), the")
    print("paper's n = 10); *within 2×* when it is not, but our mean is between half and twice the")
    print("paper's; *does not replicate* otherwise. *Order* says whether Q(0) and Q(λ) of the same")
    print("experiment rank as in the paper. Configurations are compared separately.\n")
    t3 = pd.read_csv(d / "table3.csv", dtype={"experiment": str})
    print(
        "| system | exp. | algorithm | paper | paper config | qsweep | qsweep config | successes | verdict "
        "| within 2 SE (old rule) | order | config |"
    )
    print("|---|---|---|---:|---|---:|---|---:|---|---|---|---|")
    res_cols = ["x", "x_dot", "theta", "theta_dot"]
    for _, r in t3.iterrows():
        ours = [int(r[c]) for c in res_cols if pd.notna(r[c])] + [int(r["actions"])]
        paper_cfg = [int(r[f"paper_{c}"]) for c in res_cols + ["actions"] if pd.notna(r[f"paper_{c}"])]
        verdict_ = verdict(r)
        same = t3[(t3.system == r.system) & (t3.experiment == r.experiment)]
        order = same.sort_values("mean")["algorithm"].tolist() == same.sort_values("paper_mean")["algorithm"].tolist()
        print(
            f"| {r.system} | {r.experiment} | {r.algorithm} | {r.paper_mean:g} ± {r.paper_std:g} | {paper_cfg} "
            f"| {r['mean']:.1f} ± {r['std']:.1f} | {ours} | {int(r.successes)}/{int(r.n)} | {scale_word(r)} | {verdict_} "
            f"| {'same' if order else 'reversed'} | {'same' if ours == paper_cfg else 'differs'} |"
        )
    print()
    print("### Convergence overall (cells where every seed reached the goal / trials that did)\n")
    print("| system | exp. | algorithm | cells fully converged | trials converged |")
    print("|---|---|---|---:|---:|")
    for (s, e, a), r in conv.iterrows():
        print(f"| {TITLE[s]} | {e} | {a} | {r.full}/{r.cells} | {r.ok}/{r.trials} ({100 * r.ok / r.trials:.0f}%) |")

    print("\n### 1. Q(λ) beats Q(0), crisp and fuzzy\n")
    print("Best-cell means (Table III rows) and, over every grid cell, how often Q(λ)'s mean is lower.\n")
    print("| system | exp. | Q(0) best | Q(λ) best | Q(λ) lower in cells |")
    print("|---|---|---:|---:|---:|")
    key = ["system", "experiment", "axis1_value", "axis2_value"]
    q0 = cells[cells.algorithm == "q0"].set_index(key)["mean"]
    ql = cells[cells.algorithm == "q-lambda"].set_index(key)["mean"]
    both = pd.concat([q0.rename("q0"), ql.rename("ql")], axis=1).dropna()
    for s in SYSTEMS:
        for e in sorted(cells[cells.system == s].experiment.unique()):
            x, y = b.loc[(s, e, "q0")], b.loc[(s, e, "q-lambda")]
            sub = both.loc[(s, e)]
            wins = int((sub.ql < sub.q0).sum())
            print(f"| {TITLE[s]} | {e} | {x['mean']:.1f} ± {x['std']:.1f} | {y['mean']:.1f} ± {y['std']:.1f} | {wins}/{len(sub)} |")

    print("\n### 2. Fuzzy beats crisp (Ball-Beam, Cart-Pole; Mountain Car for completeness)\n")
    print("| system | algorithm | best crisp (Exp. 1-2) | best fuzzy (Exp. 3-4) |")
    print("|---|---|---:|---:|")
    for s in SYSTEMS:
        for a in ["q0", "q-lambda"]:
            cr = min(b.loc[(s, e, a), "mean"] for e in ["1", "2"])
            fz = min(b.loc[(s, e, a), "mean"] for e in ["3", "4"])
            print(f"| {TITLE[s]} | {a} | {cr:.1f} | {fz:.1f} |")

    print("\n### 3. Mountain Car needs more than 100 episodes for every algorithm\n")
    mc = b.loc["mountain-car"]
    print("Best-cell means: " + ", ".join(f"Exp. {e} {a}: {r['mean']:.1f}" for (e, a), r in mc.iterrows()))

    print("\n### 4. Compact representations (2-4 bins or sets, 2-4 actions) are preferred\n")
    n_compact = 0
    rows = []
    for (s, e, a), r in b.iterrows():
        res = [int(r[c]) for c in res_cols if pd.notna(r[c])]
        compact = max(res) <= 4 and r["actions"] <= 4
        n_compact += compact
        rows.append(f"{TITLE[s]} {e} {a}: {res}, {int(r['actions'])} actions{'' if compact else ' (not compact)'}")
    print(f"{n_compact} of {len(b)} best cells are compact.\n")
    for line in rows:
        print(f"- {line}")

    print("\n### 5. Fine resolution with many actions degrades Q(0) (Experiments 2 and 4)\n")
    print("Mean over cells of the cell means, fine (resolution ≥ 6 and actions ≥ 6) vs coarse (≤ 4 and ≤ 4),")
    print("and the mean within-cell std.\n")
    print("| system | exp. | algorithm | coarse mean | fine mean | coarse std | fine std |")
    print("|---|---|---|---:|---:|---:|---:|")
    for s in SYSTEMS:
        for e in ["2", "4"]:
            for a in ["q0", "q-lambda"]:
                c = cells[(cells.system == s) & (cells.experiment == e) & (cells.algorithm == a)]
                fine = c[(c.axis1_value >= 6) & (c.axis2_value >= 6)]
                coarse = c[(c.axis1_value <= 4) & (c.axis2_value <= 4)]
                print(
                    f"| {TITLE[s]} | {e} | {a} | {coarse['mean'].mean():.1f} | {fine['mean'].mean():.1f} "
                    f"| {coarse['std'].mean():.1f} | {fine['std'].mean():.1f} |"
                )


if __name__ == "__main__":
    main()
