//! The settings of the preregistered readings (b) and (c) from the command line: Gym's solved rule
//! (`success: { …, window, mean_length }`, `counting: window-start`) and ballbeam-gym's
//! rate-controlled beam (`params.control: rate`, `simulate`/`feasible --control rate`).

use crate::helpers::{fails_with, qsweep, stdout, Sandbox};
use serde_json::Value;

fn trial_json(args: &[&str]) -> Value {
    serde_json::from_str(&stdout(qsweep().arg("trial").args(args).arg("--json"))).unwrap()
}

const CART_POLE: [&str; 8] =
    ["--env", "cart-pole", "--repr", "crisp", "--resolution", "3", "--algorithm", "q0"];

#[test]
fn a_trial_under_the_solved_rule_runs_on_past_its_cut_episodes() {
    // Cart-Pole cannot fall within 5 steps from rest: every episode is cut at 5, so a mean of
    // at least 5 over 3 episodes is first reached at episode 3.
    let v = trial_json(
        &[
            &CART_POLE[..],
            &["--set", "success.steps=5", "--set", "success.window=3", "--set", "success.mean_length=5"],
        ]
        .concat(),
    );
    assert_eq!(
        v["config"]["limits"]["success"],
        serde_json::json!({"kind": "solved", "window": 3, "mean_length": 5.0, "episode_steps": 5})
    );
    assert_eq!(v["outcome"]["episodes_to_goal"], 3);
    assert_eq!(v["outcome"]["episode_lengths"], serde_json::json!([5, 5, 5]));
    // The plain goal ends the trial at the first cut episode.
    let v = trial_json(&[&CART_POLE[..], &["--balance-steps", "5"]].concat());
    assert_eq!(v["outcome"]["episodes_to_goal"], 1);
}

#[test]
fn a_window_without_its_mean_length_names_the_set_argument() {
    let err = fails_with(
        qsweep().arg("trial").args(CART_POLE).args([
            "--set",
            "success.steps=200",
            "--set",
            "success.window=100",
        ]),
        2,
    );
    assert!(
        err.contains("with --set success.steps=200 --set success.window=100: systems.cart-pole.success: "),
        "{err}"
    );
    assert!(err.contains("`window` needs `mean_length`"), "{err}");
}

#[test]
fn variants_may_set_the_solved_rule_field_by_field_and_count_the_windows_start() {
    let sb = Sandbox::new();
    let text = "name: r\nseeds: 2\ndefaults: { max_episodes: 40 }\nsystems:\n  cart-pole:\n    success: { steps: 5 }\n    experiments:\n      - { id: 1, repr: crisp, algorithms: [q0], vary: { x == x_dot == theta == theta_dot: 2 } }\nvariants:\n  - id: end\n    set:\n      systems.cart-pole.success.window: 4\n      systems.cart-pole.success.mean_length: 5\n  - id: start\n    set:\n      counting: window-start\n      systems.cart-pole.success.window: 4\n      systems.cart-pole.success.mean_length: 5\n";
    let file = sb.write("r.yaml", text);
    stdout(&mut sb.qsweep(&["run", file.to_str().unwrap()]));
    let mean = |variant: &str| {
        let csv = std::fs::read_to_string(sb.path(&format!("reports/r/{variant}/table3.csv"))).unwrap();
        let rows = crate::helpers::csv_rows(&csv);
        rows[0]["mean"].parse::<f64>().unwrap()
    };
    // Every episode is cut at 5: solved at episode 4, whose window starts at episode 1.
    assert_eq!((mean("end"), mean("start")), (4.0, 1.0));
    // A variant that sets only one of the pair is refused at its own line.
    let bad = sb.write(
        "bad.yaml",
        &text.replace("      systems.cart-pole.success.mean_length: 5\n  - id: start", "  - id: start"),
    );
    let err = fails_with(&mut sb.qsweep(&["run", bad.to_str().unwrap()]), 2);
    assert!(
        err.contains("bad.yaml:10:")
            && err.contains("variant `end`")
            && err.contains("`window` needs `mean_length`"),
        "{err}"
    );
}

#[test]
fn simulate_under_rate_control_prints_the_beam_angle() {
    let out = stdout(qsweep().args([
        "simulate",
        "--env",
        "ball-beam",
        "--control",
        "rate",
        "--param",
        "tau=0.1",
        "--param",
        "beam_length=1",
        "--param",
        "angle_max=0.2",
        "--state",
        "0,0",
        "--actions",
        "0.8,0.8,0.8,-0.8",
    ]));
    let rows: Vec<Vec<&str>> = out.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows[0], ["step", "action", "x", "x_dot", "theta", "reward", "terminal"]);
    assert_eq!(rows[1], ["0", "", "0", "0", "0", "0", "0"]);
    // θ ← clamp(θ + rate·τ, ±0.2), then eq. (1) with sin(θ): 0.08, 0.16, 0.2 (the stop), 0.12.
    let theta: Vec<f64> = rows[2..].iter().map(|r| r[4].parse().unwrap()).collect();
    for (got, want) in theta.iter().zip([0.08, 0.16, 0.2, 0.12]) {
        assert!((got - want).abs() < 1e-12, "{theta:?}");
    }
    let sin = qsweep_engine::math::sin;
    let v1 = 0.1 * 9.81 * sin(0.1 * 0.8);
    assert_eq!(rows[2][2..4], ["0".to_string(), format!("{v1}")]);
    let err = fails_with(
        qsweep().args([
            "simulate",
            "--env",
            "cart-pole",
            "--control",
            "rate",
            "--state",
            "0,0,0,0",
            "--actions",
            "1",
        ]),
        2,
    );
    assert!(err.contains("--control is for ball-beam"), "{err}");
}

#[test]
fn feasible_searches_a_rate_controlled_beam() {
    let args = [
        "feasible",
        "--env",
        "ball-beam",
        "--control",
        "rate",
        "--param",
        "tau=0.1",
        "--param",
        "beam_length=1",
        "--param",
        "angle_max=0.2",
        "--resolution",
        "2",
        "--actions",
        "2",
        "--max-steps",
        "5000",
        "--state=0.3,0.4",
        "--json",
    ];
    let v: Value = serde_json::from_str(&stdout(qsweep().args(args))).unwrap();
    assert_eq!((v["best"].as_u64(), v["complete"].as_bool()), (Some(22), Some(true)));
    let actions: Vec<f64> =
        v["policy_cells"].as_array().unwrap().iter().map(|c| c["action"].as_f64().unwrap()).collect();
    assert!(actions.iter().all(|a| a.abs() == 0.8), "rates ±rate_max: {actions:?}");
}
