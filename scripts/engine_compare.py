#!/usr/bin/env python3
"""Engine 1 against engine 2, cell by cell: is engine 2 the same algorithm?

    mkdir -p /tmp/e1 && git archive 301bb2d reports/paper cache | tar -x -C /tmp/e1   # engine 1's
    python scripts/engine_compare.py /tmp/e1/reports/paper reports/paper /tmp/e1/cache cache > docs/engine-2.md

Reads the two report folders of pipelines/paper.yaml (their `cells.parquet`, every variant's
`table3.csv` and `variants.csv`; nothing else) and writes Markdown:
- per variant, the share of cells whose mean episodes differ at the 5 % level by Welch's t-test
  (two-sided, from each cell's mean, sample std and n); if engine 2 computes the same algorithm,
  about 5 % of cells differ by chance, and the count is tested against Binomial(cells, 0.05);
- the cells that differ most (p < 0.001);
- every Table III row of every variant before and after, with the difference of the two means in
  standard errors of that difference;
- every variant's Table III verdict counts before and after (`variants.csv`);
- with the two caches given, how many trials changed at all: the rows of both caches joined by
  (configuration, seed), per system × representation × algorithm.

Cells whose trials are identical in spread and mean on both sides (e.g. every trial at the cap)
count as not different; a cell with fewer than two trials on a side is left out. The cells of one
variant are independent (distinct configurations); variants share some configurations, so the
per-variant tests are not independent of each other.
"""
import sys
from pathlib import Path

import polars as pl
from scipy import stats

KEYS = ["variant", "system", "experiment", "algorithm", "axis1_value", "axis2_value"]


def welch(m1, s1, n1, m2, s2, n2):
    """Two-sided Welch p-value from summary statistics (1 when both sides have no spread)."""
    if n1 < 2 or n2 < 2:
        return None
    if s1 == 0 and s2 == 0:
        return 1.0 if m1 == m2 else 0.0
    return float(stats.ttest_ind_from_stats(m1, s1, n1, m2, s2, n2, equal_var=False).pvalue)


def fmt(v, digits=1):
    return "—" if v is None else f"{v:.{digits}f}"


def config(row, prefix=""):
    res = [row[f"{prefix}{v}"] for v in ("x", "x_dot", "theta", "theta_dot")]
    res = [str(int(v)) for v in res if v is not None and v == v]
    return "/".join(res) + f" × {int(row[prefix + 'actions'])}a"


def changed_trials(old_cache, new_cache, w):
    """How many trials of the same configuration and seed have another outcome under engine 2."""
    cols = ["config_json", "seed", "system", "repr", "algorithm", "episodes", "episode_lengths"]
    read = lambda d: pl.concat([pl.read_parquet(f, columns=cols) for f in sorted(Path(d).glob("seg-*.parquet"))]).unique(
        subset=["config_json", "seed"]
    )
    j = read(old_cache).join(
        read(new_cache).select("config_json", "seed", "episodes", "episode_lengths"), on=["config_json", "seed"], suffix="_2"
    )
    j = j.with_columns((pl.col("episode_lengths") != pl.col("episode_lengths_2")).alias("changed"))
    w("## How many trials changed at all\n")
    w(
        "Every trial of every committed pipeline that both caches hold (joined by configuration and "
        "seed): a trial changes only where a last-bit difference (sin/cos/exp, or a sum's order) "
        "first flips a decision (an action, a tie, a window edge); from there on its trajectory is "
        "another. Where few trials changed, a cell's two samples share most of their trials, and "
        "Welch's test, which assumes independent samples, rejects far less often than 5 %.\n"
    )
    w(
        "Among the changed trials the question is sharper: the same configuration and seed, run by "
        "the two engines, is a pair, and if engine 2 is the same algorithm the difference of the "
        "episodes run (engine 2 − engine 1) is symmetric around 0. The last columns give its mean "
        "and the two-sided Wilcoxon signed-rank p-value (zero differences dropped).\n"
    )
    w("| group | trials in both | changed | share | mean Δ episodes (changed) | Wilcoxon p |")
    w("|---|---:|---:|---:|---:|---:|")
    keys = ["system", "repr", "algorithm"]
    for (system, repr_, alg), d in sorted(j.group_by(keys), key=lambda x: x[0]):
        c = d.filter(pl.col("changed"))
        diff = (c["episodes_2"].cast(pl.Int64) - c["episodes"].cast(pl.Int64)).to_list()
        nz = [x for x in diff if x != 0]
        p = stats.wilcoxon(nz).pvalue if len(nz) >= 10 else None
        mean = sum(diff) / len(diff) if diff else None
        w(f"| {system} {repr_} {alg} | {d.height} | {c.height} | {100 * c.height / d.height:.1f} % | {fmt(mean, 2)} | {fmt(p, 3)} |")
    w(f"| all | {j.height} | {j['changed'].sum()} | {100 * j['changed'].sum() / j.height:.1f} % | | |\n")


def main(old_dir, new_dir, caches=None):
    old_dir, new_dir = Path(old_dir), Path(new_dir)
    cols = KEYS + ["label", "mean", "std", "n"]
    old = pl.read_parquet(old_dir / "cells.parquet").select(cols)
    new = pl.read_parquet(new_dir / "cells.parquet").select(cols)
    both = old.join(new, on=KEYS, suffix="_2", how="inner")
    assert both.height == old.height == new.height, (both.height, old.height, new.height)
    p = [
        welch(r["mean"], r["std"] or 0.0, r["n"], r["mean_2"], r["std_2"] or 0.0, r["n_2"])
        for r in both.iter_rows(named=True)
    ]
    both = both.with_columns(pl.Series("p", p, dtype=pl.Float64))
    out = []
    w = out.append
    w("# Engine 2 against engine 1, cell by cell\n")
    w(
        "Generated by `scripts/engine_compare.py` (see its header for the commands) from engine 1's "
        f"committed report of `pipelines/paper.yaml` (`{old_dir}`) and engine 2's (`{new_dir}`): "
        "every cell of every variant, 10 seeds a side (the same seeds; the trials differ because "
        "engine 2 rounds differently and the systems are chaotic, so a last-bit change becomes "
        "another trajectory). If engine 2 is the same algorithm, a cell's two means differ only "
        "by chance, and about 5 % of cells differ at the 5 % level.\n"
    )
    w("## Cells that differ, per variant (Welch's t-test, two-sided)\n")
    w("| variant | cells tested | p < 0.05 | share | p < 0.01 | share | binomial p (vs 5 %) |")
    w("|---|---:|---:|---:|---:|---:|---:|")
    total_n = total_5 = total_1 = 0
    for variant in both["variant"].unique(maintain_order=True).to_list():
        d = both.filter((pl.col("variant") == variant) & pl.col("p").is_not_null())
        n, s5, s1 = d.height, d.filter(pl.col("p") < 0.05).height, d.filter(pl.col("p") < 0.01).height
        total_n, total_5, total_1 = total_n + n, total_5 + s5, total_1 + s1
        b = stats.binomtest(s5, n, 0.05).pvalue if n else None
        w(f"| `{variant}` | {n} | {s5} | {100 * s5 / n:.1f} % | {s1} | {100 * s1 / n:.1f} % | {fmt(b, 3)} |")
    w(
        f"| all variants | {total_n} | {total_5} | {100 * total_5 / total_n:.1f} % | {total_1} | "
        f"{100 * total_1 / total_n:.1f} % | (not independent) |\n"
    )
    w("Per system, all variants together:\n")
    w("| system | cells tested | p < 0.05 | share |")
    w("|---|---:|---:|---:|")
    for system in both["system"].unique(maintain_order=True).to_list():
        d = both.filter((pl.col("system") == system) & pl.col("p").is_not_null())
        s5 = d.filter(pl.col("p") < 0.05).height
        w(f"| {system} | {d.height} | {s5} | {100 * s5 / d.height:.1f} % |")
    w("")
    strong = both.filter(pl.col("p") < 0.001).sort("p")
    w(f"## The cells that differ most (p < 0.001: {strong.height} of {total_n}; about {total_n / 1000:.0f} expected by chance)\n")
    if strong.height:
        w("| variant | system | exp. | algorithm | cell | engine 1 mean ± std (n) | engine 2 mean ± std (n) | p |")
        w("|---|---|---|---|---|---:|---:|---:|")
        for r in strong.head(40).iter_rows(named=True):
            cell = f"{r['axis1_value']:g} × {r['axis2_value']:g}"
            w(
                f"| `{r['variant']}` | {r['system']} | {r['experiment']} | {r['label']} | {cell} | "
                f"{r['mean']:.1f} ± {fmt(r['std'])} ({r['n']}) | {r['mean_2']:.1f} ± {fmt(r['std_2'])} ({r['n_2']}) | {r['p']:.1e} |"
            )
        w("")
    w("## Table III, every variant, before and after\n")
    w(
        "Each row's best cell under each engine (the configurations may differ: the best of 81 noisy "
        "cells), and the difference of the two means in standard errors of the difference, "
        "(m₂ − m₁) / √(s₁²/n₁ + s₂²/n₂).\n"
    )
    variants = sorted(p.name for p in new_dir.iterdir() if (p / "table3.csv").exists())
    big = 0
    rows = 0
    for variant in variants:
        a = pl.read_csv(old_dir / variant / "table3.csv")
        b = pl.read_csv(new_dir / variant / "table3.csv")
        w(f"### `{variant}`\n")
        w("| system | exp. | algorithm | paper | engine 1: mean ± std (n), cell | engine 2: mean ± std (n), cell | Δ / SE |")
        w("|---|---:|---|---:|---:|---:|---:|")
        for r1, r2 in zip(a.iter_rows(named=True), b.iter_rows(named=True)):
            assert (r1["system"], r1["experiment"], r1["algorithm"]) == (r2["system"], r2["experiment"], r2["algorithm"])
            se = ((r1["std"] or 0) ** 2 / r1["n"] + (r2["std"] or 0) ** 2 / r2["n"]) ** 0.5
            z = (r2["mean"] - r1["mean"]) / se if se > 0 else 0.0
            rows += 1
            big += abs(z) > 2
            w(
                f"| {r1['system']} | {r1['experiment']} | {r1['algorithm']} | {r1['paper_mean']} | "
                f"{r1['mean']:.2f} ± {fmt(r1['std'], 2)} ({r1['n']}), {config(r1)} | "
                f"{r2['mean']:.2f} ± {fmt(r2['std'], 2)} ({r2['n']}), {config(r2)} | {z:+.2f} |"
            )
        w("")
    w(f"{big} of {rows} Table III rows moved by more than 2 standard errors (about {0.046 * rows:.0f} expected by chance if the rows were independent tests).\n")
    w("## Verdict counts, before and after (`variants.csv`)\n")
    va = pl.read_csv(old_dir / "variants.csv")
    vb = pl.read_csv(new_dir / "variants.csv")
    cols = ["replicating_n10", "within_2se", "ratio_within_2x", "config_match", "order_match"]
    w("| variant | " + " | ".join(f"{c} (1 → 2)" for c in cols) + " |")
    w("|---|" + "---:|" * len(cols))
    for r1 in va.iter_rows(named=True):
        r2 = vb.filter(pl.col("variant") == r1["variant"]).row(0, named=True)
        w(f"| `{r1['variant']}` | " + " | ".join(f"{r1[c]} → {r2[c]}" for c in cols) + " |")
    w("")
    if caches:
        changed_trials(*caches, w)
    print("\n".join(out))


if __name__ == "__main__":
    if len(sys.argv) not in (3, 5):
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3:] or None)
