//! `qsweep verify`: read every cache segment in full, like `git fsck`; move damaged ones aside;
//! with `--recompute N`, run N stored trials again and compare their outcomes with the rows.

use super::pipeline_args::CacheArgs;
use clap::Args;
use qsweep_pipeline::cache::verify::QUARANTINE;
use qsweep_pipeline::error::exit;

/// Arguments of `qsweep verify`.
#[derive(Debug, Args)]
pub struct VerifyArgs {
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
    let store = a.cache.required_store()?;
    let report = store.verify()?;
    for d in &report.damaged {
        println!("damaged: {d}");
        if !a.no_quarantine {
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
        if report.damaged.is_empty() || a.no_quarantine {
            String::new()
        } else {
            format!("; their trials run again on the next `qsweep run` (segments kept in {QUARANTINE}/)")
        }
    );
    let mut ok = report.damaged.is_empty();
    // The statistics' memos: a damaged one loses nothing (the next report recomputes it), but it
    // is damage all the same, like a damaged segment.
    let d = qsweep_report::memo::stats::check(store.dir());
    for (p, why) in &d.damaged {
        println!("damaged statistics' memo: {} ({why}; the next report recomputes it)", p.display());
    }
    println!("statistics' memos: {} intact ({} entries), {} damaged", d.intact, d.entries, d.damaged.len());
    ok &= d.damaged.is_empty();
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
    ok &= parts.damaged.is_empty();
    let reports = a.reports.clone().unwrap_or_else(|| std::path::PathBuf::from("reports"));
    if reports.is_dir() {
        let m = qsweep_report::memo::folders::check_tree(&reports);
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
        ok &= m.damaged.is_empty() && m.differing.is_empty();
    }
    if let Some(n) = a.recompute {
        let started = std::time::Instant::now();
        let r = store.recompute(n, a.seed)?;
        if n > 0 && r.checked == 0 {
            // Nothing to check is not a pass: say why, and fail.
            println!(
                "recompute: no trial of engine {} to recompute ({} trials of other engine versions are stored; \
                 `qsweep run` a pipeline with this binary to compute them)",
                qsweep_pipeline::cache::ENGINE_VERSION,
                r.other_engine
            );
            return Ok(exit::FAILURE);
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
            qsweep_pipeline::cache::ENGINE_VERSION,
            a.seed,
            started.elapsed().as_secs_f64(),
            if r.differing.is_empty() {
                format!("all {} agree with the stored rows", r.checked)
            } else {
                format!("{} differ from the stored rows", r.differing.len())
            }
        );
        ok &= r.differing.is_empty();
    }
    Ok(if ok { exit::OK } else { exit::FAILURE })
}
