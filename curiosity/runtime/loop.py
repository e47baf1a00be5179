"""The env-step loop of one run: warm-up, act, observe, log, summarise."""

from __future__ import annotations

import logging
import time
from pathlib import Path

import numpy as np
from hydra.utils import get_object
from omegaconf import DictConfig, OmegaConf
from tqdm import tqdm

from curiosity.agents.base import Agent
from curiosity.config import ConfigError, build, validate
from curiosity.envs import GridCoverage, make_env, physical_state
from curiosity.runtime.logger import RunLogger
from curiosity.runtime.seeding import seed_everything
from curiosity.runtime.summary import RunSummary, git_commit

log = logging.getLogger(__name__)

CHART_KEYS = ("charts/coverage", "charts/wall_time", "charts/sps", "charts/extrinsic_reward", "intrinsic/reward")


def check_built(cfg: DictConfig) -> None:
    """Fail with a clear message when the chosen agent's code does not exist (yet)."""
    target = cfg.baseline._target_
    try:
        get_object(target)
    except (ImportError, AttributeError, ValueError) as err:
        raise ConfigError(f"baseline={cfg.baseline.name}: {target} is not built yet ({err})") from err


def run(cfg: DictConfig, run_dir: str | Path) -> RunSummary:
    """Run one experiment into ``run_dir`` and return its summary.

    Validates the config before anything is built, seeds everything, builds the env and the agent, then steps the
    one continuing episode until the goal or ``budget.max_steps``. The first ``budget.warmup_steps`` actions are
    uniformly random; every step counts towards steps-to-goal.
    """
    validate(cfg)
    check_built(cfg)
    seed_everything(cfg.seed, deterministic=cfg.deterministic, threads=cfg.threads)
    env = make_env(cfg.env, cfg.budget.max_steps)
    agent: Agent = build(cfg.baseline, cfg=cfg)
    logger = RunLogger(run_dir, [*CHART_KEYS, *agent.metric_keys])
    logger.text("config", "```yaml\n" + OmegaConf.to_yaml(cfg, resolve=True) + "```")
    try:
        summary = _loop(cfg, env, agent, logger)
    finally:
        logger.close()
        env.close()
    summary.write(run_dir)
    goal = f"goal at step {summary.steps_to_goal}" if summary.reached_goal else "goal not reached"
    log.info(
        "%s seed=%d %s: %s (cap %d), coverage %.4f, %.1f s, %.0f steps/s -> %s",
        summary.method, summary.seed, summary.env, goal, summary.max_steps, summary.final_coverage,
        summary.wall_seconds, summary.steps_per_second, run_dir,
    )  # fmt: skip
    return summary


def _loop(cfg: DictConfig, env, agent: Agent, logger: RunLogger) -> RunSummary:
    budget = cfg.budget
    rng = np.random.default_rng(cfg.seed)
    coverage = GridCoverage(cfg.env.coverage_low, cfg.env.coverage_high, cfg.env.coverage_bins)
    obs, _ = env.reset(seed=cfg.seed)
    env.action_space.seed(cfg.seed)
    coverage.update(physical_state(env))
    steps_to_goal, step = None, 0
    start = time.perf_counter()
    bar = tqdm(total=budget.max_steps, unit="step", desc=f"{cfg.method_label} seed={cfg.seed}", disable=not cfg.progress)
    for step in range(budget.max_steps):
        action = int(rng.integers(env.action_space.n)) if step < budget.warmup_steps else agent.act(obs, step)
        next_obs, reward, terminated, _, _ = env.step(action)
        logger.record_many(agent.observe(obs, action, float(reward), next_obs, bool(terminated), step))
        logger.record("charts/extrinsic_reward", float(reward))
        coverage.update(physical_state(env))
        obs = next_obs
        done = bool(terminated) or step + 1 == budget.max_steps
        if (step + 1) % cfg.log_every == 0 or done:
            elapsed = time.perf_counter() - start
            logger.record_many(
                {"charts/coverage": coverage.fraction, "charts/wall_time": elapsed, "charts/sps": (step + 1) / elapsed}
            )
            logger.dump(step + 1)
            bar.set_postfix(coverage=f"{coverage.fraction:.4f}", refresh=False)
            bar.update((step + 1) - bar.n)
        if terminated:
            steps_to_goal = step + 1
            break
    bar.close()
    wall = time.perf_counter() - start
    commit, dirty = git_commit()
    return RunSummary(
        method=cfg.method_label, seed=int(cfg.seed), env=cfg.env.id, steps_to_goal=steps_to_goal,
        reached_goal=steps_to_goal is not None, env_steps=step + 1, max_steps=budget.max_steps,
        warmup_steps=budget.warmup_steps, final_coverage=coverage.fraction, wall_seconds=wall,
        steps_per_second=(step + 1) / wall, git_commit=commit, git_dirty=dirty,
    )  # fmt: skip
