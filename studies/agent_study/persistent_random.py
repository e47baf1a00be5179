"""Steps-to-goal on Acrobot of uniformly random policies with action persistence (no learning), 64 uniform warm-up
steps first as in every run; cap 3000.

    python -m studies.agent_study.persistent_random SEEDS OUT.json

Per policy, seeds 0 .. SEEDS − 1: a summary line (printed; ``results/agent_study/persistent_random/output.txt``) and
the steps of every seed in OUT.json (``null``: the cap). Gymnasium's Acrobot-v1 state simulator, no rendering.
"""

from __future__ import annotations

import argparse
import json

import gymnasium as gym
import numpy as np

CAP, WARMUP = 3000, 64
POLICIES: dict[str, dict] = {
    "uniform": {},
    "repeat_p0.46": {"p_repeat": 0.46},
    "repeat_p0.7": {"p_repeat": 0.7},
    "repeat_p0.9": {"p_repeat": 0.9},
    "hold2": {"hold": 2},
    "hold4": {"hold": 4},
    "hold8": {"hold": 8},
}


def run(seed: int, p_repeat: float = 0.0, hold: int = 1, cap: int = CAP, warmup: int = WARMUP) -> int | None:
    """The goal step of one seed (None: not within ``cap``): uniform actions for ``warmup`` steps, then a new uniform
    action every ``hold`` steps unless the previous one is repeated (probability ``p_repeat``)."""
    env = gym.make("Acrobot-v1", max_episode_steps=10**9)
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    a = int(rng.integers(3))
    for t in range(cap):
        if t < warmup:
            a = int(rng.integers(3))
        elif (t - warmup) % int(hold) == 0 and not (rng.random() < p_repeat):
            a = int(rng.integers(3))
        _, _, term, _, _ = env.step(a)
        if term:
            return t + 1
    return None


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.persistent_random",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("seeds", type=int, help="seeds 0 .. SEEDS - 1 per policy (200 in the results)")
    parser.add_argument("out", help="JSON file: policy -> steps-to-goal per seed (null: the cap)")
    args = parser.parse_args(argv)
    out = {}
    for name, kw in POLICIES.items():
        steps = [run(s, **kw) for s in range(args.seeds)]
        reached = [s for s in steps if s is not None]
        capped = [CAP if s is None else s for s in steps]
        out[name] = steps
        print(name, "reached", len(reached), "/", len(steps), "median(capped)", np.median(capped), "mean(capped)",
              np.mean(capped), "share<=300", np.mean([c <= 300 for c in capped]), flush=True)  # fmt: skip
    with open(args.out, "w") as f:
        json.dump(out, f)


if __name__ == "__main__":
    main()
