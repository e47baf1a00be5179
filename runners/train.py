"""Train one agent in one environment: ``python -m runners.train [group=option ...] [key=value ...]``.

``-m`` sweeps with any Hydra launcher; ``seed=0-3`` is an inclusive alias for Hydra's ``seed=range(0,4)``.
"""

from __future__ import annotations

import sys

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from curiosity.config import setup
from curiosity.config.ranges import RangeError, expand_ranges
from curiosity.runtime.callbacks import LAST_SWEEP, REPORT, report_failures
from curiosity.runtime.loop import run

setup()


@hydra.main(version_base="1.3", config_path="../conf", config_name="config")
def main(cfg: DictConfig) -> float | None:
    """Run one job into its Hydra output directory; returns steps-to-goal (None when the cap was hit)."""
    summary = run(cfg, HydraConfig.get().runtime.output_dir)
    return summary.steps_to_goal


def cli() -> None:
    """Entry point: expand integer ranges in ``sys.argv``, then hand over to Hydra."""
    try:
        sys.argv = expand_ranges(sys.argv)
    except RangeError as err:
        print(f"error: {err}", file=sys.stderr)
        raise SystemExit(2) from err
    try:
        main()
    except SystemExit as exit_:
        if exit_.code and LAST_SWEEP:
            failed = report_failures(LAST_SWEEP["dir"], LAST_SWEEP["start"])
            if failed:
                print(f"error: {len(failed)} job(s) of this sweep failed (also in {LAST_SWEEP['dir'] / REPORT}):",
                      *failed, sep="\n  ", file=sys.stderr)  # fmt: skip
        raise


if __name__ == "__main__":
    cli()
