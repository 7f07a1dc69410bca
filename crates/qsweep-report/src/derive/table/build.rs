//! The report's tables built from [`ReportData`]: Table III (best cell per system, experiment and
//! algorithm, with the paper's values, ours at the paper's configuration and each row's cause when
//! the pipeline has reference values) and one cell table per experiment.

use crate::derive::judgement::{judge_row, moments};
use crate::derive::model::{resolution_columns, CellData, ReportData};
use crate::derive::table::model::{Align, Column, Row, Table, Value};
use qsweep_pipeline::analysis::consistency::CONSISTENCY_RULE;
use qsweep_pipeline::analysis::equivalence::{against_paper, EQUIVALENCE_RULE};
use qsweep_pipeline::analysis::survival::SURVIVAL_RULE;
use qsweep_pipeline::analysis::verdict::{
    cause_2se, fit_verdict, FitVerdict, CAUSE_RULE, HEADLINE_N, SCALE_RULE, SPREAD_RULE,
};
use qsweep_pipeline::analysis::{BEST_RULE, CENSORING, RACE_RULE};
use qsweep_pipeline::declared::Reference;

fn var_columns(prefix: &str) -> Vec<Column> {
    let vars = [
        ("x", "$x$", "x"),
        ("ẋ", "$\\dot{x}$", "x_dot"),
        ("θ", "$\\theta$", "theta"),
        ("θ̇", "$\\dot{\\theta}$", "theta_dot"),
    ];
    vars.iter().map(|(t, l, c)| Column::new(t, &format!("{prefix}{c}"), Align::Right).latex(l)).collect()
}

fn opt_int(v: Option<u32>) -> Value {
    v.map_or(Value::Missing, |v| Value::Int(u64::from(v)))
}

/// Table III: one row per system, experiment and algorithm.
pub fn table3(data: &ReportData) -> Table {
    let (mut t, parts) = table3_built(data);
    for (_, caption) in parts {
        t.caption.push(' ');
        t.caption.push_str(&caption);
    }
    t
}

/// The columns of one cell's estimate, CSV names after `prefix`: its bootstrap interval, its
/// fresh-seed estimate (with `fresh`), censoring, and (with `reference`) its ratio to the paper
/// and the equivalence tests.
fn estimate_columns(prefix: &str, fresh: bool, reference: bool) -> Vec<Column> {
    let name = |s: &str| format!("{prefix}{s}");
    let pair = |title: &str, lo: &str, hi: &str| {
        Column::new(title, &name(lo), Align::Right).fields(&[name(lo).as_str(), name(hi).as_str()])
    };
    let mut columns = vec![pair("95% CI", "ci_lo", "ci_hi")];
    if fresh {
        columns.push(pair("Fresh", "fresh_mean", "fresh_std"));
        columns.push(Column::new("Fresh n", &name("fresh_n"), Align::Right));
        columns.push(pair("Fresh 95% CI", "fresh_ci_lo", "fresh_ci_hi"));
    }
    columns.push(Column::new("Censored", &name("censored"), Align::Right));
    columns.push(Column::new("KM median", &name("km_median"), Align::Right));
    if reference {
        columns.push(Column::new("Ours/paper", &name("ratio"), Align::Right));
        columns.push(pair("Ours/paper 95% CI", "ratio_lo", "ratio_hi"));
        for n in qsweep_pipeline::analysis::equivalence::PAPER_N {
            columns.push(Column::new(
                &format!("TOST p (n={n})"),
                &name(&format!("tost_p_n{n}")),
                Align::Right,
            ));
            columns.push(Column::new(
                &format!("Equivalent (n={n})"),
                &name(&format!("equivalent_n{n}")),
                Align::Left,
            ));
        }
    }
    columns
}

fn num(v: Option<f64>, decimals: usize) -> Value {
    v.map_or(Value::Missing, |value| Value::Num { value, decimals, signed: false })
}

/// The values of [`estimate_columns`] for `cell` (none: every value missing) against `r`, the
/// row's published value (`None`: the row has none, or the pipeline has no reference values).
fn estimate_values(
    cell: Option<&CellData>,
    fresh: bool,
    reference: bool,
    r: Option<&Reference>,
) -> Vec<Value> {
    let mut values = vec![match cell.map(|c| (c.summary.ci_lo, c.summary.ci_hi)) {
        Some((Some(lo), Some(hi))) => Value::Range { lo, hi, decimals: 2 },
        _ => Value::Missing,
    }];
    if fresh {
        let f = cell.and_then(|c| c.fresh_summary.as_ref().map(|s| (s, c.fresh.len())));
        values.push(match f {
            Some((s, _)) => Value::MeanStd {
                mean: s.mean.expect("fresh trials are present"),
                std: s.std,
                decimals: 2,
                marked: false,
            },
            None => Value::Missing,
        });
        values.push(Value::Int(f.map_or(0, |(_, n)| n as u64)));
        values.push(match f.map(|(s, _)| (s.ci_lo, s.ci_hi)) {
            Some((Some(lo), Some(hi))) => Value::Range { lo, hi, decimals: 2 },
            _ => Value::Missing,
        });
    }
    // The row is judged on the fresh-seed estimate where it has one.
    let est = cell.map(|c| c.estimate());
    values.push(num(est.and_then(|e| e.censored_fraction()), 2));
    values.push(num(est.and_then(|e| e.km_median()), 1));
    if reference {
        let r = r.filter(|r| r.mean > 0.0);
        match (est, r) {
            (Some(est), Some(r)) if est.summary.mean.is_some() => {
                let s = est.summary;
                values.push(num(s.mean.map(|m| m / r.mean), 3));
                values.push(match (s.ci_lo, s.ci_hi) {
                    (Some(lo), Some(hi)) => Value::Range { lo: lo / r.mean, hi: hi / r.mean, decimals: 3 },
                    _ => Value::Missing,
                });
                let mean = s.mean.expect("checked above");
                for t in against_paper(mean, s.std, est.n(), r.mean, r.std) {
                    values.push(num(t.map(|t| t.p), 4));
                    values.push(t.map_or(Value::Missing, |t| {
                        Value::Text(if t.equivalent { "yes" } else { "no" }.into())
                    }));
                }
            }
            _ => values.extend(std::iter::repeat_n(Value::Missing, 6)),
        }
    }
    values
}

/// The old rule's verdict of `cell`'s estimate (fresh where present) against `r`.
fn cell_verdict_2se(cell: Option<&CellData>, r: &Reference) -> Option<FitVerdict> {
    let m = moments(cell?)?;
    Some(fit_verdict(m.mean, m.std, m.n, r.mean, r.std))
}

/// Table III with the caption of its first part, and the index of the first column and the caption
/// of each further part: the uncertainty of the best cell, and (with reference values) the cell at
/// the paper's configuration and each row's cause.
fn table3_built(data: &ReportData) -> (Table, Vec<(Vec<usize>, String)>) {
    let reference = data.has_reference();
    let mut columns = vec![
        Column::new("System", "system", Align::Left),
        Column::new("Exp.", "experiment", Align::Left),
        Column::new("Algorithm", "algorithm", Align::Left),
        Column::new("Performance", "mean", Align::Right).fields(&["mean", "std"]),
    ];
    columns.extend(var_columns(""));
    columns.push(Column::new("Actions", "actions", Align::Right));
    columns.push(Column::new("n", "n", Align::Right).latex("$n$"));
    columns.push(Column::new("Successes", "successes", Align::Right));
    if reference {
        columns.push(Column::new("Paper", "paper_mean", Align::Right).fields(&["paper_mean", "paper_std"]));
        columns.push(
            Column::new("Paper config (x, ẋ, θ, θ̇, actions)", "paper_x", Align::Left)
                .latex("Paper config ($x, \\dot{x}, \\theta, \\dot{\\theta}$, actions)")
                .fields(&["paper_x", "paper_x_dot", "paper_theta", "paper_theta_dot", "paper_actions"]),
        );
        columns.push(Column::new("Δ mean", "diff_mean", Align::Right).latex("$\\Delta$ mean"));
    }
    let raced = data.plan.raced;
    if raced {
        columns.push(Column::new("Contenders", "contenders", Align::Right));
        if reference {
            columns.push(Column::new("Paper config tied", "reference_config_tied", Align::Left));
        }
    }
    // Uncertainty last, so the earlier CSV fields keep their positions; the paper's cell after it,
    // so every field before keeps its position too.
    let split = columns.len();
    let fresh = data.plan.has_fresh();
    columns.extend(estimate_columns("", fresh, reference));
    let paper_split = columns.len();
    if reference {
        columns.push(
            Column::new("At paper config", "paper_cell_mean", Align::Right)
                .fields(&["paper_cell_mean", "paper_cell_std"]),
        );
        columns.push(Column::new("n", "paper_cell_n", Align::Right).latex("$n$"));
        columns.push(Column::new("Successes", "paper_cell_successes", Align::Right));
        columns.extend(estimate_columns("paper_cell_", fresh, true));
    }
    let cause_split = columns.len();
    if reference {
        columns.push(Column::new("Within 2 SE (best)", "verdict_2se", Align::Left));
        columns.push(Column::new("Within 2 SE (paper config)", "paper_cell_verdict_2se", Align::Left));
        columns.push(Column::new("Cause (old rule)", "cause_2se", Align::Left));
        columns.push(Column::new("Contradictory pair", "contradictory_pair", Align::Left));
        columns.push(Column::new("Paper inconsistent", "paper_inconsistent", Align::Left));
        columns.push(Column::new("TOST 2× p", "tost2x_p_n10", Align::Right));
        columns.push(Column::new("TOST 2× p (paper config)", "paper_cell_tost2x_p_n10", Align::Right));
        columns.push(Column::new("Verdict (best)", "verdict", Align::Left));
        columns.push(Column::new("Verdict (paper config)", "paper_cell_verdict", Align::Left));
        columns.push(Column::new("Cause", "cause", Align::Left));
        columns.push(Column::new("Std ratio", "std_ratio", Align::Right));
        columns.push(
            Column::new("Std ratio 95% CI", "std_ratio_lo", Align::Right)
                .fields(&["std_ratio_lo", "std_ratio_hi"]),
        );
        columns.push(Column::new("Spread differs", "spread_differs", Align::Left));
    }
    let contradictions = if reference { data.contradictions(HEADLINE_N) } else { Default::default() };
    let mut rows = Vec::new();
    for (ei, e) in data.experiments.iter().enumerate() {
        let exp = e.exp;
        for &alg in &exp.algorithms {
            let best = e.best_of(alg).map(|b| (b, &e.cells[b.cell]));
            let mut values = vec![
                Value::Text(exp.system.title().into()),
                Value::User(exp.id.clone()),
                Value::Text(alg.label(exp.repr).into()),
            ];
            let ours = best.and_then(|(_, c)| c.summary.mean);
            match best {
                Some((b, c)) => {
                    let s = &c.summary;
                    values.push(Value::MeanStd {
                        mean: s.mean.expect("a best cell has trials"),
                        std: s.std,
                        decimals: 2,
                        marked: !b.all_converged,
                    });
                    let cfg = &c.cell.config;
                    values.extend(resolution_columns(exp.system, &cfg.repr.resolution).map(opt_int));
                    values.push(Value::Int(u64::from(cfg.actions)));
                    values.push(Value::Int(c.trials.len() as u64));
                    values.push(Value::Int(c.successes as u64));
                }
                None => {
                    values.extend(std::iter::repeat_n(Value::Missing, 6));
                    values.extend([Value::Int(0), Value::Int(0)]);
                }
            }
            let r = exp.reference.get(&alg);
            if reference {
                match r {
                    Some(r) => {
                        values.push(Value::MeanStd {
                            mean: r.mean,
                            std: Some(r.std),
                            decimals: 2,
                            marked: false,
                        });
                        let mut cfg: Vec<Option<u32>> = match &r.resolution {
                            Some(res) => resolution_columns(exp.system, res).to_vec(),
                            None => vec![None; 4],
                        };
                        cfg.push(r.actions);
                        values.push(Value::List(cfg));
                        values.push(ours.map_or(Value::Missing, |m| Value::Num {
                            value: m - r.mean,
                            decimals: 2,
                            signed: true,
                        }));
                    }
                    None => values.extend([Value::Missing, Value::Missing, Value::Missing]),
                }
            }
            if raced {
                values.push(e.contenders(alg).map_or(Value::Missing, |n| Value::Int(n as u64)));
                if reference {
                    // Empty without a reference configuration, or outside a race.
                    let tied = e.reference_cell(alg).and_then(|i| e.cells[i].cell.contender);
                    values.push(tied.map_or(Value::Missing, |t| Value::Text(t.to_string())));
                }
            }
            let cell = best.map(|(_, c)| c);
            values.extend(estimate_values(cell, fresh, reference, r));
            if reference {
                let at = e.reference_cell(alg).map(|i| &e.cells[i]);
                values.push(match at.and_then(|c| c.summary.mean.map(|m| (m, c.summary.std))) {
                    Some((mean, std)) => Value::MeanStd { mean, std, decimals: 2, marked: false },
                    None => Value::Missing,
                });
                values.push(Value::Int(at.map_or(0, |c| c.trials.len() as u64)));
                values.push(Value::Int(at.map_or(0, |c| c.successes as u64)));
                values.extend(estimate_values(at, fresh, true, r));
                let text = |s: &str| Value::Text(s.into());
                let yes_no = |b: bool| text(if b { "yes" } else { "no" });
                let p = |v: Option<f64>| num(v, 4);
                match (r, cell.and_then(moments)) {
                    (Some(r), Some(best_m)) => {
                        let (best_v, at_v) = (cell_verdict_2se(cell, r), cell_verdict_2se(at, r));
                        let in_pair = contradictions.in_pair.contains(&(ei, alg));
                        let j = judge_row(
                            best_m,
                            at.and_then(moments),
                            r,
                            &contradictions,
                            (ei, alg),
                            HEADLINE_N,
                        );
                        values.push(best_v.map_or(Value::Missing, |v| text(v.label())));
                        values.push(at_v.map_or(Value::Missing, |v| text(v.label())));
                        values.push(best_v.map_or(Value::Missing, |v| text(cause_2se(v, in_pair, at_v))));
                        values.push(yes_no(j.in_pair));
                        values.push(yes_no(j.designated));
                        values.push(p(j.best.tost2x_p));
                        values.push(p(j.paper_cell.and_then(|a| a.tost2x_p)));
                        values.push(text(j.best.verdict.label()));
                        values.push(j.paper_cell.map_or(Value::Missing, |a| text(a.verdict.label())));
                        values.push(text(j.cause.label()));
                        match qsweep_pipeline::analysis::verdict::spread(
                            best_m.std, best_m.n, r.std, HEADLINE_N,
                        ) {
                            Some(sp) => values.extend([
                                num(Some(sp.ratio), 3),
                                Value::Range { lo: sp.lo, hi: sp.hi, decimals: 3 },
                                yes_no(sp.differs()),
                            ]),
                            None => values.extend(std::iter::repeat_n(Value::Missing, 3)),
                        }
                    }
                    _ => values.extend(std::iter::repeat_n(Value::Missing, 13)),
                }
            }
            rows.push(Row { values, highlight: false });
        }
    }
    let mut caption = String::from(
        "Best-performing configuration per system, experiment and algorithm (the paper's Table III): \
         mean ± std of the episodes needed to reach the learning goal over the best cell's trials, and \
         that cell's bins or fuzzy sets per state variable (— where the system has no such variable) \
         and number of actions; n = trials present, successes = trials that reached the goal. ",
    );
    caption.push_str(BEST_RULE);
    caption.push(' ');
    caption.push_str(CENSORING);
    if reference {
        caption.push_str(" Paper: the published value and configuration; Δ mean = ours − paper.");
    }
    let mut uncertainty = String::from("95% CI: bootstrap interval of the best cell's mean. ");
    if fresh {
        uncertainty.push_str(qsweep_pipeline::fresh::FRESH_RULE);
        uncertainty.push(' ');
    }
    uncertainty.push_str(SURVIVAL_RULE);
    if reference {
        uncertainty.push(' ');
        uncertainty.push_str(EQUIVALENCE_RULE);
    }
    if raced {
        caption.push(' ');
        caption.push_str(RACE_RULE);
        if reference {
            caption
                .push_str(" Paper config tied: whether the paper's configuration is among the contenders.");
        }
    }
    if data.trials_cached < data.trials_planned {
        caption.push_str(&format!(
            " Only {} of {} planned trials are present.",
            data.trials_cached, data.trials_planned
        ));
    }
    let mut parts = vec![((split..paper_split).collect::<Vec<_>>(), uncertainty)];
    if reference {
        // The paper's cell has fresh-seed trials only where it is also the best cell, whose columns
        // show them: the page leaves its fresh-seed and survival columns and its TOST p-values (its
        // equivalence verdicts stay) to the CSV, so that the table fits a page's width.
        let shown = (paper_split..cause_split).filter(|&i| {
            let key = &columns[i].csv[0];
            !key.starts_with("paper_cell_fresh")
                && !key.starts_with("paper_cell_tost_p")
                && key != "paper_cell_km_median"
        });
        parts.push((
            shown.collect(),
            "At paper config: the cell of the same heatmap at the paper's stated configuration \
             (mean ± std over the grid's seeds, n, successes), with the same interval, censoring and \
             equivalence verdicts as the best cell; table3.csv adds its fresh-seed estimate (only \
             where it is also the best cell), Kaplan–Meier median and TOST p-values."
                .to_string(),
        ));
        // The old rule's columns and the within-2× p-values are kept in the CSV for comparison;
        // the pages show the verdicts that decide.
        let csv_only = [
            "verdict_2se",
            "paper_cell_verdict_2se",
            "cause_2se",
            "tost2x_p_n10",
            "paper_cell_tost2x_p_n10",
            "std_ratio_lo",
        ];
        parts.push((
            (cause_split..columns.len())
                .filter(|&i| !csv_only.contains(&columns[i].csv[0].as_str()))
                .collect(),
            format!(
                "Verdicts of the best cell and of the paper's cell, on their fresh-seed estimate where \
                 present. {SCALE_RULE} Contradictory pair, paper inconsistent: {CONSISTENCY_RULE} \
                 {CAUSE_RULE} {SPREAD_RULE} table3.csv adds the within-2× TOST's p and, for comparison, \
                 the old rule of two standard errors (verdict_2se, paper_cell_verdict_2se, cause_2se; \
                 docs/reports.md)."
            ),
        ));
    }
    (Table { title: format!("Table III ({})", data.plan.report_name()), caption, columns, rows }, parts)
}

/// The further parts of Table III on the pages after the best configurations: (HTML id, title).
pub const TABLE3_PARTS: [(&str, &str); 3] = [
    ("uncertainty", "uncertainty"),
    ("paper-config", "at the paper's configuration"),
    ("cause", "verdicts and cause"),
];

/// Table III as the pages show it, in tables of the same rows: the best configurations (the
/// paper's columns, and a race's), then their uncertainty (the rows' keys and the interval,
/// censoring and equivalence columns), then, with reference values, ours at the paper's
/// configuration and each row's cause; side by side they would be too wide to read. The CSV is the
/// whole [`table3`].
pub fn table3_parts(data: &ReportData) -> Vec<Table> {
    let (full, parts) = table3_built(data);
    let keep = |cols: &[usize], title: String, caption: String| Table {
        title,
        caption,
        columns: cols.iter().map(|&i| full.columns[i].clone()).collect(),
        rows: full
            .rows
            .iter()
            .map(|r| Row {
                values: cols.iter().map(|&i| r.values[i].clone()).collect(),
                highlight: r.highlight,
            })
            .collect(),
    };
    let main: Vec<usize> = (0..parts[0].0[0]).collect();
    let mut out = vec![keep(&main, full.title.clone(), full.caption.clone())];
    for ((shown, caption), name) in parts.iter().zip(TABLE3_PARTS) {
        let cols: Vec<usize> = (0..3).chain(shown.iter().copied()).collect();
        out.push(keep(&cols, format!("{}: {}", full.title, name.1), caption.clone()));
    }
    out
}
