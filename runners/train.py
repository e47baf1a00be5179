"""Train one agent in one environment: ``python -m runners.train [group=option ...] [key=value ...]``.

``-m`` sweeps with any Hydra launcher; ``seed=0-3`` is an inclusive alias for Hydra's ``seed=range(0,4)``.
A refused command line prints one line (``error: <key>=<value>: ... allowed: ...``), exits with status 2 and
changes nothing on disk; SIGTERM/SIGINT checkpoint the run and exit with 128 + the signal number.
"""

from __future__ import annotations

import signal
import sys
from typing import NoReturn

import hydra
from omegaconf import DictConfig

from curiosity.config import setup
from curiosity.config.ranges import RangeError, expand_ranges
from curiosity.errors import RunError
from curiosity.runtime.callbacks import LAST_SWEEP, REPORT, report_failures
from curiosity.runtime.preflight import preflight

setup()

REFUSED = 2  # exit status of a refused command line


@hydra.main(version_base="1.3", config_path="../conf", config_name="config")
def main(cfg: DictConfig) -> float | None:
    """Run one job into its Hydra output directory; returns steps-to-goal (None when the cap was hit)."""
    from curiosity.runtime.job import run_job  # torch and the agents: imported once the command line is accepted

    return run_job(cfg)


def _refuse(message: object) -> NoReturn:
    """Print the one line of a refusal and exit with :data:`REFUSED`."""
    print(f"error: {message}", file=sys.stderr)
    raise SystemExit(REFUSED)


def cli() -> None:
    """Entry point: expand integer ranges in ``sys.argv``, check the command line, then hand over to Hydra."""
    try:
        sys.argv = expand_ranges(sys.argv)
        preflight(sys.argv[1:])
    except (RangeError, RunError) as err:
        _refuse(err)
    try:
        main()
    except KeyboardInterrupt as stop:  # the loop's Interrupted (after a checkpoint), or Ctrl-C before the loop began
        print(str(stop) or "interrupted before the run started; run the same command again", file=sys.stderr)
        raise SystemExit(128 + getattr(stop, "signum", signal.SIGINT)) from None
    except SystemExit as exit_:
        if exit_.code and LAST_SWEEP:
            failed = report_failures(LAST_SWEEP["dir"], LAST_SWEEP["start"])
            if failed:
                print(f"error: {len(failed)} job(s) of this sweep failed (also in {LAST_SWEEP['dir'] / REPORT}):",
                      *failed, sep="\n  ", file=sys.stderr)  # fmt: skip
        raise


if __name__ == "__main__":
    cli()
