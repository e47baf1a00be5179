"""Speed benchmark: ``python -m runners.bench [--threads 1] [--memory 1000 3000] [--out bench.json]``.

Measures, on this machine, with the real components and configs:
- env steps per second for each observation pipeline (random actions);
- ms per training iteration of the paper's agent (default config, and the ``paper_code`` preset);
- ms per planning step (MPC and Q-tree) and ms per memory refresh, at several memory sizes;
and prints a Markdown table with the machine description. Speed targets are checked here, never in tests.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from collections.abc import Callable, Sequence

import numpy as np
import torch

from curiosity.config import build, setup
from curiosity.config.compose import compose_config
from curiosity.envs import make_env
from curiosity.runtime.seeding import seed_everything

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")


def machine() -> dict[str, str | int]:
    cpu = platform.processor() or "unknown"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return {"cpu": cpu, "cores": os.cpu_count() or 0, "python": platform.python_version(), "torch": torch.__version__,
            "torch_threads": torch.get_num_threads(), "platform": platform.platform()}  # fmt: skip


def timed(fn: Callable[[], object], repeats: int, warmup: int = 2) -> float:
    """Median milliseconds of ``fn()`` over ``repeats`` calls after ``warmup`` calls."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(1e3 * (time.perf_counter() - start))
    return statistics.median(times)


def bench_env(env_name: str, obs: str, renderer: str, steps: int = 400) -> float:
    """Env steps per second with random actions."""
    cfg = compose_config([f"env={env_name}", f"env.obs={obs}", f"env.renderer={renderer}"])
    env = make_env(cfg.env, 10_000)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    start = time.perf_counter()
    for _ in range(steps):
        env.step(int(rng.integers(3)))
    env.close()
    return steps / (time.perf_counter() - start)


def filled_agent(overrides: Sequence[str], memory: int):
    """The paper's agent after ``memory`` random env steps (fast renderer), its memory refreshed."""
    cfg = compose_config(["env.renderer=fast", f"budget.warmup_steps={min(64, memory)}", *overrides])
    seed_everything(0, threads=torch.get_num_threads())
    env = make_env(cfg.env, memory + 10)
    agent = build(cfg.baseline, cfg=cfg)
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    for step in range(memory):
        action = int(rng.integers(3))
        nxt, r, term, _, _ = env.step(action)
        agent.replay.add(obs, action, r, nxt, term)
        with agent.model.evaluating():
            z = agent.model.encode(torch.as_tensor(obs).unsqueeze(0))[0]
        agent.curiosity.add(z, action, step)
        obs = nxt
    agent.curiosity.refresh()
    return agent, obs


def bench_agent(name: str, overrides: Sequence[str], memories: Sequence[int], repeats: int) -> list[dict]:
    rows = []
    for memory in memories:
        agent, obs = filled_agent(overrides, memory)
        row = {"agent": name, "memory": memory}
        row["train_iteration_ms"] = timed(agent._iteration, repeats)
        row["plan_ms"] = timed(lambda a=agent, o=obs: a.act(o, 0), repeats)
        row["refresh_ms"] = timed(agent.curiosity.refresh, max(3, repeats // 4), warmup=1)
        rows.append(row)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threads", type=int, default=1, help="torch intra-op threads")
    parser.add_argument("--memory", type=int, nargs="+", default=[500, 1500, 3000], help="memory sizes to plan against")
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--out", help="also write the results as JSON here")
    args = parser.parse_args()
    setup()
    torch.set_num_threads(args.threads)
    result: dict = {"machine": machine(), "env_steps_per_s": {}, "agents": []}
    for env_name in ("acrobot", "mountaincar"):
        for obs, renderer in (("pixels", "gym"), ("pixels", "fast"), ("state", "gym")):
            key = f"{env_name}/{obs}/{renderer if obs == 'pixels' else '-'}"
            result["env_steps_per_s"][key] = round(bench_env(env_name, obs, renderer), 1)
    agents = {
        "paper_text (default: mpc, kde, gaussian_potential)": [],
        "paper_text, horizon 5": ["planner.horizon=5"],
        "paper_code (qtree depth 5, renyi_mi, kde zscore)": ["+experiment=paper_code"],
    }
    for name, overrides in agents.items():
        result["agents"] += bench_agent(name, overrides, args.memory, args.repeats)
    print(f"machine: {json.dumps(result['machine'])}")
    print("\n| pipeline | env steps/s |\n|---|---|")
    for key, value in result["env_steps_per_s"].items():
        print(f"| {key} | {value:.0f} |")
    print("\n| agent | memory | train iteration ms | plan ms | refresh ms |\n|---|---|---|---|---|")
    for r in result["agents"]:
        print(f"| {r['agent']} | {r['memory']} | {r['train_iteration_ms']:.1f} | {r['plan_ms']:.1f} | {r['refresh_ms']:.1f} |")
    if args.out:
        with open(args.out, "w") as f:
            json.dump(result, f, indent=2)


if __name__ == "__main__":
    main()
