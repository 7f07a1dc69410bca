//! Table III's columns, one list: each column's heading, the part of the pages it belongs to (or
//! the CSV only), and how a row's value is computed ([`columns`]). A column cannot get out of step
//! with its values: both come from one entry.

use crate::derive::report_data::{CellData, ExpData, ReportData};
use crate::derive::table::{Align, Column, Value};
use crate::replication::judgement::{judge_row, moments, RowJudgement};
use crate::replication::published::{has_reference, km_median, reference_cell, Contradictions};
use crate::replication::stats::equivalence::{against_paper, PAPER_N};
use crate::replication::stats::verdict::{cause_2se, fit_verdict, spread, FitVerdict, Spread, HEADLINE_N};
use qsweep_engine::Algorithm;
use qsweep_pipeline::analysis::Best;
use qsweep_pipeline::declared::Reference;

/// Where a column is shown on the pages: the table of best configurations, or one of the further
/// parts ([`super::TABLE3_PARTS`]). The CSV has every column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Part {
    /// The best configurations (the paper's columns, and a race's).
    Main,
    /// The uncertainty of the best cell.
    Uncertainty,
    /// Ours at the paper's configuration.
    PaperConfig,
    /// The verdicts and each row's cause.
    Cause,
}

/// One Table III row as its columns read it: what is computed once per row.
pub(super) struct RowCtx<'c, 'a> {
    e: &'c ExpData<'a>,
    alg: Algorithm,
    /// The best cell of the row's heatmap and algorithm.
    best: Option<(Best, &'c CellData<'a>)>,
    /// The row's published value.
    r: Option<&'c Reference>,
    /// Our cell at the paper's configuration.
    at: Option<&'c CellData<'a>>,
    /// The best cell's bins or sets per variable column.
    res: Vec<Option<u32>>,
    /// The paper's configuration: per variable column, then the action count.
    paper_config: Vec<Option<u32>>,
    /// The row judged (with a published value and a best cell with trials).
    judged: Option<Judged>,
}

/// A row's verdicts, where it has a published value and a best cell with trials.
struct Judged {
    /// The old rule's verdict of the best cell and of the paper's cell.
    best_2se: FitVerdict,
    at_2se: Option<FitVerdict>,
    /// The row belongs to a contradictory pair (at the headline n).
    in_pair: bool,
    /// The row judged at the headline n.
    j: RowJudgement,
    /// Our spread against the paper's.
    spread: Option<Spread>,
}

impl<'c, 'a> RowCtx<'c, 'a> {
    /// The row of experiment `ei` (`e`) and `alg` of `data`.
    pub(super) fn new(
        data: &ReportData,
        ei: usize,
        e: &'c ExpData<'a>,
        alg: Algorithm,
        contradictions: &Contradictions,
    ) -> Self {
        let best = e.best_of(alg).map(|b| (b, &e.cells[b.cell]));
        let r = e.exp.reference.get(&alg);
        let at = reference_cell(e, alg).map(|i| &e.cells[i]);
        let system = e.exp.system;
        let vars = &data.variables;
        let res =
            best.map_or_else(Vec::new, |(_, c)| vars.resolution(system, &c.cell.config.repr.resolution));
        let paper_config = r.map_or_else(Vec::new, |r| {
            let mut cfg = match &r.resolution {
                Some(res) => vars.resolution(system, res),
                None => vec![None; vars.columns.len()],
            };
            cfg.push(r.actions);
            cfg
        });
        let judged = r.zip(best.and_then(|(_, c)| moments(c))).map(|(r, best_m)| {
            let verdict_2se =
                |c: &CellData| moments(c).map(|m| fit_verdict(m.mean, m.std, m.n, r.mean, r.std));
            Judged {
                best_2se: fit_verdict(best_m.mean, best_m.std, best_m.n, r.mean, r.std),
                at_2se: at.and_then(verdict_2se),
                in_pair: contradictions.in_pair.contains(&(ei, alg)),
                j: judge_row(best_m, at.and_then(moments), r, contradictions, (ei, alg), HEADLINE_N),
                spread: spread(best_m.std, best_m.n, r.std, HEADLINE_N),
            }
        });
        Self { e, alg, best, r, at, res, paper_config, judged }
    }

    fn cell(&self, which: Which) -> Option<&'c CellData<'a>> {
        match which {
            Which::Best => self.best.map(|(_, c)| c),
            Which::PaperCell => self.at,
        }
    }
}

/// Which cell an estimate's columns describe.
#[derive(Debug, Clone, Copy)]
enum Which {
    Best,
    PaperCell,
}

/// How a column's value is computed from its row.
type ValueOf = Box<dyn Fn(&RowCtx<'_, '_>) -> Value>;

/// One column of Table III (see the module documentation).
pub(super) struct Col {
    /// Its heading and CSV fields.
    pub(super) column: Column,
    /// The part of the pages it belongs to.
    pub(super) part: Part,
    /// Shown on the pages (`false`: in the CSV only).
    pub(super) pages: bool,
    /// Its value in a row.
    pub(super) value: ValueOf,
}

fn col(part: Part, column: Column, value: impl Fn(&RowCtx<'_, '_>) -> Value + 'static) -> Col {
    Col { column, part, pages: true, value: Box::new(value) }
}

fn num(v: Option<f64>, decimals: usize) -> Value {
    v.map_or(Value::Missing, |value| Value::Num { value, decimals, signed: false })
}

fn int(v: usize) -> Value {
    Value::Int(v as u64)
}

fn text(s: &str) -> Value {
    Value::Text(s.into())
}

fn yes_no(b: bool) -> Value {
    text(if b { "yes" } else { "no" })
}

fn range(lo: Option<f64>, hi: Option<f64>, decimals: usize) -> Value {
    match (lo, hi) {
        (Some(lo), Some(hi)) => Value::Range { lo, hi, decimals },
        _ => Value::Missing,
    }
}

/// Every column of Table III of `data`, in order (see the module documentation).
pub(super) fn columns(data: &ReportData) -> Vec<Col> {
    let reference = has_reference(data);
    let fresh = data.plan.has_fresh();
    let mut cols = best_columns(data, reference);
    cols.extend(estimate_columns("", Which::Best, Part::Uncertainty, fresh, reference));
    if reference {
        cols.extend(paper_cell_columns(fresh));
        cols.extend(cause_columns());
    }
    cols
}

/// The best configurations: the row's keys, the best cell and its configuration, the paper's value
/// (with reference values), a race's contenders.
fn best_columns(data: &ReportData, reference: bool) -> Vec<Col> {
    use Part::Main;
    let mut cols = vec![
        col(Main, Column::new("System", "system", Align::Left), |r| text(r.e.exp.system.title())),
        col(Main, Column::new("Exp.", "experiment", Align::Left), |r| Value::User(r.e.exp.id.clone())),
        col(Main, Column::new("Algorithm", "algorithm", Align::Left), |r| text(r.alg.label(r.e.exp.repr))),
        col(Main, Column::new("Performance", "mean", Align::Right).fields(&["mean", "std"]), |r| {
            r.best.map_or(Value::Missing, |(b, c)| Value::MeanStd {
                mean: c.summary.mean.expect("a best cell has trials"),
                std: c.summary.std,
                decimals: 2,
                marked: !b.all_converged,
            })
        }),
    ];
    let symbols = data.variables.symbols();
    for (j, (name, (symbol, latex))) in data.variables.columns.iter().zip(&symbols).enumerate() {
        let column = Column::new(symbol, name, Align::Right).latex(&format!("${latex}$"));
        cols.push(col(Main, column, move |r| {
            r.res.get(j).copied().flatten().map_or(Value::Missing, |v| Value::Int(u64::from(v)))
        }));
    }
    cols.extend([
        col(Main, Column::new("Actions", "actions", Align::Right), |r| {
            r.best.map_or(Value::Missing, |(_, c)| Value::Int(u64::from(c.cell.config.actions)))
        }),
        col(Main, Column::new("n", "n", Align::Right).latex("$n$"), |r| {
            int(r.best.map_or(0, |(_, c)| c.trials.len()))
        }),
        col(Main, Column::new("Successes", "successes", Align::Right), |r| {
            int(r.best.map_or(0, |(_, c)| c.successes))
        }),
    ]);
    if reference {
        cols.extend(paper_columns(data, &symbols));
    }
    if data.plan.raced {
        cols.push(col(Main, Column::new("Contenders", "contenders", Align::Right), |r| {
            r.e.contenders(r.alg).map_or(Value::Missing, int)
        }));
        if reference {
            // Empty without a reference configuration, or outside a race.
            cols.push(col(
                Main,
                Column::new("Paper config tied", "reference_config_tied", Align::Left),
                |r| {
                    let tied = reference_cell(r.e, r.alg).and_then(|i| r.e.cells[i].cell.contender);
                    tied.map_or(Value::Missing, |t| text(&t.to_string()))
                },
            ));
        }
    }
    cols
}

/// The paper's value, its configuration and ours less the paper's.
fn paper_columns(data: &ReportData, symbols: &[(String, String)]) -> Vec<Col> {
    use Part::Main;
    let names = &data.variables.columns;
    let title = symbols.iter().map(|s| s.0.as_str()).collect::<Vec<_>>().join(", ");
    let latex = symbols.iter().map(|s| s.1.as_str()).collect::<Vec<_>>().join(", ");
    let fields: Vec<String> =
        names.iter().map(|n| format!("paper_{n}")).chain(["paper_actions".to_string()]).collect();
    let fields: Vec<&str> = fields.iter().map(String::as_str).collect();
    let config = Column::new(&format!("Paper config ({title}, actions)"), fields[0], Align::Left)
        .latex(&format!("Paper config (${latex}$, actions)"))
        .fields(&fields);
    vec![
        col(
            Main,
            Column::new("Paper", "paper_mean", Align::Right).fields(&["paper_mean", "paper_std"]),
            |r| {
                r.r.map_or(Value::Missing, |p| Value::MeanStd {
                    mean: p.mean,
                    std: Some(p.std),
                    decimals: 2,
                    marked: false,
                })
            },
        ),
        col(Main, config, |r| r.r.map_or(Value::Missing, |_| Value::List(r.paper_config.clone()))),
        col(Main, Column::new("Δ mean", "diff_mean", Align::Right).latex("$\\Delta$ mean"), |r| {
            match (r.r, r.best.and_then(|(_, c)| c.summary.mean)) {
                (Some(p), Some(m)) => Value::Num { value: m - p.mean, decimals: 2, signed: true },
                _ => Value::Missing,
            }
        }),
    ]
}

/// The columns of one cell's estimate, CSV names after `prefix`: its bootstrap interval, its
/// fresh-seed estimate (with `fresh`), censoring, and (with `reference`) its ratio to the paper
/// and the equivalence tests. The row is judged on the fresh-seed estimate where it has one.
fn estimate_columns(prefix: &str, which: Which, part: Part, fresh: bool, reference: bool) -> Vec<Col> {
    let name = |s: &str| format!("{prefix}{s}");
    let pair = |title: &str, lo: &str, hi: &str| {
        Column::new(title, &name(lo), Align::Right).fields(&[name(lo).as_str(), name(hi).as_str()])
    };
    let mut cols = vec![col(part, pair("95% CI", "ci_lo", "ci_hi"), move |r| {
        r.cell(which).map_or(Value::Missing, |c| range(c.summary.ci_lo, c.summary.ci_hi, 2))
    })];
    if fresh {
        fn fresh_of<'c>(c: &'c CellData) -> Option<&'c qsweep_pipeline::analysis::Summary> {
            c.fresh_summary.as_ref()
        }
        cols.extend([
            col(part, pair("Fresh", "fresh_mean", "fresh_std"), move |r| {
                r.cell(which).and_then(fresh_of).map_or(Value::Missing, |s| Value::MeanStd {
                    mean: s.mean.expect("fresh trials are present"),
                    std: s.std,
                    decimals: 2,
                    marked: false,
                })
            }),
            col(part, Column::new("Fresh n", &name("fresh_n"), Align::Right), move |r| {
                int(r.cell(which).filter(|c| c.fresh_summary.is_some()).map_or(0, |c| c.fresh.len()))
            }),
            col(part, pair("Fresh 95% CI", "fresh_ci_lo", "fresh_ci_hi"), move |r| {
                r.cell(which).and_then(fresh_of).map_or(Value::Missing, |s| range(s.ci_lo, s.ci_hi, 2))
            }),
        ]);
    }
    cols.extend([
        col(part, Column::new("Censored", &name("censored"), Align::Right), move |r| {
            num(r.cell(which).and_then(|c| c.estimate().censored_fraction()), 2)
        }),
        col(part, Column::new("KM median", &name("km_median"), Align::Right), move |r| {
            num(r.cell(which).and_then(|c| km_median(&c.estimate())), 1)
        }),
    ]);
    if reference {
        cols.extend(ratio_columns(prefix, which, part));
    }
    cols
}

/// An estimate's ratio to the paper's mean with its interval, and the equivalence test at each
/// assumed number of paper runs; missing without an estimate or a positive published mean.
fn ratio_columns(prefix: &str, which: Which, part: Part) -> Vec<Col> {
    let name = |s: &str| format!("{prefix}{s}");
    /// An estimate against its published value, where both are there.
    struct Against {
        /// The estimate's mean, std and n.
        ours: (f64, Option<f64>, usize),
        /// Its 95 % interval ÷ the published mean.
        ci: Value,
        /// The published mean and std.
        paper: (f64, f64),
    }
    fn against(r: &RowCtx, which: Which) -> Option<Against> {
        let est = r.cell(which)?.estimate();
        let p = r.r.filter(|p| p.mean > 0.0)?;
        let s = est.summary;
        let mean = s.mean?;
        let ci = match (s.ci_lo, s.ci_hi) {
            (Some(lo), Some(hi)) => Value::Range { lo: lo / p.mean, hi: hi / p.mean, decimals: 3 },
            _ => Value::Missing,
        };
        Some(Against { ours: (mean, s.std, est.n()), ci, paper: (p.mean, p.std) })
    }
    let mut cols = vec![
        col(part, Column::new("Ours/paper", &name("ratio"), Align::Right), move |r| {
            num(against(r, which).map(|a| a.ours.0 / a.paper.0), 3)
        }),
        col(
            part,
            Column::new("Ours/paper 95% CI", &name("ratio_lo"), Align::Right)
                .fields(&[name("ratio_lo").as_str(), name("ratio_hi").as_str()]),
            move |r| against(r, which).map_or(Value::Missing, |a| a.ci),
        ),
    ];
    for (k, n) in PAPER_N.into_iter().enumerate() {
        let tost = move |r: &RowCtx<'_, '_>| {
            let Against { ours: (m, s, n), paper: (pm, ps), .. } = against(r, which)?;
            against_paper(m, s, n, pm, ps)[k]
        };
        cols.push(col(
            part,
            Column::new(&format!("TOST p (n={n})"), &name(&format!("tost_p_n{n}")), Align::Right),
            move |r| num(tost(r).map(|t| t.p), 4),
        ));
        cols.push(col(
            part,
            Column::new(&format!("Equivalent (n={n})"), &name(&format!("equivalent_n{n}")), Align::Left),
            move |r| tost(r).map_or(Value::Missing, |t| yes_no(t.equivalent)),
        ));
    }
    cols
}

/// Ours at the paper's configuration: its mean, n and successes, then the same estimate columns
/// as the best cell's. The pages leave its fresh-seed and survival columns and its TOST p-values
/// to the CSV (it has fresh-seed trials only where it is also the best cell, whose columns show
/// them), so that the table fits a page's width.
fn paper_cell_columns(fresh: bool) -> Vec<Col> {
    use Part::PaperConfig;
    let mut cols = vec![
        col(
            PaperConfig,
            Column::new("At paper config", "paper_cell_mean", Align::Right)
                .fields(&["paper_cell_mean", "paper_cell_std"]),
            |r| match r.at.and_then(|c| c.summary.mean.map(|m| (m, c.summary.std))) {
                Some((mean, std)) => Value::MeanStd { mean, std, decimals: 2, marked: false },
                None => Value::Missing,
            },
        ),
        col(PaperConfig, Column::new("n", "paper_cell_n", Align::Right).latex("$n$"), |r| {
            int(r.at.map_or(0, |c| c.trials.len()))
        }),
        col(PaperConfig, Column::new("Successes", "paper_cell_successes", Align::Right), |r| {
            int(r.at.map_or(0, |c| c.successes))
        }),
    ];
    for mut c in estimate_columns("paper_cell_", Which::PaperCell, PaperConfig, fresh, true) {
        let key = &c.column.csv[0];
        c.pages = !key.starts_with("paper_cell_fresh")
            && !key.starts_with("paper_cell_tost_p")
            && key != "paper_cell_km_median";
        cols.push(c);
    }
    cols
}

/// The verdicts of the best cell and of the paper's cell and each row's cause; the old rule's
/// columns and the within-2× p-values are kept in the CSV for comparison (the pages show the
/// verdicts that decide).
fn cause_columns() -> Vec<Col> {
    fn judged(f: impl Fn(&Judged) -> Value + 'static) -> impl Fn(&RowCtx<'_, '_>) -> Value {
        move |r| r.judged.as_ref().map_or(Value::Missing, &f)
    }
    let csv_only = |mut c: Col| {
        c.pages = false;
        c
    };
    let c = |title: &str, csv: &str, align: Align, f: fn(&Judged) -> Value| {
        col(Part::Cause, Column::new(title, csv, align), judged(f))
    };
    use Align::{Left, Right};
    vec![
        csv_only(c("Within 2 SE (best)", "verdict_2se", Left, |j| text(j.best_2se.label()))),
        csv_only(c("Within 2 SE (paper config)", "paper_cell_verdict_2se", Left, |j| {
            j.at_2se.map_or(Value::Missing, |v| text(v.label()))
        })),
        csv_only(c("Cause (old rule)", "cause_2se", Left, |j| {
            text(cause_2se(j.best_2se, j.in_pair, j.at_2se))
        })),
        c("Contradictory pair", "contradictory_pair", Left, |j| yes_no(j.j.in_pair)),
        c("Paper inconsistent", "paper_inconsistent", Left, |j| yes_no(j.j.designated)),
        csv_only(c("TOST 2× p", "tost2x_p_n10", Right, |j| num(j.j.best.tost2x_p, 4))),
        csv_only(c("TOST 2× p (paper config)", "paper_cell_tost2x_p_n10", Right, |j| {
            num(j.j.paper_cell.and_then(|a| a.tost2x_p), 4)
        })),
        c("Verdict (best)", "verdict", Left, |j| text(j.j.best.verdict.label())),
        c("Verdict (paper config)", "paper_cell_verdict", Left, |j| {
            j.j.paper_cell.map_or(Value::Missing, |a| text(a.verdict.label()))
        }),
        c("Cause", "cause", Left, |j| text(j.j.cause.label())),
        c("Std ratio", "std_ratio", Right, |j| num(j.spread.map(|s| s.ratio), 3)),
        csv_only(col(
            Part::Cause,
            Column::new("Std ratio 95% CI", "std_ratio_lo", Right).fields(&["std_ratio_lo", "std_ratio_hi"]),
            judged(|j| j.spread.map_or(Value::Missing, |s| Value::Range { lo: s.lo, hi: s.hi, decimals: 3 })),
        )),
        c("Spread differs", "spread_differs", Left, |j| {
            j.spread.map_or(Value::Missing, |s| yes_no(s.differs()))
        }),
    ]
}
