"""Errors a run reports to its user.

Each is a :class:`hydra.errors.CompactHydraException`, so that Hydra, when one ends a job, prints its message alone
(no traceback), and the command line prints it as one line: ``error: <message>``.
"""

from __future__ import annotations

from hydra.errors import CompactHydraException


class RunError(CompactHydraException):
    """An error whose message says all the user needs: the key or file, the value, and what is allowed."""


class NumericalFault(FloatingPointError, RunError):
    """A NaN or Inf in a loss, a reward or a latent; names the term (and, once the loop adds it, the env step)."""

    def __init__(self, term: str, value: float | str, step: int | None = None) -> None:
        self.term, self.value, self.step = term, value, step
        where = f" at env step {step}; the run stopped, its last good checkpoint is kept" if step is not None else ""
        super().__init__(f"{term} is {value}{where}")


class RunDirectoryError(RunError, RuntimeError):
    """A run directory that this run may not write: another live writer, or a different run's files."""


class CheckpointError(RunDirectoryError):
    """A checkpoint that cannot be read (truncated, empty, not a checkpoint), with no readable earlier one."""
