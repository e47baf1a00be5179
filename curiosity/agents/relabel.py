"""Intrinsic rewards of Q targets as NSRS's code keeps them (``agent.q_intrinsic=relabel``, docs/protocol.md §3.4, §4).

NSRS does not score a sampled batch when it builds Q targets: after every training call it recomputes the intrinsic
reward of every transition in its buffer, with the encoder and memory of that moment, and stores it; a transition added
since carries 0 until the next recomputation. The default (``batch``) scores each sampled batch with the current memory.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import torch
from torch import Tensor

from curiosity.intrinsic.base import IntrinsicReward
from curiosity.replay import ReplayBuffer

CHUNK = 512  # transitions encoded and scored at a time


class RelabelledRewards:
    """r_int of every stored transition as of the last :meth:`relabel`, looked up by global replay index."""

    def __init__(self) -> None:
        self.first = 0  # global index of values[0]
        self.values = torch.zeros(0, device="cpu")

    @torch.no_grad()
    def relabel(self, replay: ReplayBuffer, encode: Callable[[Tensor], Tensor], reward: IntrinsicReward,
                device: torch.device | str, encoded: tuple[np.ndarray, Tensor] | None = None) -> None:  # fmt: skip
        """Score every stored transition with ``reward`` on latents from ``encode`` ((B, *obs) -> (B, d), eval mode).

        Each stored observation is encoded once: a transition's o_{t+1} that is the next transition's o_t reuses that
        latent (:meth:`ReplayBuffer.follows`); only the others (episode ends, the newest) are encoded apart.
        ``encoded``: (keys (M,), latents (M, d)) of o_t already encoded by the same encoder (a memory refresh), reused
        when they are every stored transition's, oldest first.
        """
        n = len(replay)
        first = replay.total_added - n
        if encoded is not None and np.array_equal(encoded[0], np.arange(first, first + n)):
            z = encoded[1]
        else:
            z = torch.cat([encode(replay.all_obs(s, s + CHUNK).to(device)) for s in range(0, n, CHUNK)])
        follows = torch.from_numpy(replay.follows()).to(z.device)
        values = []
        for s in range(0, n, CHUNK):
            index = np.arange(first + s, first + min(n, s + CHUNK))
            batch = replay.transitions_at(index).to(device)
            rows = torch.arange(s, s + len(index), device=z.device)
            z_next = torch.where(follows[rows, None], z[(rows + 1).clamp_max(n - 1)], z[rows])
            alone = (~follows[rows]).nonzero().flatten()
            if len(alone):
                z_next[alone] = encode(batch.next_obs[alone])
            values.append(reward.compute(batch.with_latents(z[rows], z_next)).float().cpu())
        self.first, self.values = first, torch.cat(values) if values else torch.zeros(0, device="cpu")

    def lookup(self, index: Tensor) -> Tensor:
        """(B,) global indices -> (B,) stored rewards on the host; 0 for a transition added since the last relabel."""
        pos = index.to("cpu").long() - self.first
        known = (pos >= 0) & (pos < len(self.values))
        out = torch.zeros(len(index), device="cpu")
        out[known] = self.values[pos[known]]
        return out

    def state_dict(self) -> dict[str, Any]:
        return {"first": self.first, "values": self.values.clone()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.first, self.values = int(state["first"]), state["values"].clone()
