"""Steps-to-goal on Acrobot of uniformly random policies with action persistence (no learning), 64 uniform warm-up
steps first as in every run; cap 3000."""

import json
import sys
import numpy as np
import gymnasium as gym


def run(seed, p_repeat=0.0, hold=1, cap=3000, warmup=64):
    env = gym.make("Acrobot-v1", max_episode_steps=10**9)
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    a = int(rng.integers(3))
    for t in range(cap):
        if t < warmup:
            a = int(rng.integers(3))
        elif (t - warmup) % hold == 0 and not (rng.random() < p_repeat):
            a = int(rng.integers(3))
        _, _, term, _, _ = env.step(a)
        if term:
            return t + 1
    return None


out = {}
for name, kw in [
    ("uniform", {}),
    ("repeat_p0.46", {"p_repeat": 0.46}),
    ("repeat_p0.7", {"p_repeat": 0.7}),
    ("repeat_p0.9", {"p_repeat": 0.9}),
    ("hold2", {"hold": 2}),
    ("hold4", {"hold": 4}),
    ("hold8", {"hold": 8}),
]:
    steps = [run(s, **kw) for s in range(int(sys.argv[1]))]
    reached = [s for s in steps if s is not None]
    capped = [3000 if s is None else s for s in steps]
    out[name] = steps
    print(
        name,
        "reached",
        len(reached),
        "/",
        len(steps),
        "median(capped)",
        np.median(capped),
        "mean(capped)",
        np.mean(capped),
        "share<=300",
        np.mean([c <= 300 for c in capped]),
        flush=True,
    )
json.dump(out, open(sys.argv[2], "w"))
