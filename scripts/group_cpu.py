#!/usr/bin/env python3
"""Per-group CPU time of the trials in one or two caches, as a Markdown table.

    python scripts/group_cpu.py CACHE_A [CACHE_B]

A group is system × representation × algorithm. For each cache: the trials' summed `cpu_seconds`
(the thread CPU time of each trial, which load on the machine does not inflate), steps, and
steps per CPU second; with two caches, the ratio B/A of CPU seconds and of ns per step. Two
caches of the same plan computed by two engines have the same trials (keys aside) but not the
same trajectories, so the per-step ratio is the fairer comparison of speed, the total the one a
user waits for.
"""
import glob
import sys

import polars as pl

GROUP = ["system", "repr", "algorithm"]


def load(cache):
    files = glob.glob(f"{cache}/seg-*.parquet")
    df = pl.concat(
        [pl.read_parquet(f, columns=["key", *GROUP, "total_steps", "cpu_seconds"]) for f in files],
        how="vertical_relaxed",
    ).unique(subset="key")
    return (
        df.group_by(GROUP)
        .agg(pl.len().alias("trials"), pl.col("total_steps").sum().alias("steps"), pl.col("cpu_seconds").sum().alias("cpu"))
        .sort(GROUP)
    )


def main(paths):
    tables = [load(p) for p in paths]
    a = tables[0]
    total_a = a["cpu"].sum()
    if len(tables) == 1:
        print("| group | trials | G steps | CPU s | share | M steps / CPU s |")
        print("|---|---:|---:|---:|---:|---:|")
        for r in a.sort("cpu", descending=True).iter_rows(named=True):
            print(
                f"| {r['system']} {r['repr']} {r['algorithm']} | {r['trials']} | {r['steps'] / 1e9:.2f} | "
                f"{r['cpu']:,.0f} | {100 * r['cpu'] / total_a:.1f} % | {r['steps'] / r['cpu'] / 1e6:.2f} |"
            )
        print(f"| all | {a['trials'].sum()} | {a['steps'].sum() / 1e9:.2f} | {total_a:,.0f} | 100 % | "
              f"{a['steps'].sum() / total_a / 1e6:.2f} |")
        return
    b = tables[1]
    j = a.join(b, on=GROUP, suffix="_b").sort("cpu", descending=True)
    print("| group | trials | CPU s A | CPU s B | B/A | ns/step A | ns/step B | B/A |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for r in j.iter_rows(named=True):
        na, nb = 1e9 * r["cpu"] / r["steps"], 1e9 * r["cpu_b"] / r["steps_b"]
        print(
            f"| {r['system']} {r['repr']} {r['algorithm']} | {r['trials']} | {r['cpu']:,.0f} | {r['cpu_b']:,.0f} | "
            f"{r['cpu_b'] / r['cpu']:.2f} | {na:.0f} | {nb:.0f} | {nb / na:.2f} |"
        )
    ta, tb = j["cpu"].sum(), j["cpu_b"].sum()
    sa, sb = j["steps"].sum(), j["steps_b"].sum()
    print(f"| all | {j['trials'].sum()} | {ta:,.0f} | {tb:,.0f} | {tb / ta:.2f} | {1e9 * ta / sa:.0f} | {1e9 * tb / sb:.0f} | {(tb / sb) / (ta / sa):.2f} |")


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    main(sys.argv[1:])
