"""One place that seeds every source of randomness of a run."""

from __future__ import annotations

import os
import random

import numpy as np
import torch


def seed_everything(seed: int, *, deterministic: bool = False, threads: int = 1) -> None:
    """Seed python, numpy and torch; set torch's thread count; with ``deterministic`` use one thread and
    deterministic algorithms (so the same seed gives the same run, byte for byte)."""
    random.seed(seed)
    np.random.seed(seed % 2**32)
    torch.manual_seed(seed)
    torch.set_num_threads(1 if deterministic else threads)
    if deterministic:
        os.environ.setdefault("CUBLAS_WORKSPACE_CONFIG", ":4096:8")
    torch.use_deterministic_algorithms(deterministic)
