"""The ``entropy`` group: the representation regulariser that raises predictive information (paper §3.4–§3.6).

Each regulariser is called on one batch of consecutive latents and returns its weighted loss and logged scalars:

    loss, logs = regulariser(z, a_onehot, z_next)     # z, z_next: (B, d); a_onehot: (B, A)

``gaussian_potential``: coef · L_unif(z_next) (dispersion, a surrogate for raising H(s_{t+1})).
``renyi``: −coef · H_α(z_next) (matrix-based Rényi entropy of the next latents, §4.4).
``renyi_mi``: −coef · I_α(z_next; [z, a]) (matrix-based Rényi mutual information, §3.6).
``none``: 0.
"""

from __future__ import annotations

import torch
from torch import Tensor

from curiosity.info.kernels import gram_matrix
from curiosity.info.potential import gaussian_potential
from curiosity.info.renyi import renyi_entropy, renyi_mutual_information


def _mean_offdiag(x: Tensor, sigma: float, kernel: str) -> float:
    """Mean off-diagonal Gram entry: near 0 the kernel is too narrow (K -> I), near 1 too wide (K -> 11ᵀ)."""
    with torch.no_grad():
        k = gram_matrix(x.detach(), sigma=sigma, kernel=kernel)
        n = k.shape[0]
        return float((k.sum() - k.diagonal().sum()) / max(n * (n - 1), 1))


class GaussianPotentialRegulariser:
    """coef · log mean_{i<j} exp(−t‖z'_i − z'_j‖²) on the next latents (natural log)."""

    def __init__(self, coef: float = 1.0, t: float = 2.0) -> None:
        self.coef, self.t = float(coef), float(t)

    def __call__(self, z: Tensor, a_onehot: Tensor, z_next: Tensor) -> tuple[Tensor, dict[str, float]]:
        value = gaussian_potential(z_next, t=self.t)
        return self.coef * value, {"losses/entropy": value.item()}


class RenyiEntropyRegulariser:
    """−coef · H_α(z_next): matrix-based Rényi α-entropy of the next latents (in log base ``base``)."""

    def __init__(self, coef: float = 1.0, alpha: float = 0.99, sigma: float = 2.0, kernel: str = "gaussian",
                 base: float = 2.0) -> None:  # fmt: skip
        self.coef, self.alpha, self.sigma, self.kernel, self.base = float(coef), float(alpha), float(sigma), kernel, base

    def __call__(self, z: Tensor, a_onehot: Tensor, z_next: Tensor) -> tuple[Tensor, dict[str, float]]:
        h = renyi_entropy(z_next, sigma=self.sigma, alpha=self.alpha, kernel=self.kernel, base=self.base)
        logs = {"losses/entropy": -h.item(), "info/gram_offdiag": _mean_offdiag(z_next, self.sigma, self.kernel)}
        return -self.coef * h, logs


class RenyiMIRegulariser(RenyiEntropyRegulariser):
    """−coef · I_α(z_next; [z, a]): matrix-based Rényi mutual information between next latent and state–action."""

    def __call__(self, z: Tensor, a_onehot: Tensor, z_next: Tensor) -> tuple[Tensor, dict[str, float]]:
        y = torch.cat([z, a_onehot.to(z.dtype)], dim=1)
        mi = renyi_mutual_information(z_next, y, sigma=self.sigma, alpha=self.alpha, kernel=self.kernel, base=self.base)
        logs = {"losses/entropy": -mi.item(), "info/gram_offdiag": _mean_offdiag(z_next, self.sigma, self.kernel)}
        return -self.coef * mi, logs


class NoRegulariser:
    """No regulariser: a zero loss."""

    def __call__(self, z: Tensor, a_onehot: Tensor, z_next: Tensor) -> tuple[Tensor, dict[str, float]]:
        return z_next.new_zeros(()), {}


REGULARISER_LOG_KEYS = ("losses/entropy", "info/gram_offdiag")
