"""The learned latent world model: encoder, transition, reward model, backward predictor, and the verbs planners use."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import torch
from torch import Tensor, nn

from curiosity.nets.onehot import one_hot


class WorldModel(nn.Module):
    """Encoder E, residual transition T, optional reward model R and backward predictor B.

    Args:
        encoder: observations (B, *obs_shape) -> latents (B, d).
        transition: T(z (B, d), a_onehot (B, A)) -> (B, d).
        n_actions: A.
        reward_model: R(y (B, d + A)) -> (B,), or None.
        backward: B(z_next (B, d)) -> (B, K, d + A) candidate predecessors, or None.
    """

    def __init__(self, encoder: nn.Module, transition: nn.Module, n_actions: int,
                 reward_model: nn.Module | None = None, backward: nn.Module | None = None) -> None:  # fmt: skip
        super().__init__()
        self.encoder, self.transition = encoder, transition
        self.reward_model, self.backward = reward_model, backward
        self.n_actions = n_actions

    def encode(self, obs: Tensor) -> Tensor:
        """s = E(o): (B, *obs_shape) -> (B, d)."""
        return self.encoder(obs)

    def next(self, z: Tensor, a: Tensor) -> Tensor:
        """ŝ' = T(s, a): z (B, d), a (B,) long -> (B, d)."""
        return self.transition(z, one_hot(a, self.n_actions).to(z.dtype))

    def reward(self, z: Tensor, a: Tensor) -> Tensor:
        """R([s, a]): (B, d), (B,) long -> (B,); zeros without a reward model."""
        if self.reward_model is None:
            return z.new_zeros(z.shape[0])
        return self.reward_model(torch.cat([z, one_hot(a, self.n_actions).to(z.dtype)], dim=1))

    @contextlib.contextmanager
    def evaluating(self) -> Iterator[WorldModel]:
        """Eval mode (dropout off) and no gradient inside the block; the previous mode is restored after."""
        was_training = self.training
        self.eval()
        try:
            with torch.no_grad():
                yield self
        finally:
            self.train(was_training)

    @torch.no_grad()
    def ensemble_disagreement(self, z: Tensor, a: Tensor) -> Tensor:
        """mean_k ‖T_k(z, a) − mean_j T_j(z, a)‖² over the members of a transition ensemble (eval mode).

        z (N, d), a (N,) long -> (N,). Zeros for a single transition model.
        """
        members = self.transition.members
        if len(members) < 2:
            return z.new_zeros(z.shape[0])
        was_training = self.transition.training
        self.transition.eval()
        a1h = one_hot(a, self.n_actions).to(z.dtype)
        preds = torch.stack([m(z, a1h) for m in members])
        self.transition.train(was_training)
        return (preds - preds.mean(0)).square().sum(-1).mean(0)

    @torch.no_grad()
    def dropout_disagreement(self, z: Tensor, a: Tensor, samples: int) -> Tensor:
        """Expected squared error of T at (z, a) under MC dropout: mean_m ‖T_m(z, a) − T_eval(z, a)‖².

        z (N, d), a (N,) long -> (N,). With no dropout in T this is 0.
        """
        was_training = self.transition.training
        a1h = one_hot(a, self.n_actions).to(z.dtype)
        self.transition.eval()
        mean = self.transition(z, a1h)
        self.transition.train()
        draws = self.transition(z.repeat(samples, 1), a1h.repeat(samples, 1)).view(samples, *mean.shape)
        self.transition.train(was_training)
        return (draws - mean).square().sum(-1).mean(0)
