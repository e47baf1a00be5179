"""The body of one Hydra job: check it, record its configuration, run it, report an interruption.

Hydra writes a job's ``.hydra/config.yaml``, ``hydra.yaml`` and ``overrides.yaml`` before the task function runs,
so a refused job would overwrite them in an existing run's directory. ``conf/config.yaml`` therefore sets
``hydra.output_subdir: null`` and the job writes the same three files itself, once its run directory has been checked
and locked (:func:`save_hydra_files`): a refused job leaves an existing run's files byte for byte as they were.
"""

from __future__ import annotations

import logging
from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

from curiosity.config import ConfigError, sampled_candidates
from curiosity.config.overrides import appended_key_errors
from curiosity.errors import RunError
from curiosity.runtime.loop import Interrupted, run
from curiosity.runtime.rundir import check_writable

log = logging.getLogger(__name__)

HYDRA_SUBDIR = ".hydra"


def save_hydra_files(cfg: DictConfig, run_dir: Path) -> None:
    """Write ``.hydra/config.yaml``, ``hydra.yaml`` and ``overrides.yaml`` as Hydra itself would."""
    hydra = HydraConfig.instance().cfg
    assert hydra is not None
    out = run_dir / HYDRA_SUBDIR
    out.mkdir(parents=True, exist_ok=True)
    for name, node in (("config.yaml", cfg), ("hydra.yaml", hydra), ("overrides.yaml", hydra.hydra.overrides.task)):
        (out / name).write_text(OmegaConf.to_yaml(node), encoding="utf-8")


def _start(cfg: DictConfig, run_dir: Path) -> None:
    save_hydra_files(cfg, run_dir)
    log.info("%s seed=%d %s: running in %s", cfg.method_label, cfg.seed, cfg.env.id, run_dir)
    sampled = sampled_candidates(cfg)
    if sampled is not None:
        log.warning("planner.horizon=%d: the planner scores %d sampled sequences of the %d^%d per step "
                    "(planner.sample_candidates=true)", cfg.planner.horizon, sampled, cfg.planner.n_actions,
                    cfg.planner.horizon)  # fmt: skip


def _detach_logs(run_dir: Path) -> None:
    """Close the log files Hydra opened in ``run_dir``: nothing logged after a refusal may land in its train.log."""
    root = logging.getLogger()
    for handler in list(root.handlers):
        if isinstance(handler, logging.FileHandler) and Path(handler.baseFilename).parent == run_dir:
            root.removeHandler(handler)
            handler.close()


def run_job(cfg: DictConfig) -> float | None:
    """Check and run the job Hydra composed; returns its steps-to-goal (None when the cap was hit).

    Raises:
        ConfigError, RunDirectoryError: the job is refused; nothing in its run directory was changed.
        Interrupted: SIGTERM/SIGINT stopped the run after a checkpoint (logged to the run's train.log).
    """
    hydra = HydraConfig.get()
    run_dir = Path(hydra.runtime.output_dir)
    try:
        errors = appended_key_errors(list(hydra.overrides.task), cfg, hydra.runtime.choices)
        if errors:
            raise ConfigError(errors)
        check_writable(run_dir, "run directory")
        summary = run(cfg, run_dir, on_start=lambda: _start(cfg, run_dir))  # validates cfg first
    except RunError:
        _detach_logs(run_dir)
        raise
    except Interrupted as stop:
        log.warning("signal %d at env step %d: stopped after writing a checkpoint", stop.signum, stop.step)
        raise
    return summary.steps_to_goal
