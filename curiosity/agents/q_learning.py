"""Double DQN on latents with a target network (target encoder included), as NSRS trains its Q."""

from __future__ import annotations

import copy

import torch
from torch import Tensor, nn

from curiosity.losses.dqn import double_dqn_loss
from curiosity.nets.q import QNetwork


class QLearner(nn.Module):
    """Q(z, ·) with a target copy of Q and of the encoder, refreshed every ``target_every`` updates.

    Args:
        encoder: the online encoder (shared with the world model; TD gradients flow into it as in NSRS).
        latent_dim: d.
        n_actions: A.
        gamma: discount.
        target_every: Q updates between target refreshes (NSRS: 1000).
        huber: Huber TD loss (NSRS) or squared error.
    """

    def __init__(self, encoder: nn.Module, latent_dim: int, n_actions: int, gamma: float, target_every: int = 1000,
                 huber: bool = True) -> None:  # fmt: skip
        super().__init__()
        self.q = QNetwork(latent_dim, n_actions)
        self.gamma, self.target_every, self.huber = gamma, target_every, huber
        self.target_q = copy.deepcopy(self.q).requires_grad_(False)
        self.target_encoder = copy.deepcopy(encoder).requires_grad_(False)
        self._encoder = [encoder]  # not a submodule: the world model owns it
        self.updates = 0

    def loss(self, z: Tensor, act: Tensor, reward: Tensor, z_next: Tensor, next_obs: Tensor, terminated: Tensor) -> Tensor:
        """TD loss for transitions: z (B, d) with grad, z_next (B, d) online latents of ``next_obs`` (B, *obs)."""
        with torch.no_grad():
            q_next_online = self.q(z_next.detach())
            q_next_target = self.target_q(self.target_encoder(next_obs))
        return double_dqn_loss(self.q(z), q_next_online, q_next_target, act, reward, terminated, self.gamma,
                               huber=self.huber)  # fmt: skip

    def after_update(self) -> None:
        """Count an update; refresh the targets every ``target_every`` updates."""
        self.updates += 1
        if self.updates % self.target_every == 0:
            self.target_q.load_state_dict(self.q.state_dict())
            self.target_encoder.load_state_dict(self._encoder[0].state_dict())

    def get_extra_state(self) -> dict[str, int]:
        return {"updates": self.updates}

    def set_extra_state(self, state: dict[str, int]) -> None:
        self.updates = int(state["updates"])

    def values(self, z: Tensor) -> Tensor:
        """Q(z, ·): (N, d) -> (N, A)."""
        return self.q(z)
