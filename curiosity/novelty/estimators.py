"""The ``estimator`` group: novelty estimators over a memory of embeddings, as the agents use them.

An estimator is fitted to a memory (and, for KDE baselines, a random-phase reference) at each memory refresh, sees
new memory rows in between through :meth:`set_memory` (cheap: statistics stay those of the last fit), and scores
queries: ``reward = estimator(query)``, (B, D) -> (B,), higher for rarer queries.

The latent scale drifts while the encoder trains (dispersion losses push latents apart), so bandwidths and distance
scales can be relative to the memory's own spread, recomputed at every fit:
``bandwidth_rule=median_nn``: h = bandwidth × median nearest-neighbour distance in the memory (exact duplicates
left out; a k-d tree finds the neighbours, so a refit costs O(N log N));
``bandwidth_rule=scott``: h = bandwidth × N^(−1/(D+4)) (Scott's rule; with ``standardise`` as in the precursor);
``bandwidth_rule=fixed``: h = bandwidth.

Layers of a KDE score: :class:`~curiosity.intrinsic.latent_novelty.LatentNovelty` calls :class:`KDENovelty`, which
is a :class:`~curiosity.novelty.rewards.KDENoveltyReward` (the random-phase baselines, as named pure functions) and
calls :func:`~curiosity.novelty.kde.kde_log_density` itself. The kNN estimators call
:mod:`curiosity.novelty.knn` directly.
"""

from __future__ import annotations

from typing import Any

import torch
from torch import Tensor

from curiosity.novelty.knn import knn_distance, nsrs_knn_score, self_knn_distances
from curiosity.novelty.rewards import KDENoveltyReward

BANDWIDTH_RULES = ("fixed", "median_nn", "scott")


class _Standardiser:
    """Per-dimension (x − mean) / std with the memory's statistics (identity when off)."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.mean: Tensor | None = None
        self.std: Tensor | None = None

    def fit(self, memory: Tensor) -> None:
        if self.enabled:
            self.mean, self.std = memory.mean(0), memory.std(0, correction=0).clamp_min(1e-8)

    def __call__(self, x: Tensor) -> Tensor:
        if not self.enabled or self.mean is None or self.std is None:
            return x
        return (x - self.mean) / self.std


class KDENovelty(KDENoveltyReward):
    """KDE novelty: a :class:`~curiosity.novelty.rewards.KDENoveltyReward` (the baselines and the KDE itself, so a score
    is one call above :func:`~curiosity.novelty.kde.kde_log_density`) whose bandwidth follows a rule and whose
    inputs are standardised, both refitted at every :meth:`fit`.

    ``bandwidth`` after construction is the fitted h (the reward's); the constructor's ``bandwidth`` is kept as
    ``multiplier``.

    Args:
        bandwidth: h (``fixed``) or its multiplier (``median_nn``, ``scott``), > 0.
        baseline: random-phase baseline of the reward (``scalar``, ``pointwise``, ``zscore``, ``none``, ``printed``).
        bandwidth_rule: one of ``fixed``, ``median_nn``, ``scott``.
        standardise: standardise every dimension by the memory's mean and std before the KDE (the precursor's way).
        self_in_reference: count each memory point itself in the baseline statistics (sklearn's ``score_samples``).
        precision: the KDE's arithmetic: ``float64`` (exact) or ``float32`` (faster, for big or sampled memories).
    """

    def __init__(self, bandwidth: float = 2.0, baseline: str = "scalar", bandwidth_rule: str = "median_nn",
                 standardise: bool = False, self_in_reference: bool = False, precision: str = "float64") -> None:  # fmt: skip
        if bandwidth_rule not in BANDWIDTH_RULES:
            raise ValueError(f"estimator.bandwidth_rule must be one of {BANDWIDTH_RULES}, got {bandwidth_rule!r}")
        super().__init__(bandwidth=float(bandwidth), baseline=baseline, self_in_reference=self_in_reference,
                         precision=precision)  # fmt: skip
        self.multiplier, self.rule = float(bandwidth), bandwidth_rule
        self.standardiser = _Standardiser(standardise)

    @property
    def needs_reference(self) -> bool:
        return self.baseline in ("scalar", "pointwise", "printed")

    def _bandwidth(self, memory: Tensor, stream_size: int) -> float:
        if self.rule == "fixed" or len(memory) < 2:
            return self.multiplier
        n, d = max(stream_size, len(memory)), memory.shape[1]
        if self.rule == "scott":
            return self.multiplier * n ** (-1.0 / (d + 4))
        nn = self_knn_distances(memory, k=1)[:, 0]  # a k-d tree: O(N log N) at every refresh
        nn = nn[nn > 0]  # exact duplicates (e.g. repeated frames) say nothing about the spacing
        spacing = float(nn.median()) if nn.numel() else 1.0
        # a uniform sample of M of n rows is spaced (n / M)^(1/d) times wider than the n rows themselves
        return self.multiplier * spacing * (len(memory) / n) ** (1.0 / d)

    @torch.no_grad()
    def fit(self, memory: Tensor, reference: Tensor | None = None, stream_size: int | None = None) -> None:
        """Refit to ``memory`` (N, D): standardisation, bandwidth, baseline statistics (reference (M, D) if needed).

        ``stream_size``: how many rows ``memory`` stands for when it is a uniform sample of them (a reservoir); the
        bandwidth is then the one the whole stream would get (``median_nn``: the sample's spacing × (N /
        stream_size)^(1/D); ``scott``: of stream_size rows), so the sample's KDE estimates the whole stream's."""
        self.standardiser.fit(memory)
        mem = self.standardiser(memory)
        self.bandwidth = self._bandwidth(mem, stream_size or len(mem))
        if self.needs_reference:
            if reference is None or len(reference) < 2:
                raise ValueError(f"estimator.baseline={self.baseline} needs the random-phase embeddings")
            self.set_reference(self.standardiser(reference))
        super().fit(mem)

    def set_memory(self, memory: Tensor) -> None:
        """Score against ``memory`` (N, D) from now on, keeping the last fit's statistics."""
        self.memory = self.standardiser(memory).detach()

    @torch.no_grad()
    def __call__(self, query: Tensor) -> Tensor:
        """Novelty of queries (B, D) -> (B,): the reward of the standardised queries."""
        return super().__call__(self.standardiser(query))

    log_keys = ("intrinsic/bandwidth",)

    @property
    def logs(self) -> dict[str, float]:
        return {"intrinsic/bandwidth": self.bandwidth}

    def state_dict(self) -> dict[str, Any]:
        """Fitted statistics: the bandwidth, the reward's (``"reward"``: reference and baseline statistics) and the
        standardisation; the memory itself comes from ``set_memory``."""
        return {"bandwidth": self.bandwidth, "reward": super().state_dict(),
                "mean": self.standardiser.mean, "std": self.standardiser.std}  # fmt: skip

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.bandwidth = float(state["bandwidth"])
        super().load_state_dict(state["reward"])
        self.standardiser.mean, self.standardiser.std = state["mean"], state["std"]


class KNNNovelty:
    """kNN novelty: mean Euclidean distance to the k nearest memory rows.

    Args:
        k: neighbours, ≥ 1.
        normalise: divide by the memory's own mean kNN distance (leave-one-out) at the last fit, so the reward is
            scale-free like the KDE one.
    """

    def __init__(self, k: int = 5, normalise: bool = True) -> None:
        self.k, self.normalise = int(k), bool(normalise)
        self.memory: Tensor | None = None
        self.scale = 1.0

    def fit(self, memory: Tensor, reference: Tensor | None = None, stream_size: int | None = None) -> None:
        """Refit to ``memory`` (N, D) (``reference`` and ``stream_size`` are unused: the scale is the memory's own)."""
        self.set_memory(memory)
        if self.normalise and len(memory) > self.k:
            self.scale = max(float(self_knn_distances(memory, k=self.k).mean()), 1e-8)

    def set_memory(self, memory: Tensor) -> None:
        self.memory = memory.detach()

    @torch.no_grad()
    def __call__(self, query: Tensor) -> Tensor:
        if self.memory is None:
            raise RuntimeError("fit(memory) before scoring")
        k = min(self.k, len(self.memory))
        return knn_distance(query, self.memory, k=k) / self.scale

    log_keys = ("intrinsic/knn_scale",)

    @property
    def logs(self) -> dict[str, float]:
        return {"intrinsic/knn_scale": self.scale}

    def state_dict(self) -> dict[str, Any]:
        return {"scale": self.scale}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.scale = float(state["scale"])


class NSRSKNNNovelty(KNNNovelty):
    """NSRS's score: mean of the 2nd..k-th smallest squared distances to the memory (no normalisation)."""

    def __init__(self, k: int = 5) -> None:
        super().__init__(k=k, normalise=False)

    @torch.no_grad()
    def __call__(self, query: Tensor) -> Tensor:
        if self.memory is None:
            raise RuntimeError("fit(memory) before scoring")
        return nsrs_knn_score(query, self.memory, k=min(self.k, len(self.memory)))

    log_keys = ()

    @property
    def logs(self) -> dict[str, float]:
        return {}
