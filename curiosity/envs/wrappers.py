"""Observation wrappers for the pixel pipeline (gymnasium's own wrappers do the rest)."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import gymnasium as gym
import numpy as np


def normalise_pixels(frame: np.ndarray) -> np.ndarray:
    """(x - 128) / 128 for a uint8 gray frame (H, W); float32 in [-1, 0.9921875]."""
    return (frame.astype(np.float32) - 128.0) / 128.0


class NormalisePixels(gym.ObservationWrapper, gym.utils.RecordConstructorArgs):
    """Maps uint8 gray frames (H, W) to float32 (x - 128) / 128."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ObservationWrapper.__init__(self, env)
        shape = env.observation_space.shape
        self.observation_space = gym.spaces.Box(-1.0, 127.0 / 128.0, shape=shape, dtype=np.float32)

    def observation(self, observation: np.ndarray) -> np.ndarray:
        return normalise_pixels(observation)


class FastRenderObservation(gym.ObservationWrapper, gym.utils.RecordConstructorArgs):
    """Replaces the observation with a (size, size) uint8 gray frame drawn from ``env.unwrapped.state``.

    Args:
        env: a classic-control env whose ``unwrapped.state`` holds the physical state.
        renderer: callable mapping the physical state to a (size, size) uint8 frame.
        size: frame side in pixels.
    """

    def __init__(self, env: gym.Env, renderer: Callable[[np.ndarray], np.ndarray], size: int) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, renderer=renderer, size=size)
        gym.ObservationWrapper.__init__(self, env)
        self.renderer = renderer
        self.observation_space = gym.spaces.Box(0, 255, shape=(size, size), dtype=np.uint8)

    def observation(self, observation: np.ndarray) -> np.ndarray:
        return self.renderer(np.asarray(self.env.unwrapped.state))


def wrapper_chain(env: gym.Env) -> Iterator[gym.Wrapper]:
    """``env`` and each wrapper below it, outermost first, down to (not including) the unwrapped env."""
    while isinstance(env, gym.Wrapper):
        yield env
        env = env.env
