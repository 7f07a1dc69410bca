"""README's answer against the files it comes from: every count and value that README.md's
"Does the paper replicate?" paragraph and its example rows state is recomputed here from the
committed report (`variants.csv`, `cross_validation.csv`, the best variant's `table3.csv`,
`conclusions.csv`), and the yardstick's numbers (seeded permutations that only qsweep computes)
must be the ones the generated comparison page states. A changed count in any of those files fails
this test until the prose follows.
"""

from __future__ import annotations

import re

import pandas as pd
import pytest

from conftest import REPO_ROOT

PAPER = REPO_ROOT / "reports" / "paper"


def _readme() -> str:
    return (REPO_ROOT / "README.md").read_text()


def _answer() -> str:
    text = _readme()
    start = text.index("**Does the paper replicate?**")
    return " ".join(text[start : text.index("\n\n", start)].split())


@pytest.fixture(scope="module")
def variants() -> pd.DataFrame:
    return pd.read_csv(PAPER / "variants.csv")


def _best(variants: pd.DataFrame) -> pd.Series:
    declared = variants[variants["exploratory"] == "no"].sort_values("rank")
    return declared.iloc[0]


def test_the_answer_states_the_counts_of_the_report(variants: pd.DataFrame) -> None:
    answer = _answer()
    b = _best(variants)
    t3 = pd.read_csv(PAPER / b["variant"] / "table3.csv", dtype={"experiment": str})
    rows = len(t3)
    aw = variants[variants["variant"] == "as-written"].iloc[0]
    want = [
        f"Under the best-ranked declared variant, {b['variant']}, {b['replicating_n10']} of {rows} Table III rows replicate",
        f"{b['equivalent_n10']} equivalent (TOST, ours ÷ paper within 0.80–1.25) and {b['within_2x_n10']} shown within 2×",
        f"As written (as-written): {aw['replicating_n10']} of {rows} replicate",
        f"with 5 runs behind each published mean {b['replicating_n5']} rows replicate, with 3 runs {b['replicating_n3']}",
    ]
    # Leave-one-row-out, counted from cross_validation.csv; in sample from variants.csv.
    cv = pd.read_csv(PAPER / "cross_validation.csv")
    replicating = {"equivalent", "within-2x"}
    declared = variants[variants["exploratory"] == "no"]
    want.append(
        f"over the {len(declared)} declared variants), {int(cv['verdict'].isin(replicating).sum())} of {len(cv)} rows "
        f"replicate ({int((cv['verdict'] == 'equivalent').sum())} equivalent; "
        f"{int((cv['verdict_2se'] == 'replicates').sum())} within two standard errors), against "
        f"{b['replicating_n10']} ({b['equivalent_n10']}; {b['within_2se']}) for `{b['variant']}` in sample"
    )
    want.append(f"the best of {len(declared)} variants has {declared['within_2se'].max()} rows within two standard errors")
    # The yardstick's distribution is qsweep's own (seeded permutations): README repeats the page.
    page = (PAPER / "README.md").read_text()
    m = re.search(r"the best would reach a median \d+ \(95th percentile \d+, p = [0-9.]+\)", page)
    assert m, "the comparison page states the yardstick"
    want.append(m.group(0))
    causes = ["replicates", "argmin", "paper-inconsistent", "differs-at-paper-config", "unexplained"]
    want.append(", ".join(f"{int((t3['cause'] == c).sum())} {c}" for c in causes))
    spread = t3[t3["spread_differs"] == "yes"]
    wider = int((spread["std_ratio_lo"] > 1).sum())
    want.append(f"Our spread differs from the paper's in {len(spread)} rows ({wider} wider, {len(spread) - wider} narrower")
    c = pd.read_csv(PAPER / "conclusions.csv")
    c = c[c["exploratory"] == "no"]
    everywhere = int(c.groupby("claim")["verdict"].apply(lambda v: (v == "holds").all()).sum())
    words = ["none", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten"]
    want.append(f"Of the paper's ten conclusions {words[everywhere]} hold in every variant")
    for w in want:
        assert w in answer, f"README.md's answer should say:\n  {w}\nit says:\n  {answer}"


def test_the_example_rows_are_the_best_variants_fresh_seed_values(variants: pd.DataFrame) -> None:
    b = _best(variants)
    text = _readme()
    assert f"([`{b['variant']}`](reports/paper/{b['variant']}/README.md)" in text
    t3 = pd.read_csv(PAPER / b["variant"] / "table3.csv", dtype={"experiment": str})
    table = text[text.index("| System | Exp. | Algorithm | ours | paper | verdict |") :].split("\n\n")[0]
    rows = [line.strip("|").split("|") for line in table.splitlines()[2:]]
    assert len(rows) >= 3
    for system, exp, alg, ours, paper, verdict in ([x.strip() for x in r] for r in rows):
        r = t3[(t3["system"] == system) & (t3["experiment"] == exp) & (t3["algorithm"] == alg)].iloc[0]
        assert int(r["fresh_n"]) == 20, "the example rows are the fresh seeds the verdicts use"
        assert ours == f"{r['fresh_mean']:.2f} ± {r['fresh_std']:.2f}", (system, exp, alg)
        assert paper == f"{r['paper_mean']:.2f} ± {r['paper_std']:.2f}", (system, exp, alg)
        assert verdict == r["verdict"], (system, exp, alg)


def test_replication_md_repeats_the_generated_answer() -> None:
    """REPLICATION.md's answer quotes the comparison page's generated opening sentence by sentence,
    so a count that changes in the report fails here until the write-up follows."""
    page = (PAPER / "README.md").read_text()
    opening = next(p for p in page.split("\n\n") if p.startswith("Under the best-ranked declared variant"))
    notes = " ".join((PAPER / "REPLICATION.md").read_text().split())
    sentences = re.split(r"(?<=[.)]) (?=[A-Z])", " ".join(opening.split()))
    assert len(sentences) >= 6
    missing = [s for s in sentences if s not in notes]
    assert not missing, f"REPLICATION.md does not repeat: {missing}"


def test_replication_md_tables_are_the_scripts_output() -> None:
    """The claims × variants matrix and Table III on fresh seeds in REPLICATION.md are what
    scripts/replication_opening.py lays out from the committed report, line for line."""
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, str(REPO_ROOT / "scripts" / "replication_opening.py"), str(PAPER)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    rows = [line.strip() for line in out.splitlines() if line.startswith("|")]
    assert len(rows) > 20
    notes = {line.strip() for line in (PAPER / "REPLICATION.md").read_text().splitlines()}
    missing = [r for r in rows if r not in notes]
    assert not missing, f"REPLICATION.md lacks these lines of replication_opening.py: {missing[:5]}"
