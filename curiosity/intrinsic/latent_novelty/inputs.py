"""The four inputs of latent novelty, one :class:`~curiosity.intrinsic.latent_novelty.base.LatentNovelty` each: what a
memory row is (``embed``) and how an edge (s, a, s') is scored (``novelty``), plus, for ``random_target``, its random
encoder's codes and the head it trains (see :mod:`curiosity.intrinsic.latent_novelty` for what each input means).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import torch
from torch import Tensor

from curiosity.intrinsic.base import IntrinsicContext, latents_of
from curiosity.intrinsic.latent_novelty.base import LatentNovelty, mean_std
from curiosity.nets.onehot import one_hot
from curiosity.novelty.memory import EmbeddingMemory
from curiosity.novelty.protocols import NoveltyEstimator
from curiosity.novelty.random_target import RandomTarget
from curiosity.types import TransitionBatch

TARGET_KEYS = ("novelty/target_loss",)  # random_target: the head's loss ‖g(s) − R(o)‖² on the last training batch


class StateActionNovelty(LatentNovelty, input="state_action"):
    """``state_action``: rows [s, c·onehot(a)], an edge scored by its (s, a); c = ``action_scale`` (see
    :class:`LatentNovelty` for the other arguments)."""

    def __init__(self, estimator: NoveltyEstimator, memory: EmbeddingMemory, context: IntrinsicContext, *,
                 action_scale: float = 1.0, **options: Any) -> None:  # fmt: skip
        super().__init__(estimator, memory, context, **options)
        self.action_scale = float(action_scale)

    @classmethod
    def input_options(cls, context: IntrinsicContext, keys: Mapping[str, Any]) -> dict[str, Any]:
        return {"action_scale": keys["action_scale"]}

    def embed(self, z: Tensor, a: Tensor, z_next: Tensor | None = None) -> Tensor:
        """[std(z), c·onehot(a)]: (N, d), (N,) -> (N, d + A) (z_next unused)."""
        z = self._std(z)
        return torch.cat([z, self.action_scale * one_hot(a, self.n_actions).to(z.dtype)], dim=1)

    def novelty(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        """Novelty of the pair (z, a): (N, d), (N,), (N, d) -> (N,)."""
        return self.estimator(self.embed(z, a, z_next))


class StateNovelty(LatentNovelty, input="state"):
    """``state``: rows s_t, an edge scored by the state it reaches (see :class:`LatentNovelty` for the arguments)."""

    def embed(self, z: Tensor, a: Tensor, z_next: Tensor | None = None) -> Tensor:
        """std(z): (N, d) -> (N, d) (a and z_next unused)."""
        return self._std(z)

    def novelty(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        """Novelty of the state reached, z_next: (N, d), (N,), (N, d) -> (N,)."""
        return self.estimator(self._std(z_next))


class StateMotionNovelty(LatentNovelty, input="state_motion"):
    """``state_motion``: rows [s', m·(s' − s)], the state reached and the latent's motion into it, each part
    standardised by its own statistics; m = ``motion_scale`` (see :class:`LatentNovelty` for the other arguments)."""

    def __init__(self, estimator: NoveltyEstimator, memory: EmbeddingMemory, context: IntrinsicContext, *,
                 motion_scale: float = 1.0, **options: Any) -> None:  # fmt: skip
        super().__init__(estimator, memory, context, **options)
        self.motion_scale = float(motion_scale)

    @classmethod
    def input_options(cls, context: IntrinsicContext, keys: Mapping[str, Any]) -> dict[str, Any]:
        return {"motion_scale": keys["motion_scale"]}

    def _motion(self, z: Tensor, z_next: Tensor) -> Tensor:
        """The standardised, weighted motion part m·(s' − s): (N, d), (N, d) -> (N, d)."""
        motion = z_next - z
        if self.m_mean is not None and self.m_std is not None:
            motion = (motion - self.m_mean) / self.m_std
        return self.motion_scale * motion

    def embed(self, z: Tensor, a: Tensor, z_next: Tensor | None = None) -> Tensor:
        """[std(z_next), m·(z_next − z)]: (N, d), (N,), (N, d) -> (N, 2d) (a unused; z_next required)."""
        if z_next is None:
            raise ValueError("novelty input state_motion embeds transitions: z_next (the latent of o_{t+1}) is needed")
        return torch.cat([self._std(z_next), self._motion(z, z_next)], dim=1)

    def novelty(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        """Novelty of [z_next, m·(z_next − z)]: (N, d), (N,), (N, d) -> (N,)."""
        return self.estimator(self.embed(z, a, z_next))

    def _stored_next(self, keys: np.ndarray) -> Tensor | None:
        return self._encode_stored(keys, next_obs=True)

    def _fit_standardisation(self, z: Tensor, z_next: Tensor | None) -> None:
        """The states the rows hold (z_next) and the motion z_next − z, each by its own statistics."""
        assert z_next is not None
        self.z_mean, self.z_std = mean_std(z_next)
        self.m_mean, self.m_std = mean_std(z_next - z)

    def _observed(self, batch: TransitionBatch) -> tuple[Tensor, Tensor | None]:
        """The latents (B, d) of o_t and of o_{t+1}."""
        return latents_of(batch, "latent novelty")


class RandomTargetNovelty(LatentNovelty, input="random_target"):
    """``random_target``: rows R(o_t), the codes of the frozen random encoder ``target`` (R, with its head g); a real
    edge is scored by R's code of the frame reached, an imagined one by g's code of the latent reached (see
    :class:`LatentNovelty` for the other arguments)."""

    extra_log_keys = TARGET_KEYS
    target: RandomTarget

    def __init__(self, estimator: NoveltyEstimator, memory: EmbeddingMemory, context: IntrinsicContext, *,
                 target: RandomTarget, **options: Any) -> None:  # fmt: skip
        super().__init__(estimator, memory, context, **options)
        self.target = target

    @classmethod
    def input_options(cls, context: IntrinsicContext, keys: Mapping[str, Any]) -> dict[str, Any]:
        """R and g from the ``target_*`` keys, on ``context.device``."""
        target = RandomTarget(tuple(context.obs_shape), context.latent_dim, dim=keys["target_dim"],
                              hidden=keys["target_hidden"], lr=keys["target_lr"], blur_sigma=keys["target_blur"],
                              seed=context.seed).to(context.device)  # fmt: skip
        return {"target": target}

    def embed(self, z: Tensor, a: Tensor, z_next: Tensor | None = None) -> Tensor:
        """std(r): R's codes (N, k) -> (N, k) (a and z_next unused)."""
        return self._std(z)

    def novelty(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        """Novelty of the head's code g(z_next): (N, d), (N,), (N, d) -> (N,)."""
        return self.estimator(self._std(self.target.predict(z_next)))

    def compute(self, batch: TransitionBatch) -> Tensor:
        """Novelty (B,) of real transitions: of R(o_{t+1}), their frames' codes."""
        return self.estimator(self._std(self.target.codes(batch.next_obs.to(self.device))))

    def _code(self, frames: Tensor) -> Tensor:
        """R's codes of observations, (B, *obs_shape) -> (B, k)."""
        return self.target.codes(frames)

    def _before_refresh(self) -> None:
        """Standardise R on the warm-up's frames (the first refresh; later ones keep it)."""
        self.target.calibrate(self.replay.obs_at(np.arange(min(self.warmup_steps, self.replay.total_added) or 1)))

    def _observed(self, batch: TransitionBatch) -> tuple[Tensor, Tensor | None]:
        """R's codes (B, k) of o_t."""
        latents_of(batch, "latent novelty")  # the batch must carry latents, as for every input
        return self.target.codes(batch.obs.to(self.device)), None

    def update(self, batch: TransitionBatch) -> dict[str, float]:
        """One step of the head g on the batch's (s_t, o_t) and (s_{t+1}, o_{t+1}) once R is standardised."""
        if not bool(self.target.calibrated):
            return {}
        z, z_next = latents_of(batch, "latent novelty")
        frames = torch.cat([batch.obs, batch.next_obs]).to(self.device)
        return {"novelty/target_loss": self.target.fit_step(torch.cat([z, z_next]), frames)}

    def to(self, device: torch.device | str) -> LatentNovelty:
        super().to(device)
        self.target.to(device)
        return self

    def state_dict(self) -> dict[str, Any]:
        return {**super().state_dict(), "target": self.target.checkpoint()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        super().load_state_dict(state)
        self.target.restore(state["target"])
