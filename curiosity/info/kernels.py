"""Shared numerics: input checks, squared distances and Gram matrices (float64 inside)."""

from __future__ import annotations

import torch
from torch import Tensor

KERNELS = ("gaussian", "yu")


def check_2d(x: Tensor, name: str) -> None:
    """Raise ``ValueError`` unless ``x`` is a 2-D tensor (n, d) with n >= 1 and d >= 1."""
    if not isinstance(x, Tensor) or x.dim() != 2 or x.shape[0] < 1 or x.shape[1] < 1:
        shape = tuple(x.shape) if isinstance(x, Tensor) else type(x).__name__
        raise ValueError(f"{name} must be a 2-D tensor (n, d) with n, d >= 1, got {shape}")


def out_dtype(*xs: Tensor) -> torch.dtype:
    """The floating dtype results are cast back to: the promoted input dtype, or torch's default for integers."""
    dtype = xs[0].dtype
    for x in xs[1:]:
        dtype = torch.promote_types(dtype, x.dtype)
    return dtype if dtype.is_floating_point else torch.get_default_dtype()


def sq_dists_self(x: Tensor) -> Tensor:
    """Pairwise squared Euclidean distances D_ij = ||x_i - x_j||^2 of x (n, d), in float64 -> (n, n).

    Uses explicit differences (exact zeros on the diagonal and for duplicated rows, smooth gradient, no sqrt).
    """
    x64 = x.to(torch.float64)
    diff = x64.unsqueeze(1) - x64.unsqueeze(0)
    return diff.pow(2).sum(-1)


def gram_matrix(x: Tensor, *, sigma: float, kernel: str = "gaussian") -> Tensor:
    """Kernel Gram matrix of the rows of ``x``, computed in float64.

    Args:
        x: (n, d) samples.
        sigma: kernel width, > 0.
        kernel: ``"gaussian"``: K_ij = exp(-||x_i - x_j||^2 / (2 sigma^2));
            ``"yu"``: K_ij = exp(-||x_i - x_j||^2 / sigma) (the precursor code's convention).

    Returns:
        (n, n) float64 symmetric Gram matrix with unit diagonal.
    """
    check_2d(x, "x")
    if not sigma > 0:
        raise ValueError(f"sigma must be > 0, got {sigma}")
    if kernel == "gaussian":
        scale = 2.0 * float(sigma) ** 2
    elif kernel == "yu":
        scale = float(sigma)
    else:
        raise ValueError(f"kernel must be one of {KERNELS}, got {kernel!r}")
    return torch.exp(-sq_dists_self(x) / scale)
