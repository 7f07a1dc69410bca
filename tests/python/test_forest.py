"""The opening of the committed comparison page (reports/paper/README.md and index.html), recomputed
from the committed files with pandas, independently of qsweep's code (crates/qsweep-report/src/replication/pages/answer.rs):
the plotted variants are `as-written` and the rank-1 declared variant of variants.csv; per variant,
the replicating rows on the verdict scale of issue #46 (table3.csv's `verdict`: `equivalent` or
`within-2x`, the paper's means taken over 10 runs) and the scale's other verdicts, the rows
replicating with the paper's runs taken as 5 and 3 (variants.csv), the rows equivalent at 100 runs
(`equivalent_n100`), the rows within 2× by ratio alone (table3.csv's `ratio` in [0.5, 2]) and those
whose whole interval (`ratio_lo`, `ratio_hi`) is, and the rows whose spread differs from the
paper's (`spread_differs`, wider when `std_ratio_lo` > 1). The forest plot draws one dot per row
and variant.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pandas as pd

REPO_ROOT = Path(__file__).resolve().parents[2]
PAPER = REPO_ROOT / "reports" / "paper"


def counts(variant: str) -> dict[str, int]:
    t3 = pd.read_csv(PAPER / variant / "table3.csv", keep_default_na=False, na_values=[""])
    t3 = t3[t3["ratio"].notna()]
    inside = lambda s: (s >= 0.5) & (s <= 2)  # noqa: E731
    verdict = t3["verdict"].value_counts()
    n = lambda v: int(verdict.get(v, 0))  # noqa: E731
    spread = t3[t3["spread_differs"] == "yes"]
    listed = pd.read_csv(PAPER / "variants.csv").set_index("variant").loc[variant]
    out = {
        "rows": len(t3),
        "within": int(inside(t3["ratio"]).sum()),
        "whole": int((inside(t3["ratio_lo"]) & inside(t3["ratio_hi"])).sum()),
        "eq": n("equivalent"),
        "w2": n("within-2x"),
        "wide": n("consistent-but-wide"),
        "differs": n("differs"),
        "undecided": n("undecided"),
        "eq100": int((t3["equivalent_n100"] == "yes").sum()),
        "rep5": int(listed["replicating_n5"]),
        "rep3": int(listed["replicating_n3"]),
        "wider": int((spread["std_ratio_lo"] > 1).sum()),
        "narrower": int((spread["std_ratio_hi"] < 1).sum()),
    }
    out["rep10"] = out["eq"] + out["w2"]
    assert out["rep10"] == int(listed["replicating_n10"]), (variant, out["rep10"], listed["replicating_n10"])
    assert out["eq"] + out["w2"] + out["wide"] + out["differs"] + out["undecided"] == out["rows"], variant
    assert out["wider"] + out["narrower"] == len(spread), "a differing spread is wider or narrower"
    return out


def test_paper_opening_states_what_the_committed_tables_give() -> None:
    v = pd.read_csv(PAPER / "variants.csv")
    best = v[v["exploratory"] == "no"].sort_values("rank").iloc[0]["variant"]
    b, w = counts(best), counts("as-written")
    readme = (PAPER / "README.md").read_text()
    html = (PAPER / "index.html").read_text()
    undecided = lambda c: f", {c['undecided']} undecided" if c["undecided"] else ""  # noqa: E731
    first = (
        f"Under the best-ranked declared variant, {best}, {b['rep10']} of {b['rows']} Table III rows replicate, "
        f"taking the paper's means to average 10 runs: {b['eq']} equivalent (TOST, ours ÷ paper within "
        f"0.80–1.25) and {b['w2']} shown within 2× (the same test within 0.5–2). {b['wide']} more {'is' if b['wide'] == 1 else 'are'} within "
        f"two standard errors but not shown within 2× (consistent but wide), {b['differs']} differ{undecided(b)}. "
        f"With 5 runs behind each published mean {b['rep5']} rows replicate, with 3 runs {b['rep3']}; "
        f"{b['eq100']} equivalent at 100 runs. By ratio alone, {b['within']} rows are within 2× "
        f"({b['whole']} with their whole 95 % interval)"
    )
    texts = [first]
    if b["wider"] + b["narrower"]:
        texts.append(
            f"Our spread differs from the paper's in {b['wider'] + b['narrower']} rows ({b['wider']} wider, "
            f"{b['narrower']} narrower; 95 % F interval of the std ratio)."
        )
    if best != "as-written":
        texts.append(
            f"As written (as-written): {w['rep10']} of {w['rows']} replicate ({w['eq']} equivalent, {w['w2']} "
            f"within 2×), {w['wide']} consistent but wide, {w['differs']} differ; {w['rep5']} at 5 runs, "
            f"{w['rep3']} at 3; by ratio {w['within']} within 2× ({w['whole']} whole-interval)"
        )
    for text in texts:
        assert text in readme, f"{text}\nnot in README.md"
        assert text.replace("'", "&#39;") in html, f"{text}\nnot in index.html"
    # The README opens with it: right after the heading and the description.
    paragraphs = [p for p in readme.split("\n\n") if p.strip()]
    assert paragraphs[2].startswith("Under the best-ranked declared variant"), paragraphs[:3]
    assert paragraphs[3].startswith("![Forest plot") and "(figures/forest.svg)" in paragraphs[3]

    # One dot per row and variant, plus one per variant in the legend.
    svg = ET.parse(PAPER / "figures" / "forest.svg").getroot()
    dots = [e for e in svg.iter() if e.tag.rsplit("}", 1)[-1] == "circle"]
    assert len(dots) == b["rows"] + w["rows"] + 2
    assert re.search(r'width="900" height="\d+"', ET.tostring(svg, encoding="unicode"))
