"""Speed benchmark: ``python -m runners.bench [--quick] [--json FILE]``.

Measures on this machine, with the real components and configs (speed targets are checked here, never in tests):
env steps per second per observation pipeline; ms per training iteration of the default agent per batch size, its
speed-up over another commit measured side by side (``--baseline-commit``) and where its time goes (operator shares
of a ``torch.profiler`` run); ms per planning step and per memory refresh and the error of log ρ against exact KDE at
memory sizes N; where the arithmetic of an env step goes (FLOPs and times of the default agent's parts, as fractions
of a float32 matmul's rate measured in the same run); the speed-up of a 4-job sweep with two joblib workers over one;
whole seeds of the default agent alone: wall and CPU time, steps-to-goal and wall share by part; and the CPU time of
the same seeds here and at another commit (``--seed-commit``), side by side in fresh processes.
Prints Markdown tables with the machine description. ``--quick`` (under 4 minutes) shrinks every measurement.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import torch

from curiosity.config import setup
from curiosity.runtime.allocator import keep_freed_memory
from runners.benchmark.baseline import REPO, speedup_vs
from runners.benchmark.components import env_steps_per_s, planning_at, train_iter_ms
from runners.benchmark.flops import flops_per_env_step
from runners.benchmark.iteration_profile import train_iter_profile
from runners.benchmark.runs import seed_runs, sweep_speedup
from runners.benchmark.seed_cpu import seed_cpu_of, seed_cpu_vs
from runners.benchmark.timing import machine

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

BASELINE_COMMIT = "127d633"  # the code before the speed work of issue 13
SEED_COMMIT = "078a391"  # the default agent before the speed work of issue 50
QUICK_RUN = ["budget=smoke", "budget.max_steps=80"]


def parse(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="small sizes, one round, one short seed (< 4 minutes)")
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
    p.add_argument("--seed-commit", default=SEED_COMMIT, help="commit whose seeds' CPU time is measured beside this tree's")
    p.add_argument("--seed-cpu-seeds", type=int, nargs="*",
                   help="seeds run side by side with --seed-commit (default: --seeds; none: skip)")  # fmt: skip
    p.add_argument("--flops-memory", type=int, help="memory size N of the FLOP breakdown (default: the smallest --memory)")
    p.add_argument("--matmul-size", type=int, help="side of the float32 matmul of the peak rate (default 1024; quick: 512)")
    p.add_argument("--json", "--out", dest="json", help="also write the results as JSON here")
    args = p.parse_args(argv)
    args.batches = args.batches or ([64] if args.quick else [32, 64, 128])
    args.memory = args.memory or ([1000] if args.quick else [1000, 10_000, 100_000])
    args.repeats = args.repeats or (8 if args.quick else 20)
    args.seeds = args.seeds if args.seeds is not None else ([100] if args.quick else [100, 101, 102, 103])
    args.seed_cpu_seeds = args.seeds if args.seed_cpu_seeds is None else args.seed_cpu_seeds
    args.flops_memory = min(args.memory) if args.flops_memory is None else args.flops_memory
    args.matmul_size = (512 if args.quick else 1024) if args.matmul_size is None else args.matmul_size
    if min(args.flops_memory, args.matmul_size, args.repeats, args.threads) < 1:
        p.error("--flops-memory, --matmul-size, --repeats and --threads must be >= 1")
    for option, commit in (("--baseline-commit", args.baseline_commit), ("--seed-commit", args.seed_commit)):
        if not known_commit(commit):
            p.error(f"{option} {commit}: not a commit of this repository")
    return args


def known_commit(commit: str) -> bool:
    """Whether git knows ``commit`` here (``git rev-parse --verify <commit>^{commit}``)."""
    done = subprocess.run(["git", "rev-parse", "--verify", "--quiet", f"{commit}^{{commit}}"], cwd=REPO,
                          capture_output=True, check=False)  # fmt: skip
    return done.returncode == 0


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
    res.update(_flops(args))
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
    res.update(_seeds(args, seed_dir))
    return res


def _flops(args: argparse.Namespace) -> dict[str, Any]:
    """:func:`flops_per_env_step` at ``--flops-memory`` as the JSON's ``flops_per_env_step`` (part -> gflop, ms,
    gflop_per_s, peak_fraction, … per env step; ``total``), ``flops_setup``, ``matmul`` and ``matmul_gflop_per_s``."""
    out = flops_per_env_step(args.flops_memory, args.repeats, args.matmul_size)
    return {"flops_per_env_step": out["parts"], "flops_setup": out["setup"], "matmul": out["matmul"],
            "matmul_gflop_per_s": out["matmul"]["gflop_per_s"]}  # fmt: skip


def _seeds(args: argparse.Namespace, seed_dir: Path) -> dict[str, Any]:
    """The seeds of the default agent alone (``seeds``, ``seed_wall_s``, ``seed_steps_to_goal``, ``wall_share``,
    ``seed_cpu_s``, ``seed_cpu_s_each``), and side by side with ``--seed-commit`` (``seed_cpu_side_by_side`` and
    ``seed_cpu_speedup_vs_<commit>``; None with no ``--seed-cpu-seeds``)."""
    overrides = QUICK_RUN if args.quick else []
    seeds = seed_runs(args.seeds, overrides, seed_dir)
    res: dict[str, Any] = {"seeds": seeds, "seed_wall_s": [r["wall_s"] for r in seeds],
                           "seed_steps_to_goal": [r["steps_to_goal"] for r in seeds], **seed_cpu_of(seeds)}  # fmt: skip
    totals: dict[str, float] = {}
    for r in seeds:  # wall share over all seeds, weighted by each seed's wall time
        for part, share in r["wall_share"].items():
            totals[part] = totals.get(part, 0.0) + share * r["wall_s"]
    wall = sum(r["wall_s"] for r in seeds if r["wall_share"]) or 1.0
    res["wall_share"] = {part: t / wall for part, t in totals.items()}
    side = seed_cpu_vs(args.seed_commit, args.seed_cpu_seeds, overrides, seed_dir) if args.seed_cpu_seeds else None
    res["seed_cpu_side_by_side"] = side
    res[f"seed_cpu_speedup_vs_{args.seed_commit}"] = side["speedup"] if side else None
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
    lines += flops_report(res)
    s = res["sweep"]
    lines += ["", f"{s['jobs']}-job sweep: {s['one_job_s']:.1f} s with 1 worker, {s['two_jobs_s']:.1f} s with 2: "
              f"speed-up {s['speedup']:.2f}x"]  # fmt: skip
    lines += seeds_report(res)
    return "\n".join(lines)


PART_LABELS = {
    "encoder_forward": "encoder forward (eval, as acting encodes)",
    "encoder_forward_backward": "encoder forward+backward (training batch; in the iteration)",
    "heads": "heads: transition + reward models, forward+backward (in the iteration)",
    "train_iteration": "training iteration (all of it)",
    "novelty": "novelty of the real transition (KDE over the memory)",
    "planning": "planning step (all sequences: transition model + intrinsic terms)",
    "refresh": "memory refresh (re-encode every row, refit)",
}


def _num(x: float) -> str:
    """A table's number: 4 significant digits, thousands separated."""
    return f"{x:,.4g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.2e}"


def flops_report(res: dict[str, Any]) -> list[str]:
    """The report's lines on where an env step's arithmetic goes (``flops_per_env_step``) and the matmul peak."""
    setup, m, parts = res["flops_setup"], res["matmul"], res["flops_per_env_step"]
    lines = ["", f"where the arithmetic of an env step goes (the default agent, memory N = {setup['memory']:,}, batch "
             f"{setup['batch']} x {setup['n_step'] + 1} frames, {setup['iters_per_train']} iterations every "
             f"{setup['train_every']} env step(s), a plan every {setup['plan_every']} steps, a refresh every "
             f"{setup['refresh_every']}; {setup['threads']} thread(s)). FLOPs: matrix products and convolutions by "
             "torch.utils.flop_counter.FlopCounterMode (2 per multiply-add, backward included); the elementwise ops it "
             "does not count (the KDE's distances, shifts and exponentials, activations, losses) counted from their "
             "shapes, 1 per output element (reductions: per input element); max-pooling, copies, indexing, Adam's "
             "foreach updates and the refresh's k-d tree not counted. Peak: float32 torch.mm of "
             f"{m['size']}x{m['size']} matrices, median of {m['repeats']}: {res['matmul_gflop_per_s']:.1f} GFLOP/s.",
             "", "| part | per | MFLOP per call | ms per call | GFLOP/s | of peak | calls per env step | GFLOP per env step "
             "| ms per env step |", "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for name, p in parts.items():
        if name != "total":
            lines.append(f"| {PART_LABELS.get(name, name)} | {p['per']} | {_num(1e3 * p['gflop_per_call'])} | "
                         f"{_num(p['ms_per_call'])} | {p['gflop_per_s']:.1f} | {p['peak_fraction']:.1%} | "
                         f"{_num(p['per_env_step'])} | {_num(p['gflop'])} | {_num(p['ms'])} |")  # fmt: skip
    t = parts["total"]
    lines.append(f"| env step: the parts above not inside the iteration (env, rendering, logging left out) | env step "
                 f"| | | {t['gflop_per_s']:.1f} | {t['peak_fraction']:.1%} | 1 | {_num(t['gflop'])} | "
                 f"{_num(t['ms'])} |")  # fmt: skip
    return lines


def seeds_report(res: dict[str, Any]) -> list[str]:
    """The report's lines on the seeds alone (steps to goal, wall and CPU seconds, wall share) and side by side."""
    lines = ["", "| seed | steps to goal | wall s | CPU s |", "|---|---|---|---|"]
    lines += [f"| {r['seed']} | {r['steps_to_goal']} | {r['wall_s']:.0f} | "
              f"{'?' if r.get('cpu_s') is None else format(r['cpu_s'], '.0f')} |" for r in res["seeds"]]  # fmt: skip
    if res.get("seed_cpu_s") is not None:
        lines += ["", f"seed CPU: median {res['seed_cpu_s']:.1f} s per seed (summary.json's cpu_seconds)"]
    lines += ["", "wall share: " + ", ".join(f"{k} {v:.1%}" for k, v in res["wall_share"].items())]
    side = res.get("seed_cpu_side_by_side")
    if side:
        c = side["commit"]
        lines += ["", f"the same seeds here and at {c}, side by side (fresh processes, alternating, the child's CPU "
                  f"time with its start-up; {' '.join(side['overrides']) or 'the default budget'}): median "
                  f"{side['cpu_s']:.1f} s here vs {side['baseline_cpu_s']:.1f} s at {c}: speed-up "
                  f"{side['speedup']:.2f}x", "", f"| seed | CPU s here | CPU s at {c} | steps to goal here / at {c} |",
                  "|---|---|---|---|"]  # fmt: skip
        lines += [f"| {a['seed']} | {a['cpu_s']:.1f} | {b['cpu_s']:.1f} | {a['steps_to_goal']} / {b['steps_to_goal']} |"
                  for a, b in zip(side["runs"], side["baseline_runs"], strict=True)]  # fmt: skip
    return lines


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
