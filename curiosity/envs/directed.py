"""The "directed" action of a state: the one a hand-made pumping policy would take.

Exploring these tasks means building up energy, so an agent that explores on purpose pushes with the motion more
often than chance. The directed-action rate (how often the agent's action is the directed one) is 1/3 for a uniform
random policy with three actions; a state whose motion has no sign (velocity exactly 0) has no directed action.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def acrobot(state: np.ndarray) -> int | None:
    """Torque in the direction of the second joint's velocity: action 2 (+1) if θ̇2 > 0, action 0 (−1) if θ̇2 < 0."""
    return _with_sign(float(state[3]))


def mountaincar(state: np.ndarray) -> int | None:
    """Push in the direction of the car's velocity: action 2 (right) if v > 0, action 0 (left) if v < 0."""
    return _with_sign(float(state[1]))


def _with_sign(velocity: float) -> int | None:
    if velocity == 0.0:
        return None
    return 2 if velocity > 0 else 0


DIRECTED: dict[str, Callable[[np.ndarray], int | None]] = {"Acrobot-v1": acrobot, "MountainCar-v0": mountaincar}


def directed_action_fn(env_id: str) -> Callable[[np.ndarray], int | None] | None:
    """The directed-action function of env ``env_id``, or None for an env that has none (e.g. the chain)."""
    return DIRECTED.get(env_id)
