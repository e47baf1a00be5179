"""Gaussian kernel density of queries over a memory of embeddings (paper §3.3.1), exact and chunked."""

from __future__ import annotations

import math

import torch
from torch import Tensor

from curiosity.info.kernels import out_dtype
from curiosity.novelty._common import DEFAULT_CHUNK, check_query_memory, needs_grad, query_blocks, sq_dist_chunks


# Exponents below this are raised to it before exp(): exp(−60) ≈ 9e-27, so even 10^9 such terms change a row's sum
# (≥ 1: its nearest row contributes exp(0)) by less than 1e-17, under float64 rounding; and exp() of an argument that
# underflows takes the CPU's slow path (≈ 30 ns instead of 4 ns an element, measured), which far rows hit constantly.
EXP_FLOOR = -60.0
PRECISIONS = {"float64": torch.float64, "float32": torch.float32}


def _chunk_log_sum(d2: Tensor, inv_two_h2: float, inplace: bool) -> Tensor:
    """log Σ_i exp(−d2_bi / (2h²)) for one chunk (B, M) -> (B,), shifted by the row minimum of d2 for stability
    (exponents floored at ``EXP_FLOOR``: the same value to float64 rounding)."""
    d_min = d2.amin(dim=1, keepdim=True)  # values only: min(dim) also finds indices, 2-4x slower here
    if inplace:
        s = d2.sub_(d_min).mul_(-inv_two_h2).clamp_(min=EXP_FLOOR).exp_().sum(dim=1)
    else:
        s = torch.exp(((d2 - d_min) * -inv_two_h2).clamp(min=EXP_FLOOR)).sum(dim=1)
    # the shift and the log in float64 whatever the chunk's dtype: a far query's shift is large
    return s.to(torch.float64).log() - d_min.squeeze(1).to(torch.float64) * inv_two_h2


def kde_log_density(
    query: Tensor,
    memory: Tensor,
    *,
    bandwidth: float,
    exclude_self: bool = False,
    chunk_size: int = DEFAULT_CHUNK,
    precision: str = "float64",
) -> Tensor:
    """Log of the (unnormalised) Gaussian KDE of each query over the memory.

    log ρ(q_b) = log( (1/N) Σ_i exp(−‖q_b − m_i‖² / (2h²)) ) = logsumexp_i(−‖q_b − m_i‖²/(2h²)) − log N.

    The Gaussian normaliser (2πh²)^(−d/2) is left out, as in the paper, so
    ``sklearn.neighbors.KernelDensity(bandwidth=h).score_samples(q) + (d/2) log(2πh²)`` equals this value.
    Exact for any N: the memory is processed in chunks of ``chunk_size`` rows in float64 (see ``precision``), each
    chunk's log-sum is shifted by its smallest squared distance, and the chunks are combined with a logsumexp. Far-away
    queries give large negative but finite values (never −inf or NaN).

    Does a query count itself? Every memory row counts, so a query that is also stored in the memory contributes its
    own term exp(0) = 1 (resubstitution KDE, as sklearn's ``score_samples`` on its own training data). With
    ``exclude_self=True`` the query must be the memory itself (B == N) and row i leaves out memory row i
    (leave-one-out): log( (1/(N−1)) Σ_{j≠i} exp(−‖m_i − m_j‖²/(2h²)) ).

    Args:
        query: (B, d) query embeddings.
        memory: (N, d) stored embeddings (N ≥ 2 with ``exclude_self``).
        bandwidth: kernel bandwidth h > 0.
        exclude_self: leave-one-out densities of the memory's own rows (see above).
        chunk_size: memory rows per chunk (queries go in blocks, so at most ``MAX_BLOCK`` float64 distances are held
            at once: a memory of 10^5 rows scores itself in 64 MB blocks, not 13 GB).
        precision: ``"float64"`` (the reference) or ``"float32"``: the dtype of the distances and kernel terms (each
            chunk's shift, log and the logsumexp over chunks stay float64). float32 is about 1.6× faster on a CPU
            (measured in ``docs/benchmarks.md``) and, through the ‖q‖² + ‖m‖² − 2q·m expansion, off by about
            1e-7 · (‖q‖² + ‖m‖²) / (2h²) nats (≈ 1e-4 on standardised latents): for approximate memories (a reservoir),
            whose sampling error is three orders larger. With a gradient to record it stays float64 (a speed option).

    Returns:
        (B,) log-densities in the promoted dtype of ``query`` and ``memory``, differentiable in both.
    """
    check_query_memory(query, memory, exclude_self)
    if precision not in PRECISIONS:
        raise ValueError(f"precision must be one of {tuple(PRECISIONS)}, got {precision!r}")
    if not bandwidth > 0:
        raise ValueError(f"bandwidth must be > 0, got {bandwidth}")
    n = memory.shape[0] - int(exclude_self)
    if n < 1:
        raise ValueError("exclude_self=True needs at least 2 memory rows")
    inplace = not needs_grad(query, memory)
    inv_two_h2 = 1.0 / (2.0 * float(bandwidth) ** 2)
    q = query.to(PRECISIONS[precision] if inplace else torch.float64)  # float32 only where nothing needs a gradient
    blocks = []
    for q0, q1 in query_blocks(query.shape[0], chunk_size):
        # with exclude_self every chunk has >= 2 columns, so no row of a chunk is entirely left out
        parts = [_chunk_log_sum(d2, inv_two_h2, inplace)
                 for d2 in sq_dist_chunks(q[q0:q1], q0, memory, chunk_size, exclude_self=exclude_self, inplace=inplace,
                                          min_size=2 if exclude_self else 1)]  # fmt: skip
        blocks.append(parts[0] if len(parts) == 1 else torch.logsumexp(torch.stack(parts, dim=1), dim=1))
    log_rho = blocks[0] if len(blocks) == 1 else torch.cat(blocks)
    return (log_rho - math.log(n)).to(out_dtype(query, memory))
