"""Gaussian-potential dispersion loss and backward-predictor NLL: oracle values, brute force, gradients."""

from __future__ import annotations

import itertools
import math

import pytest
import torch

from curiosity.info import backward_predictor_nll, gaussian_potential

F64 = torch.float64


def _rand(*shape: int, seed: int = 0, dtype: torch.dtype = F64) -> torch.Tensor:
    return torch.randn(*shape, generator=torch.Generator().manual_seed(seed), dtype=dtype)


def _potential_loop(z: torch.Tensor, t: float) -> float:
    pairs = list(itertools.combinations(range(z.shape[0]), 2))
    total = sum(math.exp(-t * sum((float(a) - float(b)) ** 2 for a, b in zip(z[i], z[j], strict=True))) for i, j in pairs)
    return math.log(total / len(pairs))


# --- gaussian_potential (docs/method.md §8, t = 2) ---


def test_identical_points_give_zero():
    assert gaussian_potential(torch.ones(5, 3)).item() == pytest.approx(0.0, abs=1e-7)


def test_two_points_one_and_a_half_apart():
    z = torch.tensor([[0.0, 0.0], [1.5, 0.0]])
    assert gaussian_potential(z).item() == pytest.approx(-4.5, abs=1e-6)


def test_regular_tetrahedron_on_unit_sphere():
    z = torch.tensor([[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]], dtype=F64) / math.sqrt(3)
    assert gaussian_potential(z).item() == pytest.approx(-16.0 / 3.0, abs=1e-12)


@pytest.mark.parametrize("dtype", [torch.float32, F64])
def test_four_points_ten_apart_do_not_underflow(dtype):
    z = torch.tensor([[0.0], [10.0], [20.0], [30.0]], dtype=dtype)
    if dtype == torch.float32:
        naive = torch.log(torch.exp(-2.0 * torch.pdist(z).pow(2)).mean())
        assert naive.item() == -math.inf  # the naive form underflows in float32 ...
    out = gaussian_potential(z)
    assert out.dtype == dtype
    assert out.item() == pytest.approx(-200.6931471806, abs=1e-4 if dtype == torch.float32 else 1e-10)  # ... ours does not


@pytest.mark.parametrize(("n", "t"), [(2, 2.0), (7, 0.5), (12, 3.0)])
def test_matches_brute_force(n, t):
    z = _rand(n, 3, seed=n)
    assert gaussian_potential(z, t=t).item() == pytest.approx(_potential_loop(z, t), abs=1e-12)


def test_potential_invariances():
    z = _rand(9, 2, seed=1)
    v = gaussian_potential(z).item()
    assert gaussian_potential(z.flip(0) + 3.0).item() == pytest.approx(v, abs=1e-12)


def test_potential_gradcheck_and_degenerate_gradient():
    z = _rand(6, 2, seed=2).requires_grad_()
    assert torch.autograd.gradcheck(lambda a: gaussian_potential(a, t=2.0), (z,))
    same = torch.zeros(4, 2, dtype=F64, requires_grad=True)
    gaussian_potential(torch.cat([same, same])).backward()
    assert torch.isfinite(same.grad).all() and same.grad.abs().max().item() == 0.0


@pytest.mark.parametrize("n", [2, 512])
def test_potential_batch_sizes_and_dtypes(n):
    z = _rand(n, 4, seed=3)
    v64 = gaussian_potential(z)
    v32 = gaussian_potential(z.float())
    assert v32.dtype == torch.float32
    assert v32.item() == pytest.approx(v64.item(), abs=1e-5)


def test_potential_validation():
    with pytest.raises(ValueError, match="at least 2"):
        gaussian_potential(torch.zeros(1, 2))
    with pytest.raises(ValueError, match="t must"):
        gaussian_potential(torch.zeros(3, 2), t=0.0)


# --- backward_predictor_nll ---


def _nll_loop(y: torch.Tensor, cand: torch.Tensor, sigma_b: float) -> list[float]:
    out = []
    for b in range(y.shape[0]):
        terms = [math.exp(-float((y[b] - c).pow(2).sum()) / (2 * sigma_b**2)) for c in cand[b]]
        out.append(-math.log(sum(terms) / len(terms)))
    return out


@pytest.mark.parametrize(("b", "k"), [(2, 1), (5, 8), (512, 3)])
def test_nll_matches_brute_force(b, k):
    y, cand = _rand(b, 3, seed=4), _rand(b, k, 3, seed=5)
    out = backward_predictor_nll(y, cand, sigma_b=0.7)
    assert out.shape == (b,)
    torch.testing.assert_close(out, torch.tensor(_nll_loop(y, cand, 0.7), dtype=F64), atol=1e-12, rtol=0)


def test_nll_exact_values():
    y = torch.tensor([[0.0, 0.0], [1.0, 1.0]], dtype=F64)
    cand = torch.tensor([[[0.0, 0.0], [0.0, 0.0]], [[1.0, 1.0], [3.0, 1.0]]], dtype=F64)
    out = backward_predictor_nll(y, cand, sigma_b=1.0)
    assert out[0].item() == pytest.approx(0.0, abs=1e-15)  # every candidate is y
    assert out[1].item() == pytest.approx(-math.log((1.0 + math.exp(-2.0)) / 2.0), abs=1e-14)


@pytest.mark.parametrize("dtype", [torch.float32, F64])
def test_nll_far_candidates_stay_finite(dtype):
    y = torch.zeros(2, 2, dtype=dtype)
    cand = torch.full((2, 4, 2), 100.0, dtype=dtype)
    out = backward_predictor_nll(y, cand, sigma_b=0.1)
    assert out.dtype == dtype
    torch.testing.assert_close(out, torch.full((2,), 20000.0 / 0.02, dtype=dtype), rtol=1e-7, atol=1e-7)


def test_nll_gradcheck_and_duplicates():
    y, cand = _rand(3, 2, seed=6).requires_grad_(), _rand(3, 4, 2, seed=7).requires_grad_()
    assert torch.autograd.gradcheck(lambda a, c: backward_predictor_nll(a, c, sigma_b=0.8), (y, cand))
    y0 = torch.zeros(2, 2, dtype=F64, requires_grad=True)
    backward_predictor_nll(y0, torch.zeros(2, 3, 2, dtype=F64), sigma_b=0.5).sum().backward()
    assert torch.isfinite(y0.grad).all()


def test_nll_validation():
    with pytest.raises(ValueError, match="candidates"):
        backward_predictor_nll(torch.zeros(2, 3), torch.zeros(2, 4, 2), sigma_b=1.0)
    with pytest.raises(ValueError, match="sigma_b"):
        backward_predictor_nll(torch.zeros(2, 3), torch.zeros(2, 4, 3), sigma_b=0.0)
