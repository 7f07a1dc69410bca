//! `qsweep trial`: every system × representation × algorithm runs, deterministically, and bad
//! arguments are refused cleanly.

use crate::helpers::{qsweep, stdout, Test};
use serde_json::Value;

fn trial_json(args: &[&str]) -> Value {
    serde_json::from_str(&stdout(qsweep().arg("trial").args(args).arg("--json"))).unwrap()
}

#[test]
fn every_system_representation_and_algorithm_runs() {
    for env in ["ball-beam", "cart-pole", "mountain-car"] {
        for repr in ["crisp", "fuzzy"] {
            for alg in ["q0", "q-lambda"] {
                let args = [
                    "--env",
                    env,
                    "--repr",
                    repr,
                    "--resolution",
                    "3",
                    "--algorithm",
                    alg,
                    "--max-episodes",
                    "5",
                ];
                let v = trial_json(&args);
                let o = &v["outcome"];
                let lengths = o["episode_lengths"].as_array().unwrap();
                assert_eq!(o["episodes"].as_u64().unwrap() as usize, lengths.len(), "{env} {repr} {alg}");
                let sum: u64 = lengths.iter().map(|l| l.as_u64().unwrap()).sum();
                assert_eq!(o["total_steps"].as_u64().unwrap(), sum);
                assert_eq!(v["config"]["repr"]["kind"], repr);
                // Table II defaults were applied.
                let eps = v["config"]["learner"]["epsilon"].as_f64().unwrap();
                let want = match env {
                    "ball-beam" => 1e-6,
                    "cart-pole" => 1e-2,
                    _ => 5e-2,
                };
                assert_eq!(eps, want);
            }
        }
    }
}

#[test]
fn same_seed_same_outcome_other_seed_differs() {
    let args = [
        "--env",
        "cart-pole",
        "--repr",
        "fuzzy",
        "--resolution",
        "3",
        "--algorithm",
        "q-lambda",
        "--max-episodes",
        "20",
    ];
    let a = trial_json(&[&args[..], &["--seed", "4"]].concat());
    let b = trial_json(&[&args[..], &["--seed", "4"]].concat());
    let c = trial_json(&[&args[..], &["--seed", "5"]].concat());
    assert_eq!(a["outcome"], b["outcome"]);
    assert_ne!(a["outcome"]["episode_lengths"], c["outcome"]["episode_lengths"]);
}

#[test]
fn bad_arguments_exit_2_naming_the_argument() {
    let base = ["trial", "--env", "ball-beam", "--repr", "crisp", "--algorithm", "q0"];
    let cases: &[(&[&str], &str)] = &[
        (&["--resolution", "0"], "0 is not allowed"),
        (
            &["--resolution", "3,3,3"],
            "--resolution: ball-beam has 2 state variables (x,x_dot); give 2 values",
        ),
        (&["--resolution", "3", "--actions", "1"], "n ≥ 2"),
        (&["--resolution", "3", "--lambda", "1.5"], "expected a number in [0, 1]"),
        (&["--resolution", "3", "--alpha", "0"], "expected a finite number > 0"),
        (&["--resolution", "3", "--param", "nope=1"], "unknown parameter"),
    ];
    for (extra, want) in cases {
        Test::new().args(base).args(*extra).status(2).stderr_contains(want).run();
    }
}
