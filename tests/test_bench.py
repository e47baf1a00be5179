"""The benchmark's parts run and account for time correctly (no timing assertions: speeds are the benchmark's job)."""

from __future__ import annotations

import os

import json
from pathlib import Path

import pytest

import torch

import runners.benchmark.timing as timing
from curiosity.config import build
from curiosity.config.compose import compose_config
from curiosity.nets.preprocess import GaussianBlur
from runners.bench import parse, report
from runners.benchmark.components import planning_at
from runners.benchmark.flops import count_flops, flops_per_env_step
from runners.benchmark.iteration_profile import summarise, train_iter_profile
from runners.benchmark.runs import seed_runs
from runners.benchmark.seed_cpu import seed_cpu_of
from runners.benchmark.timing import PartTimer


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


class Work:
    def __init__(self, clock: Clock) -> None:
        self.clock = clock

    def inner(self) -> None:
        self.clock.now += 2.0

    def outer(self) -> None:
        self.clock.now += 1.0
        self.inner()
        self.clock.now += 3.0


def test_part_timer_charges_nested_parts_exclusively_and_restores(monkeypatch: pytest.MonkeyPatch) -> None:
    clock = Clock()
    monkeypatch.setattr(timing.time, "perf_counter", clock)
    work = Work(clock)
    timer = PartTimer()
    timer.wrap(work, "inner", "in")
    timer.wrap(work, "outer", "out")
    work.outer()
    work.inner()
    assert timer.seconds == {"out": 4.0, "in": 4.0}
    assert timer.shares(10.0) == {"in": 0.4, "out": 0.4, "other": pytest.approx(0.2)}
    timer.restore()
    work.outer()
    assert timer.seconds == {"out": 4.0, "in": 4.0}


def test_planning_at_a_small_memory_reports_exact_kde_as_exact() -> None:
    out = planning_at(80, repeats=1, queries=64)
    assert out["plan_ms"] > 0.5 and out["refresh_ms"] > 0  # every timed act() plans (243 sequences; not a queued action)
    assert out["log_rho_error_median"] < 1e-4 and out["log_rho_error_p99"] < 1e-4  # the default estimator is exact
    assert out["memory_rows"] == 80


def test_planning_at_with_a_reservoir_measures_its_error_against_every_row() -> None:
    """A reservoir of 60 of 160 rows: the memory holds 60, and its KDE (bandwidth of the whole stream) differs from
    the exact KDE over all 160 rows, by a sampling error (not 0, and well under the ~1 nat a bandwidth off by the
    sample's wider spacing would add)."""
    reservoir = ["intrinsic.terms.novelty.memory_mode=reservoir", "intrinsic.terms.novelty.memory_size=60"]
    out = planning_at(160, repeats=1, queries=64, overrides=reservoir)
    assert out["memory_rows"] == 60
    assert 1e-4 < out["log_rho_error_median"] < 0.5 and out["log_rho_error_p99"] < 3.0, out


def test_seed_runs_time_every_part_and_read_the_summary(tmp_path: Path) -> None:
    rows = seed_runs([3], ["budget=smoke", "budget.max_steps=70", "env.renderer=fast", "agent.probe_every=0"], tmp_path)
    (row,) = rows
    summary = json.loads((tmp_path / "default" / "seed=3" / "summary.json").read_text())
    assert row["wall_s"] == summary["wall_seconds"] and row["steps_to_goal"] == summary["steps_to_goal"]
    assert row["cpu_s"] == summary["cpu_seconds"] and row["cpu_s"] > 0
    shares = row["wall_share"]
    assert {"env+render", "encode", "plan", "novelty", "refresh", "train", "logging", "checkpoint"} <= set(shares)
    assert all(v >= 0 for v in shares.values()) and sum(shares.values()) == pytest.approx(1.0, abs=0.02)
    # instrumentation removed afterwards: a second run is not timed into the first's parts
    import curiosity.runtime.loop as loop
    from curiosity.envs import make_env

    assert loop.make_env is make_env


def test_parse_defaults_and_report_render() -> None:
    quick, full = parse(["--quick"]), parse([])
    assert (quick.batches, quick.memory, quick.seeds) == ([64], [1000], [100])
    assert (full.batches, full.memory, full.seeds) == ([32, 64, 128], [1000, 10_000, 100_000], [100, 101, 102, 103])
    assert (quick.seed_cpu_seeds, quick.seed_commit, quick.flops_memory, quick.matmul_size) == ([100], "078a391", 1000, 512)
    assert (full.seed_cpu_seeds, full.flops_memory, full.matmul_size) == ([100, 101, 102, 103], 1000, 1024)
    assert parse(["--seeds", "5", "6", "--seed-cpu-seeds"]).seed_cpu_seeds == []  # none: the side by side is skipped
    for bad in (["--matmul-size", "-1"], ["--seed-commit", "not-a-commit"]):
        with pytest.raises(SystemExit):
            parse(bad)
    res = {
        "machine": {"cpu": "x"},
        "quick": True,
        "env_steps_per_s": {"gym": 1.0, "fast": 2.0, "state": 3.0},
        "train_iter_ms": {64: 10.0},
        "train_iter_baseline": {
            "batch": 64,
            "ms": 10.0,
            "baseline_ms": 25.0,
            "commit": "abc",
            "speedup": 2.5,
            "ms_same_allocator": 10.0,
            "baseline_ms_same_allocator": 15.0,
            "speedup_same_allocator": 1.5,
        },
        "plan_step_ms": {1000: 3.0},
        "refresh_ms": {1000: 5.0},
        "novelty_log_rho_error": {1000: {"median": 0.0, "p99": 0.0}},
        "reservoir": {
            "size": 500,
            "precision": "float32",
            "plan_step_ms": {1000: 2.0},
            "refresh_ms": {1000: 4.0},
            "novelty_log_rho_error": {1000: {"median": 0.1, "p99": 0.5}},
        },
        "train_iter_profile": {
            "batch": 64,
            "iterations": 20,
            "ms_per_iteration": 12.0,
            "op_share": {"aten::convolution_backward": 0.5, "other": 0.5},
            "conv_forward_share": 0.25,
            "conv_backward_share": 0.5,
            "conv_forward_gflop_per_iteration": 0.63,
            "conv_gflop_per_s_estimate": 40.0,
        },
        "sweep": {"jobs": 4, "one_job_s": 10.0, "two_jobs_s": 5.5, "speedup": 1.82},
        "seeds": [{"seed": 100, "steps_to_goal": 200, "wall_s": 100.0, "cpu_s": 90.0}],
        "seed_cpu_s": 90.0,
        "wall_share": {"train": 0.5, "other": 0.5},
        "matmul": {"size": 512, "repeats": 8, "ms": 2.0, "gflop_per_s": 100.0},
        "matmul_gflop_per_s": 100.0,
        "flops_setup": {"memory": 1000, "batch": 64, "n_step": 2, "iters_per_train": 16, "train_every": 1,
                        "plan_every": 20, "refresh_every": 10, "threads": 1},
        "flops_per_env_step": {
            "train_iteration": {"per": "iteration", "gflop_per_call": 2.0, "ms_per_call": 40.0, "gflop_per_s": 50.0,
                                "peak_fraction": 0.5, "per_env_step": 16.0, "gflop": 32.0, "ms": 640.0},
            "total": {"gflop": 32.0, "ms": 640.0, "gflop_per_s": 50.0, "peak_fraction": 0.5},
        },
        "seed_cpu_side_by_side": {"commit": "078a391", "overrides": [], "cpu_s": 80.0, "baseline_cpu_s": 120.0,
                                  "speedup": 1.5, "runs": [{"seed": 100, "cpu_s": 80.0, "steps_to_goal": 200}],
                                  "baseline_runs": [{"seed": 100, "cpu_s": 120.0, "steps_to_goal": None}]},
    }  # fmt: skip
    text = report(res)
    assert "speed-up 2.50x" in text and "10.0 vs 15.0 ms: 1.50x" in text
    assert "| 100 | 200 | 100 | 90 |" in text and "train 50.0%" in text
    assert "| training iteration (all of it) | iteration | 2,000 | 40 | 50.0 | 50.0% | 16 | 32 | 640 |" in text
    assert "512x512 matrices, median of 8: 100.0 GFLOP/s" in text and "FlopCounterMode" in text
    assert "80.0 s here vs 120.0 s at 078a391: speed-up 1.50x" in text and "| 100 | 80.0 | 120.0 | 200 / None |" in text
    assert "| 1,000 (reservoir 500, float32) | 2.0 | 4.0 | 0.1 / 0.5 |" in text
    assert "convolutions forward 25%, backward 50%" in text and "| aten::convolution_backward | 50.0% |" in text


class Event:
    def __init__(self, key: str, self_us: float, flops: int = 0) -> None:
        self.key, self.self_cpu_time_total, self.flops = key, self_us, flops


def test_profile_summary_shares_and_convolution_rate() -> None:
    """Self times 600 + 300 + 100 µs over 2 iterations: shares of their sum, the top ones named and the rest
    ``other``; the forward convolutions' 2 GFLOP (counted on ``aten::conv2d``, whose own self time is small) give
    3 × 2 GFLOP / 0.9 ms."""
    events = [Event("aten::convolution_backward", 600.0), Event("aten::mkldnn_convolution", 300.0),
              Event("aten::conv2d", 0.0, flops=2_000_000_000), Event("aten::tanh", 100.0)]  # fmt: skip
    out = summarise(events, iterations=2, wall_s=0.004, top=2)
    assert out["op_share"] == pytest.approx({"aten::convolution_backward": 0.6, "aten::mkldnn_convolution": 0.3,
                                             "other": 0.1})  # fmt: skip
    assert out["conv_forward_share"] == pytest.approx(0.3) and out["conv_backward_share"] == pytest.approx(0.6)
    assert out["ms_per_iteration"] == pytest.approx(2.0) and out["conv_forward_gflop_per_iteration"] == 1.0
    assert out["conv_gflop_per_s_estimate"] == pytest.approx(3 * 2.0 / 0.0009)


def test_train_iter_profile_of_the_default_agent_finds_its_convolutions() -> None:
    out = train_iter_profile(batch=4, iterations=1)
    assert sum(out["op_share"].values()) == pytest.approx(1.0)
    assert out["conv_forward_share"] > 0 and out["conv_backward_share"] > 0  # the conv encoder, forward and backward
    assert out["conv_forward_gflop_per_iteration"] > 0 and out["conv_gflop_per_s_estimate"] > 0


def test_baseline_commit_is_timed_from_its_own_worktree_and_removed() -> None:
    import subprocess

    from runners.benchmark.baseline import REPO, speedup_vs

    out = speedup_vs("HEAD", batch=4, repeats=1, threads=1, rounds=1)
    assert out["ms"] > 0 and out["baseline_ms"] > 0 and out["speedup"] == out["baseline_ms"] / out["ms"]
    assert out["speedup_same_allocator"] == out["baseline_ms_same_allocator"] / out["ms_same_allocator"]
    listed = subprocess.run(["git", "worktree", "list"], cwd=REPO, capture_output=True, text=True).stdout
    assert f"baseline-{os.getpid()}" not in listed  # its own worktree is removed (others', e.g. a second suite's, may be)


def test_elementwise_counter_counts_floating_pointwise_ops_and_reductions_from_shapes() -> None:
    """x @ w (10x3 by 3x4): 2·10·3·4 FLOPs for FlopCounterMode; exp, + 1 (40 outputs each) and the sum (40 inputs):
    120 elementwise; the clone (a copy) and integer arithmetic are not counted."""
    x, w = torch.randn(10, 3), torch.randn(3, 4)

    def work() -> None:
        ((x @ w).exp() + 1).clone().sum()
        torch.arange(10) * 3

    assert count_flops(work) == (240, 120)


def _analytic_encoder_flops(encoder: torch.nn.Module, obs: torch.Tensor) -> int:
    """2 × the multiply-adds of one forward pass, from the layers' shapes: each convolution's output elements ×
    in-channels/groups × kernel area, each linear layer's in × out per row, and the blur's two band-matrix products
    ((h', H) @ (H, W), then (h', W) @ (W, w') per frame channel)."""
    total = 0

    def hook(module: torch.nn.Module, args: tuple, out: torch.Tensor) -> None:
        nonlocal total
        (x,) = args
        if isinstance(module, torch.nn.Conv2d):
            kh, kw = module.kernel_size
            total += 2 * out.numel() * module.in_channels // module.groups * kh * kw
        elif isinstance(module, torch.nn.Linear):
            total += 2 * out.numel() * module.in_features
        elif isinstance(module, GaussianBlur):
            b, c, h, w = x.shape
            h2, w2 = out.shape[-2:]
            total += 2 * b * c * (h2 * h * w + h2 * w * w2)

    handles = [m.register_forward_hook(hook) for m in encoder.modules()]
    with torch.no_grad():
        encoder(obs)
    for handle in handles:
        handle.remove()
    return total


def test_flops_per_env_step_of_the_default_agent() -> None:
    out = flops_per_env_step(memory=200, repeats=1, matmul_size=512)
    parts, setup = out["parts"], out["setup"]
    assert {"encoder_forward", "encoder_forward_backward", "heads", "train_iteration", "novelty", "planning",
            "refresh", "total"} <= set(parts)  # fmt: skip
    assert out["matmul"]["gflop_per_s"] > 0 and setup["memory"] == 200
    for name, p in parts.items():
        assert p["gflop"] > 0 and p["ms"] > 0 and p["gflop_per_s"] > 0, name
        assert 0 < p["peak_fraction"] < 1.5, (name, p)
        if name != "total":
            assert p["flop_matmul"] > 0 and p["flop_elementwise"] > 0 and p["gflop_per_call"] > 0, name
    cfg = compose_config([])
    frame = torch.zeros(1, cfg.env.frame_stack, cfg.env.frame_size, cfg.env.frame_size)
    assert parts["encoder_forward"]["flop_matmul"] == _analytic_encoder_flops(build(cfg.encoder), frame)
    forward, both = parts["encoder_forward"]["flop_matmul"], parts["encoder_forward_backward"]["flop_matmul"]
    assert forward < both < 3 * forward  # the first layer's backward has no input gradient to compute
    iteration = parts["train_iteration"]["flop_matmul"]
    assert both * setup["batch"] * (setup["n_step"] + 1) + parts["heads"]["flop_matmul"] <= iteration
    per_step = cfg.budget.iters_per_train / cfg.budget.train_every
    assert parts["train_iteration"]["per_env_step"] == per_step
    assert parts["planning"]["per_env_step"] == 1 / (cfg.planner.hold * cfg.planner.commit)
    top = [p for name, p in parts.items() if name != "total" and p["within"] is None]
    assert parts["total"]["gflop"] == pytest.approx(sum(p["gflop"] for p in top))


def test_seed_cpu_of_the_seed_runs() -> None:
    assert seed_cpu_of([{"cpu_s": 3.0}, {"cpu_s": 1.0}, {"cpu_s": 2.0}]) == {"seed_cpu_s_each": [3.0, 1.0, 2.0],
                                                                              "seed_cpu_s": 2.0}  # fmt: skip
    assert seed_cpu_of([{"cpu_s": 3.0}, {}])["seed_cpu_s"] is None and seed_cpu_of([])["seed_cpu_s"] is None


def test_seeds_results_name_the_side_by_side_commit(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    import runners.bench as bench

    rows = [{"seed": s, "steps_to_goal": None, "wall_s": 2.0, "cpu_s": float(s), "wall_share": {}} for s in (1, 2, 3)]
    monkeypatch.setattr(bench, "seed_runs", lambda seeds, overrides, out: rows)
    monkeypatch.setattr(bench, "seed_cpu_vs", lambda commit, seeds, overrides, out: {"speedup": 1.25, "seeds": seeds})
    res = bench._seeds(parse(["--quick", "--seeds", "1", "2", "3"]), tmp_path)
    assert (res["seed_cpu_s"], res["seed_cpu_s_each"], res["seed_cpu_speedup_vs_078a391"]) == (2.0, [1.0, 2.0, 3.0], 1.25)
    assert res["seed_cpu_side_by_side"]["seeds"] == [1, 2, 3]
    res = bench._seeds(parse(["--quick", "--seeds", "1", "--seed-cpu-seeds", "--seed-commit", "HEAD"]), tmp_path)
    assert res["seed_cpu_side_by_side"] is None and res["seed_cpu_speedup_vs_HEAD"] is None


def test_train_seed_starts_an_unfinished_run_over_and_skips_a_recorded_one(monkeypatch: pytest.MonkeyPatch,
                                                                           tmp_path: Path) -> None:  # fmt: skip
    from runners.benchmark import seed_cpu
    from runners.benchmark.baseline import REPO

    run_dir = tmp_path / "seed=5"
    run_dir.mkdir()
    (run_dir / "stale").write_text("from an interrupted run")
    calls = []

    def fake_run(cmd: list[str], cwd: Path, env: dict[str, str]) -> tuple[float, float]:
        calls.append(cmd)
        run_dir.mkdir(exist_ok=True)
        (run_dir / "summary.json").write_text(json.dumps({"steps_to_goal": 42}))
        return 1.5, 2.5

    monkeypatch.setattr(seed_cpu, "child_cpu_seconds", fake_run)
    row = seed_cpu.train_seed(REPO, 5, ["budget=smoke"], run_dir)
    assert row == {"seed": 5, "cpu_s": 1.5, "wall_s": 2.5, "steps_to_goal": 42} and not (run_dir / "stale").exists()
    assert "seed=5" in calls[0] and "threads=1" in calls[0] and calls[0][-1] == "budget=smoke"
    assert seed_cpu.train_seed(REPO, 5, ["budget=smoke"], run_dir) == row and len(calls) == 1  # recorded: skipped


def test_seed_cpu_side_by_side_with_078a391_runs_both_trees_and_resumes(monkeypatch: pytest.MonkeyPatch,
                                                                         tmp_path: Path) -> None:  # fmt: skip
    import subprocess

    from runners.benchmark import seed_cpu
    from runners.benchmark.baseline import REPO

    short = ["budget=smoke", "budget.max_steps=66", "env.renderer=fast", "agent.probe_every=0"]
    out = seed_cpu.seed_cpu_vs("078a391", [3], short, tmp_path)
    assert out["cpu_s"] > 0 and out["baseline_cpu_s"] > 0
    assert out["speedup"] > 0 and out["speedup"] == pytest.approx(out["baseline_cpu_s"] / out["cpu_s"])
    for tree in ("078a391", "this_tree"):
        assert (tmp_path / "seed_cpu" / tree / "seed=3" / "summary.json").exists()
    listed = subprocess.run(["git", "worktree", "list"], cwd=REPO, capture_output=True, text=True).stdout
    assert f"seed-cpu-{os.getpid()}" not in listed
    monkeypatch.setattr(seed_cpu, "child_cpu_seconds", lambda *a: pytest.fail("a recorded seed ran again"))
    assert seed_cpu.seed_cpu_vs("078a391", [3], short, tmp_path)["speedup"] == pytest.approx(out["speedup"])
