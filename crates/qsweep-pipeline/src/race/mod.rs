//! Races: seeds go, round by round, only to the cells of a heatmap that can still be its best.
//!
//! A heatmap is one experiment × algorithm of one variant (one Table III row). Round 0 is the
//! pipeline's `seeds`. After each round the cells still in the race (the *contenders*) are tested
//! against the current best contender, chosen by Table III's rule ([`crate::analysis::best_cell`]):
//! a cell whose mean is higher than the best's by a one-sided Welch t-test, with Holm's correction
//! over the contenders tested in that round at α = 1 − `confidence` ([`welch`]), leaves the race.
//! Every remaining contender gets `batch` more seeds, numbered on from the largest first-round
//! seed, until one contender remains or every contender has `max_seeds`.
//!
//! The measure is the one Table III averages: episodes to the goal, a trial that never reached it
//! counted at the episode cap ([`crate::analysis::episodes_counted`]). For that capped
//! measure a censored trial is an exact value, not missing data; and since its true episode count
//! is larger still, censoring can only make a cell look better than it is, so a cell is never
//! dropped because of its own failures.
//!
//! What the guarantee is, and is not: Holm keeps the chance of wrongly dropping any cell in one
//! round's family at or below α, whatever the dependence between the tests; the rounds are
//! repeated looks at growing samples and are not corrected for (as in F-Race), so over a whole race
//! the chance of losing a truly best cell is somewhat above α. Welch's test assumes roughly normal
//! means; with 5–10 skewed episode counts per cell that is an approximation, which is why the
//! first round should not be tiny and every verdict is stated as "not significantly worse".
//!
//! A race is a pure function of the pipeline and the cached outcomes: [`replay`] replays the
//! rounds from the cache, as far as their trials are present, and plans the next round's trials.
//! Rerunning a finished race runs nothing; raising `max_seeds` runs only the new rounds; the answer
//! is the same on any number of threads or shards, because every decision reads only stored outcomes.

use crate::analysis::{best_cell, episodes_counted, welch, Candidate};
use crate::cache::store::{KeySet, Store};
use crate::cache::{Key, ENGINE_VERSION};
use crate::plan::{Experiment, Plan, PlannedTrial, TrialBrief};
use qsweep_engine::{Algorithm, Outcome};
use std::borrow::Cow;
use std::collections::{HashMap, HashSet};

pub use crate::plan::ReadOutcomes;

/// How one heatmap's race stands.
#[derive(Debug, Clone, PartialEq)]
pub struct HeatRace {
    /// Index of the experiment in the plan.
    pub experiment: usize,
    /// The algorithm (the heatmap's column of the figure).
    pub algorithm: Algorithm,
    /// Cells in the heatmap.
    pub cells: usize,
    /// Rounds whose trials are all present and decided.
    pub rounds_done: u32,
    /// The most rounds the race can take (1 + ⌈(max_seeds − first seeds) / batch⌉).
    pub rounds_max: u32,
    /// The race is over (one contender left, or every contender at `max_seeds`).
    pub finished: bool,
    /// Contenders after the last decided round (every cell before the first).
    pub contenders: usize,
    /// Trials planned so far: every decided round's and the pending round's.
    pub trials: usize,
    /// Of those, in the cache.
    pub cached: usize,
    /// Trials of the same heatmap with `max_seeds` seeds in every cell.
    pub without_race: usize,
}

/// A plan whose stages (races, fresh seeds) are replayed against the cache: what a report reads.
/// Only [`replay`] makes one, so a report handed one never replays it again (a no-op `qsweep run`
/// replays its plan once, not twice).
#[derive(Debug, Clone)]
pub struct Replayed {
    /// The plan with every raced cell's trials (decided rounds and the pending one) and its
    /// `contender` flag set, and the fresh trials of every decided best cell; experiments without
    /// stages are as planned.
    plan: Plan,
    /// Every raced heatmap, in plan order.
    heats: Vec<HeatRace>,
}

impl Replayed {
    /// The replayed plan.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// How each raced heatmap stands, in plan order (none without a race).
    pub fn heats(&self) -> &[HeatRace] {
        &self.heats
    }

    /// The replayed plan, given up by the replay.
    pub fn into_plan(self) -> Plan {
        self.plan
    }
}

impl Plan {
    /// Whether some experiment races.
    pub fn has_race(&self) -> bool {
        self.experiments.iter().any(|e| e.race.is_some())
    }

    /// The most rounds any of its races can take (1 without a race).
    pub fn race_rounds_max(&self) -> u32 {
        self.experiments
            .iter()
            .filter_map(|e| {
                let r = e.race?;
                let first = e.cells.first().map_or(0, |c| c.trials.len()) as u32;
                Some(rounds_max(first, r.batch, r.max_seeds))
            })
            .max()
            .unwrap_or(1)
    }

    /// The most stages the plan can take, each planned from the outcomes of those before: a
    /// race's rounds ([`Plan::race_rounds_max`]), then one more for the fresh seeds.
    pub fn stages_max(&self) -> u32 {
        self.race_rounds_max() + u32::from(self.has_fresh())
    }
}

/// The most rounds a race from `first` seeds per cell can take, `batch` more per round up to
/// `max_seeds`: 1 + ⌈(max_seeds − first) / batch⌉ (the engine's heatmaps and program pipelines'
/// experiments alike).
pub fn rounds_max(first: u32, batch: u32, max_seeds: u32) -> u32 {
    1 + max_seeds.saturating_sub(first).div_ceil(batch)
}

/// The seeds a contender with `have` seeds gets in the next round: up to `batch` more, at most
/// `n_max` in all, numbered on from `next_seed` (the largest first-round seed + 1) past the
/// `have − first` extra seeds it already has. One rule for every race, so a cell's extra seeds
/// are the same whichever kind of pipeline races it.
pub fn round_seeds(
    next_seed: u64,
    first: usize,
    have: usize,
    batch: usize,
    n_max: usize,
) -> std::ops::Range<u64> {
    let add = n_max.saturating_sub(have).min(batch) as u64;
    let start = next_seed + (have - first) as u64;
    start..start + add
}

/// How a run has a plan it replays round by round back as planned for the next round: by undoing
/// what the replay changed (it was replayed in place: no second copy of its cells is made), or as
/// the plan itself, beside a replayed copy. A replay only appends trials to a raced cell, sets its
/// `contender` and sets the fresh trials of a best cell.
#[derive(Debug)]
pub(crate) enum Unreplay {
    /// Each staged experiment's cells as planned: their trial counts and race states.
    Undo(Vec<(usize, Vec<CellAsPlanned>)>),
    /// The plan as planned (a copy of it was replayed).
    Planned(Box<Plan>),
}

/// A staged cell as planned: its trial count and race state.
type CellAsPlanned = (usize, Option<bool>);

impl Unreplay {
    /// [`replay`] `plan`, and how to have it back as planned: replayed in place, unless `copy` (the
    /// caller needs the plan as planned beside the replayed one) or a cell already has fresh trials
    /// (a replay replaces them: not undone).
    pub(crate) fn replay(
        plan: Plan,
        copy: bool,
        cached: &HashSet<Key>,
        read: &mut ReadOutcomes,
    ) -> anyhow::Result<(Replayed, Self)> {
        match Self::note(&plan).filter(|_| !copy) {
            Some(undo) => Ok((replay(plan, cached, read)?, Self::Undo(undo))),
            None => Ok((replay(&plan, cached, read)?, Self::Planned(Box::new(plan)))),
        }
    }

    /// The staged experiments' cells of `plan` as they are; `None` when a cell already has fresh
    /// trials.
    fn note(plan: &Plan) -> Option<Vec<(usize, Vec<CellAsPlanned>)>> {
        let mut out = Vec::new();
        for (ei, e) in plan.experiments.iter().enumerate() {
            if e.race.is_none() && e.fresh.is_none() {
                continue;
            }
            if e.cells.iter().any(|c| !c.fresh.is_empty()) {
                return None;
            }
            out.push((ei, e.cells.iter().map(|c| (c.trials.len(), c.contender)).collect()));
        }
        Some(out)
    }

    /// The plan as planned while its replay is in use, where it is kept beside it (a copy was
    /// replayed); `None` when it was replayed in place.
    pub(crate) fn planned(&self) -> Option<&Plan> {
        match self {
            Self::Undo(_) => None,
            Self::Planned(p) => Some(p),
        }
    }

    /// The plan as planned, from `replayed`, the replay this was made with.
    pub(crate) fn undo(self, replayed: Replayed) -> Plan {
        match self {
            Self::Undo(cells) => {
                let mut plan = replayed.plan;
                for (ei, cells) in cells {
                    for (c, (n, contender)) in plan.experiments[ei].cells.iter_mut().zip(cells) {
                        c.trials.truncate(n);
                        c.contender = contender;
                        c.fresh.clear();
                    }
                }
                plan
            }
            Self::Planned(p) => *p,
        }
    }
}

/// How a replay reads the outcomes of a cache: what `store` holds of the trials `scan` lists
/// (pass `&scan.keys` as the replay's cached trials).
pub fn read_cached<'a>(
    store: &'a Store,
    scan: &'a KeySet,
) -> impl FnMut(&HashSet<Key>) -> anyhow::Result<Vec<(Key, TrialBrief)>> + 'a {
    move |wanted| store.read_outcomes_as(scan, wanted, false, |k, s| (k, TrialBrief::from(&s.outcome)))
}

/// Replay every stage of `plan`, given up (replayed in place) or borrowed (a copy is replayed):
/// replay its races' rounds from the outcomes of the trials in `cached` (`read` fetches the
/// outcomes of some of them; against a cache, [`read_cached`]), as far as each round's trials are
/// all cached, and plan the next round's; then plan the fresh-seed trials of every decided best
/// cell ([`crate::fresh::plan_fresh`]). Without a race or a `fresh:` block the plan comes back as
/// it is (a plan given up is not copied: a report of the paper's variants holds no second copy of
/// its 37,000 cells).
pub fn replay<'p>(
    plan: impl Into<Cow<'p, Plan>>,
    cached: &HashSet<Key>,
    read: &mut ReadOutcomes,
) -> anyhow::Result<Replayed> {
    let mut out = plan.into().into_owned();
    let mut heats = Heat::enter_all(&mut out);
    // Every heatmap advances as far as the cache allows; they share one read per pass.
    let mut known: HashMap<Key, TrialBrief> = HashMap::new();
    loop {
        let wanted = wanted(&heats, &out, cached, &known);
        if !wanted.is_empty() {
            let got = read(&wanted)?;
            known.reserve(got.len());
            known.extend(got);
        }
        let mut advanced = false;
        for h in heats.iter_mut().filter(|h| !h.finished) {
            advanced |= h.advance(&mut out.experiments[h.exp], &known);
        }
        if !advanced {
            break;
        }
    }
    // The best cells are decided only once the races are: fresh seeds come last.
    if out.has_fresh() {
        crate::fresh::plan_fresh(&mut out, cached, &mut known, read)?;
    }
    let heats = heats.into_iter().map(|h| h.standing(&out, cached)).collect();
    Ok(Replayed { plan: out, heats })
}

/// The cached trials of the unfinished races' contenders whose outcomes are not yet `known`.
fn wanted(
    heats: &[Heat],
    plan: &Plan,
    cached: &HashSet<Key>,
    known: &HashMap<Key, TrialBrief>,
) -> HashSet<Key> {
    let mut wanted = HashSet::new();
    for h in heats.iter().filter(|h| !h.finished) {
        let e = &plan.experiments[h.exp];
        let live = h.cells.iter().zip(&h.contender).filter(|(_, c)| **c);
        for (&i, _) in live {
            let keys = e.cells[i].trials.iter().map(|t| t.key);
            wanted.extend(keys.filter(|key| cached.contains(key) && !known.contains_key(key)));
        }
    }
    wanted
}

/// One heatmap's race while it is replayed.
struct Heat {
    /// Index of the experiment in the plan.
    exp: usize,
    /// The heatmap's algorithm.
    algorithm: Algorithm,
    /// Indices of the heatmap's cells in the experiment.
    cells: Vec<usize>,
    /// Their canonical configurations (for the keys of extra seeds).
    canonical: Vec<String>,
    /// Per cell, whether it is still in the race.
    contender: Vec<bool>,
    /// The first extra seed's number.
    next_seed: u64,
    /// Seeds of the first round.
    first: u32,
    /// Rounds decided.
    rounds_done: u32,
    /// The race is over.
    finished: bool,
}

impl Heat {
    /// Every heatmap of every raced experiment of `plan`, with each of its cells marked a contender.
    fn enter_all(plan: &mut Plan) -> Vec<Heat> {
        let mut heats = Vec::new();
        for (ei, e) in plan.experiments.iter_mut().enumerate() {
            if e.race.is_some() {
                heats.extend(Self::enter(ei, e));
            }
        }
        heats
    }

    /// The heatmaps of raced experiment `e` (index `ei`), one per algorithm, every cell a contender.
    fn enter(ei: usize, e: &mut Experiment) -> Vec<Heat> {
        let first_seeds: Vec<u64> =
            e.cells.first().map(|c| c.trials.iter().map(|t| t.seed).collect()).unwrap_or_default();
        let next_seed = first_seeds.iter().max().map_or(0, |m| m + 1);
        let mut heats = Vec::new();
        for &algorithm in &e.algorithms {
            let cells: Vec<usize> =
                (0..e.cells.len()).filter(|&i| e.cells[i].algorithm == algorithm).collect();
            for &i in &cells {
                e.cells[i].contender = Some(true);
            }
            heats.push(Heat {
                exp: ei,
                algorithm,
                canonical: cells
                    .iter()
                    .map(|&i| crate::cache::key::canonical_config(&e.cells[i].config))
                    .collect(),
                contender: vec![true; cells.len()],
                cells,
                next_seed,
                first: first_seeds.len() as u32,
                rounds_done: 0,
                finished: false,
            });
        }
        heats
    }

    /// Decide the next round if every contender's trials are `known`, and plan the one after it
    /// unless the race is over; whether a round was decided.
    fn advance(&mut self, e: &mut Experiment, known: &HashMap<Key, TrialBrief>) -> bool {
        let race = e.race.expect("raced experiment");
        let Some(samples) = self.samples(e, known) else { return false };
        let keep = decide(&samples, 1.0 - race.confidence.0);
        for (k, &i) in self.cells.iter().enumerate() {
            self.contender[k] = keep[k];
            e.cells[i].contender = Some(keep[k]);
        }
        self.rounds_done += 1;
        let left: Vec<usize> = (0..self.cells.len()).filter(|&k| self.contender[k]).collect();
        let n_max = race.max_seeds as usize;
        if left.len() <= 1 || left.iter().all(|&k| e.cells[self.cells[k]].trials.len() >= n_max) {
            self.finished = true;
        } else {
            self.plan_round(e, &left, n_max, race.batch as usize);
        }
        true
    }

    /// Each contender's sample (`None` for a cell out of the race), or nothing while one of its
    /// trials is missing.
    fn samples(&self, e: &Experiment, known: &HashMap<Key, TrialBrief>) -> Option<Vec<Option<Sample>>> {
        let mut samples: Vec<Option<Sample>> = Vec::with_capacity(self.cells.len());
        for (k, &i) in self.cells.iter().enumerate() {
            if !self.contender[k] {
                samples.push(None);
                continue;
            }
            let cell = &e.cells[i];
            let (limits, counting) = (&cell.config.limits, e.counting);
            let os: Vec<Outcome> = cell
                .trials
                .iter()
                .map(|t| known.get(&t.key).map(TrialBrief::outcome))
                .collect::<Option<_>>()?;
            samples.push(Some(Sample {
                values: os.iter().map(|o| f64::from(episodes_counted(o, limits, counting))).collect(),
                successes: os.iter().filter(|o| o.converged).count(),
            }));
        }
        Some(samples)
    }

    /// Give each contender in `left` up to `batch` more seeds, at most `n_max` in all.
    fn plan_round(&self, e: &mut Experiment, left: &[usize], n_max: usize, batch: usize) {
        for &k in left {
            let cell = &mut e.cells[self.cells[k]];
            let have = cell.trials.len();
            for seed in round_seeds(self.next_seed, self.first as usize, have, batch, n_max) {
                let key = Key::from_canonical(&self.canonical[k], seed, ENGINE_VERSION);
                cell.trials.push(PlannedTrial { seed, key });
            }
        }
    }

    /// How the race stands in the replayed `plan`.
    fn standing(self, plan: &Plan, cached: &HashSet<Key>) -> HeatRace {
        let e = &plan.experiments[self.exp];
        let race = e.race.expect("raced experiment");
        let trials: Vec<&PlannedTrial> = self.cells.iter().flat_map(|&i| &e.cells[i].trials).collect();
        HeatRace {
            experiment: self.exp,
            algorithm: self.algorithm,
            cells: self.cells.len(),
            rounds_done: self.rounds_done,
            rounds_max: rounds_max(self.first, race.batch, race.max_seeds),
            finished: self.finished,
            contenders: self.contender.iter().filter(|&&c| c).count(),
            trials: trials.len(),
            cached: trials.iter().filter(|t| cached.contains(&t.key)).count(),
            without_race: self.cells.len() * (race.max_seeds as usize).max(self.first as usize),
        }
    }
}

/// A contender's sample: the counted episodes of its trials and how many reached the goal.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// Episodes counted per trial ([`episodes_counted`]).
    pub values: Vec<f64>,
    /// Trials that reached the goal.
    pub successes: usize,
}

/// One round's decision over a heatmap's cells (`None`: already out of the race): which stay. The
/// best contender by Table III's rule stays; every other contender is tested against it
/// ([`welch::welch_p_greater`]) and the ones Holm's procedure rejects at family-wise level `level` leave.
pub fn decide(samples: &[Option<Sample>], level: f64) -> Vec<bool> {
    let candidates = samples.iter().enumerate().filter_map(|(i, s)| {
        s.as_ref().map(|s| Candidate {
            index: i,
            n: s.values.len(),
            successes: s.successes,
            mean: (!s.values.is_empty()).then(|| crate::analysis::mean(&s.values)),
        })
    });
    let Some(best) = best_cell(candidates) else { return samples.iter().map(Option::is_some).collect() };
    let values: Vec<Option<&[f64]>> =
        samples.iter().map(|s| s.as_ref().map(|s| s.values.as_slice())).collect();
    eliminate(&values, best.cell, level)
}

/// One round's tests, the part every race shares: each contender (`Some` sample: the values where
/// a higher one is worse) other than `best` is tested against the best's sample with the
/// one-sided Welch test ([`welch::welch_p_greater`]), Holm's procedure at family-wise level `level`
/// over the contenders tested, and the rejected ones leave; which stay (`None`: already out, stays
/// out). A contender of fewer than two values, or against a best of fewer than two, is not tested
/// and stays (a test needs a spread); the engine's cells always have the round's full sample.
pub fn eliminate(samples: &[Option<&[f64]>], best: usize, level: f64) -> Vec<bool> {
    let mut keep: Vec<bool> = samples.iter().map(Option::is_some).collect();
    let best_values = samples[best].expect("the best is a contender");
    if best_values.len() < 2 {
        return keep;
    }
    let tested: Vec<usize> =
        (0..samples.len()).filter(|&i| i != best && samples[i].is_some_and(|s| s.len() >= 2)).collect();
    let p: Vec<f64> = tested
        .iter()
        .map(|&i| welch::welch_p_greater(samples[i].expect("a contender"), best_values))
        .collect();
    for (&i, drop) in tested.iter().zip(welch::holm_reject(&p, level)) {
        keep[i] = !drop;
    }
    keep
}

#[cfg(test)]
mod tests;
