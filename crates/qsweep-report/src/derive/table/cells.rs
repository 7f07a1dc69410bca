//! One table per experiment: every cell with its statistics, the best cell of each algorithm
//! highlighted (`index.html`'s cell tables).

use crate::derive::report_data::ExpData;
use crate::derive::table::model::{Align, Column, Row, Table, Value};
use qsweep_pipeline::analysis::{CENSORING, RACE_RULE};

/// `v` as an integer value when it is a whole number a `u64` holds exactly.
fn whole(v: f64) -> Option<Value> {
    (v.fract() == 0.0 && (0.0..9e15).contains(&v)).then_some(Value::Int(v as u64))
}

/// Every cell of one experiment with its statistics; the best cell of each algorithm highlighted.
pub fn cell_table(e: &ExpData) -> Table {
    let exp = e.exp;
    let mut columns = vec![Column::new("Algorithm", "algorithm", Align::Left)];
    for a in &exp.axes {
        columns.push(Column::new(&a.label, &a.label.replace(" == ", "_eq_"), Align::Right));
    }
    columns.extend([
        Column::new("n", "n", Align::Right),
        Column::new("Successes", "successes", Align::Right),
        Column::new("Mean ± std", "mean", Align::Right).fields(&["mean", "std"]),
        Column::new("Median", "median", Align::Right),
        Column::new("IQM", "iqm", Align::Right),
        Column::new("95% CI of mean", "ci_lo", Align::Right).fields(&["ci_lo", "ci_hi"]),
        Column::new("Min", "min", Align::Right),
        Column::new("Max", "max", Align::Right),
    ]);
    if exp.race.is_some() {
        columns.push(Column::new("Contender", "contender", Align::Left));
        columns.push(Column::new("Rank test p", "rank_p", Align::Right));
        columns.push(Column::new("Rank: worse", "rank_worse", Align::Left));
    }
    let ranks = e.rank_tests();
    let num =
        |v: Option<f64>| v.map_or(Value::Missing, |value| Value::Num { value, decimals: 2, signed: false });
    let rows = e
        .cells
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let s = &c.summary;
            // The caption names the representation; the rows only need the algorithm.
            let mut values = vec![Value::Text(c.cell.algorithm.symbol().into())];
            values.extend(c.cell.coords.iter().map(|&v| {
                whole(v).unwrap_or_else(|| Value::Text(qsweep_pipeline::declared::format_value(v)))
            }));
            values.push(Value::Int(c.trials.len() as u64));
            values.push(Value::Int(c.successes as u64));
            values.push(s.mean.map_or(Value::Missing, |mean| Value::MeanStd {
                mean,
                std: s.std,
                decimals: 2,
                marked: false,
            }));
            values.push(num(s.median));
            values.push(num(s.iqm));
            values.push(match (s.ci_lo, s.ci_hi) {
                (Some(lo), Some(hi)) => Value::Range { lo, hi, decimals: 2 },
                _ => Value::Missing,
            });
            // Counts are whole numbers: min and max print without decimals.
            values.push(s.min.and_then(whole).unwrap_or_else(|| num(s.min)));
            values.push(s.max.and_then(whole).unwrap_or_else(|| num(s.max)));
            if exp.race.is_some() {
                let yes_no = |b: bool| Value::Text(if b { "yes" } else { "no" }.into());
                values.push(c.cell.contender.map_or(Value::Missing, yes_no));
                values.push(ranks[i].map_or(Value::Missing, |r| Value::Num {
                    value: r.0,
                    decimals: 4,
                    signed: false,
                }));
                values.push(ranks[i].map_or(Value::Missing, |r| yes_no(r.1)));
            }
            Row { values, highlight: e.is_best(i) }
        })
        .collect();
    let fixed: Vec<String> = exp
        .fixed
        .iter()
        .map(|(t, v)| format!("{} = {v}", qsweep_pipeline::declared::target_name(exp.system, *t)))
        .collect();
    let mut caption = format!(
        "{}, Exp. {}{} ({} representation)",
        exp.system.title(),
        exp.id,
        exp.title.as_deref().map(|t| format!(": {t}")).unwrap_or_default(),
        exp.repr.name()
    );
    if !fixed.is_empty() {
        caption.push_str(&format!("; fixed: {}", fixed.join(", ")));
    }
    caption.push_str(". Highlighted: the best cell of each algorithm (Table III). ");
    if exp.race.is_some() {
        caption.push_str(RACE_RULE);
        caption.push_str(
            " Rank test (a label beside the race, not its rule): the one-sided Mann–Whitney U test \
             of each cell against its algorithm's best, Holm-corrected over the heatmap at the race's \
             level; Rank: worse = significantly worse by ranks. ",
        );
    }
    caption.push_str(CENSORING);
    Table { title: format!("{} Exp. {}", exp.system.title(), exp.id), caption, columns, rows }
}
