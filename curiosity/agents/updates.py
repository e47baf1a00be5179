"""How a gradient iteration steps the paper's agent's parameters (``agent.updates``).

``joint`` (default): one optimiser over every trained module and one backward pass of L = Σ_k w_k L_k, the TD term of a
Q-tree agent included.

``nsrs``: as NSRS's code steps (docs/protocol.md §3.3): a representation step -- one backward pass of the
representation loss, then an optimiser over the encoder alone *and* one over the whole world model (so the encoder gets
two updates, with separate moment estimates) -- then, for a Q-tree agent, a Q step: the TD loss recomputed with the
updated encoder, its gradients clamped elementwise to [-1, 1], and a third optimiser over encoder + Q; as in NSRS, the
first training call has no Q step (the representation trains alone). Every optimiser is built from ``agent.optimizer``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import torch
from torch import Tensor, nn

from curiosity.build import build

Q_GRAD_CLAMP = 1.0  # NSRS clamps the Q step's gradients elementwise to [-1, 1]


def build_optimizers(rule: str, optimizer_cfg: Any, model: nn.Module, encoder: nn.Module, q: nn.Module | None,
                     extra: nn.Module | None = None) -> dict[str, torch.optim.Optimizer]:  # fmt: skip
    """The optimisers of ``rule``: ``{"all"}`` (joint), or ``{"encoder", "model"[, "q"]}`` (nsrs); ``extra`` (the
    plug-in loss terms' heads) is trained with the world model."""
    extra_params = list(extra.parameters()) if extra is not None else []
    if rule == "joint":
        return {"all": build(optimizer_cfg, params=[*model.parameters(), *extra_params,
                                                     *(q.parameters() if q is not None else ())])}  # fmt: skip
    if rule != "nsrs":
        raise ValueError(f"agent.updates={rule}: allowed: joint, nsrs")
    out = {"encoder": build(optimizer_cfg, params=list(encoder.parameters())),
           "model": build(optimizer_cfg, params=[*model.parameters(), *extra_params])}  # fmt: skip
    if q is not None:
        out["q"] = build(optimizer_cfg, params=[*encoder.parameters(), *q.parameters()])
    return out


def step(optimizers: Iterable[torch.optim.Optimizer], loss: Tensor, clamp: float | None = None) -> None:
    """Zero the gradients of ``optimizers``, backpropagate ``loss`` once, clamp every gradient to [-clamp, clamp] when
    given, and step each optimiser (a parameter in two of them is stepped twice)."""
    optimizers = list(optimizers)
    for opt in optimizers:
        opt.zero_grad(set_to_none=True)
    loss.backward()
    if clamp is not None:
        for opt in optimizers:
            for group in opt.param_groups:
                for p in group["params"]:
                    if p.grad is not None:
                        p.grad.clamp_(-clamp, clamp)
    for opt in optimizers:
        opt.step()


def optimizers_state(optimizers: Mapping[str, torch.optim.Optimizer]) -> dict[str, Any]:
    """Checkpoint entries: ``optimizer`` for the joint rule (as before the rules existed), ``optimizers`` otherwise."""
    if set(optimizers) == {"all"}:
        return {"optimizer": optimizers["all"].state_dict()}
    return {"optimizers": {name: opt.state_dict() for name, opt in optimizers.items()}}


def load_optimizers_state(optimizers: Mapping[str, torch.optim.Optimizer], state: Mapping[str, Any]) -> None:
    if "optimizers" in state:
        for name, opt in optimizers.items():
            opt.load_state_dict(state["optimizers"][name])
    else:
        optimizers["all"].load_state_dict(state["optimizer"])
