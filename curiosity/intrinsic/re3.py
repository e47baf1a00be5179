"""RE3 (Seo et al. 2021): novelty as the distance to the k-th nearest neighbour in a fixed random encoder's space.

r = log(1 + ‖y − y_(k)‖), y = f(o_{t+1}) with f a randomly initialised, never trained encoder (``input=obs``; or the
agent's latent z_{t+1}, ``input=latent``, so a planner can score imagined steps), y_(k) the k-th nearest of the last
``capacity`` embeddings of visited states.
"""

from __future__ import annotations

import copy
from typing import Any

import torch
from torch import Tensor, nn

from curiosity.intrinsic.base import IntrinsicContext, IntrinsicReward, latents_of
from curiosity.intrinsic.inputs import ReadsObsOrLatent
from curiosity.intrinsic.nets import make_feature_net
from curiosity.types import TransitionBatch


class RE3(ReadsObsOrLatent, IntrinsicReward):
    """The RE3 bonus over a first-in-first-out memory of ``capacity`` random embeddings (k-th neighbour, k ≥ 1)."""

    def __init__(self, encoder: nn.Module, k: int = 3, capacity: int = 10_000, input: str = "obs",
                 scale: float = 1.0) -> None:  # fmt: skip
        super().__init__(scale)
        self._set_input(input)
        self.encoder, self.k, self.capacity = encoder.requires_grad_(False).eval(), int(k), int(capacity)
        self.memory: Tensor | None = None

    @classmethod
    def from_context(cls, *, context: IntrinsicContext, out_dim: int = 32, input: str = "obs", **kwargs: Any) -> RE3:
        encoder = make_feature_net(cls.input_shape(context, input), out_dim).to(context.device)
        return cls(encoder, input=input, **kwargs)

    @property
    def ready(self) -> bool:
        return self.memory is not None and len(self.memory) >= self.k

    @torch.no_grad()
    def _embed(self, x: Tensor) -> Tensor:
        return self.encoder(x.float())

    def _next(self, batch: TransitionBatch) -> Tensor:
        return latents_of(batch, "re3 (input=latent)")[1] if self.input == "latent" else batch.next_obs

    @torch.no_grad()
    def _bonus(self, x_next: Tensor) -> Tensor:
        if not self.ready:
            raise RuntimeError(f"re3 needs {self.k} remembered states before it scores")
        kth = torch.cdist(self._embed(x_next), self.memory).kthvalue(self.k, dim=1).values
        return torch.log1p(kth)

    def compute(self, batch: TransitionBatch) -> Tensor:
        return self._bonus(self._next(batch))

    def imagine(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        if self.input != "latent":
            raise ValueError("re3 with input=obs scores observations; set its input to latent to score imagined steps")
        return self._bonus(z_next)

    def update(self, batch: TransitionBatch) -> dict[str, float]:
        return {}  # nothing trains: the encoder stays random

    def observe(self, batch: TransitionBatch) -> dict[str, float]:
        y = self._embed(self._next(batch))
        self.memory = (y if self.memory is None else torch.cat([self.memory, y]))[-self.capacity :]
        return {}

    def state_dict(self) -> dict[str, Any]:
        return copy.deepcopy({"encoder": self.encoder.state_dict(), "memory": self.memory})

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.encoder.load_state_dict(state["encoder"])
        self.memory = None if state["memory"] is None else state["memory"].clone()
