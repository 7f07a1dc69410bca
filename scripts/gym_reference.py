#!/usr/bin/env python3
"""Independent reference trajectories from Gymnasium for `qsweep simulate`.

Python is only a checking tool here; qsweep itself is Rust. This script rolls
Gymnasium's CartPole-v1 (gravity set to 9.81) and MountainCar-v0 forward from
chosen start states under chosen action *values* and writes one CSV per
trajectory in exactly the format `qsweep simulate` prints:

    step,action,<state variable names>,reward,terminal

Row 0 is the start state with an empty action, reward 0 and terminal 0; then
one row per step; a trajectory stops after its first terminal step.

Rewards follow the paper, not Gymnasium's defaults:
  * cart-pole: 0 on a non-failure step, -1 on the failure step (Gymnasium's
    `terminated`, which is exactly what `sutton_barto_reward=True` returns);
  * mountain-car: 1 on the goal step (Gymnasium's `terminated`), else -1.

Usage:
    python scripts/gym_reference.py            # (re)write tests/fixtures/gym/*.csv
    python scripts/gym_reference.py --check    # exit 1 if the stored files differ
    python scripts/gym_reference.py --out DIR  # write somewhere else

Everything is driven by one fixed numpy seed, so the output is byte-for-byte
reproducible for a given Gymnasium/numpy/libm.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import gymnasium as gym
import numpy as np

SEED = 20240521

REPO_ROOT = Path(__file__).resolve().parent.parent
FIXTURE_DIR = REPO_ROOT / "tests" / "fixtures" / "gym"

CART_POLE_GRAVITY = 9.81

# qsweep env name -> (state variable names, action values in Gymnasium order)
ENV_VARS = {
    "cart-pole": ("x", "x_dot", "theta", "theta_dot"),
    "mountain-car": ("x", "x_dot"),
}
ENV_ACTIONS = {
    "cart-pole": (-10, 10),  # Gymnasium action 0 -> -10 N, 1 -> +10 N
    "mountain-car": (-1, 0, 1),  # Gymnasium actions 0, 1, 2
}
FILE_PREFIX = {"cart-pole": "cart_pole", "mountain-car": "mountain_car"}


def env_from_filename(name: str) -> str:
    """`cart_pole_step_07.csv` -> `cart-pole`, `mountain_car_...` -> `mountain-car`."""
    for env, prefix in FILE_PREFIX.items():
        if name.startswith(prefix + "_"):
            return env
    raise ValueError(f"cannot tell the environment of fixture {name!r}")


# --------------------------------------------------------------------------
# Trajectory model
# --------------------------------------------------------------------------


@dataclass
class Row:
    step: int
    action: int | None  # action *value* (-10/10, -1/0/1); None on row 0
    state: tuple[float, ...]
    reward: int
    terminal: bool


@dataclass
class Trajectory:
    env: str
    rows: list[Row]

    @property
    def start(self) -> tuple[float, ...]:
        return self.rows[0].state

    @property
    def actions(self) -> list[int]:
        return [r.action for r in self.rows[1:]]

    @property
    def ended_terminal(self) -> bool:
        return self.rows[-1].terminal


def fmt_float(v: float) -> str:
    """Full-precision, round-trip text (Python repr of a plain float)."""
    v = float(v)
    if not math.isfinite(v):
        raise ValueError(f"non-finite value {v!r}")
    return repr(v)


def to_csv(traj: Trajectory) -> str:
    names = ENV_VARS[traj.env]
    lines = [",".join(("step", "action", *names, "reward", "terminal"))]
    for r in traj.rows:
        action = "" if r.action is None else str(int(r.action))
        fields = [str(r.step), action, *(fmt_float(v) for v in r.state)]
        fields += [str(int(r.reward)), "1" if r.terminal else "0"]
        lines.append(",".join(fields))
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------
# Gymnasium drivers
# --------------------------------------------------------------------------


def make_env(env: str):
    """The *unwrapped* Gymnasium env (no TimeLimit, no order/passive checks)."""
    if env == "cart-pole":
        u = gym.make("CartPole-v1", sutton_barto_reward=True).unwrapped
        # CartPole uses self.gravity only inside step(); nothing derived from it
        # is cached in __init__, so overriding the attribute is sufficient.
        u.gravity = CART_POLE_GRAVITY
        return u
    if env == "mountain-car":
        return gym.make("MountainCar-v0").unwrapped
    raise ValueError(env)


def current_state(u) -> tuple[float, ...]:
    return tuple(float(v) for v in np.asarray(u.state, dtype=np.float64))


Policy = Callable[[int, tuple[float, ...]], int]


def rollout(
    env: str,
    start: Sequence[float],
    policy: Policy | Sequence[int],
    max_steps: int | None = None,
) -> Trajectory:
    """Roll `env` from `start`; `policy` is either a list of action values or a
    callable (step_index, state) -> action value. Stops after the first
    terminal step, after `max_steps` steps, or when the action list runs out."""
    u = make_env(env)
    u.reset(seed=0)
    u.state = np.array([float(v) for v in start], dtype=np.float64)
    values = ENV_ACTIONS[env]

    if callable(policy):
        choose = policy
        limit = max_steps
    else:
        seq = list(policy)
        choose = lambda i, s: seq[i]  # noqa: E731
        limit = len(seq) if max_steps is None else min(max_steps, len(seq))
    if limit is None:
        raise ValueError("a policy callable needs max_steps")

    rows = [Row(0, None, current_state(u), 0, False)]
    for i in range(limit):
        a = int(choose(i, rows[-1].state))
        if a not in values:
            raise ValueError(f"{env}: action value {a!r} not in {values}")
        _obs, gym_reward, terminated, truncated, _info = u.step(values.index(a))
        assert not truncated
        terminated = bool(terminated)
        if env == "cart-pole":
            # sutton_barto_reward=True: 0.0 while balanced, -1.0 on the failure step.
            reward = -1 if terminated else 0
            assert float(gym_reward) == float(reward), (gym_reward, reward)
        else:
            assert float(gym_reward) == -1.0
            reward = 1 if terminated else -1
        rows.append(Row(i + 1, a, current_state(u), reward, terminated))
        if terminated:
            break
    return Trajectory(env, rows)


# --------------------------------------------------------------------------
# Policies and start-state samplers
# --------------------------------------------------------------------------


def cart_pole_random_start(rng: np.random.Generator) -> tuple[float, ...]:
    x = rng.uniform(-2.35, 2.35)
    x_dot = rng.uniform(-2.0, 2.0)
    theta = rng.uniform(-0.2, 0.2)
    theta_dot = rng.uniform(-2.0, 2.0)
    return (float(x), float(x_dot), float(theta), float(theta_dot))


def cart_pole_stabiliser(rng: np.random.Generator, flip_prob: float) -> Policy:
    """Push toward theta + 0.5*theta_dot (plus a weak cart-centring term), with
    occasional random flips so the trajectories are not purely periodic."""

    def policy(_i: int, s: tuple[float, ...]) -> int:
        x, x_dot, theta, theta_dot = s
        u = theta + 0.5 * theta_dot + 0.01 * x + 0.02 * x_dot
        a = 10 if u > 0 else -10
        if rng.random() < flip_prob:
            a = -a
        return a

    return policy


def mountain_car_pump(rng: np.random.Generator | None = None, eps: float = 0.0) -> Policy:
    """Energy pumping: action = sign(velocity), with an epsilon of random actions."""

    def policy(_i: int, s: tuple[float, ...]) -> int:
        if rng is not None and rng.random() < eps:
            return int(rng.integers(-1, 2))
        v = s[1]
        return 1 if v > 0 else (-1 if v < 0 else 0)

    return policy


def constant(a: int) -> Policy:
    return lambda _i, _s: a


def random_actions(rng: np.random.Generator, env: str) -> Policy:
    values = ENV_ACTIONS[env]
    return lambda _i, _s: int(values[rng.integers(len(values))])


# --------------------------------------------------------------------------
# The fixture set
# --------------------------------------------------------------------------


def generate_all(seed: int = SEED) -> dict[str, Trajectory]:
    rng = np.random.default_rng(seed)
    out: dict[str, Trajectory] = {}

    # --- Cart-Pole (a): single steps from random non-terminal starts -------
    n_single = 40
    for k in range(n_single):
        if k < n_single - 4:
            start = cart_pole_random_start(rng)
        else:
            # Near the failure boundary so some single steps are terminal.
            sx = 1.0 if k % 2 == 0 else -1.0
            if k < n_single - 2:
                start = (sx * float(rng.uniform(2.37, 2.399)), sx * float(rng.uniform(1.5, 2.0)),
                         float(rng.uniform(-0.05, 0.05)), float(rng.uniform(-0.5, 0.5)))
            else:
                start = (float(rng.uniform(-1.0, 1.0)), float(rng.uniform(-0.5, 0.5)),
                         sx * float(rng.uniform(0.19, 0.2)), sx * float(rng.uniform(1.0, 2.0)))
        action = 10 if k % 2 == 0 else -10
        out[f"cart_pole_step_{k:02d}.csv"] = rollout("cart-pole", start, [action])

    # --- Cart-Pole (b): long rollouts under a noisy stabilising policy -----
    cp_starts = [
        (0.0, 0.0, 0.0, 0.0),
        (0.5, -0.3, 0.05, -0.2),
        (-1.0, 0.5, -0.1, 0.4),
        (1.8, 0.2, 0.15, -0.5),
        None,  # random
        None,  # random
    ]
    flips = [0.05, 0.1, 0.1, 0.05, 0.15, 0.3]
    for k, (start, flip) in enumerate(zip(cp_starts, flips)):
        if start is None:
            s = cart_pole_random_start(rng)
            start = (s[0] * 0.5, s[1] * 0.5, s[2] * 0.5, s[3] * 0.5)
        out[f"cart_pole_rollout_{k}.csv"] = rollout(
            "cart-pole", start, cart_pole_stabiliser(rng, flip), max_steps=150
        )

    # --- Mountain Car rollouts ---------------------------------------------
    mc = [
        # classic start, random actions
        ((-0.5, 0.0), random_actions(rng, "mountain-car")),
        # classic start, energy pumping -> reaches the goal
        ((-0.5, 0.0), mountain_car_pump()),
        # hurled at the left wall, pushing left: clip to -1.2 and velocity reset to 0
        ((-1.0, -0.05), constant(-1)),
        # pushing right from the valley: not enough power, oscillates
        ((-0.3, 0.03), constant(1)),
        # fast start on the left slope, pushing right: velocity clip at +0.07
        ((-0.9, 0.07), constant(1)),
        # random start, noisy energy pumping
        ((float(rng.uniform(-0.6, -0.4)), 0.0), mountain_car_pump(rng, eps=0.2)),
    ]
    for k, (start, policy) in enumerate(mc):
        out[f"mountain_car_rollout_{k}.csv"] = rollout("mountain-car", start, policy, max_steps=400)

    # --- Mountain Car single-step edge cases -------------------------------
    mc_steps = [
        ((-1.19, -0.05), -1),  # position clip at the left wall, velocity -> 0
        ((-1.2, 0.0), -1),  # sitting on the wall, pushed into it
        ((0.58, 0.05), 1),  # position clip at +0.6, terminal
        ((0.499, 0.0015), 1),  # just reaches the goal
        ((-0.2, -0.0695), -1),  # velocity clip at -0.07
        ((0.0, 0.0), 0),
    ]
    for k, (start, a) in enumerate(mc_steps):
        out[f"mountain_car_step_{k:02d}.csv"] = rollout("mountain-car", start, [a])

    return out


def render_all(seed: int = SEED) -> dict[str, str]:
    return {name: to_csv(t) for name, t in generate_all(seed).items()}


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=FIXTURE_DIR)
    ap.add_argument("--check", action="store_true", help="compare with stored files, write nothing")
    args = ap.parse_args(argv)

    files = render_all()
    out: Path = args.out
    if args.check:
        stored = {p.name for p in out.glob("*.csv")}
        bad = sorted(n for n, text in files.items()
                     if not (out / n).exists() or (out / n).read_text() != text)
        extra = sorted(stored - set(files))
        for n in bad:
            print(f"differs or missing: {n}", file=sys.stderr)
        for n in extra:
            print(f"not generated (stale): {n}", file=sys.stderr)
        print(f"gymnasium {gym.__version__}, numpy {np.__version__}: "
              f"{len(files) - len(bad)}/{len(files)} fixtures identical")
        return 1 if bad or extra else 0

    out.mkdir(parents=True, exist_ok=True)
    for prefix in FILE_PREFIX.values():
        for stale in out.glob(f"{prefix}_*.csv"):
            stale.unlink()
    total = 0
    for name, text in sorted(files.items()):
        (out / name).write_text(text, newline="\n")
        total += len(text.encode())
    print(f"wrote {len(files)} fixtures ({total} bytes) to {out} "
          f"with gymnasium {gym.__version__}, numpy {np.__version__}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
