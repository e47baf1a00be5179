"""Save and restore the full state of a wrapped classic-control env (for checkpoints)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.wrappers import FrameStackObservation, TimeLimit

from curiosity.envs.adapter import EnvAdapter
from curiosity.envs.distractor import NoisyTV
from curiosity.envs.wrappers import wrapper_chain


def env_state(env: gym.Env, adapter: EnvAdapter) -> dict[str, Any]:
    """Physical state (read by the env's adapter), the env's RNG, stacked frames, the time-limit counter and the
    noisy TV's patch and generator (with a distractor)."""
    state: dict[str, Any] = {"physical": adapter.physical_state(env).copy(),
                             "np_random": env.unwrapped.np_random.bit_generator.state}  # fmt: skip
    for w in wrapper_chain(env):
        if isinstance(w, FrameStackObservation):
            state["frames"] = [np.array(f, copy=True) for f in w.obs_queue]
        elif isinstance(w, TimeLimit):
            state["elapsed"] = w._elapsed_steps
        elif isinstance(w, NoisyTV):
            state["tv"] = w.state_dict()
    return state


def restore_env(env: gym.Env, state: dict[str, Any], seed: int, adapter: EnvAdapter) -> None:
    """Bring a freshly built ``env`` to ``state`` (resets it first so every wrapper is initialised)."""
    env.reset(seed=seed)
    adapter.set_physical_state(env, state["physical"])
    env.unwrapped.np_random.bit_generator.state = state["np_random"]
    for w in wrapper_chain(env):
        if isinstance(w, FrameStackObservation):
            w.obs_queue.clear()
            w.obs_queue.extend(np.array(f, copy=True) for f in state["frames"])
        elif isinstance(w, TimeLimit):
            w._elapsed_steps = state["elapsed"]
        elif isinstance(w, NoisyTV):
            w.load_state_dict(state["tv"])
