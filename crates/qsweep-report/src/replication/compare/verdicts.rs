//! `verdicts_by_n.csv`: every variant's Table III rows judged at each assumed number of paper
//! runs (docs/preregistration.md: the sensitivity to the paper's unstated n), each with the variant
//! that comes closest to the paper for that row.

use crate::derive::table::{Align, Column, Row, Table, Value};
use crate::replication::compare::fit::{RowFit, RowJudgement};
use crate::replication::compare::VariantDigest;

/// The closest variant for a row at the `k`-th n of [`crate::replication::compare::fit::PAPER_N_SET`]: the best verdict, then the
/// smallest |ln(ours / paper)|, then pipeline order. Returns the digest and its row.
fn closest<'v>(
    variants: &'v [VariantDigest],
    row: &RowFit,
    k: usize,
) -> Option<(&'v VariantDigest<'v>, &'v RowFit)> {
    let key = row.key();
    let closer = |a: &RowFit, b: &RowFit| {
        let (va, vb) = (a.by_n[k].best.verdict, b.by_n[k].best.verdict);
        va < vb || (va == vb && a.ratio().ln().abs() < b.ratio().ln().abs())
    };
    let mut best: Option<(&VariantDigest, &RowFit)> = None;
    for v in variants {
        let Some(o) = v.rows.iter().find(|o| o.key() == key) else { continue };
        // Strictly closer only: ties keep the earlier variant (pipeline order).
        if best.is_none_or(|(_, b)| closer(o, b)) {
            best = Some((v, o));
        }
    }
    best
}

/// The rule, as stated in captions.
pub const BY_N_RULE: &str = "Every variant's Table III rows judged with the paper's std over an \
assumed n_paper = 3, 5 and 10 runs (the paper never states it). Ours: the best cell's estimate \
(fresh seeds where present) that the verdicts judge, with n; verdicts, the contradictory pairs, \
the row each pair costs, and the cause. Closest variant: of all variants (declared and exploratory), \
the one whose best cell has the best verdict for the row at that n, then the ratio closest to 1, \
then pipeline order.";

/// The long table, or `None` when no variant has a row with a reference.
pub fn verdicts_by_n_table(variants: &[VariantDigest]) -> Option<Table> {
    if variants.iter().all(|v| v.rows.is_empty()) {
        return None;
    }
    let columns = vec![
        Column::new("Variant", "variant", Align::Left),
        Column::new("Exploratory", "exploratory", Align::Left),
        Column::new("System", "system", Align::Left),
        Column::new("Exp.", "experiment", Align::Left),
        Column::new("Algorithm", "algorithm", Align::Left),
        Column::new("Ours", "mean", Align::Right).fields(&["mean", "std"]),
        Column::new("n", "n", Align::Right),
        Column::new("n_paper", "n_paper", Align::Right),
        Column::new("Verdict", "verdict", Align::Left),
        Column::new("Verdict (paper config)", "paper_cell_verdict", Align::Left),
        Column::new("Contradictory pair", "contradictory_pair", Align::Left),
        Column::new("Paper inconsistent", "paper_inconsistent", Align::Left),
        Column::new("Cause", "cause", Align::Left),
        Column::new("Closest variant", "closest_variant", Align::Left),
        Column::new("Closest exploratory", "closest_exploratory", Align::Left),
        Column::new("Closest ours/paper", "closest_ratio", Align::Right),
        Column::new("Closest verdict", "closest_verdict", Align::Left),
    ];
    let text = |s: &str| Value::Text(s.into());
    let yes_no = |b: bool| text(if b { "yes" } else { "no" });
    let mut rows = Vec::new();
    for v in variants {
        for r in &v.rows {
            for (k, j) in r.by_n.iter().enumerate() {
                let RowJudgement { paper_n, best, paper_cell, in_pair, designated, cause } = *j;
                let mut values = vec![
                    text(&v.info.id),
                    yes_no(v.info.exploratory),
                    text(r.system.title()),
                    text(&r.experiment),
                    text(r.algorithm.label(r.repr)),
                    Value::MeanStd { mean: r.mean, std: r.std, decimals: 2, marked: false },
                    Value::Int(r.n as u64),
                    Value::Int(paper_n as u64),
                    text(best.verdict.label()),
                    paper_cell.map_or(Value::Missing, |p| text(p.verdict.label())),
                    yes_no(in_pair),
                    yes_no(designated),
                    text(cause.label()),
                ];
                match closest(variants, r, k) {
                    Some((c, o)) => values.extend([
                        text(&c.info.id),
                        yes_no(c.info.exploratory),
                        Value::Num { value: o.ratio(), decimals: 3, signed: false },
                        text(o.by_n[k].best.verdict.label()),
                    ]),
                    None => values.extend(std::iter::repeat_n(Value::Missing, 4)),
                }
                rows.push(Row { values, highlight: false });
            }
        }
    }
    Some(Table {
        title: "Verdicts by the paper's n".into(),
        caption: format!("{BY_N_RULE} {}", crate::replication::compare::fit::SCALE_RULE),
        columns,
        rows,
    })
}
