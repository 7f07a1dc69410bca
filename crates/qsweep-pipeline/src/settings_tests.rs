//! The interpretation settings `truncation`, `start` and `binning`: defaults keep every key and
//! outcome of before, and each non-default value changes the trajectory exactly as documented.

use crate::cache::key::canonical_config;
use crate::cache::Key;
use qsweep_engine::config::{Algorithm, Success, TieBreak, TrialConfig, Truncation};
use qsweep_engine::env::{
    CartPole, EnvParams, Environment, MountainCar, StartKind, SystemKind, CART_POLE_GYM_START,
    MOUNTAIN_CAR_GYM_START_X,
};
use qsweep_engine::repr::{Binning, ReprKind};
use qsweep_engine::rng::TrialRng;
use qsweep_engine::run_trial;
use qsweep_engine::trial::{run_with_q, simulate};

fn cart_pole(res: u32) -> TrialConfig {
    TrialConfig::paper(SystemKind::CartPole, ReprKind::Crisp, Algorithm::QLambda, vec![res; 4], 2)
}

#[test]
fn default_settings_are_left_out_of_the_canonical_json() {
    for system in SystemKind::ALL {
        for repr in [ReprKind::Crisp, ReprKind::Fuzzy] {
            let c = TrialConfig::paper(system, repr, Algorithm::QLambda, vec![3; system.dim()], 3);
            let json = canonical_config(&c);
            for field in ["truncation", "\"start\":\"", "binning", "control", "rate_max", "solved", "window"]
            {
                assert!(!json.contains(field), "{field} in {json}");
            }
            let back: TrialConfig = serde_json::from_str(&json).unwrap();
            assert_eq!(back, c, "a stored default configuration reads back with the defaults");
        }
    }
}

#[test]
fn keys_of_the_paper_pipeline_are_those_of_the_committed_report() {
    // Engine-1 keys read from reports/paper/trials.parquet (computed before these settings existed),
    // one per system × representation × algorithm: the planned paper grid's configurations must
    // still encode to them under engine version 1, so the canonical encoding never drifts.
    const KEYS: [&str; 12] = [
        "41efc77974ce3d3c01472d2a9d344c847c85abf12708a601186825aee8b26f7e",
        "e201e75f18c3321802821119f7c41ef4236a78a66f54e4b761a494c2ff27baf0",
        "8dfda84b963dff098c77dd94e7a373c6e71186b976ba132da089b91f47fa5ee1",
        "cc55d8e5d000d7c6facb4ec329ffd02667dc483a6f414290a44ce194004eda37",
        "6817963b8e0519ca5a3fc6a88b89060c2fa1dbc23f5b0b9749b17d1a1dc592e6",
        "6785826d1741b14b52b23a017fe62eec5b60e042ed6420baced952e02a325332",
        "c986f67aca12fa3a55b129ae4bd8bb8840c3f3e1a8c48e8908d28a0cce3bd423",
        "27720d408af715caa50cbaec8a925c7b863f8e841dddda2781bc364e19484a5a",
        "05305a78e57b8da65451fa0fab09f11fecf55dd004c1dd96430d6a0524242129",
        "2dcfb56e978ba667529240dc882ee0171ca2ce0f189705960f73498d723341be",
        "0b2a51812268d1322bcbc48a2270637014fe5b432e70233b4794bbb339aeea9d",
        "ae2568341f8c60ad21055ecdea4561ddfae6541a87c54751063de3f56c809d08",
    ];
    // The workspace root, two folders above this crate.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let loaded = crate::declared::load(&root.join("pipelines/paper.yaml"), &[]).unwrap();
    let plan = crate::plan::plan(&loaded, None).unwrap();
    let keys: std::collections::HashSet<String> = plan
        .experiments
        .iter()
        .flat_map(|e| &e.cells)
        .flat_map(|c| {
            let canonical = crate::cache::key::canonical_config(&c.config);
            c.trials.iter().map(move |t| Key::from_canonical(&canonical, t.seed, 1).hex())
        })
        .collect();
    for k in KEYS {
        assert!(keys.contains(k), "key {k} of the committed report is no longer planned");
    }
}

#[test]
fn non_default_settings_change_the_key() {
    let base = cart_pole(3);
    let mut c = base.clone();
    c.repr.binning = Binning::Digitize;
    c.normalize();
    assert_ne!(Key::of(&c, 0), Key::of(&base, 0));
    let mut c = base.clone();
    c.start = StartKind::Gym;
    c.normalize();
    assert_ne!(Key::of(&c, 0), Key::of(&base, 0));
    let mc = TrialConfig::paper(SystemKind::MountainCar, ReprKind::Crisp, Algorithm::Q0, vec![4, 4], 3);
    let mut c = mc.clone();
    c.limits.truncation = Truncation::Terminal;
    c.normalize();
    assert_ne!(Key::of(&c, 0), Key::of(&mc, 0));
    assert!(canonical_config(&c).contains("\"truncation\":\"terminal\""));
}

#[test]
fn settings_that_cannot_matter_are_normalised_away() {
    // A survival task's cut is its goal: the trial ends right after, whatever the last update.
    let mut c = cart_pole(2);
    c.limits.truncation = Truncation::Terminal;
    c.normalize();
    assert_eq!(c.limits.truncation, Truncation::Bootstrap);
    // Fuzzy sets have no bin edges.
    let mut c = TrialConfig::paper(SystemKind::CartPole, ReprKind::Fuzzy, Algorithm::Q0, vec![3; 4], 2);
    c.repr.binning = Binning::Digitize;
    c.normalize();
    assert_eq!(c.repr.binning, Binning::Midpoint);
    // Gymnasium has no Ball-Beam: it keeps its fixed start.
    let mut c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![3; 2], 3);
    c.start = StartKind::Gym;
    c.normalize();
    assert_eq!(c.start, StartKind::Fixed);
}

#[test]
fn gym_starts_lie_in_gymnasiums_ranges_and_follow_the_seed() {
    let draw_cp = |seed: u64| {
        let mut env = CartPole::new(Default::default());
        let mut rng = TrialRng::new(seed);
        (0..50)
            .map(|_| {
                env.reset_gym(&mut rng);
                *env.state()
            })
            .collect::<Vec<_>>()
    };
    let [lo, hi] = CART_POLE_GYM_START;
    assert_eq!((lo, hi), (-0.05, 0.05));
    let a = draw_cp(1);
    assert!(a.iter().flatten().all(|v| (lo..hi).contains(v)));
    assert!(a.windows(2).all(|w| w[0] != w[1]), "a fresh draw every episode");
    assert_eq!(a, draw_cp(1), "the same seed draws the same starts");
    assert_ne!(a, draw_cp(2), "another seed draws other starts");
    let [lo, hi] = MOUNTAIN_CAR_GYM_START_X;
    assert_eq!((lo, hi), (-0.6, -0.4));
    let mut env = MountainCar::new(Default::default());
    let mut rng = TrialRng::new(3);
    for _ in 0..200 {
        env.reset_gym(&mut rng);
        let s = env.state();
        assert!((lo..hi).contains(&s[0]) && s[1] == 0.0, "{s:?}");
    }
}

#[test]
fn a_trials_first_episode_starts_from_the_streams_first_draws() {
    // ε = 0, ties first, Q = 0: episode 1 pushes left (action 0) until the pole falls, from the
    // start drawn by the first four numbers of the seed's stream.
    let mut c = cart_pole(2);
    c.learner.epsilon = 0.0;
    c.learner.tie_break = TieBreak::First;
    c.limits.max_episodes = 3;
    c.start = StartKind::Gym;
    c.normalize();
    for seed in [0, 1, 2] {
        let mut rng = TrialRng::new(seed);
        let start: Vec<f64> = (0..4).map(|_| -0.05 + 0.1 * rng.unit()).collect();
        let fall = simulate(&c.env, &start, &[-10.0; 200]).len() as u32;
        let o = run_trial(&c, seed);
        assert_eq!(o.episode_lengths[0], fall, "seed {seed}");
        assert_eq!(o, run_trial(&c, seed), "deterministic per seed");
    }
    let (a, b) = (run_trial(&c, 0), run_trial(&c, 1));
    assert_ne!(a.episode_lengths, b.episode_lengths);
    let mut fixed = c.clone();
    fixed.start = StartKind::Fixed;
    let f = run_trial(&fixed, 0);
    let from_zero = simulate(&c.env, &[0.0; 4], &[-10.0; 200]).len() as u32;
    assert_eq!(f.episode_lengths[0], from_zero);
}

/// Mountain Car with one cell and two actions, ε = 0, ties to the first action, Q(0), q_init −2,
/// α 0.5, γ 0.9, episodes cut after 3 steps: one episode.
fn one_cell_mountain_car(truncation: Truncation) -> TrialConfig {
    let mut c = TrialConfig::paper(SystemKind::MountainCar, ReprKind::Crisp, Algorithm::Q0, vec![1, 1], 2);
    c.learner.epsilon = 0.0;
    c.learner.tie_break = TieBreak::First;
    c.learner.q_init = -2.0;
    c.learner.alpha = 0.5;
    c.learner.gamma = 0.9;
    c.limits.success = Success::Reach { within: 200, streak: 1, max_episode_steps: 3 };
    c.limits.max_episodes = 1;
    c.limits.truncation = truncation;
    c.normalize();
    c.validate().unwrap();
    c
}

#[test]
fn only_the_cut_step_is_learned_as_terminal_under_terminal_truncation() {
    // By hand (reward −1 every step, one cell so max Q(s′) is over the same two values):
    //   step 1, a0: δ = −1 + 0.9·(−2) + 2 = −0.8 → Q = (−2.4, −2)
    //   step 2, a1: δ = −1 + 0.9·(−2) + 2 = −0.8 → Q = (−2.4, −2.4)
    //   step 3 (cut), a0: bootstrap δ = −1 + 0.9·(−2.4) + 2.4 = −0.76 → Q0 = −2.78
    //                     terminal  δ = −1 + 2.4 = 1.4               → Q0 = −1.7
    let (o, q) = run_with_q(&one_cell_mountain_car(Truncation::Bootstrap), 0);
    assert_eq!(o.episode_lengths, vec![3]);
    let q1 = -2.0 + 0.5 * (-1.0 + 0.9 * -2.0 - -2.0);
    let q0_boot = q1 + 0.5 * (-1.0 + 0.9 * q1 - q1);
    assert_eq!(q, vec![q0_boot, q1]);
    assert!((q0_boot - -2.78).abs() < 1e-12 && (q1 - -2.4).abs() < 1e-12);
    let (o, q) = run_with_q(&one_cell_mountain_car(Truncation::Terminal), 0);
    assert_eq!(o.episode_lengths, vec![3]);
    let q0_term = q1 + 0.5 * (-1.0 - q1);
    assert_eq!(q, vec![q0_term, q1]);
    assert!((q0_term - -1.7).abs() < 1e-12);
}

#[test]
fn the_episode_step_limit_cuts_episodes_at_the_stated_step() {
    let mut c =
        TrialConfig::paper(SystemKind::MountainCar, ReprKind::Crisp, Algorithm::QLambda, vec![6, 6], 3);
    c.limits.success = Success::Reach { within: 150, streak: 1, max_episode_steps: 150 };
    c.limits.max_episodes = 30;
    let mut terminal = c.clone();
    terminal.limits.truncation = Truncation::Terminal;
    let (boot, q_boot) = run_with_q(&c, 4);
    let (term, q_term) = run_with_q(&terminal, 4);
    for o in [&boot, &term] {
        // Early Mountain Car episodes never reach the goal: every one is cut at exactly 150 steps.
        assert_eq!(o.episode_lengths, vec![150; 30]);
        assert_eq!(o.total_steps, 30 * 150);
    }
    assert_ne!(q_boot, q_term, "the cut steps are learned from differently");
    // Cart-Pole: a goal of 200 steps is Gymnasium's CartPole-v0 TimeLimit; the goal episode is
    // exactly 200 steps and ends the trial.
    let mut c = cart_pole(6);
    c.limits.success = Success::Balance { steps: 200 };
    let o = run_trial(&c, 0);
    assert!(o.converged);
    assert_eq!(*o.episode_lengths.last().unwrap(), 200);
    assert!(o.episode_lengths.iter().all(|&l| l <= 200));
}

#[test]
fn digitize_binning_changes_the_trajectory() {
    let mut c = cart_pole(4);
    c.limits.max_episodes = 20;
    let mut d = c.clone();
    d.repr.binning = Binning::Digitize;
    assert_ne!(run_trial(&c, 0).episode_lengths, run_trial(&d, 0).episode_lengths);
}

#[test]
fn settings_resolve_from_every_level_and_from_set_paths() {
    let text = "name: t\nseeds: 1\ndefaults: { start: gym }\nsystems:\n  mountain-car:\n    settings: { truncation: terminal }\n    crisp: { binning: digitize }\n    experiments:\n      - { id: a, repr: crisp, algorithms: [q0], vary: { x == x_dot: 4 } }\n      - { id: b, repr: fuzzy, algorithms: [q0], vary: { x == x_dot: 4 }, settings: { start: fixed } }\n";
    let plan_of = |sets: &[&str]| {
        let overrides: Vec<_> = sets.iter().map(|s| crate::declared::Override::parse(s).unwrap()).collect();
        let spec = crate::declared::load_str(text, "t.yaml", &overrides).unwrap();
        crate::plan::plan(
            &crate::declared::LoadedSpec { spec, path: "t.yaml".into(), variants: Vec::new() },
            None,
        )
        .unwrap()
    };
    let p = plan_of(&[]);
    let (a, b) = (&p.experiments[0].cells[0].config, &p.experiments[1].cells[0].config);
    assert_eq!(
        (a.start, a.limits.truncation, a.repr.binning),
        (StartKind::Gym, Truncation::Terminal, Binning::Digitize)
    );
    assert_eq!(
        (b.start, b.limits.truncation, b.repr.binning),
        (StartKind::Fixed, Truncation::Terminal, Binning::Midpoint)
    );
    let p = plan_of(&["systems.mountain-car.crisp.binning=midpoint", "defaults.start=fixed"]);
    let a = &p.experiments[0].cells[0].config;
    assert_eq!((a.start, a.repr.binning), (StartKind::Fixed, Binning::Midpoint));
    let _ = EnvParams::default_for(SystemKind::MountainCar);
}
