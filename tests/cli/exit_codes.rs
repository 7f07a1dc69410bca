//! The guide's exit-code table (docs/commands.md), checked against every subcommand: the table lists exactly the
//! `qsweep_pipeline::error::exit` constants, and each subcommand exits with each code that applies to it.

use crate::helpers::{repo, Test};
use qsweep_pipeline::error::exit;
use std::collections::BTreeSet;

/// The codes of the guide's "Exit codes" table (docs/commands.md).
fn readme_codes() -> BTreeSet<i32> {
    let guide = std::fs::read_to_string(repo().join("docs/commands.md")).unwrap();
    let section = guide.split("## Exit codes").nth(1).expect("docs/commands.md has an Exit codes section");
    section
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .filter_map(|l| l.split('|').nth(1)?.trim().parse().ok())
        .collect()
}

#[test]
fn the_guide_table_lists_exactly_the_exit_constants() {
    let constants: BTreeSet<i32> =
        [exit::OK, exit::FAILURE, exit::USAGE, exit::INTERRUPTED].into_iter().map(i32::from).collect();
    assert_eq!(readme_codes(), constants);
}

/// One invocation per (subcommand, code) that applies. 130 (interrupted) applies to `run` and
/// `report` and needs a signal mid-way: `pipeline::ctrl_c_flushes_finished_trials_exits_130_…`,
/// `pipeline::sigterm_…` and `gc_beside::ctrl_c_stops_a_report_…` cover it.
#[test]
fn every_subcommand_exits_with_the_documented_codes() {
    let ok = i32::from(exit::OK);
    let failure = i32::from(exit::FAILURE);
    let usage = i32::from(exit::USAGE);
    let trial =
        ["trial", "--env", "cart-pole", "--repr", "crisp", "--resolution", "2,2,2,2", "--algorithm", "q0"];
    let mut covered: BTreeSet<(&str, i32)> = BTreeSet::new();
    let mut case = |name: &'static str, code: i32, t: Test| {
        t.status(code).run();
        covered.insert((name, code));
    };

    case(
        "bench",
        ok,
        Test::new().args(["bench", "--steps", "1000", "--repeat", "1", "--filter", "cart-pole"]),
    );
    case("bench", usage, Test::new().args(["bench", "--steps", "many"]));

    case(
        "simulate",
        ok,
        Test::new().args(["simulate", "--env", "cart-pole", "--state", "0,0,0,0", "--actions", "10"]),
    );
    case(
        "simulate",
        usage,
        Test::new().args(["simulate", "--env", "pendulum", "--state", "0", "--actions", "1"]),
    );

    case("trial", ok, Test::new().args(trial).args(["--max-episodes", "3"]));
    case("trial", usage, Test::new().args(trial).args(["--alpha", "0"]));
    case("trial", failure, Test::new().args(trial).args(["--max-episodes", "3", "--param", "gravity=1e308"]));

    case(
        "run",
        ok,
        Test::new().pipeline("tiny.yaml").args(["run", "tiny.yaml", "--set", "seeds=1", "--quiet"]),
    );
    case("run", usage, Test::new().pipeline("tiny.yaml").args(["run", "tiny.yaml", "--set", "sedes=1"]));
    case("run", failure, Test::new().pipeline("absurd.yaml").args(["run", "absurd.yaml", "--quiet"]));

    case("status", ok, Test::new().pipeline("tiny.yaml").args(["status", "tiny.yaml"]));
    case(
        "status",
        usage,
        Test::new().pipeline("tiny.yaml").args(["status", "tiny.yaml", "--set", "seeds=x"]),
    );

    // report, verify and gc share one code for a missing cache: 2, bad input.
    let cached = || {
        Test::new()
            .pipeline("tiny.yaml")
            .args(["run", "tiny.yaml", "--set", "seeds=1", "--quiet"])
            .run()
            .then()
    };
    case("report", ok, cached().args(["report", "tiny.yaml", "--set", "seeds=1"]).stderr_lacks("error"));
    case("report", usage, Test::new().pipeline("tiny.yaml").args(["report", "tiny.yaml"]));
    // Fewer trials than the report it would replace.
    case(
        "report",
        failure,
        cached().file("empty/.keep", "").args([
            "report",
            "tiny.yaml",
            "--set",
            "seeds=1",
            "--cache",
            "empty",
        ]),
    );

    case("verify", ok, cached().args(["verify"]));
    case("verify", usage, Test::new().args(["verify"]));
    case("verify", failure, Test::new().file("cache/seg-bad.parquet", "not parquet").args(["verify"]));

    case("gc", ok, cached().args(["gc", "--dry-run"]));
    case("gc", usage, Test::new().args(["gc"]));

    // Between two cache directories (a bucket needs a server: tests/cli/bucket.rs).
    case("cache", ok, cached().args(["cache", "push", "cache", "merged"]));
    case("cache", usage, Test::new().args(["cache", "push", "no-such-cache", "merged"]));

    case(
        "feasible",
        ok,
        Test::new().args(["feasible", "--env", "cart-pole", "--resolution", "2", "--max-steps", "1000"]),
    );
    case("feasible", usage, Test::new().args(["feasible", "--env", "mountain-car", "--resolution", "2"]));

    case("slurm", ok, Test::new().pipeline("tiny.yaml").args(["slurm", "tiny.yaml", "--array", "2"]));
    case("slurm", usage, Test::new().pipeline("tiny.yaml").args(["slurm", "tiny.yaml", "--array", "0"]));

    // Two program pipelines compared: a one-cell sweep of a shell program, run first.
    let prog =
        "name: p\nseeds: 2\nprogram:\n  command: [sh, -c, 'cat >/dev/null; echo \"{\\\"x\\\": 1}\"']\n  \
                metrics: { x: int }\nparams: { a: 1 }\n";
    let ran = Test::new().file("p.yaml", prog).args(["run", "p.yaml", "--quiet", "--no-report"]).run();
    case("compare", ok, ran.then().args(["compare", "p.yaml", "p.yaml", "--metric", "x"]));
    case(
        "compare",
        usage,
        Test::new().file("p.yaml", prog).args(["compare", "p.yaml", "p.yaml", "--where-a", "nope=1"]),
    );
    case(
        "compare",
        failure,
        Test::new().file("p.yaml", prog).args(["compare", "p.yaml", "p.yaml", "--metric", "x"]),
    );

    // Every subcommand has a success and a bad-input case.
    let help = String::from_utf8(crate::helpers::qsweep().arg("--help").output().unwrap().stdout).unwrap();
    let subcommands: Vec<&str> = help
        .split("Commands:")
        .nth(1)
        .unwrap()
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .take_while(|w| *w != "Options:")
        .filter(|w| *w != "help")
        .collect();
    assert!(subcommands.len() >= 9, "{help}");
    for s in subcommands {
        for code in [ok, usage] {
            assert!(covered.contains(&(s, code)), "no exit-code case for `qsweep {s}` exiting {code}");
        }
    }
}

/// Regression: `qsweep … | head` panicked with "failed printing to stdout: Broken pipe".
#[cfg(unix)]
#[test]
fn a_closed_stdout_ends_the_command_quietly() {
    use std::io::Read;
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_qsweep"))
        .args(["feasible", "--env", "cart-pole", "--resolution", "2"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader goes away before anything is written
    let mut err = String::new();
    child.stderr.take().unwrap().read_to_string(&mut err).unwrap();
    child.wait().unwrap();
    assert!(!err.contains("panicked"), "{err}");
}
