"""CartPole-v1 as an exploration task: the goal is the cart reaching |x| > 2; the pole falling is not the goal."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium as gym

from curiosity.envs.adapter import EnvAdapter

GOAL_X = 2.0


class CartPoleAdapter(EnvAdapter):
    """Physical state (x, ẋ, θ, θ̇); the goal: |x| > 2 (gymnasium's own termination at |x| > 2.4 or |θ| > 12° is a
    fall the loop resets from unless the cart got there)."""

    def goal_reached(self, env: gym.Env, terminated: bool, info: Mapping[str, Any]) -> bool:
        return abs(float(self.physical_state(env)[0])) > GOAL_X
