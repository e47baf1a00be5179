"""Bring a run back from its directory: its config, its env at the checkpoint's state, and its trained agent.

For analysis that needs the trained networks (the model probe, reward maps), not for resuming: nothing is written.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from omegaconf import DictConfig

from curiosity.config import build
from curiosity.config.compose import saved_config
from curiosity.envs import make_env
from curiosity.envs.adapter import adapter_of
from curiosity.envs.state import restore_env
from curiosity.errors import CheckpointError
from curiosity.runtime.checkpoint import CHECKPOINT, load_checkpoint, read_checkpoint


class RestoreError(RuntimeError):
    """The directory cannot be restored; the message says why and what to do."""


@dataclass
class RestoredRun:
    """A run at its last checkpoint: ``cfg``, ``env`` at the checkpoint's state, ``agent`` with its trained state,
    the current observation ``obs`` and the env step ``step``."""

    cfg: DictConfig
    env: Any
    agent: Any
    obs: np.ndarray
    step: int


def restore_run(run_dir: str | Path, checkpoint: str | Path | None = None) -> RestoredRun:
    """Load ``run_dir/.hydra/config.yaml`` and ``run_dir/checkpoint.pt`` (read only), or the checkpoint file
    ``checkpoint`` of that run (e.g. a kept one, ``checkpoints/step=<n>.pt``).

    Raises:
        RestoreError: no config or no checkpoint in ``run_dir``, or ``checkpoint`` is not a file.
    """
    run_dir = Path(run_dir)
    config = run_dir / ".hydra" / "config.yaml"
    if not config.is_file():
        raise RestoreError(f"{run_dir}: no .hydra/config.yaml here; give a run directory (one holding summary.json)")
    if checkpoint is not None and not Path(checkpoint).is_file():
        raise RestoreError(f"{checkpoint}: no such checkpoint file")
    if checkpoint is None and not (run_dir / CHECKPOINT).is_file():
        raise RestoreError(f"{run_dir}: no {CHECKPOINT} (checkpoints are not committed with results; re-run the run's "
                           "command to make one)")  # fmt: skip
    cfg = saved_config(run_dir)
    try:
        ckpt = load_checkpoint(run_dir) if checkpoint is None else read_checkpoint(checkpoint)
    except CheckpointError as err:
        raise RestoreError(str(err)) from None
    assert ckpt is not None
    env = make_env(cfg.env, cfg.budget.max_steps)
    agent = build(cfg.baseline, cfg=cfg)
    restore_env(env, ckpt["env"], int(cfg.seed), adapter_of(cfg.env))
    agent.load_state_dict(ckpt["agent"])
    return RestoredRun(cfg=cfg, env=env, agent=agent, obs=np.asarray(ckpt["obs"]), step=int(ckpt["step"]))
