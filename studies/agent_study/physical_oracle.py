"""Reference check (not the product): an exhaustive 3^H planner on the true simulator with the KDE novelty of the
true physical state, nothing learned.

    python -m studies.agent_study.physical_oracle SEED H MULT cs|ang

Acrobot-v1, 64 random warm-up steps, then argmax over all action sequences of the discounted (0.99) novelty
-log mean_i exp(-|f(s) - f(m_i)|^2 / 2h^2) of the states they reach, the memory m the states visited so far,
h = MULT x the median nearest-neighbour distance of the memory, features f = (cos, sin of both angles, velocities / 4
and / 9) ("cs") or the angles' cos/sin only ("ang"). Prints the goal step (``results/agent_study/physical_oracle/``).
"""

from __future__ import annotations

import argparse
import itertools

import gymnasium as gym
import numpy as np
from gymnasium.envs.classic_control.acrobot import AcrobotEnv

CAP, WARMUP, GAMMA = 3000, 64, 0.99


def features(s: np.ndarray, feat: str) -> np.ndarray:
    s = np.atleast_2d(s)
    angles = [np.cos(s[:, 0]), np.sin(s[:, 0]), np.cos(s[:, 1]), np.sin(s[:, 1])]
    return np.stack(angles + ([s[:, 2] / 4, s[:, 3] / 9] if feat == "cs" else []), 1)


def novelty(q: np.ndarray, m: np.ndarray, mult: float) -> np.ndarray:
    d2 = ((q[:, None, :] - m[None]) ** 2).sum(-1)
    nn = np.sqrt(np.sort(((m[:, None] - m[None]) ** 2).sum(-1) + np.eye(len(m)) * 1e9, 1)[:, 0])
    h = mult * np.median(nn[nn > 0])
    return -np.log(np.exp(-d2 / (2 * h * h)).mean(1) + 1e-300)


def goal_step(seed: int, horizon: int, mult: float, feat: str) -> int | None:
    """The step at which the planner reaches the goal (None: not within 3000 steps)."""
    env = gym.make("Acrobot-v1").unwrapped
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    sim = AcrobotEnv()
    seqs = np.array(list(itertools.product(range(3), repeat=horizon)))

    def step(state: np.ndarray, a: int) -> np.ndarray:
        sim.state = state.copy()
        sim.step(a)
        return sim.state.copy()

    memory = [features(env.state, feat)[0]]
    for t in range(CAP):
        if t < WARMUP:
            a = int(rng.integers(3))
        else:
            states = {(): env.state.copy()}
            for d in range(1, horizon + 1):
                for prefix in itertools.product(range(3), repeat=d):
                    states[prefix] = step(states[prefix[:-1]], prefix[-1])
            keys = [k for k in states if k]
            nov = dict(zip(keys, novelty(features(np.array([states[k] for k in keys]), feat), np.array(memory), mult),
                           strict=True))  # fmt: skip
            score = [sum(GAMMA**d * nov[tuple(sq[: d + 1])] for d in range(horizon)) for sq in seqs]
            a = int(seqs[int(np.argmax(score)), 0])
        _, _, terminated, _, _ = env.step(a)
        memory.append(features(env.state, feat)[0])
        if terminated:
            return t + 1
    return None


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.physical_oracle",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("seed", type=int, help="env and warm-up seed")
    parser.add_argument("horizon", type=int, help="H: the planner's depth (3^H sequences)")
    parser.add_argument("mult", type=float, help="the KDE bandwidth over the median nearest-neighbour distance")
    parser.add_argument("features", choices=("cs", "ang"), help="cs: angles' cos/sin and velocities; ang: angles only")
    args = parser.parse_args(argv)
    goal = goal_step(args.seed, args.horizon, args.mult, args.features)
    head = f"seed {args.seed} H {args.horizon} mult {args.mult} features {args.features}"
    print(f"{head}: goal at step {goal}" if goal is not None else f"{head}: no goal in {CAP} steps")


if __name__ == "__main__":
    main()
