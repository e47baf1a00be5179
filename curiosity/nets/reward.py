"""Reward model R_ω(y), y = [s, onehot a] (paper §3.7)."""

from __future__ import annotations

from collections.abc import Sequence

from torch import Tensor, nn

from curiosity.nets.encoders import tanh_mlp


class RewardModel(nn.Module):
    """tanh MLP [d + A, *hidden, 1] (paper widths [10, 50, 20, 1]) predicting the extrinsic reward of y = [s, a].

    Args:
        latent_dim: d.
        n_actions: A.
        hidden: hidden widths.
    """

    def __init__(self, latent_dim: int, n_actions: int, hidden: Sequence[int] = (10, 50, 20)) -> None:
        super().__init__()
        self.net = tanh_mlp([latent_dim + n_actions, *hidden, 1])

    def forward(self, y: Tensor) -> Tensor:
        """Predict rewards.

        Args:
            y: (B, d + A) state-action embeddings [s, onehot a].

        Returns:
            (B,) predicted rewards r̂ = R(y).
        """
        return self.net(y).squeeze(-1)
