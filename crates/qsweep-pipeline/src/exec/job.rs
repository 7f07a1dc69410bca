//! One trial to run ([`Job`]): what the executor and its lease-aware scheduler ([`super::leased`])
//! both take, in a module of its own so that neither imports the other back.

use crate::cache::Key;
use crate::plan::Plan;
use qsweep_engine::TrialConfig;

/// A trial to run: configuration, seed and key.
#[derive(Debug, Clone, Copy)]
pub struct Job<'a> {
    /// Its configuration.
    pub config: &'a TrialConfig,
    /// Its seed.
    pub seed: u64,
    /// Its key.
    pub key: Key,
}

/// The distinct trials of `plan` as jobs, in plan order ([`Plan::unique_trials`]).
pub fn jobs(plan: &Plan) -> Vec<Job<'_>> {
    plan.unique_trials().into_iter().map(|(config, t)| Job { config, seed: t.seed, key: t.key }).collect()
}
