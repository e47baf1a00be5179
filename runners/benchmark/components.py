"""Component timings of the benchmark: env steps, training iterations, planning, novelty and memory refresh."""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np
import torch

from curiosity.agents.paper import PaperAgent
from curiosity.config import build
from curiosity.config.compose import compose_config
from curiosity.envs import make_env
from curiosity.novelty.kde import kde_log_density
from curiosity.runtime.seeding import seed_everything
from runners.benchmark.timing import timed

PIPELINES = {"gym": ("pixels", "gym"), "fast": ("pixels", "fast"), "state": ("state", "gym")}


def env_steps_per_s(env_name: str, pipeline: str, steps: int = 400) -> float:
    """Env steps per second with uniformly random actions through one observation pipeline of ``PIPELINES``."""
    obs, renderer = PIPELINES[pipeline]
    cfg = compose_config([f"env={env_name}", f"env.obs={obs}", f"env.renderer={renderer}"])
    env = make_env(cfg.env, 10 * steps)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    start = time.perf_counter()
    for _ in range(steps):
        env.step(int(rng.integers(3)))
    env.close()
    return steps / (time.perf_counter() - start)


def filled_agent(overrides: Sequence[str], memory: int) -> tuple[PaperAgent, np.ndarray]:
    """The paper's agent after ``memory`` uniformly random env steps (fast renderer): replay and novelty memory hold
    them (encoded in batches of 512), memory refreshed. Returns the agent and the last observation."""
    cfg = compose_config(["env.renderer=fast", f"budget.warmup_steps={min(64, memory)}", *overrides])
    seed_everything(0, threads=torch.get_num_threads())
    env = make_env(cfg.env, memory + 10)
    agent = build(cfg.baseline, cfg=cfg)
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    cur = agent.curiosity
    for start in range(0, memory, 512):
        block, actions = [], []
        for _ in range(min(512, memory - start)):
            action = int(rng.integers(3))
            nxt, r, term, _, _ = env.step(action)
            agent.replay.add(obs, action, r, nxt, term)
            block.append(obs)
            actions.append(action)
            obs = nxt
        with agent.model.evaluating():
            z = agent.model.encode(torch.as_tensor(np.stack(block)))
        a = torch.tensor(actions)
        cur.memory.add(cur.embed(z, a), keys=torch.arange(start, start + len(block)))
    cur.refresh()
    return agent, obs


def train_iter_ms(batches: Sequence[int], repeats: int) -> dict[int, float]:
    """Median ms of one training iteration of the default agent at each batch size (replay of 500 random steps)."""
    out = {}
    for batch in batches:
        agent, _ = filled_agent([f"batch_size={batch}"], 500)
        out[batch] = timed(agent._iteration, repeats)
    return out


def planning_at(memory: int, repeats: int, queries: int = 2048) -> dict[str, float]:
    """At a memory of ``memory`` rows: ms per planning step, ms per memory refresh, and the error of the configured
    estimator's log ρ against exact KDE (chunked logsumexp over every row) at ``queries`` perturbed memory rows."""
    agent, obs = filled_agent([], memory)
    cur = agent.curiosity
    big = memory >= 10_000  # a refresh re-encodes every row and refits the bandwidth (O(N^2)): time it once
    out = {"plan_ms": timed(lambda: agent.act(obs, memory), repeats),
           "refresh_ms": timed(cur.refresh, 1 if big else max(2, repeats // 5), warmup=0 if big else 1)}  # fmt: skip
    estimator = cur.estimator
    mem = estimator.standardiser(cur.memory.tensor())
    rng = torch.Generator().manual_seed(0)
    rows = torch.randint(len(mem), (min(queries, len(mem)),), generator=rng)
    query = mem[rows] + 0.5 * estimator.reward.bandwidth * torch.randn(len(rows), mem.shape[1], generator=rng)
    exact = kde_log_density(query, mem, bandwidth=estimator.reward.bandwidth)
    err = (estimator.reward.log_density(query) - exact).abs()
    out["log_rho_error_median"] = float(err.median())
    out["log_rho_error_p99"] = float(err.quantile(0.99))
    return out
