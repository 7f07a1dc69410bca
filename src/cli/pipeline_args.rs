//! Arguments shared by the commands: the pipeline file, `--set` overrides and the size
//! confirmation of the pipeline commands (`run`, `status`, `report`, `slurm`), and the cache
//! directory of every command that reads or writes a cache (those, `bench`, `verify`, `gc`), or
//! its bucket (`s3://BUCKET/PREFIX`, `qsweep_pipeline::cache::remote`).

use clap::Args;
use qsweep_pipeline::cache::remote;
use qsweep_pipeline::cache::store::Store;
use qsweep_pipeline::declared::{load, Override};
use qsweep_pipeline::error::user_error;
use qsweep_pipeline::plan::{plan_variants, Plan, DEFAULT_MAX_TRIALS};
use qsweep_report::formats::{Format, Formats, DEFAULT_FORMATS};
use qsweep_report::{ReportOptions, ReportWritten};
use std::path::{Path, PathBuf};

/// Pipeline file, overrides and cache location.
#[derive(Debug, Args)]
pub struct PipelineArgs {
    /// Pipeline file, e.g. pipelines/quick.yaml.
    pub pipeline: PathBuf,
    /// Override a field by its dotted YAML path, e.g. --set seeds=3 or
    /// --set systems.cart-pole.crisp.alpha=0.05 (repeatable; list items by index).
    #[arg(long = "set", value_name = "PATH=VALUE")]
    pub set: Vec<String>,
    /// Only this variant of the pipeline's `variants:` (repeatable) [default: all of them].
    #[arg(long = "variant", value_name = "ID")]
    pub variant: Vec<String>,
    #[command(flatten)]
    pub cache: CacheArgs,
    /// Accept a plan larger than 200,000 trials.
    #[arg(long)]
    pub yes: bool,
}

impl PipelineArgs {
    /// Load, override and expand the pipeline.
    pub fn plan(&self) -> anyhow::Result<Plan> {
        let overrides =
            self.set.iter().map(|s| Override::parse(s).map_err(user_error)).collect::<Result<Vec<_>, _>>()?;
        let loaded = load(&self.pipeline, &overrides)?;
        let plan = plan_variants(&loaded, (!self.yes).then_some(DEFAULT_MAX_TRIALS), &self.variant)?;
        for w in &plan.warnings {
            eprintln!("warning: {w}");
        }
        Ok(plan)
    }
}

/// `--cache DIR`, and how a command opens it.
#[derive(Debug, Clone, Default, Args)]
pub struct CacheArgs {
    /// Cache directory, or a bucket as s3://BUCKET/PREFIX (a build with the `s3` feature)
    /// [env: QSWEEP_CACHE; default: cache].
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
}

impl CacheArgs {
    /// The cache as given: `--cache`, else `$QSWEEP_CACHE`, else `cache`.
    pub fn dir(&self) -> PathBuf {
        self.cache
            .clone()
            .or_else(|| std::env::var_os("QSWEEP_CACHE").filter(|v| !v.is_empty()).map(PathBuf::from))
            .unwrap_or_else(|| PathBuf::from("cache"))
    }

    /// The bucket's address when the cache is one (`s3://…`).
    pub fn bucket(&self) -> Option<String> {
        let dir = self.dir();
        dir.to_str().filter(|d| remote::is_remote(d)).map(str::to_string)
    }

    /// The cache as its user named it, for messages: the directory or the bucket.
    pub fn name(&self) -> String {
        self.bucket().unwrap_or_else(|| self.dir().display().to_string())
    }

    /// The cache directory of a program pipeline, whose rows live in `_programs/` of a directory:
    /// a bucket holds engine pipelines only.
    pub fn program_dir(&self) -> anyhow::Result<PathBuf> {
        match self.bucket() {
            Some(url) => Err(user_error(format!(
                "cache {url}: a bucket holds the trials of engine pipelines only; give a program \
                 pipeline a cache directory with --cache DIR (docs/cache-in-a-bucket.md)"
            ))),
            None => Ok(self.dir()),
        }
    }

    /// Open the cache store, creating its directory if needed (`run`); a bucket is connected to
    /// and checked (it must exist: qsweep never creates a bucket).
    pub fn store(&self) -> anyhow::Result<Store> {
        if let Some(url) = self.bucket() {
            return Store::open_bucket(&url);
        }
        let dir = self.dir();
        if dir.exists() && !dir.is_dir() {
            return Err(user_error(format!(
                "cache {} is a file, not a directory; give a directory with --cache DIR (or QSWEEP_CACHE), or move the file away",
                dir.display()
            )));
        }
        Store::open(&dir).map_err(|e| unwritable(&dir, &e))
    }

    /// The cache, created if needed, checked to be writable (`run`): a cache that cannot be
    /// written is a usage error found before any trial runs, not an I/O error at the first flush.
    pub fn writable_store(&self) -> anyhow::Result<Store> {
        let store = self.store()?;
        if let Some(remote) = store.remote() {
            let probe = format!("{}probe.{}", qsweep_pipeline::atomic::TEMP_PREFIX, std::process::id());
            remote.put(&probe, b"").map_err(|e| {
                user_error(format!(
                    "cache {}: cannot write to the bucket ({e:#}); check its permissions",
                    remote.url()
                ))
            })?;
            let _ = remote.delete(&probe);
            return Ok(store);
        }
        let probe =
            store.dir().join(format!("{}probe.{}", qsweep_pipeline::atomic::TEMP_PREFIX, std::process::id()));
        std::fs::File::create(&probe).map_err(|e| unwritable(store.dir(), &e))?;
        let _ = std::fs::remove_file(&probe);
        Ok(store)
    }

    /// The cache if its directory exists, else `None` (treated as empty): the rule of the
    /// commands that only read a cache and never create one (`status`, `slurm`, `bench`).
    pub fn existing_store(&self) -> anyhow::Result<Option<Store>> {
        if self.bucket().is_some() {
            return self.store().map(Some);
        }
        self.dir().is_dir().then(|| self.store()).transpose()
    }

    /// The cache, which must exist (a usage error otherwise, see [`require_cache`]): the rule of
    /// the commands that read or rewrite a cache an earlier run made (`report`, `verify`, `gc`).
    pub fn required_store(&self) -> anyhow::Result<Store> {
        if self.bucket().is_some() {
            return self.store();
        }
        require_cache(&self.dir())?;
        self.store()
    }
}

/// The usage error (exit 2) for a cache directory that cannot be made or written, and what to do.
pub fn unwritable(dir: &Path, e: &std::io::Error) -> anyhow::Error {
    let what = match e.kind() {
        std::io::ErrorKind::PermissionDenied | std::io::ErrorKind::ReadOnlyFilesystem => "cannot be written",
        std::io::ErrorKind::NotADirectory | std::io::ErrorKind::AlreadyExists => {
            "cannot be made (a file is in the way)"
        }
        _ => return anyhow::anyhow!("cache {}: {e}", dir.display()),
    };
    user_error(format!(
        "cache {} {what} ({e}); give a directory you can write with --cache DIR (or QSWEEP_CACHE), or fix its permissions",
        dir.display()
    ))
}

/// Fail with a usage error (exit 2) unless `dir` is an existing directory: the read-only
/// commands (`report`, `verify`, `gc`) never create a cache, and a missing one is almost always a
/// mistyped `--cache`/`QSWEEP_CACHE` or the wrong working directory.
fn require_cache(dir: &Path) -> anyhow::Result<()> {
    if dir.is_dir() {
        return Ok(());
    }
    let what = if dir.exists() { "is not a directory" } else { "does not exist" };
    Err(user_error(format!(
        "cache {} {what}; give the cache of an earlier `qsweep run` with --cache DIR or QSWEEP_CACHE",
        dir.display()
    )))
}

/// Where and how to write the report (`run` and `report`).
#[derive(Debug, Args)]
pub struct ReportFlags {
    /// Report directory [default: reports/<pipeline name>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// What the report writes, comma-separated: md (table3.md, README.md), csv, tex, cells
    /// (cells.parquet), trials (trials.parquet), svg, png (figures), html (index.html).
    #[arg(long, value_name = "LIST", value_delimiter = ',', default_value = DEFAULT_FORMATS)]
    pub formats: Vec<Format>,
    /// Ignore the report folders' memos (memo.json) and recompute every folder; a file is still
    /// rewritten only when its bytes change.
    #[arg(long)]
    pub rebuild: bool,
}

impl ReportFlags {
    /// The report options for `plan`.
    pub fn options(&self, plan: &Plan, force: bool) -> ReportOptions {
        ReportOptions {
            dir: self.out.clone().unwrap_or_else(|| qsweep_report::default_dir(plan)),
            formats: Formats::of(&self.formats),
            force,
            rebuild: self.rebuild,
        }
    }
}

/// Warn about each damaged cache segment that was moved aside (`run` and `report` alike).
pub fn warn_quarantined(scan: &qsweep_pipeline::run::Scan) {
    for (d, to) in &scan.quarantined {
        eprintln!("warning: damaged cache segment {d}; moved to {}", to.display());
    }
}

/// The report's closing lines.
pub fn print_report(o: &ReportWritten, opts: &ReportOptions) {
    let s = &o.summary;
    let page = if opts.formats.has(Format::Html) { "index.html" } else { "" };
    println!(
        "report: {} ({} of {} planned trials present, {} of {} cells; a trial counts once per cell and variant \
         that uses it, the distinct trials are the `executed`/`cached` counts; cells: {} recomputed, {} reused; \
         intervals: {} computed, {} reused; files: {} rewritten, {} unchanged)",
        opts.dir.join(page).display(),
        s.trials_cached,
        s.trials_planned,
        s.cells_with_trials,
        s.cells,
        o.cells_recomputed,
        o.cells_reused,
        o.statistics.computed,
        o.statistics.reused,
        o.files_written,
        o.files_unchanged,
    );
    for w in &o.warnings {
        eprintln!("warning: {w}");
    }
    for r in &o.replaced {
        println!("replaced {r}");
    }
    if !o.removed.is_empty() {
        println!("removed {} files the earlier report wrote and this one does not", o.removed.len());
    }
}
