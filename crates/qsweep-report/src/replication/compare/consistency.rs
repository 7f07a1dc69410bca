//! The paper against itself: every pair of Table III rows whose grids overlap, with the Welch test
//! of their published means ([`crate::replication::stats::consistency`]), as the comparison's
//! `consistency.csv` and `consistency.md`; and the tally of each row's cause
//! ([`crate::replication::stats::verdict::Cause`]) for the comparison page's opening.

use crate::derive::table::{Align, Column, Row, Table, Value};
use crate::replication::compare::fit::{fit_order, Cause, Fit, HEADLINE_N, PAPER_N_SET};
use crate::replication::compare::VariantDigest;
use crate::replication::published::published_rows;
use crate::replication::stats::consistency::{pairs, Config, Pair, ALPHA, CONSISTENCY_RULE};
use crate::replication::stats::verdict::CAUSE_RULE;
use qsweep_pipeline::plan::Plan;

/// A configuration as the table writes it: bins or sets per variable joined by `×`, then `/` and
/// the action count (no comma, so the CSV field needs no quotes).
fn config_text(c: &Option<Config>) -> Value {
    c.as_ref().map_or(Value::Missing, |(res, actions)| {
        let res: Vec<String> = res.iter().map(|r| r.to_string()).collect();
        Value::Text(format!("{} / {actions}", res.join("×")))
    })
}

/// The comparable pairs of `plan`'s published rows (those of its first variant: every variant
/// holds the same paper), and the table listing them (`None` when the plan has no reference
/// values).
pub fn consistency_table(plan: &Plan) -> Option<(Vec<Pair>, Table)> {
    let rows: Vec<_> = published_rows(plan).into_iter().next()?.into_iter().map(|r| r.2).collect();
    let found = pairs(&rows, HEADLINE_N);
    // The pairs with fewer paper runs: 5, then 3 (the sensitivity set below the headline).
    let fewer = [PAPER_N_SET[1], PAPER_N_SET[0]].map(|n| pairs(&rows, n));
    let columns = vec![
        Column::new("System", "system", Align::Left),
        Column::new("Representation", "representation", Align::Left),
        Column::new("Algorithm", "algorithm", Align::Left),
        Column::new("Exp. a", "experiment_a", Align::Left),
        Column::new("Paper a", "mean_a", Align::Right).fields(&["mean_a", "std_a"]),
        Column::new("Config a (bins / actions)", "config_a", Align::Left),
        Column::new("Exp. b", "experiment_b", Align::Left),
        Column::new("Paper b", "mean_b", Align::Right).fields(&["mean_b", "std_b"]),
        Column::new("Config b (bins / actions)", "config_b", Align::Left),
        Column::new("Grids imply", "implied", Align::Left),
        Column::new("Welch t (b − a)", "t", Align::Right),
        Column::new("df", "df", Align::Right),
        Column::new("p (two-sided)", "p", Align::Right),
        Column::new("Contradictory", "contradictory", Align::Left),
        Column::new("Marked", "marked", Align::Left),
        Column::new("p (n=5)", "p_n5", Align::Right),
        Column::new("n=5", "contradictory_n5", Align::Left),
        Column::new("p (n=3)", "p_n3", Align::Right),
        Column::new("n=3", "contradictory_n3", Align::Left),
    ];
    let num = |value: f64, decimals: usize| {
        if value.is_finite() {
            Value::Num { value, decimals, signed: false }
        } else {
            Value::Missing
        }
    };
    let yes_no = |b: bool| Value::Text(if b { "yes" } else { "no" }.into());
    let table_rows = found
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let (a, b) = (&rows[p.a], &rows[p.b]);
            let ms =
                |mean: f64, std: f64| Value::MeanStd { mean, std: Some(std), decimals: 2, marked: false };
            Row {
                values: vec![
                    Value::Text(a.system.title().into()),
                    Value::Text(a.repr.name().into()),
                    Value::Text(a.algorithm.label(a.repr).into()),
                    Value::User(a.experiment.clone()),
                    ms(a.mean, a.std),
                    config_text(&a.config),
                    Value::User(b.experiment.clone()),
                    ms(b.mean, b.std),
                    config_text(&b.config),
                    Value::Text(p.implied.label().into()),
                    num(p.t, 3),
                    num(p.df, 2),
                    Value::Num { value: p.p, decimals: 6, signed: false },
                    yes_no(p.contradictory),
                    match p.designated() {
                        Some(i) if i == p.a => Value::Text("a".into()),
                        Some(_) => Value::Text("b".into()),
                        None => Value::Missing,
                    },
                    Value::Num { value: fewer[0][k].p, decimals: 6, signed: false },
                    yes_no(fewer[0][k].contradictory),
                    Value::Num { value: fewer[1][k].p, decimals: 6, signed: false },
                    yes_no(fewer[1][k].contradictory),
                ],
                highlight: p.contradictory,
            }
        })
        .collect();
    let bad = found.iter().filter(|p| p.contradictory).count();
    let caption = format!(
        "Where the paper's grids overlap: {} comparable pair{} of Table III rows, {bad} contradictory \
         (α = {ALPHA}). {CONSISTENCY_RULE} Config: the published configuration's bins or sets per \
         variable, then the action count. Grids imply: what the published minima must satisfy \
         (b ≤ a: row a's configuration is a cell of row b's grid). Marked: the row the pair costs (a or \
         b). p (n=5, n=3), n=5, n=3: the same test and whether it finds the pair contradictory with the \
         paper's means taken over 5 or 3 runs.",
        found.len(),
        if found.len() == 1 { "" } else { "s" }
    );
    Some((found, Table { title: "The paper against itself".into(), caption, columns, rows: table_rows }))
}

/// The opening sentence on causes: the tally of the best declared variant (first by the fit
/// measure; in an exploratory search, the chosen variant, ranked on the fit rows), or `None`
/// without reference rows.
pub fn cause_tally(plan: &Plan, variants: &[VariantDigest]) -> Option<String> {
    let (v, which) = if plan.exploratory.is_some() {
        let id = &crate::replication::compare::explore::chosen(plan, variants)?.id;
        (variants.iter().find(|v| &v.info.id == id)?, "the chosen variant of the search")
    } else {
        let fits: Vec<Fit> = variants.iter().map(|v| v.fit).collect();
        let best = fit_order(&fits).into_iter().find(|&i| !variants[i].info.exploratory)?;
        (&variants[best], "the best declared variant")
    };
    if v.rows.is_empty() {
        return None;
    }
    let counts: Vec<String> = Cause::ALL
        .iter()
        .map(|c| format!("{} {}", v.rows.iter().filter(|r| r.headline().cause == *c).count(), c.label()))
        .collect();
    Some(format!(
        "Why each Table III row does or does not replicate, under {which} `{}` ({} rows): {}. \
         {CAUSE_RULE} Each variant's table3.csv gives the cause per row beside ours at the paper's \
         configuration; consistency.csv lists the pairs of rows the paper's own numbers contradict.",
        v.info.id,
        v.rows.len(),
        counts.join(", ")
    ))
}
