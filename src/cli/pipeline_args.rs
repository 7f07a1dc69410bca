//! Arguments shared by the pipeline commands (`run`, `status`, `report`): the pipeline file,
//! `--set` overrides, the cache directory and the size confirmation.

use crate::cache::store::Store;
use crate::error::user_error;
use crate::plan::{plan_variants, Plan, DEFAULT_MAX_TRIALS};
use crate::spec::{load, Override};
use clap::Args;
use std::path::PathBuf;

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
    /// Cache directory [env: QSWEEP_CACHE; default: cache].
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
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

    /// The cache directory: `--cache`, else `$QSWEEP_CACHE`, else `cache`.
    pub fn cache_dir(&self) -> PathBuf {
        cache_dir(self.cache.as_ref())
    }

    /// Open the cache store.
    pub fn store(&self) -> anyhow::Result<Store> {
        let dir = self.cache_dir();
        Store::open(&dir).map_err(|e| anyhow::anyhow!("cache {}: {e}", dir.display()))
    }
}

/// Resolve the cache directory from an explicit flag, the environment, or the default.
pub fn cache_dir(flag: Option<&PathBuf>) -> PathBuf {
    flag.cloned()
        .or_else(|| std::env::var_os("QSWEEP_CACHE").filter(|v| !v.is_empty()).map(PathBuf::from))
        .unwrap_or_else(|| PathBuf::from("cache"))
}
