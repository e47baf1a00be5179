"""Checkpoints of a whole run, written atomically, and the guard that keeps two writers out of one run directory.

Writing a checkpoint keeps the one it replaces as ``checkpoint.prev.pt``; when ``checkpoint.pt`` cannot be read
(truncated, empty, not a checkpoint), the run resumes from the previous one and says so in its log. With
``checkpoint_keep=true`` a run also keeps each periodic checkpoint as ``checkpoints/step=<n>.pt`` (:func:`keep_checkpoint`),
for analysis along the run (``python -m analysis.landscape RUN_DIR --step N``); resuming never reads them.
"""

from __future__ import annotations

import fcntl
import logging
import os
import random
from pathlib import Path
from typing import Any

from curiosity.errors import CheckpointError, RunDirectoryError

log = logging.getLogger(__name__)

CHECKPOINT = "checkpoint.pt"
PREVIOUS = "checkpoint.prev.pt"
KEPT = "checkpoints"  # the kept periodic checkpoints of checkpoint_keep=true: KEPT/step=<n>.pt
LOCK = "run.lock"
_KEYS = ("config", "step", "finished")  # what every checkpoint of a run holds


# numpy and torch are imported where they are used: the command line checks run directories (lock_holder,
# locked_error) before it imports them.


def rng_states() -> dict[str, Any]:
    """The global generators: python, numpy, torch."""
    import numpy as np
    import torch

    return {"python": random.getstate(), "numpy": np.random.get_state(), "torch": torch.get_rng_state()}


def set_rng_states(state: dict[str, Any]) -> None:
    import numpy as np
    import torch

    random.setstate(state["python"])
    np.random.set_state(state["numpy"])
    torch.set_rng_state(state["torch"])


def save_checkpoint(run_dir: str | Path, state: dict[str, Any]) -> Path:
    """Write ``state`` to ``run_dir/checkpoint.pt`` through a temporary file and an atomic rename.

    The checkpoint it replaces becomes ``checkpoint.prev.pt`` (renamed, not copied); :func:`load_checkpoint` falls
    back to it, also in the instant between the two renames.
    """
    import torch

    path = Path(run_dir) / CHECKPOINT
    tmp = path.with_name(f".{CHECKPOINT}.{os.getpid()}.tmp")
    torch.save(state, tmp)
    with open(tmp, "rb") as f:
        os.fsync(f.fileno())
    if path.exists():
        os.replace(path, path.with_name(PREVIOUS))
    os.replace(tmp, path)
    return path


def keep_checkpoint(run_dir: str | Path, step: int) -> Path:
    """Keep the checkpoint just written as ``run_dir/checkpoints/step=<step>.pt`` (a hard link where the file system
    allows it, else a copy; the run's next checkpoint replaces ``checkpoint.pt`` by a rename, so the kept file never
    changes)."""
    import shutil

    src = Path(run_dir) / CHECKPOINT
    dst = Path(run_dir) / KEPT / f"step={step}.pt"
    dst.parent.mkdir(exist_ok=True)
    dst.unlink(missing_ok=True)  # a resumed run passes the same step again: the same state, written again
    try:
        os.link(src, dst)
    except OSError:
        shutil.copyfile(src, dst)
    return dst


def kept_checkpoints(run_dir: str | Path) -> dict[int, Path]:
    """The run's kept checkpoints {env step: path}, in step order (empty when it kept none)."""
    found = {}
    for path in (Path(run_dir) / KEPT).glob("step=*.pt"):
        try:
            found[int(path.stem.removeprefix("step="))] = path
        except ValueError:
            continue
    return dict(sorted(found.items()))


def read_checkpoint(path: str | Path) -> dict[str, Any]:
    """One checkpoint file (a kept one, or ``checkpoint.pt``).

    Raises:
        CheckpointError: naming the file, when it cannot be read.
    """
    state, problem = _read(Path(path))
    if state is None:
        raise CheckpointError(f"{path}: cannot be read ({problem}); allowed: a file written by a run's checkpoint")
    return state


def _read(path: Path) -> tuple[dict[str, Any] | None, str]:
    """(the checkpoint, "") or (None, why it cannot be read)."""
    import torch

    try:
        state = torch.load(path, weights_only=False, map_location="cpu")  # any device's checkpoint; agents move it
    except Exception as err:  # unpickling a damaged file can fail in many ways; all mean "unreadable"
        return None, " ".join(f"{type(err).__name__}: {err}".split())[:120]
    if not isinstance(state, dict) or not all(k in state for k in _KEYS):
        return None, "not a checkpoint of a run"
    return state, ""


def load_checkpoint(run_dir: str | Path) -> dict[str, Any] | None:
    """The run's last readable checkpoint (``checkpoint.pt``, else ``checkpoint.prev.pt``), or None if it has none.

    Raises:
        CheckpointError: naming the file, when checkpoints exist but none can be read.
    """
    path = Path(run_dir) / CHECKPOINT
    problems = []
    for candidate in (path, path.with_name(PREVIOUS)):
        if not candidate.exists():
            continue
        state, problem = _read(candidate)
        if state is None:
            problems.append(f"{candidate.name}: {problem}")
            continue
        if candidate != path:
            why = problems[0] if problems else f"{CHECKPOINT}: missing"
            log.warning("%s cannot be read (%s); resuming from %s at env step %d", path, why, candidate.name, state["step"])
        return state
    if not problems:
        return None
    raise CheckpointError(f"{path}: cannot be read ({'; '.join(problems)}); allowed: move the run directory away (or "
                          "delete it) to start the run again from step 0, or another run directory")  # fmt: skip


def _held(path: Path) -> bool:
    """Whether a process holds the kernel lock (``flock``) on the file at ``path``; False when there is no file."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)  # closing releases the shared lock this took
    return False


def lock_holder(run_dir: str | Path) -> int | None:
    """The id of another process that holds ``run_dir``'s lock, or None (no lock, or a lock no live process holds).

    The lock is the kernel's advisory lock (``flock``) on ``run.lock``, which the kernel releases when its process
    dies (a process killed with SIGKILL and not yet reaped, a zombie, holds nothing); the file names the holder.
    """
    path = Path(run_dir) / LOCK
    try:
        pid = int(path.read_text().strip() or 0)
    except (OSError, ValueError):
        pid = 0
    if pid == os.getpid() or not _held(path):
        return None
    return pid or -1  # -1: held, by a process that has not written its id yet


def locked_error(run_dir: str | Path, pid: int) -> RunDirectoryError:
    """The refusal of a run directory that process ``pid`` (-1: a process not yet named in the file) is writing."""
    who = f"process {pid}" if pid > 0 else "another process"
    return RunDirectoryError(f"{run_dir} is being written by {who} (its {LOCK}); two jobs never share a run "
                             "directory; allowed: wait for it, or other overrides or another hydra.run.dir")  # fmt: skip


class RunLock:
    """Exclusive ownership of a run directory for one live process: the kernel's advisory lock (``flock``) on
    ``run.lock``, released by the kernel when the process ends however it ends, so a killed run's directory is free
    at once; the file holds the owner's process id for the refusal's message."""

    def __init__(self, run_dir: str | Path) -> None:
        self.path = Path(run_dir) / LOCK
        self.fd: int | None = None

    def __enter__(self) -> RunLock:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        for _ in range(10):
            fd = os.open(self.path, os.O_CREAT | os.O_RDWR, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                os.close(fd)
                raise locked_error(self.path.parent, lock_holder(self.path.parent) or -1) from None
            try:  # the file may have been unlinked by its last owner between our open and our lock: lock the current one
                same = os.fstat(fd).st_ino == os.stat(self.path).st_ino
            except FileNotFoundError:
                same = False
            if not same:
                os.close(fd)
                continue
            os.ftruncate(fd, 0)
            os.write(fd, str(os.getpid()).encode())
            self.fd = fd
            return self
        raise RunDirectoryError(f"could not lock {self.path}")

    def __exit__(self, *exc: object) -> None:
        self.path.unlink(missing_ok=True)  # while still locked: a waiting opener sees another inode and retries
        if self.fd is not None:
            os.close(self.fd)  # releases the lock
            self.fd = None
