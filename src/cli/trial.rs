//! `qsweep trial`: one configuration and one seed, with Table II defaults, printed as text or JSON.
//! The flags are `trial_args`, how they become a configuration `trial_config`; this file runs it.

use super::trial_args::TrialArgs;
use super::trial_config::config;
use crate::json::TrialReport;
use qsweep_engine::run_trial;

/// Run `qsweep trial`.
pub fn run(a: TrialArgs) -> anyhow::Result<u8> {
    let cfg = config(&a)?;
    let start = std::time::Instant::now();
    let out = run_trial(&cfg, a.seed);
    let seconds = start.elapsed().as_secs_f64();
    if a.json {
        let v = TrialReport {
            format_version: TrialReport::FORMAT_VERSION,
            config: cfg.clone(),
            seed: a.seed,
            outcome: out.clone(),
            seconds,
        };
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        let label = cfg.learner.algorithm.label(cfg.repr.kind);
        println!(
            "{} {} {:?} × {} actions, seed {}",
            cfg.system().title(),
            label,
            cfg.repr.resolution,
            cfg.actions,
            a.seed
        );
        match out.episodes_to_goal {
            Some(n) => println!("reached the learning goal in episode {n}"),
            None => println!(
                "did not reach the learning goal ({}) after {} episodes",
                out.stop.name(),
                out.episodes
            ),
        }
        if let Some(f) = &out.failure {
            println!("failure: {f}");
        }
        let rate = out.total_steps as f64 / seconds.max(1e-9);
        println!("{} steps in {:.3} s ({:.2} M steps/s)", out.total_steps, seconds, rate / 1e6);
    }
    Ok(if out.failure.is_some() {
        qsweep_pipeline::error::exit::FAILURE
    } else {
        qsweep_pipeline::error::exit::OK
    })
}
