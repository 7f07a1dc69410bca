//! `qsweep status`: what is cached and what is missing, per system and experiment, without running
//! anything; `--explain` says why missing cells are missing.

use super::pipeline_args::PipelineArgs;
use crate::cache::TrialRecord;
use crate::formats::{StatusExperiment, StatusRace, StatusReport};
use clap::Args;
use serde_json::Value;
use std::collections::{BTreeMap, HashMap, HashSet};

/// Arguments of `qsweep status`.
#[derive(Debug, Args)]
pub struct StatusArgs {
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    /// Print the counts as JSON.
    #[arg(long)]
    pub json: bool,
    /// For missing cells, show which resolved fields differ from the cached trial at the same grid
    /// position (same system, representation, algorithm, resolution, actions and seed).
    #[arg(long)]
    pub explain: bool,
}

/// Run `qsweep status`.
pub fn run(a: StatusArgs) -> anyhow::Result<u8> {
    let plan = a.pipeline.plan()?;
    // A dry run before the first run stays useful: a missing cache means every trial is missing,
    // and status (read-only) does not create it.
    let store = a.pipeline.existing_store()?;
    let scan = match &store {
        Some(store) => store.keys()?,
        None => crate::cache::store::KeyScan::default(),
    };
    let cached = &scan.keys;
    // A race's trials so far come from the cached outcomes of its earlier rounds.
    let raced = match &store {
        Some(store) if plan.has_race() => Some(crate::race::replay_cached(&plan, store, &scan)?),
        _ if plan.has_race() => Some(crate::race::replay(&plan, cached, &mut |_| Ok(Default::default()))?),
        _ => None,
    };
    let plan = raced.as_ref().map_or(&plan, |r| &r.plan);
    let race_rows: Vec<StatusRace> = raced
        .iter()
        .flat_map(|r| &r.heats)
        .map(|h| {
            let e = &plan.experiments[h.experiment];
            StatusRace {
                variant: e.variant.clone(),
                system: e.system.name().into(),
                experiment: e.id.clone(),
                algorithm: h.algorithm.name().into(),
                cells: h.cells,
                rounds_done: h.rounds_done,
                rounds_max: h.rounds_max,
                finished: h.finished,
                contenders: h.contenders,
                trials: h.trials,
                cached: h.present,
                without_race: h.without_race,
            }
        })
        .collect();
    let mut rows = Vec::new();
    for e in &plan.experiments {
        let keys: HashSet<_> = e.cells.iter().flat_map(|c| c.trials.iter().map(|t| t.key)).collect();
        let hit = keys.iter().filter(|k| cached.contains(k)).count();
        rows.push((e, keys.len(), hit));
    }
    let unique: HashSet<_> = plan.trials().map(|(_, _, t)| t.key).collect();
    let unique_hit = unique.iter().filter(|k| cached.contains(k)).count();
    if a.json {
        let experiments = rows
            .iter()
            .map(|&(e, n, hit)| StatusExperiment {
                variant: e.variant.clone(),
                system: e.system.name().into(),
                experiment: e.id.clone(),
                repr: e.repr.name().into(),
                cells: e.cells.len(),
                trials: n,
                cached: hit,
                missing: n - hit,
            })
            .collect();
        let v = StatusReport {
            format_version: StatusReport::FORMAT_VERSION,
            pipeline: plan.name.clone(),
            trials: unique.len(),
            cached: unique_hit,
            missing: unique.len() - unique_hit,
            experiments,
            damaged_segments: scan.damaged.len(),
            race: raced.is_some().then_some(race_rows),
        };
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        let width = plan.variants.iter().map(|v| v.id.len()).max().map_or(0, |w| w.max(7) + 1);
        // Experiment ids are usually numbers; a longer id widens its column.
        let ew = plan.experiments.iter().map(|e| e.id.len()).max().unwrap_or(0).max(4);
        if width > 0 {
            print!("{:<width$}", "variant");
        }
        println!(
            "{:<13} {:>ew$} {:<6} {:>6} {:>7} {:>7} {:>8}",
            "system", "exp", "repr", "cells", "trials", "cached", "missing"
        );
        for (e, n, hit) in &rows {
            if width > 0 {
                print!("{:<width$}", e.variant.as_deref().unwrap_or_default());
            }
            println!(
                "{:<13} {:>ew$} {:<6} {:>6} {:>7} {:>7} {:>8}",
                e.system.name(),
                e.id,
                e.repr.name(),
                e.cells.len(),
                n,
                hit,
                n - hit
            );
        }
        println!(
            "total: {} trials, {} cached, {} missing (cache: {}{})",
            unique.len(),
            unique_hit,
            unique.len() - unique_hit,
            a.pipeline.cache_dir().display(),
            if store.is_none() { ", does not exist yet" } else { "" }
        );
        if raced.is_some() {
            print_race(&race_rows, width, ew);
        }
        for d in &scan.damaged {
            println!("damaged segment: {d}");
        }
    }
    if a.explain && unique_hit < unique.len() {
        let records = match &store {
            Some(store) => store.read_all()?,
            None => Vec::new(),
        };
        explain(plan, &records, cached);
    }
    Ok(crate::error::exit::OK)
}

type Position = (String, String, String, Vec<u32>, u32, u64);

fn position(c: &crate::sim::TrialConfig, seed: u64) -> Position {
    (
        c.system().name().to_string(),
        c.repr.kind.name().to_string(),
        c.learner.algorithm.name().to_string(),
        c.repr.resolution.clone(),
        c.actions,
        seed,
    )
}

fn explain(plan: &crate::plan::Plan, records: &[TrialRecord], cached: &HashSet<crate::cache::Key>) {
    let mut at: HashMap<Position, Vec<&TrialRecord>> = HashMap::new();
    for r in records {
        at.entry(position(&r.config, r.seed)).or_default().push(r);
    }
    // One line per missing cell: the differences are the same for all its seeds.
    let mut reasons: BTreeMap<String, usize> = BTreeMap::new();
    for e in &plan.experiments {
        for c in &e.cells {
            let missing: Vec<_> = c.trials.iter().filter(|t| !cached.contains(&t.key)).collect();
            let Some(t) = missing.first() else { continue };
            let label = format!(
                "{}{} exp {} {} {}",
                e.variant.as_deref().map(|v| format!("[{v}] ")).unwrap_or_default(),
                e.system.name(),
                e.id,
                c.algorithm.name(),
                c.coords.iter().map(|&v| crate::spec::format_value(v)).collect::<Vec<_>>().join("×")
            );
            let why = match at.get(&position(&c.config, t.seed)) {
                None => "never computed (no cached trial at this grid position and seed)".to_string(),
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
                        "cached under another engine version".to_string()
                    } else {
                        best.join(", ")
                    }
                }
            };
            println!("missing {label} ({} of {} seeds): {why}", missing.len(), c.trials.len());
            *reasons.entry(why).or_default() += 1;
        }
    }
    if reasons.len() > 1 {
        println!("summary of reasons:");
        for (why, n) in reasons {
            println!("  {n} cells: {why}");
        }
    }
}

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
    if old_version != crate::cache::ENGINE_VERSION {
        out.push(format!("engine version: {old_version} → {}", crate::cache::ENGINE_VERSION));
    }
    out
}

/// The race section: per heatmap, rounds done and to come, contenders and trials against
/// `max_seeds` in every cell.
fn print_race(rows: &[StatusRace], width: usize, ew: usize) {
    println!();
    if width > 0 {
        print!("{:<width$}", "variant");
    }
    println!(
        "{:<13} {:>ew$} {:<9} {:>6} {:>7} {:>11} {:>7} {:>7} {:>8}",
        "race", "exp", "algorithm", "cells", "rounds", "contenders", "trials", "cached", "max-all"
    );
    for r in rows {
        if width > 0 {
            print!("{:<width$}", r.variant.as_deref().unwrap_or_default());
        }
        let rounds = format!("{}/{}{}", r.rounds_done, r.rounds_max, if r.finished { "" } else { "+" });
        println!(
            "{:<13} {:>ew$} {:<9} {:>6} {:>7} {:>11} {:>7} {:>7} {:>8}",
            r.system,
            r.experiment,
            r.algorithm,
            r.cells,
            rounds,
            r.contenders,
            r.trials,
            r.cached,
            r.without_race
        );
    }
    let open = rows.iter().filter(|r| !r.finished).count();
    let trials: usize = rows.iter().map(|r| r.trials).sum();
    let all: usize = rows.iter().map(|r| r.without_race).sum();
    let to_come =
        rows.iter().filter(|r| !r.finished).map(|r| r.rounds_max - r.rounds_done).max().unwrap_or(0);
    println!(
        "race: {} heatmaps, {} finished, {open} still racing (at most {to_come} more rounds); {trials} trials so far, {:.1}% of the {all} that max_seeds in every cell would run",
        rows.len(),
        rows.len() - open,
        100.0 * trials as f64 / all.max(1) as f64
    );
    println!("rounds: decided/most possible, + while racing; max-all: trials with max_seeds in every cell");
}
