"""The one interface every intrinsic reward implements (the paper's agent, ICM, RND, NSRS)."""

from __future__ import annotations

import abc

from torch import Tensor

from curiosity.types import TransitionBatch


class IntrinsicReward(abc.ABC):
    """An intrinsic reward module.

    Subclasses implement :meth:`compute` (the raw bonus, no gradient) and :meth:`update` (one training step of
    whatever the bonus learns, returning detached floats keyed by TensorBoard tag). Scaling is applied here, once:
    ``__call__`` returns ``scale * compute(batch)``.
    """

    log_keys: tuple[str, ...] = ()  # every key update() may return (they become metrics.csv columns)

    def __init__(self, scale: float = 1.0) -> None:
        self.scale = float(scale)

    @abc.abstractmethod
    def compute(self, batch: TransitionBatch) -> Tensor:
        """Raw bonus for each transition, shape (B,), computed without gradient.

        Must change no state (networks, optimisers, running statistics): a planner may call it many times per env
        step. Statistics move only in :meth:`update` or in a method the subclass documents (e.g. ``RND.observe``).
        """

    @abc.abstractmethod
    def update(self, batch: TransitionBatch) -> dict[str, float]:
        """One training update on ``batch``; returns logged scalars such as ``{"losses/icm_inverse": 1.09}``."""

    def observe(self, batch: TransitionBatch) -> None:  # noqa: B027 (an optional hook, not abstract)
        """Fold freshly experienced transitions, in time order, into running statistics (default: none kept)."""

    def __call__(self, batch: TransitionBatch) -> Tensor:
        return self.scale * self.compute(batch)
