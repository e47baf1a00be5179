"""How a gradient iteration steps the paper's agent's parameters (``agent.updates``).

``joint`` (default): one optimiser over every trained module and one backward pass of L = Σ_k w_k L_k, the TD term of a
Q-tree agent included.

``nsrs``: as NSRS's code steps (docs/protocol.md §3.3): a representation step -- one backward pass of the
representation loss, then an optimiser over the encoder alone *and* one over the whole world model (so the encoder gets
two updates, with separate moment estimates) -- then, for a Q-tree agent, a Q step: the TD loss recomputed with the
updated encoder, its gradients clamped elementwise to [-1, 1], and a third optimiser over encoder + Q; as in NSRS, the
first training call has no Q step (the representation trains alone). Every optimiser is built from ``agent.optimizer``.

Each rule is an :class:`UpdateRule`: it owns its optimisers and the order of its steps, and builds the logged
``losses/total`` with :func:`~curiosity.agents.representation.total_loss` (the only place a total is formed).
"""

from __future__ import annotations

import abc
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import torch
from torch import Tensor, nn

from curiosity.agents.representation import check_finite, total_loss
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


@dataclass(frozen=True)
class TDTerm:
    """A Q-tree agent's TD loss for one iteration, unweighted (a scalar): ``on_latents()`` scores it on the iteration's
    latents (the joint step); ``fresh()`` re-encodes with the encoder as stepped so far (NSRS's Q step)."""

    on_latents: Callable[[], Tensor]
    fresh: Callable[[], Tensor]


class UpdateRule(abc.ABC):
    """How one gradient iteration steps the agent's parameters: the optimisers and the order of the steps.

    Args:
        optimizer_cfg: ``agent.optimizer`` (a ``_target_`` node taking ``params``).
        model: the world model; encoder: its encoder; q: the Q network of a Q-tree agent (or None); extra: the
            plug-in loss terms' heads (trained with the world model).
    """

    name: str

    def __init__(self, optimizer_cfg: Any, model: nn.Module, encoder: nn.Module, q: nn.Module | None,
                 extra: nn.Module | None = None) -> None:  # fmt: skip
        self.optimizers = build_optimizers(self.name, optimizer_cfg, model, encoder, q, extra)

    @abc.abstractmethod
    def steps_q(self, calls: int) -> bool:
        """Whether training call number ``calls`` (1-based) steps a Q network, if the agent has one."""

    @abc.abstractmethod
    def apply(self, terms: Mapping[str, Tensor], weights: Mapping[str, float], td: TDTerm | None) -> dict[str, float]:
        """Step on the representation ``terms`` (name -> scalar) weighted by ``weights`` and, when ``td`` is given, on
        the TD term (weight ``weights["q"]``); returns ``losses/total`` (and ``losses/q``, unweighted)."""


class JointUpdate(UpdateRule):
    """One optimiser, one backward pass of L = Σ_k w_k L_k over every term, the TD term included."""

    name = "joint"

    def steps_q(self, calls: int) -> bool:
        return True

    def apply(self, terms: Mapping[str, Tensor], weights: Mapping[str, float], td: TDTerm | None) -> dict[str, float]:
        logs: dict[str, float] = {}
        if td is not None:
            terms = {**terms, "q": td.on_latents()}
            logs["losses/q"] = terms["q"].item()
        loss = total_loss(terms, weights)
        check_finite("losses/total", loss)
        step(self.optimizers.values(), loss)
        logs["losses/total"] = loss.item()
        return logs


class NSRSUpdate(UpdateRule):
    """NSRS's order: a representation step (encoder and world-model optimisers), then a Q step with the updated
    encoder, its gradients clamped to [-1, 1]; no Q step in the first training call. ``losses/total`` is the sum of
    the two steps' losses."""

    name = "nsrs"

    def steps_q(self, calls: int) -> bool:
        return calls > 1

    def apply(self, terms: Mapping[str, Tensor], weights: Mapping[str, float], td: TDTerm | None) -> dict[str, float]:
        loss = total_loss(terms, weights)
        check_finite("losses/total", loss)
        step((self.optimizers["encoder"], self.optimizers["model"]), loss)
        logs = {"losses/total": loss.item()}
        if td is not None:
            q_loss = total_loss({"q": td.fresh()}, weights)
            step((self.optimizers["q"],), q_loss, clamp=Q_GRAD_CLAMP)
            logs["losses/q"] = q_loss.item() / weights["q"] if weights["q"] else 0.0
            logs["losses/total"] += q_loss.item()
        return logs


UPDATE_RULES: dict[str, type[UpdateRule]] = {rule.name: rule for rule in (JointUpdate, NSRSUpdate)}


def update_rule(name: str, optimizer_cfg: Any, model: nn.Module, encoder: nn.Module, q: nn.Module | None,
                extra: nn.Module | None = None) -> UpdateRule:  # fmt: skip
    """The rule ``agent.updates`` names (``joint`` or ``nsrs``), with its optimisers."""
    if name not in UPDATE_RULES:
        raise ValueError(f"agent.updates={name}: allowed: {', '.join(UPDATE_RULES)}")
    return UPDATE_RULES[name](optimizer_cfg, model, encoder, q, extra)
