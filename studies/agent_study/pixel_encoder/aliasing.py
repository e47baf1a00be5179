"""How far Acrobot's links turn between two frames: |θ̇| · dt per step under three policies, from the env's reset.

    python -m studies.agent_study.pixel_encoder.aliasing OUT.json

Policies, 20 seeds each, up to 3000 steps (the goal ends a run): ``random`` (uniform), ``half_pump`` (torque in the
direction of θ̇2 on half the steps, uniform otherwise), ``pump`` (always). A link that turns by more than π between two
frames cannot show its direction of motion in a frame stack (``results/agent_study/pixel_encoder/aliasing/``).
"""

from __future__ import annotations

import argparse
import json

import gymnasium as gym
import numpy as np

QUANTILES = {"median": 50, "p90": 90, "p99": 99, "max": 100}


def action(policy: str, state: np.ndarray, rng: np.random.Generator) -> int:
    pump = 2 if state[3] > 0 else 0
    if policy == "pump" or (policy == "half_pump" and rng.random() < 0.5):
        return pump
    return int(rng.integers(3))


def run(policy: str, seed: int, steps: int = 3000) -> tuple[np.ndarray, int | None]:
    """Per step: |Δθ1|, |Δθ2| (wrapped) and |θ̇1|·dt, |θ̇2|·dt after the step; and the goal step (None: not reached)."""
    env = gym.make("Acrobot-v1").unwrapped
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    rows, prev = [], env.state.copy()
    for t in range(steps):
        _, _, terminated, _, _ = env.step(action(policy, env.state, rng))
        turned = np.abs(np.angle(np.exp(1j * (env.state[:2] - prev[:2]))))
        rows.append((*turned, abs(env.state[2]) * env.dt, abs(env.state[3]) * env.dt))
        prev = env.state.copy()
        if terminated:
            return np.array(rows), t + 1
    return np.array(rows), None


def quantiles(x: np.ndarray) -> dict[str, float]:
    return {name: float(np.percentile(x, q)) for name, q in QUANTILES.items()}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.pixel_encoder.aliasing",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("out", help="JSON file of the quantiles per policy")
    out = parser.parse_args(argv).out
    result = {}
    for policy in ("random", "half_pump", "pump"):
        runs = [run(policy, seed) for seed in range(20)]
        every = np.concatenate([r for r, _ in runs])
        last = np.concatenate([r[-50:] for r, _ in runs])  # the last 50 steps before the goal (or the cap)
        result[policy] = {
            "goals": [g for _, g in runs],
            "link2_rad_per_step_from_velocity": quantiles(every[:, 3]),
            "link1_rad_per_step_from_velocity": quantiles(every[:, 2]),
            "share_link2_over_pi_2": float((every[:, 3] > np.pi / 2).mean()),
            "share_link2_over_pi": float((every[:, 3] > np.pi).mean()),
            "last50_link2": quantiles(last[:, 3]),
            "last50_share_link2_over_pi_2": float((last[:, 3] > np.pi / 2).mean()),
            "last50_share_link2_over_pi": float((last[:, 3] > np.pi).mean()),
            "last50_link1": quantiles(last[:, 2]),
        }
    print(json.dumps(result, indent=1))
    with open(out, "w") as f:
        json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()
