//! How well one variant's Table III reproduces the pipeline's `reference:` values: each row judged
//! ([`RowFit`]: the verdict scale at every assumed paper n, the old rule, the cause; rules defined
//! once in [`crate::replication::stats::verdict`]), the per-variant tally ([`Fit`]) and the order of the
//! comparison table ([`FIT_ORDER`], the pre-registered fit measure on the old rule).

use crate::derive::report_data::ReportData;
use crate::derive::table::{Align, Column, Row, Table, Value};
use crate::replication::compare::info::VariantInfo;
pub use crate::replication::judgement::{judge_row, moments, RowJudgement};
use crate::replication::published::{contradictions, reference_cell};
use crate::replication::stats::equivalence::{against_paper, Moments, Tost, EQUIVALENCE_RULE};
pub use crate::replication::stats::verdict::{
    cause, cause_2se, fit_verdict, judge, spread, Cause, FitVerdict, Judged, Spread, Verdict, HEADLINE_N,
    PAPER_N_SET, REFERENCE_N, SCALE_RULE, VERDICT_RULE,
};
use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::Algorithm;

/// How the rows are ordered, as stated in the caption.
pub const FIT_ORDER: &str = "Rows are ordered by fit (the measure pre-registered in \
docs/preregistration.md, kept as declared): most rows within 2 SE first, then most rows within 2×, then most matching \
best configurations, then the geometric mean of ours/reference closest to 1 (smallest |ln|), then \
pipeline order.";

/// How well one variant's Table III matches the reference values.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Fit {
    /// Table III rows with a reference value and a best cell.
    pub rows: usize,
    /// Of those, rows within two standard errors (the old rule, [`VERDICT_RULE`]; the fit
    /// measure's first key).
    pub within_2se: usize,
    /// Rows not within 2 SE but whose ratio is within a factor 2 (the old rule).
    pub ratio_within_2x: usize,
    /// Rows that replicate on the scale (`equivalent` or `within-2x`) at each n of
    /// [`PAPER_N_SET`].
    pub replicating_by_n: [usize; 3],
    /// Rows per verdict of the scale at the headline n, in [`Verdict::ALL`]'s order.
    pub scale: [usize; 5],
    /// Rows whose best cell has the reference's resolution and action count.
    pub config_match: usize,
    /// Experiments whose algorithms rank by mean as in the reference.
    pub order_match: usize,
    /// Experiments with two or more algorithms, every one with a reference and a best cell.
    pub order_experiments: usize,
    /// Geometric mean of ours / reference over the rows (`None` without rows).
    pub geo_mean: Option<f64>,
    /// Rows equivalent to their reference at the pre-registered margin, for each assumed number
    /// of paper runs in [`crate::replication::stats::equivalence::PAPER_N`] (10, 100).
    pub equivalent: [usize; 2],
    /// Rows judged on a fresh-seed estimate, and over those the geometric mean of fresh ÷
    /// selection mean (above 1: the grid's choice flattered the row; `None` without such rows).
    pub fresh: (usize, Option<f64>),
}

/// One Table III row scored against its reference: what [`Fit`] tallies, kept per row so a fit can
/// be taken over some rows (an exploratory search's fit rows) and judged on the others.
#[derive(Debug, Clone, PartialEq)]
pub struct RowFit {
    /// The system.
    pub system: SystemKind,
    /// The experiment id.
    pub experiment: String,
    /// The algorithm.
    pub algorithm: Algorithm,
    /// The representation (crisp or fuzzy).
    pub repr: ReprKind,
    /// Our best cell's mean (the fresh-seed estimate where there is one).
    pub mean: f64,
    /// Its std (none for a single trial).
    pub std: Option<f64>,
    /// Its trials.
    pub n: usize,
    /// The reference mean.
    pub ref_mean: f64,
    /// The reference std.
    pub ref_std: f64,
    /// The row's verdict under the old rule ([`fit_verdict`]).
    pub fit_verdict: FitVerdict,
    /// Our best cell has the reference's bins or sets per variable and action count.
    pub config_match: bool,
    /// Algorithms of the row's experiment (the order measure needs all of them).
    pub exp_algorithms: usize,
    /// The equivalence test (TOST) for each assumed number of paper runs (10, 100); `None`
    /// where undecidable.
    pub tost: [Option<Tost>; 2],
    /// Whether `mean`, `std` and `n` are the fresh-seed estimate ([`qsweep_pipeline::fresh`]) rather than
    /// the selection estimate.
    pub fresh: bool,
    /// The selection estimate: the best cell's mean over the grid's seeds that chose it.
    pub selection_mean: f64,
    /// Our cell at the paper's configuration (its fresh-seed estimate where it has one; `None`: no
    /// such cell with trials).
    pub paper_cell: Option<Moments>,
    /// The row judged at each n of [`PAPER_N_SET`].
    pub by_n: [RowJudgement; 3],
    /// The old rule's cause ([`cause_2se`], at n = 10).
    pub cause_2se: &'static str,
    /// Our std against the paper's ([`spread`]).
    pub spread: Option<Spread>,
}

/// A Table III row's identity: system, experiment id, algorithm.
pub type RowKey = (SystemKind, String, Algorithm);

impl RowFit {
    /// The row's identity, the same in every variant.
    pub fn key(&self) -> RowKey {
        (self.system, self.experiment.clone(), self.algorithm)
    }

    /// The row judged at the headline n ([`HEADLINE_N`]).
    pub fn headline(&self) -> &RowJudgement {
        &self.by_n[PAPER_N_SET.len() - 1]
    }

    /// Ours ÷ the paper.
    pub fn ratio(&self) -> f64 {
        self.mean / self.ref_mean
    }
}

/// Every Table III row of `data` that has a reference value and a best cell, in report order.
pub fn rows_of(data: &ReportData) -> Vec<RowFit> {
    let mut out = Vec::new();
    let contradictions = PAPER_N_SET.map(|n| contradictions(data, n));
    for (ei, e) in data.experiments.iter().enumerate() {
        let system = e.exp.system;
        for &alg in &e.exp.algorithms {
            let Some(r) = e.exp.reference.get(&alg) else { continue };
            let Some(c) = e.best_of(alg).map(|b| &e.cells[b.cell]) else { continue };
            // Judged on the fresh-seed estimate where the row has one (the winner's curse).
            let Some(best) = moments(c) else { continue };
            let Some(selection_mean) = c.summary.mean else { continue };
            let Moments { mean, std, n } = best;
            let cfg = &c.cell.config;
            let vars = &data.variables;
            let ours: Vec<u32> = vars
                .resolution(system, &cfg.repr.resolution)
                .into_iter()
                .flatten()
                .chain([cfg.actions])
                .collect();
            let theirs: Vec<u32> = r
                .resolution
                .as_ref()
                .map_or_else(|| vec![None; vars.columns.len()], |res| vars.resolution(system, res))
                .into_iter()
                .flatten()
                .chain(r.actions)
                .collect();
            let paper_cell = reference_cell(e, alg).and_then(|i| moments(&e.cells[i]));
            let row_verdict = fit_verdict(mean, std, n, r.mean, r.std);
            let at_2se = paper_cell.map(|m| fit_verdict(m.mean, m.std, m.n, r.mean, r.std));
            let by_n: [RowJudgement; 3] = std::array::from_fn(|k| {
                judge_row(best, paper_cell, r, &contradictions[k], (ei, alg), PAPER_N_SET[k])
            });
            // The old rule's cause reads the pairs at the headline n (the last of the set).
            let in_pair = by_n[PAPER_N_SET.len() - 1].in_pair;
            out.push(RowFit {
                system,
                experiment: e.exp.id.clone(),
                algorithm: alg,
                repr: e.exp.repr,
                mean,
                std,
                n,
                ref_mean: r.mean,
                ref_std: r.std,
                fit_verdict: row_verdict,
                config_match: ours == theirs,
                exp_algorithms: e.exp.algorithms.len(),
                tost: against_paper(mean, std, n, r.mean, r.std),
                fresh: c.estimate().fresh,
                selection_mean,
                paper_cell,
                by_n,
                cause_2se: cause_2se(row_verdict, in_pair, at_2se),
                spread: spread(std, n, r.std, HEADLINE_N),
            });
        }
    }
    out
}

impl Fit {
    /// Tally some scored rows (in report order). The order measure counts an experiment only when
    /// the rows hold every one of its algorithms.
    pub fn from_rows<'a>(rows: impl IntoIterator<Item = &'a RowFit>) -> Self {
        let rows: Vec<&RowFit> = rows.into_iter().collect();
        let mut f = Self::default();
        let mut logs = Vec::new();
        let mut curse = Vec::new();
        for r in &rows {
            if r.fresh && r.mean > 0.0 && r.selection_mean > 0.0 {
                curse.push((r.mean / r.selection_mean).ln());
            }
            f.rows += 1;
            match r.fit_verdict {
                FitVerdict::Replicates => f.within_2se += 1,
                FitVerdict::Within2x => f.ratio_within_2x += 1,
                FitVerdict::DoesNotReplicate => {}
            }
            for (k, j) in r.by_n.iter().enumerate() {
                f.replicating_by_n[k] += usize::from(j.best.verdict.replicates());
            }
            let v = r.headline().best.verdict;
            f.scale[Verdict::ALL.iter().position(|&a| a == v).expect("every verdict is listed")] += 1;
            f.config_match += usize::from(r.config_match);
            for (k, t) in r.tost.iter().enumerate() {
                f.equivalent[k] += usize::from(t.is_some_and(|t| t.equivalent));
            }
            if r.mean > 0.0 && r.ref_mean > 0.0 {
                logs.push((r.mean / r.ref_mean).ln());
            }
        }
        for group in rows.chunk_by(|a, b| a.system == b.system && a.experiment == b.experiment) {
            if group.len() >= 2 && group.len() == group[0].exp_algorithms {
                f.order_experiments += 1;
                f.order_match +=
                    usize::from(rank(group.iter().map(|r| r.mean)) == rank(group.iter().map(|r| r.ref_mean)));
            }
        }
        let geo =
            |logs: &[f64]| (!logs.is_empty()).then(|| (logs.iter().sum::<f64>() / logs.len() as f64).exp());
        f.geo_mean = geo(&logs);
        f.fresh = (rows.iter().filter(|r| r.fresh).count(), geo(&curse));
        f
    }
}

/// Indices in ascending order of value (stable: ties keep algorithm order).
fn rank(values: impl Iterator<Item = f64>) -> Vec<usize> {
    let v: Vec<f64> = values.collect();
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&i, &j| v[i].total_cmp(&v[j]));
    idx
}

/// Indices of `fits` in [`FIT_ORDER`].
pub fn fit_order(fits: &[Fit]) -> Vec<usize> {
    let off = |f: &Fit| f.geo_mean.map_or(f64::INFINITY, |g| g.ln().abs());
    let mut idx: Vec<usize> = (0..fits.len()).collect();
    idx.sort_by(|&i, &j| {
        let (a, b) = (&fits[i], &fits[j]);
        b.within_2se
            .cmp(&a.within_2se)
            .then(b.ratio_within_2x.cmp(&a.ratio_within_2x))
            .then(b.config_match.cmp(&a.config_match))
            .then(off(a).total_cmp(&off(b)))
    });
    idx
}

/// The comparison table: one row per variant, in [`FIT_ORDER`]. With `fresh` (the pipeline has a
/// `fresh:` block), the fresh-seed columns too, whether or not the cache holds their trials yet,
/// so the file's columns depend on the pipeline alone.
pub fn comparison_table(variants: &[(&VariantInfo, Fit)], fresh: bool) -> Table {
    let mut columns = vec![
        Column::new("Rank", "rank", Align::Right),
        Column::new("Variant", "variant", Align::Left),
        Column::new("Title", "title", Align::Left),
        Column::new("Rows with reference", "rows", Align::Right),
        Column::new("Replicate", "replicating_n10", Align::Right),
        Column::new("Equiv.", "equivalent_n10", Align::Right),
        Column::new("Within 2×", "within_2x_n10", Align::Right),
        Column::new("Wide", "consistent_but_wide_n10", Align::Right),
        Column::new("Differs", "differs_n10", Align::Right),
        Column::new("Repl. n=5", "replicating_n5", Align::Right),
        Column::new("Repl. n=3", "replicating_n3", Align::Right),
        Column::new("≤ 2 SE (old)", "within_2se", Align::Right),
        Column::new("Ratio ≤ 2× (old)", "ratio_within_2x", Align::Right),
        Column::new("Config matches", "config_match", Align::Right),
        Column::new("Order matches", "order_match", Align::Right),
        Column::new("Experiments ordered", "order_experiments", Align::Right),
        Column::new("Geo. mean ours/ref.", "geo_mean_ratio", Align::Right),
        Column::new("Equiv. n=100", "equivalent_n100", Align::Right),
        Column::new("Exploratory", "exploratory", Align::Left),
    ];
    // Only pipelines with fresh seeds have these columns, so other comparisons keep their bytes.
    if fresh {
        columns.push(Column::new("Rows on fresh seeds", "fresh_rows", Align::Right));
        columns.push(Column::new("Geo. mean fresh/selection", "fresh_over_selection", Align::Right));
    }
    let fits: Vec<Fit> = variants.iter().map(|v| v.1).collect();
    // Declared variants first, then the exploratory ones, each in fit order.
    let (declared, exploratory): (Vec<usize>, Vec<usize>) =
        fit_order(&fits).into_iter().partition(|&i| !variants[i].0.exploratory);
    let rows = declared
        .into_iter()
        .chain(exploratory)
        .enumerate()
        .map(|(k, i)| {
            let (v, f) = &variants[i];
            let int = |n: usize| Value::Int(n as u64);
            let ratio = |v: Option<f64>| {
                v.map_or(Value::Missing, |value| Value::Num { value, decimals: 3, signed: false })
            };
            let mut values = vec![
                int(k + 1),
                Value::User(v.id.clone()),
                v.title.clone().map_or(Value::Missing, Value::User),
                int(f.rows),
                int(f.replicating_by_n[2]),
                int(f.scale[0]),
                int(f.scale[1]),
                int(f.scale[2]),
                int(f.scale[3]),
                int(f.replicating_by_n[1]),
                int(f.replicating_by_n[0]),
                int(f.within_2se),
                int(f.ratio_within_2x),
                int(f.config_match),
                int(f.order_match),
                int(f.order_experiments),
                ratio(f.geo_mean),
                int(f.equivalent[1]),
                Value::Text(if v.exploratory { "yes" } else { "no" }.into()),
            ];
            if fresh {
                values.extend([int(f.fresh.0), ratio(f.fresh.1)]);
            }
            Row { values, highlight: k == 0 }
        })
        .collect();
    let caption = format!(
        "How well each variant reproduces the reference values (one row per variant; counts over its \
         Table III rows that have a reference value and a best cell). {SCALE_RULE} Replicate: equivalent \
         or within-2x (Equiv., Within 2×), with the paper's n taken as 10 (Repl. n=5, n=3: as 5 or 3); \
         Wide: consistent but wide. ≤ 2 SE and Ratio ≤ 2× (old): the old rule, which ranks the variants. {VERDICT_RULE} Config matches: the \
         best cell has the reference's bins or sets per variable and action count. Order matches: of the \
         experiments where every algorithm has a reference, those whose algorithms (Q(0), Q(λ)) rank by \
         mean as in the reference. Geo. mean: exp of the mean of ln(ours/reference) over the rows. {FIT_ORDER} \
         {EQUIVALENCE_RULE} Exploratory variants (suggested by the data, not declared before they ran) \
         are ranked after the declared ones."
    );
    let caption = if fresh {
        format!(
            "{caption} Where a row's best cell was re-run on fresh seeds, every verdict above uses that \
             fresh estimate; Geo. mean fresh/selection: exp of the mean of ln(fresh ÷ selection mean) over \
             those rows (above 1: the winner's curse)."
        )
    } else {
        caption
    };
    Table { title: "Variants".into(), caption, columns, rows }
}
