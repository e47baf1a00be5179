"""Component timings of the benchmark: env steps, training iterations, planning, novelty and memory refresh."""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np
import torch
from torch import Tensor

from curiosity.agents.paper import PaperAgent
from curiosity.config import build
from curiosity.config.compose import compose_config
from curiosity.envs import make_env
from curiosity.novelty.estimators import KDENovelty
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


def filled_agent(overrides: Sequence[str], memory: int) -> tuple[PaperAgent, np.ndarray, Tensor, Tensor]:
    """The paper's agent after ``memory`` uniformly random env steps (fast renderer): replay and novelty memory hold
    them (encoded in batches of 512; a reservoir keeps a sample), memory refreshed. Returns the agent, the last
    observation, and what the memory embeds of every step, latents (memory, d) or random codes (memory, k), and its
    actions (memory,) (the exact reference)."""
    cfg = compose_config(["env.renderer=fast", f"budget.warmup_steps={min(64, memory)}", *overrides])
    seed_everything(0, threads=torch.get_num_threads())
    env = make_env(cfg.env, memory + 10)
    agent = build(cfg.baseline, cfg=cfg)
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    cur = agent.novelty
    assert cur is not None, "the benchmark measures the latent novelty memory"
    latents, all_actions = [], []
    for start in range(0, memory, 512):
        block, actions = [], []
        for _ in range(min(512, memory - start)):
            action = int(rng.integers(3))
            nxt, r, term, _, _ = env.step(action)
            agent.replay.add(obs, action, r, nxt, term)
            block.append(obs)
            actions.append(action)
            obs = nxt
        z = _novelty_source(agent, torch.as_tensor(np.stack(block)))
        a = torch.tensor(actions)
        cur.memory.add(cur.embed(z, a), keys=torch.arange(start, start + len(block)))
        latents.append(z)
        all_actions.append(a)
    cur.refresh()
    return agent, obs, torch.cat(latents), torch.cat(all_actions)


def _novelty_source(agent: PaperAgent, frames: Tensor) -> Tensor:
    """What the novelty memory embeds for ``frames`` (B, *obs), by the novelty's own code: E(o), or the frozen random
    encoder's codes for random-code novelty (standardised first on the warm-up's frames, as at a run's first refresh)."""
    cur = agent.novelty
    assert cur is not None
    cur._before_refresh()
    return cur._code(frames)


def train_iter_ms(batches: Sequence[int], repeats: int) -> dict[int, float]:
    """Median ms of one training iteration of the default agent at each batch size (replay of 500 random steps)."""
    out = {}
    for batch in batches:
        agent, *_ = filled_agent([f"agent.batch_size={batch}"], 500)
        out[batch] = timed(agent._iteration, repeats)
    return out


def planning_at(memory: int, repeats: int, queries: int = 2048, overrides: Sequence[str] = ()) -> dict[str, float]:
    """At a memory of ``memory`` rows: ms per planning step, ms per memory refresh, and the error of the configured
    estimator's log ρ (``overrides``, e.g. a reservoir) against the exact KDE over every row with the bandwidth of
    every row (chunked logsumexp), at ``queries`` perturbed rows."""
    # every act() plans: one action per plan, held one step (with the default planner.hold=4 an act() would replay the
    # held action for 3 steps; the novelty scores of a plan are the same count, 243 x 5, whatever the hold)
    agent, obs, latents, actions = filled_agent(["planner.commit=1", "planner.hold=1", *overrides], memory)
    cur = agent.novelty
    assert cur is not None
    big = len(cur.memory) >= 10_000  # a refresh re-encodes every stored row: time it once
    out = {"plan_ms": timed(lambda: agent.act(obs, memory), repeats),
           "refresh_ms": timed(cur.refresh, 1 if big else max(2, repeats // 5), warmup=0 if big else 1)}  # fmt: skip
    estimator = cur.estimator
    everything = estimator.standardiser(cur.embed(latents, actions))  # every row, as the memory now embeds them
    exact = KDENovelty(bandwidth=estimator.multiplier, baseline="none", bandwidth_rule=estimator.rule)
    exact.fit(everything)
    rng = torch.Generator().manual_seed(0)
    rows = torch.randint(len(everything), (min(queries, len(everything)),), generator=rng)
    h = exact.bandwidth
    query = everything[rows] + 0.5 * h * torch.randn(len(rows), everything.shape[1], generator=rng)
    err = (estimator.log_density(query) - kde_log_density(query, everything, bandwidth=h)).abs()
    out["log_rho_error_median"] = float(err.median())
    out["log_rho_error_p99"] = float(err.quantile(0.99))
    out["memory_rows"] = len(cur.memory)
    return out
