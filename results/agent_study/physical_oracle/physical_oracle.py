"""Reference check (not the product): an exhaustive 3^H planner on the true simulator with the KDE novelty of the
true physical state, nothing learned. Acrobot-v1, 64 random warm-up steps, then argmax over all action sequences of
the discounted (0.99) novelty -log mean_i exp(-|f(s) - f(m_i)|^2 / 2h^2) of the states they reach, the memory m the
states visited so far, h = MULT x the median nearest-neighbour distance of the memory, features f = (cos, sin of both
angles, velocities / 4 and / 9) or the angles' cos/sin only ("ang").

    python results/agent_study/physical_oracle/physical_oracle.py SEED H MULT cs|ang
"""

import itertools
import sys

import gymnasium as gym
import numpy as np
from gymnasium.envs.classic_control.acrobot import AcrobotEnv

seed, H, mult, feat = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
env = gym.make("Acrobot-v1").unwrapped
env.reset(seed=seed)
rng = np.random.default_rng(seed)
sim = AcrobotEnv()
seqs = np.array(list(itertools.product(range(3), repeat=H)))


def features(s: np.ndarray) -> np.ndarray:
    s = np.atleast_2d(s)
    angles = [np.cos(s[:, 0]), np.sin(s[:, 0]), np.cos(s[:, 1]), np.sin(s[:, 1])]
    return np.stack(angles + ([s[:, 2] / 4, s[:, 3] / 9] if feat == "cs" else []), 1)


def novelty(q: np.ndarray, m: np.ndarray) -> np.ndarray:
    d2 = ((q[:, None, :] - m[None]) ** 2).sum(-1)
    nn = np.sqrt(np.sort(((m[:, None] - m[None]) ** 2).sum(-1) + np.eye(len(m)) * 1e9, 1)[:, 0])
    h = mult * np.median(nn[nn > 0])
    return -np.log(np.exp(-d2 / (2 * h * h)).mean(1) + 1e-300)


def step(state: np.ndarray, a: int) -> np.ndarray:
    sim.state = state.copy()
    sim.step(a)
    return sim.state.copy()


memory = [features(env.state)[0]]
for t in range(3000):
    if t < 64:
        a = int(rng.integers(3))
    else:
        states = {(): env.state.copy()}
        for d in range(1, H + 1):
            for prefix in itertools.product(range(3), repeat=d):
                states[prefix] = step(states[prefix[:-1]], prefix[-1])
        keys = [k for k in states if k]
        nov = dict(zip(keys, novelty(features(np.array([states[k] for k in keys])), np.array(memory)), strict=True))
        score = [sum(0.99**d * nov[tuple(sq[: d + 1])] for d in range(H)) for sq in seqs]
        a = int(seqs[int(np.argmax(score)), 0])
    _, _, terminated, _, _ = env.step(a)
    memory.append(features(env.state)[0])
    if terminated:
        print(f"seed {seed} H {H} mult {mult} features {feat}: goal at step {t + 1}")
        break
else:
    print(f"seed {seed} H {H} mult {mult} features {feat}: no goal in 3000 steps")
