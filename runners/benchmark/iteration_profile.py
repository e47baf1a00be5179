"""Where a training iteration's time goes: operator self-times and the arithmetic of its convolutions (issue 13's
"what stands in the way" of a faster iteration, measured by the benchmark instead of by hand)."""

from __future__ import annotations

import time
from typing import Any

from torch.profiler import ProfilerActivity, profile

from runners.benchmark.components import filled_agent


def _is_conv(key: str) -> bool:
    """A convolution operator (``aten::conv2d`` and its dispatch layers, whose own self time is small, and the kernel
    that computes, which differs by build and shape: ``mkldnn_convolution``, ``_slow_conv2d_forward``, …)."""
    return any(name in key for name in ("convolution", "conv2d", "conv_depthwise"))


def summarise(events: list[Any], iterations: int, wall_s: float, top: int = 8) -> dict[str, Any]:
    """A profile's operator events (objects with ``key``, ``self_cpu_time_total`` in µs and ``flops``, as
    ``torch.profiler``'s ``key_averages()`` gives them) as the benchmark's ``train_iter_profile``: ms per iteration
    (wall, under the profiler), the ``top`` operators' shares of the summed self time and ``other``, the shares of the
    convolutions forward and backward, the forward arithmetic the profiler counts (GFLOP per iteration, of which the
    convolutions), and the convolutions' rate estimated as 3 × their forward FLOPs (a backward pass costs about two
    forward passes) over their forward + backward self time."""
    self_us = {e.key: float(e.self_cpu_time_total) for e in events}
    total = sum(self_us.values()) or 1.0
    ranked = sorted(self_us.items(), key=lambda kv: -kv[1])
    shares = {k: v / total for k, v in ranked[:top]}
    shares["other"] = max(0.0, 1.0 - sum(shares.values()))
    forward = sum(v for k, v in self_us.items() if _is_conv(k) and "backward" not in k)
    backward = sum(v for k, v in self_us.items() if _is_conv(k) and "backward" in k)
    conv_flops = sum(float(e.flops or 0) for e in events if e.key == "aten::conv2d")
    all_flops = sum(float(e.flops or 0) for e in events)
    conv_s = (forward + backward) / 1e6
    return {
        "iterations": iterations,
        "ms_per_iteration": 1e3 * wall_s / iterations,
        "op_share": shares,
        "conv_forward_share": forward / total,
        "conv_backward_share": backward / total,
        "forward_gflop_per_iteration": all_flops / iterations / 1e9,
        "conv_forward_gflop_per_iteration": conv_flops / iterations / 1e9,
        "conv_gflop_per_s_estimate": 3 * conv_flops / 1e9 / conv_s if conv_s > 0 else 0.0,
    }


def train_iter_profile(batch: int, iterations: int) -> dict[str, Any]:
    """``torch.profiler`` over ``iterations`` training iterations of the default agent at ``batch`` (replay of 500
    random steps, after two unprofiled iterations), summarised by :func:`summarise`. The profiler adds its own
    overhead: read the shares, and take the iteration's time from ``train_iter_ms``."""
    agent, *_ = filled_agent([f"agent.batch_size={batch}"], 500)
    for _ in range(2):
        agent._iteration()
    with profile(activities=[ProfilerActivity.CPU], with_flops=True) as prof:
        start = time.perf_counter()
        for _ in range(iterations):
            agent._iteration()
        wall = time.perf_counter() - start
    return {"batch": batch, **summarise(list(prof.key_averages()), iterations, wall)}
