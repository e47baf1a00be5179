"""The command line's checks before Hydra starts anything: a refused command changes nothing and says why in one line.

Hydra creates a job's run directory and opens its ``train.log`` before the task function runs (and would write
``.hydra/*.yaml`` there too; ``conf/config.yaml`` leaves that to the job, see :mod:`curiosity.runtime.job`). So a
single run is composed with Hydra's compose API and checked here first: the overrides compose and append no unknown
key, the config validates, and its run directory can be written and holds nothing this run may not continue. A
sweep's jobs are checked each in its own job (their run directories are known only there); here its sweep directory.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from pathlib import Path

from hydra._internal.utils import get_args_parser
from hydra.core.hydra_config import HydraConfig
from hydra.core.override_parser.overrides_parser import OverridesParser
from omegaconf import DictConfig, OmegaConf, open_dict, read_write
from omegaconf.errors import OmegaConfBaseException

from curiosity.config import ConfigError, validate
from curiosity.config.compose import COMPOSE_ERRORS, compose_config, describe_compose_error
from curiosity.config.overrides import appended_key_errors
from curiosity.runtime.rundir import check_run_dir, check_writable

# Command-line flags that show something instead of running, or that point Hydra at another config: Hydra alone.
_NOT_A_RUN = ("help", "hydra_help", "cfg", "info", "shell_completion", "experimental_rerun", "config_path",
              "config_name", "config_dir")  # fmt: skip


def preflight(args: Sequence[str]) -> None:
    """Check the command line ``args`` (``sys.argv[1:]``) of ``python -m runners.train``; writes nothing.

    Raises:
        ConfigError: the overrides do not compose, append an unknown key, or give an invalid config.
        RunDirectoryError: the run (or sweep) directory is a file, not writable, locked, or holds another run.
    """
    parsed = get_args_parser().parse_args(list(args))
    if any(getattr(parsed, flag, None) for flag in _NOT_A_RUN):
        return
    overrides = list(parsed.overrides)
    if parsed.multirun or "hydra.mode=MULTIRUN" in overrides:
        _check_sweep(overrides)
    else:
        _check_run(overrides)


def _compose(overrides: list[str]) -> DictConfig:
    try:
        return compose_config(overrides, hydra_node=True)
    except COMPOSE_ERRORS as err:
        raise ConfigError([describe_compose_error(err, overrides)]) from None


def _directory(cfg: DictConfig, key: str) -> Path:
    """The absolute directory that ``cfg``'s ``key`` (``hydra.run.dir``, ``hydra.sweep.dir``) names."""
    HydraConfig.instance().set_config(cfg)
    try:
        value = OmegaConf.select(cfg, key, throw_on_resolution_failure=True)
    except OmegaConfBaseException as err:
        raise ConfigError([f"{key}: {str(err).splitlines()[0]}"]) from None
    return Path(str(value)).absolute()


def task_config(cfg: DictConfig) -> DictConfig:
    """``cfg`` without Hydra's node: the config a job's task function receives."""
    task = copy.deepcopy(cfg)
    with read_write(task), open_dict(task):
        del task["hydra"]
    return task


def checked_config(overrides: Sequence[str]) -> tuple[DictConfig, DictConfig]:
    """Compose ``overrides`` as one run and check them as ``runners.train`` does before anything is written.

    Returns:
        The composed config with Hydra's node, and the task config (without it).

    Raises:
        ConfigError: the overrides do not compose, append an unknown key, or give an invalid config.
    """
    overrides = list(overrides)
    cfg = _compose(overrides)
    errors = appended_key_errors(overrides, cfg, cfg.hydra.runtime.choices)
    if errors:
        raise ConfigError(errors)
    task = task_config(cfg)
    validate(task)
    return cfg, task


def _check_run(overrides: list[str]) -> None:
    cfg, task = checked_config(overrides)
    if OmegaConf.select(cfg, "hydra.sweeper.params"):  # a sweep preset (+sweep=...) without -m: Hydra would run one job
        preset = next((o for o in overrides if o.lstrip("+").startswith("sweep=")), "hydra.sweeper.params")
        raise ConfigError([f"{preset}: a sweep preset lists jobs, which only -m runs (without it Hydra would run one "
                           f"job with the defaults); allowed: python -m runners.train -m {' '.join(overrides)}"])  # fmt: skip
    check_run_dir(task, _directory(cfg, "hydra.run.dir"))


def _check_sweep(overrides: list[str]) -> None:
    try:
        parsed = OverridesParser.create().parse_overrides(overrides)
    except COMPOSE_ERRORS as err:
        raise ConfigError([describe_compose_error(err, overrides)]) from None
    cfg = _compose([o.input_line for o in parsed if not o.is_sweep_override()])
    check_writable(_directory(cfg, "hydra.sweep.dir"), "hydra.sweep.dir")
