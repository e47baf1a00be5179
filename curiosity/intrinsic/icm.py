"""Intrinsic Curiosity Module (Pathak et al., 2017): the bonus is the forward model's error in a learned feature space.

Features φ are trained by an inverse model (which action led from o_t to o_{t+1}?), so they keep what the agent can
affect; a forward model predicts φ_{t+1} from (φ_t, a_t), and its error is the curiosity bonus (docs/method.md §7).
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from typing import Any

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from curiosity.intrinsic.base import IntrinsicContext, IntrinsicReward, latents_of
from curiosity.intrinsic.inputs import ReadsObsOrLatent
from curiosity.intrinsic.nets import make_feature_net, mlp
from curiosity.types import TransitionBatch


def inverse_loss(logits: Tensor, act: Tensor) -> Tensor:
    """L_inv = mean_b CE(softmax(logits_b), a_b); logits (B, n_actions), act (B,) long → scalar."""
    return F.cross_entropy(logits, act.long())


def forward_error(pred_next: Tensor, next_feat: Tensor) -> Tensor:
    """e_b = ½ ‖φ̂_{t+1} − φ_{t+1}‖², **summed** over features (Pathak's ½‖·‖²₂); (B, F), (B, F) → (B,)."""
    return 0.5 * (pred_next - next_feat).square().sum(dim=-1)


class ICM(ReadsObsOrLatent, IntrinsicReward):
    """ICM bonus r = η · ½ ‖φ̂_{t+1} − φ_{t+1}‖² and its joint training loss.

    Networks: encoder φ: (B, *obs_shape) → (B, F); inverse head cat(φ_t, φ_{t+1}) → (B, n_actions) logits;
    forward head cat(φ_t, onehot a_t) → φ̂_{t+1} (B, F). Both heads are MLPs with one hidden ReLU layer.

    Loss (one Adam step per :meth:`update`):

        L = loss_weight · [(1 − β) L_inv + β L_fwd],   L_fwd = mean_b ½ ‖φ̂_{t+1} − φ_{t+1}‖²,

    with β = 0.2 and loss_weight = 10 by default (docs/method.md §7). Norms are sums over the F features, so the
    bonus grows with ``feature_dim``; divide ``eta`` by F to get a per-feature mean. As in the original code,
    L_fwd's gradient reaches the encoder too (neither φ_t nor φ_{t+1} is detached); L_inv keeps φ from collapsing.

    :meth:`compute` runs the networks in eval mode under ``torch.no_grad`` and changes no state; :meth:`update`
    switches them back to train mode.

    Args:
        encoder: Feature network φ, (B, *obs_shape) → (B, feature_dim); pixel or vector observations.
        feature_dim: F, the width of φ's output.
        n_actions: Number of discrete actions.
        hidden: Hidden width of the inverse and forward heads.
        eta: η, bonus scale inside the module (the base class's ``scale`` is applied on top by ``__call__``).
        beta: β, weight of the forward loss against the inverse loss.
        loss_weight: Overall multiplier of the loss (10 in Pathak et al.'s code).
        lr: Adam learning rate.
        scale: Multiplier applied by :meth:`IntrinsicReward.__call__`.
        input: ``obs``: φ reads the observations o_t, o_{t+1} (Pathak's ICM); ``latent``: φ reads the agent's latents
            z_t, z_{t+1} (detached), so ICM can also score a planner's imagined latent edges.
    """

    log_keys = ("losses/icm_inverse", "losses/icm_forward")

    def __init__(
        self,
        encoder: nn.Module,
        feature_dim: int,
        n_actions: int,
        hidden: int = 64,
        eta: float = 1.0,
        beta: float = 0.2,
        loss_weight: float = 10.0,
        lr: float = 1e-3,
        scale: float = 1.0,
        input: str = "obs",
    ) -> None:
        super().__init__(scale=scale)
        self._set_input(input)
        if not 0.0 <= beta <= 1.0:
            raise ValueError(f"beta must lie in [0, 1], got {beta}")
        self.feature_dim, self.n_actions = int(feature_dim), int(n_actions)
        self.eta, self.beta, self.loss_weight = float(eta), float(beta), float(loss_weight)
        self.encoder = encoder
        self.inverse_head = mlp(2 * self.feature_dim, self.n_actions, (hidden,))
        self.forward_head = mlp(self.feature_dim + self.n_actions, self.feature_dim, (hidden,))
        self.nets = nn.ModuleDict({"encoder": encoder, "inverse_head": self.inverse_head, "forward_head": self.forward_head})
        self.optimiser = torch.optim.Adam(self.nets.parameters(), lr=lr)

    @classmethod
    def from_obs_shape(
        cls,
        *,
        obs_shape: Sequence[int],
        n_actions: int,
        feature_dim: int = 32,
        mlp_hidden: Sequence[int] = (64, 64),
        **kwargs: Any,
    ) -> ICM:
        """Build with :func:`~curiosity.intrinsic.nets.make_feature_net` as φ (conv for (C, H, W), MLP for (D,));
        ``kwargs`` go to the constructor (``hidden``, ``eta``, ``beta``, ``loss_weight``, ``lr``, ``scale``, ``input``)."""
        encoder = make_feature_net(obs_shape, feature_dim, mlp_hidden)
        return cls(encoder, feature_dim, n_actions, **kwargs)

    @classmethod
    def from_context(cls, *, context: IntrinsicContext, input: str = "obs", **kwargs: Any) -> ICM:
        """Built from the agent's parts: φ over its observations (``input=obs``) or its latents (``latent``: an MLP)."""
        shape = cls.input_shape(context, input)
        return cls.from_obs_shape(obs_shape=shape, n_actions=context.n_actions, input=input, **kwargs).to(context.device)

    def _device(self) -> torch.device:
        return next(self.nets.parameters()).device

    def _inputs(self, batch: TransitionBatch) -> tuple[Tensor, Tensor]:
        if self.input == "latent":
            z, z_next = latents_of(batch, "icm (input=latent)")
            return z.detach(), z_next.detach()
        return batch.obs, batch.next_obs

    def _predict(self, batch: TransitionBatch) -> tuple[Tensor, Tensor, Tensor]:
        """(φ̂_{t+1}, φ_{t+1}, inverse logits), shapes (B, F), (B, F), (B, n_actions)."""
        return self._predict_from(*self._inputs(batch), batch.act)

    def _predict_from(self, x: Tensor, x_next: Tensor, act: Tensor) -> tuple[Tensor, Tensor, Tensor]:
        device = self._device()
        feat = self.encoder(x.to(device).float())
        next_feat = self.encoder(x_next.to(device).float())
        onehot = F.one_hot(act.to(device).long(), self.n_actions).to(feat.dtype)
        pred_next = self.forward_head(torch.cat([feat, onehot], dim=-1))
        logits = self.inverse_head(torch.cat([feat, next_feat], dim=-1))
        return pred_next, next_feat, logits

    def compute(self, batch: TransitionBatch) -> Tensor:
        """r_b = η · ½ ‖φ̂_{t+1} − φ_{t+1}‖² (sum over features), shape (B,), without gradient or state change."""
        self.nets.eval()
        with torch.no_grad():
            pred_next, next_feat, _ = self._predict(batch)
            return self.eta * forward_error(pred_next, next_feat)

    def imagine(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        """The bonus of imagined latent edges (``input=latent`` only), (N,); no gradient or state change."""
        if self.input != "latent":
            raise ValueError("icm with input=obs scores observations; set its input to latent to score imagined steps")
        self.nets.eval()
        with torch.no_grad():
            pred_next, next_feat, _ = self._predict_from(z, z_next, a)
            return self.eta * forward_error(pred_next, next_feat)

    def update(self, batch: TransitionBatch) -> dict[str, float]:
        """One Adam step on L; returns the pre-step ``losses/icm_inverse`` and ``losses/icm_forward``."""
        self.nets.train()
        pred_next, next_feat, logits = self._predict(batch)
        l_inv = inverse_loss(logits, batch.act.to(logits.device))
        l_fwd = forward_error(pred_next, next_feat).mean()
        loss = self.loss_weight * ((1.0 - self.beta) * l_inv + self.beta * l_fwd)
        self.optimiser.zero_grad(set_to_none=True)
        loss.backward()
        self.optimiser.step()
        return {"losses/icm_inverse": float(l_inv.detach()), "losses/icm_forward": float(l_fwd.detach())}

    def to(self, device: torch.device | str) -> ICM:
        """Move networks and optimiser state to ``device`` (in place); returns ``self``."""
        self.nets.to(device)
        self.optimiser.load_state_dict(self.optimiser.state_dict())  # re-casts Adam state onto the params' device
        return self

    def state_dict(self) -> dict[str, Any]:
        """Copies of the networks (encoder, inverse, forward heads) and of the Adam state, not aliases."""
        return copy.deepcopy({"nets": self.nets.state_dict(), "optimiser": self.optimiser.state_dict()})

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned (copied, so ``state`` can be loaded into several modules)."""
        self.nets.load_state_dict(state["nets"])
        self.optimiser.load_state_dict(copy.deepcopy(state["optimiser"]))
