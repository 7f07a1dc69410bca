"""Tabular Q-learning on Gymnasium's CartPole-v1 or MountainCar-v0, as a qsweep program.

qsweep writes one JSON object on stdin, the trial's params plus `seed`:
    {"env": "CartPole-v1", "alpha": 0.1, "gamma": 0.99, "epsilon": 0.1, "bins": 6,
     "max_episodes": 300, "window": 20, "seed": 3}
and reads the last line of stdout, one JSON object with every declared metric:
    {"episodes": 187, "solved": true, "returns": [12.0, 31.0, ...]}
Earlier stdout lines (and stderr) are the log. Under `protocol: worker` (qsweep sets
`QSWEEP_WORKER`) it reads one object per line and answers each with one result line, its log
going to stderr.

The state is cut into `bins` equal bins per variable; actions are epsilon-greedy. A run is solved
when the mean return of the last `window` episodes reaches the environment's target (Gymnasium's
classic thresholds: 195 for CartPole, -110 for MountainCar); `episodes` is the episode where that
happened, or `max_episodes` if it never did. Numpy and the environment are seeded from `seed`
alone, so a trial is a function of its config: `qsweep verify --recompute` checks it.
"""

import json
import os
import sys

import gymnasium as gym
import numpy as np

TARGET = {"CartPole-v1": 195.0, "MountainCar-v0": -110.0}
# CartPole's velocities are unbounded; these ranges cover what a balancing pole visits.
CARTPOLE_BOUNDS = ([-2.4, -3.0, -0.21, -3.5], [2.4, 3.0, 0.21, 3.5])


def run(env, alpha, gamma, epsilon, bins, max_episodes, window, seed, log=print):
    world = gym.make(env)
    rng = np.random.default_rng(seed)
    if env == "CartPole-v1":
        low, high = (np.array(b) for b in CARTPOLE_BOUNDS)
    else:
        low, high = world.observation_space.low, world.observation_space.high
    edges = [np.linspace(lo, hi, bins + 1)[1:-1] for lo, hi in zip(low, high)]
    # Optimistic initial values (CartPole's returns are positive; MountainCar's are not, so 0
    # already is): the greedy policy tries each action of a new state before settling.
    optimistic = 1.0 / (1.0 - gamma) if env == "CartPole-v1" else 0.0
    q = np.full((bins,) * len(edges) + (world.action_space.n,), optimistic)

    def cell(obs):
        return tuple(int(np.digitize(x, e)) for x, e in zip(obs, edges))

    returns = []
    obs, _ = world.reset(seed=seed)
    for episode in range(1, max_episodes + 1):
        if episode > 1:
            obs, _ = world.reset()
        s, total, done = cell(obs), 0.0, False
        while not done:
            a = int(rng.integers(q.shape[-1])) if rng.random() < epsilon else int(np.argmax(q[s]))
            obs, reward, terminated, truncated, _ = world.step(a)
            s2 = cell(obs)
            target = reward + (0.0 if terminated else gamma * np.max(q[s2]))
            q[s + (a,)] += alpha * (target - q[s + (a,)])
            s, total, done = s2, total + float(reward), terminated or truncated
        returns.append(total)
        if episode % 50 == 0:
            log(f"episode {episode}: mean return of the last 50 {np.mean(returns[-50:]):.1f}")
        if len(returns) >= window and np.mean(returns[-window:]) >= TARGET[env]:
            log(f"solved in episode {episode}")
            return {"episodes": episode, "solved": True, "returns": returns}
    return {"episodes": max_episodes, "solved": False, "returns": returns}


def main():
    if "QSWEEP_WORKER" in os.environ:
        for line in sys.stdin:
            if line.strip():
                result = run(**json.loads(line), log=lambda m: print(m, file=sys.stderr))
                print(json.dumps(result), flush=True)
    else:
        print(json.dumps(run(**json.load(sys.stdin))))


if __name__ == "__main__":
    main()
