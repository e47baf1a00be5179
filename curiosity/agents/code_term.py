"""The model trained to predict the codes the planner's novelty scores (``agent.code_coef`` with
``intrinsic.terms.novelty.input=random_target``; issue 52, not in the paper).

Random-code novelty scores an imagined latent ŝ by the code g(ŝ) its head predicts, but the world model is trained
on its own latent alone, so nothing asks ŝ_{t+k} = T^k(E(o_t)) to land where g reads the code of o_{t+k}. This term
does: L gains ``code_coef`` × :func:`~curiosity.losses.nstep_code_loss` of the segment's rollout against R's codes
of the frames reached, with g's weights held (g keeps its own fit on real latents), so its gradient trains the
encoder and the transition model to predict, n steps ahead, what the planner scores.
"""

from __future__ import annotations

from torch import Tensor
from torch.func import functional_call

from curiosity.agents.representation import Encoded, LossTerm, per_frame
from curiosity.losses import nstep_code_loss
from curiosity.nets.world_model import WorldModel
from curiosity.novelty.random_target import RandomTarget
from curiosity.types import SegmentBatch


class CodePrediction(LossTerm):
    """(1/n) Σ_i ‖g(ŝ_{t+i}) − R(o_{t+i})‖² over a segment batch, g's weights detached; 0 until R is standardised.

    Args:
        target: the novelty's :class:`~curiosity.novelty.random_target.RandomTarget` (R and g); not a submodule here:
            the novelty term trains and saves it.
        coef: the term's weight (``agent.code_coef``).
    """

    def __init__(self, target: RandomTarget, coef: float = 1.0) -> None:
        super().__init__(coef)
        self._target = [target]

    def forward(self, model: WorldModel, seg: SegmentBatch, enc: Encoded) -> Tensor:
        """The scalar loss: ``enc.z`` (B, n + 1, d), ``enc.a1h`` (B, n, A), ``seg.obs`` (B, n + 1, *obs)."""
        target = self._target[0]
        z0 = enc.z[:, 0]
        if not bool(target.calibrated):
            return z0.sum() * 0.0
        codes = per_frame(target.codes, seg.obs[:, 1:])
        # a copy: g takes its own optimiser step before this loss is backpropagated (detach would share its storage)
        held = {name: p.detach().clone() for name, p in target.head.named_parameters()}

        def head(z: Tensor) -> Tensor:
            return functional_call(target.head, held, (z,))

        return nstep_code_loss(z0, enc.a1h, codes.to(z0.dtype), seg.terminateds, model.transition, head)


def code_term(target: RandomTarget | None, coef: float) -> dict[str, CodePrediction]:
    """``{"code": CodePrediction}`` for ``coef`` > 0 (``target`` required then), else ``{}``."""
    if coef <= 0:
        return {}
    if target is None:
        raise ValueError(f"agent.code_coef={coef}: the model predicts random codes, which need "
                         "intrinsic.terms.novelty.input=random_target")  # fmt: skip
    return {"code": CodePrediction(target, coef)}


__all__ = ["CodePrediction", "code_term"]
