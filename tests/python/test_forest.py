"""The opening of the committed comparison page (reports/paper/README.md and index.html), recomputed
from the committed files with pandas, independently of qsweep's code (src/report/compare/forest.rs):
the plotted readings are `as-written` and the rank-1 declared reading of variants.csv; per reading,
the rows within 2× (table3.csv's `ratio` in [0.5, 2]), those whose whole interval (`ratio_lo`,
`ratio_hi`) is, the replicating rows by scripts/replication_summary.py's rule, and the equivalent
rows (`equivalent_n10`, `equivalent_n100`). The forest plot draws one dot per row and reading.
"""

from __future__ import annotations

import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pandas as pd

REPO_ROOT = Path(__file__).resolve().parents[2]
PAPER = REPO_ROOT / "reports" / "paper"
sys.path.insert(0, str(REPO_ROOT / "scripts"))
from replication_summary import judged, verdict  # noqa: E402


def counts(reading: str) -> dict[str, int]:
    t3 = pd.read_csv(PAPER / reading / "table3.csv", keep_default_na=False, na_values=[""])
    t3 = t3[t3["ratio"].notna()]
    inside = lambda s: (s >= 0.5) & (s <= 2)  # noqa: E731
    return {
        "rows": len(t3),
        "within": int(inside(t3["ratio"]).sum()),
        "whole": int((inside(t3["ratio_lo"]) & inside(t3["ratio_hi"])).sum()),
        "replicate": int((judged(t3).apply(verdict, axis=1) == "replicates").sum()),
        "eq10": int((t3["equivalent_n10"] == "yes").sum()),
        "eq100": int((t3["equivalent_n100"] == "yes").sum()),
    }


def none(n: int) -> str:
    return {0: "none is", 1: "1 is"}.get(n, f"{n} are")


def test_paper_opening_states_what_the_committed_tables_give() -> None:
    v = pd.read_csv(PAPER / "variants.csv")
    best = v[v["exploratory"] == "no"].sort_values("rank").iloc[0]["variant"]
    b, w = counts(best), counts("as-written")
    readme = (PAPER / "README.md").read_text()
    html = (PAPER / "index.html").read_text()
    first = (
        f"Under the best-ranked declared reading, {best}, {b['within']} of {b['rows']} Table III rows are "
        f"within 2× of the paper ({b['whole']} with their whole 95 % interval), {b['replicate']} replicate "
        f"(within two standard errors) and {none(b['eq10'])} equivalent by TOST (margin 0.80–1.25, the "
        f"paper's runs taken as 10; {b['eq100']} at 100)"
    )
    second = (
        f"As written (as-written): {w['within']} of {w['rows']} within 2× ({w['whole']} whole-interval), "
        f"{w['replicate']} replicate, {w['eq10']} equivalent ({w['eq100']} at 100)"
    )
    for text in (first, second):
        assert text in readme, f"{text}\nnot in README.md"
        assert text.replace("'", "&#39;") in html or text in html, f"{text}\nnot in index.html"
    # The README opens with it: right after the heading and the description.
    paragraphs = [p for p in readme.split("\n\n") if p.strip()]
    assert paragraphs[2].startswith("Under the best-ranked declared reading"), paragraphs[:3]
    assert paragraphs[3].startswith("![Forest plot") and "(figures/forest.svg)" in paragraphs[3]

    # One dot per row and reading, plus one per reading in the legend.
    svg = ET.parse(PAPER / "figures" / "forest.svg").getroot()
    dots = [e for e in svg.iter() if e.tag.rsplit("}", 1)[-1] == "circle"]
    assert len(dots) == b["rows"] + w["rows"] + 2
    assert re.search(r'width="900" height="\d+"', ET.tostring(svg, encoding="unicode"))
