"""Compare the cache written by Slurm array tasks with a single-machine run's (scripts/slurm/test.sh).

Usage: compare.py SLURM_CACHE SINGLE_CACHE EXECUTED

Checks that every trial is stored exactly once in the Slurm cache (so the shards were disjoint),
that EXECUTED (the tasks' summed "executed" counts) equals the number of rows, and that both
caches hold the same trials with equal values in every column but the timings (`seconds`,
`cpu_seconds`), which differ between runs by nature.
"""

import sys

import pandas as pd


def load(path: str) -> pd.DataFrame:
    return pd.read_parquet(path)


def main() -> int:
    slurm_dir, single_dir, executed = sys.argv[1], sys.argv[2], int(sys.argv[3])
    slurm, single = load(slurm_dir), load(single_dir)
    dupes = slurm["key"].duplicated().sum()
    if dupes:
        print(f"FAIL: {dupes} trials stored more than once in {slurm_dir}", file=sys.stderr)
        return 1
    if len(slurm) != executed:
        print(f"FAIL: tasks executed {executed} trials but the cache holds {len(slurm)}", file=sys.stderr)
        return 1
    if set(slurm["key"]) != set(single["key"]):
        print(
            f"FAIL: key sets differ: {len(set(slurm['key']) - set(single['key']))} only in Slurm, "
            f"{len(set(single['key']) - set(slurm['key']))} only in the single run",
            file=sys.stderr,
        )
        return 1
    timings = {"seconds", "cpu_seconds"}
    assert timings <= set(single.columns), "the cache records both timings"
    columns = [c for c in single.columns if c not in timings]
    a = slurm[columns].sort_values("key").reset_index(drop=True)
    b = single[columns].sort_values("key").reset_index(drop=True)
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    print(f"[slurm-test] {len(a)} trials, each stored once, equal in all {len(columns)} columns but the timings")
    return 0


if __name__ == "__main__":
    sys.exit(main())
