//! `qsweep verify`: read every cache segment in full, like `git fsck`; move damaged ones aside.

use super::pipeline_args::{cache_dir, require_cache};
use crate::cache::verify::QUARANTINE;
use crate::cache::Store;
use crate::error::exit;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `qsweep verify`.
#[derive(Debug, Args)]
pub struct VerifyArgs {
    /// Cache directory [env: QSWEEP_CACHE; default: cache].
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Only report damage; leave damaged segments where they are.
    #[arg(long)]
    pub no_quarantine: bool,
}

/// Run `qsweep verify`: exit 0 when every segment is intact, 1 when damage was found, 2 when the
/// cache does not exist.
pub fn run(a: VerifyArgs) -> anyhow::Result<u8> {
    let dir = cache_dir(a.cache.as_ref());
    require_cache(&dir)?;
    let store = Store::open(&dir)?;
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
    Ok(if report.damaged.is_empty() { exit::OK } else { exit::FAILURE })
}
