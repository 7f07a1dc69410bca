//! Which fuzzy trials take the dense path ([`DenseFuzzy`], the window grid) and the switch that
//! turns it off: a choice of speed only, since either path gives a trial the same bits
//! (`dense_tests.rs`), measured cell by cell (notes/engine-notes.md, "The dense fuzzy path").

use super::config::{LearnerConfig, TrialConfig};
use super::learner::grid_row_len;
use super::repr::{DenseFuzzy, Fuzzy, ReprKind, Representation};

/// Whether fuzzy trials take the dense path where it pays ([`dense_pays`]): `QSWEEP_DENSE` is not
/// `off` (it never changes a result, only the speed; `off` is there to compare).
pub fn dense_enabled() -> bool {
    static ON: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ON.get_or_init(|| {
        std::env::var("QSWEEP_DENSE")
            .map_or(true, |v| !matches!(v.trim().to_ascii_lowercase().as_str(), "off" | "0" | "no" | "false"))
    })
}

/// Whether a fuzzy rule base takes the dense path ([`DenseFuzzy`]) under `learner` with
/// `actions`: two variables whose prune windows hold at most four sets (the default width and
/// prune, whatever the number of sets), at most 16 actions (its Q(s, ·) kernels are unrolled up to
/// that many), and with eligibility traces a table of at most [`DENSE_SWEEP_MAX_PARAMS`]
/// parameters. That is where it measured less time a step than the windowed path (docs/speed.md);
/// either path gives the same bits.
pub(crate) fn dense_pays(fuzzy: &Fuzzy, actions: u32, learner: &LearnerConfig) -> bool {
    let traces = learner.gamma * learner.lambda != 0.0;
    let params = fuzzy.n_features() * grid_row_len(actions as usize);
    actions <= 16 && DenseFuzzy::fits(fuzzy) && (!traces || params <= DENSE_SWEEP_MAX_PARAMS)
}

/// The most parameters (rules × [`grid_row_len`]) of a dense trial with eligibility traces, all
/// of which each step sweeps: past it (Mountain Car Q(λ) 9² and 10² with three actions, four
/// values a row) the windowed path, which sweeps only where traces live, measured as fast or
/// faster.
const DENSE_SWEEP_MAX_PARAMS: usize = 256;

/// Whether trial `cfg` takes the dense fuzzy path ([`DenseFuzzy`]) when it runs.
pub fn takes_dense_path(cfg: &TrialConfig) -> bool {
    let r = &cfg.repr;
    r.kind == ReprKind::Fuzzy
        && dense_enabled()
        && r.resolution.len() == 2
        && dense_pays(&Fuzzy::new(&r.resolution, &r.ranges, r.width, r.prune), cfg.actions, &cfg.learner)
}
