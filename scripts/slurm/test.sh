#!/usr/bin/env bash
# Integration test on a real Slurm: start a one-node cluster on this machine, submit
# pipelines/quick.yaml with the script `qsweep slurm --array 4` prints (a 4-task job array plus
# a report job that waits for it), and check that the cache and the report equal a single-machine
# run's: every trial stored exactly once, the same rows, the same Table III. Then submit again and
# check that every task finds its shard cached. Then a raced pipeline's chained round arrays. Then
# two overlapping pipelines submitted together on one cache (every shared trial computed once).
#
# Needs root: it installs slurm-wlm with apt-get if slurmctld is missing, and runs the daemons
# (no systemd: they are started directly and stopped by their PID files, even on failure).
# CI runs it from .ci/run; by hand: sudo bash scripts/slurm/test.sh
#
# Environment: QSWEEP=path/to/qsweep (default: `cargo build --locked`, target/debug/qsweep);
# SLURM_TEST_PORT=N (slurmctld's port, slurmd uses N+1; default 16817); KEEP=1 keeps the temp dir.
set -euo pipefail
cd "$(dirname "$0")/../.."
repo=$PWD
here=$repo/scripts/slurm

log() { printf '[slurm-test] %s\n' "$*"; }
fail() { printf '[slurm-test] FAIL: %s\n' "$*" >&2; exit 1; }
trap 'printf "[slurm-test] FAIL: line %s: %s\n" "$LINENO" "$BASH_COMMAND" >&2' ERR

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v sbatch >/dev/null; then
    [ "$(id -u)" = 0 ] || fail "slurm-wlm is not installed and installing it needs root (sudo bash $0)"
    log "installing slurm-wlm"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm >/dev/null
fi
[ "$(id -u)" = 0 ] || fail "run as root: the one-node cluster runs its daemons and jobs as root"

if [ -z "${QSWEEP:-}" ]; then
    log "building qsweep"
    cargo build --locked --quiet
    QSWEEP=$repo/target/debug/qsweep
fi
QSWEEP=$(realpath "$QSWEEP")

tmp=$(mktemp -d /tmp/qsweep-slurm.XXXXXX)
mkdir -p "$tmp/state" "$tmp/spool" "$tmp/log" "$tmp/work"
export SLURM_CONF=$tmp/slurm.conf

cleanup() {
    local status=$?
    set +e
    if [ -s "$tmp/slurmctld.pid" ]; then
        scancel --quiet --user="$(id -un)" 2>/dev/null
    fi
    if [ "$status" != 0 ]; then
        for f in "$tmp"/log/*.log "$tmp"/work/slurm-logs/*; do
            [ -f "$f" ] && { echo "----- $f (last 40 lines)"; tail -n 40 "$f"; }
        done
    fi
    for name in slurmd slurmctld; do
        local pid_file=$tmp/$name.pid
        if [ -s "$pid_file" ]; then
            local pid
            pid=$(cat "$pid_file")
            kill "$pid" 2>/dev/null
            for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
            kill -9 "$pid" 2>/dev/null
        fi
    done
    if [ "${KEEP:-0}" = 1 ]; then log "kept $tmp"; else rm -rf "$tmp"; fi
    exit "$status"
}
trap cleanup EXIT

# One node: this machine, reached on loopback. auth/none and cred/none need no munge key;
# proctrack/linuxproc and task/none need no cgroups.
host=$(hostname -s 2>/dev/null || uname -n)
cpus=$(nproc)
port=${SLURM_TEST_PORT:-16817}
cat >"$SLURM_CONF" <<EOF
ClusterName=qsweep-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/none
CredType=cred/none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

log "starting slurmctld and slurmd ($host, $cpus CPUs, port $port)"
slurmctld -i
slurmd
for i in $(seq 120); do
    state=$(sinfo -h -N -o %t 2>/dev/null || true)
    [ "$state" = idle ] && break
    [ "$i" = 120 ] && fail "node not idle after 60 s (sinfo says '${state:-nothing}')"
    sleep 0.5
done
log "node idle"

cd "$tmp/work"
pipeline=$repo/pipelines/quick.yaml
"$QSWEEP" slurm "$pipeline" --array 4 --partition debug --time 30 --cpus-per-task 1 \
    --cache "$tmp/work/cache" --out "$tmp/work/report-slurm" >submit.sh

# Submit a script, wait until the queue is empty, and keep every job of the submission in $jobs,
# one line each (no accounting storage here, so ask slurmctld, which keeps finished jobs for
# MinJobAge = 300 s).
submit_and_wait() {
    bash "$1" | tee submit.out
    array_job=$(sed -n 's/^submitted array job \([0-9]*\) .* report job \([0-9]*\) .*/\1/p' submit.out)
    report_job=$(sed -n 's/^submitted array job \([0-9]*\) .* report job \([0-9]*\) .*/\2/p' submit.out)
    [ -n "$array_job" ] && [ -n "$report_job" ] || fail "could not read the job ids from $1's output"
    for i in $(seq 1800); do
        [ -z "$(squeue -h -o %i)" ] && break
        [ "$i" = 1800 ] && fail "jobs still queued after 15 min: $(squeue)"
        sleep 0.5
    done
    jobs=$(scontrol -o show job "$array_job"; scontrol -o show job "$report_job")
}

# Every array task and the report job completed with exit code 0.
expect_all_completed() {
    local completed
    completed=$(grep -c 'JobState=COMPLETED .*ExitCode=0:0' <<<"$jobs" || true)
    [ "$completed" = 5 ] || fail "expected 4 array tasks + 1 report job COMPLETED with exit 0, got:
$jobs"
    log "array job $array_job (4 tasks) and report job $report_job completed"
}

submit_and_wait submit.sh
expect_all_completed
# Each task's log ends with "executed E, cached C, failed F in T s".
executed=0
for task in 1 2 3 4; do
    f=$(ls slurm-logs/qsweep-quick-"${array_job}"_"$task".out)
    line=$(grep -E '^executed [0-9]+, cached [0-9]+, failed 0 ' "$f") || fail "no summary line in $f"
    e=$(sed -E 's/^executed ([0-9]+),.*/\1/' <<<"$line")
    [ "$e" -gt 0 ] || fail "task $task ran nothing: $line"
    executed=$((executed + e))
    log "task $task: $line"
done

log "single-machine run of the same pipeline"
"$QSWEEP" run "$pipeline" --quiet --cache "$tmp/work/cache-single" --out "$tmp/work/report-single"
# pandas lives in the venv scripts/test sets up (Debian's system python3 has none).
python=$repo/.venv/bin/python
[ -x "$python" ] || python=python3
"$python" "$here/compare.py" "$tmp/work/cache" "$tmp/work/cache-single" "$executed"
for f in table3.md table3.csv table3.tex cells.parquet; do
    cmp "report-slurm/$f" "report-single/$f" || fail "report file $f differs from the single-machine run's"
done
log "cache rows and report (table3.md/.csv/.tex, cells.parquet) equal the single-machine run's"

log "submitting again: every task must find its shard cached"
segments_before=$(find cache -name 'seg-*.parquet' | wc -l)
submit_and_wait submit.sh
expect_all_completed
for task in 1 2 3 4; do
    grep -qE '^executed 0, cached [1-9][0-9]*, failed 0 ' slurm-logs/qsweep-quick-"${array_job}"_"$task".out ||
        fail "resubmitted task $task ran trials again"
done
[ "$(find cache -name 'seg-*.parquet' | wc -l)" = "$segments_before" ] || fail "the resubmission wrote segments"
log "resubmission executed nothing"

# Failing tasks (every trial of tests/fixtures/pipelines/absurd.yaml diverges, so `qsweep run`
# exits 1) must keep the report job from running: afterok is never satisfied and
# --kill-on-invalid-dep cancels it.
"$QSWEEP" slurm "$repo/tests/fixtures/pipelines/absurd.yaml" --array 4 --time 30 --cache "$tmp/work/cache-absurd" \
    --out "$tmp/work/report-absurd" >submit-absurd.sh
submit_and_wait submit-absurd.sh
failed=$(grep -c 'JobState=FAILED .*ExitCode=1:0' <<<"$jobs" || true)
[ "$failed" = 4 ] || fail "expected 4 FAILED array tasks (exit 1), got:
$jobs"
grep "JobId=$report_job " <<<"$jobs" | grep -q 'JobState=CANCELLED' ||
    fail "the report job was not cancelled after the tasks failed: $(grep "JobId=$report_job " <<<"$jobs")"
[ ! -e report-absurd ] || fail "a report was written although the tasks failed"
log "failed tasks: report job $report_job cancelled, no report written"
# A raced pipeline: one array per possible round, chained with afterok, then the report; the
# result must equal a single-machine run's, round decisions included.
race=$repo/tests/fixtures/pipelines/race.yaml
"$QSWEEP" slurm "$race" --array 2 --time 30 --cpus-per-task 1 --cache "$tmp/work/cache-race" \
    --out "$tmp/work/report-race" >submit-race.sh
[ "$(grep -c "<<'QSWEEP_SHARD_JOB'" submit-race.sh)" = 3 ] || fail "expected 3 round arrays in submit-race.sh"
bash submit-race.sh | tee submit-race.out
report_job=$(sed -n 's/^submitted .* report job \([0-9]*\) .*/\1/p' submit-race.out)
[ -n "$report_job" ] || fail "could not read the report job id from submit-race.sh's output"
for i in $(seq 1800); do
    [ -z "$(squeue -h -o %i)" ] && break
    [ "$i" = 1800 ] && fail "race jobs still queued after 15 min: $(squeue)"
    sleep 0.5
done
scontrol -o show job "$report_job" | grep -q 'JobState=COMPLETED .*ExitCode=0:0' ||
    fail "the race's report job did not complete: $(scontrol -o show job "$report_job")"
"$QSWEEP" run "$race" --quiet --cache "$tmp/work/cache-race-single" --out "$tmp/work/report-race-single"
for f in table3.csv cells.parquet; do
    cmp "report-race/$f" "report-race-single/$f" || fail "race report file $f differs from the single-machine run's"
done
log "race: 3 chained round arrays and the report equal the single-machine run's"

# Two overlapping pipelines submitted together on one empty cache (quick.yaml and the same with a
# third seed: two thirds of the second's trials are the first's): key leases let each trial be
# computed once, whichever task reaches it first (issue 39).
log "two overlapping pipelines submitted together on one cache"
for seeds in 2 3; do
    "$QSWEEP" slurm "$pipeline" --set seeds=$seeds --array 2 --partition debug --time 30 --cpus-per-task 1 \
        --cache "$tmp/work/cache-overlap" --out "$tmp/work/report-overlap-$seeds" >submit-overlap-$seeds.sh
done
bash submit-overlap-2.sh | tee submit-overlap.out
bash submit-overlap-3.sh | tee -a submit-overlap.out
ids=$(sed -n 's/^submitted array job \([0-9]*\) .* report job \([0-9]*\) .*/\1 \2/p' submit-overlap.out)
[ "$(wc -w <<<"$ids")" = 4 ] || fail "could not read the four job ids from submit-overlap.out"
for i in $(seq 1800); do
    [ -z "$(squeue -h -o %i)" ] && break
    [ "$i" = 1800 ] && fail "overlap jobs still queued after 15 min: $(squeue)"
    sleep 0.5
done
jobs=$(for id in $ids; do scontrol -o show job "$id"; done)
completed=$(grep -c 'JobState=COMPLETED .*ExitCode=0:0' <<<"$jobs" || true)
[ "$completed" = 6 ] || fail "expected 2 × (2 array tasks + 1 report job) COMPLETED with exit 0, got:
$jobs"
"$python" - "$tmp/work/cache-overlap" 216 <<'PY' || fail "the overlapping pipelines computed some trial twice"
import glob, sys
import pandas as pd
keys = pd.concat(pd.read_parquet(f, columns=["key"]) for f in glob.glob(sys.argv[1] + "/seg-*.parquet"))["key"]
print(f"[slurm-test] overlap: {len(keys)} rows, {keys.nunique()} distinct trials (want {sys.argv[2]} of each)")
sys.exit(0 if len(keys) == keys.nunique() == int(sys.argv[2]) else 1)
PY
[ -z "$(ls -A cache-overlap/_leases 2>/dev/null)" ] || fail "key leases left behind: $(ls cache-overlap/_leases)"
cmp report-overlap-2/table3.csv report-single/table3.csv || fail "the overlapped quick.yaml report differs"
log "overlap: every shared trial computed once, no key leases left, the same Table III"
log "PASS"
