//! `qsweep trial`'s flags: the system, representation and algorithm, and every setting a
//! pipeline could give the cell (Table II defaults where left out).

use super::args;
use clap::Args;
use qsweep_engine::config::TieBreak;
use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::Algorithm;

/// Arguments of `qsweep trial`.
#[derive(Debug, Args)]
pub struct TrialArgs {
    /// System: ball-beam, cart-pole or mountain-car.
    #[arg(long, value_parser = args::system)]
    pub env: SystemKind,
    /// State representation.
    #[arg(long, value_enum)]
    pub repr: ReprKind,
    /// Bins or fuzzy sets per state variable, comma-separated in state order (one value = all variables).
    #[arg(long, value_parser = args::count_list)]
    pub resolution: args::Counts,
    /// Number of actions n of A_n (eq. 22) [default: the system's fixed set: 2 cart-pole, 3 otherwise].
    #[arg(long, value_parser = args::action_count)]
    pub actions: Option<u32>,
    /// Learning algorithm.
    #[arg(long, value_enum)]
    pub algorithm: Algorithm,
    /// Seed of the trial's random stream.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Exploration rate ε [default: Table II].
    #[arg(long, value_parser = args::unit)]
    pub epsilon: Option<f64>,
    /// Discount γ [default: Table II].
    #[arg(long, value_parser = args::unit)]
    pub gamma: Option<f64>,
    /// Learning rate α > 0 [default: Table II].
    #[arg(long, value_parser = args::positive)]
    pub alpha: Option<f64>,
    /// Trace decay λ in [0, 1] [default: Table II; ignored by q0].
    #[arg(long, value_parser = args::unit)]
    pub lambda: Option<f64>,
    /// Initial Q value [default: 0].
    #[arg(long, value_parser = args::finite, allow_hyphen_values = true)]
    pub q_init: Option<f64>,
    /// Greedy tie-breaking [default: random].
    #[arg(long, value_enum)]
    pub tie_break: Option<TieBreak>,
    /// Use replacing traces instead of accumulating ones.
    #[arg(long)]
    pub replacing_traces: bool,
    /// Watkins's Q(λ): clear traces after an exploratory action.
    #[arg(long)]
    pub watkins_cut: bool,
    /// Fuzzy σ as a multiple of the centre spacing [default: 0.4247, neighbours cross at 0.5].
    #[arg(long, value_parser = args::positive)]
    pub width: Option<f64>,
    /// Fuzzy memberships below this are skipped; 0 is exact [default: 1e-3].
    #[arg(long, value_parser = args::sub_unit)]
    pub prune: Option<f64>,
    /// Q(λ) traces below this are dropped; 0 keeps every trace [default: 1e-10].
    #[arg(long, value_parser = args::sub_unit)]
    pub trace_cutoff: Option<f64>,
    /// Episode cap [default: 1000].
    #[arg(long, value_parser = args::episodes)]
    pub max_episodes: Option<u32>,
    /// Step cap over the whole trial [default: 10,000,000].
    #[arg(long, value_parser = args::at_least_one)]
    pub max_total_steps: Option<u64>,
    /// Steps without failure that reach the goal (survival tasks) [default: 100,000].
    #[arg(long, value_parser = args::steps)]
    pub balance_steps: Option<u64>,
    /// Override a physical parameter, e.g. --param gravity=9.8 (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = args::param)]
    pub params: Vec<(String, f64)>,
    /// Set any pipeline setting, as in a pipeline's `--set` (repeatable; applied after the flags):
    /// a bare setting name means `defaults.NAME` (`--set q_init=-1`), `success.`, `params.` and
    /// `ranges.` paths are the system's (`--set ranges.x_dot=[-1,1]`), others are full pipeline
    /// paths (`--set systems.cart-pole.success.steps=200`).
    #[arg(long = "set", value_name = "PATH=VALUE", allow_hyphen_values = true)]
    pub set: Vec<String>,
    /// Print the outcome (with every episode length) and the resolved configuration as JSON.
    #[arg(long)]
    pub json: bool,
}
