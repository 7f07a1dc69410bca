//! The paper's conclusions as tests: each claim is a statistic over a variant's cells with a null
//! value and a direction, and a percentile-bootstrap interval that redraws every cell's trials.
//! The definitions ([`CLAIMS`]) were fixed in `docs/preregistration.md` before any was computed;
//! a claim **holds** when its interval lies entirely on the claimed side of the null, is
//! **reversed** when it lies entirely on the other side, and is **undecided** otherwise.

use super::best::{best_cell, Candidate};
use super::rank::{average_ranks, pearson, spearman};
use super::summary::{interval_95, resample_mean};
use qsweep_engine::env::SystemKind;
use qsweep_engine::rng::{below_from, TrialRng};
use qsweep_engine::Algorithm;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Bootstrap resamples per claim.
pub const CLAIM_RESAMPLES: usize = 1000;

/// The verdict rule, as stated in captions.
pub const CLAIM_RULE: &str = "Each claim is a statistic over the variant's cells (definitions in \
docs/preregistration.md) with a 95 % percentile-bootstrap interval (1,000 resamples, each redrawing \
every cell's trials with replacement). holds: the interval lies entirely on the claimed side of the \
null value; reversed: entirely on the other side; undecided: otherwise; — : not computable here.";

/// Which side of the null a claim asserts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The statistic is claimed to exceed the null.
    Above,
    /// The statistic is claimed to lie below the null.
    Below,
}

/// One claim of the paper, as declared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Claim {
    /// Identifier (a `conclusions.csv` key).
    pub id: &'static str,
    /// The paper's words, shortened, and where they are.
    pub text: &'static str,
    /// What the statistic measures.
    pub statistic: &'static str,
    /// The null value.
    pub null: f64,
    /// The claimed side.
    pub side: Side,
    /// Whether the null itself is on the claimed side (a threshold to reach, like "at least 95 %
    /// converged"), rather than the boundary of a strict inequality.
    pub at_null_holds: bool,
}

/// The ten claims, in the order of `docs/preregistration.md`.
pub const CLAIMS: [Claim; 10] = [
    Claim {
        id: "qlambda-beats-q0",
        text: "Q(λ) outperforms Q(0) in all environments (Conclusion)",
        statistic: "smallest over systems of P(Q(λ) cell mean < Q(0) cell mean), paired cells",
        null: 0.5,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "traces-delayed-reward",
        text: "traces overcome Mountain Car's delayed reward (Conclusion)",
        statistic: "Mountain Car: success rate of Q(λ) trials − of Q(0) trials",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "compact-best",
        text: "compact configurations (2–4 bins/sets, 2–4 actions) are often optimal (§V)",
        statistic: "fraction of the best cells that are compact − fraction of all cells",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "excessive-hinders",
        text: "excessive discretisation or fuzzy granularity hinders learning (Conclusion)",
        statistic: "mean over heatmaps of Spearman ρ(state count, cell mean)",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "qlambda-robust",
        text: "Q(λ) is more robust to representation complexity (§V)",
        statistic: "mean over experiments of ρ(Q(0)) − ρ(Q(λ))",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "fuzzy-qlambda-fastest",
        text: "fuzzy Q(λ) converges fastest (Abstract, §V)",
        statistic: "mean over systems of ln(best of the other three ÷ best fuzzy Q(λ))",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "fuzzy-benefit-low-granularity",
        text: "the fuzzy benefit is largest at low to moderate granularity (Discussion)",
        statistic: "mean over systems and algorithms of ρ(state count, ln(crisp ÷ fuzzy)), Exp. 1 vs 3",
        null: 0.0,
        side: Side::Below,
        at_null_holds: false,
    },
    Claim {
        id: "mountain-car-gap-narrowed",
        text: "in Mountain Car the gap between methods narrowed (Discussion)",
        statistic: "mean |ln(best Q(0) ÷ best Q(λ))|: Mountain Car − the other systems",
        null: 0.0,
        side: Side::Below,
        at_null_holds: false,
    },
    Claim {
        id: "qlambda-richer-fuzzy",
        text: "Q(λ) favours slightly richer fuzzy representations than Q(0) (§V)",
        statistic: "mean over fuzzy experiments of ln(states of best Q(λ) ÷ of best Q(0))",
        null: 0.0,
        side: Side::Above,
        at_null_holds: false,
    },
    Claim {
        id: "cart-pole-converged",
        text: "in Cart-Pole all algorithms ultimately converged (§V)",
        statistic: "fraction of Cart-Pole trials that reached the goal",
        null: 0.95,
        side: Side::Above,
        at_null_holds: true,
    },
];

/// What a claim needs of one cell.
#[derive(Debug, Clone, PartialEq)]
pub struct ClaimCell {
    /// The system.
    pub system: SystemKind,
    /// Index of the cell's experiment in the variant (cells of one heatmap share it and the
    /// algorithm).
    pub experiment: usize,
    /// The experiment's id as written ("1" … "4" in the paper's pipelines).
    pub experiment_id: String,
    /// Fuzzy sets (true) or crisp bins.
    pub fuzzy: bool,
    /// The algorithm.
    pub algorithm: Algorithm,
    /// Bins or fuzzy sets per state variable.
    pub resolution: Vec<u32>,
    /// Number of actions.
    pub actions: u32,
    /// Episodes each present trial counts (Table III's rule).
    pub counted: Vec<f64>,
    /// Whether each present trial reached the goal.
    pub converged: Vec<bool>,
    /// Seed of this cell's resamples.
    pub seed: u64,
}

impl ClaimCell {
    fn states(&self) -> f64 {
        self.resolution.iter().map(|&r| f64::from(r)).product()
    }

    fn compact(&self) -> bool {
        self.resolution.iter().all(|&r| r <= 4) && self.actions <= 4
    }
}

/// How one claim came out in one variant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClaimResult {
    /// The claim.
    pub claim: &'static Claim,
    /// The statistic on the cells as they are (`None`: not computable, e.g. a system missing).
    pub estimate: Option<f64>,
    /// 95 % bootstrap interval (`None` with the estimate, or when most resamples are undefined).
    pub interval: Option<(f64, f64)>,
    /// The verdict.
    pub verdict: ClaimVerdict,
}

/// A claim's verdict in one variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClaimVerdict {
    /// The interval lies on the claimed side of the null.
    Holds,
    /// The interval lies on the other side.
    Reversed,
    /// The interval contains the null.
    Undecided,
    /// Not computable from these cells.
    Missing,
}

impl ClaimVerdict {
    /// The word the reports print.
    pub fn word(self) -> &'static str {
        match self {
            Self::Holds => "holds",
            Self::Reversed => "reversed",
            Self::Undecided => "undecided",
            Self::Missing => "—",
        }
    }
}

/// One resample's view of a cell: its mean and its successes out of n.
#[derive(Debug, Clone, Copy)]
struct View {
    mean: Option<f64>,
    successes: usize,
    n: usize,
}

/// Every claim of [`CLAIMS`] over `cells`.
pub fn evaluate(cells: &[ClaimCell]) -> Vec<ClaimResult> {
    let point: Vec<View> = cells
        .iter()
        .map(|c| View {
            mean: (!c.counted.is_empty()).then(|| c.counted.iter().sum::<f64>() / c.counted.len() as f64),
            successes: c.converged.iter().filter(|&&b| b).count(),
            n: c.counted.len(),
        })
        .collect();
    let g = Groups::of(cells);
    let estimates = statistics(cells, &g, &point);
    // Each cell's resamples come from its own stream, consumed in order, so drawing them a block
    // at a time gives the same resamples on any number of threads, with one block in memory
    // instead of every cell's thousand.
    let mut streams: Vec<TrialRng> = cells.iter().map(|c| TrialRng::new(c.seed)).collect();
    let mut reps: Vec<[Option<f64>; CLAIMS.len()]> = Vec::with_capacity(CLAIM_RESAMPLES);
    for start in (0..CLAIM_RESAMPLES).step_by(RESAMPLE_BLOCK) {
        let len = RESAMPLE_BLOCK.min(CLAIM_RESAMPLES - start);
        let draws: Vec<Vec<View>> =
            cells.par_iter().zip(streams.par_iter_mut()).map(|(c, rng)| resample(c, rng, len)).collect();
        // All claims of one resample at once: its view, best cells and correlations are shared.
        let block: Vec<[Option<f64>; CLAIMS.len()]> = (0..len)
            .into_par_iter()
            .map(|r| {
                let view: Vec<View> = draws.iter().map(|d| d[r]).collect();
                statistics(cells, &g, &view)
            })
            .collect();
        reps.extend(block);
    }
    CLAIMS
        .iter()
        .enumerate()
        .map(|(k, claim)| {
            let estimate = estimates[k];
            let mut values: Vec<f64> = reps.iter().filter_map(|r| r[k]).collect();
            let interval =
                (estimate.is_some() && values.len() * 2 > CLAIM_RESAMPLES).then(|| interval_95(&mut values));
            result(claim, estimate, interval)
        })
        .collect()
}

/// A claim's result from its estimate and interval (the verdict follows from the interval).
pub fn result(claim: &'static Claim, estimate: Option<f64>, interval: Option<(f64, f64)>) -> ClaimResult {
    ClaimResult { claim, estimate, interval, verdict: verdict(claim, interval) }
}

/// Resamples drawn at once per cell ([`evaluate`]).
const RESAMPLE_BLOCK: usize = 100;

/// A cell's next `len` resamples from its stream: each redraws its trials with replacement.
fn resample(c: &ClaimCell, rng: &mut TrialRng, len: usize) -> Vec<View> {
    let n = c.counted.len();
    if n == 0 {
        return vec![View { mean: None, successes: 0, n: 0 }; len];
    }
    let mut draws = vec![0u64; n * len];
    rng.fill_u64(&mut draws);
    draws
        .chunks_exact(n)
        .map(|r| View {
            mean: Some(resample_mean(&c.counted, r)),
            successes: r.iter().filter(|&&x| c.converged[below_from(x, n)]).count(),
            n,
        })
        .collect()
}

/// The verdict rule ([`CLAIM_RULE`]) for one interval.
fn verdict(claim: &Claim, interval: Option<(f64, f64)>) -> ClaimVerdict {
    let Some((lo, hi)) = interval else { return ClaimVerdict::Missing };
    let above = if claim.at_null_holds { lo >= claim.null } else { lo > claim.null };
    let below = hi < claim.null;
    match (claim.side, above, below) {
        (Side::Above, true, _) | (Side::Below, _, true) => ClaimVerdict::Holds,
        (Side::Above, _, true) | (Side::Below, true, _) => ClaimVerdict::Reversed,
        _ => ClaimVerdict::Undecided,
    }
}

/// A heatmap: its cells and their state counts.
struct Heatmap {
    system: SystemKind,
    fuzzy: bool,
    experiment: usize,
    algorithm: Algorithm,
    cells: Vec<usize>,
    states: Vec<f64>,
    /// Ranks of `states` (fixed: only the means are resampled).
    state_ranks: Vec<f64>,
}

/// Two paired cells and their state count.
type StatePair = (usize, usize, f64);

/// Index structures shared by every resample.
struct Groups {
    /// One per (experiment, algorithm), in that order.
    heatmaps: Vec<Heatmap>,
    /// Per system (in order), pairs (Q(0) cell, Q(λ) cell) of one experiment and configuration.
    algorithm_pairs: Vec<Vec<(usize, usize)>>,
    /// Per (system, algorithm), pairs (crisp Exp. 1 cell, fuzzy Exp. 3 cell) of one configuration,
    /// with the pair's state count.
    repr_pairs: Vec<Vec<StatePair>>,
    /// Cart-Pole cells; Mountain Car cells of Q(0) and of Q(λ).
    cart_pole: Vec<usize>,
    mountain_car: [Vec<usize>; 2],
    /// Cells with a compact configuration.
    compact: Vec<bool>,
    /// The experiments and the systems present, in order.
    experiments: Vec<usize>,
    systems: Vec<SystemKind>,
}

impl Groups {
    fn of(cells: &[ClaimCell]) -> Self {
        let mut by_heatmap: BTreeMap<(usize, Algorithm), Vec<usize>> = BTreeMap::new();
        type Config = (Vec<u32>, u32);
        let mut by_config: BTreeMap<(usize, Config, Algorithm), usize> = BTreeMap::new();
        let mut by_exp_id: BTreeMap<(SystemKind, String, Config, Algorithm), usize> = BTreeMap::new();
        for (i, c) in cells.iter().enumerate() {
            by_heatmap.entry((c.experiment, c.algorithm)).or_default().push(i);
            let cfg = (c.resolution.clone(), c.actions);
            by_config.insert((c.experiment, cfg.clone(), c.algorithm), i);
            by_exp_id.insert((c.system, c.experiment_id.clone(), cfg, c.algorithm), i);
        }
        let heatmaps: Vec<Heatmap> = by_heatmap
            .into_iter()
            .map(|((experiment, algorithm), idx)| Heatmap {
                system: cells[idx[0]].system,
                fuzzy: cells[idx[0]].fuzzy,
                experiment,
                algorithm,
                states: idx.iter().map(|&i| cells[i].states()).collect(),
                state_ranks: average_ranks(&idx.iter().map(|&i| cells[i].states()).collect::<Vec<_>>()),
                cells: idx,
            })
            .collect();
        let mut algorithm_pairs: BTreeMap<SystemKind, Vec<(usize, usize)>> = BTreeMap::new();
        for ((e, cfg, a), &i) in &by_config {
            if *a == Algorithm::Q0 {
                if let Some(&j) = by_config.get(&(*e, cfg.clone(), Algorithm::QLambda)) {
                    algorithm_pairs.entry(cells[i].system).or_default().push((i, j));
                }
            }
        }
        let mut repr_pairs: BTreeMap<(SystemKind, Algorithm), Vec<StatePair>> = BTreeMap::new();
        for ((s, id, cfg, a), &i) in &by_exp_id {
            if id == "1" && !cells[i].fuzzy {
                if let Some(&j) = by_exp_id.get(&(*s, "3".to_string(), cfg.clone(), *a)) {
                    if cells[j].fuzzy {
                        repr_pairs.entry((*s, *a)).or_default().push((i, j, cells[i].states()));
                    }
                }
            }
        }
        // Heatmaps are in (experiment, algorithm) order, so one experiment's are adjacent.
        let mut experiments: Vec<usize> = heatmaps.iter().map(|h| h.experiment).collect();
        experiments.dedup();
        let mut systems: Vec<SystemKind> = heatmaps.iter().map(|h| h.system).collect();
        systems.sort();
        systems.dedup();
        let of = |pred: &dyn Fn(&ClaimCell) -> bool| (0..cells.len()).filter(|&i| pred(&cells[i])).collect();
        Self {
            heatmaps,
            algorithm_pairs: algorithm_pairs.into_values().collect(),
            repr_pairs: repr_pairs.into_values().collect(),
            cart_pole: of(&|c| c.system == SystemKind::CartPole),
            mountain_car: [
                of(&|c| c.system == SystemKind::MountainCar && c.algorithm == Algorithm::Q0),
                of(&|c| c.system == SystemKind::MountainCar && c.algorithm == Algorithm::QLambda),
            ],
            compact: cells.iter().map(ClaimCell::compact).collect(),
            experiments,
            systems,
        }
    }
}

fn average(v: impl IntoIterator<Item = f64>) -> Option<f64> {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v {
        s += x;
        n += 1;
    }
    (n > 0).then(|| s / n as f64)
}

/// Fraction of the trials of `idx` that reached the goal.
fn success_rate(idx: &[usize], view: &[View]) -> Option<f64> {
    let (ok, n) = idx.iter().fold((0, 0), |(ok, n), &i| (ok + view[i].successes, n + view[i].n));
    (n > 0).then(|| ok as f64 / n as f64)
}

/// Every claim's statistic under `view`, in [`CLAIMS`] order.
fn statistics(cells: &[ClaimCell], g: &Groups, view: &[View]) -> [Option<f64>; CLAIMS.len()] {
    let mean = |i: usize| view[i].mean;
    // Per heatmap: its best cell (Table III's rule) and ρ(state count, mean).
    let best: Vec<Option<usize>> = g
        .heatmaps
        .iter()
        .map(|h| {
            let cands = h.cells.iter().map(|&i| Candidate {
                index: i,
                n: view[i].n,
                successes: view[i].successes,
                mean: view[i].mean,
            });
            best_cell(cands).map(|b| b.cell)
        })
        .collect();
    let rho: Vec<Option<f64>> = g
        .heatmaps
        .iter()
        .map(|h| {
            let y: Vec<f64> = h.cells.iter().filter_map(|&i| mean(i)).collect();
            if y.len() == h.cells.len() {
                pearson(&h.state_ranks, &average_ranks(&y))
            } else {
                let (x, y): (Vec<f64>, Vec<f64>) =
                    h.cells.iter().zip(&h.states).filter_map(|(&i, &s)| mean(i).map(|m| (s, m))).collect();
                spearman(&x, &y)
            }
        })
        .collect();
    // Heatmap index by (experiment, algorithm).
    let find = |e: usize, a: Algorithm| g.heatmaps.iter().position(|h| h.experiment == e && h.algorithm == a);
    let experiments = &g.experiments;
    let best_mean = |k: usize| best[k].and_then(mean);
    let gap = |e: usize| {
        let a = best_mean(find(e, Algorithm::Q0)?)?;
        let b = best_mean(find(e, Algorithm::QLambda)?)?;
        (a > 0.0 && b > 0.0).then(|| (a / b).ln().abs())
    };
    let system_of = |e: usize| g.heatmaps.iter().find(|h| h.experiment == e).map(|h| (h.system, h.fuzzy));

    let qlambda_beats_q0 = if g.algorithm_pairs.len() < SystemKind::ALL.len() {
        None
    } else {
        g.algorithm_pairs
            .iter()
            .filter_map(|pairs| {
                average(pairs.iter().filter_map(|&(q0, ql)| {
                    let (a, b) = (mean(q0)?, mean(ql)?);
                    Some(if b < a {
                        1.0
                    } else if b == a {
                        0.5
                    } else {
                        0.0
                    })
                }))
            })
            .min_by(f64::total_cmp)
    };
    let traces =
        (|| Some(success_rate(&g.mountain_car[1], view)? - success_rate(&g.mountain_car[0], view)?))();
    let compact_best = (|| {
        let all =
            average((0..cells.len()).filter(|&i| view[i].n > 0).map(|i| f64::from(u8::from(g.compact[i]))))?;
        let chosen = average(best.iter().flatten().map(|&i| f64::from(u8::from(g.compact[i]))))?;
        Some(chosen - all)
    })();
    let excessive = average(rho.iter().flatten().copied());
    let robust = average(
        experiments
            .iter()
            .filter_map(|&e| Some(rho[find(e, Algorithm::Q0)?]? - rho[find(e, Algorithm::QLambda)?]?)),
    );
    let fastest = average(g.systems.iter().filter_map(|&s| {
        // The best mean of each (representation, algorithm) over the system's experiments.
        let combo = |fuzzy: bool, a: Algorithm| {
            g.heatmaps
                .iter()
                .enumerate()
                .filter(|(_, h)| h.system == s && h.fuzzy == fuzzy && h.algorithm == a)
                .filter_map(|(k, _)| best_mean(k))
                .min_by(f64::total_cmp)
        };
        let fl = combo(true, Algorithm::QLambda)?;
        let others =
            [combo(false, Algorithm::Q0)?, combo(false, Algorithm::QLambda)?, combo(true, Algorithm::Q0)?];
        let other = others.into_iter().min_by(f64::total_cmp)?;
        (fl > 0.0 && other > 0.0).then(|| (other / fl).ln())
    }));
    let fuzzy_benefit = average(g.repr_pairs.iter().filter_map(|pairs| {
        let (x, y): (Vec<f64>, Vec<f64>) = pairs
            .iter()
            .filter_map(|&(c, f, states)| {
                let (a, b) = (mean(c)?, mean(f)?);
                (a > 0.0 && b > 0.0).then(|| (states, (a / b).ln()))
            })
            .unzip();
        spearman(&x, &y)
    }));
    let mc = |want: bool| {
        average(
            experiments
                .iter()
                .filter(|&&e| system_of(e).is_some_and(|s| (s.0 == SystemKind::MountainCar) == want))
                .filter_map(|&e| gap(e)),
        )
    };
    let narrowed = (|| Some(mc(true)? - mc(false)?))();
    let richer =
        average(experiments.iter().filter(|&&e| system_of(e).is_some_and(|s| s.1)).filter_map(|&e| {
            let a = cells[best[find(e, Algorithm::Q0)?]?].states();
            let b = cells[best[find(e, Algorithm::QLambda)?]?].states();
            Some((b / a).ln())
        }));
    let converged = success_rate(&g.cart_pole, view);
    [
        qlambda_beats_q0,
        traces,
        compact_best,
        excessive,
        robust,
        fastest,
        fuzzy_benefit,
        narrowed,
        richer,
        converged,
    ]
}

#[cfg(test)]
mod tests;
