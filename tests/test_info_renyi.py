"""Matrix-based Rényi entropy / MI: exact oracle values of docs/method.md §8, properties, gradients and numerics."""

from __future__ import annotations

import itertools
import math

import pytest
import torch

from curiosity.info import (
    gram_matrix,
    matrix_renyi_entropy,
    renyi_entropy,
    renyi_joint_entropy,
    renyi_mutual_information,
)

ALPHAS = [0.5, 0.99, 1.0, 1.01, 2.0]
F64 = torch.float64


@pytest.fixture
def xy() -> tuple[torch.Tensor, torch.Tensor]:
    x = torch.tensor([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [3.0, 3.0]], dtype=F64)
    y = torch.tensor([[0.0], [1.0], [1.0], [-2.0]], dtype=F64)
    return x, y


def _rand(n: int, d: int, seed: int = 0, dtype: torch.dtype = F64) -> torch.Tensor:
    return torch.randn(n, d, generator=torch.Generator().manual_seed(seed), dtype=dtype)


def _rotation(theta: float) -> torch.Tensor:
    c, s = math.cos(theta), math.sin(theta)
    return torch.tensor([[c, -s], [s, c]], dtype=F64)


# --- exact oracle values (docs/method.md §8: Gaussian kernel, σ = 2, bits) ---


def test_spectrum_oracle(xy):
    k = gram_matrix(xy[0], sigma=2.0)
    lam = torch.linalg.eigvalsh(k / torch.trace(k))
    expected = torch.tensor([0.0187114566, 0.0552998042, 0.2399888256, 0.6859999135], dtype=F64)
    torch.testing.assert_close(lam, expected, atol=1e-10, rtol=0)


@pytest.mark.parametrize(
    ("alpha", "expected"), [(0.99, 1.2101834673), (1.0, 1.2054859555), (1.01, 1.2008388159), (2.0, 0.9115905054)]
)
def test_entropy_oracle(xy, alpha, expected):
    assert renyi_entropy(xy[0], sigma=2.0, alpha=alpha).item() == pytest.approx(expected, abs=1e-9)


def test_h2_is_minus_log2_sum_of_squares(xy):
    k = gram_matrix(xy[0], sigma=2.0)
    a = k / torch.trace(k)
    assert renyi_entropy(xy[0], sigma=2.0, alpha=2.0).item() == pytest.approx(-math.log2(a.pow(2).sum().item()), abs=1e-12)


def test_mutual_information_oracle(xy):
    mi = renyi_mutual_information(xy[0], xy[1], sigma=2.0, alpha=0.99)
    assert mi.item() == pytest.approx(0.7016688906, abs=1e-9)


def test_von_neumann_threshold(xy):
    h1 = renyi_entropy(xy[0], sigma=2.0, alpha=1.0)
    assert renyi_entropy(xy[0], sigma=2.0, alpha=1.0 + 5e-7).item() == pytest.approx(h1.item(), abs=1e-15)
    h_near = renyi_entropy(xy[0], sigma=2.0, alpha=1.0 + 1e-4).item()
    assert h_near == pytest.approx(h1.item(), abs=1e-4) and h_near != h1.item()


def test_gram_kernels(xy):
    d2 = torch.cdist(xy[0], xy[0]).pow(2)
    torch.testing.assert_close(gram_matrix(xy[0], sigma=2.0), torch.exp(-d2 / 8.0), atol=1e-14, rtol=0)
    torch.testing.assert_close(gram_matrix(xy[0], sigma=0.5, kernel="yu"), torch.exp(-2.0 * d2), atol=1e-14, rtol=0)


def test_yu_sigma_half_equals_gaussian_sigma_half(xy):
    h_yu = renyi_entropy(xy[0], sigma=0.5, alpha=1.01, kernel="yu")
    h_g = renyi_entropy(xy[0], sigma=0.5, alpha=1.01, kernel="gaussian")
    assert h_yu.item() == pytest.approx(h_g.item(), abs=1e-12)


def test_log_base(xy):
    bits = renyi_entropy(xy[0], sigma=2.0, alpha=0.99)
    nats = renyi_entropy(xy[0], sigma=2.0, alpha=0.99, base=math.e)
    assert nats.item() == pytest.approx(bits.item() * math.log(2.0), abs=1e-12)


# --- special configurations ---


@pytest.mark.parametrize("alpha", ALPHAS)
def test_far_apart_points_give_log_n(alpha):
    x = 100.0 * torch.arange(32, dtype=F64).unsqueeze(1)
    assert renyi_entropy(x, sigma=2.0, alpha=alpha).item() == pytest.approx(5.0, abs=1e-9)


@pytest.mark.parametrize("alpha", ALPHAS)
def test_identical_points_give_zero(alpha):
    x = torch.full((16, 3), 0.7, dtype=F64)
    assert renyi_entropy(x, sigma=2.0, alpha=alpha).item() == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("alpha", ALPHAS)
def test_four_far_clusters_give_two_bits(alpha):
    centres = torch.tensor([[0.0, 0.0], [100.0, 0.0], [0.0, 100.0], [100.0, 100.0]], dtype=F64)
    x = centres.repeat_interleave(8, dim=0)
    assert renyi_entropy(x, sigma=2.0, alpha=alpha).item() == pytest.approx(2.0, abs=1e-9)


@pytest.mark.parametrize("alpha", ALPHAS)
def test_mi_with_constant_is_zero(alpha):
    x = _rand(10, 2)
    c = torch.ones(10, 1, dtype=F64)
    assert renyi_mutual_information(x, c, sigma=1.0, alpha=alpha).item() == pytest.approx(0.0, abs=1e-10)


# --- properties ---


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bounds_and_monotone_in_alpha(seed):
    x = _rand(20, 3, seed)
    hs = [renyi_entropy(x, sigma=1.0, alpha=a).item() for a in [0.5, 0.99, 1.0, 1.01, 2.0, 3.0]]
    assert all(0.0 <= h <= math.log2(20) + 1e-12 for h in hs)
    assert all(h1 >= h2 - 1e-12 for h1, h2 in itertools.pairwise(hs))


@pytest.mark.parametrize("alpha", ALPHAS)
def test_invariances(alpha):
    x = _rand(12, 2, seed=3)
    h = renyi_entropy(x, sigma=1.0, alpha=alpha).item()
    perm = torch.randperm(12, generator=torch.Generator().manual_seed(0))
    assert renyi_entropy(x[perm], sigma=1.0, alpha=alpha).item() == pytest.approx(h, abs=1e-10)
    shift = torch.tensor([5.0, -3.0], dtype=F64)
    assert renyi_entropy(x + shift, sigma=1.0, alpha=alpha).item() == pytest.approx(h, abs=1e-10)
    assert renyi_entropy(x @ _rotation(0.7).T, sigma=1.0, alpha=alpha).item() == pytest.approx(h, abs=1e-10)


@pytest.mark.parametrize("alpha", ALPHAS)
def test_mi_symmetric_and_nonnegative_enough(alpha):
    x, y = _rand(15, 2, seed=4), _rand(15, 3, seed=5)
    ixy = renyi_mutual_information(x, y, sigma=1.5, alpha=alpha).item()
    iyx = renyi_mutual_information(y, x, sigma=1.5, alpha=alpha).item()
    assert ixy == pytest.approx(iyx, abs=1e-12)
    assert ixy >= -1e-4


@pytest.mark.parametrize("alpha", ALPHAS)
def test_joint_is_entropy_of_concatenation_and_mi_identity(alpha):
    x, y, z = _rand(10, 2, seed=6), _rand(10, 1, seed=7), _rand(10, 2, seed=8)
    kw = {"sigma": 1.3, "alpha": alpha}
    joint = renyi_joint_entropy(x, y, z, **kw).item()
    assert joint == pytest.approx(renyi_entropy(torch.cat([x, y, z], 1), **kw).item(), abs=1e-10)
    assert renyi_joint_entropy(x, **kw).item() == pytest.approx(renyi_entropy(x, **kw).item(), abs=1e-14)
    mi = renyi_entropy(x, **kw) + renyi_entropy(y, **kw) - renyi_joint_entropy(x, y, **kw)
    assert renyi_mutual_information(x, y, **kw).item() == pytest.approx(mi.item(), abs=1e-12)


def test_matrix_entropy_matches_sample_entropy(xy):
    k = gram_matrix(xy[0], sigma=2.0)
    for alpha in ALPHAS:
        h = renyi_entropy(xy[0], sigma=2.0, alpha=alpha).item()
        assert matrix_renyi_entropy(3.0 * k, alpha=alpha).item() == pytest.approx(h, abs=1e-12)


# --- gradients ---


@pytest.mark.parametrize("alpha", ALPHAS)
def test_gradcheck_float64(alpha):
    x, y = _rand(6, 2, seed=9).requires_grad_(), _rand(6, 1, seed=10).requires_grad_()
    assert torch.autograd.gradcheck(lambda a: renyi_entropy(a, sigma=1.0, alpha=alpha), (x,))
    assert torch.autograd.gradcheck(lambda a, b: renyi_mutual_information(a, b, sigma=1.0, alpha=alpha), (x, y))
    assert torch.autograd.gradcheck(lambda a, b: renyi_joint_entropy(a, b, sigma=1.0, alpha=alpha, base=math.e), (x, y))


def _finite_grad(fn, x: torch.Tensor) -> torch.Tensor:
    x = x.clone().requires_grad_()
    out = fn(x)
    (g,) = torch.autograd.grad(out, x)
    assert torch.isfinite(out).all()
    assert torch.isfinite(g).all(), g
    return g


@pytest.mark.parametrize("alpha", ALPHAS)
@pytest.mark.parametrize("dtype", [torch.float32, F64])
def test_gradients_finite_on_degenerate_inputs(alpha, dtype):
    dup = torch.cat([_rand(4, 2, seed=11), _rand(4, 2, seed=11)], 0).to(dtype)  # duplicated rows
    same = torch.zeros(8, 2, dtype=dtype)  # K = 11ᵀ: eigenvalues [1, 0 x 7]
    far = 100.0 * torch.arange(16, dtype=dtype).unsqueeze(1)  # A = I/16: one eigenvalue repeated 16 times
    clusters = torch.tensor([[0.0], [50.0]], dtype=dtype).repeat_interleave(4, 0)  # eigenvalue 1/2 twice, 0 x 6
    for x in (dup, same, far, clusters):
        _finite_grad(lambda a: renyi_entropy(a, sigma=1.0, alpha=alpha), x)
        _finite_grad(lambda a, x=x: renyi_mutual_information(a, x.flip(0), sigma=1.0, alpha=alpha), x)
    g = _finite_grad(lambda a: renyi_entropy(a, sigma=1.0, alpha=alpha), same)
    assert g.abs().max().item() == 0.0  # nothing moves a fully collapsed batch (symmetry)


@pytest.mark.parametrize("alpha", ALPHAS)
def test_gradient_finite_at_diag_1000(alpha):
    a = torch.diag(torch.tensor([1.0, 0.0, 0.0, 0.0], dtype=F64))
    g = _finite_grad(lambda m: matrix_renyi_entropy(m, alpha=alpha), a)
    assert matrix_renyi_entropy(a, alpha=alpha).item() == pytest.approx(0.0, abs=1e-12)
    assert g.abs().max().item() < 1e3


# --- numerics, dtypes, sizes ---


@pytest.mark.parametrize("alpha", ALPHAS)
def test_float32_matches_float64(alpha):
    x = _rand(64, 4, seed=12)
    h64 = renyi_entropy(x, sigma=2.0, alpha=alpha)
    h32 = renyi_entropy(x.float(), sigma=2.0, alpha=alpha)
    mi32 = renyi_mutual_information(x[:, :2].float(), x[:, 2:].float(), sigma=2.0, alpha=alpha)
    mi64 = renyi_mutual_information(x[:, :2], x[:, 2:], sigma=2.0, alpha=alpha)
    assert h32.dtype == torch.float32 and h64.dtype == F64 and mi32.dtype == torch.float32
    # float64 inside: only input/output rounding remains (≤ 1.1e-7 here); a float32 eigvalsh is off by up to 1e-5
    assert h32.item() == pytest.approx(h64.item(), abs=3e-7)
    assert mi32.item() == pytest.approx(mi64.item(), abs=3e-7)


@pytest.mark.parametrize("n", [2, 512])
def test_batch_sizes(n):
    x = _rand(n, 3, seed=13, dtype=torch.float32).requires_grad_()
    h = renyi_entropy(x, sigma=1.0, alpha=1.01)
    assert 0.0 < h.item() <= math.log2(n)
    h.backward()
    assert torch.isfinite(x.grad).all()
    if n == 2:  # two points: eigenvalues (1 ± k)/2 with k = exp(-d²/2)
        k = math.exp(-(x.detach()[0] - x.detach()[1]).pow(2).sum().item() / 2.0)
        lam = [(1 - k) / 2, (1 + k) / 2]
        expected = math.log2(sum(v**1.01 for v in lam)) / (1 - 1.01)
        assert h.item() == pytest.approx(expected, abs=1e-5)


def test_input_validation(xy):
    with pytest.raises(ValueError, match="kernel"):
        renyi_entropy(xy[0], sigma=1.0, alpha=2.0, kernel="laplace")
    with pytest.raises(ValueError, match="sigma"):
        renyi_entropy(xy[0], sigma=0.0, alpha=2.0)
    with pytest.raises(ValueError, match="alpha"):
        renyi_entropy(xy[0], sigma=1.0, alpha=0.0)
    with pytest.raises(ValueError, match="same n"):
        renyi_mutual_information(xy[0], xy[1][:3], sigma=1.0, alpha=2.0)
    with pytest.raises(ValueError, match="2-D"):
        renyi_entropy(xy[0].flatten(), sigma=1.0, alpha=2.0)
