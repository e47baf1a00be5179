"""CPU seconds of whole seeds of the default agent, this tree beside another commit (``--seed-commit``).

Each seed runs as ``python -m runners.train seed=N threads=1 progress=false hydra.run.dir=...`` in a fresh process,
with its tree as the working directory and ``PYTHONPATH`` (the commit's own code, through a temporary ``git
worktree``), the two trees alternating seed by seed so a change of machine load hits both. Both are measured the same
way: the child process's CPU time (user + system, the ``getrusage(RUSAGE_CHILDREN)`` delta around it), start-up
included; an older commit's ``summary.json`` has no ``cpu_seconds``. CPU time is less sensitive than wall time to
other jobs on the machine.

Run directories go to ``<out>/seed_cpu/<tree>/seed=<n>`` and each finished one keeps its measurement in
``bench_cpu.json``: re-running skips those; a run without it (interrupted) starts over, since the CPU time of its
first part is lost.
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from runners.benchmark.baseline import REPO, worktree

RECORD = "bench_cpu.json"
THIS_TREE = "this_tree"


def child_cpu_seconds(cmd: Sequence[str], cwd: Path, env: dict[str, str]) -> tuple[float, float]:
    """Run ``cmd`` to its end; (CPU seconds of the child and its waited-for descendants, user + system; wall seconds).
    A failed command raises ``RuntimeError`` with the end of its stderr."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(list(cmd), cwd=cwd, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode:
        raise RuntimeError(f"{' '.join(cmd[2:4])} in {cwd} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), wall


def train_seed(tree: Path, seed: int, overrides: Sequence[str], run_dir: Path) -> dict[str, Any]:
    """One seed of ``tree``'s default agent into ``run_dir`` (skipped when its ``bench_cpu.json`` is there, started
    over when the directory holds an unfinished run); returns and records seed, cpu_s, wall_s and steps_to_goal."""
    record = run_dir / RECORD
    if record.exists():
        return json.loads(record.read_text())
    if run_dir.exists():
        shutil.rmtree(run_dir)
    cmd = [sys.executable, "-m", "runners.train", f"seed={seed}", "threads=1", "progress=false",
           f"hydra.run.dir='{run_dir}'", *overrides]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(tree), "OMP_NUM_THREADS": "1", "SDL_VIDEODRIVER": "dummy"}
    cpu, wall = child_cpu_seconds(cmd, tree, env)
    summary = json.loads((run_dir / "summary.json").read_text())
    row = {"seed": seed, "cpu_s": cpu, "wall_s": wall, "steps_to_goal": summary.get("steps_to_goal")}
    record.write_text(json.dumps(row))
    return row


def seed_cpu_vs(commit: str, seeds: Sequence[int], overrides: Sequence[str], out_dir: Path) -> dict[str, Any]:
    """CPU seconds of ``seeds`` of the default agent at ``commit`` and here, alternating (:func:`train_seed`).

    Returns:
        ``commit``, ``seeds``, ``overrides``, ``runs`` and ``baseline_runs`` (each seed's :func:`train_seed` row),
        ``cpu_s`` and ``baseline_cpu_s`` (medians over the seeds), ``speedup`` = baseline_cpu_s / cpu_s.
    """
    if not seeds:
        raise ValueError("the side-by-side seed CPU needs at least one seed")
    ours, theirs = [], []
    runs = {label: [out_dir / "seed_cpu" / label / f"seed={seed}" for seed in seeds] for label in (commit, THIS_TREE)}
    pending = any(not (d / RECORD).exists() for d in runs[commit])  # else no worktree: every run of it is recorded
    with worktree(commit, name="seed-cpu") if pending else contextlib.nullcontext(REPO) as tree:
        for seed, there, here in zip(seeds, runs[commit], runs[THIS_TREE], strict=True):
            theirs.append(train_seed(tree, seed, overrides, there))
            ours.append(train_seed(REPO, seed, overrides, here))
    here = statistics.median(r["cpu_s"] for r in ours)
    there = statistics.median(r["cpu_s"] for r in theirs)
    return {"commit": commit, "seeds": list(seeds), "overrides": list(overrides), "runs": ours, "baseline_runs": theirs,
            "cpu_s": here, "baseline_cpu_s": there, "speedup": there / here}  # fmt: skip


def seed_cpu_of(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """``seed_cpu_s_each`` (each in-process seed run's ``cpu_seconds``, None where its summary has none) and
    ``seed_cpu_s``, their median (None when any is unknown or there are no seeds)."""
    each = [r.get("cpu_s") for r in rows]
    known = [v for v in each if v is not None]
    return {"seed_cpu_s_each": each, "seed_cpu_s": statistics.median(known) if known and len(known) == len(each) else None}
