//! Choosing the variant honestly (docs/preregistration.md): leave-one-row-out — each Table III
//! row judged under the declared variant that the fit measure picks on the other rows — and the
//! permutation yardstick ([`crate::replication::stats::selection`]) for the best variant's count. Written as
//! `cross_validation.csv` and stated in the answer.

use crate::derive::table::{Align, Column, Row, Table, Value};
use crate::replication::compare::fit::{fit_order, Fit, FitVerdict, RowFit, RowKey, Verdict};
use crate::replication::compare::VariantDigest;
use crate::replication::stats::selection::{yardstick, Yardstick, PERMUTATIONS, SEED};
/// One held-out row: the variant chosen on the other rows and the row's verdicts under it.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOut {
    /// The row.
    pub row: RowKey,
    /// Its representation's label of the algorithm (as Table III writes it).
    pub label: String,
    /// The declared variant the fit measure picks on the other rows.
    pub chosen: String,
    /// The row's verdict under it (the scale, at the headline n).
    pub verdict: Verdict,
    /// The row's verdict under it by the old rule.
    pub fit_verdict: FitVerdict,
}

/// What choosing among the declared variants is worth.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// The best declared variant in sample (the fit measure's first).
    pub best: String,
    /// Its rows judged in sample: (replicating, equivalent, within 2 SE).
    pub in_sample: (usize, usize, usize),
    /// Every row held out in turn, in report order.
    pub held_out: Vec<HeldOut>,
    /// Declared variants compared.
    pub variants: usize,
    /// The yardstick of the fit measure's first key (rows within 2 SE).
    pub yardstick_2se: Option<Yardstick>,
    /// The yardstick of replicating rows on the scale.
    pub yardstick_scale: Option<Yardstick>,
}

impl Selection {
    /// Cross-validated counts: (replicating, equivalent, within 2 SE).
    pub fn cross_validated(&self) -> (usize, usize, usize) {
        let count = |f: &dyn Fn(&HeldOut) -> bool| self.held_out.iter().filter(|h| f(h)).count();
        (
            count(&|h| h.verdict.replicates()),
            count(&|h| h.verdict == Verdict::Equivalent),
            count(&|h| h.fit_verdict == FitVerdict::Replicates),
        )
    }
}

/// The selection over the declared variants of `variants` (none in an exploratory search, whose
/// choice is judged on held-out rows of its own, or with fewer than two declared variants), over
/// the rows every declared variant scores.
pub fn selection(exploratory: bool, variants: &[VariantDigest]) -> Option<Selection> {
    let declared: Vec<&VariantDigest> = variants.iter().filter(|v| !v.info.exploratory).collect();
    if exploratory || declared.len() < 2 {
        return None;
    }
    let rows: Vec<&RowFit> = declared[0]
        .rows
        .iter()
        .filter(|r| declared.iter().all(|v| v.rows.iter().any(|o| o.key() == r.key())))
        .collect();
    if rows.is_empty() {
        return None;
    }
    fn row_of<'v>(v: &'v VariantDigest, k: &RowKey) -> Option<&'v RowFit> {
        v.rows.iter().find(|o| &o.key() == k)
    }
    let held_out = rows
        .iter()
        .map(|r| {
            let k = r.key();
            let fits: Vec<Fit> =
                declared.iter().map(|v| Fit::from_rows(v.rows.iter().filter(|o| o.key() != k))).collect();
            let chosen = declared[fit_order(&fits)[0]];
            let under = row_of(chosen, &k).expect("every declared variant scores the row");
            HeldOut {
                label: r.algorithm.label(r.repr).to_string(),
                row: k,
                chosen: chosen.info.id.clone(),
                verdict: under.headline().best.verdict,
                fit_verdict: under.fit_verdict,
            }
        })
        .collect();
    let fits: Vec<Fit> = declared.iter().map(|v| v.fit).collect();
    let best = declared[fit_order(&fits)[0]];
    let outcomes = |f: &dyn Fn(&RowFit) -> bool| -> Vec<Vec<bool>> {
        rows.iter().map(|r| declared.iter().map(|v| row_of(v, &r.key()).is_some_and(f)).collect()).collect()
    };
    Some(Selection {
        best: best.info.id.clone(),
        in_sample: (best.fit.replicating_by_n[2], best.fit.scale[0], best.fit.within_2se),
        held_out,
        variants: declared.len(),
        yardstick_2se: yardstick(&outcomes(&|o| o.fit_verdict == FitVerdict::Replicates), PERMUTATIONS, SEED),
        yardstick_scale: yardstick(
            &outcomes(&|o| o.headline().best.verdict.replicates()),
            PERMUTATIONS,
            SEED,
        ),
    })
}

/// The rule, as stated in captions.
pub const SELECTION_RULE: &str = "Leave-one-row-out (docs/preregistration.md): for each Table III \
row, the declared variants are ranked by the fit measure on the other rows; the first is that row's \
chosen variant, and the row is judged under it (verdict: the scale at n_paper = 10; verdict_2se: the \
old rule).";

/// `cross_validation.csv`: one line per held-out row.
pub fn table(s: &Selection) -> Table {
    let columns = vec![
        Column::new("System", "system", Align::Left),
        Column::new("Exp.", "experiment", Align::Left),
        Column::new("Algorithm", "algorithm", Align::Left),
        Column::new("Chosen on the other rows", "chosen_variant", Align::Left),
        Column::new("Verdict", "verdict", Align::Left),
        Column::new("Verdict (old rule)", "verdict_2se", Align::Left),
    ];
    let rows = s
        .held_out
        .iter()
        .map(|h| Row {
            values: vec![
                Value::Text(h.row.0.title().into()),
                Value::User(h.row.1.clone()),
                Value::Text(h.label.clone()),
                Value::User(h.chosen.clone()),
                Value::Text(h.verdict.label().into()),
                Value::Text(h.fit_verdict.label().into()),
            ],
            highlight: h.chosen != s.best,
        })
        .collect();
    let (rep, eq, se) = s.cross_validated();
    Table {
        title: "Leave-one-row-out".into(),
        caption: format!(
            "{SELECTION_RULE} Cross-validated: {rep} of {} rows replicate ({eq} equivalent), {se} within 2 SE; \
             in sample under `{}`: {}, {}, {}. Highlighted: rows whose chosen variant is not `{}`.",
            s.held_out.len(),
            s.best,
            s.in_sample.0,
            s.in_sample.1,
            s.in_sample.2,
            s.best
        ),
        columns,
        rows,
    }
}
