"""Exhaustive novelty + Q tree search of NSRS (docs/protocol.md §5), with the subtree bookkeeping done right."""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar

import torch
from torch import Tensor

from curiosity.planning.protocols import Plan, PlanRequest, QFn
from curiosity.planning.rollout import StepFn

EdgeRewardFn = Callable[[Tensor, Tensor, Tensor], Tensor]


class QTreePlanner:
    """Depth-D tree over all A^D action sequences with novelty rewards on predicted states and Q at the leaves.

        V(a_0) = n(ẑ_1) + γ max_{a_1} [ n(ẑ_2) + γ max_{a_2} [ … n(ẑ_D) + γ max_{a_D} Q(ẑ_D, a_D) ] ],
        ẑ_0 = z0,  ẑ_{k+1} = T(ẑ_k, a_k).

    D novelty terms (NSRS: on ẑ_1 .. ẑ_D, the states reached; the intrinsic function sees each edge (ẑ_k, a_k, ẑ_{k+1}),
    so it may score state–action pairs instead) and one Q term at the deepest state. Level k holds A^k
    states in state-major order: the child of node j under action a is row j·A + a, so backing up is
    ``v.reshape(A^(k-1), A).max(1)``. (NSRS's released code builds levels action-major and reshapes state-major,
    which mixes subtrees at depth ≥ 2.)

    Args:
        horizon: the tree depth D ≥ 1 (the ``planner.horizon`` key, shared with MPC).
        gamma: discount γ.
        n_actions: A.
    """

    scores_candidates: ClassVar[bool] = False  # scores an explicit candidate set (candidates(), scores())
    needs_q: ClassVar[bool] = True  # Q at the leaves: the agent trains one and passes it as ``PlanRequest.q_fn``
    commit = 1  # actions executed per search: the tree's value is for the first action only

    def __init__(self, horizon: int = 5, gamma: float = 0.8, n_actions: int = 3) -> None:
        if horizon < 1:
            raise ValueError("horizon (the tree depth) must be >= 1")
        self.depth = self.horizon = horizon
        self.gamma = gamma
        self.n_actions = n_actions

    @property
    def step_discount(self) -> float:
        """The discount per env step of the Q at the leaves: γ (each depth is one env step)."""
        return float(self.gamma)

    def expand(self, z: Tensor, step_fn: StepFn) -> Tensor:
        """All children of a level, state-major.

        Args:
            z: (N, d) latents of one level.
            step_fn: T(z (M, d), a (M,) long) -> (M, d).

        Returns:
            (N·A, d); row j·A + a is T(z_j, a).
        """
        actions = torch.arange(self.n_actions, device=z.device).repeat(z.shape[0])
        return step_fn(z.repeat_interleave(self.n_actions, dim=0), actions)

    def values(self, z0: Tensor, step_fn: StepFn, intrinsic_fn: EdgeRewardFn, q_fn: QFn) -> Tensor:
        """Root action values V(a_0).

        Args:
            z0: (d,) current latent.
            step_fn: T(z (M, d), a (M,) long) -> (M, d), in eval mode.
            intrinsic_fn: the reward of each edge, r(z (M, d), a (M,) long, z_next (M, d)) -> (M,); NSRS uses the
                novelty of the reached state, ``lambda z, a, z_next: n(z_next)``.
            q_fn: Q(z (M, d)) -> (M, A).

        Returns:
            (A,) V(a_0) for every first action.
        """
        with torch.no_grad():
            z = z0.unsqueeze(0)
            novelty = []
            for _ in range(self.depth):
                parents = z.repeat_interleave(self.n_actions, dim=0)
                actions = torch.arange(self.n_actions, device=z.device).repeat(z.shape[0])
                z = step_fn(parents, actions)
                novelty.append(intrinsic_fn(parents, actions, z))
            value = novelty[-1] + self.gamma * q_fn(z).max(dim=1).values
            for level in reversed(novelty[:-1]):
                value = level + self.gamma * value.reshape(-1, self.n_actions).max(dim=1).values
        return value

    def plan(self, request: PlanRequest) -> Plan:
        """Greedy root action argmax_a V(a) (ties to the lowest index) at ``request.z0``.

        Reads ``z0``, ``step_fn``, ``intrinsic`` (one tensor per edge) and ``q_fn`` (required).

        Returns:
            the action (a one-action sequence), its value V(a), and info key ``value_gap`` (best minus runner-up; 0
            with one action).
        """
        if request.q_fn is None:
            raise ValueError("the Q-tree planner needs a Q-function (PlanRequest.q_fn)")
        intrinsic = request.intrinsic

        def edge(z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
            out = intrinsic(z, a, z_next)
            return out if isinstance(out, Tensor) else torch.stack(list(out.values())).sum(0)

        value = self.values(request.z0, request.step_fn, edge, request.q_fn)
        top = torch.topk(value, min(2, value.numel())).values
        gap = float(top[0] - top[1]) if top.numel() > 1 else 0.0
        return Plan([int(torch.argmax(value))], float(top[0]), {"value_gap": gap})
