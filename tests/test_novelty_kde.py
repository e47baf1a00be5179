"""kde_log_density: worked example, brute-force double loop, sklearn oracle, chunking, self-counting, numerics."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from sklearn.neighbors import KernelDensity

from curiosity.novelty import kde_log_density

F64 = torch.float64


@pytest.fixture
def replay() -> torch.Tensor:
    return torch.tensor([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [2.0, 2.0]], dtype=F64)


def _rand(*shape: int, seed: int = 0, dtype: torch.dtype = F64) -> torch.Tensor:
    return torch.randn(*shape, generator=torch.Generator().manual_seed(seed), dtype=dtype)


def _kde_loop(query: torch.Tensor, memory: torch.Tensor, h: float, skip_diagonal: bool = False) -> list[float]:
    out = []
    for b in range(query.shape[0]):
        logs = [
            -sum((float(q) - float(m)) ** 2 for q, m in zip(query[b], memory[i], strict=True)) / (2 * h * h)
            for i in range(memory.shape[0])
            if not (skip_diagonal and i == b)
        ]
        top = max(logs)
        out.append(top + math.log(sum(math.exp(v - top) for v in logs) / len(logs)))
    return out


def test_worked_example(replay):
    query = torch.tensor([[0.5, 0.5], [3.0, 3.0], [10.0, 10.0]], dtype=F64)
    expected = torch.tensor([-0.4398695, -2.5527778, -65.6094379], dtype=F64)
    torch.testing.assert_close(kde_log_density(query, replay, bandwidth=1.0), expected, atol=5e-8, rtol=0)


@pytest.mark.parametrize(("b", "n", "d", "h"), [(2, 7, 2, 0.5), (13, 40, 3, 1.3), (512, 30, 6, 0.8)])
def test_matches_double_loop(b, n, d, h):
    query, memory = _rand(b, d, seed=1), _rand(n, d, seed=2)
    out = kde_log_density(query, memory, bandwidth=h)
    assert out.shape == (b,)
    torch.testing.assert_close(out, torch.tensor(_kde_loop(query, memory, h), dtype=F64), atol=1e-11, rtol=0)


def test_narrow_kernels_whose_far_terms_are_floored_stay_exact():
    """h = 0.05 over unit-spaced rows: most exponents are below −60 (raised to it before exp, for speed); the result
    equals the double loop's exact (underflowing) sums to float64 rounding."""
    query, memory = _rand(40, 3, seed=5), _rand(300, 3, seed=6)
    out = kde_log_density(query, memory, bandwidth=0.05)
    exponents = -torch.cdist(query, memory).pow(2) / (2 * 0.05**2)
    assert (exponents < -60).float().mean() > 0.9  # the floor is exercised
    torch.testing.assert_close(out, torch.tensor(_kde_loop(query, memory, 0.05), dtype=F64), atol=1e-11, rtol=1e-13)


@pytest.mark.parametrize("h", [0.3, 1.0, 2.5])
def test_matches_sklearn_with_normaliser(h):
    query, memory = _rand(50, 3, seed=3), _rand(200, 3, seed=4)
    score = KernelDensity(bandwidth=h, kernel="gaussian").fit(memory.numpy()).score_samples(query.numpy())
    expected = torch.from_numpy(score + 1.5 * np.log(2 * np.pi * h * h))
    torch.testing.assert_close(kde_log_density(query, memory, bandwidth=h), expected, atol=1e-9, rtol=0)


@pytest.mark.parametrize("chunk_size", [1, 7, 64, 10_000])
def test_chunking_is_exact(chunk_size):
    query, memory = _rand(9, 2, seed=5), _rand(150, 2, seed=6)
    full = kde_log_density(query, memory, bandwidth=0.4, chunk_size=10**6)
    torch.testing.assert_close(kde_log_density(query, memory, bandwidth=0.4, chunk_size=chunk_size), full, atol=1e-12, rtol=0)
    loo = kde_log_density(memory, memory, bandwidth=0.4, exclude_self=True, chunk_size=10**6)
    chunked = kde_log_density(memory, memory, bandwidth=0.4, exclude_self=True, chunk_size=chunk_size)
    torch.testing.assert_close(chunked, loo, atol=1e-12, rtol=0)


def test_query_in_memory_counts_itself_unless_excluded(replay):
    with_self = kde_log_density(replay, replay, bandwidth=1.0)
    torch.testing.assert_close(with_self, torch.tensor(_kde_loop(replay, replay, 1.0), dtype=F64), atol=1e-12, rtol=0)
    assert (with_self >= -math.log(5) - 1e-12).all()  # its own term exp(0) = 1 gives ρ ≥ 1/N
    loo = kde_log_density(replay, replay, bandwidth=1.0, exclude_self=True)
    expected = torch.tensor(_kde_loop(replay, replay, 1.0, skip_diagonal=True), dtype=F64)
    torch.testing.assert_close(loo, expected, atol=1e-12, rtol=0)
    # the isolated point (2, 2): nearest others at squared distances 2, 5, 5, 8
    assert loo[4].item() == pytest.approx(math.log((math.exp(-1) + 2 * math.exp(-2.5) + math.exp(-4)) / 4), abs=1e-13)


@pytest.mark.parametrize("dtype", [torch.float32, F64])
def test_far_queries_are_finite(dtype, replay):
    query = torch.tensor([[1e3, -1e3], [1e4, 1e4]], dtype=dtype)
    out = kde_log_density(query, replay.to(dtype), bandwidth=0.1)
    assert torch.isfinite(out).all() and out.dtype == dtype
    d2_nearest = (1e3 - 1.0) ** 2 + 1e6  # nearest stored point to (1e3, −1e3) is (1, 0)
    assert out[0].item() == pytest.approx(-d2_nearest / 0.02 - math.log(5), rel=1e-6)


def test_float32_matches_float64():
    query, memory = _rand(64, 4, seed=7), _rand(300, 4, seed=8)
    out64 = kde_log_density(query, memory, bandwidth=0.9)
    out32 = kde_log_density(query.float(), memory.float(), bandwidth=0.9)
    assert out32.dtype == torch.float32
    torch.testing.assert_close(out32.double(), out64, atol=1e-5, rtol=0)


def test_float32_precision_is_close_to_the_float64_reference():
    """``precision="float32"`` (a speed option) computes distances and kernel terms in float32: within 2e-3 nats of the
    float64 KDE on standardised 4-d latents with a narrow bandwidth (a big memory's), for queries near the memory and
    far from it (a far query's large shift stays float64); the output dtype follows the inputs, as before."""
    memory = _rand(5000, 4, seed=11)
    near = memory[:200] + 0.05 * _rand(200, 4, seed=12)
    far = 4.0 * _rand(50, 4, seed=13)
    for query in (near, far):
        ref = kde_log_density(query, memory, bandwidth=0.1, chunk_size=1024)
        fast = kde_log_density(query, memory, bandwidth=0.1, chunk_size=1024, precision="float32")
        assert fast.dtype == F64 and torch.isfinite(fast).all()
        assert (fast - ref).abs().max().item() < 2e-3  # float32 rounding, not bit-exact across machines
    with pytest.raises(ValueError, match="precision must be one of"):
        kde_log_density(near, memory, bandwidth=0.1, precision="float16")


def test_float32_precision_keeps_float64_where_a_gradient_is_recorded():
    query, memory = _rand(5, 3, seed=14).requires_grad_(), _rand(40, 3, seed=15)
    a = kde_log_density(query, memory, bandwidth=0.5, precision="float32")
    b = kde_log_density(query, memory, bandwidth=0.5)
    torch.testing.assert_close(a, b, atol=0, rtol=0)  # exact: the same float64 computation, same machine and call
    a.sum().backward()
    assert torch.isfinite(query.grad).all()


def test_gradcheck_and_duplicate_rows():
    query, memory = _rand(3, 2, seed=9).requires_grad_(), _rand(6, 2, seed=10).requires_grad_()
    assert torch.autograd.gradcheck(lambda q, m: kde_log_density(q, m, bandwidth=0.7, chunk_size=4), (query, memory))
    mem = torch.cat([memory.detach(), memory.detach()]).requires_grad_()
    kde_log_density(mem, mem, bandwidth=0.5, exclude_self=True, chunk_size=11).sum().backward()
    assert torch.isfinite(mem.grad).all()


def test_validation(replay):
    with pytest.raises(ValueError, match="bandwidth"):
        kde_log_density(replay, replay, bandwidth=0.0)
    with pytest.raises(ValueError, match="same d"):
        kde_log_density(replay[:, :1], replay, bandwidth=1.0)
    with pytest.raises(ValueError, match="exclude_self"):
        kde_log_density(replay[:2], replay, bandwidth=1.0, exclude_self=True)


def test_queries_in_blocks_are_exact_and_bound_memory(monkeypatch: pytest.MonkeyPatch) -> None:
    """A memory scoring itself (B = N) goes block by block over the queries (a memory of 10^5 rows once needed
    13 GB for one chunk): the values are the double loop's, with and without leave-one-out, for KDE and kNN."""
    import curiosity.novelty._common as common
    from curiosity.novelty import k_smallest_sq_dists

    memory = _rand(23, 3, seed=8)
    whole_kde = kde_log_density(memory, memory, bandwidth=0.7, exclude_self=True, chunk_size=7)
    whole_knn = k_smallest_sq_dists(memory, memory, k=3, exclude_self=True, chunk_size=7)
    monkeypatch.setattr(common, "MAX_BLOCK", 35)  # 5 queries per block with chunks of 7 memory rows
    assert list(common.query_blocks(23, 7)) == [(0, 5), (5, 10), (10, 15), (15, 20), (20, 23)]
    for exclude in (False, True):
        blocked = kde_log_density(memory, memory, bandwidth=0.7, exclude_self=exclude, chunk_size=7)
        torch.testing.assert_close(blocked, torch.tensor(_kde_loop(memory, memory, 0.7, exclude), dtype=F64),
                                   atol=1e-10, rtol=0)  # fmt: skip
    torch.testing.assert_close(kde_log_density(memory, memory, bandwidth=0.7, exclude_self=True, chunk_size=7), whole_kde,
                               atol=1e-12, rtol=0)  # fmt: skip
    blocked_knn = k_smallest_sq_dists(memory, memory, k=3, exclude_self=True, chunk_size=7)
    torch.testing.assert_close(blocked_knn, whole_knn, atol=1e-12, rtol=0)
    brute = torch.cdist(memory, memory).square().fill_diagonal_(math.inf).sort(dim=1).values[:, :3]
    torch.testing.assert_close(blocked_knn, brute, atol=1e-10, rtol=0)
