"""One logger façade feeding ``metrics.csv`` and TensorBoard from the same calls.

``record(key, value)`` as often as you like (values are averaged until the next dump), then ``dump(step)`` once:
one CSV row (flushed at once) and one TensorBoard scalar per recorded key, at the global env step. Keys are
TensorBoard tags (``charts/coverage``, ``losses/transition``, ``intrinsic/reward``) and are also the CSV's column
names; the columns are fixed when the logger is made, and recording an undeclared key is an error, so nothing
logged is silently dropped.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path

from typing import Any

from torch.utils.tensorboard import SummaryWriter

from curiosity.errors import NumericalFault

# Columns that measure the machine, not the run: excluded when two runs' metrics.csv are compared.
WALL_CLOCK_COLUMNS = ("charts/wall_time", "charts/sps", "timing/")


def is_wall_clock(column: str) -> bool:
    """Whether ``column`` holds wall-clock measurements (differs between identical runs)."""
    return any(column == c or (c.endswith("/") and column.startswith(c)) for c in WALL_CLOCK_COLUMNS)


class RunLogger:
    """CSV + TensorBoard logger of one run.

    A non-finite value (NaN, ±Inf) is refused with :class:`~curiosity.errors.NumericalFault` naming its key, so no
    NaN row is ever written.

    Args:
        run_dir: the run directory; writes ``metrics.csv`` and ``tb/``.
        columns: every key that may be recorded (``step`` is added first).
        flush_secs: TensorBoard flush period; everything is flushed on :meth:`close`.
        resume: a :meth:`state_dict` of an earlier logger of this run: ``metrics.csv`` is cut back to the bytes written
            then (rows logged after it are dropped, so no step appears twice), TensorBoard events after its last
            step are purged, and its open window is restored.
    """

    def __init__(self, run_dir: str | Path, columns: Sequence[str], flush_secs: int = 30,
                 resume: dict[str, Any] | None = None) -> None:  # fmt: skip
        self.run_dir = Path(run_dir)
        self.run_dir.mkdir(parents=True, exist_ok=True)
        self.columns = ["step", *dict.fromkeys(columns)]
        self.csv_path = self.run_dir / "metrics.csv"
        self._sums: dict[str, float] = {}
        self._counts: dict[str, int] = {}
        self.last_step = 0  # the step of the last dump
        purge = None
        if resume is None:
            self._file = self.csv_path.open("w", newline="")
            self._writer = csv.DictWriter(self._file, fieldnames=self.columns)
            self._writer.writeheader()
            self._file.flush()
        else:
            self._reopen(resume)
            purge = int(resume["last_step"]) + 1
        self.tb = SummaryWriter(log_dir=str(self.run_dir / "tb"), flush_secs=flush_secs, purge_step=purge)

    def _reopen(self, state: dict[str, Any]) -> None:
        with self.csv_path.open("r+b") as f:
            f.truncate(int(state["csv_bytes"]))
        with self.csv_path.open(newline="") as f:
            header = next(csv.reader(f))
        if header != self.columns:
            raise ValueError(f"{self.csv_path} has columns {header}, this run logs {self.columns}")
        self._file = self.csv_path.open("a", newline="")
        self._writer = csv.DictWriter(self._file, fieldnames=self.columns)
        self._sums, self._counts = dict(state["sums"]), dict(state["counts"])
        self.last_step = int(state["last_step"])

    def state_dict(self) -> dict[str, Any]:
        """Where the logger is: bytes of ``metrics.csv`` written, the last dumped step, the open window."""
        self._file.flush()
        return {"csv_bytes": self._file.tell(), "last_step": self.last_step, "sums": dict(self._sums),
                "counts": dict(self._counts)}  # fmt: skip

    def record(self, key: str, value: float) -> None:
        """Add one value of ``key`` to the current window (its mean is logged at the next dump).

        Raises:
            KeyError: ``key`` is not a declared column.
            NumericalFault: ``value`` is NaN or infinite.
        """
        if key not in self.columns or key == "step":
            raise KeyError(f"metric {key!r} is not a declared column of metrics.csv; declared: {self.columns[1:]}")
        if not math.isfinite(value):
            raise NumericalFault(key, value)
        self._sums[key] = self._sums.get(key, 0.0) + float(value)
        self._counts[key] = self._counts.get(key, 0) + 1

    def record_many(self, values: dict[str, float]) -> None:
        for key, value in values.items():
            self.record(key, value)

    def dump(self, step: int) -> dict[str, float]:
        """Write the window's means at global env step ``step``; returns them."""
        means = {k: self._sums[k] / self._counts[k] for k in self._sums}
        row: dict[str, object] = {"step": int(step)}
        row.update({k: _fmt(v) for k, v in means.items()})
        self._writer.writerow(row)
        self._file.flush()
        for key, value in means.items():
            self.tb.add_scalar(key, value, int(step))
        self.last_step = int(step)
        self._sums.clear()
        self._counts.clear()
        return means

    def text(self, tag: str, text: str) -> None:
        self.tb.add_text(tag, text, 0)

    def close(self) -> None:
        self.tb.close()
        self._file.close()


def _fmt(value: float) -> str:
    """Shortest text that round-trips a float32-precision value (keeps the CSV small and deterministic)."""
    if math.isfinite(value) and value == int(value) and abs(value) < 2**53:
        return str(int(value))
    return f"{value:.9g}"
