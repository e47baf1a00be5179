"""A slowly moving copy of a module (TD-MPC's target encoder): θ' ← (1 − τ) θ' + τ θ after each update."""

from __future__ import annotations

import copy

import torch
from torch import Tensor, nn


class PolyakCopy(nn.Module):
    """A frozen copy of ``online`` that follows it by Polyak averaging at rate ``tau`` per :meth:`update`.

    Buffers (a frozen encoder's standardisation) are copied as they are. The online module is not a submodule: its
    owner trains and saves it; this copy saves its own parameters.

    Args:
        online: the module to follow (e.g. the world model's encoder), (B, *in) -> (B, *out).
        tau: the averaging rate in (0, 1] (TD-MPC: 0.01; 1 copies the online module at every update).
    """

    def __init__(self, online: nn.Module, tau: float) -> None:
        super().__init__()
        if not 0 < tau <= 1:
            raise ValueError(f"tau must be in (0, 1], got {tau}")
        self.tau = float(tau)
        self.copy = copy.deepcopy(online).requires_grad_(False)
        self._online = [online]

    @torch.no_grad()
    def update(self) -> None:
        """θ' ← (1 − τ) θ' + τ θ for every parameter; buffers copied."""
        online = self._online[0]
        for target, source in zip(self.copy.parameters(), online.parameters(), strict=True):
            target.lerp_(source, self.tau)
        for target, source in zip(self.copy.buffers(), online.buffers(), strict=True):
            target.copy_(source)

    @torch.no_grad()
    def forward(self, x: Tensor) -> Tensor:
        """The copy's output, without gradient, in eval mode: (B, *in) -> (B, *out)."""
        was_training = self.copy.training
        self.copy.eval()
        try:
            return self.copy(x)
        finally:
            self.copy.train(was_training)
