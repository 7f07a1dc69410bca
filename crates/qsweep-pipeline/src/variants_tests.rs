//! The two engine settings of the preregistered variants (b) and (c) in whole trials: Gym's solved
//! rule (`Success::Solved`) and ballbeam-gym's rate-controlled beam (`control: rate`). Their
//! defaults keep every key of before; each changes the trial exactly as documented.

use crate::cache::key::canonical_config;
use crate::cache::Key;
use qsweep_engine::actions::action_set;
use qsweep_engine::config::{Algorithm, Success, TieBreak, TrialConfig, Truncation};
use qsweep_engine::env::{BallBeamParams, BeamControl, EnvParams, SystemKind};
use qsweep_engine::repr::ReprKind;
use qsweep_engine::run_trial;
use qsweep_engine::trial::{run_with_q, simulate};

/// One cell, two actions, ε = 0, ties to the first action, Q(0): a trial whose every choice is
/// known in advance.
fn one_cell(system: SystemKind, success: Success, max_episodes: u32) -> TrialConfig {
    let mut c = TrialConfig::paper(system, ReprKind::Crisp, Algorithm::Q0, vec![1; system.dim()], 2);
    c.learner.epsilon = 0.0;
    c.learner.tie_break = TieBreak::First;
    c.limits.success = success;
    c.limits.max_episodes = max_episodes;
    c.normalize();
    c.validate().unwrap();
    c
}

const fn solved(window: u32, mean_length: f64, episode_steps: u64) -> Success {
    Success::Solved { window, mean_length, episode_steps }
}

#[test]
fn a_goal_task_is_solved_at_the_windows_end_with_cut_episodes_counting_at_the_cut() {
    // Mountain Car cut after 3 steps never reaches the goal: every episode is 3 steps long
    // (MountainCar's return −3). Mean ≤ 3 over 4 episodes: solved at episode 4, not before.
    let o = run_trial(&one_cell(SystemKind::MountainCar, solved(4, 3.0, 3), 10), 0);
    assert_eq!((o.converged, o.episodes_to_goal), (true, Some(4)));
    assert_eq!(o.episode_lengths, vec![3; 4]);
    assert_eq!(o.total_steps, 12);
    // Mean ≤ 2.9 never holds: the trial runs to its episode cap.
    let o = run_trial(&one_cell(SystemKind::MountainCar, solved(4, 2.9, 3), 10), 0);
    assert_eq!((o.converged, o.episodes_to_goal, o.stop.name()), (false, None, "max-episodes"));
    assert_eq!(o.episode_lengths, vec![3; 10]);
}

#[test]
fn under_the_solved_rule_a_survival_tasks_cut_is_an_ordinary_episode() {
    // Cart-Pole from rest cannot fall within 5 steps: every episode is cut at 5.
    // Balance: the first cut episode is the goal.
    let o = run_trial(&one_cell(SystemKind::CartPole, Success::Balance { steps: 5 }, 10), 0);
    assert_eq!((o.episodes_to_goal, o.episode_lengths.clone()), (Some(1), vec![5]));
    // Solved: mean ≥ 5 over 3 episodes, at episode 3.
    let o = run_trial(&one_cell(SystemKind::CartPole, solved(3, 5.0, 5), 10), 0);
    assert_eq!((o.episodes_to_goal, o.episode_lengths.clone()), (Some(3), vec![5; 3]));
    // Mean ≥ 5.01 never holds: ten cut episodes and no goal.
    let o = run_trial(&one_cell(SystemKind::CartPole, solved(3, 5.01, 5), 10), 0);
    assert_eq!((o.converged, o.episode_lengths.clone()), (false, vec![5; 10]));
}

#[test]
fn truncation_is_kept_and_matters_for_survival_tasks_only_under_the_solved_rule() {
    let with = |success, truncation, q_init| {
        let mut c = TrialConfig::paper(SystemKind::CartPole, ReprKind::Crisp, Algorithm::Q0, vec![3; 4], 2);
        c.limits.success = success;
        c.limits.max_episodes = 6;
        c.limits.truncation = truncation;
        c.learner.q_init = q_init;
        c.normalize();
        c
    };
    assert_eq!(
        with(Success::Balance { steps: 5 }, Truncation::Terminal, 0.5).limits.truncation,
        Truncation::Bootstrap
    );
    let terminal = with(solved(100, 195.0, 5), Truncation::Terminal, 0.5);
    assert_eq!(terminal.limits.truncation, Truncation::Terminal);
    assert!(canonical_config(&terminal).contains("\"truncation\":\"terminal\""));
    // Optimistic Q (0.5) with rewards 0: the cut step bootstraps to γ·max Q > 0 or, as terminal, to 0.
    let (_, q_term) = run_with_q(&terminal, 0);
    let (_, q_boot) = run_with_q(&with(solved(100, 195.0, 5), Truncation::Bootstrap, 0.5), 0);
    assert_ne!(q_term, q_boot);
}

#[test]
fn a_rate_controlled_trial_levels_the_beam_at_every_episode_start() {
    // ballbeam-gym's discrete mode: τ 0.1, L 1, θ within ±0.2, rates ±0.8. With one cell and
    // ties to the first action, episode 1 lowers the beam (−0.8) until the ball falls; that
    // failure makes action 0 worse, so episode 2 raises it (+0.8) all along, from a level beam.
    let mut c = one_cell(SystemKind::BallBeam, Success::Balance { steps: 10_000 }, 2);
    c.env = EnvParams::BallBeam(BallBeamParams {
        tau: 0.1,
        beam_length: 1.0,
        angle_max: 0.2,
        control: BeamControl::Rate,
        ..BallBeamParams::default()
    });
    c.validate().unwrap();
    assert_eq!(action_set(c.env.action_max(), c.actions), vec![-0.8, 0.8]);
    let o = run_trial(&c, 0);
    let fall = |rate: f64| simulate(&c.env, &[0.0; 2], &[rate; 1000]).len() as u32;
    assert_eq!(o.episode_lengths, vec![fall(-0.8), fall(0.8)]);
    // By hand the ball starts from rest on a level beam and θ reaches the 0.2 stop at step 3, so
    // it leaves a half-beam of 0.5 within a few steps: 0, 0.0078, 0.0313, 0.0743, … (see
    // `ball_beam::tests`); an angle-controlled beam at a tilt of 0.8 rad would fall sooner.
    assert!(fall(0.8) > 3 && fall(0.8) < 20, "{}", fall(0.8));
    let mut angle = c.clone();
    if let EnvParams::BallBeam(p) = &mut angle.env {
        p.control = BeamControl::Angle;
    }
    assert_ne!(run_trial(&angle, 0).episode_lengths, o.episode_lengths);
}

#[test]
fn the_new_settings_enter_the_key_only_when_they_are_not_the_default() {
    let base = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![3; 2], 3);
    // rate_max is unused under angle control: normalised away.
    let mut c = base.clone();
    if let EnvParams::BallBeam(p) = &mut c.env {
        p.rate_max = 0.5;
    }
    c.normalize();
    assert_eq!(Key::of(&c, 0), Key::of(&base, 0));
    // Under rate control both enter the canonical JSON (rate_max only when not 0.8).
    let mut rate = base.clone();
    if let EnvParams::BallBeam(p) = &mut rate.env {
        p.control = BeamControl::Rate;
    }
    rate.normalize();
    let json = canonical_config(&rate);
    assert!(json.contains("\"control\":\"rate\"") && !json.contains("rate_max"), "{json}");
    let mut faster = rate.clone();
    if let EnvParams::BallBeam(p) = &mut faster.env {
        p.rate_max = 0.5;
    }
    faster.normalize();
    assert!(canonical_config(&faster).contains("\"rate_max\":0.5"));
    let keys = [Key::of(&base, 0), Key::of(&rate, 0), Key::of(&faster, 0)];
    assert!(keys[0] != keys[1] && keys[1] != keys[2] && keys[0] != keys[2]);
    for c in [&rate, &faster] {
        let back: TrialConfig = serde_json::from_str(&canonical_config(c)).unwrap();
        assert_eq!(&back, c, "reads back from its canonical JSON");
    }
    // The solved rule is its own criterion.
    let mut s = base.clone();
    s.limits.success = solved(100, 195.0, 200);
    let json = canonical_config(&s);
    assert!(
        json.contains(r#""success":{"kind":"solved","window":100,"mean_length":195.0,"episode_steps":200}"#),
        "{json}"
    );
    assert_eq!(serde_json::from_str::<TrialConfig>(&json).unwrap(), s);
    assert_ne!(Key::of(&s, 0), Key::of(&base, 0));
}

#[test]
fn bad_values_are_refused_with_the_field_name() {
    let mut c = one_cell(SystemKind::CartPole, solved(3, 5.0, 5), 10);
    c.limits.success = solved(0, 5.0, 5);
    assert_eq!(c.validate().unwrap_err(), "success.window: 0 is not allowed here; expected an integer ≥ 1");
    c.limits.success = solved(3, f64::NAN, 5);
    assert!(c.validate().unwrap_err().starts_with("success.mean_length: NaN is not allowed"));
    c.limits.success = solved(3, 5.0, 0);
    assert!(c.validate().unwrap_err().starts_with("success.steps: "));
    let mut m = one_cell(SystemKind::MountainCar, solved(3, 5.0, 5), 10);
    m.limits.success = solved(3, 5.0, 0);
    assert!(m.validate().unwrap_err().starts_with("success.max_episode_steps: "));
    let mut b = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![3; 2], 3);
    b.env.set_param("rate_max", -1.0).unwrap();
    assert!(b.validate().unwrap_err().starts_with("env: rate_max: -1 is not allowed"));
}

#[test]
fn pipelines_resolve_the_variants_settings() {
    let text = "name: t\nseeds: 1\nsystems:\n  cart-pole:\n    success: { steps: 200, window: 100, mean_length: 195 }\n    experiments:\n      - { id: a, repr: crisp, algorithms: [q0], vary: { x == x_dot == theta == theta_dot: 2 } }\n  mountain-car:\n    success: { within: 200, max_episode_steps: 200, window: 100, mean_length: 110 }\n    experiments:\n      - { id: a, repr: crisp, algorithms: [q0], vary: { x == x_dot: 2 } }\n      - { id: b, repr: crisp, algorithms: [q0], vary: { x == x_dot: 2 }, success: { within: 150 } }\n  ball-beam:\n    params: { control: rate, tau: 0.1, beam_length: 1, angle_max: 0.2, start: [0, 0] }\n    experiments:\n      - { id: a, repr: crisp, algorithms: [q0], vary: { x == x_dot: 2 }, fixed: { actions: 2 } }\n";
    let spec = crate::declared::load_str(text, "t.yaml", &[]).unwrap();
    let plan = crate::plan::plan(
        &crate::declared::LoadedSpec { spec, path: "t.yaml".into(), variants: Vec::new() },
        None,
    )
    .unwrap();
    let config = |system: SystemKind, i: usize| {
        let e = plan.experiments.iter().filter(|e| e.system == system).nth(i).unwrap();
        e.cells[0].config.clone()
    };
    assert_eq!(config(SystemKind::CartPole, 0).limits.success, solved(100, 195.0, 200));
    assert_eq!(config(SystemKind::CartPole, 0).limits.episode_cap(), 200);
    assert_eq!(config(SystemKind::MountainCar, 0).limits.success, solved(100, 110.0, 200));
    // An experiment's success replaces the system's: without a window it is the streak rule.
    assert_eq!(
        config(SystemKind::MountainCar, 1).limits.success,
        Success::Reach { within: 150, streak: 1, max_episode_steps: 10_000 }
    );
    let b = config(SystemKind::BallBeam, 0);
    let EnvParams::BallBeam(p) = &b.env else { unreachable!() };
    assert_eq!((p.control, p.rate_max, p.tau, p.angle_max), (BeamControl::Rate, 0.8, 0.1, 0.2));
    assert_eq!(action_set(b.env.action_max(), b.actions), vec![-0.8, 0.8]);
}
