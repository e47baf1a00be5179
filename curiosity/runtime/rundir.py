"""Checks of a run directory that write nothing: run before Hydra creates or writes anything in it.

A run directory is refused when it is a file, cannot be written, is locked by a live process, or holds another run
that this one may not continue (another configuration, ``resume=false``, no checkpoint, an unreadable checkpoint).
"""

from __future__ import annotations

import os
from pathlib import Path

from omegaconf import DictConfig

from curiosity.errors import RunDirectoryError
from curiosity.runtime.checkpoint import CHECKPOINT, PREVIOUS, lock_holder, locked_error

# Files that show a directory holds a run (Hydra's ``.hydra/`` is written by the run itself, once it starts).
RUN_FILES = (".hydra", "metrics.csv", CHECKPOINT, PREVIOUS, "summary.json", "tb")


def holds_run(run_dir: Path) -> bool:
    """Whether ``run_dir`` holds (part of) a run."""
    return any((run_dir / name).exists() for name in RUN_FILES)


def check_writable(path: Path, key: str) -> None:
    """Refuse a directory path that is a file, lies below a file, or cannot be created or written.

    Args:
        path: the directory (it need not exist yet).
        key: what set it, for the message (``hydra.run.dir``, ``hydra.sweep.dir``).
    """
    if path.exists() and not path.is_dir():
        raise RunDirectoryError(f"{key}={path}: is a file, not a directory; allowed: a directory, or a path to create one")
    existing = path
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise RunDirectoryError(f"{key}={path}: {existing} is a file, so the directory cannot be created; allowed: "
                                "a path below directories only")  # fmt: skip
    if not os.access(existing, os.W_OK | os.X_OK):
        raise RunDirectoryError(f"{key}={path}: {existing} is not writable (a read-only file system, or no permission); "
                                "allowed: a directory this user can write")  # fmt: skip


def check_run_dir(cfg: DictConfig, run_dir: Path, key: str = "hydra.run.dir") -> None:
    """Refuse ``run_dir`` for the run ``cfg`` unless the run may start or continue there; writes nothing.

    Raises:
        RunDirectoryError: naming the directory (or file), the reason and what is allowed.
    """
    check_writable(run_dir, key)
    pid = lock_holder(run_dir) if run_dir.is_dir() else None
    if pid is not None:
        raise locked_error(run_dir, pid)
    from curiosity.runtime.loop import check_built, existing_checkpoint  # torch: once the cheap checks have passed

    check_built(cfg)
    if run_dir.is_dir() and holds_run(run_dir):
        existing_checkpoint(cfg, run_dir)
