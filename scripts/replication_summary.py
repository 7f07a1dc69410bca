#!/usr/bin/env python3
"""Numbers behind REPLICATION.md's verdicts, computed from a report's cells.parquet.

Usage: python3 scripts/replication_summary.py [reports/paper]

Prints Markdown: the paper's conclusions, each with the figures that decide it. Analysis only;
qsweep itself is Rust. Every figure here can be recomputed from cells.parquet with any tool.
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


def main() -> None:
    d = Path(sys.argv[1] if len(sys.argv) > 1 else "reports/paper")
    cells = pd.read_parquet(d / "cells.parquet")
    b = best(cells)
    conv = cells.groupby(["system", "experiment", "algorithm"]).agg(
        cells=("n", "size"), full=("all_converged", "sum"), trials=("n", "sum"), ok=("successes", "sum")
    )

    print("### Table III side by side\n")
    print("Verdict: *replicates* when the difference of the means is within two standard errors")
    print("(√(s₁²/n₁ + s₂²/n₂), both n = 10: an approximate two-sample test at the 5% level);")
    print("*within 2×* when it is not, but our mean is between half and twice the paper's;")
    print("*does not replicate* otherwise. *Order* says whether Q(0) and Q(λ) of the same experiment")
    print("rank as in the paper. Configurations are compared separately.\n")
    t3 = pd.read_csv(d / "table3.csv", dtype={"experiment": str})
    print("| system | exp. | algorithm | paper | paper config | qsweep | qsweep config | successes | verdict | order | config |")
    print("|---|---|---|---:|---|---:|---|---:|---|---|---|")
    res_cols = ["x", "x_dot", "theta", "theta_dot"]
    for _, r in t3.iterrows():
        ours = [int(r[c]) for c in res_cols if pd.notna(r[c])] + [int(r["actions"])]
        paper_cfg = [int(r[f"paper_{c}"]) for c in res_cols + ["actions"] if pd.notna(r[f"paper_{c}"])]
        se = math.sqrt(r["paper_std"] ** 2 / 10 + r["std"] ** 2 / r["n"])
        diff = abs(r["mean"] - r["paper_mean"])
        if diff <= 2 * se:
            verdict = "replicates"
        elif 0.5 <= r["mean"] / r["paper_mean"] <= 2:
            verdict = "within 2×"
        else:
            verdict = "does not replicate"
        same = t3[(t3.system == r.system) & (t3.experiment == r.experiment)]
        order = same.sort_values("mean")["algorithm"].tolist() == same.sort_values("paper_mean")["algorithm"].tolist()
        print(
            f"| {r.system} | {r.experiment} | {r.algorithm} | {r.paper_mean:g} ± {r.paper_std:g} | {paper_cfg} "
            f"| {r['mean']:.1f} ± {r['std']:.1f} | {ours} | {int(r.successes)}/{int(r.n)} | {verdict} "
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
