"""``summary.json``: what a run achieved, and which code and config produced it."""

from __future__ import annotations

import json
import os
import subprocess
from dataclasses import asdict, dataclass, field
from typing import Any
from pathlib import Path

_REPO = Path(__file__).resolve().parents[2]


def git_commit(repo: Path = _REPO) -> tuple[str, bool]:
    """(HEAD commit, whether tracked files differ from it) of the checkout holding this package, or ("unknown", False)."""
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=repo, capture_output=True, text=True, check=True).stdout
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"], cwd=repo, capture_output=True, text=True, check=True
        ).stdout
    except (OSError, subprocess.CalledProcessError):
        return "unknown", False
    return head.strip(), bool(dirty.strip())


@dataclass
class RunSummary:
    """The fields of ``summary.json``.

    ``steps_to_goal`` counts every env step, random warm-up included, up to and including the step that reached the
    goal; it is ``None`` when the goal was not reached within ``max_steps`` (a censored run).
    ``planner_sampled_candidates`` is the number of action sequences the MPC planner sampled per step when it could
    not score all of them (``planner.sample_candidates=true``); ``None`` when it scored every one. ``behaviour`` and
    ``agent`` are absent from runs made before they existed. ``episode_resets`` counts the env resets: terminations that
    were not the goal (none on Acrobot and MountainCar, whose only termination is the goal) and, when the run goes on
    past the goal (``budget.stop_at_goal=false``), the goals. ``goals`` counts the times the goal was reached (absent
    from runs made before it existed); ``steps_to_goal`` is always the first. ``machine`` is the CPU and torch build
    that finished the run (:mod:`curiosity.runtime.machine`; a run resumed on another machine was partly made by that
    one): the same config and seed repeat exactly only on the same machine. ``cpu_seconds`` is the CPU time of the run's
process over the loop (``time.process_time``: every thread, start-up excluded as in ``wall_seconds``), summed over its
resumes; ``None`` for runs made before it existed or resumed from a checkpoint without it.
    """

    method: str
    seed: int
    env: str
    steps_to_goal: int | None
    reached_goal: bool
    env_steps: int
    max_steps: int
    warmup_steps: int
    final_coverage: float
    wall_seconds: float
    steps_per_second: float
    git_commit: str
    git_dirty: bool
    planner_sampled_candidates: int | None = None
    behaviour: dict[str, Any] | None = None  # BehaviourTracker.summary(): action frequencies, repeat and directed rates
    agent: dict[str, Any] = field(default_factory=dict)  # the agent's own run totals (Agent.summary())
    episode_resets: int = 0  # env resets: non-goal terminations, and goals when the run goes on past them
    goals: int | None = None  # times the goal was reached (None: a run made before the field existed)
    machine: dict[str, Any] | None = None  # curiosity.runtime.machine.machine() (None: a run made before it existed)
    cpu_seconds: float | None = None  # the run's CPU time (process_time, every thread), resumes summed; None: unknown

    def write(self, run_dir: str | Path) -> Path:
        """Write ``summary.json`` atomically (temporary file + rename)."""
        path = Path(run_dir) / "summary.json"
        tmp = path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(asdict(self), indent=2) + "\n")
        os.replace(tmp, path)
        return path
