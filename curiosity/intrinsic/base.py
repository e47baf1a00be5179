"""The one interface every intrinsic reward implements, and what an agent hands a reward when it builds it.

Every reward (latent novelty, the prediction-error bonus, ICM, RND, and their :class:`~curiosity.intrinsic.mixture.
Mixture`) is built from the ``intrinsic`` config group by the agent that uses it, so any reward can drive any agent
whose parts it needs: a reward on the agent's latents (``needs_latents``) can score the imagined edges of a planner
(``imaginable``); a reward that reads observations drives the Q agent, or the planner's real transitions only.
"""

from __future__ import annotations

import abc
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import torch
from torch import Tensor

from curiosity.types import TransitionBatch

if TYPE_CHECKING:
    from curiosity.nets.world_model import WorldModel
    from curiosity.replay import ReplayBuffer


@dataclass
class IntrinsicContext:
    """What the agent gives the rewards it builds (``reward_factory(context=...)``).

    Attributes:
        n_actions: A.
        obs_shape: shape of one observation, e.g. (4, 32, 32).
        latent_dim: d, the size of the agent's latents.
        warmup_steps: length of the uniformly random phase (transitions with a lower global index form it).
        seed: the run's seed (for rewards that sample, e.g. a reservoir memory).
        device: where the agent's networks live.
        replay: the agent's replay buffer (rewards that re-encode stored observations read it), or None.
        encode: the agent's encoder in eval mode without gradient, (B, *obs_shape) -> (B, d), or None.
        model: the agent's latent world model (transition for prediction errors), or None (the Q agent has none).
    """

    n_actions: int
    obs_shape: tuple[int, ...]
    latent_dim: int
    warmup_steps: int = 0
    seed: int = 0
    device: torch.device | str = "cpu"
    replay: ReplayBuffer | None = None
    encode: Callable[[Tensor], Tensor] | None = None
    model: WorldModel | None = None


class IntrinsicReward(abc.ABC):
    """An intrinsic reward module.

    Subclasses implement :meth:`compute` (the raw bonus of real transitions, no gradient, no state change),
    :meth:`update` (one training step of whatever the bonus learns, on a replay batch), :meth:`state_dict` and
    :meth:`load_state_dict`; they may implement :meth:`observe` (fold each fresh env transition into running
    statistics or a memory, once per env step, after its reward was used) and :meth:`imagine` (the bonus of imagined
    latent edges, for planners). ``__call__`` returns ``scale * compute(batch)``.
    """

    log_keys: tuple[str, ...] = ()  # every key update() and observe() may return (they become metrics.csv columns)
    needs_latents: bool = False  # compute() reads batch.z / batch.z_next, which the agent must fill in
    needs_model: ClassVar[bool] = False  # needs the agent's latent world model (IntrinsicContext.model)

    @classmethod
    def can_imagine(cls, options: Mapping[str, Any]) -> bool:
        """Whether a reward built with these config ``options`` will be :attr:`imaginable` (checked before a run)."""
        return False

    def __init__(self, scale: float = 1.0) -> None:
        self.scale = float(scale)

    @abc.abstractmethod
    def compute(self, batch: TransitionBatch) -> Tensor:
        """Raw bonus for each transition, shape (B,), computed without gradient.

        Must change no state (networks, optimisers, running statistics): a planner may call it many times per env
        step. Statistics move only in :meth:`update` or :meth:`observe`.
        """

    @abc.abstractmethod
    def update(self, batch: TransitionBatch) -> dict[str, float]:
        """One training update on ``batch``; returns logged scalars such as ``{"losses/icm_inverse": 1.09}``."""

    def observe(self, batch: TransitionBatch) -> dict[str, float]:
        """Fold freshly experienced transitions, in time order, into running statistics (default: none kept);
        returns logged scalars. Called once per env step, after the step's reward was computed."""
        return {}

    @property
    def imaginable(self) -> bool:
        """Whether :meth:`imagine` can score latent edges that have no observations (a planner's imagined steps)."""
        return False

    @property
    def ready(self) -> bool:
        """Whether :meth:`compute` can score transitions yet (e.g. a novelty memory is fitted after the warm-up)."""
        return True

    @property
    def stochastic(self) -> bool:
        """Whether :meth:`imagine` draws random numbers, so two evaluations of the same edges differ."""
        return False

    def imagine(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        """Bonus of imagined edges (z (N, d), a (N,) long, z_next (N, d)) -> (N,), without gradient or state change."""
        raise NotImplementedError(f"{type(self).__name__} scores observations, not imagined latent edges")

    def summary(self) -> dict[str, Any]:
        """Run-level facts for ``summary.json`` (default none)."""
        return {}

    def to(self, device: torch.device | str) -> IntrinsicReward:
        """Move networks and statistics to ``device`` in place; returns ``self`` (default: nothing to move)."""
        return self

    @abc.abstractmethod
    def state_dict(self) -> dict[str, Any]:
        """Everything needed to resume the reward exactly (networks, optimisers, running statistics, memory)."""

    @abc.abstractmethod
    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned."""

    def __call__(self, batch: TransitionBatch) -> Tensor:
        return self.scale * self.compute(batch)


def latents_of(batch: TransitionBatch, who: str) -> tuple[Tensor, Tensor]:
    """``(batch.z, batch.z_next)``, or a clear error naming the reward ``who`` when the agent left them out."""
    if batch.z is None or batch.z_next is None:
        raise ValueError(f"{who} scores latents: the batch must carry z and z_next (TransitionBatch.with_latents)")
    return batch.z, batch.z_next
