"""Where a planner's imagined futures come from: the learned latent model, or the real simulator (the oracle).

A rollout holds the nodes of one depth of a search tree and expands them: ``expand(parents, actions)`` steps node
``parents[j]`` with ``actions[j]`` and makes the results the new depth, whose latents ``latents()`` returns. The
planner never sees anything but latents, so the same planner, novelty and scores run on either source.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import torch
from torch import Tensor

from curiosity.envs.simulator import Simulator, SimStates

StepFn = Callable[[Tensor, Tensor], Tensor]
EncodeFn = Callable[[Tensor], Tensor]


class Rollout(Protocol):
    """The nodes of one depth of a search tree.

    ``hold`` (an optional attribute, 1 when absent): how many env steps one ``expand`` covers. ``advance(parents,
    actions)`` (an optional method): ``expand`` without computing the new latents, for steps whose latents nobody reads
    (the inner steps of a :class:`HeldRollout`).
    """

    def latents(self) -> Tensor:
        """(M, d) latents of the current depth's nodes."""
        ...

    def expand(self, parents: Tensor, actions: Tensor) -> Tensor:
        """Step nodes ``parents`` (K,) long with ``actions`` (K,) long; the K results become the current depth.

        Returns:
            (K, d) their latents.
        """
        ...


class LatentRollout:
    """Imagined futures from the learned transition: ẑ' = T(ẑ, a) (the caller puts the model in eval mode).

    Args:
        z0: (d,) the current latent.
        step_fn: T(z (M, d), a (M,) long) -> (M, d).
    """

    def __init__(self, z0: Tensor, step_fn: StepFn) -> None:
        self.z, self.step_fn = z0.unsqueeze(0), step_fn

    def latents(self) -> Tensor:
        return self.z

    def expand(self, parents: Tensor, actions: Tensor) -> Tensor:
        self.z = self.step_fn(self.z[parents], actions)
        return self.z


class SimulatorRollout:
    """True futures: the real simulator branched from the run's state, each observation encoded by the encoder.

    Args:
        simulator: a :class:`~curiosity.envs.simulator.Simulator` of the run's env.
        root: the branch point (one state).
        z0: (d,) the latent of the root's observation.
        encode: observations (M, *obs_shape) -> latents (M, d) (the caller puts the model in eval mode).
    """

    def __init__(self, simulator: Simulator, root: SimStates, z0: Tensor, encode: EncodeFn) -> None:
        self.simulator, self.states, self.encode = simulator, root, encode
        self.z = z0.unsqueeze(0)

    def latents(self) -> Tensor:
        return self.z

    def advance(self, parents: Tensor, actions: Tensor) -> None:
        """Step the simulator without encoding: :meth:`latents` is stale until the next :meth:`expand`."""
        self.states, _ = self.simulator.step(self.states.take(parents.cpu().numpy()), actions.cpu().numpy())

    def expand(self, parents: Tensor, actions: Tensor) -> Tensor:
        self.advance(parents, actions)
        self.z = self.encode(torch.as_tensor(self.states.obs, device=self.z.device))
        return self.z


class ReplayRollout:
    """Tree latents computed before (one (A^k, d) tensor per depth k = 1..H, prefixes in lexicographic order), replayed
    for a full enumeration, so that a tree expanded once can be scored again without stepping anything. ``hold``: the
    env steps one depth of ``levels`` covers (as the rollout that made them)."""

    def __init__(self, z0: Tensor, levels: list[Tensor], hold: int = 1) -> None:
        self.z, self.levels, self.depth, self.hold = z0.unsqueeze(0), levels, 0, hold

    def latents(self) -> Tensor:
        return self.z

    def expand(self, parents: Tensor, actions: Tensor) -> Tensor:
        self.z = self.levels[self.depth]
        assert len(parents) == len(self.z), "ReplayRollout replays the full enumeration only"
        self.depth += 1
        return self.z


class HeldRollout:
    """Each action held for ``hold`` env steps: one ``expand`` of this rollout is ``hold`` steps of ``inner`` with
    the same actions, so a depth of the planner's tree is ``hold`` steps of the model or the simulator. Only the last
    step's latents are computed where ``inner`` can step without them (``advance``: the simulator is not encoded at
    the inner steps).

    Args:
        inner: a rollout whose ``expand`` is one env step.
        hold: env steps per expand (>= 1).
    """

    def __init__(self, inner: Rollout, hold: int) -> None:
        if hold < 1:
            raise ValueError(f"hold must be >= 1, got {hold}")
        if getattr(inner, "hold", 1) != 1:
            raise ValueError(f"HeldRollout wraps a one-step rollout, got one holding {inner.hold} steps")  # type: ignore[attr-defined]
        self.inner, self.hold = inner, int(hold)

    def latents(self) -> Tensor:
        return self.inner.latents()

    def expand(self, parents: Tensor, actions: Tensor) -> Tensor:
        step = getattr(self.inner, "advance", self.inner.expand)
        same = torch.arange(len(actions), device=parents.device)
        for i in range(self.hold - 1):
            step(parents if i == 0 else same, actions)
        return self.inner.expand(parents if self.hold == 1 else same, actions)


def held(rollout: Rollout, hold: int) -> Rollout:
    """``rollout`` with each expand covering ``hold`` env steps: itself when it already does, else a
    :class:`HeldRollout` around it."""
    return rollout if getattr(rollout, "hold", 1) == hold else HeldRollout(rollout, hold)
