//! Why a planned program trial is not in the cache (`status --explain`): the nearest stored row
//! of the same seed, and what differs from it, in the words of the pipeline file:
//! `params.alpha: 0.1 → 0.2`, `input agents/q_learning.py changed`, `input agents/new.py added`,
//! `command changed: …`, `provenance changed: …`. The rows are described by what their key was
//! made of ([`StoredIdentity`], read from the cache's rows), so rows of another param schema
//! compare as well (a param added or removed shows as `(unset)`).

use crate::cache::Key;
use crate::program::key::Identity;
use crate::program::model::{ParamType, ParamValue, ProgramPlan, ProgramRow, Provenance};
use crate::program::provenance::{parse_record, shell_words};
use std::collections::{BTreeMap, HashMap, HashSet};

/// What a stored row's key was made of.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredIdentity {
    /// The seed.
    pub seed: u64,
    /// Every param with its value.
    pub params: Vec<(String, ParamValue)>,
    /// `ProgramRow::command_json`.
    pub command_json: String,
    /// `ProgramRow::inputs_json`.
    pub inputs_json: String,
    /// `ProgramRow::provenance_json`.
    pub provenance_json: String,
}

impl StoredIdentity {
    /// The identity of `row`, whose params are in the order of `params` (its schema's).
    pub fn of_row(row: &ProgramRow, params: &[(String, ParamType)]) -> Self {
        Self {
            seed: row.seed,
            params: params.iter().map(|(n, _)| n.clone()).zip(row.params.iter().cloned()).collect(),
            command_json: row.command_json.clone(),
            inputs_json: row.inputs_json.clone(),
            provenance_json: row.provenance_json.clone(),
        }
    }
}

/// Why a cell's trials are missing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Reason {
    /// No stored row has this seed.
    NeverComputed {
        /// The seed of the cell's first missing trial.
        seed: u64,
    },
    /// What differs from the nearest stored row of the same seed.
    Differences(Vec<String>),
}

impl std::fmt::Display for Reason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NeverComputed { seed } => write!(f, "never computed (no stored trial has seed {seed})"),
            Self::Differences(d) => f.write_str(&d.join(", ")),
        }
    }
}

/// A cell with missing trials, and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MissingCell {
    /// Its experiment's index in the plan.
    pub experiment: usize,
    /// Its index in the experiment.
    pub cell: usize,
    /// How many of its trials are missing.
    pub missing: usize,
    /// How many trials it has.
    pub trials: usize,
    /// Why its first missing trial is missing.
    pub reason: Reason,
}

/// Each cell of `plan` with trials not in `cached`, and why: its first missing trial against
/// the nearest of the `stored` rows with that trial's seed (fewest differences; ties by text,
/// so the answer never depends on the rows' order).
pub fn why_missing(plan: &ProgramPlan, cached: &HashSet<Key>, stored: &[StoredIdentity]) -> Vec<MissingCell> {
    let now = Now::of(plan);
    let mut by_seed: HashMap<u64, Vec<&StoredIdentity>> = HashMap::new();
    for s in stored {
        by_seed.entry(s.seed).or_default().push(s);
    }
    // Rows share their command, inputs and provenance: each distinct triple is compared once.
    let mut shared: HashMap<(&str, &str, &str), Vec<String>> = HashMap::new();
    let mut out = Vec::new();
    for (ei, e) in plan.experiments.iter().enumerate() {
        for (ci, c) in e.cells.iter().enumerate() {
            let missing: Vec<_> = c.trials.iter().filter(|t| !cached.contains(&t.key)).collect();
            let Some(first) = missing.first() else { continue };
            let params: Vec<(String, ParamValue)> =
                plan.params.iter().map(|(n, _)| n.clone()).zip(c.params.iter().cloned()).collect();
            let reason = match by_seed.get(&first.seed) {
                None => Reason::NeverComputed { seed: first.seed },
                Some(rows) => {
                    for r in rows {
                        shared
                            .entry((&r.command_json, &r.inputs_json, &r.provenance_json))
                            .or_insert_with(|| now.environment(r));
                    }
                    let envs: Vec<&Vec<String>> = rows
                        .iter()
                        .map(|r| {
                            &shared[&(
                                r.command_json.as_str(),
                                r.inputs_json.as_str(),
                                r.provenance_json.as_str(),
                            )]
                        })
                        .collect();
                    // Count first (no text built per row), then write out only the nearest.
                    let counts: Vec<usize> = rows
                        .iter()
                        .zip(&envs)
                        .map(|(r, env)| param_difference_count(&r.params, &params) + env.len())
                        .collect();
                    let fewest = counts.iter().copied().min().unwrap_or(0);
                    let best = rows
                        .iter()
                        .zip(&envs)
                        .zip(&counts)
                        .filter(|(_, n)| **n == fewest)
                        .map(|((r, env), _)| [param_differences(&r.params, &params), env.to_vec()].concat())
                        .min()
                        .unwrap_or_default();
                    if best.is_empty() {
                        Reason::Differences(vec![
                            "stored with the same params, command, inputs and provenance under another key"
                                .into(),
                        ])
                    } else {
                        Reason::Differences(best)
                    }
                }
            };
            out.push(MissingCell {
                experiment: ei,
                cell: ci,
                missing: missing.len(),
                trials: c.trials.len(),
                reason,
            });
        }
    }
    out
}

/// What differs between a stored row's identity and the trial of `plan` with `params` (by name)
/// — the explanation of one trial.
pub fn differences(
    plan: &ProgramPlan,
    params: &[(String, ParamValue)],
    stored: &StoredIdentity,
) -> Vec<String> {
    [param_differences(&stored.params, params), Now::of(plan).environment(stored)].concat()
}

/// How many lines [`param_differences`] gives, without writing them.
fn param_difference_count(old: &[(String, ParamValue)], new: &[(String, ParamValue)]) -> usize {
    let value = |list: &[(String, ParamValue)], name: &str| list.iter().position(|(n, _)| n == name);
    let changed = new.iter().filter(|(n, v)| value(old, n).is_none_or(|i| old[i].1 != *v)).count();
    changed + old.iter().filter(|(n, _)| value(new, n).is_none()).count()
}

/// `params.NAME: OLD → NEW` for each param that differs, `(unset)` where one side lacks it.
fn param_differences(old: &[(String, ParamValue)], new: &[(String, ParamValue)]) -> Vec<String> {
    let shown = |v: Option<&ParamValue>| v.map_or("(unset)".to_string(), ParamValue::to_string);
    fn find<'a>(list: &'a [(String, ParamValue)], name: &str) -> Option<&'a ParamValue> {
        list.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }
    let mut out: Vec<String> = new
        .iter()
        .filter(|(n, v)| find(old, n) != Some(v))
        .map(|(n, v)| format!("params.{n}: {} → {v}", shown(find(old, n))))
        .collect();
    out.extend(
        old.iter().filter(|(n, _)| find(new, n).is_none()).map(|(n, v)| format!("params.{n}: {v} → (unset)")),
    );
    out
}

/// The plan's side of a comparison: its command, inputs and keyed provenance.
struct Now<'a> {
    identity: Identity,
    command: &'a [String],
    inputs: BTreeMap<&'a str, &'a str>,
    keyed: Vec<(&'a Provenance, &'a str)>,
}

impl<'a> Now<'a> {
    fn of(plan: &'a ProgramPlan) -> Self {
        let p = &plan.program;
        Self {
            identity: Identity::of(p),
            command: &p.command,
            inputs: p.inputs.iter().map(|f| (f.path.as_str(), f.digest.as_str())).collect(),
            keyed: p
                .provenance
                .iter()
                .zip(&p.provenance_outputs)
                .filter(|(p, _)| p.key)
                .map(|(p, o)| (p, o.as_str()))
                .collect(),
        }
    }

    /// What differs in command, inputs and keyed provenance between `stored` and the plan.
    fn environment(&self, stored: &StoredIdentity) -> Vec<String> {
        let mut out = Vec::new();
        if stored.command_json != self.identity.command_json {
            let old: Option<Vec<String>> = serde_json::from_str(&stored.command_json).ok();
            out.push(match old {
                Some(old) => {
                    format!("command changed: {} → {}", shell_words(&old), shell_words(self.command))
                }
                None => "command changed".to_string(),
            });
        }
        if stored.inputs_json != self.identity.inputs_json {
            out.extend(self.inputs(&stored.inputs_json));
        }
        if stored.provenance_json != self.identity.provenance_json {
            out.extend(self.provenance(&stored.provenance_json));
        }
        out
    }

    fn inputs(&self, stored: &str) -> Vec<String> {
        let Ok(old) = serde_json::from_str::<BTreeMap<String, String>>(stored) else {
            return vec!["inputs changed".to_string()];
        };
        let mut out = Vec::new();
        for (path, digest) in &self.inputs {
            match old.get(*path) {
                None => out.push(format!("input {path} added")),
                Some(d) if d != digest => out.push(format!("input {path} changed")),
                Some(_) => {}
            }
        }
        out.extend(
            old.keys()
                .filter(|p| !self.inputs.contains_key(p.as_str()))
                .map(|p| format!("input {p} removed")),
        );
        out
    }

    /// The keyed provenance that differs (unkeyed outputs are recorded, never keyed: no reason).
    fn provenance(&self, stored: &str) -> Vec<String> {
        let Some(old) = parse_record(stored) else { return vec!["provenance changed".to_string()] };
        let old: Vec<(&Provenance, &str)> =
            old.iter().filter(|(p, _)| p.key).map(|(p, o)| (p, o.as_str())).collect();
        let same = old.len() == self.keyed.len()
            && old.iter().zip(&self.keyed).all(|((a, x), (b, y))| a.command == b.command && x == y);
        if same {
            return Vec::new();
        }
        let mut out = Vec::new();
        for (p, now) in &self.keyed {
            let cmd = shell_words(&p.command);
            match old.iter().find(|(o, _)| o.command == p.command) {
                None => out.push(format!("provenance added: `{cmd}` (key: true)")),
                Some((_, was)) if was != now => {
                    out.push(format!("provenance changed: `{cmd}`: {} → {}", short(was), short(now)))
                }
                Some(_) => {}
            }
        }
        for (o, _) in &old {
            if !self.keyed.iter().any(|(p, _)| p.command == o.command) {
                out.push(format!("provenance removed: `{}`", shell_words(&o.command)));
            }
        }
        if out.is_empty() {
            out.push("provenance changed (its keyed commands in another order)".to_string());
        }
        out
    }
}

/// An output as one short line: its first line, at most 60 characters.
fn short(output: &str) -> String {
    let line = output.lines().next().unwrap_or("");
    let cut: String = line.chars().take(60).collect();
    if cut.len() < line.len() || output.lines().nth(1).is_some() {
        format!("{cut}…")
    } else if cut.is_empty() {
        "(nothing)".to_string()
    } else {
        cut
    }
}

#[cfg(test)]
mod tests;
