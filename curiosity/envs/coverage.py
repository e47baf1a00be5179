"""State-space coverage: the fraction of cells of a fixed grid over the true physical state visited so far."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


class GridCoverage:
    """Counts visited cells of a regular grid over a box of the physical state.

    Args:
        low: (D,) lower corner of the box; values below it fall into the first cell.
        high: (D,) upper corner of the box; values above it fall into the last cell.
        bins: (D,) number of cells per dimension.
    """

    def __init__(self, low: Sequence[float], high: Sequence[float], bins: Sequence[int]) -> None:
        self.low = np.asarray(low, dtype=np.float64)
        self.high = np.asarray(high, dtype=np.float64)
        self.bins = np.asarray(bins, dtype=np.int64)
        if not (self.low.shape == self.high.shape == self.bins.shape) or self.low.ndim != 1:
            raise ValueError(f"coverage low/high/bins must be 1-D of one length, got {self.low}, {self.high}, {self.bins}")
        self.visited = np.zeros(int(np.prod(self.bins)), dtype=bool)
        self._strides = np.cumprod(np.concatenate([[1], self.bins[:0:-1]]))[::-1]

    @property
    def n_cells(self) -> int:
        return int(self.visited.size)

    def cell(self, state: np.ndarray) -> int:
        """Flat index of the cell holding ``state`` (D,)."""
        frac = (np.asarray(state, dtype=np.float64) - self.low) / (self.high - self.low)
        idx = np.clip(np.floor(frac * self.bins).astype(np.int64), 0, self.bins - 1)
        return int(idx @ self._strides)

    def update(self, state: np.ndarray) -> None:
        """Mark the cell of ``state`` (D,) visited."""
        self.visited[self.cell(state)] = True

    @property
    def fraction(self) -> float:
        """Visited cells / all cells, in [0, 1]."""
        return float(self.visited.mean())

    def state_dict(self) -> dict[str, np.ndarray]:
        return {"visited": self.visited.copy()}

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        self.visited = np.asarray(state["visited"], dtype=bool).copy()
