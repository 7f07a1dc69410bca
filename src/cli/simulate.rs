//! `qsweep simulate`: the physics alone, as CSV, for checking against other implementations.
//! Ball-Beam under `--control rate` adds the (hidden) beam angle as a `theta` column.

use super::args;
use clap::Args;
use qsweep_engine::env::{BeamControl, EnvParams, SystemKind};
use qsweep_pipeline::error::user_error;
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
    /// Action values, comma-separated: force in N (cart-pole), tilt in rad (ball-beam; its rate
    /// in rad/s under --control rate), throttle −1..1 (mountain-car).
    #[arg(long, value_parser = args::finite_list, allow_hyphen_values = true)]
    pub actions: args::Floats,
    /// Override a physical parameter, e.g. --param gravity=9.8 (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = args::param)]
    pub params: Vec<(String, f64)>,
    /// Ball-Beam only: what an action sets, the beam angle or its rate (the parameter `control`)
    /// [default: angle].
    #[arg(long, value_enum)]
    pub control: Option<BeamControl>,
}

/// Build the system's parameters from defaults, `--param` overrides and Ball-Beam's `--control`.
pub fn env_params(
    system: SystemKind,
    overrides: &[(String, f64)],
    control: Option<BeamControl>,
) -> anyhow::Result<EnvParams> {
    let mut env = EnvParams::default_for(system);
    for (name, value) in overrides {
        env.set_param(name, *value).map_err(|e| user_error(format!("--param: {e}")))?;
    }
    match (&mut env, control) {
        (_, None) => {}
        (EnvParams::BallBeam(p), Some(c)) => p.control = c,
        (_, Some(_)) => {
            return Err(user_error(format!("--control: {system} has no beam; --control is for ball-beam")))
        }
    }
    env.validate().map_err(|e| user_error(format!("--param: {e}")))?;
    Ok(env)
}

/// Run `qsweep simulate`.
pub fn run(a: SimulateArgs) -> anyhow::Result<u8> {
    let env = env_params(a.env, &a.params, a.control)?;
    let theta = matches!(&env, EnvParams::BallBeam(p) if p.control == BeamControl::Rate);
    let vars: Vec<&str> = a.env.variables().iter().copied().chain(theta.then_some("theta")).collect();
    let dim = a.env.dim();
    let (state, actions) = (a.state.0, a.actions.0);
    if state.len() != dim {
        return Err(user_error(format!(
            "--state: {} needs {dim} values ({}), got {}",
            a.env,
            vars[..dim].join(","),
            state.len()
        )));
    }
    let steps = qsweep_engine::trial::simulate(&env, &state, &actions);
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    writeln!(out, "step,action,{},reward,terminal", vars.join(","))?;
    let row = |s: &[f64]| s[..vars.len()].iter().map(|v| format!("{v}")).collect::<Vec<_>>().join(",");
    // The beam starts level, as at every episode start.
    let start: Vec<f64> = state.iter().copied().chain(theta.then_some(0.0)).collect();
    writeln!(out, "0,,{},0,0", row(&start))?;
    for (i, (action, s, t)) in steps.iter().enumerate() {
        writeln!(out, "{},{action},{},{},{}", i + 1, row(s), t.reward, u8::from(t.terminal))?;
    }
    out.flush()?;
    Ok(qsweep_pipeline::error::exit::OK)
}
