//! `qsweep slurm`: the printed submission script, run by bash against a stand-in `sbatch` that
//! runs each array task in turn and honours `afterok`. (The real-Slurm test is
//! `scripts/slurm/test.sh`, run by CI.)

use crate::helpers::{fails_with, stdout, Sandbox};
use qsweep_pipeline::cache::Store;
use std::collections::HashSet;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};

/// A fake `sbatch --parsable`: numbers jobs 1, 2, ...; runs the script from stdin at once, once
/// per array task (with SLURM_ARRAY_TASK_ID/COUNT and SLURM_CPUS_PER_TASK set, output to
/// --output with %x %A %a %j filled in); skips a job whose afterok dependency failed. Every call's
/// arguments are appended to calls.log.
const FAKE_SBATCH: &str = r#"#!/usr/bin/env bash
set -u
dir=$(dirname "$0")
echo "$*" >>"$dir/calls.log"
array="" dep="" out="slurm-%j.out" name="sbatch" cpus="" chdir=$PWD
for a in "$@"; do
  case "$a" in
    --array=*) array=${a#--array=} ;;
    --dependency=*) dep=${a#--dependency=afterok:} ;;
    --output=*) out=${a#--output=} ;;
    --job-name=*) name=${a#--job-name=} ;;
    --cpus-per-task=*) cpus=${a#--cpus-per-task=} ;;
    --chdir=*) chdir=${a#--chdir=} ;;
  esac
done
id=$(( $(cat "$dir/next-id" 2>/dev/null || echo 0) + 1 ))
echo "$id" >"$dir/next-id"
script="$dir/job-$id.sh"
cat >"$script"
echo "$id"
if [ -n "$dep" ] && [ -e "$dir/failed-$dep" ]; then exit 0; fi
tasks=1
if [ -n "$array" ]; then range=${array%%%*}; tasks=${range#1-}; fi
for ((t = 1; t <= tasks; t++)); do
  log=${out//%x/$name}; log=${log//%A/$id}; log=${log//%a/$t}; log=${log//%j/$id}
  if [ -n "$array" ]; then task_env=(SLURM_ARRAY_TASK_ID=$t SLURM_ARRAY_TASK_COUNT=$tasks); else task_env=(); fi
  (cd "$chdir" && env "${task_env[@]}" SLURM_CPUS_PER_TASK="$cpus" bash "$script" >"$log" 2>&1) || touch "$dir/failed-$id"
done
"#;

/// A sandbox with the fake sbatch on PATH; returns its bin directory.
fn fake_sbatch(sb: &Sandbox) -> PathBuf {
    let bin = sb.path("fakebin");
    std::fs::create_dir_all(&bin).unwrap();
    let sbatch = bin.join("sbatch");
    std::fs::write(&sbatch, FAKE_SBATCH).unwrap();
    std::fs::set_permissions(&sbatch, std::fs::Permissions::from_mode(0o755)).unwrap();
    bin
}

/// Run a generated submission script with the fake sbatch first on PATH.
fn submit(sb: &Sandbox, script: &Path, bin: &Path) -> std::process::Output {
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    std::process::Command::new("bash")
        .arg(script)
        .current_dir(sb.dir.path())
        .env("PATH", path)
        .output()
        .unwrap()
}

#[test]
fn slurm_script_runs_every_trial_once_then_the_report() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    // A cache path that needs quoting in the script.
    let cache = sb.path("shared fs/it's the cache");
    let out = qsweep_slurm(&sb, &p, &cache, &["--array", "3", "--cpus-per-task", "2", "--time", "10"]);
    let script = sb.write("submit.sh", &String::from_utf8(out.stdout).unwrap());
    let summary = String::from_utf8(out.stderr).unwrap();
    assert!(summary.contains("56 distinct trials (56 not cached) in 3 shards"), "{summary}");

    let bin = fake_sbatch(&sb);
    let run = submit(&sb, &script, &bin);
    let said = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{said}{}", String::from_utf8_lossy(&run.stderr));
    assert!(said.contains("submitted array job 1 (3 tasks) and report job 2"), "{said}");

    let calls = std::fs::read_to_string(bin.join("calls.log")).unwrap();
    let calls: Vec<&str> = calls.lines().collect();
    assert!(calls[0].contains("--array=1-3") && calls[0].contains("--cpus-per-task=2"), "{calls:?}");
    assert!(calls[0].contains("--time=10"), "{calls:?}");
    assert!(calls[1].contains("--dependency=afterok:1 --kill-on-invalid-dep=yes"), "{calls:?}");

    // Each task ran its own shard with as many threads as CPUs; together, every trial once.
    let mut executed = 0;
    for task in 1..=3 {
        let log = std::fs::read_to_string(sb.path(&format!("slurm-logs/qsweep-tiny-1_{task}.out"))).unwrap();
        let line = log.lines().find(|l| l.starts_with("executed ")).unwrap_or_else(|| panic!("{log}"));
        let n: usize = line["executed ".len()..].split(',').next().unwrap().parse().unwrap();
        assert!(n > 0, "task {task} ran nothing: {line}");
        executed += n;
    }
    let records = Store::open(&cache).unwrap().read_all().unwrap();
    let keys: HashSet<_> = records.iter().map(|r| r.key).collect();
    assert_eq!((executed, records.len(), keys.len()), (56, 56, 56), "each trial stored exactly once");
    let job = std::fs::read_to_string(bin.join("job-1.sh")).unwrap();
    assert!(job.contains(r#"--shard "$SLURM_ARRAY_TASK_ID/3" --jobs "${SLURM_CPUS_PER_TASK:-2}""#), "{job}");

    let report = std::fs::read_to_string(sb.path("slurm-logs/qsweep-tiny-report-2.out")).unwrap();
    assert!(report.contains("56 of 56 planned trials present"), "{report}");
    assert!(sb.path("reports/tiny/table3.md").is_file());

    // Submitting again (a requeue, or after a failure) runs nothing that is cached.
    let again = submit(&sb, &script, &bin);
    assert!(again.status.success());
    for task in 1..=3 {
        let log = std::fs::read_to_string(sb.path(&format!("slurm-logs/qsweep-tiny-3_{task}.out"))).unwrap();
        assert!(log.lines().any(|l| l.starts_with("executed 0, cached ")), "{log}");
    }
}

#[test]
fn slurm_report_job_is_skipped_when_a_task_fails() {
    let sb = Sandbox::new();
    let p = sb.fixture("absurd.yaml");
    let cache = sb.cache();
    let out = qsweep_slurm(&sb, &p, &cache, &["--array", "2"]);
    let script = sb.write("submit.sh", &String::from_utf8(out.stdout).unwrap());
    let bin = fake_sbatch(&sb);
    assert!(submit(&sb, &script, &bin).status.success());
    assert!(bin.join("failed-1").exists(), "diverged trials make the tasks exit 1");
    assert!(!sb.path("slurm-logs/qsweep-absurd-report-2.out").exists(), "no report after a failed task");
}

#[test]
fn slurm_options_are_passed_to_sbatch_and_quoted() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let args = [
        "--array",
        "5",
        "--max-running",
        "2",
        "--partition",
        "long jobs",
        "--mem",
        "4G",
        "--account",
        "proj-7",
        "--job-name",
        "mine",
        "--sbatch-arg=--qos=low",
        "--qsweep",
        "/opt/q sweep/qsweep",
        "--set",
        "seeds=3",
        "--yes",
    ];
    let script = String::from_utf8(qsweep_slurm(&sb, &p, &sb.cache(), &args).stdout).unwrap();
    for want in [
        "--array=1-5%2 \\",
        "--partition='long jobs' \\",
        "--mem=4G \\",
        "--account=proj-7 \\",
        "--job-name=mine \\",
        "--job-name=mine-report \\",
        "    --qos=low \\",
        "exec '/opt/q sweep/qsweep' run ",
        " --set seeds=3 --yes \\",
    ] {
        assert!(script.contains(want), "missing {want:?} in\n{script}");
    }
    let syntax = std::process::Command::new("bash").args(["-n", "-c", &script]).status().unwrap();
    assert!(syntax.success(), "the script parses");
}

#[test]
fn slurm_bad_input_exits_2_and_prints_no_script() {
    let sb = Sandbox::new();
    let p = sb.fixture("tiny.yaml");
    let ps = p.to_str().unwrap();
    for (args, expect) in [
        (vec!["--array", "0"], "0 is not in 1.."),
        (vec!["--array", "4", "--time", "2h"], "not a Slurm time limit"),
        (vec!["--array", "4", "--mem", "4GB"], "not a Slurm memory size"),
        (vec!["--array", "4", "--sbatch-arg=--array=1-9"], "set by the generated script"),
        (vec!["--array", "4", "--partition", "a\nb"], "control character"),
        (vec!["--array", "4", "--set", "seeds=0"], "seeds"),
    ] {
        let mut c = sb.qsweep(&["slurm", ps]);
        c.args(&args);
        let out = c.assert().code(2).get_output().clone();
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?} printed a script");
    }
    let broken = sb.write("broken.yaml", "name: broken\nseeds: [1, 2\n");
    let err = fails_with(&mut sb.qsweep(&["slurm", broken.to_str().unwrap(), "--array", "2"]), 2);
    assert!(err.contains("broken.yaml"), "{err}");
    let help = stdout(crate::helpers::qsweep().args(["slurm", "--help"]));
    assert!(help.contains("--cpus-per-task") && help.contains("--array <N>"), "{help}");
}

fn qsweep_slurm(sb: &Sandbox, pipeline: &Path, cache: &Path, args: &[&str]) -> std::process::Output {
    let mut c = crate::helpers::qsweep();
    c.current_dir(sb.dir.path()).args(["slurm", pipeline.to_str().unwrap(), "--cache"]).arg(cache).args(args);
    c.assert().success().get_output().clone()
}

/// Issue 61: a program pipeline's script runs each shard's trials once (the split by program
/// keys), then its report job writes the program report.
#[test]
fn slurm_script_runs_a_program_pipelines_shards_once_then_its_report() {
    use crate::programs::{doubler_yaml, lines, DOUBLER};
    let sb = Sandbox::new();
    sb.write("prog.sh", DOUBLER);
    let p = sb.write("p.yaml", &doubler_yaml("prog", "1, 2, 3, 4", 2));
    let cache = sb.cache();
    let out = qsweep_slurm(&sb, &p, &cache, &["--array", "3"]);
    let script = sb.write("submit.sh", &String::from_utf8(out.stdout).unwrap());
    let summary = String::from_utf8(out.stderr).unwrap();
    assert!(summary.contains("pipeline 'prog': 8 distinct trials (8 not cached) in 3 shards"), "{summary}");
    let bin = fake_sbatch(&sb);
    let run = submit(&sb, &script, &bin);
    let said = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{said}{}", String::from_utf8_lossy(&run.stderr));
    assert!(said.contains("/reports/prog/README.md"), "{said}");
    assert!(!bin.join("failed-1").exists(), "a task failed");
    assert_eq!(lines(&sb.path("trials.log")), 8, "each trial once, over the shards");
    let report = std::fs::read_to_string(sb.path("slurm-logs/qsweep-prog-report-2.out")).unwrap();
    assert!(report.contains("8 of 8 planned trials present, 0 failed"), "{report}");
    assert!(sb.path("reports/prog/trials.parquet").is_file());
}
