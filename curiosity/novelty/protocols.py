"""The typed interface of a novelty estimator (the ``estimator`` group), as :mod:`curiosity.intrinsic` uses it."""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

from torch import Tensor


@runtime_checkable
class NoveltyEstimator(Protocol):
    """Scores queries against a memory of embeddings: higher for rarer queries.

    Fitted to the memory (and, for KDE baselines, the random-phase reference) at each memory refresh; sees new rows in
    between through :meth:`set_memory` (statistics stay those of the last fit).
    """

    log_keys: tuple[str, ...]  # the keys of :attr:`logs`

    def fit(self, memory: Tensor, reference: Tensor | None = None, stream_size: int | None = None) -> None:
        """Refit to ``memory`` (N, D); ``reference`` (M, D) random-phase rows or None; ``stream_size``: how many rows
        the memory stands for (a reservoir's whole stream), default N."""

    def set_memory(self, memory: Tensor) -> None:
        """Score against ``memory`` (N, D) from now on, keeping the last fit's statistics."""

    def __call__(self, query: Tensor) -> Tensor:
        """Novelty of queries (B, D) -> (B,), without gradient."""

    @property
    def logs(self) -> dict[str, float]:
        """Statistics of the last fit (e.g. the bandwidth), logged at each refresh."""

    def state_dict(self) -> dict[str, Any]:
        """Fitted statistics (not the memory, which comes back through :meth:`set_memory`)."""

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned."""
