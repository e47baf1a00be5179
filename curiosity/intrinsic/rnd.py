"""Random Network Distillation (Burda et al., 2018): the bonus is a predictor's error at matching a fixed random net.

Both networks see the *next* observation o_{t+1}, normalised per pixel/feature by running statistics and clipped;
the bonus is divided by the running std of its own discounted return (docs/method.md §7).
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from typing import Any

import torch
from torch import Tensor, nn

from curiosity.intrinsic.base import IntrinsicContext, IntrinsicReward, latents_of
from curiosity.intrinsic.inputs import ReadsObsOrLatent
from curiosity.intrinsic.nets import make_feature_net, make_predictor_net
from curiosity.intrinsic.normalisers import ReturnNormaliser, RunningMeanStd
from curiosity.types import TransitionBatch


def distillation_error(pred: Tensor, target: Tensor) -> Tensor:
    """e_b = mean_k (f̂_k − f_k)², the **mean** over the K outputs; (B, K), (B, K) → (B,)."""
    return (pred - target).square().mean(dim=-1)


class RND(ReadsObsOrLatent, IntrinsicReward):
    """RND bonus r = mean_k (f̂(x)_k − f(x)_k)² / σ_R, with x = clip((o_{t+1} − μ_o) / σ_o, −c, c).

    f is a fixed random target (``requires_grad`` off, never stepped); f̂ is trained by Adam on the batch mean of
    the same error. μ_o, σ_o are per-element running statistics of next observations (:class:`RunningMeanStd` of
    shape ``obs_shape``); σ_R is the running std of the discounted raw bonus R ← γ_int R + r
    (:class:`ReturnNormaliser`, no mean subtraction).

    Statistics contract:
        * :meth:`compute` reads the statistics and **never** changes them (nor any network or optimiser), so a
          planner may call it any number of times.
        * :meth:`observe` is the only method that changes them: first it merges ``batch.next_obs`` into (μ_o, σ_o),
          then it feeds the raw bonus of the batch, under the updated statistics, into σ_R, treating the B
          transitions as consecutive steps of one time-ordered stream (update-then-use for both).
        * :meth:`update` calls :meth:`observe` on its batch first when ``observe_in_update`` is true (the default),
          then takes one predictor step. Set it to false and call :meth:`observe` on every fresh env transition
          (in time order) to get RND's own statistics: then replay order never enters σ_R. Observing the warm-up
          steps of a random agent initialises (μ_o, σ_o) as in Burda et al.

    Args:
        target: Fixed random network f, (B, *obs_shape) → (B, K). Its parameters are frozen here.
        predictor: Trained network f̂ with the same input and output shapes.
        obs_shape: Shape of one observation, for the per-element observation statistics.
        lr: Adam learning rate of the predictor.
        gamma_int: γ_int, discount of the intrinsic return used for σ_R.
        obs_clip: c, normalised observations are clipped to [−c, c].
        scale: Multiplier applied by :meth:`IntrinsicReward.__call__`.
        observe_in_update: Whether :meth:`update` calls :meth:`observe` on its batch before the predictor step.
        input: ``obs``: the networks read o_{t+1} (Burda's RND); ``latent``: they read the agent's latent z_{t+1}
            (detached), so RND can also score a planner's imagined latent edges.
    """

    log_keys = ("losses/rnd",)

    def __init__(
        self,
        target: nn.Module,
        predictor: nn.Module,
        obs_shape: tuple[int, ...],
        lr: float = 1e-4,
        gamma_int: float = 0.99,
        obs_clip: float = 5.0,
        scale: float = 1.0,
        observe_in_update: bool = True,
        input: str = "obs",
    ) -> None:
        super().__init__(scale=scale)
        self._set_input(input)
        self.obs_shape = tuple(int(s) for s in obs_shape)
        self.obs_clip = float(obs_clip)
        self.observe_in_update = bool(observe_in_update)
        self.target, self.predictor = target, predictor
        self.target.requires_grad_(False)
        self.target.eval()
        self.nets = nn.ModuleDict({"target": target, "predictor": predictor})
        self.optimiser = torch.optim.Adam(self.predictor.parameters(), lr=lr)
        self.obs_rms = RunningMeanStd(shape=self.obs_shape)
        self.return_normaliser = ReturnNormaliser(gamma=gamma_int)

    @classmethod
    def from_obs_shape(
        cls,
        *,
        obs_shape: Sequence[int],
        out_dim: int = 64,
        predictor_hidden: int = 128,
        mlp_hidden: Sequence[int] = (64, 64),
        **kwargs: Any,
    ) -> RND:
        """Build f with :func:`~curiosity.intrinsic.nets.make_feature_net` and the deeper f̂ with ``make_predictor_net``;
        ``kwargs`` go to the constructor (``lr``, ``gamma_int``, ``obs_clip``, ``scale``, ``observe_in_update``, ``input``)."""
        obs_shape = tuple(int(s) for s in obs_shape)
        target = make_feature_net(obs_shape, out_dim, mlp_hidden)
        predictor = make_predictor_net(obs_shape, out_dim, predictor_hidden, mlp_hidden)
        return cls(target, predictor, obs_shape, **kwargs)

    @classmethod
    def from_context(cls, *, context: IntrinsicContext, input: str = "obs", **kwargs: Any) -> RND:
        """Built from the agent's parts: over its observations (``input=obs``) or its latents (``latent``: MLPs)."""
        return cls.from_obs_shape(obs_shape=cls.input_shape(context, input), input=input, **kwargs).to(context.device)

    def _next_input(self, batch: TransitionBatch) -> Tensor:
        if self.input == "latent":
            return latents_of(batch, "rnd (input=latent)")[1].detach()
        return batch.next_obs

    def _device(self) -> torch.device:
        return next(self.predictor.parameters()).device

    def _normalised(self, next_obs: Tensor) -> Tensor:
        """clip((o − μ_o) / σ_o, −c, c), (B, *obs_shape) float32 on the networks' device."""
        return self.obs_rms.normalise(next_obs.to(self._device()).float(), clip=self.obs_clip)

    def _errors(self, next_obs: Tensor) -> Tensor:
        """Per-transition distillation error (B,), with gradient into the predictor only."""
        x = self._normalised(next_obs)
        with torch.no_grad():
            target = self.target(x)
        return distillation_error(self.predictor(x), target)

    def raw_bonus(self, next_obs: Tensor) -> Tensor:
        """mean_k (f̂ − f)² before the return normalisation, (B, *obs_shape) → (B,); no gradient, no state change."""
        self.predictor.eval()
        with torch.no_grad():
            return self._errors(next_obs)

    def compute(self, batch: TransitionBatch) -> Tensor:
        """r_b = raw_bonus(o_{t+1})_b / σ_R, shape (B,); no gradient, no state change (see the class contract)."""
        return self.return_normaliser.normalise(self.raw_bonus(self._next_input(batch)))

    def imagine(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        """The bonus of imagined latent edges, raw_bonus(z_next) / σ_R (``input=latent`` only), (N,)."""
        if self.input != "latent":
            raise ValueError("rnd with input=obs scores observations; set its input to latent to score imagined steps")
        return self.return_normaliser.normalise(self.raw_bonus(z_next))

    def observe(self, batch: TransitionBatch) -> dict[str, float]:
        """Merge the next inputs into (μ_o, σ_o), then the batch's raw bonus, as a time-ordered stream, into σ_R."""
        x = self._next_input(batch)
        self.obs_rms.update(x.float())
        self.return_normaliser.update(self.raw_bonus(x))
        return {}

    def update(self, batch: TransitionBatch) -> dict[str, float]:
        """[:meth:`observe`, if ``observe_in_update``] then one predictor step; returns the pre-step ``losses/rnd``."""
        if self.observe_in_update:
            self.observe(batch)
        self.predictor.train()
        loss = self._errors(self._next_input(batch)).mean()
        self.optimiser.zero_grad(set_to_none=True)
        loss.backward()
        self.optimiser.step()
        return {"losses/rnd": float(loss.detach())}

    def to(self, device: torch.device | str) -> RND:
        """Move networks, optimiser state and statistics to ``device`` (in place); returns ``self``."""
        self.nets.to(device)
        self.optimiser.load_state_dict(self.optimiser.state_dict())  # re-casts Adam state onto the params' device
        self.obs_rms.to(device)
        self.return_normaliser.to(device)
        return self

    def state_dict(self) -> dict[str, Any]:
        """Copies of both networks, the Adam state and both running statistics."""
        return copy.deepcopy(
            {
                "nets": self.nets.state_dict(),
                "optimiser": self.optimiser.state_dict(),
                "obs_rms": self.obs_rms.state_dict(),
                "return_normaliser": self.return_normaliser.state_dict(),
            }
        )

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned (copied, so ``state`` can be loaded into several modules)."""
        self.nets.load_state_dict(state["nets"])
        self.optimiser.load_state_dict(copy.deepcopy(state["optimiser"]))
        self.obs_rms.load_state_dict(state["obs_rms"])
        self.return_normaliser.load_state_dict(state["return_normaliser"])
