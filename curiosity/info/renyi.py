"""Matrix-based Rényi α-entropy, joint entropy and mutual information (Sánchez Giraldo et al.; paper §3.6).

For n samples with Gram matrix K, A = K / tr(K) has eigenvalues λ_i ≥ 0 with Σ λ_i = 1 and

    H_α(A) = log_b(Σ_i λ_i^α) / (1 − α),        H_1(A) = −Σ_i λ_i log_b λ_i  (von Neumann, |α − 1| < 1e-6).

Numerics: Gram matrices and ``torch.linalg.eigvalsh`` run in float64 and the result is cast back to the input dtype.
Only eigenvalues are used (never A^α through eigenvectors), so the backward pass is V diag(∂H/∂λ) Vᵀ, which does not
divide by eigenvalue gaps and stays finite for repeated eigenvalues. Eigenvalues are clamped at ``EIG_FLOOR`` before
any fractional power or log, and eigenvalues at or below the floor (zeros up to round-off) contribute exactly 0.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor

from curiosity.info.kernels import check_2d, gram_matrix, out_dtype

EIG_FLOOR = 1e-12
VON_NEUMANN_TOL = 1e-6


def _check_alpha_base(alpha: float, base: float) -> None:
    if not alpha > 0:
        raise ValueError(f"alpha must be > 0, got {alpha}")
    if not (base > 0 and base != 1):
        raise ValueError(f"base must be > 0 and != 1, got {base}")


def _spectral_entropy(a64: Tensor, alpha: float, base: float) -> Tensor:
    """H_α of a float64 unit-trace PSD matrix (n, n) -> float64 scalar, in units of log base ``base``."""
    lam = torch.linalg.eigvalsh(a64)
    kept = lam > EIG_FLOOR
    lam_c = lam.clamp_min(EIG_FLOOR)
    if abs(alpha - 1.0) < VON_NEUMANN_TOL:
        h = -torch.where(kept, lam_c * lam_c.log(), torch.zeros_like(lam_c)).sum()
    else:
        h = torch.where(kept, lam_c.pow(alpha), torch.zeros_like(lam_c)).sum().log() / (1.0 - alpha)
    return h / math.log(base)


def matrix_renyi_entropy(a: Tensor, *, alpha: float, base: float = 2.0) -> Tensor:
    """Rényi α-entropy of the spectrum of a given PSD matrix, normalised to unit trace.

    H_α(A) = log_b(Σ_i λ_i^α) / (1 − α) with λ the eigenvalues of A / tr(A); von Neumann −Σ λ_i log_b λ_i when
    |α − 1| < 1e-6. Eigenvalues are computed in float64 and clamped at 1e-12; those at or below it contribute 0.

    Args:
        a: (n, n) symmetric positive semi-definite matrix (e.g. a Gram matrix or A itself).
        alpha: order α > 0.
        base: logarithm base (2 gives bits, e gives nats).

    Returns:
        Scalar tensor in ``a``'s floating dtype.
    """
    if a.dim() != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"a must be a square (n, n) matrix, got {tuple(a.shape)}")
    _check_alpha_base(alpha, base)
    a64 = a.to(torch.float64)
    return _spectral_entropy(a64 / torch.trace(a64), alpha, base).to(out_dtype(a))


def renyi_entropy(x: Tensor, *, sigma: float, alpha: float, kernel: str = "gaussian", base: float = 2.0) -> Tensor:
    """Matrix-based Rényi α-entropy of the n samples in ``x``.

    K_ij = κ(x_i, x_j) (``kernel="gaussian"``: exp(−‖x_i − x_j‖²/(2σ²)); ``"yu"``: exp(−‖x_i − x_j‖²/σ)),
    A = K / tr(K), H_α(A) = log_b(Σ_i λ_i(A)^α) / (1 − α); α within 1e-6 of 1 gives −Σ λ_i log_b λ_i.
    0 ≤ H_α ≤ log_b n, non-increasing in α.

    Args:
        x: (n, d) samples (one batch).
        sigma: kernel width σ > 0.
        alpha: order α > 0.
        kernel: ``"gaussian"`` or ``"yu"``.
        base: logarithm base (2 = bits, as in the precursor code).

    Returns:
        Scalar tensor in ``x``'s dtype, differentiable with respect to ``x``.
    """
    _check_alpha_base(alpha, base)
    k = gram_matrix(x, sigma=sigma, kernel=kernel)
    return _spectral_entropy(k / torch.trace(k), alpha, base).to(out_dtype(x))


def _joint_gram(xs: tuple[Tensor, ...], sigma: float, kernel: str) -> Tensor:
    if not xs:
        raise ValueError("renyi_joint_entropy needs at least one sample set")
    for i, x in enumerate(xs):
        check_2d(x, f"xs[{i}]")
        if x.shape[0] != xs[0].shape[0]:
            raise ValueError(f"all sample sets need the same n, got {[int(x.shape[0]) for x in xs]}")
    k = gram_matrix(xs[0], sigma=sigma, kernel=kernel)
    for x in xs[1:]:
        k = k * gram_matrix(x, sigma=sigma, kernel=kernel)
    return k


def renyi_joint_entropy(*xs: Tensor, sigma: float, alpha: float, kernel: str = "gaussian", base: float = 2.0) -> Tensor:
    """Matrix-based joint Rényi α-entropy of several paired sample sets.

    C = (A_1 ∘ A_2 ∘ … ∘ A_m) / tr(A_1 ∘ … ∘ A_m) with A_k = K_k / tr(K_k) (∘ = Hadamard product),
    H_α(x_1, …, x_m) = H_α(C). With one shared σ (either kernel) this equals ``renyi_entropy`` of the
    concatenation [x_1, …, x_m].

    Args:
        *xs: m ≥ 1 tensors (n, d_k), row i of each belonging to the same sample.
        sigma: kernel width σ > 0, shared by all sets.
        alpha: order α > 0.
        kernel: ``"gaussian"`` or ``"yu"``.
        base: logarithm base.

    Returns:
        Scalar tensor in the promoted dtype of ``xs``.
    """
    _check_alpha_base(alpha, base)
    k = _joint_gram(xs, sigma, kernel)
    return _spectral_entropy(k / torch.trace(k), alpha, base).to(out_dtype(*xs))


def renyi_mutual_information(
    x: Tensor, y: Tensor, *, sigma: float, alpha: float, kernel: str = "gaussian", base: float = 2.0
) -> Tensor:
    """Matrix-based Rényi α mutual information I_α(x; y) = H_α(A) + H_α(B) − H_α(A ∘ B / tr(A ∘ B)).

    A and B are the unit-trace Gram matrices of x and y. Symmetric in (x, y); I(x; constant) = 0. For α ≠ 1 it can
    be slightly negative (Rényi entropy is not subadditive).

    Args:
        x: (n, d_x) samples.
        y: (n, d_y) samples paired row by row with ``x``.
        sigma: kernel width σ > 0 for both Gram matrices.
        alpha: order α > 0.
        kernel: ``"gaussian"`` or ``"yu"``.
        base: logarithm base.

    Returns:
        Scalar tensor in the promoted dtype of ``x`` and ``y``.
    """
    _check_alpha_base(alpha, base)
    check_2d(x, "x")
    check_2d(y, "y")
    if x.shape[0] != y.shape[0]:
        raise ValueError(f"x and y need the same n, got {x.shape[0]} and {y.shape[0]}")
    kx = gram_matrix(x, sigma=sigma, kernel=kernel)
    ky = gram_matrix(y, sigma=sigma, kernel=kernel)
    kxy = kx * ky
    h = sum(_spectral_entropy(k / torch.trace(k), alpha, base) for k in (kx, ky))
    return (h - _spectral_entropy(kxy / torch.trace(kxy), alpha, base)).to(out_dtype(x, y))
