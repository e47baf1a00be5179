"""Branch the real simulator from any physical state: the true futures of imagined action sequences.

The oracle-model planner and the model-quality probe need what the environment would really show after an action
sequence, from the state the run is in. Classic-control envs hold their whole physical state in
``env.unwrapped.state`` and are deterministic given it (Acrobot's torque noise is 0), so one private copy of the env
can be set to any state and stepped. Observations are made the way the run makes them: pixels are drawn from the
physical state by the fast renderer (gymnasium's own frames differ from it by 0.6 gray levels on average,
``tests/test_envs.py``) and pushed onto a copy of the frame stack; state vectors are the env's own observation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
from hydra.utils import instantiate

from curiosity.config.build import choice
from curiosity.envs.make import physical_state
from curiosity.envs.wrappers import normalise_pixels


@dataclass
class SimStates:
    """A batch of branch points: physical states (M, P) float64 and observations (M, *obs_shape) float32."""

    physical: np.ndarray
    obs: np.ndarray

    def __len__(self) -> int:
        return len(self.physical)

    def take(self, index: np.ndarray) -> SimStates:
        """Rows ``index`` (K,) -> a batch of K states."""
        return SimStates(self.physical[index], self.obs[index])


class Simulator:
    """A private copy of a run's env that steps any physical state.

    Args:
        env_cfg: the run's ``env`` node (``id``, ``obs``, ``frame_size``, ``fast_renderer``).
    """

    def __init__(self, env_cfg: Any) -> None:
        self.core = gym.make(env_cfg.id).unwrapped
        self.core.reset(seed=0)
        self.pixels = choice(env_cfg.obs) == "pixels"
        self.renderer = instantiate(env_cfg.fast_renderer, size=env_cfg.frame_size) if self.pixels else None

    def root(self, env: gym.Env, obs: np.ndarray) -> SimStates:
        """The branch point the run is at: its env's physical state and its current observation ``obs``."""
        return SimStates(physical_state(env)[None].copy(), np.asarray(obs, dtype=np.float32)[None].copy())

    def step(self, states: SimStates, actions: np.ndarray) -> tuple[SimStates, np.ndarray]:
        """Step every state with its action: (M,) states, (M,) int actions -> next states and (M,) bool goal flags."""
        physical = np.empty_like(states.physical)
        obs = np.empty_like(states.obs)
        goal = np.zeros(len(states), dtype=bool)
        for i, a in enumerate(np.asarray(actions, dtype=np.int64)):
            self.core.state = states.physical[i].copy()
            ob, _, terminated, _, _ = self.core.step(int(a))
            physical[i] = np.asarray(self.core.state, dtype=np.float64)
            goal[i] = bool(terminated)
            obs[i] = self._next_obs(states.obs[i], ob, physical[i])
        return SimStates(physical, obs), goal

    def _next_obs(self, obs: np.ndarray, env_obs: np.ndarray, physical: np.ndarray) -> np.ndarray:
        if self.renderer is None:
            return np.asarray(env_obs, dtype=np.float32)
        frame = normalise_pixels(self.renderer(physical))
        return np.concatenate([obs[1:], frame[None]], axis=0)
