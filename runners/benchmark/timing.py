"""Timing helpers of the benchmark: the machine's description, medians of repeated calls, time spent per part."""

from __future__ import annotations

import os
import statistics
import time
from collections.abc import Callable
from typing import Any

from curiosity.runtime.machine import machine as run_machine


def machine() -> dict[str, str | int]:
    """What a run's ``summary.json`` records of this machine (:func:`curiosity.runtime.machine.machine`: CPU model and
    vector capability, torch and Python versions, torch threads, platform), its cores and the code's commit."""
    from curiosity.runtime.summary import git_commit

    commit, dirty = git_commit()
    return {**run_machine(), "cores": os.cpu_count() or 0, "commit": f"{commit}{'-dirty' if dirty else ''}"}


def timed(fn: Callable[[], object], repeats: int, warmup: int = 2) -> float:
    """Median milliseconds of ``fn()`` over ``repeats`` calls after ``warmup`` calls."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(1e3 * (time.perf_counter() - start))
    return statistics.median(times)


class PartTimer:
    """Wall seconds spent inside chosen methods of live objects, by part name, each part exclusive of the timed parts
    it calls (planning's novelty scoring counts as ``novelty``, not ``plan``).

    ``wrap(obj, "method", "part")`` replaces the method on that object (an instance, a class or a module) by a timed
    one; ``restore()`` puts every original back.
    """

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self._stack: list[float] = []  # time spent in timed children of each open call
        self._wrapped: list[tuple[Any, str, Any]] = []

    def wrap(self, obj: Any, method: str, part: str) -> None:
        inner = getattr(obj, method)
        self._wrapped.append((obj, method, obj.__dict__.get(method, inner) if hasattr(obj, "__dict__") else inner))

        def timed_call(*args: Any, **kwargs: Any) -> Any:
            self._stack.append(0.0)
            start = time.perf_counter()
            try:
                return inner(*args, **kwargs)
            finally:
                elapsed = time.perf_counter() - start
                children = self._stack.pop()
                self.seconds[part] = self.seconds.get(part, 0.0) + elapsed - children
                if self._stack:
                    self._stack[-1] += elapsed

        setattr(obj, method, timed_call)

    def replace(self, obj: Any, name: str, new: Any) -> None:
        """Set ``obj.name = new`` until ``restore()``."""
        self._wrapped.append((obj, name, getattr(obj, name)))
        setattr(obj, name, new)

    def restore(self) -> None:
        for obj, method, original in reversed(self._wrapped):
            setattr(obj, method, original)
        self._wrapped = []

    def shares(self, total: float) -> dict[str, float]:
        """Fraction of ``total`` seconds per part, and ``other`` for the rest."""
        out = {part: s / total for part, s in sorted(self.seconds.items())}
        out["other"] = max(0.0, 1.0 - sum(out.values()))
        return out
