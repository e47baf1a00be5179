"""The paper's novelty (§3.3): how rare a latent state, or state–action pair, is in a memory of the agent's own
experience, by a density (KDE) or distance (kNN) estimator from the ``estimator`` group.

Input (``input``):
    ``state_action`` (paper text): memory rows y_t = [s_t, c·onehot(a_t)], an edge (s, a, s') is scored by
    novelty(y) with y = [s, c·onehot(a)]; c = ``action_scale`` sets how far apart actions are (docs/method.md §9).
    ``state`` (precursor code, NSRS): memory rows s_t; an edge is scored by the novelty of the state reached, s'.
    ``state_motion`` (ours, off by default): memory rows [s_{t+1}, m·(s_{t+1} − s_t)], the state each transition reached
    and the latent's one-step motion into it; an edge (s, a, s') is scored by novelty([s', m·(s' − s)]). A latent that
    codes the pose but not the velocity (the trained pixel encoder, ``studies.encoder_geometry``) then still tells a
    fast swing from a slow one through its motion; m = ``motion_scale``, in motion standard deviations.
    ``random_target`` (ours, off by default; image observations): memory rows r_t = R(o_t), the codes of a frozen
    random conv encoder of blurred frames (:class:`~curiosity.novelty.random_target.RandomTarget`); a real edge is
    scored by novelty(R(o_{t+1})), an imagined one (no frame) by novelty(g(s')), g a head trained on replay batches to
    predict R(o) from the agent's latent. The model plans in the trained latent; the novelty keeps R's geometry.
With ``standardise=True`` the latent part is standardised per dimension by the memory's mean and standard deviation
at the last refresh (the motion part of ``state_motion`` by its own), so the bandwidth, ``action_scale`` and
``motion_scale`` are in units of the latent spread, which drifts while the encoder trains.

The memory holds one row per real transition (keyed by its global replay index). The encoder keeps changing, so the
memory is re-embedded from the replay's observations (a *refresh*) every ``refresh_every`` env steps from the end of
the warm-up, and in between whenever its drift exceeds ``refresh_drift`` (> 0); the estimator is refitted then.
Nothing is scored before the first refresh (``ready``).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import torch
from torch import Tensor

from curiosity.intrinsic.base import IntrinsicContext, IntrinsicReward, latents_of
from curiosity.nets.onehot import one_hot
from curiosity.novelty.memory import EmbeddingMemory
from curiosity.novelty.protocols import NoveltyEstimator
from curiosity.novelty.random_target import RandomTarget
from curiosity.types import TransitionBatch

INPUTS = ("state_action", "state", "state_motion", "random_target")
MEMORY_KEYS = ("intrinsic/memory_size", "memory/drift", "memory/refreshed", "timing/refresh_ms")
TARGET_KEYS = ("novelty/target_loss",)  # random_target: the head's loss ‖g(s) − R(o)‖² on the last training batch


class LatentNovelty(IntrinsicReward):
    """r_nov of edges (s, a, s') on the agent's latents over a refreshed memory (see the module docstring).

    Args:
        estimator: the novelty estimator (fitted at each refresh).
        memory: the embedding memory (exact or reservoir).
        context: the agent's parts; ``replay`` and ``encode`` are required (refreshes re-encode stored observations).
        input: ``state_action``, ``state``, ``state_motion`` or ``random_target``.
        action_scale: c, the length of the action part of y (``state_action``).
        motion_scale: m, the weight of the standardised motion part (``state_motion``).
        target: R and g of ``random_target`` (required there, None otherwise).
        standardise: standardise latents per dimension by the memory's statistics at each refresh.
        refresh_every: env steps between refreshes, counted from the end of the warm-up.
        refresh_drift: also refresh whenever :meth:`drift` exceeds this (standardised units); 0: off.
        scale: multiplies ``__call__``.
    """

    needs_latents = True

    @classmethod
    def can_imagine(cls, options: Mapping[str, Any]) -> bool:
        return True

    def __init__(self, estimator: NoveltyEstimator, memory: EmbeddingMemory, context: IntrinsicContext, *,
                 input: str = "state", action_scale: float = 1.0, motion_scale: float = 1.0, standardise: bool = True,
                 refresh_every: int = 10, refresh_drift: float = 0.0, scale: float = 1.0,
                 target: RandomTarget | None = None) -> None:  # fmt: skip
        super().__init__(scale)
        if input not in INPUTS:
            raise ValueError(f"novelty input must be one of {INPUTS}, got {input!r}")
        if (input == "random_target") != (target is not None):
            raise ValueError("novelty input random_target needs its RandomTarget, and no other input takes one")
        self.target = target
        if context.replay is None or context.encode is None:
            raise ValueError("latent novelty needs the agent's replay and encoder (IntrinsicContext.replay, .encode)")
        self.estimator, self.memory, self.replay, self.encode = estimator, memory, context.replay, context.encode
        self.n_actions, self.warmup_steps, self.device = context.n_actions, context.warmup_steps, context.device
        self.input, self.action_scale, self.standardise = input, float(action_scale), bool(standardise)
        self.motion_scale = float(motion_scale)
        self.refresh_every, self.refresh_drift = int(refresh_every), float(refresh_drift)
        self.z_mean: Tensor | None = None
        self.z_std: Tensor | None = None
        self.m_mean: Tensor | None = None  # the motion part's statistics (state_motion)
        self.m_std: Tensor | None = None
        self._ready = False
        self.log_keys = (*MEMORY_KEYS, *estimator.log_keys, *(TARGET_KEYS if target is not None else ()))

    @classmethod
    def from_context(cls, *, context: IntrinsicContext, estimator: NoveltyEstimator, memory_mode: str = "exact",
                     memory_size: int = 100_000, target_dim: int = 4, target_hidden: int = 64,
                     target_lr: float = 1e-3, target_blur: float = 4.0, **kwargs: Any) -> LatentNovelty:  # fmt: skip
        """With an :class:`EmbeddingMemory` of ``memory_mode`` (``exact`` or ``reservoir`` of ``memory_size`` rows);
        ``input=random_target`` builds its :class:`RandomTarget` from the ``target_*`` keys (ignored otherwise)."""
        if not isinstance(estimator, NoveltyEstimator):
            raise TypeError(f"estimator must be a NoveltyEstimator, got {type(estimator).__name__}")
        memory = EmbeddingMemory(mode=memory_mode, reservoir_size=memory_size, seed=context.seed)
        target = None
        if str(kwargs.get("input", "state")) == "random_target":
            target = RandomTarget(tuple(context.obs_shape), context.latent_dim, dim=target_dim, hidden=target_hidden,
                                  lr=target_lr, blur_sigma=target_blur, seed=context.seed).to(context.device)  # fmt: skip
        return cls(estimator, memory, context, target=target, **kwargs)

    @property
    def ready(self) -> bool:
        return self._ready

    @property
    def imaginable(self) -> bool:
        return True

    # ------------------------------------------------------------------ embeddings
    def _std(self, z: Tensor) -> Tensor:
        if self.z_mean is None or self.z_std is None:
            return z
        return (z - self.z_mean) / self.z_std

    def _motion(self, z: Tensor, z_next: Tensor) -> Tensor:
        """The standardised, weighted motion part m·(s' − s) of ``state_motion``: (N, d), (N, d) -> (N, d)."""
        motion = z_next - z
        if self.m_mean is not None and self.m_std is not None:
            motion = (motion - self.m_mean) / self.m_std
        return self.motion_scale * motion

    def embed(self, z: Tensor, a: Tensor, z_next: Tensor | None = None) -> Tensor:
        """Memory/query embedding of transitions: z (N, d) the latent of o_t, a (N,) long, z_next (N, d) the latent of
        o_{t+1} (``state_motion`` only) -> (N, d + A) (``state_action``), (N, d) (``state``: of z) or (N, 2d)
        (``state_motion``: [s', m·(s' − s)])."""
        if self.input == "state_motion":
            if z_next is None:
                raise ValueError("novelty input state_motion embeds transitions: z_next (the latent of o_{t+1}) is needed")
            return torch.cat([self._std(z_next), self._motion(z, z_next)], dim=1)
        z = self._std(z)
        if self.input in ("state", "random_target"):  # random_target: z holds R's codes (see observe and refresh)
            return z
        return torch.cat([z, self.action_scale * one_hot(a, self.n_actions).to(z.dtype)], dim=1)

    def _encode_stored(self, keys: np.ndarray, next_obs: bool = False) -> Tensor:
        """Latents of stored transitions' o_t (``next_obs``: o_{t+1}) by global index, with the current encoder:
        (M,) -> (M, d)."""

        def frames(k: np.ndarray) -> Tensor:
            return self.replay.transitions_at(k).next_obs if next_obs else self.replay.obs_at(k)

        encode = self.encode if self.target is None else self.target.codes  # random_target: R's codes
        parts = [encode(frames(keys[i : i + 512]).to(self.device)) for i in range(0, len(keys), 512)]
        return torch.cat(parts)

    def _embed_stored(self, keys: np.ndarray, z: Tensor) -> Tensor:
        """The memory rows of stored transitions by global index, z (M, d) being the latents of their o_t."""
        z_next = self._encode_stored(keys, next_obs=True) if self.input == "state_motion" else None
        return self.embed(z, self.replay.actions_at(keys).to(z.device), z_next)

    def add(self, z: Tensor, a: int, index: int, z_next: Tensor | None = None) -> None:
        """Store the embedding of transition ``index`` (z: (d,) latent of o_t; z_next: (d,) of o_{t+1}, which
        ``state_motion`` needs)."""
        nxt = None if z_next is None else z_next.unsqueeze(0)
        emb = self.embed(z.unsqueeze(0), torch.tensor([a], device=z.device), nxt)
        self.memory.add(emb, keys=torch.tensor([index], device="cpu"))
        if self._ready:
            self.estimator.set_memory(self.memory.tensor())

    @torch.no_grad()
    def refresh(self) -> tuple[np.ndarray, Tensor]:
        """Re-embed every memory row and the random-phase reference with the current encoder; refit the estimator.

        Returns:
            The memory's keys (M,) (global transition indices) and the latents (M, d) of their o_t just encoded
            (``random_target``: R's codes of them, R standardised on the warm-up's frames at the first refresh).
        """
        if self.target is not None:
            self.target.calibrate(self.replay.obs_at(np.arange(min(self.warmup_steps, self.replay.total_added) or 1)))
        keys = self.memory.keys().numpy()
        z = self._encode_stored(keys)
        z_next = self._encode_stored(keys, next_obs=True) if self.input == "state_motion" else None
        if self.standardise:
            rows = z if z_next is None else z_next  # the states the rows hold
            self.z_mean, self.z_std = rows.mean(0), rows.std(0, correction=0).clamp_min(1e-8)
            if z_next is not None:
                motion = z_next - z
                self.m_mean, self.m_std = motion.mean(0), motion.std(0, correction=0).clamp_min(1e-8)
        self.memory.replace(self.embed(z, self.replay.actions_at(keys).to(z.device), z_next))
        ref_keys = np.arange(min(self.warmup_steps, self.replay.total_added))
        reference = None
        if len(ref_keys) > 1:
            row = {int(k): i for i, k in enumerate(keys)}
            if all(int(k) in row for k in ref_keys):  # the random phase is in the memory: no second encoding
                reference = self.memory.tensor()[[row[int(k)] for k in ref_keys]]
            else:  # a reservoir may have dropped some of it
                reference = self._embed_stored(ref_keys, self._encode_stored(ref_keys))
        self.estimator.fit(self.memory.tensor(), reference, stream_size=self.memory.stands_for)
        self._ready = True
        return keys, z

    @torch.no_grad()
    def drift(self, rows: int = 64) -> float:
        """How far the memory has gone stale: the median distance, in standardised latent units, between up to ``rows``
        memory rows (evenly spaced) and the embedding the current encoder gives their observations."""
        keys = self.memory.keys()
        index = torch.linspace(0, len(keys) - 1, min(rows, len(keys)), device="cpu").round().long()
        chosen = keys[index].numpy()
        now = self._embed_stored(chosen, self._encode_stored(chosen))  # the action part, if any, is the stored one
        stored = self.memory.tensor()[index]
        return float((now - stored).norm(dim=1).median())

    def _refresh_due(self, step: int, logs: dict[str, float]) -> bool:
        """Every ``refresh_every`` env steps from the end of the warm-up, and in between whenever the memory's drift
        (logged as ``memory/drift``) exceeds ``refresh_drift`` (> 0)."""
        since = step + 1 - self.warmup_steps
        if since < 0:
            return False
        if since % self.refresh_every == 0:
            return True
        if self.refresh_drift > 0 and self._ready:
            logs["memory/drift"] = self.drift()
            return logs["memory/drift"] > self.refresh_drift
        return False

    # ------------------------------------------------------------------ rewards
    def novelty(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        """Novelty of edges (z, a, z_next): (N, d), (N,), (N, d) -> (N,) (``random_target``: of g(z_next))."""
        if self.target is not None:
            return self.estimator(self._std(self.target.predict(z_next)))
        if self.input == "state":
            return self.estimator(self._std(z_next))
        return self.estimator(self.embed(z, a, z_next))

    def compute(self, batch: TransitionBatch) -> Tensor:
        """Novelty of real transitions (``random_target``: of R(o_{t+1}), their frames' codes)."""
        if self.target is not None:
            return self.estimator(self._std(self.target.codes(batch.next_obs.to(self.device))))
        z, z_next = latents_of(batch, "latent novelty")
        return self.novelty(z, batch.act, z_next)

    def imagine(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        return self.novelty(z, a, z_next)

    def update(self, batch: TransitionBatch) -> dict[str, float]:
        """``random_target``: one step of the head g on the batch's (s_t, o_t) and (s_{t+1}, o_{t+1}) once R is
        standardised; otherwise nothing trains here (the encoder trains in the agent)."""
        if self.target is None or not bool(self.target.calibrated):
            return {}
        z, z_next = latents_of(batch, "latent novelty")
        frames = torch.cat([batch.obs, batch.next_obs]).to(self.device)
        return {"novelty/target_loss": self.target.fit_step(torch.cat([z, z_next]), frames)}

    def observe(self, batch: TransitionBatch) -> dict[str, float]:
        """Add each fresh transition's (s_t, a_t) to the memory; refresh when due (see the module docstring)."""
        z, z_next = latents_of(batch, "latent novelty")
        if self.target is not None:  # the memory holds R's codes of o_t
            z = self.target.codes(batch.obs.to(self.device))
        if batch.index is None:
            raise ValueError("latent novelty keys its memory by transition index: the batch must carry index")
        for row, (a, index) in enumerate(zip(batch.act.tolist(), batch.index.tolist(), strict=True)):
            self.add(z[row], int(a), int(index), z_next[row] if self.input == "state_motion" else None)
        logs: dict[str, float] = {"intrinsic/memory_size": float(len(self.memory))} if self._ready else {}
        if self._refresh_due(int(batch.index[-1]), logs):
            start = time.perf_counter()
            self.refresh()
            logs.update(self.estimator.logs, **{"timing/refresh_ms": 1e3 * (time.perf_counter() - start)})
            logs["memory/refreshed"] = 1.0
        elif self._ready:
            logs["memory/refreshed"] = 0.0
        return logs

    # ------------------------------------------------------------------ checkpointing
    def to(self, device: torch.device | str) -> LatentNovelty:
        self.device = device
        if self.target is not None:
            self.target.to(device)
        return self

    def state_dict(self) -> dict[str, Any]:
        return {"memory": self.memory.state_dict(), "ready": self._ready, "z_mean": self.z_mean, "z_std": self.z_std,
                "m_mean": self.m_mean, "m_std": self.m_std, "estimator": self.estimator.state_dict(),
                "target": None if self.target is None else self.target.checkpoint()}  # fmt: skip

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.memory.load_state_dict(state["memory"])
        self._ready = bool(state["ready"])
        self.z_mean, self.z_std = state["z_mean"], state["z_std"]
        self.m_mean, self.m_std = state.get("m_mean"), state.get("m_std")  # checkpoints before state_motion had none
        if state["estimator"] is not None:
            self.estimator.load_state_dict(state["estimator"])
        if self.target is not None:
            self.target.restore(state["target"])
        if self._ready:
            self.estimator.set_memory(self.memory.tensor())
