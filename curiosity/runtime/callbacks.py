"""Hydra callbacks: a sweep lists its failed jobs with their run directories.

Hydra goes on with the other jobs when one fails and exits non-zero at the end; it does not say which jobs failed.
Each failed job leaves ``FAILED.json`` (error and overrides) in its run directory (a job that succeeds removes one an
earlier failure left), and :func:`report_failures` lists this sweep's failures on the console and in
``<sweep dir>/failed_jobs.txt`` (called by ``runners.train`` when the sweep exits non-zero).

A job refused in a directory that already held a run (another configuration, ``resume=false``, a live lock) writes
nothing there: its marker goes to ``<sweep dir>/FAILED.job<N>.json`` instead, naming the run directory.
"""

from __future__ import annotations

import json
import logging
import time
from pathlib import Path
from typing import Any

from hydra.core.utils import JobReturn, JobStatus
from hydra.experimental.callback import Callback
from hydra.types import RunMode
from omegaconf import DictConfig

from curiosity.config import ConfigError
from curiosity.errors import RunDirectoryError
from curiosity.runtime.rundir import holds_run

log = logging.getLogger(__name__)

MARKER = "FAILED.json"
REFUSED = "FAILED.job*.json"  # in the sweep directory: jobs refused in a directory that held a run
REPORT = "failed_jobs.txt"
LAST_SWEEP: dict[str, Any] = {}  # the sweep of this process: {"dir": Path, "start": float}


def report_failures(sweep_dir: Path, since: float = 0.0) -> list[str]:
    """Lines ``<run dir>  [overrides]  error`` for the jobs of ``sweep_dir`` that failed after ``since``."""
    lines = []
    for marker in sorted(sweep_dir.rglob(MARKER)) + sorted(sweep_dir.glob(REFUSED)):
        if marker.stat().st_mtime < since:
            continue
        info = json.loads(marker.read_text())
        run_dir = info.get("run_dir", marker.parent)
        lines.append(f"{run_dir}  [{' '.join(info['overrides'])}]  {' '.join(info['error'].split())}")
    report = sweep_dir / REPORT
    if lines:
        report.write_text("\n".join(lines) + "\n")
    else:
        report.unlink(missing_ok=True)
    return lines


class FailureReport(Callback):
    """Marks failed jobs and remembers the sweep directory (see the module docstring)."""

    def __init__(self) -> None:
        self._held_run = False  # whether the current job's directory held a run before the job

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        LAST_SWEEP.update({"dir": Path(config.hydra.sweep.dir), "start": time.time() - 1.0})

    def on_job_start(self, config: DictConfig, **kwargs: Any) -> None:
        self._held_run = holds_run(Path(config.hydra.runtime.output_dir))

    def on_job_end(self, config: DictConfig, job_return: JobReturn, **kwargs: Any) -> None:
        out = Path(config.hydra.runtime.output_dir)
        if job_return.status != JobStatus.FAILED:
            (out / MARKER).unlink(missing_ok=True)
            return
        error = job_return._return_value
        info = {"error": f"{type(error).__name__}: {error}", "overrides": list(job_return.overrides or [])}
        if not (self._held_run and isinstance(error, (ConfigError, RunDirectoryError))):
            (out / MARKER).write_text(json.dumps(info, indent=2))
        elif config.hydra.mode == RunMode.MULTIRUN:  # refused in another run's directory: leave it as it was
            marker = Path(config.hydra.sweep.dir) / REFUSED.replace("*", str(config.hydra.job.num))
            marker.write_text(json.dumps({**info, "run_dir": str(out)}, indent=2))

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        report_failures(Path(config.hydra.sweep.dir), LAST_SWEEP.get("start", 0.0))
