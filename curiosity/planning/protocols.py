"""The one interface of a planner: ``plan(request) -> Plan``, with what it needs declared, not probed.

A :class:`PlanRequest` carries everything any planner may use (the latent, the transition, the intrinsic reward of
imagined edges, the extrinsic reward model, a Q-function, a random generator, where the futures come from); a planner
reads what it needs. A planner that needs a Q-function says so with ``needs_q``, so the agent trains one.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import ClassVar, Protocol, runtime_checkable

import torch
from torch import Tensor

from curiosity.planning.rollout import Rollout, StepFn

ScoreFn = Callable[[Tensor, Tensor], Tensor]
IntrinsicFn = Callable[[Tensor, Tensor, Tensor], Tensor | Mapping[str, Tensor]]
QFn = Callable[[Tensor], Tensor]


@dataclass
class PlanRequest:
    """What a planner may use to choose an action at latent ``z0``.

    Attributes:
        z0: (d,) the current latent.
        step_fn: T(z (M, d), a (M,) long) -> (M, d), the learned transition (eval mode).
        intrinsic: r_int(z (M, d), a (M,) long, z_next (M, d)) -> (M,), or a mapping of named terms (M,) each.
        reward_fn: R(z (M, d), a (M,) long) -> (M,) extrinsic reward model, or None (zero).
        q_fn: Q(z (M, d)) -> (M, A), for planners with ``needs_q``; else None.
        generator: the CPU random generator of sampling planners.
        rollout: where imagined futures come from (default: the learned model through ``step_fn``).
    """

    z0: Tensor
    step_fn: StepFn
    intrinsic: IntrinsicFn
    reward_fn: ScoreFn | None = None
    q_fn: QFn | None = None
    generator: torch.Generator | None = None
    rollout: Rollout | None = None


@dataclass
class Plan:
    """A planner's choice.

    Attributes:
        sequence: the chosen actions, first to execute first (one action for planners that value only the first).
        score: the chosen sequence's (or first action's) value, as the planner scores it.
        info: further scalars to log (``planner/<key>``), e.g. ``entropy``, ``spread/<term>``, ``p_first/<a>``.
    """

    sequence: list[int]
    score: float
    info: dict[str, float] = field(default_factory=dict)

    @property
    def action(self) -> int:
        """The action to execute now."""
        return self.sequence[0]


@runtime_checkable
class Planner(Protocol):
    """Chooses actions by searching imagined futures of the latent model."""

    needs_q: bool  # whether the agent must train a Q-function and pass it as ``PlanRequest.q_fn``
    # whether it scores an explicit set of candidate sequences (``candidates()``, ``scores(...)``), which the agent's
    # diagnostics (score noise, the model probe) re-score
    scores_candidates: ClassVar[bool]
    horizon: int  # how many steps ahead it looks
    commit: int  # how many actions of a plan the agent executes before planning again (1 <= commit <= len(sequence))
    step_discount: float  # the discount per env step of the Q-function a planner with ``needs_q`` reads

    def plan(self, request: PlanRequest) -> Plan:
        """Choose a sequence of actions at ``request.z0``."""
        ...
