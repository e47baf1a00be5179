"""Whole-run measurements of the benchmark: a sweep with one vs two joblib jobs, and single seeds with wall time by
part (env + render, encode, plan, novelty, refresh, train, logging, checkpoint)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from omegaconf import DictConfig, OmegaConf

import curiosity.runtime.loop as loop
from curiosity.config.compose import compose_config
from curiosity.runtime.logger import RunLogger
from runners.benchmark.timing import PartTimer

REPO = Path(__file__).resolve().parents[2]


def sweep_seconds(n_jobs: int, jobs: int, overrides: Sequence[str], sweep_dir: Path) -> float:
    """Wall seconds of ``python -m runners.train -m seed=0-(jobs-1)`` with ``n_jobs`` joblib workers, one torch
    thread each."""
    cmd = [sys.executable, "-m", "runners.train", "-m", f"seed=0-{jobs - 1}", "progress=false", "threads=1",
           "hydra/launcher=joblib", f"hydra.launcher.n_jobs={n_jobs}", f"hydra.sweep.dir={sweep_dir}", *overrides]  # fmt: skip
    env = {**os.environ, "OMP_NUM_THREADS": "1", "SDL_VIDEODRIVER": "dummy"}
    start = time.perf_counter()
    done = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, check=False)
    if done.returncode:
        raise RuntimeError(f"the sweep failed:\n{done.stderr[-2000:]}")
    return time.perf_counter() - start


def sweep_speedup(overrides: Sequence[str], jobs: int = 4) -> dict[str, float]:
    """Wall time of a ``jobs``-job sweep with 1 and with 2 joblib workers, and the speed-up of 2 over 1."""
    with tempfile.TemporaryDirectory() as tmp:
        one = sweep_seconds(1, jobs, overrides, Path(tmp) / "one")
        two = sweep_seconds(2, jobs, overrides, Path(tmp) / "two")
    return {"jobs": jobs, "one_job_s": one, "two_jobs_s": two, "speedup": one / two}


def _instrument(timer: PartTimer) -> None:
    """Time the parts of every run made by ``curiosity.runtime.loop`` until ``timer.restore()``."""
    make_env, build = loop.make_env, loop.build

    def timed_env(*args: Any, **kwargs: Any) -> Any:
        env = make_env(*args, **kwargs)
        timer.wrap(env, "step", "env+render")
        return env

    def timed_agent(*args: Any, **kwargs: Any) -> Any:
        agent = build(*args, **kwargs)
        for method, part in (("encode_obs", "encode"), ("_plan", "plan"), ("_train", "train")):
            if hasattr(agent, method):
                timer.wrap(agent, method, part)
        diagnostics = getattr(agent, "diagnostics", None)  # the paper agent's score noise and model probe
        if diagnostics is not None:
            timer.wrap(diagnostics, "after_plan", "diagnostics")
        intrinsic = getattr(agent, "intrinsic", None)  # the intrinsic reward (random has none)
        if intrinsic is not None:
            for method in ("imagined_terms", "compute_terms", "observe"):
                timer.wrap(intrinsic, method, "novelty")
        novelty = getattr(agent, "novelty", None)  # its latent novelty term, whose refresh is timed apart
        if novelty is not None:
            timer.wrap(novelty, "refresh", "refresh")
        return agent

    timer.replace(loop, "make_env", timed_env)
    timer.replace(loop, "build", timed_agent)
    timer.wrap(loop, "save_checkpoint", "checkpoint")
    for method in ("dump", "record", "record_many"):
        timer.wrap(RunLogger, method, "logging")


def write_config(cfg: DictConfig, overrides: list[str], run_dir: Path) -> None:
    """``.hydra/config.yaml`` and ``overrides.yaml`` of a run the benchmark makes in-process (as a Hydra job would), so
    the analysis commands read it like any run."""
    out = run_dir / ".hydra"
    out.mkdir(parents=True, exist_ok=True)
    (out / "config.yaml").write_text(OmegaConf.to_yaml(cfg), encoding="utf-8")
    (out / "overrides.yaml").write_text(OmegaConf.to_yaml(OmegaConf.create(list(overrides))), encoding="utf-8")


def seed_runs(seeds: Sequence[int], overrides: Sequence[str], out_dir: Path) -> list[dict[str, Any]]:
    """Run the configured agent once per seed, alone, in this process, each into ``out_dir/default/seed=<n>`` (resumed
    if already there); return each seed's steps-to-goal, wall and CPU seconds (``summary.json``'s ``wall_seconds`` and
    ``cpu_seconds``, None where a run resumed from before it had none) and wall share by part."""
    rows = []
    for seed in seeds:
        run_dir = out_dir / "default" / f"seed={seed}"  # the layout of a run, so the analysis names its command
        timer = PartTimer()
        _instrument(timer)
        args = [*overrides, f"seed={seed}", "progress=false"]
        cfg = compose_config(args)
        try:
            summary = loop.run(cfg, run_dir, on_start=lambda c=cfg, a=args, d=run_dir: write_config(c, a, d))
        finally:
            timer.restore()
        saved = json.loads((run_dir / "summary.json").read_text())
        rows.append({"seed": seed, "steps_to_goal": saved["steps_to_goal"], "wall_s": saved["wall_seconds"],
                     "cpu_s": saved.get("cpu_seconds"),
                     "wall_share": timer.shares(max(summary.wall_seconds, 1e-9)) if timer.seconds else {}})  # fmt: skip
    return rows
