"""The total representation loss of one iteration (paper §3.8), from one batch of n-step segments."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import torch
from torch import Tensor

from curiosity.agents.world_model import WorldModel
from curiosity.errors import NumericalFault
from curiosity.info.backward import backward_predictor_nll
from curiosity.info.yardstick import latent_logdet
from curiosity.losses.model import nstep_backward_loss, nstep_reward_loss, nstep_transition_loss
from curiosity.nets.onehot import one_hot
from curiosity.types import SegmentBatch

Regulariser = Callable[[Tensor, Tensor, Tensor], tuple[Tensor, dict[str, float]]]

LOSS_KEYS = ("losses/transition", "losses/entropy", "losses/reward", "losses/backward", "losses/total", "info/gram_offdiag",
             "info/latent_logdet")


def check_finite(term: str, value: Tensor) -> None:
    """Raise :class:`~curiosity.errors.NumericalFault` naming ``term`` if ``value`` holds a NaN or an Inf."""
    if not bool(torch.isfinite(value).all()):
        raise NumericalFault(term, "nan" if bool(torch.isnan(value).any()) else "inf")


@dataclass
class LossWeights:
    """Coefficients of L = c_T L_trans(n) + λ_back L_back(n) + [regulariser, weighted inside] + λ_R L_R(n)."""

    transition: float = 1.0
    reward: float = 1.0
    backward: float = 0.0
    sigma_b: float = 1.0
    normalised_transition: bool = False
    detach_targets: bool = True


@dataclass
class Encoded:
    """Latents of a segment batch: z (B, n + 1, d) and one-hot actions (B, n, A)."""

    z: Tensor
    a1h: Tensor


def encode_segments(model: WorldModel, seg: SegmentBatch) -> Encoded:
    """Encode every observation of the segments in one pass: (B, n + 1, *obs) -> (B, n + 1, d)."""
    b, n1 = seg.obs.shape[:2]
    z = model.encode(seg.obs.reshape(b * n1, *seg.obs.shape[2:])).reshape(b, n1, -1)
    return Encoded(z=z, a1h=one_hot(seg.act, model.n_actions).to(z.dtype))


def representation_loss(
    model: WorldModel, seg: SegmentBatch, enc: Encoded, regulariser: Regulariser, w: LossWeights
) -> tuple[Tensor, dict[str, float]]:
    """L_total for one batch; returns the loss and every term as a float (keys in ``LOSS_KEYS``).

    The regulariser sees the first transition of each segment: (z_t, a_t, z_{t+1}); ``info/latent_logdet`` is the
    common yardstick :func:`~curiosity.info.latent_logdet` of the same next latents z_{t+1}.
    """
    z, a1h = enc.z, enc.a1h
    targets = z[:, 1:].detach() if w.detach_targets else z[:, 1:]
    members = model.transition.members  # an ensemble trains each member on its own loss
    l_trans = sum(nstep_transition_loss(z[:, 0], a1h, targets, seg.terminateds, member,
                                        normalised=w.normalised_transition) for member in members) / len(members)  # fmt: skip
    check_finite("losses/transition", l_trans)
    l_reg, logs = regulariser(z[:, 0], a1h[:, 0], z[:, 1])
    check_finite("losses/entropy", l_reg)
    total = w.transition * l_trans + l_reg
    logs = {"losses/transition": l_trans.item(), **logs, "info/latent_logdet": latent_logdet(z[:, 1])}
    if w.reward > 0 and model.reward_model is not None:
        l_r = nstep_reward_loss(z[:, :-1], a1h, seg.rewards, seg.terminateds, model.reward_model)
        check_finite("losses/reward", l_r)
        total = total + w.reward * l_r
        logs["losses/reward"] = l_r.item()
    if w.backward > 0 and model.backward is not None:
        y = torch.cat([z[:, :-1], a1h], dim=2)
        nll = partial(backward_predictor_nll, sigma_b=w.sigma_b)
        l_b = nstep_backward_loss(y, z[:, 1:], seg.terminateds, model.backward, nll)
        check_finite("losses/backward", l_b)
        total = total + w.backward * l_b
        logs["losses/backward"] = l_b.item()
    logs["losses/total"] = total.item()
    return total, logs
