"""knn_distance and nsrs_knn_score against brute force, sklearn NearestNeighbors and hand-computed values."""

from __future__ import annotations

import math

import pytest
import torch
from sklearn.neighbors import NearestNeighbors

from curiosity.novelty import k_smallest_sq_dists, knn_distance, nsrs_knn_score
from curiosity.novelty.knn import self_knn_distances

F64 = torch.float64


def _rand(*shape: int, seed: int = 0, dtype: torch.dtype = F64) -> torch.Tensor:
    return torch.randn(*shape, generator=torch.Generator().manual_seed(seed), dtype=dtype)


def _sorted_sq_dists_loop(query: torch.Tensor, memory: torch.Tensor, skip_diagonal: bool = False) -> list[list[float]]:
    rows = []
    for b in range(query.shape[0]):
        d2 = [
            sum((float(q) - float(m)) ** 2 for q, m in zip(query[b], memory[i], strict=True))
            for i in range(memory.shape[0])
            if not (skip_diagonal and i == b)
        ]
        rows.append(sorted(d2))
    return rows


@pytest.fixture
def line() -> torch.Tensor:
    return torch.tensor([[0.0], [1.0], [3.0], [6.0], [10.0], [15.0]], dtype=F64)


def test_hand_computed_values(line):
    query = torch.tensor([[0.0], [2.0]], dtype=F64)
    # from 0: distances 0, 1, 3, 6, 10, 15; from 2: 2, 1, 1, 4, 8, 13 -> five nearest 1, 1, 2, 4, 8
    torch.testing.assert_close(knn_distance(query, line, k=5), torch.tensor([20 / 5, 16 / 5], dtype=F64), atol=1e-14, rtol=0)
    nsrs = nsrs_knn_score(query, line, k=5)  # squared, nearest dropped: 2nd..5th
    expected = torch.tensor([(1 + 9 + 36 + 100) / 4, (1 + 4 + 16 + 64) / 4], dtype=F64)
    torch.testing.assert_close(nsrs, expected, atol=1e-12, rtol=0)


def test_exclude_self(line):
    out = knn_distance(line, line, k=2, exclude_self=True)
    expected = torch.tensor([(1 + 3) / 2, (1 + 2) / 2, (2 + 3) / 2, (3 + 4) / 2, (4 + 5) / 2, (5 + 9) / 2], dtype=F64)
    torch.testing.assert_close(out, expected, atol=1e-14, rtol=0)
    with_self = knn_distance(line, line, k=2)
    torch.testing.assert_close(with_self, torch.tensor([0.5, 0.5, 1.0, 1.5, 2.0, 2.5], dtype=F64), atol=1e-14, rtol=0)


@pytest.mark.parametrize(("b", "n", "k", "chunk"), [(2, 9, 1, 4), (17, 50, 5, 7), (512, 40, 5, 4096)])
def test_matches_brute_force(b, n, k, chunk):
    query, memory = _rand(b, 3, seed=1), _rand(n, 3, seed=2)
    loop = torch.tensor(_sorted_sq_dists_loop(query, memory), dtype=F64)
    kw = {"k": k, "chunk_size": chunk}
    torch.testing.assert_close(k_smallest_sq_dists(query, memory, **kw), loop[:, :k], atol=1e-12, rtol=0)
    torch.testing.assert_close(knn_distance(query, memory, **kw), loop[:, :k].sqrt().mean(1), atol=1e-12, rtol=0)
    if k >= 2:
        torch.testing.assert_close(nsrs_knn_score(query, memory, **kw), loop[:, 1:k].mean(1), atol=1e-12, rtol=0)


@pytest.mark.parametrize("chunk", [3, 4096])
def test_exclude_self_matches_brute_force(chunk):
    memory = _rand(30, 2, seed=3)
    loop = torch.tensor(_sorted_sq_dists_loop(memory, memory, skip_diagonal=True), dtype=F64)
    out = knn_distance(memory, memory, k=4, exclude_self=True, chunk_size=chunk)
    torch.testing.assert_close(out, loop[:, :4].sqrt().mean(1), atol=1e-12, rtol=0)


def test_matches_sklearn_nearest_neighbors():
    query, memory = _rand(100, 4, seed=4), _rand(500, 4, seed=5)
    dist, _ = NearestNeighbors(n_neighbors=5).fit(memory.numpy()).kneighbors(query.numpy())
    dist = torch.from_numpy(dist)
    torch.testing.assert_close(knn_distance(query, memory, k=5, chunk_size=64), dist.mean(1), atol=1e-10, rtol=0)
    torch.testing.assert_close(nsrs_knn_score(query, memory, k=5), dist[:, 1:].pow(2).mean(1), atol=1e-10, rtol=0)


def test_float32_and_gradient():
    query, memory = _rand(64, 3, seed=6), _rand(200, 3, seed=7)
    out32 = knn_distance(query.float(), memory.float(), k=5)
    assert out32.dtype == torch.float32
    torch.testing.assert_close(out32.double(), knn_distance(query, memory, k=5), atol=1e-5, rtol=0)
    q = memory[:4].clone().requires_grad_()  # queries exactly on stored points: zero distances
    knn_distance(q, memory, k=3).sum().backward()
    assert torch.isfinite(q.grad).all()
    q2 = _rand(3, 3, seed=8).requires_grad_()
    assert torch.autograd.gradcheck(lambda a: knn_distance(a, memory, k=3), (q2,))


def test_validation(line):
    with pytest.raises(ValueError, match="k"):
        knn_distance(line, line, k=7)
    with pytest.raises(ValueError, match="k"):
        knn_distance(line, line, k=6, exclude_self=True)
    with pytest.raises(ValueError, match="k >= 2"):
        nsrs_knn_score(line, line, k=1)
    assert math.isfinite(knn_distance(line, line, k=6).sum().item())


@pytest.mark.parametrize("k", [1, 3])
def test_self_knn_distances_by_tree_match_the_exact_leave_one_out(k):
    """The k-d tree's neighbour distances equal brute force over explicit differences (row i left out), exact
    duplicates included: a duplicated row's nearest other row is at distance exactly 0, where the chunked
    ||q||² + ||m||² − 2 q·m expansion leaves ~1e-8 of rounding. Tolerance: different summation orders."""
    gen = torch.Generator().manual_seed(3)
    memory = torch.randn(300, 4, generator=gen, dtype=torch.float64)
    memory[10] = memory[11]  # an exact duplicate pair
    memory[20] = memory[21] = memory[22]  # and a triple
    tree = self_knn_distances(memory, k=k)
    pairwise = (memory[:, None, :] - memory[None, :, :]).pow(2).sum(-1).sqrt().fill_diagonal_(math.inf)
    exact = pairwise.sort(dim=1).values[:, :k]
    assert tree.shape == (300, k) and tree.dtype == torch.float64
    torch.testing.assert_close(tree, exact, rtol=1e-9, atol=1e-12)
    assert tree[10, 0] == 0 and tree[20, 0] == 0
    chunked = k_smallest_sq_dists(memory, memory, k=k, exclude_self=True).sqrt()
    torch.testing.assert_close(tree, chunked, rtol=0, atol=1e-7)  # the expansion's rounding at duplicates
    with pytest.raises(ValueError, match="neighbours"):
        self_knn_distances(memory[:3], k=3)
