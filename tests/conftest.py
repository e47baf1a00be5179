"""Shared test helpers: compose the real configs, run the real CLI in a subprocess."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import pytest
import torch
from omegaconf import DictConfig

from curiosity.config import setup
from curiosity.config.compose import compose_config
from curiosity.types import TransitionBatch

REPO = Path(__file__).resolve().parents[1]
CONF = REPO / "conf"

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
if os.environ.get("PYTEST_XDIST_WORKER"):  # `make test` runs the suite in parallel workers (pytest-xdist): one torch
    os.environ.setdefault("OMP_NUM_THREADS", "1")  # thread each, and in the CLIs they launch, so that the workers do
    torch.set_num_threads(1)  # not oversubscribe the cores
setup()


def compose_cfg(overrides: Sequence[str] = ()) -> DictConfig:
    """The composed run config for ``overrides`` (no Hydra runtime node)."""
    return compose_config(overrides)


@pytest.fixture
def cfg_for() -> Callable[..., DictConfig]:
    return lambda *overrides: compose_cfg(overrides)


@contextmanager
def holding_lock(run_dir: Path) -> Iterator[int]:
    """A live process that holds ``run_dir``'s run lock as a run does (the kernel's ``flock`` on ``run.lock``, its id
    in the file) until the block ends; yields its id."""
    hold = ("import fcntl, os, sys, time; fd = os.open(sys.argv[1], os.O_CREAT | os.O_RDWR); "
            "fcntl.flock(fd, fcntl.LOCK_EX); os.write(fd, str(os.getpid()).encode()); print('held', flush=True); "
            "time.sleep(300)")  # fmt: skip
    with subprocess.Popen([sys.executable, "-c", hold, str(Path(run_dir) / "run.lock")], stdout=subprocess.PIPE,
                          text=True) as other:  # fmt: skip
        try:
            assert other.stdout is not None and other.stdout.readline().strip() == "held"
            yield other.pid
        finally:
            other.kill()


def run_cli(args: Sequence[str], cwd: Path, timeout: float = 600) -> subprocess.CompletedProcess:
    """``python -m runners.train *args`` in a subprocess, from ``cwd``, progress bar off."""
    env = {**os.environ, "HYDRA_FULL_ERROR": "0", "PYTHONPATH": str(REPO)}
    return subprocess.run(
        [sys.executable, "-m", "runners.train", *args, "progress=false"],
        cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout,
    )  # fmt: skip


@pytest.fixture
def one_thread():
    """One torch intra-op thread for the test (tiny nets run faster so, and far faster on a shared machine)."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def random_batch(batch_size: int, obs_shape: tuple[int, ...], seed: int, n_actions: int = 3) -> TransitionBatch:
    """A seeded batch of random transitions: observations in [0, 1), zero rewards, no terminals."""
    g = torch.Generator().manual_seed(seed)
    return TransitionBatch(
        obs=torch.rand(batch_size, *obs_shape, generator=g),
        act=torch.randint(0, n_actions, (batch_size,), generator=g),
        next_obs=torch.rand(batch_size, *obs_shape, generator=g),
        rewards=torch.zeros(batch_size),
        terminateds=torch.zeros(batch_size),
    )


def group_options() -> list[tuple[str, str]]:
    """Every (group, option) pair under ``conf/`` (hydra/ excluded; experiment/ and sweep/, appended with ``+``, are
    tested in test_sweeps.py)."""
    return sorted(
        (p.parent.name, p.stem) for p in CONF.glob("*/*.yaml") if p.parent.name not in {"hydra", "experiment", "sweep"}
    )
