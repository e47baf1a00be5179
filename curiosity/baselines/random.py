"""The uniformly random policy."""

from __future__ import annotations

import numpy as np
from omegaconf import DictConfig

from curiosity.agents.base import Agent


class RandomAgent(Agent):
    """Uniformly random actions over ``env.n_actions``, seeded from ``seed``; learns nothing."""

    metric_keys: tuple[str, ...] = ()

    def __init__(self, cfg: DictConfig) -> None:
        self.n_actions = int(cfg.env.n_actions)
        self.rng = np.random.default_rng([int(cfg.seed), 1])
        self.label = str(cfg.method_label)

    def act(self, obs: np.ndarray, step: int) -> int:
        return int(self.rng.integers(self.n_actions))

    def observe(
        self, obs: np.ndarray, action: int, reward: float, next_obs: np.ndarray, terminated: bool, step: int
    ) -> dict[str, float]:
        return {}

    def state_dict(self) -> dict:
        return {"rng": self.rng.bit_generator.state}

    def load_state_dict(self, state: dict) -> None:
        self.rng.bit_generator.state = state["rng"]
