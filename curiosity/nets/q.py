"""Latent Q-network (NSRS ``LowDimQFunction``, docs/protocol.md §3.2)."""

from __future__ import annotations

import itertools
from collections.abc import Sequence

from torch import Tensor, nn


class QNetwork(nn.Module):
    """ReLU MLP [d, *hidden, A] (NSRS: 4 → 20 → 50 → 20 → 3).

    Args:
        latent_dim: d.
        n_actions: A.
        hidden: hidden widths.
    """

    def __init__(self, latent_dim: int, n_actions: int, hidden: Sequence[int] = (20, 50, 20)) -> None:
        super().__init__()
        sizes = [latent_dim, *hidden]
        layers: list[nn.Module] = []
        for fan_in, fan_out in itertools.pairwise(sizes):
            layers += [nn.Linear(fan_in, fan_out), nn.ReLU()]
        layers.append(nn.Linear(sizes[-1], n_actions))
        self.net = nn.Sequential(*layers)

    def forward(self, z: Tensor) -> Tensor:
        """Action values.

        Args:
            z: (B, d) latents.

        Returns:
            (B, A) Q(z, ·).
        """
        return self.net(z)
