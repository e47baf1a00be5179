"""The env-step loop of one run: warm-up, act, observe, log, checkpoint, resume, summarise."""

from __future__ import annotations

import json
import logging
import signal
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from hydra.utils import get_object
from omegaconf import DictConfig, OmegaConf
from tqdm import tqdm

from curiosity.agents.base import Agent
from curiosity.config import ConfigError, build, sampled_candidates, validate
from curiosity.config.compose import LEGACY
from curiosity.envs import GridCoverage, make_env
from curiosity.envs.adapter import adapter_of
from curiosity.envs.distractor import find_tv
from curiosity.envs.state import env_state, restore_env
from curiosity.errors import NumericalFault, RunDirectoryError
from curiosity.runtime.allocator import keep_freed_memory
from curiosity.runtime.behaviour import BehaviourTracker
from curiosity.runtime.checkpoint import (
    RunLock,
    keep_checkpoint,
    load_checkpoint,
    rng_states,
    save_checkpoint,
    set_rng_states,
)
from curiosity.runtime.logger import RunLogger
from curiosity.runtime.machine import machine
from curiosity.runtime.seeding import seed_everything
from curiosity.runtime.summary import RunSummary, git_commit

log = logging.getLogger(__name__)

CHART_KEYS = ("charts/coverage", "charts/wall_time", "charts/sps", "charts/extrinsic_reward", "intrinsic/reward")
# Keys that do not change what a run computes: a run may resume with other values of them.
VOLATILE_KEYS = ("progress", "threads", "device", "resume", "checkpoint_every", "checkpoint_keep")


class Interrupted(KeyboardInterrupt):
    """The run was stopped by SIGTERM/SIGINT after writing a checkpoint; re-run the same command to resume it.

    A ``KeyboardInterrupt``, so a local sweep stops too instead of going on with its next job. Its message is the one
    line the command prints; ``signum`` gives the exit status (128 + signum)."""

    def __init__(self, signum: int, step: int) -> None:
        self.signum, self.step = signum, step
        super().__init__(f"interrupted at step {step}, checkpoint written; run the same command again to resume")


def check_built(cfg: DictConfig) -> None:
    """Fail with a clear message when the chosen agent's code does not exist (yet)."""
    target = cfg.baseline._target_
    try:
        get_object(target)
    except (ImportError, AttributeError, ValueError) as err:
        raise ConfigError(f"baseline={cfg.baseline.name}: {target} is not built yet ({err})") from err


def identity(cfg: DictConfig) -> dict[str, Any]:
    """The resolved config without :data:`VOLATILE_KEYS`: two runs with equal identities compute the same thing."""
    container = OmegaConf.to_container(cfg, resolve=True, enum_to_str=True)
    assert isinstance(container, dict)
    return {k: v for k, v in container.items() if k not in VOLATILE_KEYS}


_MISSING = object()


def _differences(saved: dict[str, Any], now: dict[str, Any], prefix: str = "") -> list[str]:
    """``key: <saved> there, <now> now`` for every key whose values differ. A key the checkpoint's run did not have
    yet, set now to the value that reproduces what such a run did (``LEGACY``), is no difference: that run resumes."""
    out = []
    for key in sorted(set(saved) | set(now)):
        a, b = saved.get(key, _MISSING), now.get(key, _MISSING)
        if a is _MISSING and isinstance(b, dict) and any(k.startswith(f"{prefix}{key}.") for k in LEGACY):
            a = {}  # a node added since: each of its keys is checked against LEGACY
        if isinstance(a, dict) and isinstance(b, dict):
            out += _differences(a, b, f"{prefix}{key}.")
        elif a is _MISSING and f"{prefix}{key}" in LEGACY and str(b) == str(LEGACY[f"{prefix}{key}"]):
            continue
        elif a != b:
            out.append(f"{prefix}{key}: {None if a is _MISSING else a!r} there, {None if b is _MISSING else b!r} now")
    return out


FINISHED = {"finished": True}  # what existing_checkpoint returns for a complete run kept without its checkpoint


def _saved_identity(run_dir: Path) -> dict[str, Any] | None:
    """The identity of the config in ``run_dir/.hydra/config.yaml``; None when there is none or it cannot be read."""
    path = run_dir / ".hydra" / "config.yaml"
    try:
        return identity(OmegaConf.load(path))  # type: ignore[arg-type]
    except Exception:  # missing, unparsable or unresolvable: not a run this one can recognise
        return None


def _finished_without_checkpoint(cfg: DictConfig, run_dir: Path) -> bool:
    """Whether ``run_dir`` holds this configuration's complete run with its checkpoint removed (committed results keep
    ``.hydra/``, ``metrics.csv`` and ``summary.json`` only). A complete run of another configuration is refused."""
    saved = _saved_identity(run_dir) if (run_dir / "summary.json").exists() else None
    if saved is None:
        return False
    diff = _differences(saved, identity(cfg))
    if diff:
        raise RunDirectoryError(f"{run_dir} holds a finished run of another configuration ({', '.join(diff[:5])}); it "
                                "is not overwritten; allowed: that run's configuration, or another run directory")  # fmt: skip
    return True


def existing_checkpoint(cfg: DictConfig, run_dir: Path) -> dict[str, Any] | None:
    """The checkpoint to resume from, :data:`FINISHED` for this configuration's complete run kept without its
    checkpoint, None for a fresh directory; refuses anything else."""
    ckpt = load_checkpoint(run_dir)
    if ckpt is None:
        if (run_dir / "metrics.csv").exists():
            if _finished_without_checkpoint(cfg, run_dir):
                if not cfg.resume:
                    raise RunDirectoryError(f"resume=false: {run_dir} holds this configuration's finished run, not "
                                            "overwritten; allowed: resume=true (reports that run), or another run "
                                            "directory")  # fmt: skip
                return FINISHED
            raise RunDirectoryError(f"{run_dir} already holds a run without a checkpoint; it is not overwritten; "
                                    "allowed: another run directory (hydra.run.dir)")  # fmt: skip
        return None
    if not cfg.resume:
        raise RunDirectoryError(f"resume=false: {run_dir} holds a checkpoint at step {ckpt['step']}, not overwritten; "
                                "allowed: resume=true (resumes or completes that run), or another run directory")  # fmt: skip
    diff = _differences(ckpt["config"], identity(cfg))
    if diff:
        raise RunDirectoryError(f"{run_dir} holds a run of another configuration ({', '.join(diff[:5])}); not resuming "
                                "it; allowed: that run's configuration (resumes it), or another run directory")  # fmt: skip
    return ckpt


def run(cfg: DictConfig, run_dir: str | Path, on_start: Callable[[], None] | None = None) -> RunSummary:
    """Run one experiment into ``run_dir`` (resuming it from its checkpoint if there is one) and return its summary.

    Validates the config before anything is built. The first ``budget.warmup_steps`` actions are uniformly random;
    every step counts towards steps-to-goal. A checkpoint is written every ``checkpoint_every`` env steps, at the end,
    and on SIGTERM/SIGINT; re-running the same command resumes from it. ``on_start`` is called once the directory is
    locked and checked, before a run starts or resumes (not for a complete run): nothing is written before.
    """
    validate(cfg)
    check_built(cfg)
    run_dir = Path(run_dir)
    with RunLock(run_dir):
        ckpt = existing_checkpoint(cfg, run_dir)
        if ckpt is not None and ckpt["finished"]:
            summary = RunSummary(**json.loads((run_dir / "summary.json").read_text()))
            log.info("%s seed=%d: already complete in %s", summary.method, summary.seed, run_dir)
            return summary
        if on_start is not None:
            on_start()
        summary = _Run(cfg, run_dir, ckpt).execute()
    goal = f"goal at step {summary.steps_to_goal}" if summary.reached_goal else "goal not reached"
    log.info(
        "%s seed=%d %s: %s (cap %d), coverage %.4f, %.1f s, %.0f steps/s -> %s",
        summary.method, summary.seed, summary.env, goal, summary.max_steps, summary.final_coverage,
        summary.wall_seconds, summary.steps_per_second, run_dir,
    )  # fmt: skip
    return summary


class _Run:
    """The state of one run in progress: env, agent, logger, coverage and the loop's own counters."""

    def __init__(self, cfg: DictConfig, run_dir: Path, ckpt: dict[str, Any] | None) -> None:
        self.cfg, self.run_dir = cfg, run_dir
        keep_freed_memory()  # no page faults on every iteration's activations (curiosity/runtime/allocator.py)
        seed_everything(cfg.seed, deterministic=cfg.deterministic, threads=cfg.threads)
        self.env = make_env(cfg.env, cfg.budget.max_steps)
        self.adapter = adapter_of(cfg.env)
        self.agent: Agent = build(cfg.baseline, cfg=cfg)
        self.agent.attach_env(self.env)
        tv = find_tv(self.env)
        self.behaviour = BehaviourTracker(int(self.env.action_space.n), self.adapter.directed_action,
                                          tv.tv_action if tv is not None else None)  # fmt: skip
        self.coverage = GridCoverage(cfg.env.coverage_low, cfg.env.coverage_high, cfg.env.coverage_bins)
        self.rng = np.random.default_rng(cfg.seed)
        self.step, self.steps_to_goal, self.wall_before, self.resets, self.goals = 0, None, 0.0, 0, 0
        self.cpu_before: float | None = 0.0  # None: resumed from a checkpoint made before CPU time was kept
        self.stop_signal: int | None = None
        self._start: float | None = None  # perf_counter at the start of execute()
        self._cpu_start: float | None = None  # process_time at the start of execute()
        columns = [*CHART_KEYS, *self.behaviour.keys, *self.agent.metric_keys]
        if ckpt is None:
            self.obs, _ = self.env.reset(seed=cfg.seed)
            self.env.action_space.seed(cfg.seed)
            self.coverage.update(self.adapter.physical_state(self.env))
            self.logger = RunLogger(run_dir, columns)
            self.logger.text("config", "```yaml\n" + OmegaConf.to_yaml(cfg, resolve=True) + "```")
            self.save(finished=False)  # step 0: a killed run always has something to resume from
        else:
            self._restore(ckpt, columns)

    def _restore(self, ckpt: dict[str, Any], columns: list[str]) -> None:
        restore_env(self.env, ckpt["env"], self.cfg.seed, self.adapter)
        self.resets = int(ckpt.get("resets", 0))
        self.goals = int(ckpt.get("goals", ckpt["steps_to_goal"] is not None))  # a checkpoint made before the count
        self.agent.load_state_dict(ckpt["agent"])
        self.coverage.load_state_dict(ckpt["coverage"])
        self.behaviour.load_state_dict(ckpt["behaviour"])
        self.rng.bit_generator.state = ckpt["loop_rng"]
        set_rng_states(ckpt["rng"])
        self.obs, self.step, self.steps_to_goal = ckpt["obs"], int(ckpt["step"]), ckpt["steps_to_goal"]
        self.wall_before = float(ckpt["wall_seconds"])
        self.cpu_before = None if ckpt.get("cpu_seconds") is None else float(ckpt["cpu_seconds"])
        self.logger = RunLogger(self.run_dir, columns, resume=ckpt["logger"])
        log.info("resuming %s from its checkpoint at env step %d", self.run_dir, self.step)

    def save(self, finished: bool) -> None:
        """Checkpoint everything the rest of the run depends on (atomically)."""
        save_checkpoint(self.run_dir, {
            "config": identity(self.cfg), "step": self.step, "finished": finished, "obs": self.obs,
            "steps_to_goal": self.steps_to_goal, "env": env_state(self.env, self.adapter), "resets": self.resets,
            "goals": self.goals,
            "agent": self.agent.state_dict(),
            "coverage": self.coverage.state_dict(), "behaviour": self.behaviour.state_dict(),
            "loop_rng": self.rng.bit_generator.state, "rng": rng_states(), "logger": self.logger.state_dict(),
            "wall_seconds": self._wall(), "cpu_seconds": self._cpu(),
        })  # fmt: skip

    def _wall(self) -> float:
        return self.wall_before + (0.0 if self._start is None else time.perf_counter() - self._start)

    def _cpu(self) -> float | None:
        """CPU seconds of this run's process (every thread) inside ``execute``, summed over resumes; None if unknown."""
        if self.cpu_before is None:
            return None
        return self.cpu_before + (0.0 if self._cpu_start is None else time.process_time() - self._cpu_start)

    def _on_signal(self, signum: int, frame: object) -> None:
        self.stop_signal = signum

    def execute(self) -> RunSummary:
        self._start, self._cpu_start = time.perf_counter(), time.process_time()
        handlers = {}
        for sig in (signal.SIGTERM, signal.SIGINT):
            try:
                handlers[sig] = signal.signal(sig, self._on_signal)
            except ValueError:  # not the main thread: no signal handling
                pass
        try:
            self._loop()
            summary = self._summary()
            summary.write(self.run_dir)
            self.save(finished=True)
        finally:
            for sig, handler in handlers.items():
                signal.signal(sig, handler)
            self.logger.close()
            self.env.close()
        return summary

    def _loop(self) -> None:
        cfg, budget = self.cfg, self.cfg.budget
        bar = tqdm(total=budget.max_steps, initial=self.step, unit="step", desc=f"{cfg.method_label} seed={cfg.seed}",
                   disable=not cfg.progress)  # fmt: skip
        try:
            while self.step < budget.max_steps and (self.steps_to_goal is None or not budget.stop_at_goal):
                try:
                    goal = self._step()
                except NumericalFault as fault:  # stop; keep the last good checkpoint; no NaN row was written
                    raise NumericalFault(fault.term, fault.value, self.step + 1) from None
                self.step += 1
                if goal:
                    self.goals += 1
                    self.steps_to_goal = self.steps_to_goal or self.step  # the first time counts
                done = (goal and budget.stop_at_goal) or self.step == budget.max_steps
                if self.step % cfg.log_every == 0 or done:
                    self._dump()
                    bar.set_postfix(coverage=f"{self.coverage.fraction:.4f}", refresh=False)
                    bar.update(self.step - bar.n)
                if self.step % cfg.checkpoint_every == 0 and not done:
                    self.save(finished=False)
                    if cfg.checkpoint_keep:
                        keep_checkpoint(self.run_dir, self.step)
                if self.stop_signal is not None and not done:
                    self.save(finished=False)
                    raise Interrupted(self.stop_signal, self.step)
        finally:
            bar.close()

    def _step(self) -> bool:
        """One env step (``self.step`` is its 0-based index); returns whether it reached the goal.

        A termination that is not the goal (the adapter's predicate) is a terminal transition for the agent; the env
        is then reset and the run goes on from the new episode's first observation. So is the goal itself when the run
        goes on past it (``budget.stop_at_goal=false``)."""
        step = self.step
        if step < self.cfg.budget.warmup_steps:
            action = int(self.rng.integers(self.env.action_space.n))
        else:
            action = self.agent.act(self.obs, step)
            self.logger.record_many(self.behaviour.record(action, self.adapter.physical_state(self.env)))
        next_obs, reward, terminated, _, info = self.env.step(action)
        goal = self.adapter.goal_reached(self.env, bool(terminated), info)
        self.logger.record_many(self.agent.observe(self.obs, action, float(reward), next_obs, bool(terminated), step))
        self.logger.record("charts/extrinsic_reward", float(reward))
        self.coverage.update(self.adapter.physical_state(self.env))
        self.obs = next_obs
        if terminated and (not goal or not self.cfg.budget.stop_at_goal):
            self.obs, _ = self.env.reset()
            self.resets += 1
            self.coverage.update(self.adapter.physical_state(self.env))
        return goal

    def _dump(self) -> None:
        elapsed = self._wall()
        self.logger.record_many({"charts/coverage": self.coverage.fraction, "charts/wall_time": elapsed,
                                 "charts/sps": self.step / max(elapsed, 1e-9)})  # fmt: skip
        self.logger.dump(self.step)

    def _summary(self) -> RunSummary:
        wall = self._wall()
        commit, dirty = git_commit()
        budget = self.cfg.budget
        return RunSummary(
            method=self.cfg.method_label, seed=int(self.cfg.seed), env=self.cfg.env.id, steps_to_goal=self.steps_to_goal,
            reached_goal=self.steps_to_goal is not None, env_steps=self.step, max_steps=budget.max_steps,
            warmup_steps=budget.warmup_steps, final_coverage=self.coverage.fraction, wall_seconds=wall,
            steps_per_second=self.step / max(wall, 1e-9), cpu_seconds=self._cpu(), git_commit=commit, git_dirty=dirty,
            planner_sampled_candidates=sampled_candidates(self.cfg),
            behaviour=self.behaviour.summary(), agent=self.agent.summary(), episode_resets=self.resets, goals=self.goals,
            machine=machine(),
        )  # fmt: skip
