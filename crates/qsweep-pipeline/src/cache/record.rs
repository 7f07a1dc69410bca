//! One stored trial: its key, resolved configuration, seed and outcome.

use super::key::{canonical_config, Key, ENGINE_VERSION};
use qsweep_engine::{Outcome, TrialConfig};

/// A trial as stored in the cache: one Parquet row.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialRecord {
    /// Content address of (config, seed, engine version).
    pub key: Key,
    /// Engine version the outcome was computed with.
    pub engine_version: u32,
    /// The resolved configuration.
    pub config: TrialConfig,
    /// The trial's seed.
    pub seed: u64,
    /// What the trial produced.
    pub outcome: Outcome,
    /// Wall-clock seconds the trial took (informational; not part of the result).
    pub seconds: f64,
    /// CPU seconds of the thread that ran the trial, which load on the machine does not inflate
    /// (a trial in lockstep: its equal share of its loop's while it was in it; `None` in rows
    /// written before qsweep recorded it, and where the OS cannot tell).
    pub cpu_seconds: Option<f64>,
}

impl TrialRecord {
    /// A record for a freshly computed trial.
    pub fn new(config: TrialConfig, seed: u64, outcome: Outcome, seconds: f64) -> Self {
        Self {
            key: Key::of(&config, seed),
            engine_version: ENGINE_VERSION,
            config,
            seed,
            outcome,
            seconds,
            cpu_seconds: None,
        }
    }

    /// The record with the trial's thread CPU time.
    pub fn with_cpu_seconds(mut self, cpu_seconds: Option<f64>) -> Self {
        self.cpu_seconds = cpu_seconds;
        self
    }

    /// The canonical configuration encoding stored as `config_json`.
    pub fn config_json(&self) -> String {
        canonical_config(&self.config)
    }
}
