//! `qsweep cache push` / `pull`: copy the trials one cache lacks from another, by key
//! (`qsweep_pipeline::cache::remote::transfer`): a directory and a bucket, or two directories.

use super::pipeline_args::CacheArgs;
use clap::{Args, Subcommand};
use qsweep_pipeline::cache::remote::transfer::{copy, Copied};
use qsweep_pipeline::cache::store::Store;
use qsweep_pipeline::error::exit;
use std::path::PathBuf;

/// `qsweep cache`.
#[derive(Debug, Args)]
pub struct CacheCommand {
    /// What to do.
    #[command(subcommand)]
    pub action: Action,
}

/// `qsweep cache`'s actions.
#[derive(Debug, Subcommand)]
pub enum Action {
    /// Copy the trials a cache directory holds and a bucket (or another directory) lacks into it.
    Push {
        /// The cache directory, which must exist.
        dir: PathBuf,
        /// Where to: a bucket cache, s3://BUCKET/PREFIX, or a cache directory (created if needed).
        to: String,
        /// Count what would be copied; copy nothing.
        #[arg(long)]
        dry_run: bool,
    },
    /// Copy the trials a bucket (or another directory) holds and a cache directory lacks into it.
    Pull {
        /// Where from: a bucket cache, s3://BUCKET/PREFIX, or a cache directory, which must exist.
        from: String,
        /// The cache directory (created if needed).
        dir: PathBuf,
        /// Count what would be copied; copy nothing.
        #[arg(long)]
        dry_run: bool,
    },
}

fn open(cache: PathBuf) -> CacheArgs {
    CacheArgs { cache: Some(cache) }
}

/// Run `qsweep cache`.
pub fn run(a: CacheCommand) -> anyhow::Result<u8> {
    let (from, to, dry_run, verb): (Store, Store, bool, &str) = match a.action {
        Action::Push { dir, to, dry_run } => {
            let to = open(PathBuf::from(to));
            (
                open(dir).required_store()?,
                if dry_run { to.store()? } else { to.writable_store()? },
                dry_run,
                "pushed",
            )
        }
        Action::Pull { from, dir, dry_run } => {
            let to = open(dir);
            (
                open(PathBuf::from(from)).required_store()?,
                if dry_run { to.store()? } else { to.writable_store()? },
                dry_run,
                "pulled",
            )
        }
    };
    let c = copy(&from, &to, dry_run)?;
    print(&c, verb, dry_run, &to);
    Ok(exit::OK)
}

fn print(c: &Copied, verb: &str, dry_run: bool, to: &Store) {
    for d in &c.damaged {
        eprintln!("warning: skipped unreadable segment (run `qsweep verify`): {d}");
    }
    let verb = if dry_run { format!("would have {verb}") } else { verb.to_string() };
    println!(
        "{verb} {} trials to {} in {} segments ({:.2} MiB); {} of the {} trials were there already",
        c.copied,
        to.location(),
        c.segments,
        c.bytes as f64 / (1 << 20) as f64,
        c.present,
        c.source_trials
    );
}
