"""The total representation loss of one iteration (paper §3.8), from one batch of n-step segments."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import partial

import torch
from torch import Tensor, nn

from curiosity.nets.world_model import WorldModel
from curiosity.errors import NumericalFault
from curiosity.info.backward import backward_predictor_nll
from curiosity.info.yardstick import latent_logdet
from curiosity.losses.model import nstep_backward_loss, nstep_reward_loss, nstep_transition_loss
from curiosity.nets.onehot import one_hot
from curiosity.types import SegmentBatch

Regulariser = Callable[[Tensor, Tensor, Tensor], tuple[Tensor, dict[str, float]]]


class LossTerm(nn.Module):
    """A plug-in term of the representation loss (``agent.extra_terms.<name>``: ``_target_`` a subclass, ``coef`` its
    weight, built with ``latent_dim`` and ``n_actions``): L gains ``coef × term(model, seg, enc)``, logged as
    ``losses/<name>``. A term may own parameters (a head): they are trained by the agent's optimiser with the world
    model's and saved in its checkpoints."""

    def __init__(self, coef: float = 1.0) -> None:
        super().__init__()
        self.coef = float(coef)

    def forward(self, model: WorldModel, seg: SegmentBatch, enc: Encoded) -> Tensor:  # pragma: no cover - abstract
        """The term's scalar value for one batch of segments (``enc.z``: (B, n + 1, d), ``enc.a1h``: (B, n, A))."""
        raise NotImplementedError

LOSS_KEYS = (
    "losses/transition",
    "losses/entropy",
    "losses/reward",
    "losses/backward",
    "losses/total",
    "info/gram_offdiag",
    "info/latent_logdet",
)


def check_finite(term: str, value: Tensor) -> None:
    """Raise :class:`~curiosity.errors.NumericalFault` naming ``term`` if ``value`` holds a NaN or an Inf."""
    if not bool(torch.isfinite(value).all()):
        raise NumericalFault(term, "nan" if bool(torch.isnan(value).any()) else "inf")


@dataclass
class LossWeights:
    """The config weights of the named loss terms, L = Σ_k w_k L_k (:func:`total_loss`), and the losses' options.

    ``transition`` = ``agent.transition_coef``, ``reward`` = ``agent.reward_coef`` (λ_R), ``backward`` =
    ``backward.coef`` (λ_back), ``q`` = ``agent.q_coef`` (the TD loss of Q-tree agents); the entropy regulariser weighs itself
    (``entropy.coef``), so its weight here is 1.
    """

    transition: float = 1.0
    reward: float = 1.0
    backward: float = 0.0
    q: float = 1.0
    sigma_b: float = 1.0
    normalised_transition: bool = False
    detach_targets: bool = True

    def of_terms(self) -> dict[str, float]:
        """name -> weight of every term a loss may have."""
        return {"transition": self.transition, "entropy": 1.0, "reward": self.reward, "backward": self.backward,
                "q": self.q}  # fmt: skip


def total_loss(terms: Mapping[str, Tensor], weights: Mapping[str, float]) -> Tensor:
    """L = Σ_k w_k L_k over the named terms present, in their order: ``terms`` name -> scalar, ``weights`` name -> w."""
    total: Tensor | None = None
    for name, value in terms.items():
        total = weights[name] * value if total is None else total + weights[name] * value
    if total is None:
        raise ValueError("a loss needs at least one term")
    return total


@dataclass
class Encoded:
    """Latents of a segment batch: z (B, n + 1, d), one-hot actions (B, n, A) and, with a target encoder, the
    transition loss's targets (B, n, d) of o_{t+1} .. o_{t+n} (else None: the targets are z[:, 1:])."""

    z: Tensor
    a1h: Tensor
    targets: Tensor | None = None


def per_frame(fn: Callable[[Tensor], Tensor], frames: Tensor) -> Tensor:
    """``fn`` over every frame of segments in one pass: fn (M, *obs) -> (M, k), frames (B, n, *obs) -> (B, n, k)."""
    b, n = frames.shape[:2]
    return fn(frames.reshape(b * n, *frames.shape[2:])).reshape(b, n, -1)


def encode_segments(model: WorldModel, seg: SegmentBatch, target: Callable[[Tensor], Tensor] | None = None) -> Encoded:
    """Encode every observation of the segments in one pass: (B, n + 1, *obs) -> (B, n + 1, d); with ``target`` (a
    slowly moving copy of the encoder, no gradient) also the targets of o_{t+1} .. o_{t+n}, (B, n, d)."""
    z = per_frame(model.encode, seg.obs)
    targets = per_frame(target, seg.obs[:, 1:]) if target is not None else None
    return Encoded(z=z, a1h=one_hot(seg.act, model.n_actions).to(z.dtype), targets=targets)


def representation_terms(
    model: WorldModel, seg: SegmentBatch, enc: Encoded, regulariser: Regulariser, w: LossWeights,
    extra: Mapping[str, LossTerm] | None = None,
) -> tuple[dict[str, Tensor], dict[str, float]]:
    """The representation loss's named terms for one batch (each checked finite), and their values as floats.

    Terms: ``transition`` (n-step, averaged over an ensemble's members; its targets are ``enc.targets`` when a target
    encoder made them, else z_{t+1} .. z_{t+n}, detached with ``w.detach_targets``), ``entropy`` (the regulariser on the first
    transition of each segment, (z_t, a_t, z_{t+1}), weighted inside), ``reward`` (with a reward model and
    λ_R > 0), ``backward`` (with a backward predictor and λ_back > 0), then each plug-in of ``extra`` under its
    name (:class:`LossTerm`; weighted by :func:`term_weights`). Logs: ``losses/<term>``, the regulariser's own
    diagnostics, and ``info/latent_logdet``, the common yardstick :func:`~curiosity.info.latent_logdet` of z_{t+1}.
    """
    z, a1h = enc.z, enc.a1h
    if enc.targets is not None:  # a target encoder's (agent.target_tau > 0)
        targets = enc.targets
    else:
        targets = z[:, 1:].detach() if w.detach_targets else z[:, 1:]
    members = model.transition.members  # an ensemble trains each member on its own loss
    terms = {"transition": sum(nstep_transition_loss(z[:, 0], a1h, targets, seg.terminateds, member,
                                                     normalised=w.normalised_transition)
                               for member in members) / len(members)}  # fmt: skip
    terms["entropy"], logs = regulariser(z[:, 0], a1h[:, 0], z[:, 1])
    if w.reward > 0 and model.reward_model is not None:
        terms["reward"] = nstep_reward_loss(z[:, :-1], a1h, seg.rewards, seg.terminateds, model.reward_model)
    if w.backward > 0 and model.backward is not None:
        y = torch.cat([z[:, :-1], a1h], dim=2)
        nll = partial(backward_predictor_nll, sigma_b=w.sigma_b)
        terms["backward"] = nstep_backward_loss(y, z[:, 1:], seg.terminateds, model.backward, nll)
    for name, term in (extra or {}).items():
        terms[name] = term(model, seg, enc)
    for name, value in terms.items():
        check_finite(f"losses/{name}", value)
    logs = {"losses/transition": terms["transition"].item(), **logs, "info/latent_logdet": latent_logdet(z[:, 1])}
    logs.update({f"losses/{name}": terms[name].item() for name in ("reward", "backward", *(extra or {})) if name in terms})
    return terms, logs


def term_weights(w: LossWeights, extra: Mapping[str, LossTerm] | None = None) -> dict[str, float]:
    """name -> weight of every term a loss may have: the config's (:meth:`LossWeights.of_terms`) and each plug-in's
    ``coef``."""
    return {**w.of_terms(), **{name: term.coef for name, term in (extra or {}).items()}}


def representation_loss(
    model: WorldModel, seg: SegmentBatch, enc: Encoded, regulariser: Regulariser, w: LossWeights
) -> tuple[Tensor, dict[str, float]]:
    """L_total of the representation terms alone (:func:`representation_terms`, :func:`total_loss`); logs as there,
    with ``losses/total``."""
    terms, logs = representation_terms(model, seg, enc, regulariser, w)
    total = total_loss(terms, w.of_terms())
    logs["losses/total"] = total.item()
    return total, logs
