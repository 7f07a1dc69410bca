//! `qsweep simulate`: the CSV format, hand-computed Ball-Beam values, and bad input.

use crate::helpers::{fails_with, qsweep, stdout};

#[test]
fn ball_beam_matches_equation_1_computed_by_hand() {
    let out = stdout(qsweep().args([
        "simulate",
        "--env",
        "ball-beam",
        "--state",
        "0.1,0.5",
        "--actions",
        "0.5,-0.25",
    ]));
    let rows: Vec<Vec<&str>> = out.lines().map(|l| l.split(',').collect()).collect();
    assert_eq!(rows[0], ["step", "action", "x", "x_dot", "reward", "terminal"]);
    assert_eq!(rows[1], ["0", "", "0.1", "0.5", "0", "0"]);
    // x1 = x0 + τ ẋ0; ẋ1 = ẋ0 + τ g sin(φ1), with the engine's own sin (the same on every CPU).
    let (tau, g) = (0.02, 9.81);
    let sin = qsweep_engine::math::sin;
    let (x1, v1) = (0.1 + tau * 0.5, 0.5 + tau * g * sin(0.5));
    let (x2, v2) = (x1 + tau * v1, v1 + tau * g * sin(-0.25));
    for (row, (x, v)) in rows[2..].iter().zip([(x1, v1), (x2, v2)]) {
        assert_eq!(row[2].parse::<f64>().unwrap(), x);
        assert_eq!(row[3].parse::<f64>().unwrap(), v);
        assert_eq!(&row[4..], ["0", "0"]);
    }
    assert_eq!(rows.len(), 4);
}

#[test]
fn stops_after_the_first_terminal_step_with_the_failure_reward() {
    let out = stdout(qsweep().args([
        "simulate",
        "--env",
        "ball-beam",
        "--state",
        "0.99,1",
        "--actions",
        "0,0,0,0",
    ]));
    let last = out.lines().last().unwrap();
    assert!(last.ends_with(",-1,1"), "{out}");
    assert_eq!(out.lines().count(), 3, "{out}");
}

#[test]
fn mountain_car_reaches_the_goal_with_reward_1_and_zeroes_velocity_at_the_left_wall() {
    let out = stdout(qsweep().args([
        "simulate",
        "--env",
        "mountain-car",
        "--state",
        "0.49,0.07",
        "--actions",
        "1",
    ]));
    assert!(out.lines().last().unwrap().ends_with(",1,1"), "{out}");
    let out = stdout(qsweep().args([
        "simulate",
        "--env",
        "mountain-car",
        "--state",
        "-1.19,-0.05",
        "--actions",
        "-1",
    ]));
    let last: Vec<&str> = out.lines().last().unwrap().split(',').collect();
    assert_eq!(last[2], "-1.2");
    assert_eq!(last[3], "0");
}

#[test]
fn bad_input_is_a_one_line_error_with_exit_code_2() {
    let cases: &[(&[&str], &str)] = &[
        (&["--env", "pendulum", "--state", "0,0", "--actions", "1"], "unknown system"),
        (&["--env", "cart-pole", "--state", "0,0", "--actions", "1"], "needs 4 values"),
        (&["--env", "ball-beam", "--state", "0,abc", "--actions", "1"], "not a number"),
        (&["--env", "ball-beam", "--state", "0,inf", "--actions", "1"], "expected a finite number"),
        (
            &["--env", "ball-beam", "--state", "0,0", "--actions", "1", "--param", "mass=2"],
            "unknown parameter",
        ),
        (&["--env", "ball-beam", "--state", "0,0", "--actions", "1", "--param", "tau=-1"], "tau"),
    ];
    for (args, want) in cases {
        let err = fails_with(qsweep().arg("simulate").args(*args), 2);
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}
