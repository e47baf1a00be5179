"""Negative log-likelihood of the backward stochastic predictor (paper §3.5)."""

from __future__ import annotations

import math

import torch
from torch import Tensor

from curiosity.info.kernels import check_2d, out_dtype


def backward_predictor_nll(y: Tensor, candidates: Tensor, *, sigma_b: float) -> Tensor:
    """Per-sample NLL of the true predecessor under a kernel mixture of K sampled candidates.

    L_b = −log( (1/K) Σ_k exp(−‖y_b − ŷ_b^(k)‖² / (2 σ_b²)) ), computed as ``−(logsumexp_k(−x_k) − log K)`` in float64.
    (The Gaussian normaliser is omitted, as in the paper, so L ≥ 0 with equality when every candidate equals y.)

    Args:
        y: (B, d) true predecessor embeddings y_t = [s_t, a_t].
        candidates: (B, K, d) candidates ŷ^(k) = B_ξ(s_{t+1}, ε^(k)).
        sigma_b: kernel width σ_b > 0.

    Returns:
        (B,) tensor in the promoted dtype of the inputs; average it (with a terminal mask) for the loss.
    """
    check_2d(y, "y")
    if candidates.dim() != 3 or candidates.shape[0] != y.shape[0] or candidates.shape[2] != y.shape[1]:
        raise ValueError(f"candidates must be (B, K, d) = ({y.shape[0]}, K, {y.shape[1]}), got {tuple(candidates.shape)}")
    if candidates.shape[1] < 1:
        raise ValueError("candidates needs K >= 1")
    if not sigma_b > 0:
        raise ValueError(f"sigma_b must be > 0, got {sigma_b}")
    diff = candidates.to(torch.float64) - y.to(torch.float64).unsqueeze(1)
    x = diff.pow(2).sum(-1) / (2.0 * float(sigma_b) ** 2)
    nll = -(torch.logsumexp(-x, dim=1) - math.log(candidates.shape[1]))
    return nll.to(out_dtype(y, candidates))
