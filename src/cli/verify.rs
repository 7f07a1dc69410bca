//! `qsweep verify`: read every cache segment in full, like `git fsck` (the engine's and the
//! program folders'); move damaged ones aside; with `--recompute N`, run N stored trials again and
//! compare their outcomes with the rows (a program pipeline's, given as `PIPELINE`, in fresh
//! processes of its program).

use super::pipeline_args::CacheArgs;
use clap::Args;
use qsweep_pipeline::cache::store::Store;
use qsweep_pipeline::cache::verify::QUARANTINE;
use qsweep_pipeline::cache::ENGINE_VERSION;
use qsweep_pipeline::error::exit;
use std::path::{Path, PathBuf};

/// Arguments of `qsweep verify`.
#[derive(Debug, Args)]
pub struct VerifyArgs {
    /// A program pipeline whose stored trials `--recompute` reruns (its command and inputs are
    /// needed); without one, `--recompute` reruns the engine's trials.
    #[arg(value_name = "PIPELINE")]
    pub pipeline: Option<PathBuf>,
    #[command(flatten)]
    pub cache: CacheArgs,
    /// Only report damage; leave damaged segments where they are.
    #[arg(long)]
    pub no_quarantine: bool,
    /// Also recompute N stored trials, drawn at random, and compare every outcome field with the
    /// stored row (exit 1 naming each key that differs): checks that this machine reproduces the
    /// cache. 500 trials of the committed cache take about half a minute on 2 cores.
    #[arg(long, value_name = "N")]
    pub recompute: Option<usize>,
    /// Seed of the `--recompute` draw (the same seed draws the same trials from the same cache).
    #[arg(long, value_name = "S", default_value_t = 0, requires = "recompute")]
    pub seed: u64,
    /// Also check the report memos (memo.json) under this directory: each sealed, each file it
    /// lists with its recorded digest [default: reports, when it exists].
    #[arg(long, value_name = "DIR")]
    pub reports: Option<std::path::PathBuf>,
}

/// Run `qsweep verify`: exit 0 when every segment is intact, 1 when damage was found, 2 when the
/// cache does not exist.
pub fn run(a: VerifyArgs) -> anyhow::Result<u8> {
    let program = match &a.pipeline {
        Some(p) if !p.is_file() => {
            return Err(qsweep_pipeline::error::user_error(format!(
                "pipeline {} does not exist; give the program pipeline whose trials --recompute reruns",
                p.display()
            )))
        }
        Some(p) if super::program::is_program_file(p) => Some(p.clone()),
        Some(p) => {
            return Err(qsweep_pipeline::error::user_error(format!(
            "{} is not a program pipeline (it declares no `program:`): `qsweep verify --recompute N` draws \
                 the engine's trials from the whole cache; leave the pipeline out",
            p.display()
        )))
        }
        None => None,
    };
    let store = a.cache.required_store()?;
    let mut ok = check_segments(&store, a.no_quarantine)?;
    ok &= check_program_folders(&store, a.no_quarantine)?;
    // The statistics' memos: a damaged one loses nothing (the next report recomputes it), but it
    // is damage all the same, like a damaged segment.
    ok &= check_stats_memos(&store);
    ok &= check_trial_parts(&store);
    let reports = a.reports.clone().unwrap_or_else(|| PathBuf::from("reports"));
    if reports.is_dir() {
        ok &= check_report_memos(&reports);
    }
    match (a.recompute, &program) {
        (Some(n), Some(p)) => ok &= super::program::recompute(p, &a.cache, n, a.seed)?,
        (Some(n), None) => ok &= recompute(&store, n, a.seed)?,
        (None, _) => {}
    }
    Ok(if ok { exit::OK } else { exit::FAILURE })
}

/// Read every segment, print the damaged ones (moved aside unless `no_quarantine`) and the
/// totals; whether all are intact.
fn check_segments(store: &Store, no_quarantine: bool) -> anyhow::Result<bool> {
    let report = store.verify()?;
    for d in &report.damaged {
        println!("damaged: {d}");
        if !no_quarantine {
            let to = store.quarantine(&d.path)?;
            println!("  moved to {}", to.display());
        }
    }
    println!(
        "{} segments, {} rows ({} distinct trials) intact, {} damaged{}",
        report.segments,
        report.rows,
        report.distinct,
        report.damaged.len(),
        if report.damaged.is_empty() || no_quarantine {
            String::new()
        } else {
            format!("; their trials run again on the next `qsweep run` (segments kept in {QUARANTINE}/)")
        }
    );
    Ok(report.damaged.is_empty())
}

/// Read every segment of the program folders (`<cache>/_programs/*/`), print the damaged ones
/// (moved aside into their folder's quarantine unless `no_quarantine`) and, when there are any
/// folders, the totals; whether all are intact.
fn check_program_folders(store: &Store, no_quarantine: bool) -> anyhow::Result<bool> {
    let report = qsweep_pipeline::program::verify::check(store.dir())?;
    if report.folders == 0 {
        return Ok(true);
    }
    for d in &report.damaged {
        println!("damaged: {d}");
        if !no_quarantine {
            let folder = d.path.parent().unwrap_or(store.dir());
            let to = Store::open(folder)?.quarantine(&d.path)?;
            println!("  moved to {}", to.display());
        }
    }
    println!(
        "program rows: {} folders, {} segments, {} rows ({} distinct trials) intact, {} damaged{}",
        report.folders,
        report.segments,
        report.rows,
        report.distinct,
        report.damaged.len(),
        if report.damaged.is_empty() || no_quarantine {
            String::new()
        } else {
            format!("; their trials run again on the next `qsweep run` (segments kept in their folder's {QUARANTINE}/)")
        }
    );
    Ok(report.damaged.is_empty())
}

/// Check and print the cache's statistics' memos; whether none is damaged.
fn check_stats_memos(store: &Store) -> bool {
    let d = qsweep_report::memo::stats::check(store.dir());
    for (p, why) in &d.damaged {
        println!("damaged statistics' memo: {} ({why}; the next report recomputes it)", p.display());
    }
    println!("statistics' memos: {} intact ({} entries), {} damaged", d.intact, d.entries, d.damaged.len());
    d.damaged.is_empty()
}

/// Check and print the cache's encoded trial parts; whether none is damaged.
fn check_trial_parts(store: &Store) -> bool {
    let parts = qsweep_report::memo::parts::check(store.dir());
    for p in &parts.damaged {
        println!("damaged trial part: {} (the next report encodes it again)", p.display());
    }
    println!(
        "trial parts: {} whole, {} damaged, {} without a recorded blake3 (encoded again when next used)",
        parts.whole,
        parts.damaged.len(),
        parts.unrecorded
    );
    parts.damaged.is_empty()
}

/// Check and print the report memos under `reports`; whether none is damaged or differs.
fn check_report_memos(reports: &Path) -> bool {
    let m = qsweep_report::memo::folders::check_tree(reports);
    for (p, why) in &m.damaged {
        println!("damaged memo: {} ({why})", p.display());
    }
    for p in &m.differing {
        println!(
            "differs from its memo: {} (edited since written; the next report rewrites it)",
            p.display()
        );
    }
    println!(
        "report memos in {}: {} intact, {} damaged, {} with edited files, {} listed files not there (the next \
         report writes them)",
        reports.display(),
        m.intact,
        m.damaged.len(),
        m.differing.len(),
        m.missing.len()
    );
    m.damaged.is_empty() && m.differing.is_empty()
}

/// Recompute `n` stored trials drawn with `seed` and print how they compare with their rows;
/// whether all agree (false when there was nothing of this engine to recompute).
fn recompute(store: &Store, n: usize, seed: u64) -> anyhow::Result<bool> {
    let started = std::time::Instant::now();
    let r = store.recompute(n, seed)?;
    if n > 0 && r.checked == 0 {
        // Nothing to check is not a pass: say why, and fail.
        println!(
            "recompute: no trial of engine {} to recompute ({} trials of other engine versions are stored; \
             `qsweep run` a pipeline with this binary to compute them{})",
            ENGINE_VERSION,
            r.other_engine,
            if store.dir().join(qsweep_pipeline::program::rows::PROGRAMS_DIR).is_dir() {
                "; a program pipeline's trials: `qsweep verify PIPELINE --recompute N`"
            } else {
                ""
            }
        );
        return Ok(false);
    }
    for m in &r.differing {
        println!("differs: {} ({})", m.key, m.fields.join(", "));
    }
    let others = if r.other_engine > 0 {
        format!(" ({} trials of other engine versions left out)", r.other_engine)
    } else {
        String::new()
    };
    println!(
        "recomputed {} of {} trials of engine {} (draw seed {}) in {:.1} s: {}{others}",
        r.checked,
        r.eligible,
        ENGINE_VERSION,
        seed,
        started.elapsed().as_secs_f64(),
        if r.differing.is_empty() {
            format!("all {} agree with the stored rows", r.checked)
        } else {
            format!("{} differ from the stored rows", r.differing.len())
        }
    );
    Ok(r.differing.is_empty())
}
