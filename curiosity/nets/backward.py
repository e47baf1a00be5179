"""Stochastic backward predictor B_ξ(s_{t+1}, ε) (paper §3.5)."""

from __future__ import annotations

import torch
from torch import Tensor, nn

from curiosity.nets.encoders import tanh_mlp


class BackwardPredictor(nn.Module):
    """Maps a next latent and Gaussian noise to K candidate predecessor embeddings ŷ^(k) = B([s', ε^(k)]).

    Network: tanh MLP [d + noise_dim, hidden, hidden, d + A]; ε^(k) ~ N(0, I_noise_dim), drawn fresh on every call.

    Args:
        latent_dim: d.
        n_actions: A.
        n_candidates: K, samples per next latent.
        noise_dim: size of ε.
        hidden: hidden width.
    """

    def __init__(self, latent_dim: int, n_actions: int, n_candidates: int = 8, noise_dim: int = 4, hidden: int = 32) -> None:
        super().__init__()
        self.n_candidates = n_candidates
        self.noise_dim = noise_dim
        self.net = tanh_mlp([latent_dim + noise_dim, hidden, hidden, latent_dim + n_actions])

    def forward(self, z_next: Tensor, generator: torch.Generator | None = None) -> Tensor:
        """Sample candidate predecessors.

        Args:
            z_next: (B, d) next latents s_{t+1}.
            generator: optional RNG for ε (must live on ``z_next``'s device).

        Returns:
            (B, K, d + A) candidate embeddings ŷ = [ŝ_t, â_t].
        """
        b, d = z_next.shape
        eps = torch.randn(b, self.n_candidates, self.noise_dim, generator=generator, dtype=z_next.dtype, device=z_next.device)
        z = z_next.unsqueeze(1).expand(b, self.n_candidates, d)
        return self.net(torch.cat([z, eps], dim=-1))
