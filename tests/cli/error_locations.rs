//! Every validation error names the field (its full dotted path) and points at the line and column
//! of the field's own key, in flow style (`crisp: { alpha: -0.1 }`) and block style alike; a value
//! given by `--set` names the field and the `--set` argument; the CLI and pipeline files refuse a
//! value in the same words.

use crate::helpers::{fails_with, qsweep, Sandbox};

/// Where a case's snippet goes in the pipeline.
#[derive(Clone, Copy)]
enum At {
    /// Top level (replaces `seeds: 2`).
    Top,
    /// Inside `ball-beam:`.
    BallBeam,
    /// Inside ball-beam's experiment (a `vary:` here replaces the default one).
    Experiment,
    /// Inside `mountain-car:`.
    MountainCar,
}

/// One bad value: where it goes, its snippet in flow and in block style (unindented), the text
/// that starts the field's key in both, the field's full path, and part of the message.
struct Case {
    at: At,
    flow: &'static str,
    block: &'static str,
    key: &'static str,
    path: &'static str,
    says: &'static str,
}

/// The pipeline with `snippet` placed at `at`.
fn pipeline(at: At, snippet: &str) -> String {
    let put = |here: At, indent: usize| {
        if std::mem::discriminant(&here) != std::mem::discriminant(&at) {
            return String::new();
        }
        snippet.lines().map(|l| format!("{}{l}\n", " ".repeat(indent))).collect()
    };
    let top = match at {
        At::Top => put(At::Top, 0),
        _ => "seeds: 2\n".to_string(),
    };
    let vary = if matches!(at, At::Experiment) && snippet.contains("vary") {
        String::new()
    } else {
        "        vary: { x: 2..3, x_dot: 2 }\n".to_string()
    };
    format!(
        "name: locations\n{top}systems:\n  ball-beam:\n{}    experiments:\n      - id: 1\n        repr: crisp\n{vary}{}\
         \x20 mountain-car:\n{}    experiments:\n      - {{ id: 1, repr: crisp, vary: {{ x: 2, x_dot: 2 }} }}\n",
        put(At::BallBeam, 4),
        put(At::Experiment, 8),
        put(At::MountainCar, 4),
    )
}

/// 1-based line and column where `key` starts in `text` (it must occur once).
fn position(text: &str, key: &str) -> (usize, usize) {
    assert_eq!(text.matches(key).count(), 1, "`{key}` must be unique in:\n{text}");
    let offset = text.find(key).unwrap();
    let line = text[..offset].matches('\n').count() + 1;
    let col = offset - text[..offset].rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, col)
}

fn cases() -> Vec<Case> {
    let setting = |key: &'static str, flow: &'static str, block: &'static str, path: &'static str, says| {
        Case { at: At::BallBeam, flow, block, key, path, says }
    };
    vec![
        setting(
            "epsilon: -0.1",
            "crisp: { gamma: 0.9, epsilon: -0.1, alpha: 0.1 }",
            "crisp:\n  gamma: 0.9\n  epsilon: -0.1\n  alpha: 0.1",
            "systems.ball-beam.crisp.epsilon",
            "-0.1 is not allowed here; expected a number in [0, 1]",
        ),
        setting(
            "gamma: 1.5",
            "crisp: { epsilon: 0.1, gamma: 1.5, alpha: 0.1 }",
            "crisp:\n  epsilon: 0.1\n  gamma: 1.5\n  alpha: 0.1",
            "systems.ball-beam.crisp.gamma",
            "1.5 is not allowed here; expected a number in [0, 1]",
        ),
        setting(
            "alpha: -0.1",
            "crisp: { gamma: 0.9, alpha: -0.1, epsilon: 0.1 }",
            "crisp:\n  gamma: 0.9\n  alpha: -0.1\n  epsilon: 0.1",
            "systems.ball-beam.crisp.alpha",
            "-0.1 is not allowed here; expected a finite number > 0",
        ),
        setting(
            "lambda: 2",
            "crisp: { gamma: 0.9, lambda: 2, epsilon: 0.1 }",
            "crisp:\n  gamma: 0.9\n  lambda: 2\n  epsilon: 0.1",
            "systems.ball-beam.crisp.lambda",
            "2 is not allowed here; expected a number in [0, 1]",
        ),
        setting(
            "q_init: .nan",
            "crisp: { gamma: 0.9, q_init: .nan, epsilon: 0.1 }",
            "crisp:\n  gamma: 0.9\n  q_init: .nan\n  epsilon: 0.1",
            "systems.ball-beam.crisp.q_init",
            "NaN is not allowed here; expected a finite number",
        ),
        setting(
            "trace_cutoff: 1",
            "crisp: { gamma: 0.9, trace_cutoff: 1, epsilon: 0.1 }",
            "crisp:\n  gamma: 0.9\n  trace_cutoff: 1\n  epsilon: 0.1",
            "systems.ball-beam.crisp.trace_cutoff",
            "1 is not allowed here; expected a number in [0, 1)",
        ),
        setting(
            "width: 0",
            "fuzzy: { gamma: 0.9, width: 0, epsilon: 0.1 }",
            "fuzzy:\n  gamma: 0.9\n  width: 0\n  epsilon: 0.1",
            "systems.ball-beam.fuzzy.width",
            "0 is not allowed here; expected a finite number > 0",
        ),
        setting(
            "prune: 1.5",
            "fuzzy: { gamma: 0.9, prune: 1.5, epsilon: 0.1 }",
            "fuzzy:\n  gamma: 0.9\n  prune: 1.5\n  epsilon: 0.1",
            "systems.ball-beam.fuzzy.prune",
            "1.5 is not allowed here; expected a number in [0, 1)",
        ),
        setting(
            "max_episodes: 0",
            "settings: { gamma: 0.9, max_episodes: 0, epsilon: 0.1 }",
            "settings:\n  gamma: 0.9\n  max_episodes: 0\n  epsilon: 0.1",
            "systems.ball-beam.settings.max_episodes",
            "0 is not allowed here; expected an integer ≥ 1",
        ),
        setting(
            "max_total_steps: 0",
            "settings: { gamma: 0.9, max_total_steps: 0, epsilon: 0.1 }",
            "settings:\n  gamma: 0.9\n  max_total_steps: 0\n  epsilon: 0.1",
            "systems.ball-beam.settings.max_total_steps",
            "0 is not allowed here; expected an integer ≥ 1",
        ),
        setting(
            "steps: 0",
            "success: { steps: 0 }",
            "success:\n  steps: 0",
            "systems.ball-beam.success.steps",
            "0 is not allowed here; expected an integer from 1 to 4294967295",
        ),
        setting(
            "window: 0",
            "success: { steps: 200, window: 0, mean_length: 195 }",
            "success:\n  steps: 200\n  window: 0\n  mean_length: 195",
            "systems.ball-beam.success.window",
            "0 is not allowed here; expected an integer ≥ 1",
        ),
        setting(
            "mean_length: -195",
            "success: { steps: 200, window: 100, mean_length: -195 }",
            "success:\n  steps: 200\n  window: 100\n  mean_length: -195",
            "systems.ball-beam.success.mean_length",
            "-195 is not allowed here; expected a finite number > 0",
        ),
        Case {
            at: At::MountainCar,
            flow: "success: { max_episode_steps: 200, window: 100, mean_length: .nan }",
            block: "success:\n  max_episode_steps: 200\n  window: 100\n  mean_length: .nan",
            key: "mean_length: .nan",
            path: "systems.mountain-car.success.mean_length",
            says: "NaN is not allowed here; expected a finite number > 0",
        },
        setting(
            "control: speed",
            "params: { tau: 0.1, control: speed }",
            "params:\n  tau: 0.1\n  control: speed",
            "systems.ball-beam.params.control",
            "unknown variant `speed`, expected `angle` or `rate`",
        ),
        setting(
            "rate_max: 0",
            "params: { control: rate, rate_max: 0, tau: 0.1 }",
            "params:\n  control: rate\n  rate_max: 0\n  tau: 0.1",
            "systems.ball-beam.params.rate_max",
            "0 is not allowed here; expected a finite number > 0",
        ),
        Case {
            at: At::MountainCar,
            flow: "success: { within: 0, streak: 1 }",
            block: "success:\n  within: 0\n  streak: 1",
            key: "within: 0",
            path: "systems.mountain-car.success.within",
            says: "0 is not allowed here; expected an integer ≥ 1",
        },
        Case {
            at: At::MountainCar,
            flow: "success: { within: 10, streak: 0 }",
            block: "success:\n  within: 10\n  streak: 0",
            key: "streak: 0",
            path: "systems.mountain-car.success.streak",
            says: "0 is not allowed here; expected an integer ≥ 1",
        },
        Case {
            at: At::MountainCar,
            flow: "success: { max_episode_steps: 0, streak: 1 }",
            block: "success:\n  max_episode_steps: 0\n  streak: 1",
            key: "max_episode_steps: 0",
            path: "systems.mountain-car.success.max_episode_steps",
            says: "0 is not allowed here; expected an integer from 1 to 4294967295",
        },
        setting(
            "x_dot: [1, -1]",
            "ranges: { x: [-1, 1], x_dot: [1, -1] }",
            "ranges:\n  x: [-1, 1]\n  x_dot: [1, -1]",
            "systems.ball-beam.ranges.x_dot",
            "[1, -1] is not allowed; expected two finite numbers with lo < hi",
        ),
        setting(
            "theta: [0, 1]",
            "ranges: { x: [-1, 1], theta: [0, 1] }",
            "ranges:\n  x: [-1, 1]\n  theta: [0, 1]",
            "systems.ball-beam.ranges.theta",
            "unknown variable `theta` for ball-beam",
        ),
        setting(
            "beam_length: -2",
            "params: { gravity: 9.81, beam_length: -2, tau: 0.02 }",
            "params:\n  gravity: 9.81\n  beam_length: -2\n  tau: 0.02",
            "systems.ball-beam.params.beam_length",
            "-2 is not allowed here; expected a finite number > 0",
        ),
        Case {
            at: At::Top,
            flow: "seeds: 0",
            block: "seeds:\n  0",
            key: "seeds:",
            path: "seeds",
            says: "0 is not allowed; use at least 1",
        },
        Case {
            at: At::Top,
            flow: "seeds: [4, 5, 4]",
            block: "seeds:\n  - 4\n  - 5\n  - 4",
            key: "seeds:",
            path: "seeds",
            says: "seed 4 is listed twice",
        },
        Case {
            at: At::Experiment,
            flow: "vary: { x: 2..3, x_dot: [2, 0] }",
            block: "vary:\n  x: 2..3\n  x_dot: [2, 0]",
            key: "x_dot: [2, 0]",
            path: "systems.ball-beam.experiments.0.vary.x_dot",
            says: "0 is not allowed; every variable needs at least 1 bin or fuzzy set",
        },
        Case {
            at: At::Experiment,
            flow: "vary: { x == x_dot: \"3..1\" }",
            block: "vary:\n  x == x_dot: \"3..1\"",
            key: "x == x_dot:",
            path: "systems.ball-beam.experiments.0.vary.x == x_dot",
            says: "range \"3..1\" is empty",
        },
        Case {
            at: At::Experiment,
            flow: "fixed: { actions: 1 }",
            block: "fixed:\n  actions: 1",
            key: "actions: 1",
            path: "systems.ball-beam.experiments.0.fixed.actions",
            says: "1 actions is not allowed; A_n needs n ≥ 2",
        },
        Case {
            at: At::Experiment,
            flow: "fixed: { x: 0 }",
            block: "fixed:\n  x: 0",
            key: "x: 0",
            path: "systems.ball-beam.experiments.0.fixed.x",
            says: "0 is not allowed; every variable needs at least 1 bin",
        },
    ]
}

#[test]
fn every_bad_value_points_at_its_own_key_in_flow_and_block_style() {
    let sb = Sandbox::new();
    let mut checked = 0;
    for case in cases() {
        for (style, snippet) in [("flow", case.flow), ("block", case.block)] {
            let text = pipeline(case.at, snippet);
            let file = sb.write("bad.yaml", &text);
            let err = fails_with(&mut sb.qsweep(&["run", file.to_str().unwrap()]), 2);
            let (line, col) = position(&text, case.key);
            let want = format!("bad.yaml:{line}:{col}: {}: {}", case.path, case.says);
            assert!(err.contains(&want), "{} ({style}): wanted {want:?} in {err}\n{text}", case.path);
            checked += 1;
        }
    }
    assert_eq!(checked, 2 * cases().len());
    assert_eq!(sb.segments(), 0, "nothing was written");
}

#[test]
fn errors_about_a_whole_section_point_at_its_key() {
    let sb = Sandbox::new();
    let cases = [
        (
            At::BallBeam,
            "crisp: { gamma: 0.9, alpah: 0.1 }",
            "alpah:",
            "systems.ball-beam.crisp",
            "did you mean `alpha`?",
        ),
        (
            At::Experiment,
            "algorithms: [q0, q0]",
            "algorithms:",
            "systems.ball-beam.experiments.0.algorithms",
            "listed twice",
        ),
        (At::Experiment, "fixed:\n  x: 3", "fixed:", "systems.ball-beam.experiments.0.fixed", "both varied"),
        (
            At::BallBeam,
            "success: { steps: 200, window: 100 }",
            "success:",
            "systems.ball-beam.success",
            "`window` needs `mean_length`: Gym's solved rule takes both",
        ),
        (
            At::Experiment,
            "success:\n  steps: 200\n  mean_length: 195",
            "success:",
            "systems.ball-beam.experiments.0.success",
            "`mean_length` needs `window`",
        ),
        (
            At::MountainCar,
            "success: { streak: 2, window: 100, mean_length: 110 }",
            "success:",
            "systems.mountain-car.success",
            "`streak` and `window` are two different goals",
        ),
        (
            At::Experiment,
            "vary: { x: 2 }",
            "vary: { x: 2 }",
            "systems.ball-beam.experiments.0.vary",
            "`x_dot` has no resolution",
        ),
    ];
    for (at, snippet, key, path, says) in cases {
        let text = pipeline(at, snippet);
        let file = sb.write("section.yaml", &text);
        let err = fails_with(&mut sb.qsweep(&["run", file.to_str().unwrap()]), 2);
        let (line, col) = position(&text, key);
        let want = format!("section.yaml:{line}:{col}: {path}: ");
        assert!(err.contains(&want) && err.contains(says), "wanted {want:?} and {says:?} in {err}\n{text}");
    }
}

#[test]
fn a_duplicate_experiment_id_points_at_the_second_id() {
    let sb = Sandbox::new();
    let text = pipeline(At::BallBeam, "").replace(
        "        vary: { x: 2..3, x_dot: 2 }\n",
        "        vary: { x: 2..3, x_dot: 2 }\n      - { id: 1, repr: fuzzy, vary: { x: 2, x_dot: 2 } }\n",
    );
    let file = sb.write("dup.yaml", &text);
    let err = fails_with(&mut sb.qsweep(&["run", file.to_str().unwrap()]), 2);
    let (line, col) = position(&text, "id: 1, repr: fuzzy");
    let want = format!("dup.yaml:{line}:{col}: systems.ball-beam.experiments.1.id: id 1 is used twice");
    assert!(err.contains(&want), "wanted {want:?} in {err}");
}

#[test]
fn a_bad_set_value_names_the_field_and_its_argument() {
    let sb = Sandbox::new();
    let file = sb.write("ok.yaml", &pipeline(At::BallBeam, "crisp: { alpha: 0.1 }"));
    let err = fails_with(
        &mut sb.qsweep(&[
            "run",
            file.to_str().unwrap(),
            "--set",
            "seeds=3",
            "--set",
            "systems.ball-beam.crisp.alpha=-1",
        ]),
        2,
    );
    let want =
        "ok.yaml with --set systems.ball-beam.crisp.alpha=-1: systems.ball-beam.crisp.alpha: -1 is not \
                allowed here; expected a finite number > 0";
    assert!(err.contains(want), "wanted {want:?} in {err}");
    assert!(!err.contains("seeds=3"), "only the argument that set the field is named: {err}");
}

#[test]
fn the_cli_and_pipeline_files_refuse_a_value_in_the_same_words() {
    let sb = Sandbox::new();
    let base =
        ["trial", "--env", "ball-beam", "--repr", "fuzzy", "--algorithm", "q-lambda", "--resolution", "3"];
    let cases: &[(&str, &str, &str)] = &[
        ("--alpha", "0", "alpha: 0"),
        ("--gamma", "1.5", "gamma: 1.5"),
        ("--prune", "1", "prune: 1"),
        ("--trace-cutoff", "2", "trace_cutoff: 2"),
        ("--width", "-1", "width: -1"),
    ];
    for (flag, value, yaml) in cases {
        let cli = fails_with(qsweep().args(base).arg(format!("{flag}={value}")), 2);
        let text = pipeline(At::BallBeam, &format!("fuzzy: {{ {yaml} }}"));
        let file = sb.write("same.yaml", &text);
        let file_err = fails_with(&mut sb.qsweep(&["run", file.to_str().unwrap()]), 2);
        let rule = file_err.rsplit(": ").next().unwrap().trim();
        assert!(rule.starts_with(&format!("{value} is not allowed here; expected ")), "{file_err}");
        assert!(cli.contains(rule), "{flag}: the CLI says {cli:?}, the pipeline says {rule:?}");
    }
}
