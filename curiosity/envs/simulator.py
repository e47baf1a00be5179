"""Branch the real simulator from any physical state: the true futures of imagined action sequences.

The oracle-model planner and the model-quality probe need what the environment would really show after an action
sequence, from the state the run is in. The env's adapter reads and sets its physical state (classic-control envs
hold all of it in ``env.unwrapped.state`` and are deterministic given it: Acrobot's torque noise is 0), so one private
copy of the env can be set to any state and stepped. Observations go through the run's own observation wrappers
(same renderer, same resizing and gray conversion, bit for bit), and frames are pushed onto a copy of the frame stack.
With a noisy TV, the TV action steps the env's no-op; an imagined frame shows fresh noise where the action redraws
it and the previous frame's patch where it stays frozen (:meth:`~curiosity.envs.distractor.NoisyTV.overlay`).
The learned encoder must see imagined frames exactly as it sees real ones: frames of the other renderer (0.6 gray
levels apart on average) moved the oracle's latents enough to swamp the novelty differences between candidates.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from curiosity.build import choice
from curiosity.envs.adapter import adapter_of
from curiosity.envs.distractor import find_tv
from curiosity.envs.make import make_single_obs_env, observe_state


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
        env_cfg: the run's ``env`` node.
    """

    def __init__(self, env_cfg: Any) -> None:
        self.env: gym.Env = make_single_obs_env(env_cfg, max_steps=10**9)
        self.env.reset(seed=0)
        self.core = self.env.unwrapped
        self.adapter = adapter_of(env_cfg)
        self.pixels = choice(env_cfg.obs) == "pixels"
        self.tv = find_tv(self.env)

    def root(self, env: gym.Env, obs: np.ndarray) -> SimStates:
        """The branch point the run is at: its env's physical state and its current observation ``obs``."""
        return SimStates(self.adapter.physical_state(env)[None].copy(), np.asarray(obs, dtype=np.float32)[None].copy())

    def step(self, states: SimStates, actions: np.ndarray) -> tuple[SimStates, np.ndarray]:
        """Step every state with its action: (M,) states, (M,) int actions -> next states and (M,) bool goal flags (the
        adapter's goal, not any termination)."""
        physical = np.empty_like(states.physical)
        obs = np.empty_like(states.obs)
        goal = np.zeros(len(states), dtype=bool)
        for i, a in enumerate(np.asarray(actions, dtype=np.int64)):
            self.adapter.set_physical_state(self.core, states.physical[i])
            ob, _, terminated, _, info = self.core.step(int(a) if self.tv is None else self.tv.core_action(int(a)))
            physical[i] = self.adapter.physical_state(self.core)
            goal[i] = self.adapter.goal_reached(self.core, bool(terminated), info)
            obs[i] = self._next_obs(states.obs[i], ob, int(a))
        return SimStates(physical, obs), goal

    def _next_obs(self, obs: np.ndarray, env_obs: np.ndarray, action: int) -> np.ndarray:
        new = observe_state(self.env, env_obs).astype(np.float32)
        if self.tv is not None:
            new = self.tv.overlay(new, obs[-1], action)
        return np.concatenate([obs[1:], new[None]], axis=0) if self.pixels else new
