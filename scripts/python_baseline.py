#!/usr/bin/env python3
"""The Python baseline for `qsweep bench`: tabular Q(0), tabular Q(λ) and fuzzy Q(λ) on Cart-Pole,
written the way a Python user would write them — Gymnasium's CartPole-v1 (gravity set to the paper's
9.81) for the physics, numpy for discretisation, fuzzy memberships, Q tables and dense eligibility
traces.

Same algorithms and hyperparameters as qsweep (Table II: ε 0.01, γ 0.995, α 0.1, λ 0.5; reward 0,
or −1 on failure; start state 0; Gaussian sets with σ = 0.4247 × centre spacing, normalised product
firing strengths), same configuration names as `qsweep bench`, and the same budget rule: run whole
episodes until at least `steps` steps have been taken. The trajectories are not meant to match
qsweep's bit for bit (different random streams); only the work per step is comparable. Note that the
fuzzy version evaluates every rule (the dense outer product a numpy user writes), where qsweep skips
memberships below 1e-6: at 10⁴ rules part of the gap is algorithmic, not just language.

Usage: python_baseline.py [--json] [--filter SUBSTR] [--scale X]
"""

import argparse
import functools
import json
import math
import sys
import time

import gymnasium as gym
import numpy as np

EPSILON, GAMMA, ALPHA, LAMBDA = 0.01, 0.995, 0.1, 0.5
THETA_LIMIT = 12 * 2 * math.pi / 360
RANGES = np.array([[-2.4, 2.4], [-2.0, 2.0], [-THETA_LIMIT, THETA_LIMIT], [-2.0, 2.0]])
WIDTH = 0.4246609001440095

# (qsweep bench name, kind, sets or bins per variable, actions, default step budget)
CONFIGS = [
    ("cart-pole/crisp/q0/2^4/2a", "q0", 2, 2, 40_000),
    ("cart-pole/crisp/q0/10^4/2a", "q0", 10, 2, 40_000),
    ("cart-pole/crisp/q-lambda/2^4/2a", "q-lambda", 2, 2, 40_000),
    ("cart-pole/crisp/q-lambda/10^4/2a", "q-lambda", 10, 2, 20_000),
    ("cart-pole/fuzzy/q-lambda/2^4/2a", "fuzzy", 2, 2, 20_000),
    ("cart-pole/fuzzy/q-lambda/4^4/2a", "fuzzy", 4, 2, 20_000),
    ("cart-pole/fuzzy/q-lambda/10^4/10a", "fuzzy", 10, 10, 2_000),
]


def make_env(steps):
    env = gym.make("CartPole-v1", max_episode_steps=steps)
    env.unwrapped.gravity = 9.81
    return env


def reset(env):
    env.reset()
    env.unwrapped.state = np.zeros(4)
    return np.zeros(4)


def step(env, force):
    # CartPole-v1 pushes with ±force_mag; any force of A_n is a magnitude and a direction.
    env.unwrapped.force_mag = abs(force)
    obs, _, terminated, truncated, _ = env.step(1 if force > 0 else 0)
    return obs, (-1.0 if terminated else 0.0), terminated, truncated


def epsilon_greedy(q, rng):
    if rng.random() < EPSILON:
        return int(rng.integers(len(q)))
    best = np.flatnonzero(q == q.max())
    return int(best[0] if len(best) == 1 else rng.choice(best))


def run_tabular(bins, n_actions, steps, lam):
    env = make_env(steps)
    rng = np.random.default_rng(0)
    forces = np.linspace(-10.0, 10.0, n_actions)
    dims = np.full(4, bins)
    lo, width = RANGES[:, 0], (RANGES[:, 1] - RANGES[:, 0]) / bins

    def state_index(obs):
        b = np.clip(np.floor((obs - lo) / width).astype(np.int64), 0, bins - 1)
        return int(np.ravel_multi_index(b, dims))

    Q = np.zeros((bins**4, n_actions))
    E = np.zeros_like(Q)
    total = 0
    while total < steps:
        s = state_index(reset(env))
        E[:] = 0.0
        done = False
        while not done:
            a = epsilon_greedy(Q[s], rng)
            obs, r, terminated, truncated = step(env, forces[a])
            total += 1
            s2 = state_index(obs)
            target = r if terminated else r + GAMMA * Q[s2].max()
            delta = target - Q[s, a]
            if lam == 0.0:
                Q[s, a] += ALPHA * delta
            else:
                E *= GAMMA * lam
                E[s, a] += 1.0
                Q += ALPHA * delta * E
            s = s2
            done = terminated or truncated
    env.close()
    return total


def run_fuzzy(sets, n_actions, steps):
    env = make_env(steps)
    rng = np.random.default_rng(0)
    forces = np.linspace(-10.0, 10.0, n_actions)
    centres = [np.linspace(lo, hi, sets) for lo, hi in RANGES]
    sigmas = [WIDTH * (hi - lo) / (sets - 1) for lo, hi in RANGES]

    def phi(obs):
        mus = []
        for x, c, sigma, (lo, hi) in zip(obs, centres, sigmas, RANGES):
            mu = np.exp(-((np.clip(x, lo, hi) - c) ** 2) / (2 * sigma**2))
            mus.append(mu / mu.sum())
        return functools.reduce(np.multiply.outer, mus).ravel()

    Q = np.zeros((sets**4, n_actions))
    E = np.zeros_like(Q)
    total = 0
    while total < steps:
        f = phi(reset(env))
        E[:] = 0.0
        done = False
        while not done:
            q = f @ Q
            a = epsilon_greedy(q, rng)
            obs, r, terminated, truncated = step(env, forces[a])
            total += 1
            f2 = phi(obs)
            target = r if terminated else r + GAMMA * (f2 @ Q).max()
            delta = target - q[a]
            E *= GAMMA * LAMBDA
            E[:, a] += f
            Q += ALPHA * delta * E
            f = f2
            done = terminated or truncated
    env.close()
    return total


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print a JSON list like the `results` of `qsweep bench --json`")
    p.add_argument("--filter", default="", help="only configurations whose name contains this")
    p.add_argument("--scale", type=float, default=1.0, help="multiply every step budget by this")
    args = p.parse_args()
    results = []
    for name, kind, res, n_actions, budget in CONFIGS:
        if args.filter not in name:
            continue
        steps = max(1, int(budget * args.scale))
        start = time.perf_counter()
        if kind == "fuzzy":
            ran = run_fuzzy(res, n_actions, steps)
        else:
            ran = run_tabular(res, n_actions, steps, 0.0 if kind == "q0" else LAMBDA)
        seconds = time.perf_counter() - start
        r = {"config": name, "steps": ran, "seconds": seconds, "steps_per_s": ran / seconds}
        results.append(r)
        if not args.json:
            print(f"{name:<40} {ran:>9} {seconds:>9.3f} {ran / seconds:>12.0f}", flush=True)
    if args.json:
        json.dump(results, sys.stdout, indent=2)
        print()


if __name__ == "__main__":
    main()
