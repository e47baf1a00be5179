"""Input checks, memory chunking and the fused squared-distance kernel shared by the KDE and kNN scores."""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator

import torch
from torch import Tensor

from curiosity.info.kernels import check_2d

DEFAULT_CHUNK = 16384
MAX_BLOCK = 2**23  # float64 distances held at once (64 MB): queries are split into blocks of MAX_BLOCK // chunk rows


def query_blocks(n_query: int, chunk_size: int) -> Iterator[tuple[int, int]]:
    """(start, stop) blocks of the queries such that a block times a memory chunk stays within ``MAX_BLOCK`` values
    (one block for the planner's few hundred queries; a memory scoring itself, B = N, goes block by block)."""
    step = max(1, MAX_BLOCK // max(chunk_size, 1))
    yield from itertools.pairwise([*range(0, n_query, step), n_query])


def check_query_memory(query: Tensor, memory: Tensor, exclude_self: bool) -> None:
    """Validate query (B, d) against memory (N, d); with ``exclude_self`` the query must be the memory (B == N)."""
    check_2d(query, "query")
    check_2d(memory, "memory")
    if query.shape[1] != memory.shape[1]:
        raise ValueError(f"query and memory need the same d, got {query.shape[1]} and {memory.shape[1]}")
    if exclude_self and query.shape[0] != memory.shape[0]:
        raise ValueError("exclude_self=True needs query to be the memory itself (B == N, row i = memory row i)")


def chunks(n: int, chunk_size: int, min_size: int = 1) -> Iterator[tuple[int, int]]:
    """Yield (start, stop) pairs covering range(n) in steps of ``chunk_size``; no chunk is smaller than ``min_size``
    (a short last chunk is merged into the previous one) unless n itself is."""
    if chunk_size < 1:
        raise ValueError(f"chunk_size must be >= 1, got {chunk_size}")
    step = max(chunk_size, min_size)
    bounds = [*range(0, n, step), n]
    if len(bounds) > 2 and bounds[-1] - bounds[-2] < min_size:
        del bounds[-2]
    yield from itertools.pairwise(bounds)


def needs_grad(*xs: Tensor) -> bool:
    """True when autograd will record operations on any of ``xs`` (then no in-place shortcuts)."""
    return torch.is_grad_enabled() and any(x.requires_grad for x in xs)


def sq_dist_chunks(q64: Tensor, row0: int, memory: Tensor, chunk_size: int, *, exclude_self: bool, inplace: bool,
                   min_size: int = 1) -> Iterator[Tensor]:  # fmt: skip
    """Squared distances (b, stop − start) of queries ``q64`` (b, d), the memory's rows row0 … row0 + b − 1 when
    ``exclude_self``, to each chunk of ``memory`` (:func:`chunks`), computed in the queries' dtype (float64 unless a
    caller asks for less); with ``exclude_self`` a query's own memory row is at distance inf."""
    q2 = q64.pow(2).sum(-1, keepdim=True)
    rows = torch.arange(row0, row0 + q64.shape[0], device=q64.device).unsqueeze(1)
    for start, stop in chunks(memory.shape[0], chunk_size, min_size=min_size):
        d2 = sq_dists_chunk(q64, q2, memory[start:stop].to(q64.dtype), inplace)
        if exclude_self:
            d2 = d2.masked_fill(rows == torch.arange(start, stop, device=q64.device).unsqueeze(0), math.inf)
        yield d2


def sq_dists_chunk(q64: Tensor, q2: Tensor, m64: Tensor, inplace: bool) -> Tensor:
    """||q_b - m_i||^2 = ||q||^2 + ||m||^2 - 2 q.m for q (B, d), q2 = ||q||^2 (B, 1), m (M, d) of one dtype -> (B, M) ≥ 0."""
    d2 = torch.addmm(m64.pow(2).sum(-1).unsqueeze(0), q64, m64.T, alpha=-2.0)
    return d2.add_(q2).clamp_(min=0.0) if inplace else (d2 + q2).clamp(min=0.0)
