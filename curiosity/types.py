"""Typed batches shared by losses, intrinsic rewards and agents."""

from __future__ import annotations

from dataclasses import dataclass, replace

import torch
from torch import Tensor


@dataclass
class TransitionBatch:
    """One-step transitions.

    Attributes:
        obs: (B, *obs_shape) float observations o_t.
        act: (B,) long action indices a_t.
        next_obs: (B, *obs_shape) float observations o_{t+1}.
        rewards: (B,) float extrinsic rewards r_t.
        terminateds: (B,) float in {0, 1}; 1 where o_{t+1} is terminal.
        z: (B, d) latents of o_t from the agent's encoder, or None (intrinsic rewards on latents read them).
        z_next: (B, d) latents of o_{t+1}, or None.
        index: (B,) long global transition indices in the replay (the env step of each), or None.
    """

    obs: Tensor
    act: Tensor
    next_obs: Tensor
    rewards: Tensor
    terminateds: Tensor
    z: Tensor | None = None
    z_next: Tensor | None = None
    index: Tensor | None = None

    def __len__(self) -> int:
        return int(self.act.shape[0])

    def to(self, device: torch.device | str) -> TransitionBatch:
        """The same transitions on ``device`` (indices stay on the host)."""
        moved = {k: None if v is None else v.to(device)
                 for k, v in (("obs", self.obs), ("act", self.act), ("next_obs", self.next_obs), ("rewards", self.rewards),
                              ("terminateds", self.terminateds), ("z", self.z), ("z_next", self.z_next))}  # fmt: skip
        return TransitionBatch(**moved, index=self.index)

    def with_latents(self, z: Tensor, z_next: Tensor) -> TransitionBatch:
        """The same transitions carrying latents z (B, d) of o_t and z_next (B, d) of o_{t+1}."""
        return replace(self, z=z, z_next=z_next)


@dataclass
class SegmentBatch:
    """n-step trajectory segments that never cross a terminal transition's successor.

    Attributes:
        obs: (B, n + 1, *obs_shape) observations o_t .. o_{t+n}.
        act: (B, n) long actions a_t .. a_{t+n-1}.
        rewards: (B, n) float rewards r_t .. r_{t+n-1}.
        terminateds: (B, n) float in {0, 1}; d_{t+i} = 1 where o_{t+i+1} is terminal.
        index: (B,) long global replay index of each segment's first transition, or None.
    """

    obs: Tensor
    act: Tensor
    rewards: Tensor
    terminateds: Tensor
    index: Tensor | None = None

    def __len__(self) -> int:
        return int(self.act.shape[0])

    @property
    def horizon(self) -> int:
        """n, the number of transitions per segment."""
        return int(self.act.shape[1])

    def to(self, device: torch.device | str) -> SegmentBatch:
        """The same segments on ``device`` (no copy when already there; indices stay on the host)."""
        return SegmentBatch(*(t.to(device) for t in (self.obs, self.act, self.rewards, self.terminateds)), index=self.index)

    def first_step(self) -> TransitionBatch:
        """The first transition of every segment as a :class:`TransitionBatch`."""
        return TransitionBatch(self.obs[:, 0], self.act[:, 0], self.obs[:, 1], self.rewards[:, 0], self.terminateds[:, 0],
                               index=self.index)  # fmt: skip
