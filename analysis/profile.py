"""Where a run spent its wall time, by part: ``python -m analysis.profile DIR [DIR ...]``.

Reads ``metrics.csv`` (the ``timing/*`` columns are per-call means over each logging window), ``summary.json`` and
``.hydra/config.yaml``. Calls per window are known from the config (training every ``budget.train_every`` steps after
the warm-up, planning every step after it, a memory refresh every ``memory_refresh_every`` steps), so each part's
total is Σ_windows mean × calls; the rest of the wall time is the environment, rendering, logging and bookkeeping.
A DIR that is not a run directory (a sweep's root, say) profiles every run below it; an unfinished run (no
``summary.json``) is profiled up to its last ``metrics.csv`` row, with the wall time logged there.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from analysis.collect import all_run_dirs, existing_roots, last_step

PARTS = {"training": "timing/train_ms", "planning": "timing/plan_ms", "memory refresh": "timing/refresh_ms"}


def _calls(steps: np.ndarray, warmup: int, every: int) -> np.ndarray:
    """Calls per window (previous row's step, step] of an event due at 1-based steps s >= warmup with
    (s - warmup) % every == 0."""

    def upto(s: np.ndarray) -> np.ndarray:
        return np.where(s >= warmup, (s - warmup) // every + 1, 0)

    prev = np.concatenate([[0], steps[:-1]])
    return upto(steps) - upto(prev)


def profile(run_dir: str | Path) -> dict[str, float]:
    """Seconds per part and in total for one run directory (up to its last metrics row if it is unfinished)."""
    run_dir = Path(run_dir)
    df = pd.read_csv(run_dir / "metrics.csv")
    cfg = yaml.safe_load((run_dir / ".hydra" / "config.yaml").read_text())
    summary = run_dir / "summary.json"
    wall = json.loads(summary.read_text())["wall_seconds"] if summary.exists() else float(df["charts/wall_time"].iloc[-1])
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


def _runs(path: Path) -> list[Path]:
    """``path`` if it is a run directory that can be profiled, else every such run below it."""
    if (path / "metrics.csv").exists():
        return [path]
    return [p for p in all_run_dirs(path) if (p / "metrics.csv").exists() and (p / ".hydra" / "config.yaml").exists()]


def _print(run_dir: Path) -> None:
    if not (run_dir / ".hydra" / "config.yaml").exists() or len(pd.read_csv(run_dir / "metrics.csv")) == 0:
        print(f"{run_dir}\n  no profile: it has no .hydra/config.yaml or no metrics row yet")
        return
    parts = profile(run_dir)
    done = "" if (run_dir / "summary.json").exists() else f"  (unfinished: up to env step {last_step(run_dir)})"
    print(f"{run_dir}{done}")
    for part, seconds in parts.items():
        print(f"  {part:30s} {seconds:8.1f} s  {100 * seconds / max(parts['total'], 1e-9):5.1f} %")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dirs", nargs="+", help="run directories, or directories holding them (a sweep's root)")
    for path in existing_roots(parser.parse_args().dirs):
        runs = _runs(path)
        if not runs:
            print(f"error: {path}: no run below it has metrics.csv and .hydra/config.yaml; allowed: a run "
                  "directory, or a directory holding some", file=sys.stderr)  # fmt: skip
            raise SystemExit(1)
        for run_dir in runs:
            _print(run_dir)


if __name__ == "__main__":
    main()
