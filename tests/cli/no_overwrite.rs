//! No silent overwrites and no cache created by a read-only command: `report` (and the report at
//! the end of `run`) refuses to replace a report of more trials unless `--force`; `report`, `verify`
//! and `gc` exit 2 on a missing cache without creating it; `status` shows every trial missing.

use crate::helpers::Test;

#[test]
fn report_refuses_to_replace_a_bigger_report_unless_forced() {
    let done = Test::new()
        .pipeline("tiny.yaml")
        .args(["run", "tiny.yaml", "--quiet"])
        .run()
        .then()
        .file("empty/.keep", "")
        .args(["report", "tiny.yaml", "--cache", "empty"])
        .status(1)
        .stderr_contains("reports/tiny holds a report of 56 trials, 28 cells")
        .stderr_contains("has only 0 of this pipeline's 56 distinct trials now")
        .stderr_contains("--force")
        .run();
    let index = done.sandbox.path("reports/tiny/index.html");
    let before = std::fs::read(&index).unwrap();
    assert!(String::from_utf8_lossy(&before).contains("Trials present: 56 of 56 planned"));
    // A report of as many trials replaces it; --force replaces it with fewer.
    let done = done
        .then()
        .args(["report", "tiny.yaml"])
        .stdout_contains("(56 of 56 planned trials present")
        .run()
        .then()
        .args(["report", "tiny.yaml", "--cache", "empty", "--force"])
        .stdout_contains("(0 of 56 planned trials present")
        .run();
    let after = std::fs::read_to_string(done.sandbox.path("reports/tiny/index.html")).unwrap();
    assert!(after.contains("Trials present: 0 of 56 planned"), "{after}");
}

/// Regression: the guard refused a complete report of a changed pipeline (lowering `seeds`), although
/// every planned trial was cached. Now it replaces the report and says what changed; a report
/// whose plan lacks trials still refuses.
#[test]
fn lowering_seeds_replaces_a_complete_report_and_says_what_changed() {
    let done = Test::new()
        .pipeline("tiny.yaml")
        .args(["run", "tiny.yaml", "--quiet"])
        .run()
        .then()
        .args(["run", "tiny.yaml", "--set", "seeds=1"])
        .stdout_contains("executed 0, cached 28, failed 0")
        .stdout_contains("replaced reports/tiny: 56 trials, 28 cells → 28 trials, 28 cells")
        .run();
    let index = std::fs::read_to_string(done.sandbox.path("reports/tiny/index.html")).unwrap();
    assert!(index.contains("Trials present: 28 of 28 planned"));
    // Raising them again: the new plan lacks trials and the kept report holds fewer, so the
    // report is written (it holds more than the kept one); `--no-report` keeps it as it is.
    let done = done
        .then()
        .args(["report", "tiny.yaml", "--set", "seeds=3"])
        .stdout_contains("(56 of 84 planned trials present")
        .run();
    // Fewer than the kept report and incomplete: refused, nothing written.
    let before = std::fs::read(done.sandbox.path("reports/tiny/index.html")).unwrap();
    let done = done
        .then()
        .args(["report", "tiny.yaml", "--set", "seeds=4", "--cache", "empty"])
        .file("empty/.keep", "")
        .status(1)
        .stderr_contains("holds a report of 56 trials")
        .run();
    assert_eq!(std::fs::read(done.sandbox.path("reports/tiny/index.html")).unwrap(), before);
}

#[test]
fn read_only_commands_never_create_the_cache() {
    for cmd in [&["report", "tiny.yaml"][..], &["verify"], &["gc"], &["gc", "tiny.yaml", "--dry-run"]] {
        let done = Test::new()
            .pipeline("tiny.yaml")
            .args(cmd)
            .status(2)
            .stderr_contains("does not exist; give the cache of an earlier `qsweep run`")
            .run();
        assert!(!done.sandbox.cache().exists(), "{cmd:?} created the cache");
        assert!(!done.sandbox.path("reports").exists(), "{cmd:?} wrote a report");
    }
    let done = Test::new()
        .pipeline("tiny.yaml")
        .args(["status", "tiny.yaml", "--explain"])
        .stdout_contains("total: 56 trials, 0 cached, 56 missing")
        .stdout_contains("does not exist yet")
        .stdout_contains("never computed")
        .run();
    assert!(!done.sandbox.cache().exists(), "status created the cache");
    assert_eq!(done.stderr, "", "a missing cache is no warning for status");
    assert!(done.stdout.starts_with("system "), "{}", done.stdout);
    // A file where the cache should be is bad input too.
    Test::new().file("cache", "").args(["verify"]).status(2).stderr_contains("is not a directory").run();
}

#[test]
fn an_unreadable_old_report_is_kept_unless_forced() {
    let done = Test::new()
        .pipeline("tiny.yaml")
        .file("cache/.keep", "")
        .file("reports/tiny/trials.parquet", "not parquet")
        .args(["report", "tiny.yaml"])
        .status(1)
        .stderr_contains("reports/tiny holds a report whose size cannot be read; replace it with --force")
        .run();
    assert_eq!(std::fs::read(done.sandbox.path("reports/tiny/trials.parquet")).unwrap(), b"not parquet");
    done.then().args(["report", "tiny.yaml", "--force"]).stdout_contains("(0 of 56 planned").run();
}
