"""Speed benchmark: ``python -m runners.bench [--quick] [--json FILE]``.

Measures on this machine, with the real components and configs (speed targets are checked here, never in tests):
env steps per second per observation pipeline; ms per training iteration of the default agent per batch size, its
speed-up over another commit measured side by side (``--baseline-commit``) and where its time goes (operator shares
of a ``torch.profiler`` run); ms per planning step and per memory refresh and the error of log ρ against exact KDE at
memory sizes N; the speed-up of a 4-job sweep with two joblib workers over one; and whole seeds of the default agent
alone: wall time, steps-to-goal and wall share by part.
Prints Markdown tables with the machine description. ``--quick`` (under 3 minutes) shrinks every measurement.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
from pathlib import Path
from typing import Any

import torch

from curiosity.config import setup
from curiosity.runtime.allocator import keep_freed_memory
from runners.benchmark.baseline import speedup_vs
from runners.benchmark.components import env_steps_per_s, planning_at, train_iter_ms
from runners.benchmark.iteration_profile import train_iter_profile
from runners.benchmark.runs import seed_runs, sweep_speedup
from runners.benchmark.timing import machine

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

BASELINE_COMMIT = "127d633"  # the code before the speed work of issue 13
QUICK_RUN = ["budget=smoke", "budget.max_steps=80"]


def parse(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="small sizes, one round, one short seed (< 3 minutes)")
    p.add_argument("--threads", type=int, default=1, help="torch intra-op threads")
    p.add_argument("--batches", type=int, nargs="+", help="training batch sizes (default 32 64 128; quick: 64)")
    p.add_argument("--memory", type=int, nargs="+", help="memory sizes N (default 1000 10000 100000; quick: 1000)")
    p.add_argument("--repeats", type=int, help="timed calls per median (default 20; quick: 8)")
    p.add_argument(
        "--reservoir",
        type=int,
        default=4096,
        help="also measure planning, refresh and log rho error with memory_mode=reservoir of this size at the "
        "memory sizes above it (0: skip)",
    )
    p.add_argument(
        "--reservoir-precision",
        default="float32",
        choices=("float64", "float32"),
        help="the KDE arithmetic of the reservoir measurement (estimator.precision; the exact rows are float64)",
    )
    p.add_argument("--baseline-commit", default=BASELINE_COMMIT, help="commit to time the training iteration against")
    p.add_argument("--seeds", type=int, nargs="*", help="seeds of the default agent to run alone (default 100-103)")
    p.add_argument("--seed-dir", help="where the seed runs go (default: a temporary directory); re-running resumes")
    p.add_argument("--json", "--out", dest="json", help="also write the results as JSON here")
    args = p.parse_args(argv)
    args.batches = args.batches or ([64] if args.quick else [32, 64, 128])
    args.memory = args.memory or ([1000] if args.quick else [1000, 10_000, 100_000])
    args.repeats = args.repeats or (8 if args.quick else 20)
    args.seeds = args.seeds if args.seeds is not None else ([100] if args.quick else [100, 101, 102, 103])
    return args


def _by_memory(at: dict[int, dict[str, float]]) -> dict[str, Any]:
    """:func:`planning_at`'s results per memory size N as the JSON's ``plan_step_ms``, ``refresh_ms`` and
    ``novelty_log_rho_error`` {N: …}."""
    return {"plan_step_ms": {n: v["plan_ms"] for n, v in at.items()},
            "refresh_ms": {n: v["refresh_ms"] for n, v in at.items()},
            "novelty_log_rho_error": {n: {"median": v["log_rho_error_median"], "p99": v["log_rho_error_p99"]}
                                      for n, v in at.items()}}  # fmt: skip


def measure(args: argparse.Namespace, seed_dir: Path) -> dict[str, Any]:
    default_batch = 64
    # the allocator setting every run makes (curiosity/runtime/allocator.py): components timed as runs see them
    res: dict[str, Any] = {"machine": {**machine(), "keep_freed_memory": keep_freed_memory()}, "quick": args.quick}
    res["env_steps_per_s"] = {p: round(env_steps_per_s("acrobot", p, 150 if args.quick else 400), 1)
                              for p in ("gym", "fast", "state")}  # fmt: skip
    res["train_iter_ms"] = train_iter_ms(args.batches, args.repeats)
    base = speedup_vs(args.baseline_commit, default_batch, args.repeats, args.threads, rounds=1 if args.quick else 2)
    res["train_iter_baseline"] = base
    res["train_iter_speedup_vs_baseline"] = base["speedup"]
    res["train_iter_speedup_same_allocator"] = base["speedup_same_allocator"]
    res["train_iter_profile"] = train_iter_profile(default_batch, args.repeats)
    res.update(_by_memory({n: planning_at(n, args.repeats) for n in args.memory}))
    size = args.reservoir
    reservoir = ["intrinsic.terms.novelty.memory_mode=reservoir", f"intrinsic.terms.novelty.memory_size={size}",
                 f"estimator.precision={args.reservoir_precision}"]  # fmt: skip
    sampled = {n: planning_at(n, args.repeats, overrides=reservoir)
               for n in args.memory if 0 < size < n}  # fmt: skip
    res["reservoir"] = {"size": size, "precision": args.reservoir_precision, **_by_memory(sampled)}
    sweep = ["budget=smoke", "budget.max_steps=70"] if args.quick else ["budget=smoke"]
    res["sweep"] = sweep_speedup(sweep)
    res["sweep_speedup_2_jobs"] = res["sweep"]["speedup"]
    seeds = seed_runs(args.seeds, QUICK_RUN if args.quick else [], seed_dir)
    res["seeds"] = seeds
    res["seed_wall_s"] = [r["wall_s"] for r in seeds]
    res["seed_steps_to_goal"] = [r["steps_to_goal"] for r in seeds]
    totals: dict[str, float] = {}
    for r in seeds:  # wall share over all seeds, weighted by each seed's wall time
        for part, share in r["wall_share"].items():
            totals[part] = totals.get(part, 0.0) + share * r["wall_s"]
    wall = sum(r["wall_s"] for r in seeds if r["wall_share"]) or 1.0
    res["wall_share"] = {part: t / wall for part, t in totals.items()}
    return res


def report(res: dict[str, Any]) -> str:
    lines = [f"machine: {json.dumps(res['machine'])}" + ("  (quick)" if res["quick"] else ""), "",
             "| Acrobot pipeline | env steps/s |", "|---|---|"]  # fmt: skip
    lines += [f"| {k} | {v:,.0f} |" for k, v in res["env_steps_per_s"].items()]
    b = res["train_iter_baseline"]
    lines += ["", "| batch | ms per training iteration |", "|---|---|"]
    lines += [f"| {k} | {v:.1f} |" for k, v in res["train_iter_ms"].items()]
    lines += ["", f"training iteration at batch {b['batch']}: {b['ms']:.1f} ms here, {b['baseline_ms']:.1f} ms at "
              f"{b['commit']} (side by side): speed-up {b['speedup']:.2f}x; with the same allocator setting for "
              f"both, {b['ms_same_allocator']:.1f} vs {b['baseline_ms_same_allocator']:.1f} ms: "
              f"{b['speedup_same_allocator']:.2f}x"]  # fmt: skip
    p = res["train_iter_profile"]
    lines += ["", f"where an iteration at batch {p['batch']} goes (torch.profiler, {p['iterations']} iterations, "
              f"{p['ms_per_iteration']:.1f} ms each under the profiler): convolutions forward "
              f"{p['conv_forward_share']:.0%}, backward {p['conv_backward_share']:.0%}; "
              f"{p['conv_forward_gflop_per_iteration']:.2f} GFLOP of forward convolutions per iteration, the "
              f"convolutions at ~{p['conv_gflop_per_s_estimate']:.0f} GFLOP/s (3 x forward FLOPs / their time)",
              "", "| operator | share of self time |", "|---|---|"]  # fmt: skip
    lines += [f"| {k} | {v:.1%} |" for k, v in p["op_share"].items()]
    lines += ["", "| memory N | ms per planning step | ms per refresh | log rho error median / p99 |", "|---|---|---|---|"]
    for n, ms in res["plan_step_ms"].items():
        e = res["novelty_log_rho_error"][n]
        lines.append(f"| {n:,} | {ms:.1f} | {res['refresh_ms'][n]:.1f} | {e['median']:.2g} / {e['p99']:.2g} |")
    r = res.get("reservoir", {})
    for n, ms in r.get("plan_step_ms", {}).items():
        e = r["novelty_log_rho_error"][n]
        lines.append(f"| {n:,} (reservoir {r['size']:,}, {r.get('precision', 'float64')}) | {ms:.1f} | "
                     f"{r['refresh_ms'][n]:.1f} | {e['median']:.2g} / {e['p99']:.2g} |")  # fmt: skip
    s = res["sweep"]
    lines += ["", f"{s['jobs']}-job sweep: {s['one_job_s']:.1f} s with 1 worker, {s['two_jobs_s']:.1f} s with 2: "
              f"speed-up {s['speedup']:.2f}x"]  # fmt: skip
    lines += ["", "| seed | steps to goal | wall s |", "|---|---|---|"]
    lines += [f"| {r['seed']} | {r['steps_to_goal']} | {r['wall_s']:.0f} |" for r in res["seeds"]]
    lines += ["", "wall share: " + ", ".join(f"{k} {v:.1%}" for k, v in res["wall_share"].items())]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    args = parse(argv)
    setup()
    torch.set_num_threads(args.threads)
    with tempfile.TemporaryDirectory() as tmp:
        res = measure(args, Path(args.seed_dir or tmp))
    print(report(res))
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
