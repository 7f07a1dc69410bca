//! Trials in lockstep: several crisp trials of one system, or several two-variable fuzzy rule
//! bases of one system on the dense path, stepped as lanes of one loop, each lane taking the next
//! trial when its own stops.
//!
//! A crisp step is one trial's chain of dependent operations (dynamics → bin → greedy choice →
//! update), and the core idles behind it; Mountain Car's cos(3x) alone is about half of it. With
//! [`LANES`] trials in one loop, their dynamics run as vector lanes ([`Environment::step_each`],
//! [`crate::math::cos_lanes`]) and the rest of their steps overlap in the core. A second hardware
//! thread on the same core fills the same idle slots, so the gain is largest where a trial's
//! thread has its core to itself (docs/speed.md, "Trials in lockstep"). A dense fuzzy step
//! ([`crate::repr::DenseFuzzy`]) is such a chain too, only longer (activation → Q(s′, ·) → δ →
//! update → Q(s, ·) → choice), and its loop is compiled for the vector level as a whole.
//!
//! Each lane performs exactly the operations its trial performs when run alone, in the same
//! order ([`TrialRun`] is both), and shares nothing with the other lanes but the loop: a trial's
//! outcome never depends on which trials share its loop or on how many lanes there are
//! (`tests::a_trial_in_lockstep_is_the_trial_alone`).

use super::config::{Algorithm, TrialConfig};
use super::dense_path::takes_dense_path;
use super::env::{with_env_type, FromParams, SystemKind, Transition};
use super::repr::{Crisp, DenseFuzzy, Encode, ReprKind};
use super::simd::{self, Simd};
use super::trial::{run_trial, Outcome, TrialRun};

/// Trials one lockstep loop steps at once.
pub const LANES: usize = crate::env::LANES;

/// Whether a trial runs faster in lockstep than alone: crisp tables, of every system, and the
/// fuzzy rule bases that take the dense path (measured, docs/speed.md). Other fuzzy steps are long
/// and mostly independent operations already.
pub fn benefits(cfg: &TrialConfig) -> bool {
    cfg.repr.kind == ReprKind::Crisp || takes_dense_path(cfg)
}

/// The trials that run best together in one loop, for a trial that [`benefits`]: those of the same
/// system, representation and algorithm (lanes that take the same branches, and whose steps cost
/// about the same); `None` for the others.
pub fn group(cfg: &TrialConfig) -> Option<(SystemKind, ReprKind, Algorithm)> {
    benefits(cfg).then(|| (cfg.system(), cfg.repr.kind, cfg.learner.algorithm))
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
/// iteration of the loop, so the trials in it share its time equally. Every trial must be of
/// `system` and of the first trial's kind (crisp, or fuzzy on the dense path, [`benefits`]); one
/// that is not runs alone when it comes (the same outcome).
pub fn run_lockstep<'c>(
    system: SystemKind,
    mut next: impl FnMut() -> Option<(usize, &'c TrialConfig, u64)>,
    done: impl FnMut(usize, Outcome),
) {
    let Some(first) = next() else { return };
    let dense = takes_dense_path(first.1);
    let mut first = Some(first);
    let next = move || first.take().or_else(&mut next);
    with_env_type!(system, E => if dense {
        dense_at_level::<E>(simd::level(), next, done)
    } else {
        lockstep::<E, Crisp>(next, done)
    })
}

/// The outcomes of `trials` (configuration and seed each), in order: the trials of each lockstep
/// [`group`] in one loop, every other trial alone. One thread; give it a batch of trials (a few
/// loads of [`LANES`]) per thread to compute many in parallel.
pub fn run_batch(trials: &[(&TrialConfig, u64)]) -> Vec<Outcome> {
    let mut out: Vec<Option<Outcome>> = vec![None; trials.len()];
    let mut groups: Vec<_> = trials.iter().filter_map(|(cfg, _)| group(cfg)).collect();
    groups.sort();
    groups.dedup();
    for g in groups {
        let mut next = (0..trials.len())
            .filter(|&i| group(trials[i].0) == Some(g))
            .map(|i| (i, trials[i].0, trials[i].1));
        run_lockstep(g.0, || next.next(), |i, o| out[i] = Some(o));
    }
    out.iter_mut()
        .zip(trials)
        .map(|(o, &(cfg, seed))| o.take().unwrap_or_else(|| run_trial(cfg, seed)))
        .collect()
}

/// A kind of trial that lanes of one loop share: how a lane's trial starts.
trait LaneKind {
    /// The representation its trials encode states with.
    type Repr: Encode;
    /// Trial `cfg` with `seed` on system `E`, if it is of this kind.
    fn run<'c, E: FromParams>(cfg: &'c TrialConfig, seed: u64) -> Option<TrialRun<'c, Self::Repr>>;
}

impl LaneKind for Crisp {
    type Repr = Crisp;
    fn run<'c, E: FromParams>(cfg: &'c TrialConfig, seed: u64) -> Option<TrialRun<'c, Crisp>> {
        (cfg.repr.kind == ReprKind::Crisp).then(|| TrialRun::crisp::<E>(cfg, seed))
    }
}

impl LaneKind for DenseFuzzy {
    type Repr = DenseFuzzy;
    fn run<'c, E: FromParams>(cfg: &'c TrialConfig, seed: u64) -> Option<TrialRun<'c, DenseFuzzy>> {
        TrialRun::dense::<E>(cfg, seed)
    }
}

/// [`lockstep`] of dense fuzzy lanes with the whole loop compiled for `level` (as a dense trial
/// alone is, `trial.rs`): the activation, the learner's kernels and the systems' steps inline
/// into one function of that width, with the same bits.
fn dense_at_level<'c, E: FromParams>(
    level: Simd,
    next: impl FnMut() -> Option<(usize, &'c TrialConfig, u64)>,
    done: impl FnMut(usize, Outcome),
) {
    #[cfg(target_arch = "x86_64")]
    {
        #[target_feature(enable = "avx2")]
        unsafe fn avx2<'c, E: FromParams>(
            next: impl FnMut() -> Option<(usize, &'c TrialConfig, u64)>,
            done: impl FnMut(usize, Outcome),
        ) {
            lockstep::<E, DenseFuzzy>(next, done)
        }
        #[target_feature(enable = "avx512f")]
        unsafe fn avx512<'c, E: FromParams>(
            next: impl FnMut() -> Option<(usize, &'c TrialConfig, u64)>,
            done: impl FnMut(usize, Outcome),
        ) {
            lockstep::<E, DenseFuzzy>(next, done)
        }
        match level.capped() {
            // SAFETY: capped by what the CPU has.
            Simd::Avx2 => return unsafe { avx2::<E>(next, done) },
            Simd::Avx512 => return unsafe { avx512::<E>(next, done) },
            Simd::Baseline => {}
        }
    }
    lockstep::<E, DenseFuzzy>(next, done)
}

/// One lane's trial.
struct Lane<'c, R: Encode> {
    id: usize,
    run: TrialRun<'c, R>,
}

#[inline(always)]
fn lockstep<'c, E: FromParams, K: LaneKind>(
    mut next: impl FnMut() -> Option<(usize, &'c TrialConfig, u64)>,
    mut done: impl FnMut(usize, Outcome),
) {
    let mut lanes: Vec<Option<Lane<'c, K::Repr>>> = Vec::new();
    let mut envs: Vec<E> = Vec::new();
    while lanes.len() < LANES {
        let Some((lane, env)) = start::<E, K>(&mut next, &mut done) else { break };
        lanes.push(Some(lane));
        envs.push(env);
    }
    let n = lanes.len();
    let mut more = n == LANES;
    let mut actions = vec![0.0; n];
    let mut steps = vec![Transition { reward: 0.0, terminal: false }; n];
    let (mut bootstraps, mut targets) = (vec![false; n], vec![0.0; n]);
    while lanes.iter().any(Option::is_some) {
        for (lane, a) in lanes.iter_mut().zip(&mut actions) {
            // An idle lane's system keeps stepping with its last action; nothing reads it.
            if let Some(lane) = lane {
                *a = lane.run.choose();
            }
        }
        E::step_each(&mut envs, &actions, &mut steps);
        // Each part of every lane's step before the next part of any: the lanes' chains of
        // dependent operations (the activation, Q(s′, ·), the update) lie side by side for the CPU.
        for (((slot, env), &t), boots) in lanes.iter_mut().zip(&envs).zip(&steps).zip(&mut bootstraps) {
            if let Some(lane) = slot {
                *boots = lane.run.encode_next(env, t);
            }
        }
        for (((slot, &t), &boots), target) in lanes.iter_mut().zip(&steps).zip(&bootstraps).zip(&mut targets)
        {
            if let Some(lane) = slot {
                *target = lane.run.target_of(t, boots);
            }
        }
        for (((slot, env), &t), &target) in lanes.iter_mut().zip(&mut envs).zip(&steps).zip(&targets) {
            let Some(lane) = slot else { continue };
            let Some(o) = lane.run.learn_toward(env, t, target) else { continue };
            done(lane.id, o);
            *slot = None;
            if more {
                match start::<E, K>(&mut next, &mut done) {
                    Some((lane, e)) => (*slot, *env) = (Some(lane), e),
                    None => more = false,
                }
            }
        }
    }
}

/// The next trial that needs a lane, with its system at the start of its first episode. A trial
/// that stops before its first step, or is not of `E` and the lanes' kind, is settled here.
fn start<'c, E: FromParams, K: LaneKind>(
    next: &mut impl FnMut() -> Option<(usize, &'c TrialConfig, u64)>,
    done: &mut impl FnMut(usize, Outcome),
) -> Option<(Lane<'c, K::Repr>, E)> {
    loop {
        let (id, cfg, seed) = next()?;
        let lane = E::from_params(&cfg.env).and_then(|env| Some((env, K::run::<E>(cfg, seed)?)));
        let Some((mut env, mut run)) = lane else {
            done(id, run_trial(cfg, seed));
            continue;
        };
        match run.begin(&mut env) {
            Some(o) => done(id, o),
            None => return Some((Lane { id, run }, env)),
        }
    }
}

#[cfg(test)]
mod tests;
