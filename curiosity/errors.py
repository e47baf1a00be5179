"""Errors a run reports to its user."""

from __future__ import annotations


class NumericalFault(FloatingPointError):
    """A NaN or Inf in a loss, a reward or a latent; names the term (and, once the loop adds it, the env step)."""

    def __init__(self, term: str, value: float | str, step: int | None = None) -> None:
        self.term, self.value, self.step = term, value, step
        where = f" at env step {step}; the run stopped, its last good checkpoint is kept" if step is not None else ""
        super().__init__(f"{term} is {value}{where}")


class RunDirectoryError(RuntimeError):
    """A run directory that this run may not write: another live writer, or a different run's files."""
