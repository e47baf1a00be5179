"""Which checkpoint of a run the diagnostics restore (``--step N …|all`` of ``analysis.landscape`` and
``analysis.probe``), and where their walk along the agent's policy starts and goes on after the goal."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from curiosity.config.compose import saved_config
from curiosity.runtime.checkpoint import kept_checkpoints
from curiosity.runtime.restore import RestoreError


def checkpoints_at(run_dir: Path, steps: list[str] | None) -> dict[int | None, Path | None]:
    """{step: kept checkpoint} for ``--step`` values (``["all"]``: every kept one; ``None``: ``{None: None}``, the
    run's last checkpoint). Only checkpoints from the end of the warm-up on: before it the agent has not acted (nor
    fitted its novelty) yet.

    Raises:
        RestoreError: one line naming the run, the value asked for and the steps allowed.
    """
    if steps is None:
        return {None: None}
    try:
        warmup = int(saved_config(run_dir).budget.warmup_steps)
    except Exception:  # no or an unreadable config: restore_run says so
        warmup = 0
    kept = {step: path for step, path in kept_checkpoints(run_dir).items() if step >= warmup}
    if steps == ["all"]:
        if not kept:
            raise RestoreError(f"{run_dir}: --step all: the run kept no checkpoints after its {warmup} warm-up steps "
                               "(kept every checkpoint_every steps when it ran with checkpoint_keep=true)")  # fmt: skip
        return dict(kept)
    out: dict[int | None, Path | None] = {}
    for value in steps:
        step = int(value) if value.isdigit() else None
        if step not in kept:
            allowed = ", ".join(map(str, kept)) or f"none after the {warmup} warm-up steps (checkpoint_keep=true)"
            raise RestoreError(f"{run_dir}: --step {value}: no kept checkpoint at that step; allowed: all, {allowed}")
        out[step] = kept[step]
    return out


def ended_at_goal(run_dir: Path, step: int) -> bool:
    """Whether the run reached the goal at the checkpoint's step (the env is terminal there), from its summary."""
    path = run_dir / "summary.json"
    if not path.is_file():
        return False
    summary = json.loads(path.read_text())
    return summary.get("steps_to_goal") == step  # None when it never reached it; a run past the goal was reset


def new_episode(env: Any, agent: Any) -> Any:
    """Reset ``env`` after the goal and drop the rest of the agent's committed sequence (it belongs to the episode
    that ended); returns the new first observation."""
    obs, _ = env.reset()
    agent.queue = []
    return obs


def walk_start(run_dir: Path, run: Any) -> Any:
    """The observation a diagnostic's walk starts from in a restored run (``restore_run``): the checkpoint's, or the
    start of a new episode when the checkpoint was taken at the goal (a terminal env)."""
    return new_episode(run.env, run.agent) if ended_at_goal(run_dir, run.step) else run.obs
