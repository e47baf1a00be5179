"""MountainCar-v0: its adapter, with the directed action and the mechanical energy.

The car cannot climb without swinging to build energy, so pushing with the motion (the directed action) and novelty
pointing towards higher energy are task-level checks of an exploration signal.
"""

from __future__ import annotations

import numpy as np

from curiosity.envs.adapter import EnvAdapter, with_sign


def directed(state: np.ndarray) -> int | None:
    """Push in the direction of the car's velocity: action 2 (right) if v > 0, action 0 (left) if v < 0."""
    return with_sign(float(state[1]))


def energy(state: np.ndarray) -> np.ndarray:
    """Energy per unit mass of gymnasium's MountainCar: ½ v² + (0.0025 / 3) sin(3x) (its gravity term is
    −0.0025 cos(3x) per step). state: (..., 2) position, velocity -> (...)."""
    x, v = np.moveaxis(np.asarray(state, dtype=np.float64), -1, 0)
    return 0.5 * v**2 + 0.0025 / 3 * np.sin(3 * x)


class MountainCarAdapter(EnvAdapter):
    """MountainCar-v0: termination is the goal; physical state (position, velocity)."""

    directed_action = staticmethod(directed)
    energy = staticmethod(energy)
    noop_action = 1  # no push
