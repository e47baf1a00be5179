"""A tiny deterministic corridor for learning tests and quick checks of exploration."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np


class ChainEnv(gym.Env):
    """A corridor of ``length`` cells; actions 0 = left, 1 = stay, 2 = right; the episode starts in the middle cell.

    There is no goal (the episode never terminates; the run's step cap ends it) and the reward is −1 per step, so
    only exploration moves the agent. Observation: the position scaled to [−1, 1], shape (1,), float32.
    ``state`` holds the physical position (the cell index), for coverage.
    """

    metadata = {"render_modes": []}  # noqa: RUF012

    def __init__(self, length: int = 61) -> None:
        self.length = int(length)
        self.observation_space = gym.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(3)
        self.state = np.array([self.length // 2], dtype=np.float64)

    def _obs(self) -> np.ndarray:
        return np.array([2.0 * self.state[0] / (self.length - 1) - 1.0], dtype=np.float32)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        self.state = np.array([self.length // 2], dtype=np.float64)
        return self._obs(), {}

    def step(self, action: int) -> tuple[np.ndarray, float, bool, bool, dict]:
        self.state = np.clip(self.state + (int(action) - 1), 0, self.length - 1)
        return self._obs(), -1.0, False, False, {}


gym.register(id="curiosity/Chain-v0", entry_point=ChainEnv)
