"""A stand-in for a training run: SGD on the loss (w - 3)², with gradients noisy by 1/√batch."""
import json
import random
import sys

config = json.load(sys.stdin)  # the trial: {"lr": 0.1, "batch": 32, "seed": 0}
rng = random.Random(config["seed"])  # every draw comes from the seed: a trial is repeatable
w, steps = 0.0, 0
while (w - 3) ** 2 > 1e-3 and steps < 1000:
    grad = 2 * (w - 3) + rng.gauss(0, 1) / config["batch"] ** 0.5
    w -= config["lr"] * grad
    steps += 1
print(f"w = {w:.4f} after {steps} steps")  # the log: any lines before the result
print(json.dumps({"loss": (w - 3) ** 2, "steps": steps}))
