#!/usr/bin/env python3
"""The paper's crisp tabular Q(0) and Q(lambda), on Gymnasium's own CartPole-v1 and MountainCar-v0.

A second implementation of the learner, written from the paper's equations (4)-(7), (22)-(25),
its Tables I-II and Gymnasium's documentation, so that the engine's `gym-v0-terminal` numbers
(pipelines/paper.yaml) can be checked against code that shares nothing with the engine: not
the dynamics (Gymnasium's), not the binning, not the learner, not the random streams.
docs/replication.md ("An independent implementation: Gymnasium + Python") lists what it
implements and where the two cannot match.

The qsweep program protocol (docs/programs.md): a config is one JSON object holding every param
and `seed`. Under `protocol: worker` (qsweep sets QSWEEP_WORKER) the program reads one config per
stdin line and answers each with one result line on stdout; otherwise (`protocol: process`) it
reads one config from stdin and prints one result line. The log goes to stderr. Every random draw
comes from `seed` (the agent's numpy Generator and the environment's reset), and nothing is kept
from one trial to the next, so a trial is a function of its config.

Result: {"episodes": 37, "solved": true, "total_steps": 2841, "lengths": [12, 9, ...]}
  episodes     the episode (1-based) in which the learning goal was reached; `max_episodes` when
               it never was (the engine's reports count a non-converged trial at the cap too)
  solved       whether the goal was reached
  total_steps  environment steps in the whole trial
  lengths      the lengths of episodes 1, 11, 21, ... (every 10th, to keep the rows small)
"""

from __future__ import annotations

import json
import math
import os
import sys

import gymnasium as gym
import numpy as np

# Per environment: the state variables' ranges for binning (the paper's and docs/replication.md's
# "Modelling choices": Cart-Pole's x and theta at its failure limits, its velocities at +-2;
# Mountain Car's the paper's intervals), the paper's action bounds (A_n spans them, eq. 22), the
# force of each of Gymnasium's discrete actions on that scale, and the paper's fixed start
# (Table II's initial states), passed to Gymnasium's reset as equal low/high bounds.
TWELVE_DEGREES = 12 * 2 * math.pi / 360  # Gymnasium's theta_threshold_radians
ENVS = {
    "CartPole-v1": {
        "ranges": [(-2.4, 2.4), (-2.0, 2.0), (-TWELVE_DEGREES, TWELVE_DEGREES), (-2.0, 2.0)],
        "bounds": (-10.0, 10.0),  # newtons: Gymnasium's action 0 pushes with -force_mag, 1 with +
        "gym_forces": (-10.0, 10.0),
        "start": 0.0,  # x = x_dot = theta = theta_dot = 0
    },
    "MountainCar-v0": {
        "ranges": [(-1.2, 0.5), (-0.07, 0.07)],
        "bounds": (-1.0, 1.0),  # eq. (3)'s a; Gymnasium's action k adds (k - 1) * 0.001
        "gym_forces": (-1.0, 0.0, 1.0),
        "start": -0.5,  # x = -0.5, Gymnasium's reset sets the velocity to 0
    },
}
PAPER_GRAVITY = 9.81  # eq. (2) (Gymnasium's CartPole uses 9.8)
PARAMS = {
    "env", "algorithm", "x", "x_dot", "bins", "actions", "alpha", "gamma", "epsilon", "lambda",
    "max_episode_steps", "max_episodes", "truncation", "start",
}


class ConfigError(ValueError):
    """A config this program cannot run (reported on stderr, exit status 2)."""


def gym_actions(env_id: str, n: int) -> list[int]:
    """Gymnasium's action index for each element of A_n (eq. 22), or ConfigError."""
    spec = ENVS[env_id]
    if n < 2:
        raise ConfigError(f"actions: {n}: A_n needs at least 2 actions")
    lo, hi = spec["bounds"]
    out = []
    for k in range(n):
        force = lo + k * (hi - lo) / (n - 1)
        matches = [i for i, f in enumerate(spec["gym_forces"]) if abs(f - force) < 1e-9]
        if not matches:
            raise ConfigError(
                f"actions: {n}: {env_id}'s Discrete({len(spec['gym_forces'])}) has no action "
                f"for {force:g} (A_{n}'s element {k}); it expresses "
                + (
                    "A_2 only"
                    if len(spec["gym_forces"]) == 2
                    else "A_2 = {-1, 1} and A_3 = {-1, 0, 1} only"
                )
            )
        out.append(matches[0])
    return out


def bin_counts(env_id: str, x: int, x_dot: int, bins: int) -> list[int]:
    """Bins per state variable. `bins` > 0 gives every variable that count (Table I's
    Exp. 2, x == x_dot (== theta == theta_dot)); otherwise positions take `x` and velocities
    `x_dot`, Cart-Pole's theta sharing x's count and theta_dot x_dot's (Exp. 1's pairs)."""
    if bins > 0:
        counts = [bins] * len(ENVS[env_id]["ranges"])
    elif env_id == "CartPole-v1":
        counts = [x, x_dot, x, x_dot]
    else:
        counts = [x, x_dot]
    if min(counts) < 1:
        raise ConfigError(f"bins: every variable needs at least 1 bin, got {counts}")
    return counts


def run(cfg: dict, log=lambda msg: print(msg, file=sys.stderr, flush=True)) -> dict:
    """One trial: learn until the goal or `max_episodes`; the result line's metrics."""
    missing, unknown = PARAMS - cfg.keys() - {"seed"}, cfg.keys() - PARAMS - {"seed"}
    if missing or unknown or "seed" not in cfg:
        raise ConfigError(f"config keys: missing {sorted(missing)}, unknown {sorted(unknown)}")
    env_id = cfg["env"]
    if env_id not in ENVS:
        raise ConfigError(f"env: {env_id!r}: not one of {sorted(ENVS)}")
    if cfg["algorithm"] not in ("q0", "q-lambda"):
        raise ConfigError(f"algorithm: {cfg['algorithm']!r}: not q0 or q-lambda")
    if cfg["truncation"] not in ("terminal", "bootstrap"):
        raise ConfigError(f"truncation: {cfg['truncation']!r}: not terminal or bootstrap")
    if cfg["start"] not in ("fixed", "gym"):
        raise ConfigError(f"start: {cfg['start']!r}: not fixed or gym")
    spec = ENVS[env_id]
    counts = bin_counts(env_id, cfg["x"], cfg["x_dot"], cfg["bins"])
    actions = gym_actions(env_id, cfg["actions"])
    alpha, gamma, epsilon = float(cfg["alpha"]), float(cfg["gamma"]), float(cfg["epsilon"])
    lam = float(cfg["lambda"]) if cfg["algorithm"] == "q-lambda" else 0.0
    horizon, max_episodes, seed = cfg["max_episode_steps"], cfg["max_episodes"], cfg["seed"]
    cut_is_terminal = cfg["truncation"] == "terminal"
    survival = env_id == "CartPole-v1"

    # Gymnasium's registration with its TimeLimit set to the learning goal's horizon (CartPole-v1
    # with 200 is CartPole-v0's registration; MountainCar-v0's own is 200). Cart-Pole's reward is
    # the Sutton-Barto one, eq. (24): 0 per step, -1 on failure.
    kwargs = {"sutton_barto_reward": True} if survival else {}
    env = gym.make(env_id, max_episode_steps=horizon, **kwargs)
    if survival:
        env.unwrapped.gravity = PAPER_GRAVITY
    options = None
    if cfg["start"] == "fixed":
        options = {"low": spec["start"], "high": spec["start"]}

    # Crisp bins, n equal bins over [lo, hi]; values outside fall into the edge bins.
    edges = [np.linspace(lo, hi, n + 1)[1:-1] for (lo, hi), n in zip(spec["ranges"], counts)]
    strides = np.cumprod([1] + counts[:0:-1])[::-1]

    def state(obs) -> int:
        return int(sum(int(np.digitize(v, e)) * s for v, e, s in zip(obs, edges, strides)))

    n_states, n_actions = int(np.prod(counts)), len(actions)
    q = np.zeros((n_states, n_actions))  # Q initialised to 0
    trace = np.zeros_like(q) if lam > 0 else None
    rng = np.random.default_rng(seed)  # the agent's stream: exploration and tie-breaking

    def choose(s: int) -> int:
        """Epsilon-greedy: with probability epsilon a uniform action (maybe the greedy one),
        else a greedy one, ties broken uniformly."""
        if rng.random() < epsilon:
            return int(rng.integers(n_actions))
        row = q[s]
        best = np.flatnonzero(row == row.max())
        return int(best[0]) if len(best) == 1 else int(rng.choice(best))

    lengths, total_steps, solved, episode = [], 0, False, 0
    for episode in range(1, max_episodes + 1):
        if episode == 1:
            obs, _ = env.reset(seed=seed, options=options)
        else:
            obs, _ = env.reset(options=options)
        if trace is not None:
            trace[:] = 0.0  # traces reset at every episode start
        s, steps = state(obs), 0
        while True:
            a = choose(s)
            obs, _, terminated, truncated, _ = env.step(actions[a])
            steps += 1
            if survival:
                reward = -1.0 if terminated else 0.0  # eq. (24)
            else:
                reward = 1.0 if terminated else -1.0  # eq. (25): the goal x >= 0.5
            s2 = state(obs)
            if terminated or (truncated and cut_is_terminal):
                delta = reward - q[s, a]  # eq. (4) with no successor
            else:
                delta = reward + gamma * q[s2].max() - q[s, a]  # eq. (4)
            if trace is None:
                q[s, a] += alpha * delta  # eq. (5)
            else:
                trace *= gamma * lam  # eq. (7): every trace decays, the visited pair gains 1
                trace[s, a] += 1.0
                q += alpha * delta * trace  # eq. (6)
            # The learning goal: Cart-Pole an episode of `horizon` steps without failure,
            # Mountain Car the goal within `horizon` steps (the episode is cut there).
            if (survival and truncated and not terminated) or (not survival and terminated):
                solved = True
            if terminated or truncated:
                break
            s = s2
        total_steps += steps
        if (episode - 1) % 10 == 0:
            lengths.append(steps)
        if solved:
            break
    env.close()
    episodes = episode if solved else max_episodes
    log(
        f"{env_id} {cfg['algorithm']} bins={counts} actions={n_actions} seed={seed}: "
        + (f"goal in episode {episode}" if solved else f"no goal in {max_episodes} episodes")
        + f", {total_steps} steps"
    )
    return {"episodes": episodes, "solved": solved, "total_steps": total_steps, "lengths": lengths}


def main() -> int:
    try:
        if os.environ.get("QSWEEP_WORKER") is not None:
            for line in sys.stdin:
                if line.strip():
                    print(json.dumps(run(json.loads(line))), flush=True)
        else:
            print(json.dumps(run(json.load(sys.stdin))), flush=True)
    except ConfigError as err:
        print(f"tabular_q.py: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
