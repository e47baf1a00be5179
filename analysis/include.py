"""Runs one results directory lends another: the ``include`` setting of ``RUNS_DIR/analysis.yaml``.

Two presets often share a configuration: Figure 6's Gaussian-potential arm is Table 1's default agent on the same
seeds, and the hybrid claim's three rows are the noisy-TV test's rows without the TV. ``include`` lists globs (relative
to RUNS_DIR) of finished run directories made elsewhere; the analysis reads them as if they were below RUNS_DIR, so
each such run is made once and counted in every table that needs it. A run below RUNS_DIR wins over an included run of
the same configuration and seed (re-running the preset there replaces nothing and counts nothing twice). An included
directory's own ``include`` is not followed.
"""

from __future__ import annotations

import glob
import json
import os
from pathlib import Path

from analysis.runconfig import IGNORED, flat_config
from analysis.settings import SETTINGS, settings


def _patterns(root: Path) -> list[str]:
    found = settings(root).get("include", [])
    if not isinstance(found, list) or not all(isinstance(p, str) and p for p in found):
        raise ValueError(f"{root / SETTINGS}: include: {found!r} is not allowed; allowed: a list of globs, relative to "
                         f"{root}, naming finished run directories")  # fmt: skip
    return found


def _identity(run_dir: Path) -> tuple[object, ...]:
    """(seed, the run's resolved config without the bookkeeping keys): two runs with the same identity are the same
    experiment."""
    config = flat_config(run_dir)
    seed = json.loads((run_dir / "summary.json").read_text())["seed"]
    return (int(seed), *sorted((k, repr(v)) for k, v in config.items() if k not in IGNORED))


def included_runs(root: str | Path, local: list[Path]) -> list[Path]:
    """The finished run directories ``root``'s ``include`` names (each glob must match at least one), sorted, without
    those that repeat a run of ``local`` (the finished runs below ``root``). Raises ValueError on a bad setting."""
    root = Path(root)
    patterns = _patterns(root)
    if not patterns:
        return []
    found: set[Path] = set()
    for pattern in patterns:
        matched = {Path(os.path.normpath(m)).parent for m in glob.glob(os.path.join(root, pattern, "summary.json"))}
        if not matched:
            raise ValueError(f"{root / SETTINGS}: include: {pattern!r} matches no finished run directory (one holding "
                             f"summary.json) relative to {root}; allowed: globs naming finished run directories")  # fmt: skip
        found |= matched
    here = {Path(os.path.normpath(d)) for d in local}
    taken = {_identity(d) for d in local} if local else set()
    return sorted(d for d in found - here if _identity(d) not in taken)
