"""Build the environment a run explores: one continuing episode, pixels (two renderers) or the state vector."""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.wrappers import (
    AddRenderObservation,
    DtypeObservation,
    FrameStackObservation,
    GrayscaleObservation,
    ResizeObservation,
)
from hydra.utils import instantiate

from curiosity.build import choice
from curiosity.envs.adapter import adapter_of
from curiosity.envs.distractor import REMOTE, NoisyTV
from curiosity.envs.wrappers import FastRenderObservation, NormalisePixels


def _gym_frames(cfg: Any, max_steps: int) -> gym.Env:
    """gymnasium's own rgb_array frame, resized first (INTER_AREA), then converted to gray."""
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    env = gym.make(cfg.id, render_mode="rgb_array", max_episode_steps=max_steps)
    env = AddRenderObservation(env, render_only=True)
    env = ResizeObservation(env, (cfg.frame_size, cfg.frame_size))
    return GrayscaleObservation(env, keep_dim=False)


def _fast_frames(cfg: Any, max_steps: int) -> gym.Env:
    """Frames drawn straight at low resolution from the physical state (no pygame)."""
    env = gym.make(cfg.id, max_episode_steps=max_steps)
    return FastRenderObservation(env, instantiate(cfg.fast_renderer, size=cfg.frame_size), cfg.frame_size)


_RENDERERS: dict[str, Callable[[Any, int], gym.Env]] = {"gym": _gym_frames, "fast": _fast_frames}


def distractor_of(cfg: Any) -> str:
    """The ``env`` node's ``distractor`` (``none`` for runs saved before it existed)."""
    return choice(cfg.get("distractor", "none"))


def _frames(cfg: Any, max_steps: int) -> gym.Env:
    env = NormalisePixels(_RENDERERS[choice(cfg.renderer)](cfg, max_steps))
    distractor = distractor_of(cfg)
    if distractor == "none":
        return env
    remote = distractor == REMOTE
    noop = adapter_of(cfg).noop_action if remote else None
    return NoisyTV(env, int(cfg.tv.size), int(cfg.tv.row), int(cfg.tv.col), remote=remote, noop_action=noop)


def _pixels(cfg: Any, max_steps: int) -> gym.Env:
    return FrameStackObservation(_frames(cfg, max_steps), stack_size=cfg.frame_stack)


def _state(cfg: Any, max_steps: int) -> gym.Env:
    return DtypeObservation(gym.make(cfg.id, max_episode_steps=max_steps), np.float32)


_OBS: dict[str, Callable[[Any, int], gym.Env]] = {"pixels": _pixels, "state": _state}
_SINGLE_OBS: dict[str, Callable[[Any, int], gym.Env]] = {"pixels": _frames, "state": _state}


def make_single_obs_env(cfg: Any, max_steps: int) -> gym.Env:
    """The env of :func:`make_env` without the frame stack: one normalised frame (or the state vector) per step."""
    return _SINGLE_OBS[choice(cfg.obs)](cfg, max_steps)


def observe_state(env: gym.Env, raw_obs: Any) -> np.ndarray:
    """What ``env``'s observation wrappers make of the raw observation ``raw_obs`` of its core env in its current
    physical state: the same code path as a real step (pixel wrappers render from the state and ignore ``raw_obs``)."""
    chain = []
    while isinstance(env, gym.Wrapper):
        if isinstance(env, gym.ObservationWrapper):
            chain.append(env)
        env = env.env
    obs = raw_obs
    for wrapper in reversed(chain):
        obs = wrapper.observation(obs)
    return np.asarray(obs)


def make_env(cfg: Any, max_steps: int) -> gym.Env:
    """Build the env of an ``env`` config node.

    Args:
        cfg: the ``env`` node: ``id``, ``obs`` (pixels | state), ``renderer`` (gym | fast), ``frame_size``,
            ``frame_stack``, ``fast_renderer``, ``distractor`` (none | noisy_tv | noisy_tv_background) and ``tv``
            (the noise patch: :mod:`curiosity.envs.distractor`).
        max_steps: the run's step cap; gymnasium's own episode limit (500 for Acrobot-v1) is raised to it.

    Returns:
        A gymnasium env. Pixels: observations (frame_stack, frame_size, frame_size) float32, (x - 128)/128, the last
        ``frame_stack`` frames channel-first, the reset frame repeated at the start (with a distractor, each frame shows
        the noise patch). State: the env's vector, float32.
    """
    return _OBS[choice(cfg.obs)](cfg, max_steps)
