"""KDE novelty scores of the paper (§3.3) with a random-phase baseline.

Every score is a named pure function; :class:`KDENoveltyReward` wraps them with the state they need (reference
statistics), takes constructor kwargs only (``hydra.utils.instantiate`` friendly) and exposes ``state_dict()`` /
``load_state_dict()``. Scores are computed without gradient. The agents' KDE estimator,
:class:`~curiosity.novelty.estimators.KDENovelty`, is a :class:`KDENoveltyReward` with a bandwidth rule and
standardisation. The prediction-error bonus and the hybrid live in :mod:`curiosity.intrinsic`.
"""

from __future__ import annotations

from typing import Any

import torch
from torch import Tensor

from curiosity.novelty._common import DEFAULT_CHUNK
from curiosity.novelty.kde import PRECISIONS, kde_log_density

BASELINES = ("scalar", "pointwise", "printed", "zscore", "none")


def kde_reward_scalar(log_rho: Tensor, log_rho0_bar: Tensor | float) -> Tensor:
    """Default KDE reward (docs/method.md §4): r = log ρ̄0 − log ρ(y), shapes (B,) and scalar -> (B,).

    ρ̄0 is a scalar reference: log ρ̄0 = mean over the random-phase samples of their log-density under their own KDE.
    Large where y is rare in the replay memory compared with what the random agent typically met (the paper's intent).
    """
    return log_rho0_bar - log_rho


def kde_reward_pointwise(log_rho: Tensor, log_rho0: Tensor) -> Tensor:
    """Pointwise random-phase baseline with the intended sign: r = log ρ0(y) − log ρ(y), (B,), (B,) -> (B,).

    ρ0(y) is the KDE of the random-phase samples at y. Far outside their support log ρ0 → −∞, so this punishes
    exactly the novel states (docs/method.md §4); kept as an alternative.
    """
    return log_rho0 - log_rho


def kde_reward_printed(log_rho: Tensor, log_rho0: Tensor) -> Tensor:
    """The paper's formula as printed (Eq. 7): r = log(ρ(y) / ρ0(y)) = log ρ(y) − log ρ0(y), (B,), (B,) -> (B,).

    This sign rewards familiar regions (contrary to the text's stated intent); kept only for ablations.
    """
    return log_rho - log_rho0


def kde_reward_zscore(log_rho: Tensor, mem_mean: Tensor | float, mem_std: Tensor | float, eps: float = 1e-8) -> Tensor:
    """The precursor code's negative z-score: r = −(log ρ(y) − mean_mem log ρ) / max(std_mem log ρ, eps), (B,) -> (B,).

    ``mem_mean`` / ``mem_std`` are the mean and population standard deviation (ddof = 0, numpy's default) of the
    memory's log-densities under the memory's own KDE.
    """
    return -(log_rho - mem_mean) / max(float(mem_std), eps)


def kde_reward_none(log_rho: Tensor) -> Tensor:
    """No baseline: r = −log ρ(y), (B,) -> (B,)."""
    return -log_rho


class KDENoveltyReward:
    """KDE novelty reward r(y) from log ρ(y) over a memory and a random-phase baseline (docs/method.md §4).

    ``baseline`` selects the reward (see the named functions): ``"scalar"`` (default) log ρ̄0 − log ρ(y);
    ``"pointwise"`` log ρ0(y) − log ρ(y); ``"printed"`` log ρ(y) − log ρ0(y) (paper Eq. 7 as printed);
    ``"zscore"`` −(log ρ(y) − mean_mem log ρ) / std_mem log ρ (precursor code); ``"none"`` −log ρ(y).

    Usage: ``set_reference(random_phase_emb)`` (scalar / pointwise / printed; call again after re-embedding with the
    current encoder), ``fit(memory_emb)`` whenever the memory changes, then ``reward = obj(query)``.

    Self-counting: queries (imagined or new embeddings) are scored against every memory row. The reference statistics
    computed from a set's KDE of itself (ρ̄0 for ``scalar``, mean/std over the memory for ``zscore``) leave each
    sample's own kernel term out by default (leave-one-out, so they match a query that is not in the set);
    ``self_in_reference=True`` counts it, as sklearn's ``score_samples`` on its own fit data did in the precursor.

    Args:
        bandwidth: KDE bandwidth h > 0 (log ρ(y) = logsumexp_i(−‖y − y_i‖²/(2h²)) − log N).
        baseline: one of ``BASELINES``.
        self_in_reference: see above.
        zscore_eps: floor on the memory's standard deviation in ``zscore`` mode.
        chunk_size: memory rows per KDE chunk.
        precision: the KDE's arithmetic, ``"float64"`` (exact, the reference) or ``"float32"`` (about 1.6× faster,
            ≈ 1e-4 nats off on standardised latents; see :func:`~curiosity.novelty.kde.kde_log_density`).
    """

    def __init__(
        self,
        bandwidth: float,
        baseline: str = "scalar",
        self_in_reference: bool = False,
        zscore_eps: float = 1e-8,
        chunk_size: int = DEFAULT_CHUNK,
        precision: str = "float64",
    ) -> None:
        if baseline not in BASELINES:
            raise ValueError(f"baseline must be one of {BASELINES}, got {baseline!r}")
        if not bandwidth > 0:
            raise ValueError(f"bandwidth must be > 0, got {bandwidth}")
        self.bandwidth = float(bandwidth)
        self.baseline = baseline
        self.self_in_reference = bool(self_in_reference)
        self.zscore_eps = float(zscore_eps)
        self.chunk_size = int(chunk_size)
        if precision not in PRECISIONS:
            raise ValueError(f"precision must be one of {tuple(PRECISIONS)}, got {precision!r}")
        self.precision = precision
        self.memory: Tensor | None = None
        self.reference: Tensor | None = None
        self.log_rho0_bar: Tensor | None = None
        self.mem_mean: Tensor | None = None
        self.mem_std: Tensor | None = None

    def _self_log_density(self, emb: Tensor) -> Tensor:
        loo = not self.self_in_reference
        return kde_log_density(emb, emb, bandwidth=self.bandwidth, exclude_self=loo, chunk_size=self.chunk_size,
                               precision=self.precision)  # fmt: skip

    @torch.no_grad()
    def set_reference(self, emb: Tensor) -> None:
        """Set the random-phase embeddings (M, d): stores them and log ρ̄0 = mean_j log ρ0(x_j) (under their own KDE)."""
        self.reference = emb.detach().clone()
        self.log_rho0_bar = self._self_log_density(self.reference).mean()

    @torch.no_grad()
    def fit(self, memory: Tensor) -> None:
        """Use ``memory`` (N, d) as the replay memory; in ``zscore`` mode also compute its log-density mean and std."""
        self.memory = memory.detach()
        if self.baseline == "zscore":
            log_rho = self._self_log_density(self.memory)
            self.mem_mean, self.mem_std = log_rho.mean(), log_rho.std(correction=0)

    @torch.no_grad()
    def log_density(self, query: Tensor) -> Tensor:
        """log ρ(y) of queries (B, d) over the fitted memory -> (B,)."""
        if self.memory is None:
            raise RuntimeError("call fit(memory) before scoring queries")
        return kde_log_density(query, self.memory, bandwidth=self.bandwidth, chunk_size=self.chunk_size,
                               precision=self.precision)  # fmt: skip

    def _reference_log_density(self, query: Tensor) -> Tensor:
        if self.reference is None:
            raise RuntimeError(f"baseline={self.baseline!r} needs set_reference(random_phase_embeddings) first")
        return kde_log_density(query, self.reference, bandwidth=self.bandwidth, chunk_size=self.chunk_size,
                               precision=self.precision)  # fmt: skip

    @torch.no_grad()
    def __call__(self, query: Tensor) -> Tensor:
        """Novelty reward of queries (B, d) -> (B,), following ``baseline``."""
        log_rho = self.log_density(query)
        if self.baseline == "none":
            return kde_reward_none(log_rho)
        if self.baseline == "zscore":
            return kde_reward_zscore(log_rho, self.mem_mean, self.mem_std, self.zscore_eps)
        if self.baseline == "scalar":
            if self.log_rho0_bar is None:
                raise RuntimeError("baseline='scalar' needs set_reference(random_phase_embeddings) first")
            return kde_reward_scalar(log_rho, self.log_rho0_bar.to(log_rho.dtype))
        log_rho0 = self._reference_log_density(query).to(log_rho.dtype)
        fn = kde_reward_pointwise if self.baseline == "pointwise" else kde_reward_printed
        return fn(log_rho, log_rho0)

    def state_dict(self) -> dict[str, Any]:
        """Reference embeddings and statistics (the memory itself is not saved: call ``fit`` again after loading)."""
        keys = ("reference", "log_rho0_bar", "mem_mean", "mem_std")
        return {"baseline": self.baseline, **{k: None if getattr(self, k) is None else getattr(self, k).clone() for k in keys}}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` saved; the baseline must match."""
        if state["baseline"] != self.baseline:
            raise ValueError(f"state is for baseline={state['baseline']!r}, this object uses {self.baseline!r}")
        for k in ("reference", "log_rho0_bar", "mem_mean", "mem_std"):
            setattr(self, k, state[k])
