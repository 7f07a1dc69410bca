"""Cross-check `qsweep simulate` against Gymnasium's CartPole-v1 / MountainCar-v0.

Three kinds of test:
  * test_fixture_against_qsweep: every stored tests/fixtures/gym/*.csv (made by
    scripts/gym_reference.py) replayed through the qsweep binary;
  * test_live_against_qsweep: fresh trajectories made here and now by the
    installed Gymnasium (not from the stored files) replayed the same way;
  * test_fixtures_reproduce_with_gymnasium: the stored files still agree with
    the installed Gymnasium (needs no binary).

The binary is `$QSWEEP_BIN`, else target/release/qsweep, else target/debug/qsweep;
when none exists the binary tests fail (never skip): run `cargo build --release`.
The live trajectories are seeded by `$QSWEEP_LIVE_SEED` (default fixed), so a
failure can be replayed.
"""

from __future__ import annotations

import csv
import io
import math
import os
import subprocess
from pathlib import Path
from typing import Sequence

import numpy as np
import pytest

import gym_reference as gr  # scripts/ is put on sys.path by conftest.py

ATOL = 1e-9
FIXTURE_DIR = gr.FIXTURE_DIR
FIXTURES = sorted(FIXTURE_DIR.glob("*.csv"))
EXTRA_AFTER_TERMINAL = 3  # actions appended past a terminal step: qsweep must ignore them
LIVE_SEED = int(os.environ.get("QSWEEP_LIVE_SEED", "7051"))


# --------------------------------------------------------------------------
# Parsing and comparing
# --------------------------------------------------------------------------


def parse_terminal(text: str) -> bool:
    t = text.strip().lower()
    if t in ("1", "true"):
        return True
    if t in ("0", "false"):
        return False
    raise AssertionError(f"terminal field {text!r} is not 0/1/true/false")


def parse_rows(text: str, env: str, source: str) -> list[gr.Row]:
    names = gr.ENV_VARS[env]
    want_header = ["step", "action", *names, "reward", "terminal"]
    lines = [ln.rstrip("\r") for ln in text.strip().splitlines() if ln.strip()]
    assert lines, f"{source}: empty CSV"
    reader = csv.reader(io.StringIO("\n".join(lines)))
    header = [h.strip() for h in next(reader)]
    assert header == want_header, f"{source}: header {header} != {want_header}"
    rows = []
    for lineno, rec in enumerate(reader, start=2):
        assert len(rec) == len(header), f"{source}:{lineno}: {len(rec)} fields, want {len(header)}: {rec}"
        rec = [f.strip() for f in rec]
        action = None if rec[1] == "" else float(rec[1])
        rows.append(
            gr.Row(
                step=int(rec[0]),
                action=action,
                state=tuple(float(v) for v in rec[2 : 2 + len(names)]),
                reward=float(rec[-2]),
                terminal=parse_terminal(rec[-1]),
            )
        )
    return rows


def assert_same_trajectory(expected: Sequence[gr.Row], actual: Sequence[gr.Row], env: str, what: str) -> None:
    names = gr.ENV_VARS[env]
    first = actual[0] if actual else None
    assert first is not None, f"{what}: qsweep printed a header but no rows"
    # Row 0: start state, empty action, reward 0, not terminal.
    assert first.step == 0, f"{what}: row 0 has step {first.step}"
    assert first.action is None, f"{what}: row 0 must have an empty action, got {first.action!r}"
    assert first.reward == 0, f"{what}: row 0 reward {first.reward} != 0"
    assert first.terminal is False, f"{what}: row 0 must not be terminal"

    for i, (e, a) in enumerate(zip(expected, actual)):
        where = f"{what}, step {i}"
        assert a.step == i, f"{where}: step column {a.step} != {i}"
        if i > 0:
            assert a.action is not None and float(a.action) == float(e.action), (
                f"{where}: action {a.action!r} != {e.action!r}"
            )
        assert a.terminal == e.terminal, f"{where}: terminal {a.terminal} != gym {e.terminal} (state {a.state} vs {e.state})"
        assert float(a.reward) == float(e.reward), f"{where}: reward {a.reward} != gym {e.reward}"
        for name, ev, av in zip(names, e.state, a.state):
            assert math.isfinite(av) and abs(av - ev) <= ATOL, (
                f"{where}: {name} = {av!r}, gym = {ev!r} (|diff| = {abs(av - ev):.3e} > {ATOL})\n"
                f"  qsweep state: {a.state}\n  gym state:    {e.state}"
            )
    assert len(actual) == len(expected), (
        f"{what}: qsweep printed {len(actual)} rows, gym has {len(expected)} "
        f"(gym's last row terminal={expected[-1].terminal}; qsweep must stop after the first terminal step)"
    )


def simulate_args(bin_path: Path, env: str, start: Sequence[float], actions: Sequence[float]) -> list[str]:
    # `--opt=value` so that values beginning with '-' are never taken for flags.
    state = ",".join(repr(float(v)) for v in start)
    acts = ",".join(repr(int(a)) if float(a).is_integer() else repr(float(a)) for a in actions)
    args = [str(bin_path), "simulate", f"--env={env}", f"--state={state}", f"--actions={acts}"]
    if env == "mountain-car":
        # MountainCar-v0 clips the position at max_position = 0.6; the paper's range (qsweep's
        # default) is [-1.2, 0.5]. The two differ only in the reported state of the goal step.
        args.append("--param=x_max=0.6")
    return args


def run_qsweep(bin_path: Path, env: str, start: Sequence[float], actions: Sequence[float], what: str) -> list[gr.Row]:
    args = simulate_args(bin_path, env, start, actions)
    proc = subprocess.run(args, capture_output=True, text=True, timeout=120, cwd=gr.REPO_ROOT)
    shown = " ".join(args)
    if len(shown) > 400:
        shown = shown[:400] + " ..."
    assert proc.returncode == 0, f"{what}: `{shown}` exited {proc.returncode}\nstderr:\n{proc.stderr}"
    return parse_rows(proc.stdout, env, f"{what} (qsweep stdout)")


def check_against_qsweep(bin_path: Path, traj: gr.Trajectory, what: str) -> None:
    actions = list(traj.actions)
    assert actions, f"{what}: trajectory has no steps"
    if traj.ended_terminal:
        actions += [actions[-1]] * EXTRA_AFTER_TERMINAL
    actual = run_qsweep(bin_path, traj.env, traj.start, actions, what)
    assert_same_trajectory(traj.rows, actual, traj.env, what)


def load_fixture(path: Path) -> gr.Trajectory:
    env = gr.env_from_filename(path.name)
    rows = parse_rows(path.read_text(), env, str(path))
    return gr.Trajectory(env, rows)


# --------------------------------------------------------------------------
# Tests
# --------------------------------------------------------------------------


def test_fixture_set_present():
    names = {p.name for p in FIXTURES}
    assert any(n.startswith("cart_pole_step_") for n in names), f"no cart-pole step fixtures in {FIXTURE_DIR}"
    assert any(n.startswith("cart_pole_rollout_") for n in names), f"no cart-pole rollouts in {FIXTURE_DIR}"
    assert any(n.startswith("mountain_car_rollout_") for n in names), f"no mountain-car rollouts in {FIXTURE_DIR}"


@pytest.mark.parametrize("path", FIXTURES, ids=[p.stem for p in FIXTURES])
def test_fixture_against_qsweep(path: Path, qsweep_bin: Path):
    check_against_qsweep(qsweep_bin, load_fixture(path), path.name)


def _live_trajectories(seed: int) -> list[tuple[str, gr.Trajectory]]:
    rng = np.random.default_rng(seed)
    out = []
    for k in range(4):
        start = gr.cart_pole_random_start(rng)
        out.append((f"cart-pole random actions #{k}",
                    gr.rollout("cart-pole", start, gr.random_actions(rng, "cart-pole"), max_steps=60)))
    for k in range(2):
        s = gr.cart_pole_random_start(rng)
        start = tuple(v * 0.5 for v in s)
        out.append((f"cart-pole stabilised #{k}",
                    gr.rollout("cart-pole", start, gr.cart_pole_stabiliser(rng, 0.2), max_steps=120)))
    for k in range(3):
        start = (float(rng.uniform(-1.2, 0.45)), float(rng.uniform(-0.07, 0.07)))
        out.append((f"mountain-car random actions #{k}",
                    gr.rollout("mountain-car", start, gr.random_actions(rng, "mountain-car"), max_steps=150)))
    for k in range(2):
        start = (float(rng.uniform(-1.2, 0.0)), float(rng.uniform(-0.07, 0.07)))
        out.append((f"mountain-car pumping #{k}",
                    gr.rollout("mountain-car", start, gr.mountain_car_pump(rng, eps=0.1), max_steps=300)))
    return out


LIVE_IDS = [name for name, _ in _live_trajectories(LIVE_SEED)]


@pytest.mark.parametrize("index", range(len(LIVE_IDS)), ids=LIVE_IDS)
def test_live_against_qsweep(index: int, qsweep_bin: Path):
    # Regenerated inside the test, straight from the installed Gymnasium.
    name, traj = _live_trajectories(LIVE_SEED)[index]
    check_against_qsweep(qsweep_bin, traj, f"live {name} (QSWEEP_LIVE_SEED={LIVE_SEED})")


def test_fixtures_reproduce_with_gymnasium():
    """The stored fixtures are what the installed Gymnasium produces (no binary needed)."""
    fresh = gr.generate_all()
    stored = {p.name for p in FIXTURES}
    assert stored == set(fresh), (
        f"fixture set differs from scripts/gym_reference.py: missing {sorted(set(fresh) - stored)}, "
        f"stale {sorted(stored - set(fresh))}; rerun `python scripts/gym_reference.py`"
    )
    for name, traj in sorted(fresh.items()):
        stored_traj = load_fixture(FIXTURE_DIR / name)
        # Reuse the comparison with the stored file in the role of the checked output.
        # Tolerance far tighter than ATOL: only last-ulp libm differences are acceptable here.
        assert len(stored_traj.rows) == len(traj.rows), f"{name}: {len(stored_traj.rows)} rows stored, gym gives {len(traj.rows)}"
        for e, s in zip(traj.rows, stored_traj.rows):
            assert (s.step, s.terminal, float(s.reward)) == (e.step, e.terminal, float(e.reward)), f"{name} step {e.step}"
            assert (s.action is None) == (e.action is None) and (e.action is None or float(s.action) == e.action), name
            for sv, ev in zip(s.state, e.state):
                assert abs(sv - ev) <= 1e-12, f"{name} step {e.step}: stored {sv!r} vs gym {ev!r}"


def test_cart_pole_gravity_override_is_used():
    """Guard for the fixture generator: gravity 9.81 must actually change CartPole's step."""
    start = (0.0, 0.0, 0.1, 0.0)
    u = gr.make_env("cart-pole")
    assert u.gravity == 9.81
    t981 = gr.rollout("cart-pole", start, [10])
    u98 = gr.make_env("cart-pole")
    u98.gravity = 9.8
    u98.reset(seed=0)
    u98.state = np.array(start, dtype=np.float64)
    u98.step(1)
    assert float(u98.state[3]) != t981.rows[1].state[3]
