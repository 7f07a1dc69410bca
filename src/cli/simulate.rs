//! `qsweep simulate`: the physics alone, as CSV, for checking against other implementations.

use super::args;
use crate::error::user_error;
use crate::sim::env::{EnvParams, SystemKind};
use clap::Args;
use std::io::Write;

/// Arguments of `qsweep simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// System: ball-beam, cart-pole or mountain-car.
    #[arg(long, value_parser = args::system)]
    pub env: SystemKind,
    /// Start state, comma-separated in state order (cart-pole: x,x_dot,theta,theta_dot; others: x,x_dot).
    #[arg(long, value_parser = args::finite_list, allow_hyphen_values = true)]
    pub state: args::Floats,
    /// Action values, comma-separated: force in N (cart-pole), tilt in rad (ball-beam), throttle −1..1 (mountain-car).
    #[arg(long, value_parser = args::finite_list, allow_hyphen_values = true)]
    pub actions: args::Floats,
    /// Override a physical parameter, e.g. --param gravity=9.8 (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = args::param)]
    pub params: Vec<(String, f64)>,
}

/// Build the system's parameters from defaults and `--param` overrides.
pub fn env_params(system: SystemKind, overrides: &[(String, f64)]) -> anyhow::Result<EnvParams> {
    let mut env = EnvParams::default_for(system);
    for (name, value) in overrides {
        env.set_param(name, *value).map_err(|e| user_error(format!("--param: {e}")))?;
    }
    env.validate().map_err(|e| user_error(format!("--param: {e}")))?;
    Ok(env)
}

/// Run `qsweep simulate`.
pub fn run(a: SimulateArgs) -> anyhow::Result<u8> {
    let env = env_params(a.env, &a.params)?;
    let vars = a.env.variables();
    let (state, actions) = (a.state.0, a.actions.0);
    if state.len() != vars.len() {
        return Err(user_error(format!(
            "--state: {} needs {} values ({}), got {}",
            a.env,
            vars.len(),
            vars.join(","),
            state.len()
        )));
    }
    let steps = crate::sim::trial::simulate(&env, &state, &actions);
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    writeln!(out, "step,action,{},reward,terminal", vars.join(","))?;
    let row = |s: &[f64]| s[..vars.len()].iter().map(|v| format!("{v}")).collect::<Vec<_>>().join(",");
    writeln!(out, "0,,{},0,0", row(&state))?;
    for (i, (action, s, t)) in steps.iter().enumerate() {
        writeln!(out, "{},{action},{},{},{}", i + 1, row(s), t.reward, u8::from(t.terminal))?;
    }
    out.flush()?;
    Ok(crate::error::exit::OK)
}
