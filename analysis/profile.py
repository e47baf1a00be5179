"""Where a run spent its wall time, by part: ``python -m analysis.profile RUN_DIR [RUN_DIR ...]``.

Reads ``metrics.csv`` (the ``timing/*`` columns are per-call means over each logging window), ``summary.json`` and
``.hydra/config.yaml``. Calls per window are known from the config (training every ``budget.train_every`` steps after
the warm-up, planning every step after it, a memory refresh every ``memory_refresh_every`` steps), so each part's
total is Σ_windows mean × calls; the rest of the wall time is the environment, rendering, logging and bookkeeping.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

PARTS = {"training": "timing/train_ms", "planning": "timing/plan_ms", "memory refresh": "timing/refresh_ms"}


def _calls(steps: np.ndarray, warmup: int, every: int) -> np.ndarray:
    """Calls per window (previous row's step, step] of an event due at 1-based steps s >= warmup with
    (s - warmup) % every == 0."""
    def upto(s: np.ndarray) -> np.ndarray:
        return np.where(s >= warmup, (s - warmup) // every + 1, 0)

    prev = np.concatenate([[0], steps[:-1]])
    return upto(steps) - upto(prev)


def profile(run_dir: str | Path) -> dict[str, float]:
    """Seconds per part and in total for one run directory."""
    run_dir = Path(run_dir)
    df = pd.read_csv(run_dir / "metrics.csv")
    cfg = yaml.safe_load((run_dir / ".hydra" / "config.yaml").read_text())
    wall = json.loads((run_dir / "summary.json").read_text())["wall_seconds"]
    steps = df["step"].to_numpy()
    warmup = cfg["budget"]["warmup_steps"]
    every = {"training": cfg["budget"]["train_every"], "planning": 1, "memory refresh": cfg.get("memory_refresh_every", 1)}
    start = {"training": warmup, "planning": warmup + 1, "memory refresh": warmup}
    out = {}
    for part, column in PARTS.items():
        if column in df:
            out[part] = float((df[column].fillna(0).to_numpy() * _calls(steps, start[part], every[part])).sum() / 1e3)
    out["env, rendering and the rest"] = wall - sum(out.values())
    out["total"] = wall
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_dirs", nargs="+")
    for run_dir in parser.parse_args().run_dirs:
        parts = profile(run_dir)
        print(run_dir)
        for part, seconds in parts.items():
            print(f"  {part:30s} {seconds:8.1f} s  {100 * seconds / parts['total']:5.1f} %")


if __name__ == "__main__":
    main()
