"""A common yardstick of latent spread, logged for every run whatever its entropy regulariser (Figure 6 analogue).

The losses of different regularisers (Gaussian potential, matrix-based Rényi entropy or MI) are not on one scale, so
each run also logs ``info/latent_logdet``: the log-determinant of the covariance of a batch of next latents, plus a
small ridge, computed the same way for every run. It is, up to the constant d/2·log(2πe) and a factor 1/2, the entropy
of a Gaussian fitted to the batch (nats).
"""

from __future__ import annotations

import torch
from torch import Tensor


def latent_logdet(z: Tensor, ridge: float = 1e-3) -> float:
    """log det(Cov(z) + ridge·I) of a batch of latents z (B, d), B ≥ 2; covariance with ddof = 1, in float64."""
    if z.ndim != 2 or z.shape[0] < 2:
        raise ValueError(f"latent_logdet: needs a (B, d) batch with B >= 2, got shape {tuple(z.shape)}")
    x = z.detach().to(torch.float64)
    cov = torch.cov(x.T).reshape(x.shape[1], x.shape[1])  # (d, d); torch.cov returns a scalar when d = 1
    sign, logdet = torch.linalg.slogdet(cov + ridge * torch.eye(x.shape[1], dtype=torch.float64, device=x.device))
    return float(logdet) if float(sign) > 0 else float("-inf")
