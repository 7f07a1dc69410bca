//! Trials in lockstep: several crisp trials of one system stepped as lanes of one loop, each
//! lane taking the next trial when its own stops.
//!
//! A crisp step is one trial's chain of dependent operations (dynamics → bin → greedy choice →
//! update), and the core idles behind it; Mountain Car's cos(3x) alone is about half of it. With
//! [`LANES`] trials in one loop, their dynamics run as vector lanes ([`Environment::step_each`],
//! [`crate::math::cos_lanes`]) and the rest of their steps overlap in the core. A second hardware
//! thread on the same core fills the same idle slots, so the gain is largest where a trial's
//! thread has its core to itself (docs/speed.md, "Trials in lockstep").
//!
//! Each lane performs exactly the operations its trial performs when run alone, in the same
//! order ([`TrialRun`] is both), and shares nothing with the other lanes but the loop: a trial's
//! outcome never depends on which trials share its loop or on how many lanes there are
//! (`tests::a_trial_in_lockstep_is_the_trial_alone`).

use super::config::{Algorithm, TrialConfig};
use super::env::{with_env_type, FromParams, SystemKind, Transition};
use super::repr::{Crisp, ReprKind};
use super::trial::{run_trial, Outcome, TrialRun};

/// Trials one lockstep loop steps at once.
pub const LANES: usize = crate::env::LANES;

/// Whether a trial runs faster in lockstep than alone: crisp tables, of every system (measured,
/// docs/speed.md). Fuzzy steps are long and mostly independent operations already.
pub fn benefits(cfg: &TrialConfig) -> bool {
    cfg.repr.kind == ReprKind::Crisp
}

/// The trials that run best together in one loop, for a trial that [`benefits`]: those of the same
/// system and algorithm (lanes that take the same branches, and whose steps cost about the
/// same); `None` for the others.
pub fn group(cfg: &TrialConfig) -> Option<(SystemKind, Algorithm)> {
    benefits(cfg).then(|| (cfg.system(), cfg.learner.algorithm))
}

/// Whether callers should run trials in lockstep: `QSWEEP_LOCKSTEP` is not `off` (it never
/// changes a result, only the speed; `off` is there to compare).
pub fn enabled() -> bool {
    static ON: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ON.get_or_init(|| {
        std::env::var("QSWEEP_LOCKSTEP")
            .map_or(true, |v| !matches!(v.trim().to_ascii_lowercase().as_str(), "off" | "0" | "no" | "false"))
    })
}

/// Run the trials `next` hands out, [`LANES`] at a time in one loop, and give each to `done` as
/// it stops (in stopping order): its id and its outcome. Every live lane takes one step per
/// iteration of the loop, so the trials in it share its time equally. Every trial must be crisp
/// and of `system`; one that is not runs alone when it comes (the same outcome).
pub fn run_lockstep<'c>(
    system: SystemKind,
    next: impl FnMut() -> Option<(usize, &'c TrialConfig, u64)>,
    done: impl FnMut(usize, Outcome),
) {
    with_env_type!(system, E => lockstep::<E>(next, done))
}

/// The outcomes of `trials` (configuration and seed each), in order: the crisp trials of each
/// system in one lockstep loop, every other trial alone. One thread; give it a batch of trials
/// (a few loads of [`LANES`]) per thread to compute many in parallel.
pub fn run_batch(trials: &[(&TrialConfig, u64)]) -> Vec<Outcome> {
    let mut out: Vec<Option<Outcome>> = vec![None; trials.len()];
    for system in SystemKind::ALL {
        let mut next = (0..trials.len())
            .filter(|&i| benefits(trials[i].0) && trials[i].0.system() == system)
            .map(|i| (i, trials[i].0, trials[i].1));
        run_lockstep(system, || next.next(), |i, o| out[i] = Some(o));
    }
    out.iter_mut()
        .zip(trials)
        .map(|(o, &(cfg, seed))| o.take().unwrap_or_else(|| run_trial(cfg, seed)))
        .collect()
}

/// One lane's trial.
struct Lane<'c> {
    id: usize,
    run: TrialRun<'c, Crisp>,
}

fn lockstep<'c, E: FromParams>(
    mut next: impl FnMut() -> Option<(usize, &'c TrialConfig, u64)>,
    mut done: impl FnMut(usize, Outcome),
) {
    let (mut lanes, mut envs): (Vec<Option<Lane<'c>>>, Vec<E>) = (Vec::new(), Vec::new());
    while lanes.len() < LANES {
        let Some((lane, env)) = start::<E>(&mut next, &mut done) else { break };
        lanes.push(Some(lane));
        envs.push(env);
    }
    let n = lanes.len();
    let mut more = n == LANES;
    let mut actions = vec![0.0; n];
    let mut steps = vec![Transition { reward: 0.0, terminal: false }; n];
    while lanes.iter().any(Option::is_some) {
        for (lane, a) in lanes.iter_mut().zip(&mut actions) {
            // An idle lane's system keeps stepping with its last action; nothing reads it.
            if let Some(lane) = lane {
                *a = lane.run.choose();
            }
        }
        E::step_each(&mut envs, &actions, &mut steps);
        for ((slot, env), &t) in lanes.iter_mut().zip(&mut envs).zip(&steps) {
            let Some(lane) = slot else { continue };
            let Some(o) = lane.run.learn(env, t) else { continue };
            done(lane.id, o);
            *slot = None;
            if more {
                match start::<E>(&mut next, &mut done) {
                    Some((lane, e)) => (*slot, *env) = (Some(lane), e),
                    None => more = false,
                }
            }
        }
    }
}

/// The next trial that needs a lane, with its system at the start of its first episode. A trial
/// that stops before its first step, or is not a crisp trial of `E`, is settled here.
fn start<'c, E: FromParams>(
    next: &mut impl FnMut() -> Option<(usize, &'c TrialConfig, u64)>,
    done: &mut impl FnMut(usize, Outcome),
) -> Option<(Lane<'c>, E)> {
    loop {
        let (id, cfg, seed) = next()?;
        let env = E::from_params(&cfg.env).filter(|_| cfg.repr.kind == ReprKind::Crisp);
        let Some(mut env) = env else {
            done(id, run_trial(cfg, seed));
            continue;
        };
        let mut run = TrialRun::crisp::<E>(cfg, seed);
        match run.begin(&mut env) {
            Some(o) => done(id, o),
            None => return Some((Lane { id, run }, env)),
        }
    }
}

#[cfg(test)]
mod tests;
