"""k-nearest-neighbour novelty scores: the mean Euclidean distance and NSRS's own squared-distance variant."""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor

from curiosity.info.kernels import out_dtype
from curiosity.novelty._common import DEFAULT_CHUNK, check_query_memory, needs_grad, query_blocks, sq_dist_chunks


def k_smallest_sq_dists(
    query: Tensor, memory: Tensor, *, k: int, exclude_self: bool = False, chunk_size: int = DEFAULT_CHUNK
) -> Tensor:
    """The k smallest squared Euclidean distances from each query to the memory, ascending, exact and chunked.

    Args:
        query: (B, d) queries.
        memory: (N, d) stored embeddings, N ≥ k (N ≥ k + 1 with ``exclude_self``).
        k: number of neighbours, ≥ 1.
        exclude_self: the query is the memory itself (B == N) and row i never counts memory row i.
        chunk_size: memory rows per chunk.

    Returns:
        (B, k) float64 squared distances d²_(1) ≤ … ≤ d²_(k).
    """
    check_query_memory(query, memory, exclude_self)
    if k < 1 or memory.shape[0] - int(exclude_self) < k:
        raise ValueError(f"need 1 <= k <= {memory.shape[0] - int(exclude_self)} neighbours, got k={k}")
    inplace = not needs_grad(query, memory)
    q64 = query.to(torch.float64)
    blocks = []
    for q0, q1 in query_blocks(query.shape[0], chunk_size):  # bounded memory when the memory scores itself
        best = q64.new_empty((q1 - q0, 0))
        for d2 in sq_dist_chunks(q64[q0:q1], q0, memory, chunk_size, exclude_self=exclude_self, inplace=inplace):
            merged = torch.cat([best, d2], dim=1)
            best = torch.topk(merged, min(k, merged.shape[1]), dim=1, largest=False, sorted=True).values
        blocks.append(best)
    return blocks[0] if len(blocks) == 1 else torch.cat(blocks)


def knn_distance(
    query: Tensor, memory: Tensor, *, k: int, exclude_self: bool = False, chunk_size: int = DEFAULT_CHUNK
) -> Tensor:
    """Mean Euclidean distance to the k nearest memory embeddings (the paper's kNN novelty baseline, §3.3).

    score(q) = (1/k) Σ_{j=1..k} ‖q − m_(j)‖, m_(j) the j-th nearest memory row. A query stored in the memory counts
    itself (distance 0) unless ``exclude_self=True`` (then the query must be the memory, row i skipping row i).
    The square root is taken with a safe gradient (0 at zero distance, never NaN).

    Args:
        query: (B, d) queries.
        memory: (N, d) stored embeddings.
        k: number of neighbours (5 in the paper).
        exclude_self: see above.
        chunk_size: memory rows per chunk.

    Returns:
        (B,) mean distances in the promoted dtype of the inputs.
    """
    d2 = k_smallest_sq_dists(query, memory, k=k, exclude_self=exclude_self, chunk_size=chunk_size)
    pos = d2 > 0
    dist = torch.where(pos, d2.clamp_min(1e-300).sqrt(), torch.zeros_like(d2))
    return dist.mean(dim=1).to(out_dtype(query, memory))


def nsrs_knn_score(query: Tensor, memory: Tensor, *, k: int = 5, chunk_size: int = DEFAULT_CHUNK) -> Tensor:
    """NSRS's kNN novelty score: the mean of the 2nd … k-th smallest **squared** distances.

    score(q) = (1/(k−1)) Σ_{j=2..k} ‖q − m_(j)‖². NSRS drops the nearest neighbour as if it were the query itself,
    even when the query is not in the memory (as for its planning queries), so k = 5 averages 4 neighbours.

    Args:
        query: (B, d) queries.
        memory: (N, d) stored embeddings, N ≥ k.
        k: neighbours taken before dropping the nearest, ≥ 2.
        chunk_size: memory rows per chunk.

    Returns:
        (B,) scores in the promoted dtype of the inputs.
    """
    if k < 2:
        raise ValueError(f"nsrs_knn_score needs k >= 2 (the nearest is dropped), got {k}")
    d2 = k_smallest_sq_dists(query, memory, k=k, chunk_size=chunk_size)
    return d2[:, 1:].mean(dim=1).to(out_dtype(query, memory))


def self_knn_distances(memory: Tensor, *, k: int) -> Tensor:
    """Euclidean distances from each memory row to its k nearest *other* rows, ascending, by a k-d tree.

    The same values as ``k_smallest_sq_dists(memory, memory, k=k, exclude_self=True).sqrt()`` in O(N log N) instead of
    O(N²) (a memory of 10^5 rows: about a second instead of minutes): the tree returns the k + 1 nearest rows, the
    first of which is at distance 0 (the row itself, or an exact duplicate of it: either way the remaining k
    distances are the k smallest to the other rows). No gradient; computed on the host in float64.

    Args:
        memory: (N, d) embeddings, N ≥ k + 1.
        k: neighbours, ≥ 1.

    Returns:
        (N, k) float64 distances on ``memory``'s device.
    """
    from scipy.spatial import KDTree  # here, not at the top: importing the novelty package stays torch + numpy only

    check_query_memory(memory, memory, exclude_self=True)
    if k < 1 or memory.shape[0] - 1 < k:
        raise ValueError(f"need 1 <= k <= {memory.shape[0] - 1} neighbours, got k={k}")
    points = memory.detach().to("cpu", torch.float64).numpy()
    dist, _ = KDTree(points).query(points, k=k + 1)
    return torch.from_numpy(np.ascontiguousarray(dist[:, 1:])).to(memory.device)
