//! `qsweep status`: prints what is cached and what is missing, per system and experiment, without
//! running anything, and with `--explain` why missing cells are missing (the diagnosis is
//! [`qsweep_pipeline::status`]).

use super::pipeline_args::PipelineArgs;
use crate::json::{StatusRace, StatusReport};
use clap::Args;
use qsweep_pipeline::status::{reason_counts, MissingCell};

/// Arguments of `qsweep status`.
#[derive(Debug, Args)]
pub struct StatusArgs {
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    /// Print the counts as JSON.
    #[arg(long)]
    pub json: bool,
    /// For missing cells, show which resolved fields differ from the cached trial at the same grid
    /// position (same system, representation, algorithm, resolution, actions and seed); and for
    /// each folder of the report (reports/<name>, default formats), whether the next report
    /// recomputes it and why (its memo.json).
    #[arg(long)]
    pub explain: bool,
}

/// Run `qsweep status`.
pub fn run(a: StatusArgs) -> anyhow::Result<u8> {
    let plan = a.pipeline.plan()?;
    // A dry run before the first run stays useful: a missing cache means every trial is missing,
    // and status (read-only) does not create it.
    let store = a.pipeline.cache.existing_store()?;
    // `--explain`'s report folders are judged from the plan as planned (replayed by the report).
    let planned = (a.explain && !a.json && store.is_some()).then(|| plan.clone());
    let s = qsweep_pipeline::status::status(plan, store.as_ref(), a.explain)?;
    let v = StatusReport::of(&s);
    if a.json {
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        let width = s.plan.variants.iter().map(|v| v.id.len()).max().map_or(0, |w| w.max(7) + 1);
        // Experiment ids are usually numbers; a longer id widens its column.
        let ew = s.plan.experiments.iter().map(|e| e.id.len()).max().unwrap_or(0).max(4);
        if width > 0 {
            print!("{:<width$}", "variant");
        }
        println!(
            "{:<13} {:>ew$} {:<6} {:>6} {:>7} {:>7} {:>8}",
            "system", "exp", "repr", "cells", "trials", "cached", "missing"
        );
        for e in &v.experiments {
            if width > 0 {
                print!("{:<width$}", e.variant.as_deref().unwrap_or_default());
            }
            println!(
                "{:<13} {:>ew$} {:<6} {:>6} {:>7} {:>7} {:>8}",
                e.system, e.experiment, e.repr, e.cells, e.trials, e.cached, e.missing
            );
        }
        println!(
            "total: {} trials, {} cached, {} missing{} (cache: {}{})",
            v.trials,
            v.cached,
            v.missing,
            match v.running_elsewhere {
                0 => String::new(),
                n => format!(", {n} of them running elsewhere (another run on this cache)"),
            },
            a.pipeline.cache.name(),
            if store.is_none() { ", does not exist yet" } else { "" }
        );
        if let Some(race) = &v.race {
            print_race(race, width, ew);
        }
        for d in &s.damaged {
            println!("damaged segment: {d}");
        }
    }
    if let Some(cells) = &s.explanation {
        print_explanation(&s.plan, cells);
    }
    if let (Some(plan), Some(store)) = (planned, &store) {
        let dir = qsweep_report::default_dir(&plan);
        let keys = store.keys()?;
        let formats = qsweep_report::formats::Formats::default();
        let explained = qsweep_report::staleness(plan, store, &keys, &dir, formats)?;
        let folders = &explained.folders;
        let stale = folders.iter().filter(|(_, why)| why.is_some()).count();
        for (d, why) in folders {
            if let Some(why) = why {
                println!("report {} is recomputed by the next report: {why}", d.display());
            }
        }
        println!(
            "report folders: {} of {} up to date (their memo.json matches; default formats)",
            folders.len() - stale,
            folders.len()
        );
        print_stale_intervals(&explained);
    }
    Ok(qsweep_pipeline::error::exit::OK)
}

/// The cells whose intervals the next report computes, at most [`LISTED`] of them by name.
fn print_stale_intervals(e: &qsweep_report::Staleness) {
    const LISTED: usize = 20;
    for name in e.stale.iter().take(LISTED) {
        println!("interval computed by the next report (not in the statistics' memo: new trials, or never reported): {name}");
    }
    if e.stale.len() > LISTED {
        println!("... and {} more", e.stale.len() - LISTED);
    }
    println!(
        "cell intervals: {} of {} in the statistics' memo {}",
        e.intervals - e.stale.len(),
        e.intervals,
        e.memo.display()
    );
}

/// One line per missing cell, then how many cells each reason explains when there are several.
fn print_explanation(plan: &qsweep_pipeline::plan::Plan, cells: &[MissingCell]) {
    for m in cells {
        let e = &plan.experiments[m.experiment];
        let c = &e.cells[m.cell];
        let label = format!(
            "{}{} exp {} {} {}",
            e.variant.as_deref().map(|v| format!("[{v}] ")).unwrap_or_default(),
            e.system.name(),
            e.id,
            c.algorithm.name(),
            c.coords
                .iter()
                .map(|&v| qsweep_pipeline::declared::format_value(v))
                .collect::<Vec<_>>()
                .join("×")
        );
        println!("missing {label} ({} of {} seeds): {}", m.missing, m.trials, m.reason);
    }
    let reasons = reason_counts(cells);
    if reasons.len() > 1 {
        println!("summary of reasons:");
        for (why, n) in reasons {
            println!("  {n} cells: {why}");
        }
    }
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
