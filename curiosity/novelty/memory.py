"""A memory of embeddings for novelty queries, exact or a fixed-size uniform reservoir."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import torch
from torch import Tensor

MODES = ("exact", "reservoir")


class EmbeddingMemory:
    """Stores embeddings (and an integer key per item, to re-embed it later) for KDE / kNN novelty queries.

    Modes:
        ``"exact"``: keeps every item (or the newest ``capacity`` items, FIFO, if ``capacity`` is set). Queries over
        it are exact; the KDE / kNN functions chunk over it, so their cost is linear in its size.
        ``"reservoir"``: a uniform random sample of at most ``reservoir_size`` items of the whole stream
        (Vitter's algorithm R, seeded): item t (0-based) enters with probability R / (t + 1), replacing a uniformly
        chosen slot. Query cost stays bounded at R rows however long the stream; KDE on it is an unbiased estimate of
        the exact density (a mean over a uniform sample), with relative error ~ 1/√(R · local mass).

    Keys: ``add(emb, keys)`` stores a long key per row (default: the running stream index 0, 1, 2, …). To refresh
    embeddings after the encoder changes, call ``reembed(fn)`` with ``fn(keys (b,)) -> (b, d)`` (e.g. look the
    observations up in the replay buffer and encode them), or ``replace(emb)`` with fresh (M, d) rows in
    ``tensor()`` order. Rows are in slot order, not chronological order.

    Args:
        mode: ``"exact"`` or ``"reservoir"``.
        reservoir_size: R, the maximum size in reservoir mode.
        capacity: optional FIFO limit in exact mode (``None`` = unbounded).
        seed: seed of the reservoir's random generator.
    """

    def __init__(self, mode: str = "exact", reservoir_size: int = 100_000, capacity: int | None = None, seed: int = 0) -> None:
        if mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
        limit = reservoir_size if mode == "reservoir" else capacity
        if limit is not None and int(limit) < 1:
            raise ValueError(f"reservoir_size / capacity must be >= 1, got {limit}")
        self.mode = mode
        self.limit = None if limit is None else int(limit)
        self.n_seen = 0
        self._size = 0
        self._data: Tensor | None = None
        self._keys = torch.empty(0, dtype=torch.long, device="cpu")  # keys and the reservoir's draws stay on the host
        self._gen = torch.Generator(device="cpu").manual_seed(int(seed))

    def __len__(self) -> int:
        """Number of stored items M."""
        return self._size

    @property
    def stands_for(self) -> int:
        """How many items the stored rows represent: the whole stream for a reservoir (a uniform sample of it), the
        stored rows themselves otherwise (a FIFO window is not a sample of the stream)."""
        return self.n_seen if self.mode == "reservoir" else self._size

    def tensor(self) -> Tensor:
        """Stored embeddings (M, d), a view of the storage (do not modify in place; copy to keep)."""
        if self._data is None:
            raise RuntimeError("the memory is empty and has no dimension yet")
        return self._data[: self._size]

    def keys(self) -> Tensor:
        """Keys (M,) long of the stored rows, aligned with :meth:`tensor`."""
        return self._keys[: self._size]

    def _ensure_room(self, emb: Tensor, needed: int) -> None:
        if self._data is None:
            self._data = emb.new_empty((0, emb.shape[1]))
        elif emb.shape[1] != self._data.shape[1]:
            raise ValueError(f"embedding dim {emb.shape[1]} != memory dim {self._data.shape[1]}")
        if needed > self._data.shape[0]:
            new_cap = max(needed, 2 * self._data.shape[0], 64)
            if self.limit is not None:
                new_cap = min(new_cap, self.limit)
            data = self._data.new_empty((new_cap, self._data.shape[1]))
            data[: self._size] = self._data[: self._size]
            keys = torch.empty(new_cap, dtype=torch.long, device="cpu")
            keys[: self._size] = self._keys[: self._size]
            self._data, self._keys = data, keys

    def _slots(self, b: int) -> Tensor:
        """Destination slot of each of b incoming items (−1 = dropped); later items win on repeated slots."""
        t = torch.arange(self.n_seen, self.n_seen + b, device="cpu")
        if self.limit is None:
            return t
        if self.mode == "exact":
            return t % self.limit
        j = (torch.rand(b, generator=self._gen, dtype=torch.float64, device="cpu") * (t + 1).to(torch.float64)).floor().long()
        slots = torch.where(t < self.limit, t, j)
        return torch.where(slots < self.limit, slots, torch.full_like(slots, -1))

    def add(self, emb: Tensor, keys: Tensor | None = None) -> None:
        """Add embeddings (B, d) with optional long keys (B,) (default: stream indices n_seen … n_seen + B − 1)."""
        if emb.dim() != 2:
            raise ValueError(f"emb must be (B, d), got {tuple(emb.shape)}")
        b = emb.shape[0]
        keys = torch.arange(self.n_seen, self.n_seen + b, device="cpu") if keys is None else keys.reshape(-1).long().cpu()
        if keys.shape[0] != b:
            raise ValueError(f"got {keys.shape[0]} keys for {b} embeddings")
        slots = self._slots(b)
        self._ensure_room(emb, min(self.n_seen + b, self.limit or self.n_seen + b))
        rows = torch.arange(b, device="cpu")[slots >= 0]
        slots = slots[slots >= 0]
        uniq, inverse = torch.unique(slots, return_inverse=True)
        last = torch.full_like(uniq, -1).scatter_reduce(0, inverse, rows, reduce="amax")
        self._data[uniq.to(self._data.device)] = emb.detach()[last.to(emb.device)].to(self._data.dtype)
        self._keys[uniq] = keys[last]
        self.n_seen += b
        self._size = min(self.n_seen, self.limit or self.n_seen)

    def replace(self, emb: Tensor) -> None:
        """Overwrite all stored embeddings with fresh ones (M, d), rows aligned with :meth:`tensor` / :meth:`keys`."""
        if emb.shape != self.tensor().shape:
            raise ValueError(f"replace needs shape {tuple(self.tensor().shape)}, got {tuple(emb.shape)}")
        self._data[: self._size] = emb.detach().to(self._data.dtype)

    @torch.no_grad()
    def reembed(self, fn: Callable[[Tensor], Tensor], batch_size: int = 4096) -> None:
        """Recompute every stored embedding as ``fn(keys)`` ((b,) long -> (b, d)), in batches of ``batch_size``."""
        keys = self.keys()
        for start in range(0, self._size, batch_size):
            stop = min(start + batch_size, self._size)
            self._data[start:stop] = fn(keys[start:stop]).detach().to(self._data.dtype)

    def state_dict(self) -> dict[str, Any]:
        """Everything needed to resume: mode, limit, stored rows and keys, stream count and generator state."""
        data = None if self._data is None else self.tensor().clone()
        return {
            "mode": self.mode,
            "limit": self.limit,
            "data": data,
            "keys": self.keys().clone(),
            "n_seen": self.n_seen,
            "rng_state": self._gen.get_state(),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` saved; mode and limit must match the constructor's."""
        if (state["mode"], state["limit"]) != (self.mode, self.limit):
            raise ValueError(f"state is for {state['mode']}/{state['limit']}, this memory is {self.mode}/{self.limit}")
        self._data = None if state["data"] is None else state["data"].clone()
        self._keys = state["keys"].clone()
        self._size = self._keys.shape[0]
        self.n_seen = int(state["n_seen"])
        self._gen.set_state(state["rng_state"])
