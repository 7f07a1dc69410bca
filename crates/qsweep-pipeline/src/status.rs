//! A pipeline's cache status, as data: how many of its distinct trials are cached, overall, per
//! experiment and per raced heatmap, and (on request) why each missing cell is missing. Reads the
//! cache and runs nothing; `qsweep status` prints it and `formats::StatusReport` is its `--json`.

use crate::cache::store::{Damaged, KeySet, Store};
use crate::cache::{Key, TrialRecord, ENGINE_VERSION};
use crate::plan::Plan;
use crate::race::HeatRace;
use serde_json::Value;
use std::collections::{BTreeMap, HashMap, HashSet};

/// Distinct trials and how many of them are cached.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Count {
    /// Distinct trials (a trial shared by two cells counts once).
    pub trials: usize,
    /// Of those, in the cache.
    pub cached: usize,
}

impl Count {
    /// Of the trials, not in the cache.
    pub fn missing(&self) -> usize {
        self.trials - self.cached
    }

    fn of<'a>(keys: impl Iterator<Item = &'a Key>, cached: &HashSet<Key>) -> Self {
        let keys: HashSet<_> = keys.collect();
        Self { trials: keys.len(), cached: keys.iter().filter(|k| cached.contains(k)).count() }
    }
}

/// What [`status`] found.
#[derive(Debug, Clone)]
pub struct Status {
    /// The plan with its races replayed from the cache (each raced cell holds the trials of its
    /// decided rounds and the pending one); without a race, the plan as given.
    pub plan: Plan,
    /// The plan's distinct trials.
    pub total: Count,
    /// One count per experiment of [`Status::plan`], in plan order.
    pub experiments: Vec<Count>,
    /// Every raced heatmap, in plan order; `None` for a plan without a race.
    pub heats: Option<Vec<HeatRace>>,
    /// Cache segments that could not be read (their trials count as missing).
    pub damaged: Vec<Damaged>,
    /// Of the missing trials, how many another run is computing now (a live lease in the cache).
    pub running_elsewhere: usize,
    /// Why missing cells are missing: only when asked for and some trial is missing.
    pub explanation: Option<Vec<MissingCell>>,
}

/// A cell with missing trials, and why (the same for all its seeds).
#[derive(Debug, Clone, PartialEq)]
pub struct MissingCell {
    /// Index of the experiment in [`Status::plan`].
    pub experiment: usize,
    /// Index of the cell in its experiment.
    pub cell: usize,
    /// Its trials not in the cache.
    pub missing: usize,
    /// Its trials.
    pub trials: usize,
    /// Why its first missing trial is missing.
    pub reason: Reason,
}

/// Why a trial is not in the cache.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub enum Reason {
    /// No cached trial at its grid position (system, representation, algorithm, resolution,
    /// actions) and seed.
    NeverComputed,
    /// A cached trial at the same position has the same configuration: it was keyed under
    /// another engine version.
    OtherEngineVersion,
    /// The resolved fields that differ from the closest cached trial at the same position
    /// (`field: old → new`, and the engine version when it differs).
    Differences(Vec<String>),
}

impl std::fmt::Display for Reason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NeverComputed => {
                f.write_str("never computed (no cached trial at this grid position and seed)")
            }
            Self::OtherEngineVersion => f.write_str("cached under another engine version"),
            Self::Differences(d) => f.write_str(&d.join(", ")),
        }
    }
}

/// The status of `plan` against `store` (`None`: no cache yet, every trial missing); with
/// `explain`, also why each missing cell is missing (this reads every cached row).
pub fn status(plan: Plan, store: Option<&Store>, explain: bool) -> anyhow::Result<Status> {
    let scan = match store {
        Some(store) => store.keys()?,
        None => KeySet::default(),
    };
    let cached = &scan.keys;
    // A race's trials so far come from the cached outcomes of its earlier rounds.
    // So do the fresh seeds of the best cells the grid has decided. The plan is replayed in
    // place (no second copy of its cells).
    let (plan, heats) = if plan.is_staged() {
        let has_race = plan.has_race();
        let r = match store {
            Some(store) => crate::race::replay(plan, cached, &mut crate::race::read_cached(store, &scan))?,
            None => crate::race::replay(plan, cached, &mut |_| Ok(Vec::new()))?,
        };
        let heats = has_race.then(|| r.heats().to_vec());
        (r.into_plan(), heats)
    } else {
        (plan, None)
    };
    let experiments = plan
        .experiments
        .iter()
        .map(|e| {
            Count::of(e.cells.iter().flat_map(|c| c.trials.iter().chain(&c.fresh).map(|t| &t.key)), cached)
        })
        .collect();
    let total = Count::of(plan.trials().map(|(_, _, t)| &t.key), cached);
    let explanation = match store {
        _ if !explain || total.missing() == 0 => None,
        Some(store) => Some(missing_cells(&plan, &store.read_all()?, cached)),
        None => Some(missing_cells(&plan, &[], cached)),
    };
    let running_elsewhere = match store {
        Some(store) if total.missing() > 0 => crate::cache::leases::running_elsewhere(
            store,
            plan.trials().map(|(_, _, t)| &t.key).filter(|k| !cached.contains(k)),
        ),
        _ => 0,
    };
    Ok(Status { plan, total, experiments, heats, damaged: scan.damaged, running_elsewhere, explanation })
}

/// A trial's grid position: system, representation, algorithm, resolution, actions and seed.
type Position = (String, String, String, Vec<u32>, u32, u64);

fn position(c: &qsweep_engine::TrialConfig, seed: u64) -> Position {
    (
        c.system().name().to_string(),
        c.repr.kind.name().to_string(),
        c.learner.algorithm.name().to_string(),
        c.repr.resolution.clone(),
        c.actions,
        seed,
    )
}

fn missing_cells(plan: &Plan, records: &[TrialRecord], cached: &HashSet<Key>) -> Vec<MissingCell> {
    let mut at: HashMap<Position, Vec<&TrialRecord>> = HashMap::new();
    for r in records {
        at.entry(position(&r.config, r.seed)).or_default().push(r);
    }
    let mut out = Vec::new();
    for (ei, e) in plan.experiments.iter().enumerate() {
        for (ci, c) in e.cells.iter().enumerate() {
            let missing: Vec<_> =
                c.trials.iter().chain(&c.fresh).filter(|t| !cached.contains(&t.key)).collect();
            let Some(t) = missing.first() else { continue };
            let reason = match at.get(&position(&c.config, t.seed)) {
                None => Reason::NeverComputed,
                Some(prev) => {
                    let new = flatten(&serde_json::to_value(&c.config).unwrap_or(Value::Null));
                    let best = prev
                        .iter()
                        .map(|r| {
                            let old = flatten(&serde_json::to_value(&r.config).unwrap_or(Value::Null));
                            diff(&old, &new, r.engine_version)
                        })
                        // Fewest differences; ties by text, so the answer never depends on segment order.
                        .min_by(|a, b| a.len().cmp(&b.len()).then_with(|| a.cmp(b)))
                        .unwrap_or_default();
                    if best.is_empty() {
                        Reason::OtherEngineVersion
                    } else {
                        Reason::Differences(best)
                    }
                }
            };
            out.push(MissingCell {
                experiment: ei,
                cell: ci,
                missing: missing.len(),
                trials: c.trials.len() + c.fresh.len(),
                reason,
            });
        }
    }
    out
}

/// A JSON value's leaves by dotted path, each as its JSON text.
fn flatten(v: &Value) -> BTreeMap<String, String> {
    fn go(prefix: &str, v: &Value, out: &mut BTreeMap<String, String>) {
        match v {
            Value::Object(m) => {
                for (k, v) in m {
                    go(&if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") }, v, out);
                }
            }
            other => {
                out.insert(prefix.to_string(), other.to_string());
            }
        }
    }
    let mut out = BTreeMap::new();
    go("", v, &mut out);
    out
}

fn diff(old: &BTreeMap<String, String>, new: &BTreeMap<String, String>, old_version: u32) -> Vec<String> {
    let mut out: Vec<String> = new
        .iter()
        .filter(|(k, v)| old.get(*k) != Some(v))
        .map(|(k, v)| format!("{k}: {} → {v}", old.get(k).map_or("(unset)", String::as_str)))
        .collect();
    if old_version != ENGINE_VERSION {
        out.push(format!("engine version: {old_version} → {ENGINE_VERSION}"));
    }
    out
}

/// How many cells each distinct reason explains, by the reason's text.
pub fn reason_counts(cells: &[MissingCell]) -> BTreeMap<String, usize> {
    let mut out = BTreeMap::new();
    for c in cells {
        *out.entry(c.reason.to_string()).or_default() += 1;
    }
    out
}
