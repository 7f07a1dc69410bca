#!/usr/bin/env python3
"""qsweep beside its peers on one job: sweep a program over a grid, rerun it unchanged, rerun it
with one value added. A benchmark, never a test: it prints a Markdown table and asserts nothing.

The job: 1,000 trials (x in 0..99 × seeds 0..9) of `work` (work.c here, compiled on the spot), a
program that spins for 10 ms of its own CPU time and prints one JSON line. Then the same sweep
again (every tool with a cache should run nothing), then x in 0..100 (10 new trials).

Each tool runs in its own virtual environment under the scratch folder, from its pinned
requirements file (requirements-TOOL.txt); `--setup` creates them. Times: wall clock, and the
CPU (user + system) of the tool and every process it waited for (getrusage RUSAGE_CHILDREN). A
tool that detaches workers (DVC's queue) shows less CPU than it used: its row says so.

    python3 scripts/bench_peers/bench.py --setup                   # venvs, once (needs PyPI)
    python3 scripts/bench_peers/bench.py                            # the peers and the shell floor
    python3 scripts/bench_peers/bench.py --qsweep target/release/qsweep --only qsweep-process,qsweep-worker

The scratch folder (default $TMPDIR/qsweep-bench-peers) holds the venvs and every tool's outputs;
delete it when done (`--clean` does, venvs included).
"""

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
TOOLS = ["shell", "qsweep-process", "qsweep-worker", "snakemake", "hydra-basic", "hydra-joblib", "dvc-matrix", "dvc-queue"]
VENVS = {"snakemake": "snakemake", "hydra-basic": "hydra", "hydra-joblib": "hydra", "dvc-matrix": "dvc", "dvc-queue": "dvc"}


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(cmd, cwd, env=None, input=None):
    """Runs cmd (a list, or a shell string) in cwd; returns (wall s, CPU s); fails loudly."""
    env = {**os.environ, **(env or {})}
    c0, t0 = cpu_children(), time.perf_counter()
    p = subprocess.run(cmd, cwd=cwd, env=env, input=input, shell=isinstance(cmd, str), text=True,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    wall, cpu = time.perf_counter() - t0, cpu_children() - c0
    if p.returncode != 0:
        sys.exit(f"failed ({p.returncode}): {cmd}\n{p.stdout[-4000:]}")
    return wall, cpu


def count(folder, suffix=".json"):
    return sum(1 for f in Path(folder).glob(f"*{suffix}")) if Path(folder).exists() else 0


class Job:
    """The grid and where each tool works."""

    def __init__(self, a):
        self.nx, self.seeds, self.jobs, self.work_ms = a.nx, a.seeds, a.jobs, a.work_ms
        self.scratch = Path(a.scratch)
        self.work = str(self.scratch / "work")
        self.qsweep = a.qsweep and str(Path(a.qsweep).resolve())
        self.queue_trials = a.queue_trials

    def venv_bin(self, tool, exe):
        return str(self.scratch / f"venv-{VENVS[tool]}" / "bin" / exe)

    def dir(self, tool):
        d = self.scratch / "runs" / tool
        return d

    def env(self, tool=None):
        env = {"WORK": self.work, "WORK_MS": str(self.work_ms), "DVC_NO_ANALYTICS": "1"}
        if tool in VENVS:  # the tool's venv first on PATH: DVC's queue starts `dvc` by name
            env["PATH"] = str(self.scratch / f"venv-{VENVS[tool]}" / "bin") + os.pathsep + os.environ["PATH"]
        return env


# Each tool: prepare(job, folder), then phase(job, folder, nx) runs the grid x in 0..nx-1 and
# returns (wall, cpu, trials it ran or None when it cannot tell).


def shell_phase(job, d, nx):
    # The floor: one process per trial, spawned by sh, an output file per trial, existing ones
    # skipped; xargs keeps --jobs of them running.
    before = count(d / "out")
    script = (
        f"mkdir -p out; for x in $(seq 0 {nx - 1}); do for s in $(seq 0 {job.seeds - 1}); do "
        '[ -e out/$x-$s.json ] || echo $x $s; done; done | '
        f"xargs -r -P {job.jobs} -n 2 sh -c "
        "'printf \"{\\\"x\\\": %d, \\\"seed\\\": %d}\" $1 $2 | \"$0\" > out/$1-$2.tmp && mv out/$1-$2.tmp out/$1-$2.json' "
        f"{job.work}"
    )
    wall, cpu = timed(script, d, job.env())
    return wall, cpu, count(d / "out") - before


QSWEEP_YAML = """name: bench-{mode}
seeds: {seeds}
program:
  command: {command}
  protocol: {mode}
  metrics: {{ value: int }}
params: {{ x: 0 }}
experiments:
  - {{ id: x, vary: {{ x: 0..{last} }} }}
"""


def qsweep_phase(mode):
    def phase(job, d, nx):
        command = json.dumps([job.work] + (["--worker"] if mode == "worker" else []))
        (d / "bench.yaml").write_text(QSWEEP_YAML.format(mode=mode, seeds=job.seeds, command=command, last=nx - 1))
        c0, t0 = cpu_children(), time.perf_counter()
        p = subprocess.run([job.qsweep, "run", "bench.yaml", "--jobs", str(job.jobs), "--no-report", "--json"],
                           cwd=d, env={**os.environ, **job.env()}, text=True, capture_output=True)
        wall, cpu = time.perf_counter() - t0, cpu_children() - c0
        if p.returncode != 0:
            sys.exit(f"qsweep failed ({p.returncode}):\n{p.stderr[-4000:]}")
        return wall, cpu, json.loads(p.stdout)["executed"]

    return phase


SNAKEFILE = """X = range(int(config.get("nx", 100)))
SEEDS = range(int(config.get("seeds", 10)))

rule all:
    input: expand("out/{x}-{seed}.json", x=X, seed=SEEDS)

rule trial:
    output: "out/{x}-{seed}.json"
    shell: "printf '{{\\"x\\": %d, \\"seed\\": %d}}' {wildcards.x} {wildcards.seed} | $WORK > {output}"
"""


def snakemake_phase(job, d, nx):
    (d / "Snakefile").write_text(SNAKEFILE)
    before = count(d / "out")
    cmd = [job.venv_bin("snakemake", "snakemake"), "--cores", str(job.jobs), "--quiet", "all",
           "--config", f"nx={nx}", f"seeds={job.seeds}"]
    wall, cpu = timed(cmd, d, job.env("snakemake"))
    return wall, cpu, count(d / "out") - before


HYDRA_APP = """import json, os, subprocess
from dataclasses import dataclass

import hydra
from hydra.core.config_store import ConfigStore


@dataclass
class Config:
    x: int = 0
    seed: int = 0


ConfigStore.instance().store(name="config", node=Config)


@hydra.main(version_base=None, config_name="config")
def main(cfg):
    config = json.dumps({"x": cfg.x, "seed": cfg.seed})
    out = subprocess.run([os.environ["WORK"]], input=config, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])["value"]


if __name__ == "__main__":
    main()
"""


def hydra_phase(launcher):
    def phase(job, d, nx):
        (d / "app.py").write_text(HYDRA_APP)
        runs = len(list(d.glob("multirun-*")))
        cmd = [job.venv_bin("hydra-basic", "python"), "app.py", "--multirun", f"x=range(0,{nx})",
               f"seed=range(0,{job.seeds})", f"hydra.sweep.dir=multirun-{runs}"]
        if launcher == "joblib":
            cmd += ["hydra/launcher=joblib", f"hydra.launcher.n_jobs={job.jobs}"]
        wall, cpu = timed(cmd, d, job.env("hydra-basic"))
        # Hydra has no memory across runs: every job of the sweep runs.
        return wall, cpu, sum(1 for p in (d / f"multirun-{runs}").iterdir() if p.name.isdigit())

    return phase


DVC_MATRIX = """stages:
  trial:
    matrix:
      x: {xs}
      seed: {seeds}
    cmd: printf '{{"x":%d,"seed":%d}}' ${{item.x}} ${{item.seed}} | $WORK > out/${{item.x}}-${{item.seed}}.json
    outs:
      - out/${{item.x}}-${{item.seed}}.json
"""


def dvc_prepare(job, d):
    dvc = job.venv_bin("dvc-matrix", "dvc")
    subprocess.run(["git", "init", "-q"], cwd=d, check=True)
    subprocess.run([dvc, "init", "-q"], cwd=d, check=True, env={**os.environ, **job.env("dvc-matrix")})
    subprocess.run([dvc, "config", "core.analytics", "false"], cwd=d, check=True)
    subprocess.run([dvc, "config", "core.autostage", "true"], cwd=d, check=True)
    subprocess.run("git add -A && git -c user.name=b -c user.email=b@b commit -qm init", shell=True, cwd=d, check=True)


def dvc_matrix_phase(job, d, nx):
    # One stage per trial (a matrix of x × seed), each its own entry in dvc.lock and the run-cache:
    # DVC's way to cache per trial.
    (d / "out").mkdir(exist_ok=True)
    (d / "dvc.yaml").write_text(DVC_MATRIX.format(xs=list(range(nx)), seeds=list(range(job.seeds))))
    before = count(d / "out")
    wall, cpu = timed([job.venv_bin("dvc-matrix", "dvc"), "repro", "-q"], d, job.env("dvc-matrix"))
    return wall, cpu, count(d / "out") - before


DVC_QUEUE = """stages:
  trial:
    cmd: printf '{"x":%d,"seed":%d}' ${x} ${seed} | $WORK > result.json
    params: [x, seed]
    outs: [result.json]
"""


def dvc_queue_phase(job, d, nx):
    # Queued experiments: one `dvc exp run --queue -S …` per trial, then the queue's workers. Each
    # experiment is a git commit in a temporary workspace, so this runs `queue_trials` of them
    # (the first cells of the grid) and the table scales its figures to 1,000.
    dvc = job.venv_bin("dvc-queue", "dvc")
    env = job.env("dvc-queue")
    if not (d / "dvc.yaml").exists():
        (d / "dvc.yaml").write_text(DVC_QUEUE)
        (d / "params.yaml").write_text("x: 0\nseed: 0\n")
        subprocess.run("git add -A && git -c user.name=b -c user.email=b@b commit -qm stage", shell=True, cwd=d, check=True)
    cells = [(x, s) for x in range(nx) for s in range(job.seeds)]
    cells = cells[:job.queue_trials] + (cells[-job.seeds:] if nx != job.nx else [])
    script = " && ".join(f"{dvc} exp run -q --queue -S x={x} -S seed={s}" for x, s in cells)
    script += (f" && {dvc} queue start -j {job.jobs} && timeout 3600 sh -c "
               f"'while {dvc} queue status | grep -qE \"Queued|Running\"; do sleep 0.2; done'")
    wall, cpu = timed(script, d, env)
    return wall, cpu, f"{len(cells)} queued"


PHASES = {
    "shell": (None, shell_phase),
    "qsweep-process": (None, qsweep_phase("process")),
    "qsweep-worker": (None, qsweep_phase("worker")),
    "snakemake": (None, snakemake_phase),
    "hydra-basic": (None, hydra_phase("basic")),
    "hydra-joblib": (None, hydra_phase("joblib")),
    "dvc-matrix": (dvc_prepare, dvc_matrix_phase),
    "dvc-queue": (dvc_prepare, dvc_queue_phase),
}


def setup(job, tools):
    for name in sorted({VENVS[t] for t in tools if t in VENVS}):
        venv = job.scratch / f"venv-{name}"
        if not venv.exists():
            subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        subprocess.run([str(venv / "bin" / "pip"), "install", "-q", "-r", str(HERE / f"requirements-{name}.txt")], check=True)


def versions(job, tools):
    out = {"python": sys.version.split()[0]}
    probes = {"snakemake": ("snakemake", ["snakemake"]), "hydra": ("hydra-basic", ["hydra-core", "hydra-joblib-launcher", "joblib"]),
              "dvc": ("dvc-matrix", ["dvc"])}
    for _, (tool, pkgs) in probes.items():
        if tool in tools or (tool == "hydra-basic" and "hydra-joblib" in tools) or (tool == "dvc-matrix" and "dvc-queue" in tools):
            py = job.venv_bin(tool, "python")
            for pkg in pkgs:
                r = subprocess.run([py, "-c", f"import importlib.metadata as m; print(m.version('{pkg}'))"], capture_output=True, text=True)
                out[pkg] = r.stdout.strip() or "?"
    if job.qsweep:
        out["qsweep"] = subprocess.run([job.qsweep, "--version"], capture_output=True, text=True).stdout.strip()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scratch", default=os.path.join(tempfile.gettempdir(), "qsweep-bench-peers"))
    ap.add_argument("--only", help="comma-separated tools: " + ",".join(TOOLS))
    ap.add_argument("--qsweep", help="the qsweep binary (needs program pipelines); without it the qsweep rows are skipped")
    ap.add_argument("--jobs", type=int, default=2, help="parallel trials for the tools that run them in parallel (default 2)")
    ap.add_argument("--nx", type=int, default=100, help="values of x (default 100; × seeds = trials)")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--work-ms", type=float, default=10.0, help="CPU milliseconds each trial spins (default 10)")
    ap.add_argument("--queue-trials", type=int, default=20, help="trials DVC's experiment queue runs (default 20)")
    ap.add_argument("--setup", action="store_true", help="create the venvs from requirements-*.txt and exit")
    ap.add_argument("--clean", action="store_true", help="delete the scratch folder (venvs included) and exit")
    a = ap.parse_args()
    job = Job(a)
    tools = a.only.split(",") if a.only else [t for t in TOOLS if a.qsweep or not t.startswith("qsweep")]
    if a.clean:
        shutil.rmtree(job.scratch, ignore_errors=True)
        return
    job.scratch.mkdir(parents=True, exist_ok=True)
    if a.setup:
        setup(job, tools)
        return
    if any(t.startswith("qsweep") for t in tools) and not job.qsweep:
        sys.exit("the qsweep rows need --qsweep BIN")
    # Compiled under another name and renamed: a run of this script beside another (--only) never
    # finds the program missing or half-written.
    subprocess.run(["cc", "-O2", "-o", f"{job.work}.{os.getpid()}", str(HERE / "work.c")], check=True)
    os.replace(f"{job.work}.{os.getpid()}", job.work)
    rows = []
    for tool in tools:
        prepare, phase = PHASES[tool]
        d = job.dir(tool)
        shutil.rmtree(d, ignore_errors=True)
        d.mkdir(parents=True)
        if prepare:
            prepare(job, d)
        results = [phase(job, d, job.nx), phase(job, d, job.nx), phase(job, d, job.nx + 1)]
        print(f"{tool}: " + "; ".join(f"{w:.2f} s wall, {c:.2f} s CPU, ran {n}" for w, c, n in results), file=sys.stderr, flush=True)
        rows.append((tool, results))
    trials = job.nx * job.seeds
    print(f"\n{trials} trials of {job.work_ms:g} ms CPU each, --jobs {job.jobs}; versions: "
          + ", ".join(f"{k} {v}" for k, v in versions(job, tools).items()) + "\n")
    print("| tool | sweep wall | sweep CPU | CPU per trial beyond the work | no-op rerun wall | no-op CPU | ran | add one value: wall | CPU | ran |")
    print("|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|")
    for tool, ((w1, c1, n1), (w2, c2, n2), (w3, c3, n3)) in rows:
        beyond = f"{(c1 - trials * job.work_ms / 1e3) / trials * 1e3:.1f} ms"
        if tool == "dvc-queue":
            beyond = "(workers detached: not measured)"
        print(f"| {tool} | {w1:.2f} s | {c1:.2f} s | {beyond} | {w2:.2f} s | {c2:.2f} s | {n2} | {w3:.2f} s | {c3:.2f} s | {n3} |")


if __name__ == "__main__":
    main()
