"""What a learned bonus (ICM, RND) reads: the observations, as its authors ran it, or the agent's latents.

On latents (``input=latent``) the bonus can also score a planner's imagined latent steps, which have no observations.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from curiosity.intrinsic.base import IntrinsicContext

INPUTS = ("obs", "latent")


class ReadsObsOrLatent:
    """Mixin of an :class:`~curiosity.intrinsic.base.IntrinsicReward` whose networks read ``input``."""

    input: str = "obs"
    needs_latents: bool = False

    def _set_input(self, input: str) -> None:
        if input not in INPUTS:
            raise ValueError(f"{type(self).__name__.lower()} input must be one of {INPUTS}, got {input!r}")
        self.input, self.needs_latents = input, input == "latent"

    @staticmethod
    def input_shape(context: IntrinsicContext, input: str) -> tuple[int, ...]:
        """The shape of one input: an observation's, or (latent_dim,)."""
        return tuple(context.obs_shape) if input == "obs" else (context.latent_dim,)

    @property
    def imaginable(self) -> bool:
        return self.input == "latent"

    @classmethod
    def can_imagine(cls, options: Mapping[str, Any]) -> bool:
        return str(options.get("input", "obs")) == "latent"
