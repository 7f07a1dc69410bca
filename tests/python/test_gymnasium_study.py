"""The Gymnasium study's agent (examples/gymnasium/tabular_q.py, pipelines/gymnasium.yaml) in
seconds: two of its cells on one seed with a 5-episode cap, run by qsweep in worker mode and
again in process mode, give the same keys and the same metrics, and those are what the program
prints when run by hand; an action count Gymnasium cannot express is refused, naming it."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import polars as pl
import yaml

from conftest import REPO_ROOT

AGENT = "examples/gymnasium/tabular_q.py"
METRICS = ["episodes", "solved", "total_steps", "lengths"]


def small_study(tmp_path, protocol: str) -> str:
    """pipelines/gymnasium.yaml cut to 2 cells x 1 seed x 5 episodes, with this interpreter."""
    p = yaml.safe_load((REPO_ROOT / "pipelines" / "gymnasium.yaml").read_text())
    p["seeds"] = [3]
    p["params"]["max_episodes"] = 5
    prog = p["program"]
    prog["protocol"] = protocol
    prog["command"] = [sys.executable] + prog["command"][1:]
    prog["provenance"] = [
        {**e, "command": [sys.executable] + e["command"][1:]} if isinstance(e, dict) else [sys.executable] + e[1:]
        for e in prog["provenance"]
    ]
    byid = {e["id"]: e for e in p["experiments"]}
    cp, mc = byid["cart-pole-1-q-lambda"], byid["mountain-car-2-q0"]
    p["experiments"] = [
        {"id": cp["id"], "fixed": cp["fixed"], "vary": {"x": [3], "x_dot": [2]}},
        {"id": mc["id"], "fixed": mc["fixed"], "vary": {"bins": [4], "actions": [2]}},
    ]
    name = f"study-{protocol}.yaml"
    (tmp_path / name).write_text(yaml.safe_dump(p, allow_unicode=True))
    return name


def test_gymnasium_study_worker_rows_equal_process_rows_and_the_program_by_hand(qsweep_bin, tmp_path):
    (tmp_path / "examples" / "gymnasium").mkdir(parents=True)
    shutil.copy(REPO_ROOT / AGENT, tmp_path / AGENT)
    rows = {}
    for protocol in ("worker", "process"):
        pipeline = small_study(tmp_path, protocol)
        run = subprocess.run(
            [str(qsweep_bin), "run", pipeline, "--cache", f"cache-{protocol}", "--jobs", "2", "--no-report"],
            cwd=tmp_path, capture_output=True, text=True, timeout=300,
        )
        assert run.returncode == 0, run.stderr
        assert "executed 2, cached 0, failed 0" in run.stderr + run.stdout
        t = pl.read_parquet(tmp_path / f"cache-{protocol}" / "_programs" / "*" / "seg-*.parquet")
        assert t.height == 2 and set(t["status"]) == {"ok"}
        rows[protocol] = t.sort("key")
    # The protocol is not part of a trial's key, and a worker that serves both trials gives each
    # what a fresh process gives it: no state carried from one trial to the next.
    w, p = rows["worker"], rows["process"]
    assert w["key"].to_list() == p["key"].to_list()
    assert w.select(METRICS).to_dicts() == p.select(METRICS).to_dicts()
    assert set(w["env"]) == {"CartPole-v1", "MountainCar-v0"}
    for row in w.iter_rows(named=True):
        config = {k: row[k] for k in yaml.safe_load((tmp_path / "study-worker.yaml").read_text())["params"]}
        config["seed"] = row["seed"]
        out = subprocess.run(
            [sys.executable, AGENT], cwd=tmp_path, input=json.dumps(config),
            capture_output=True, text=True, check=True,
        ).stdout.strip().splitlines()[-1]
        assert json.loads(out) == {m: row[m] for m in METRICS}
        assert 1 <= row["episodes"] <= 5 and row["total_steps"] >= row["episodes"]
        assert row["lengths"][0] >= 1 and len(row["lengths"]) == (row["episodes"] - 1) // 10 + 1


def test_gymnasium_agent_refuses_actions_gymnasium_cannot_express():
    p = yaml.safe_load((REPO_ROOT / "pipelines" / "gymnasium.yaml").read_text())["params"]
    config = {**p, "env": "MountainCar-v0", "actions": 4, "seed": 0}
    run = subprocess.run(
        [sys.executable, str(REPO_ROOT / AGENT)], input=json.dumps(config),
        capture_output=True, text=True, timeout=120,
    )
    assert run.returncode == 2 and run.stdout == ""
    assert "MountainCar-v0's Discrete(3) has no action for -0.333333" in run.stderr
    assert "A_2 = {-1, 1} and A_3 = {-1, 0, 1} only" in run.stderr
