"""The benchmark's parts run and account for time correctly (no timing assertions: speeds are the benchmark's job)."""

from __future__ import annotations

import os

import json
from pathlib import Path

import pytest

import runners.benchmark.timing as timing
from runners.bench import parse, report
from runners.benchmark.components import planning_at
from runners.benchmark.iteration_profile import summarise, train_iter_profile
from runners.benchmark.runs import seed_runs
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
        "seeds": [{"seed": 100, "steps_to_goal": 200, "wall_s": 100.0}],
        "wall_share": {"train": 0.5, "other": 0.5},
    }
    text = report(res)
    assert "speed-up 2.50x" in text and "10.0 vs 15.0 ms: 1.50x" in text
    assert "| 100 | 200 | 100 |" in text and "train 50.0%" in text
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
