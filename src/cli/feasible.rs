//! `qsweep feasible`: the longest survival any deterministic policy of a small crisp table reaches
//! from the start state (an exhaustive search; see `qsweep_engine::feasible`), with a policy that reaches it.

use super::args;
use super::simulate::env_params;
use crate::json::FeasibleReport as Report;
use clap::Args;
use qsweep_engine::config::TrialConfig;
use qsweep_engine::env::{BeamControl, EnvParams, StartKind, State, SystemKind};
use qsweep_engine::feasible::{first_start, policy_cells, search};
use qsweep_engine::repr::{Binning, ReprKind};
use qsweep_engine::Algorithm;
use qsweep_pipeline::error::user_error;

/// Arguments of `qsweep feasible`.
#[derive(Debug, Args)]
#[command(after_help = "Example: no policy over Cart-Pole's 16 midpoint cells balances long:\n  \
    qsweep feasible --env cart-pole --resolution 2 --actions 2\n\
    With a zero-force third action, one balances 100,000 steps:\n  \
    qsweep feasible --env cart-pole --resolution 2 --actions 3\n\
    Velocity splits moved to -0.4 (ranges centred there):\n  \
    qsweep feasible --env cart-pole --resolution 2 --range x_dot=-2.4,1.6 --range theta_dot=-2.4,1.6")]
pub struct FeasibleArgs {
    /// Survival system: cart-pole or ball-beam.
    #[arg(long, value_parser = args::system)]
    pub env: SystemKind,
    /// Bins per state variable, comma-separated in state order (one value = all variables).
    #[arg(long, value_parser = args::count_list)]
    pub resolution: args::Counts,
    /// Number of actions n of A_n (eq. 22) [default: the system's fixed set: 2 cart-pole, 3 ball-beam].
    #[arg(long, value_parser = args::action_count)]
    pub actions: Option<u32>,
    /// Override a physical parameter, e.g. --param gravity=9.8 (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = args::param)]
    pub params: Vec<(String, f64)>,
    /// Ball-Beam only: what an action sets, the beam angle or its rate (the parameter `control`)
    /// [default: angle].
    #[arg(long, value_enum)]
    pub control: Option<BeamControl>,
    /// Bin range of one variable, e.g. --range x_dot=-3,3 (repeatable) [default: the pipeline defaults].
    #[arg(long = "range", value_name = "VAR=LO,HI", allow_hyphen_values = true)]
    pub ranges: Vec<String>,
    /// Where the bin edges lie (the pipeline setting `binning`).
    #[arg(long, value_enum, default_value = "midpoint")]
    pub binning: Binning,
    /// Start state: fixed, or the first start a trial with --seed draws under `start: gym`.
    #[arg(long, value_enum, default_value = "fixed")]
    pub start: StartKind,
    /// Seed whose first gym start is searched from (with --start gym).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Explicit start state, comma-separated in state order (overrides --start).
    #[arg(long, value_parser = args::finite_list, allow_hyphen_values = true)]
    pub state: Option<args::Floats>,
    /// Survival goal: stop as soon as a policy survives this many steps.
    #[arg(long, default_value_t = 100_000)]
    pub max_steps: u64,
    /// Most action assignments to try; beyond it the answer is a lower bound.
    #[arg(long, default_value_t = 50_000_000)]
    pub max_nodes: u64,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

fn parse_range(system: SystemKind, s: &str) -> anyhow::Result<(usize, [f64; 2])> {
    let bad = || user_error(format!("--range: '{s}' is not VAR=LO,HI (e.g. x_dot=-3,3)"));
    let (name, value) = s.split_once('=').ok_or_else(bad)?;
    let j = qsweep_pipeline::declared::variable_index(system, name.trim())
        .map_err(|e| user_error(format!("--range: {e}")))?;
    let v = args::finite_list(value).map_err(|e| user_error(format!("--range {s}: {e}")))?.0;
    match v[..] {
        [lo, hi] if lo < hi => Ok((j, [lo, hi])),
        _ => Err(bad()),
    }
}

/// The start state `--start`/`--state` ask for.
fn start_state(a: &FeasibleArgs, env: &EnvParams) -> anyhow::Result<State> {
    let dim = a.env.dim();
    if let Some(s) = &a.state {
        if s.0.len() != dim {
            return Err(user_error(format!(
                "--state: {} needs {dim} values ({}), got {}",
                a.env,
                a.env.variables().join(","),
                s.0.len()
            )));
        }
        let mut out = [0.0; 4];
        out[..dim].copy_from_slice(&s.0);
        return Ok(out);
    }
    Ok(first_start(env, a.start, a.seed))
}

/// Run `qsweep feasible`.
pub fn run(a: FeasibleArgs) -> anyhow::Result<u8> {
    let system = a.env;
    if !qsweep_engine::feasible::searchable(system) {
        return Err(user_error(format!("--env: {}", qsweep_engine::feasible::not_searchable(system))));
    }
    let dim = system.dim();
    let resolution = match a.resolution.0[..] {
        [n] => vec![n; dim],
        ref r => r.to_vec(),
    };
    let actions = a.actions.unwrap_or(system.default_actions());
    let mut c = TrialConfig::paper(system, ReprKind::Crisp, Algorithm::Q0, resolution, actions);
    c.env = env_params(system, &a.params, a.control)?;
    for r in &a.ranges {
        let (j, lohi) = parse_range(system, r)?;
        c.repr.ranges[j] = lohi;
    }
    c.repr.binning = a.binning;
    c.start = a.start;
    c.validate().map_err(|e| user_error(format!("--resolution/--actions/--range: {e}")))?;
    let cells: u64 = c.repr.resolution.iter().map(|&n| u64::from(n)).product();
    if cells > 1 << 24 {
        return Err(user_error(format!(
            "--resolution: {cells} cells is too many for the search (limit 2^24)"
        )));
    }
    let start = start_state(&a, &c.env)?;
    let result = search(&c, &start, a.max_steps, a.max_nodes).map_err(user_error)?;
    let policy_cells = policy_cells(&c, &result.policy);
    let report = Report {
        format_version: Report::FORMAT_VERSION,
        system,
        resolution: c.repr.resolution.clone(),
        actions: c.actions,
        ranges: c.repr.ranges.clone(),
        binning: c.repr.binning.name(),
        start: start[..dim].to_vec(),
        max_steps: a.max_steps,
        max_nodes: a.max_nodes,
        result,
        policy_cells,
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_text(&report, system);
    }
    Ok(0)
}

fn print_text(r: &Report, system: SystemKind) {
    let f = &r.result;
    let res: Vec<String> = r.resolution.iter().map(u32::to_string).collect();
    println!(
        "{system}: {} crisp cells ({}), {} actions, {} bins, start {:?}",
        f.policy.len(),
        res.join("/"),
        r.actions,
        r.binning,
        r.start
    );
    let verdict = if f.survives {
        format!("a policy survives {} steps (the --max-steps goal)", r.max_steps)
    } else if f.complete {
        format!("no policy survives more than {} steps (exhaustive)", f.best)
    } else {
        format!("at least {} steps; search incomplete after {} nodes (--max-nodes)", f.best, f.nodes)
    };
    println!("longest episode: {verdict}");
    println!("searched {} nodes, {} simulation steps", f.nodes, f.steps);
    println!(
        "policy ({} of {} cells visited; the others may take any action):",
        r.policy_cells.len(),
        f.policy.len()
    );
    let vars = system.variables();
    for c in &r.policy_cells {
        let parts: Vec<String> = vars
            .iter()
            .zip(&c.intervals)
            .map(|(v, [lo, hi])| format!("{v} in [{}, {})", short(*lo), short(*hi)))
            .collect();
        println!("  {} -> {}", parts.join(", "), c.action);
    }
}

fn short(v: f64) -> String {
    if v.is_infinite() {
        if v > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        }
    } else {
        format!("{}", (v * 1e6).round() / 1e6)
    }
}
