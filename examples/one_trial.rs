//! The engine alone: resolve one cell's configuration the way a pipeline does (every default
//! filled in, so its key is the pipeline cell's key) and run one trial of it, as `qsweep trial`
//! does. `cargo run --release --example one_trial`.

use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::{run_trial, Algorithm};
use qsweep_pipeline::declared::Override;
use qsweep_pipeline::plan::{one_cell, CellRequest};

fn main() -> anyhow::Result<()> {
    let request = CellRequest {
        system: SystemKind::BallBeam,
        repr: ReprKind::Fuzzy,
        resolution: vec![5, 5],
        actions: 3,
        algorithm: Algorithm::QLambda,
        seed: 0,
        // Any pipeline setting by its path, as `--set defaults.max_episodes=50` gives it.
        overrides: vec![Override::setting(&["defaults", "max_episodes"], 50)],
    };
    let config = one_cell(&request)?;
    let outcome = run_trial(&config, request.seed);
    match outcome.episodes_to_goal {
        Some(n) => println!("reached the learning goal in episode {n}"),
        None => println!("stopped ({}) after {} episodes", outcome.stop.name(), outcome.episodes),
    }
    println!("{} steps; episode lengths {:?}", outcome.total_steps, outcome.episode_lengths);
    Ok(())
}
