"""Gaussian-potential dispersion loss L_unif (paper §3.4.2; Wang & Isola's uniformity loss)."""

from __future__ import annotations

import math

import torch
from torch import Tensor

from curiosity.info.kernels import check_2d, out_dtype, sq_dists_self


def gaussian_potential(z: Tensor, *, t: float = 2.0) -> Tensor:
    """Log of the mean Gaussian potential over distinct pairs of a batch (natural log).

    L_unif(z) = log( (2 / (B(B−1))) Σ_{i<j} exp(−t ‖z_i − z_j‖²) ), computed as
    ``logsumexp_{i<j}(−t d_ij²) − log(B(B−1)/2)`` in float64 from squared distances (no sqrt, no underflow to −inf).
    Identical points give 0; it decreases as the batch spreads out.

    Args:
        z: (B, d) latent batch, B ≥ 2.
        t: temperature t > 0 (2 in NSRS).

    Returns:
        Scalar tensor in ``z``'s dtype, ≤ 0.
    """
    check_2d(z, "z")
    n = z.shape[0]
    if n < 2:
        raise ValueError(f"gaussian_potential needs at least 2 samples, got {n}")
    if not t > 0:
        raise ValueError(f"t must be > 0, got {t}")
    i, j = torch.triu_indices(n, n, offset=1, device=z.device)
    d2 = sq_dists_self(z)[i, j]
    n_pairs = n * (n - 1) / 2
    return (torch.logsumexp(-float(t) * d2, dim=0) - math.log(n_pairs)).to(out_dtype(z))
