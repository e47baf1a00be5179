"""Where the arithmetic of an env step goes: FLOPs and times of the default agent's parts, beside a matmul peak.

Each part is one call on the agent :func:`~runners.benchmark.components.filled_agent` builds (the default config,
a memory of N rows), counted once and timed (median of repeats):

- ``encoder_forward``: E(o) of one observation in eval mode, as acting encodes it (per frame: one stacked observation);
- ``encoder_forward_backward``: E of a training batch's B·(n + 1) observations, forward and backward (per frame);
- ``heads``: the transition and reward models' n-step losses on a training batch, forward and backward;
- ``train_iteration``: ``agent._iteration()`` (sampling, encoder, heads, regulariser, Adam);
- ``novelty``: the novelty term of one real transition (standardise, KDE over the N rows);
- ``planning``: ``agent._plan``: all A^H action sequences through the transition model and the intrinsic terms;
- ``refresh``: the novelty memory re-encoded and refitted (the k-d tree of its bandwidth runs in scipy: not counted).

How often each runs per env step comes from the composed config: frames encoded when acting 1 + 1/``train_every``
(o_{t+1}, and o_t again once a training call has changed the encoder); ``iters_per_train``/``train_every``
iterations; one novelty score; a plan every ``planner.hold`` × ``planner.commit`` steps; a refresh every
``refresh_every`` steps. The encoder's and heads' rows are inside the iteration's and are not added to the total.

FLOPs: ``torch.utils.flop_counter.FlopCounterMode`` counts matrix products and convolutions (2 per multiply-add,
backward included); the elementwise arithmetic it leaves out (the KDE's distances, shifts and exponentials,
activations, losses) is counted from the shapes by :class:`ElementwiseCounter`: 1 FLOP per output element of a
floating-point pointwise op, 1 per input element of a reduction (max-pooling, copies, indexing and Adam's fused
foreach updates are not counted).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from omegaconf import DictConfig
from torch import Tensor
from torch.utils._python_dispatch import TorchDispatchMode
from torch.utils._pytree import tree_leaves
from torch.utils.flop_counter import FlopCounterMode

from curiosity.agents.paper import PaperAgent
from curiosity.agents.representation import encode_segments
from curiosity.losses.model import nstep_reward_loss, nstep_transition_loss
from curiosity.nets.onehot import one_hot
from runners.benchmark.components import filled_agent
from runners.benchmark.timing import timed

NOT_ARITHMETIC = {torch.ops.aten.clone}  # tagged pointwise, but a copy


class ElementwiseCounter(TorchDispatchMode):
    """FLOPs of the elementwise ops ``FlopCounterMode`` does not count, from shapes: each floating-point pointwise op
    (``torch.Tag.pointwise``) 1 per output element, each reduction (``torch.Tag.reduction``) 1 per input element.
    ``flops`` holds the sum of every op run inside the ``with`` block (forward and backward)."""

    def __init__(self) -> None:
        super().__init__()
        self.flops = 0

    def __torch_dispatch__(self, func: Any, types: Any, args: tuple = (), kwargs: dict | None = None) -> Any:
        out = func(*args, **(kwargs or {}))
        self.flops += elementwise_flops(func, args, out)
        return out


def elementwise_flops(func: Any, args: tuple, out: Any) -> int:
    """FLOPs one aten call ``func(*args) -> out`` adds to :class:`ElementwiseCounter` (0 for any other op)."""
    tags = getattr(func, "tags", ())
    if torch.Tag.pointwise in tags and func.overloadpacket not in NOT_ARITHMETIC:
        return sum(t.numel() for t in tree_leaves(out) if isinstance(t, Tensor) and t.is_floating_point())
    if torch.Tag.reduction in tags and args and isinstance(args[0], Tensor) and args[0].is_floating_point():
        return args[0].numel()
    return 0


def count_flops(fn: Callable[[], object]) -> tuple[int, int]:
    """(matrix-product and convolution FLOPs counted by ``FlopCounterMode``, elementwise FLOPs counted by
    :class:`ElementwiseCounter`) of one call of ``fn``."""
    with FlopCounterMode(display=False) as matmuls, ElementwiseCounter() as elementwise:
        fn()
    return int(matmuls.get_total_flops()), elementwise.flops


def matmul_gflop_per_s(size: int = 1024, repeats: int = 10) -> dict[str, float]:
    """Rate of float32 ``torch.mm`` of two (size, size) matrices on the current torch threads: 2·size³ FLOPs over the
    median time of ``repeats`` calls (after two warm-up calls)."""
    a, b = torch.randn(size, size), torch.randn(size, size)
    ms = timed(lambda: torch.mm(a, b), repeats)
    return {"size": size, "repeats": repeats, "ms": ms, "gflop_per_s": 2 * size**3 / 1e6 / ms}


@dataclass
class Part:
    """One call of a part of an env step: ``run()`` does ``units`` units of it (``per``: frames, …) and runs
    ``per_env_step`` times per env step (in units); ``within``: the part whose count already includes it."""

    run: Callable[[], object]
    per: str
    per_env_step: float
    units: int = 1
    within: str | None = None
    repeats: float = 1.0  # times the benchmark's repeats (short calls are timed more often, a refresh less)


def _heads_step(agent: PaperAgent, seg: Any, z: Tensor) -> None:
    """Forward and backward of the transition and reward models' n-step losses (as the iteration computes them) on
    a batch's latents z (B, n + 1, d), which are leaves here: the encoder is not in it."""
    model, w = agent.model, agent.weights
    z = z.detach().requires_grad_(True)
    a1h = one_hot(seg.act, model.n_actions).to(z.dtype)
    targets = z[:, 1:].detach() if w.detach_targets else z[:, 1:]
    members = model.transition.members
    loss = sum(nstep_transition_loss(z[:, 0], a1h, targets, seg.terminateds, m, normalised=w.normalised_transition)
               for m in members) / len(members)  # fmt: skip
    if w.reward > 0 and model.reward_model is not None:
        loss = loss + w.reward * nstep_reward_loss(z[:, :-1], a1h, seg.rewards, seg.terminateds, model.reward_model)
    loss.backward()


def _training_parts(agent: PaperAgent, cfg: DictConfig) -> dict[str, Part]:
    """The training parts: the encoder forward and backward on one batch, the heads, the whole iteration."""
    b, n = int(cfg.agent.batch_size), int(cfg.agent.n_step)
    iterations = int(cfg.budget.iters_per_train) / int(cfg.budget.train_every)
    seg = agent.replay.sample_segments(b, n, np.random.default_rng(0))
    frames = seg.obs.reshape(-1, *seg.obs.shape[2:])
    with agent.model.evaluating():
        z = encode_segments(agent.model, seg).z

    def encoder_step() -> None:
        out = agent.model.encode(frames)
        out.backward(torch.ones_like(out))

    agent.model.train()
    return {
        "encoder_forward_backward": Part(encoder_step, "frame", b * (n + 1) * iterations, units=len(frames),
                                         within="train_iteration"),
        "heads": Part(lambda: _heads_step(agent, seg, z), "iteration", iterations, within="train_iteration"),
        "train_iteration": Part(agent._iteration, "iteration", iterations),
    }  # fmt: skip


def agent_parts(agent: PaperAgent, obs: np.ndarray, cfg: DictConfig) -> dict[str, Part]:
    """The parts of an env step of ``agent`` (filled, its memory refreshed) at observation ``obs`` (*obs_shape), each
    with its calls per env step from ``cfg`` (the agent's composed config)."""
    cur = agent.novelty
    assert cur is not None, "the benchmark measures the latent novelty memory"
    one = torch.as_tensor(obs).unsqueeze(0)
    with agent.model.evaluating():
        z0 = agent.model.encode(one)
    edge = (z0, torch.tensor([0]), agent.model.next(z0, torch.tensor([0])).detach())

    def encode() -> None:
        with agent.model.evaluating():
            agent.model.encode(one)

    def plan() -> None:
        with agent.model.evaluating():
            agent._plan(z0[0], obs)

    refresh_every = int(cfg.intrinsic.terms.novelty.refresh_every)
    return {
        "encoder_forward": Part(encode, "frame", 1 + 1 / int(cfg.budget.train_every), repeats=5),
        **_training_parts(agent, cfg),
        "novelty": Part(lambda: cur.novelty(*edge), "query", 1.0, repeats=5),
        "planning": Part(plan, "plan", 1 / (int(cfg.planner.hold) * int(cfg.planner.commit))),
        "refresh": Part(cur.refresh, "refresh", 1 / refresh_every, repeats=0.25),
    }


def measure_part(part: Part, repeats: int, peak: float) -> dict[str, Any]:
    """A part's FLOPs (per unit: matrix products, elementwise; GFLOP), ms per unit (median of repeats), GFLOP/s, its
    fraction of ``peak`` GFLOP/s, and per env step (units, GFLOP, ms)."""
    matmul, elementwise = count_flops(part.run)
    ms = timed(part.run, max(2, round(repeats * part.repeats)), warmup=1) / part.units
    gflop = (matmul + elementwise) / part.units / 1e9
    rate = gflop / ms * 1e3
    return {"per": part.per, "flop_matmul": matmul // part.units, "flop_elementwise": elementwise // part.units,
            "gflop_per_call": gflop, "ms_per_call": ms, "gflop_per_s": rate, "peak_fraction": rate / peak,
            "per_env_step": part.per_env_step, "gflop": gflop * part.per_env_step, "ms": ms * part.per_env_step,
            "within": part.within}  # fmt: skip


def total(parts: dict[str, dict[str, Any]], peak: float) -> dict[str, float]:
    """GFLOP, ms, GFLOP/s and fraction of ``peak`` of an env step: the parts not inside another one, summed."""
    top = [p for p in parts.values() if p["within"] is None]
    gflop, ms = sum(p["gflop"] for p in top), sum(p["ms"] for p in top)
    return {"gflop": gflop, "ms": ms, "gflop_per_s": gflop / ms * 1e3, "peak_fraction": gflop / ms * 1e3 / peak}


def flops_per_env_step(memory: int, repeats: int, matmul_size: int = 1024) -> dict[str, Any]:
    """Every part of an env step of the default agent at a memory of ``memory`` rows (:func:`measure_part`) and
    their total, beside the matmul rate (:func:`matmul_gflop_per_s`) each part's rate is a fraction of.

    Returns:
        ``matmul`` (its rate), ``setup`` (memory, batch, n_step, the schedule read from the config) and
        ``parts``: name -> :func:`measure_part`'s dict, with ``total`` (:func:`total`).
    """
    agent, obs, *_ = filled_agent([], memory)
    cfg = agent.cfg
    peak = matmul_gflop_per_s(matmul_size, max(3, repeats))
    parts = {name: measure_part(p, repeats, peak["gflop_per_s"]) for name, p in agent_parts(agent, obs, cfg).items()}
    parts["total"] = total(parts, peak["gflop_per_s"])
    setup = {"memory": len(agent.novelty.memory) if agent.novelty is not None else 0,
             "batch": int(cfg.agent.batch_size), "n_step": int(cfg.agent.n_step),
             "iters_per_train": int(cfg.budget.iters_per_train), "train_every": int(cfg.budget.train_every),
             "plan_every": int(cfg.planner.hold) * int(cfg.planner.commit),
             "refresh_every": int(cfg.intrinsic.terms.novelty.refresh_every), "threads": torch.get_num_threads()}  # fmt: skip
    return {"matmul": peak, "setup": setup, "parts": parts}
