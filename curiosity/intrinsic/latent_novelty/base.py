"""The common part of latent novelty (:class:`LatentNovelty`): the memory of one row per real transition, its refresh
schedule, the standardisation and the checkpoint; one subclass per input says what a row is and how an edge is scored
(:mod:`curiosity.intrinsic.latent_novelty.inputs`, the design in :mod:`curiosity.intrinsic.latent_novelty`).

The memory is keyed by each transition's global replay index. The encoder keeps changing, so the memory is
re-embedded from the replay's observations (a *refresh*) every ``refresh_every`` env steps from the end of the
warm-up, and in between whenever its drift exceeds ``refresh_drift`` (> 0); the estimator is refitted then. Nothing
is scored before the first refresh (``ready``). With ``standardise=True`` the latents are standardised per dimension
by the memory's mean and standard deviation at the last refresh.

Each subclass registers under its input name (``class StateNovelty(LatentNovelty, input="state")``) in
:data:`NOVELTY_INPUTS`, where :meth:`LatentNovelty.from_context` (the config's entry point) looks ``input`` up.
"""

from __future__ import annotations

import abc
import time
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
import torch
from torch import Tensor

from curiosity.intrinsic.base import IntrinsicContext, IntrinsicReward, latents_of
from curiosity.novelty.memory import EmbeddingMemory
from curiosity.novelty.protocols import NoveltyEstimator
from curiosity.types import TransitionBatch

if TYPE_CHECKING:
    from curiosity.novelty.random_target import RandomTarget

MEMORY_KEYS = ("intrinsic/memory_size", "memory/drift", "memory/refreshed", "timing/refresh_ms")
NOVELTY_INPUTS: dict[str, type[LatentNovelty]] = {}  # input name -> its class, in the order the classes are defined


def novelty_class(input: str) -> type[LatentNovelty]:
    """The :class:`LatentNovelty` subclass of the input named ``input`` (a key of :data:`NOVELTY_INPUTS`)."""
    if input not in NOVELTY_INPUTS:
        raise ValueError(f"novelty input must be one of {tuple(NOVELTY_INPUTS)}, got {input!r}")
    return NOVELTY_INPUTS[input]


def mean_std(rows: Tensor) -> tuple[Tensor, Tensor]:
    """Per-dimension mean and population standard deviation (floored at 1e-8) of rows (M, d) -> (d,), (d,)."""
    return rows.mean(0), rows.std(0, correction=0).clamp_min(1e-8)


class LatentNovelty(IntrinsicReward):
    """r_nov of edges (s, a, s') on the agent's latents over a refreshed memory (see the module docstring).

    The base of one class per input: it keeps the memory, refreshes it, standardises and checkpoints; a subclass
    says what a memory row is (:meth:`embed`) and how an edge is scored (:meth:`novelty`).

    Args:
        estimator: the novelty estimator (fitted at each refresh).
        memory: the embedding memory (exact or reservoir).
        context: the agent's parts; ``replay`` and ``encode`` are required (refreshes re-encode stored observations).
        standardise: standardise latents per dimension by the memory's statistics at each refresh.
        refresh_every: env steps between refreshes, counted from the end of the warm-up.
        refresh_drift: also refresh whenever :meth:`drift` exceeds this (standardised units); 0: off.
        scale: multiplies ``__call__``.
    """

    needs_latents = True
    input: ClassVar[str]  # the subclass's input name (set by ``input=`` in its class statement)
    target: RandomTarget | None = None  # R and g (random_target only)
    extra_log_keys: ClassVar[tuple[str, ...]] = ()  # keys this input's update() adds to the memory's and estimator's

    def __init_subclass__(cls, *, input: str | None = None, **kwargs: Any) -> None:
        """``input``: the name the subclass is built under (:data:`NOVELTY_INPUTS`); None: not registered."""
        super().__init_subclass__(**kwargs)
        if input is not None:
            cls.input = input
            NOVELTY_INPUTS[input] = cls

    @classmethod
    def can_imagine(cls, options: Mapping[str, Any]) -> bool:
        return True

    def __init__(self, estimator: NoveltyEstimator, memory: EmbeddingMemory, context: IntrinsicContext, *,
                 standardise: bool = True, refresh_every: int = 10, refresh_drift: float = 0.0,
                 scale: float = 1.0) -> None:  # fmt: skip
        super().__init__(scale)
        if context.replay is None or context.encode is None:
            raise ValueError("latent novelty needs the agent's replay and encoder (IntrinsicContext.replay, .encode)")
        self.estimator, self.memory, self.replay, self.encode = estimator, memory, context.replay, context.encode
        self.n_actions, self.warmup_steps, self.device = context.n_actions, context.warmup_steps, context.device
        self.standardise = bool(standardise)
        self.refresh_every, self.refresh_drift = int(refresh_every), float(refresh_drift)
        self.z_mean: Tensor | None = None
        self.z_std: Tensor | None = None
        self.m_mean: Tensor | None = None  # the motion part's statistics (state_motion; None for the other inputs)
        self.m_std: Tensor | None = None
        self._ready = False
        self.log_keys = (*MEMORY_KEYS, *estimator.log_keys, *self.extra_log_keys)

    @classmethod
    def from_context(cls, *, context: IntrinsicContext, estimator: NoveltyEstimator, input: str = "state",
                     memory_mode: str = "exact", memory_size: int = 100_000, action_scale: float = 1.0,
                     motion_scale: float = 1.0, target_dim: int = 4, target_hidden: int = 64, target_lr: float = 1e-3,
                     target_blur: float = 4.0, **options: Any) -> LatentNovelty:  # fmt: skip
        """The class of ``input`` (:data:`NOVELTY_INPUTS`) with an :class:`EmbeddingMemory` of ``memory_mode``
        (``exact`` or ``reservoir`` of ``memory_size`` rows); of the input keys (``action_scale``, ``motion_scale``,
        ``target_*``) each class takes its own (:meth:`input_options`) and ignores the others; ``options``: the
        base's keyword arguments."""
        if not isinstance(estimator, NoveltyEstimator):
            raise TypeError(f"estimator must be a NoveltyEstimator, got {type(estimator).__name__}")
        kind = novelty_class(input)
        memory = EmbeddingMemory(mode=memory_mode, reservoir_size=memory_size, seed=context.seed)
        keys = {"action_scale": action_scale, "motion_scale": motion_scale, "target_dim": target_dim,
                "target_hidden": target_hidden, "target_lr": target_lr, "target_blur": target_blur}  # fmt: skip
        return kind(estimator, memory, context, **kind.input_options(context, keys), **options)

    @classmethod
    def input_options(cls, context: IntrinsicContext, keys: Mapping[str, Any]) -> dict[str, Any]:
        """This input's constructor options from the config's input keys (``action_scale``, ``motion_scale``,
        ``target_*``); the base takes none."""
        return {}

    @property
    def ready(self) -> bool:
        return self._ready

    @property
    def imaginable(self) -> bool:
        return True

    # ------------------------------------------------------------------ embeddings (what a subclass defines)
    @abc.abstractmethod
    def embed(self, z: Tensor, a: Tensor, z_next: Tensor | None = None) -> Tensor:
        """Memory/query embedding of transitions: z (N, d) the latent of o_t (``random_target``: R's code of it),
        a (N,) long, z_next (N, d) the latent of o_{t+1} (``state_motion`` only) -> (N, D), D depending on the input."""

    @abc.abstractmethod
    def novelty(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        """Novelty of edges (z, a, z_next): (N, d), (N,) long, (N, d) -> (N,)."""

    def _std(self, z: Tensor) -> Tensor:
        """z (N, d) standardised by the memory's statistics at the last refresh (as is before the first)."""
        if self.z_mean is None or self.z_std is None:
            return z
        return (z - self.z_mean) / self.z_std

    def _code(self, frames: Tensor) -> Tensor:
        """What the memory holds of observations: the agent's latents, (B, *obs_shape) -> (B, d)."""
        return self.encode(frames)

    def _encode_stored(self, keys: np.ndarray, next_obs: bool = False) -> Tensor:
        """:meth:`_code` of stored transitions' o_t (``next_obs``: o_{t+1}) by global index, with the current
        encoder: (M,) -> (M, d)."""

        def frames(k: np.ndarray) -> Tensor:
            return self.replay.transitions_at(k).next_obs if next_obs else self.replay.obs_at(k)

        parts = [self._code(frames(keys[i : i + 512]).to(self.device)) for i in range(0, len(keys), 512)]
        return torch.cat(parts)

    def _stored_next(self, keys: np.ndarray) -> Tensor | None:
        """The latents (M, d) of stored transitions' o_{t+1} if the memory rows need them (``state_motion``), else None."""
        return None

    def _embed_stored(self, keys: np.ndarray, z: Tensor) -> Tensor:
        """The memory rows of stored transitions by global index, z (M, d) being the latents of their o_t."""
        z_next = self._stored_next(keys)
        return self.embed(z, self.replay.actions_at(keys).to(z.device), z_next)

    def _fit_standardisation(self, z: Tensor, z_next: Tensor | None) -> None:
        """Standardisation statistics from the memory's re-encoded latents z (M, d) (and z_next (M, d) or None)."""
        self.z_mean, self.z_std = mean_std(z)

    # ------------------------------------------------------------------ memory
    def add(self, z: Tensor, a: int, index: int, z_next: Tensor | None = None) -> None:
        """Store the embedding of transition ``index`` (z: (d,) latent of o_t; z_next: (d,) of o_{t+1}, which
        ``state_motion`` needs)."""
        nxt = None if z_next is None else z_next.unsqueeze(0)
        emb = self.embed(z.unsqueeze(0), torch.tensor([a], device=z.device), nxt)
        self.memory.add(emb, keys=torch.tensor([index], device="cpu"))
        if self._ready:
            self.estimator.set_memory(self.memory.tensor())

    def _before_refresh(self) -> None:
        """Anything to do before the memory is re-encoded (nothing here)."""

    @torch.no_grad()
    def refresh(self) -> tuple[np.ndarray, Tensor]:
        """Re-embed every memory row and the random-phase reference with the current encoder; refit the estimator.

        Returns:
            The memory's keys (M,) (global transition indices) and the latents (M, d) of their o_t just encoded
            (``random_target``: R's codes of them, R standardised on the warm-up's frames at the first refresh).
        """
        self._before_refresh()
        keys = self.memory.keys().numpy()
        z = self._encode_stored(keys)
        z_next = self._stored_next(keys)
        if self.standardise:
            self._fit_standardisation(z, z_next)
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
    def compute(self, batch: TransitionBatch) -> Tensor:
        """Novelty (B,) of real transitions: :meth:`novelty` of their latents."""
        z, z_next = latents_of(batch, "latent novelty")
        return self.novelty(z, batch.act, z_next)

    def imagine(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        return self.novelty(z, a, z_next)

    def update(self, batch: TransitionBatch) -> dict[str, float]:
        """Nothing trains here (the encoder trains in the agent)."""
        return {}

    def _observed(self, batch: TransitionBatch) -> tuple[Tensor, Tensor | None]:
        """What :meth:`add` stores of fresh transitions: the latents (B, d) of o_t, and of o_{t+1} (B, d) or None."""
        z, _ = latents_of(batch, "latent novelty")
        return z, None

    def observe(self, batch: TransitionBatch) -> dict[str, float]:
        """Add each fresh transition's (s_t, a_t) to the memory; refresh when due (see the module docstring)."""
        z, z_next = self._observed(batch)
        if batch.index is None:
            raise ValueError("latent novelty keys its memory by transition index: the batch must carry index")
        for row, (a, index) in enumerate(zip(batch.act.tolist(), batch.index.tolist(), strict=True)):
            self.add(z[row], int(a), int(index), None if z_next is None else z_next[row])
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
        return self

    def state_dict(self) -> dict[str, Any]:
        """The memory, the standardisation, the estimator's fit and ``target`` (None but for ``random_target``)."""
        return {"memory": self.memory.state_dict(), "ready": self._ready, "z_mean": self.z_mean, "z_std": self.z_std,
                "m_mean": self.m_mean, "m_std": self.m_std, "estimator": self.estimator.state_dict(),
                "target": None}  # fmt: skip

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.memory.load_state_dict(state["memory"])
        self._ready = bool(state["ready"])
        self.z_mean, self.z_std = state["z_mean"], state["z_std"]
        self.m_mean, self.m_std = state.get("m_mean"), state.get("m_std")  # checkpoints before state_motion had none
        if state["estimator"] is not None:
            self.estimator.load_state_dict(state["estimator"])
        if self._ready:
            self.estimator.set_memory(self.memory.tensor())
