//! A program's failures lose nothing and say why (issue 61, docs/programs.md's failure table): a
//! non-zero exit and a malformed result are stored as failed rows naming the exit code, or the
//! line and the field; a timeout stores nothing and the trial runs next time; the run exits 1 with
//! every other trial stored; `--retry-failed` reruns the failed ones and only those.

use crate::helpers::{fails_with, stdout, Sandbox};
use crate::programs::{lines, read_parquet, summary};
use arrow::array::{Array, Int32Array, Int64Array, StringArray};
use std::collections::HashMap;

/// A program whose behaviour the `mode` param picks; it logs every trial it starts, and once
/// `fixed` exists (not a declared input) every mode succeeds.
const MODES: &str = r#"read line
echo "$line" >> trials.log
if [ -e fixed ]; then echo '{"y": 7}'; exit 0; fi
case "$line" in
  *'"mode":"ok"'*) echo 'a log line'; echo '{"y": 1}' ;;
  *'"mode":"fail"'*) echo "oops, bad config" >&2; exit 3 ;;
  *'"mode":"slow"'*) sleep 30; echo '{"y": 1}' ;;
  *'"mode":"bad"'*) echo 'not json at all' ;;
  *'"mode":"missing"'*) echo '{}' ;;
  *'"mode":"wrong"'*) echo '{"y": "a"}' ;;
  *'"mode":"extra"'*) echo '{"y": 1, "z": 2}' ;;
esac
"#;

fn pipeline(modes: &str) -> String {
    format!(
        "name: modes\nseeds: 1\nprogram:\n  command: [sh, modes.sh]\n  inputs: [modes.sh]\n  timeout: 1s\n  \
         metrics: {{ y: int }}\nparams: {{ mode: ok }}\nexperiments:\n  - {{ id: m, vary: {{ mode: [{modes}] }} }}\n"
    )
}

/// The rows of trials.parquet by mode: (status, y, exit code, error, stderr tail).
type Row = (String, Option<i64>, Option<i32>, Option<String>, Option<String>);

fn rows(sb: &Sandbox) -> HashMap<String, Row> {
    let t = read_parquet(&sb.path("reports/modes/trials.parquet"));
    let text = |n: &str| t.column_by_name(n).unwrap().as_any().downcast_ref::<StringArray>().unwrap().clone();
    let (mode, status, error, tail) = (text("mode"), text("status"), text("error"), text("stderr_tail"));
    let y = t.column_by_name("y").unwrap().as_any().downcast_ref::<Int64Array>().unwrap().clone();
    let code = t.column_by_name("exit_code").unwrap().as_any().downcast_ref::<Int32Array>().unwrap().clone();
    let opt = |c: &StringArray, i: usize| c.is_valid(i).then(|| c.value(i).to_string());
    (0..t.num_rows())
        .map(|i| {
            let row = (
                status.value(i).to_string(),
                y.is_valid(i).then(|| y.value(i)),
                code.is_valid(i).then(|| code.value(i)),
                opt(&error, i),
                opt(&tail, i),
            );
            (mode.value(i).to_string(), row)
        })
        .collect()
}

#[test]
fn program_a_failing_config_a_timeout_and_a_malformed_result_each_give_their_outcome_and_lose_nothing() {
    let sb = Sandbox::new();
    sb.write("modes.sh", MODES);
    sb.write("p.yaml", &pipeline("ok, fail, slow, bad, missing, wrong, extra"));
    let out = sb.qsweep(&["run", "p.yaml"]).assert().code(1).get_output().clone();
    let (so, se) = (String::from_utf8(out.stdout).unwrap(), String::from_utf8(out.stderr).unwrap());
    assert!(summary(&so).starts_with("executed 6, cached 0, failed 5"), "{so}");
    assert!(se.contains("(timed out after 1s); it runs next time"), "{se}");
    assert!(se.contains("1 trials did not finish") && se.contains("5 trials failed"), "{se}");
    let r = rows(&sb);
    assert!(!r.contains_key("slow"), "a timed-out trial stores nothing");
    assert_eq!(
        r["ok"],
        ("ok".into(), Some(1), None, None, None),
        "earlier stdout lines are the program's log"
    );
    let failed = |mode: &str| {
        let (status, y, code, error, _) = &r[mode];
        assert_eq!((status.as_str(), y), ("failed", &None), "{mode}");
        (code.to_owned(), error.clone().unwrap())
    };
    assert_eq!(failed("fail"), (Some(3), "exit 3".to_string()));
    assert!(
        r["fail"].4.as_deref().unwrap().contains("oops, bad config"),
        "the tail of stderr: {:?}",
        r["fail"]
    );
    let reason = |mode: &str| {
        let (code, error) = failed(mode);
        assert_eq!(code, None, "{mode} exited 0");
        error
    };
    assert!(reason("bad").starts_with("result line `not json at all`: not JSON"), "{}", reason("bad"));
    assert_eq!(reason("missing"), "result line `{}`: missing metric `y` (int)");
    assert!(
        reason("wrong").starts_with("result line `{\"y\": \"a\"}`: metric `y` should be"),
        "{}",
        reason("wrong")
    );
    assert!(reason("extra").contains("undeclared metric `z`"), "{}", reason("extra"));
    let status = stdout(&mut sb.qsweep(&["status", "p.yaml"]));
    assert!(status.contains("total: 7 trials, 6 cached (5 failed), 1 missing"), "{status}");
    // The next run runs the timed-out trial (and only it: failed rows are cached).
    let before = lines(&sb.path("trials.log"));
    let out = sb.qsweep(&["run", "p.yaml"]).assert().code(1).get_output().stdout.clone();
    assert!(summary(&String::from_utf8(out).unwrap()).starts_with("executed 0, cached 6, failed 0"));
    assert_eq!(lines(&sb.path("trials.log")), before + 1);
}

/// Regression: `--retry-failed` ran nothing (`3 computed meanwhile by another run on this cache`),
/// and `--force` likewise, because the run's leases judged a trial stored against every row of
/// the folder, the rows chosen to run again among them.
#[test]
fn program_retry_failed_and_force_ran_nothing_when_the_leases_took_the_stored_rows_for_another_runs() {
    let sb = Sandbox::new();
    sb.write("modes.sh", MODES);
    sb.write("p.yaml", &pipeline("ok, fail, bad, extra"));
    let err = fails_with(&mut sb.qsweep(&["run", "p.yaml"]), 1);
    assert!(err.contains("3 trials failed") && err.contains("--retry-failed"), "{err}");
    assert_eq!(lines(&sb.path("trials.log")), 4);
    sb.write("fixed", "");
    // A plain rerun takes failed rows as stored.
    let out = stdout(&mut sb.qsweep(&["run", "p.yaml"]));
    assert!(summary(&out).starts_with("executed 0, cached 4, failed 0"), "{out}");
    assert_eq!(lines(&sb.path("trials.log")), 4);
    let out = stdout(&mut sb.qsweep(&["run", "p.yaml", "--retry-failed"]));
    assert!(summary(&out).starts_with("executed 3, cached 1, failed 0"), "{out}");
    let log = std::fs::read_to_string(sb.path("trials.log")).unwrap();
    let rerun: Vec<&str> = log.lines().skip(4).collect();
    assert_eq!(rerun.len(), 3, "{log}");
    assert!(!rerun.iter().any(|l| l.contains("\"mode\":\"ok\"")), "the succeeded trial ran again: {log}");
    let r = rows(&sb);
    assert!(r.values().all(|(status, ..)| status == "ok"), "{r:?}");
    assert_eq!(r["fail"].1, Some(7), "the retried row is served");
    let status = stdout(&mut sb.qsweep(&["status", "p.yaml"]));
    assert!(status.contains("total: 4 trials, 4 cached (0 failed), 0 missing"), "{status}");
    let out = stdout(&mut sb.qsweep(&["run", "p.yaml", "--force"]));
    assert!(summary(&out).starts_with("executed 4, cached 0, failed 0"), "{out}");
    assert_eq!(lines(&sb.path("trials.log")), 11);
}
