"""Residual latent transition model T_ψ([s, a]) (docs/method.md §2)."""

from __future__ import annotations

import torch
from torch import Tensor, nn

from curiosity.nets.encoders import tanh_mlp


class ResidualTransition(nn.Module):
    """ŝ' = s + f([s, onehot a]) with f = Linear(d+A, h) → 30 → 30 → h → d, tanh and dropout after each hidden layer.

    Dropout is active only in train mode; call ``.eval()`` for planning and reward evaluation.

    Args:
        latent_dim: d.
        n_actions: A.
        hidden: h, the outer hidden width (10 in NSRS and the paper).
        dropout: dropout probability (paper 0.5, NSRS code 0.1).
    """

    def __init__(self, latent_dim: int, n_actions: int, hidden: int = 10, dropout: float = 0.5) -> None:
        super().__init__()
        self.latent_dim = latent_dim
        self.n_actions = n_actions
        self.net = tanh_mlp([latent_dim + n_actions, hidden, 30, 30, hidden, latent_dim], dropout=dropout)

    @property
    def members(self) -> list[nn.Module]:
        """The models trained on their own losses: this one."""
        return [self]

    def forward(self, z: Tensor, a_onehot: Tensor) -> Tensor:
        """Predict the next latent.

        Args:
            z: (B, d) latents.
            a_onehot: (B, A) one-hot actions.

        Returns:
            (B, d) predicted next latents z + f([z, a]).
        """
        return z + self.net(torch.cat([z, a_onehot], dim=-1))


class TransitionEnsemble(nn.Module):
    """K independently initialised residual transitions (a deep ensemble, paper ref. [24]); predicts their mean.

    Each member is trained on its own transition loss (``members``); the spread of their predictions,
    ``WorldModel.ensemble_disagreement``, is a deterministic estimate of the model's error at (s, a) that needs no
    dropout.

    Args:
        latent_dim: d.
        n_actions: A.
        size: K ≥ 2.
        hidden: h of every member.
        dropout: dropout of every member.
    """

    def __init__(self, latent_dim: int, n_actions: int, size: int = 5, hidden: int = 10, dropout: float = 0.0) -> None:
        super().__init__()
        if size < 2:
            raise ValueError(f"an ensemble needs size >= 2, got {size}")
        self.latent_dim, self.n_actions = latent_dim, n_actions
        self.nets = nn.ModuleList(ResidualTransition(latent_dim, n_actions, hidden, dropout) for _ in range(size))

    @property
    def members(self) -> list[nn.Module]:
        return list(self.nets)

    def predictions(self, z: Tensor, a_onehot: Tensor) -> Tensor:
        """Every member's prediction: (B, d), (B, A) -> (K, B, d)."""
        return torch.stack([net(z, a_onehot) for net in self.nets])

    def forward(self, z: Tensor, a_onehot: Tensor) -> Tensor:
        """The members' mean prediction: (B, d), (B, A) -> (B, d)."""
        return self.predictions(z, a_onehot).mean(0)
