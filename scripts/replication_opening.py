#!/usr/bin/env python3
"""The opening tables of REPLICATION.md, from the committed report's files.

Usage: .venv/bin/python scripts/replication_opening.py [reports/paper]

Prints Markdown: the claims x variants matrix of the declared variants (conclusions.csv), then
Table III of the best-fitting declared variant (variants.csv, rank 1) with every row's fresh-seed
estimate and its interval, the paper's value, ours/paper with its interval, the verdict on the
pre-registered scale and the cause (table3.csv's `verdict`, `cause`: issue #46), the old rule's
within-2-SE / within-2x verdict and the equivalence verdicts (table3.csv). Analysis only; the
numbers are qsweep's, this only lays them out (the old rule's verdicts are recomputed by
scripts/replication_summary.py, the scale's by tests/python/test_verdicts.py).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).parent))
from replication_summary import judged, verdict  # noqa: E402


def claims(d: Path, declared: list[str]) -> None:
    c = pd.read_csv(d / "conclusions.csv", keep_default_na=False, na_values=[""])
    c = c[c["variant"].isin(declared)]
    print("| claim | " + " | ".join(f"`{v}`" for v in declared) + " |")
    print("|---|" + "---|" * len(declared))
    for claim, rows in c.groupby("claim", sort=False):
        cells = []
        for v in declared:
            r = rows[rows["variant"] == v].iloc[0]
            cells.append(f"{r.verdict} [{r.ci_lo:.2f}, {r.ci_hi:.2f}]" if pd.notna(r.ci_lo) else r.verdict)
        print(f"| `{claim}` | " + " | ".join(cells) + " |")
    tally = c.groupby("variant")["verdict"].value_counts().unstack(fill_value=0)
    print()
    print("Per variant (holds / reversed / undecided): " + "; ".join(
        f"`{v}` {tally.loc[v].get('holds', 0)} / {tally.loc[v].get('reversed', 0)} / {tally.loc[v].get('undecided', 0)}"
        for v in declared
    ) + ".")


def table3(d: Path, v: str) -> None:
    t = pd.read_csv(d / v / "table3.csv", dtype={"experiment": str})
    j = judged(t)
    text = lambda x: "" if pd.isna(x) else str(x)  # noqa: E731
    print(
        "| system | exp. | algorithm | selection (n = 10) | fresh mean ± std [95 % CI] (n) | paper | ours/paper [95 % CI] "
        "| verdict | cause | within 2 SE (old rule) | equivalent n=10 / n=100 | censored |"
    )
    print("|---|---|---|---:|---:|---:|---:|---|---|---|---|---:|")
    for (_, r), (_, rj) in zip(t.iterrows(), j.iterrows()):
        print(
            f"| {r.system} | {r.experiment} | {r.algorithm} | {r['mean']:.2f} | "
            f"{r.fresh_mean:.2f} ± {r.fresh_std:.2f} [{r.fresh_ci_lo:.2f}, {r.fresh_ci_hi:.2f}] ({int(r.fresh_n)}) | "
            f"{r.paper_mean:g} ± {r.paper_std:g} | {r.ratio:.2f} [{r.ratio_lo:.2f}, {r.ratio_hi:.2f}] | "
            f"{text(r.verdict)} | {text(r.cause)} | {verdict(rj)} | {r.equivalent_n10} / {r.equivalent_n100} | {r.censored:.2f} |"
        )


def main() -> None:
    d = Path(sys.argv[1] if len(sys.argv) > 1 else "reports/paper")
    listed = pd.read_csv(d / "variants.csv")
    declared = listed[listed["exploratory"] == "no"]["variant"].tolist()
    claims(d, declared)
    print()
    print(f"Table III of the best-fitting declared variant, `{declared[0]}`:\n")
    table3(d, declared[0])


if __name__ == "__main__":
    main()
