"""The noisy TV (paper §2.3, §3.2, §3.3.3): a square patch of every frame that shows i.i.d. noise.

A prediction-error bonus is drawn to transitions it cannot predict; noise is unpredictable and says nothing about the
task, so an agent rewarded by prediction error alone should stare at it. Two variants (``env.distractor``):

- ``noisy_tv``, the remote control (the classic form): the env gets one more action, the last one. It applies the
  environment's no-op (its adapter's ``noop_action``: Acrobot's zero torque, MountainCar's no push) and redraws the
  noise; any other action leaves the patch frozen.
- ``noisy_tv_background``: the noise is redrawn at every step, whatever the agent does; the actions are the env's own.

The patch covers ``env.tv.size`` × ``env.tv.size`` pixels from row ``env.tv.row``, column ``env.tv.col`` of each
normalised frame; the rest of the frame is the clean frame. The noise is uniform over the 256 gray levels, normalised
like every pixel, drawn from the TV's own generator (seeded at ``reset(seed=...)``), so the env's own random stream
is untouched. Coverage, steps-to-goal and the probe read the physical state, which the TV never changes.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from curiosity.envs.wrappers import normalise_pixels, wrapper_chain

REMOTE = "noisy_tv"
_STREAM = 0x7E1E  # the TV generator's stream, apart from any other generator seeded with the run's seed


def extra_actions(distractor: str) -> int:
    """Actions a distractor adds to the env's own: 1 for the remote control, else 0."""
    return int(distractor == REMOTE)


class NoisyTV(gym.ObservationWrapper, gym.utils.RecordConstructorArgs):
    """Overlays a patch of noise on (H, W) normalised float32 frames.

    Args:
        env: an env whose observations are (H, W) normalised frames (:class:`~curiosity.envs.wrappers.NormalisePixels`).
        size, row, col: the patch's side and its top-left pixel; the patch must lie inside the frame.
        remote: the remote-control variant (one added action: the no-op plus a redraw); else redrawn every step.
        noop_action: the env's own no-op action (needed by the remote control).
    """

    def __init__(self, env: gym.Env, size: int, row: int, col: int, remote: bool, noop_action: int | None = None) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, size=size, row=row, col=col, remote=remote,
                                                 noop_action=noop_action)  # fmt: skip
        gym.ObservationWrapper.__init__(self, env)
        h, w = env.observation_space.shape
        if not (size >= 1 and 0 <= row and row + size <= h and 0 <= col and col + size <= w):
            raise ValueError(f"env.tv: a {size}x{size} patch at ({row}, {col}) does not fit a {h}x{w} frame")
        if remote and noop_action is None:
            raise ValueError("env.distractor=noisy_tv: the env has no no-op action for the remote control")
        self.rows, self.cols = slice(row, row + size), slice(col, col + size)
        self.size, self.remote, self.noop_action = size, remote, noop_action
        n = int(env.action_space.n)
        self.tv_action: int | None = n if remote else None
        if remote:
            self.action_space = gym.spaces.Discrete(n + 1)
        self.rng = np.random.default_rng(_STREAM)
        self.patch = self.noise()

    def noise(self) -> np.ndarray:
        """A fresh (size, size) patch: uniform gray levels 0..255, normalised."""
        return normalise_pixels(self.rng.integers(0, 256, size=(self.size, self.size), dtype=np.uint8))

    def redraws(self, action: int) -> bool:
        """Whether ``action`` redraws the noise (always for the background variant)."""
        return not self.remote or action == self.tv_action

    def core_action(self, action: int) -> int:
        """The env's own action for ``action``: the no-op for the TV action."""
        return int(self.noop_action) if self.remote and action == self.tv_action else int(action)

    def observation(self, observation: np.ndarray) -> np.ndarray:
        out = np.array(observation, dtype=np.float32, copy=True)
        out[self.rows, self.cols] = self.patch
        return out

    def overlay(self, frame: np.ndarray, previous: np.ndarray, action: int) -> np.ndarray:
        """The frame an imagined ``action`` shows: ``frame`` (H, W) with a fresh patch when the action redraws it,
        else the patch of ``previous`` (H, W), the frame before (frozen, as in the real env)."""
        out = np.array(frame, dtype=np.float32, copy=True)
        out[self.rows, self.cols] = self.noise() if self.redraws(action) else previous[self.rows, self.cols]
        return out

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict]:
        if seed is not None:
            self.rng = np.random.default_rng([int(seed), _STREAM])
        self.patch = self.noise()
        return super().reset(seed=seed, options=options)

    def step(self, action: Any) -> tuple[np.ndarray, Any, bool, bool, dict]:
        if self.redraws(int(action)):
            self.patch = self.noise()
        return super().step(self.core_action(int(action)))

    def state_dict(self) -> dict[str, Any]:
        """The patch on screen and the generator (for checkpoints)."""
        return {"patch": self.patch.copy(), "rng": self.rng.bit_generator.state}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.patch = np.array(state["patch"], dtype=np.float32, copy=True)
        self.rng.bit_generator.state = state["rng"]


def find_tv(env: gym.Env) -> NoisyTV | None:
    """The :class:`NoisyTV` among ``env``'s wrappers, or None."""
    return next((w for w in wrapper_chain(env) if isinstance(w, NoisyTV)), None)
