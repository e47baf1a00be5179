"""Compose the run config in Python, as ``python -m runners.train`` would (for notebooks, tests, benchmarks)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from hydra import compose, initialize_config_dir
from omegaconf import DictConfig

from curiosity.config import setup

CONF_DIR = Path(__file__).resolve().parents[2] / "conf"


def compose_config(overrides: Sequence[str] = ()) -> DictConfig:
    """The run config for command-line style ``overrides`` (``["estimator=knn", "seed=3"]``), without Hydra's node."""
    setup()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose(config_name="config", overrides=list(overrides))
