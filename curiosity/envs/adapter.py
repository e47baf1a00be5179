"""How the project uses one environment: an :class:`EnvAdapter`, named by the ``env`` group's ``_target_``.

An environment is one YAML (``conf/env/<name>.yaml``: ``_target_``, gymnasium ``id``, rendering, coverage grid) and,
when it needs code, one module (``curiosity/envs/<name>.py``) with its adapter. The adapter says what the loop, the
coverage grid, the behaviour columns, the oracle planner and the model probe need to know about the environment:

- its **physical state** (read and set: checkpoints, coverage, branching the simulator);
- whether a step **reached the goal**, which is not the same as terminating: a termination that is not the goal (a
  fallen pole) ends the episode, the loop resets the env and the run goes on; the goal ends the run (steps-to-goal);
- its **directed action** (what a hand-made energy-pumping policy would do) and its **energy**, where it has them;
- its **no-op action**, where it has one (the noisy TV's remote control, :mod:`curiosity.envs.distractor`).

The number of actions and the state vector's length come from the environment's own spaces (``env_actions`` and
``env_state_dim`` resolvers), not from hand-written YAML.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from typing import Any

import gymnasium as gym
import numpy as np
from hydra.utils import get_class


class EnvAdapter:
    """The default adapter: a gymnasium classic-control env whose ``unwrapped.state`` is its whole physical state and
    whose termination is its goal (Acrobot's tip above the line, MountainCar's flag).

    Args:
        env_id: the gymnasium id.
    """

    directed_action: Callable[[np.ndarray], int | None] | None = None  # physical state -> the pumping action, or None
    energy: Callable[[np.ndarray], np.ndarray] | None = None  # physical states (..., P) -> mechanical energy (...)
    noop_action: int | None = None  # the action that does nothing (the noisy TV's remote control applies it), or None

    def __init__(self, env_id: str) -> None:
        self.env_id = env_id

    def physical_state(self, env: gym.Env) -> np.ndarray:
        """The true physical state of ``env`` (any wrapper of it), float64 (P,)."""
        return np.asarray(env.unwrapped.state, dtype=np.float64)

    def set_physical_state(self, env: gym.Env, state: np.ndarray) -> None:
        """Put ``env`` (any wrapper of it) in physical state ``state`` (P,)."""
        env.unwrapped.state = np.array(state, dtype=np.float64)

    def goal_reached(self, env: gym.Env, terminated: bool, info: Mapping[str, Any]) -> bool:
        """Whether the step that left ``env`` (any wrapper of it) in its state and returned ``terminated`` and ``info``
        reached the goal (here: any termination)."""
        return bool(terminated)


def with_sign(velocity: float) -> int | None:
    """The push in the direction of a velocity, of three actions (0: −, 1: none, 2: +): 2 if > 0, 0 if < 0, None at 0
    (a state without motion has no directed action)."""
    if velocity == 0.0:
        return None
    return 2 if velocity > 0 else 0


def adapter_of(env_cfg: Any) -> EnvAdapter:
    """The adapter an ``env`` node names with its ``_target_``, for its ``id``."""
    return get_class(str(env_cfg._target_))(str(env_cfg.id))


@functools.cache
def _spaces(env_id: str) -> tuple[int, tuple[int, ...]]:
    import curiosity.envs  # noqa: F401  (registers the project's own envs)

    env = gym.make(env_id)
    try:
        space = env.action_space
        if not isinstance(space, gym.spaces.Discrete):
            raise ValueError(f"env.id={env_id}: has a {type(space).__name__} action space; allowed: discrete actions")
        return int(space.n), tuple(int(s) for s in env.observation_space.shape or ())
    finally:
        env.close()


def env_actions(env_id: str, distractor: str = "none") -> int:
    """``${env_actions:<id>,<distractor>}``: the number of discrete actions of gymnasium env ``env_id``, plus the
    actions its distractor adds (the noisy TV's remote control: one)."""
    from curiosity.build import choice
    from curiosity.envs.distractor import extra_actions

    return _spaces(str(env_id))[0] + extra_actions(choice(distractor))


def env_state_dim(env_id: str) -> int:
    """``${env_state_dim:<id>}``: the length of gymnasium env ``env_id``'s own (vector) observation."""
    shape = _spaces(str(env_id))[1]
    return int(np.prod(shape)) if shape else 1
