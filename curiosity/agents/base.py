"""The agent interface the training loop drives."""

from __future__ import annotations

import abc
from typing import Any, ClassVar

import numpy as np


class Agent(abc.ABC):
    """An exploring agent.

    The training loop calls :meth:`act` (after the random warm-up) and :meth:`observe` on every env step, in that
    order, and logs what :meth:`observe` returns. ``metric_keys`` lists every key :meth:`observe` may return, so the
    per-run CSV has a fixed header; keys are TensorBoard-style tags (``losses/transition``, ``intrinsic/reward``).
    """

    metric_keys: tuple[str, ...] = ()
    label: str = "agent"
    # what config validation asks of an agent class (curiosity/config/validate.py, from the baseline's _target_):
    imagines: ClassVar[bool] = False  # plans over imagined latent steps, so some intrinsic term must score them
    model_free_intrinsic: ClassVar[bool] = False  # learns from intrinsic rewards without a latent world model

    @abc.abstractmethod
    def act(self, obs: np.ndarray, step: int) -> int:
        """Choose an action for observation ``obs`` (shape ``obs_shape``) at global env step ``step``."""

    @abc.abstractmethod
    def observe(
        self, obs: np.ndarray, action: int, reward: float, next_obs: np.ndarray, terminated: bool, step: int
    ) -> dict[str, float]:
        """Store the transition taken at env step ``step`` (0-based), train if scheduled, return logged scalars."""

    def attach_env(self, env: Any) -> None:  # noqa: B027  (optional hook)
        """Called once by the loop with the run's env, before the first step; agents that branch the real simulator
        (the oracle planner, the model probe) keep it. Default: nothing."""

    def summary(self) -> dict[str, Any]:
        """Run totals for ``summary.json`` (``agent``); default none."""
        return {}

    @abc.abstractmethod
    def state_dict(self) -> dict[str, Any]:
        """Everything needed to resume the agent exactly (networks, optimisers, replay, RNGs)."""

    @abc.abstractmethod
    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned."""
