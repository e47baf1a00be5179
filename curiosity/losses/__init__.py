"""Named loss functions, each returning a scalar (docs/method.md §3)."""

from curiosity.losses.dqn import double_dqn_loss, double_dqn_target
from curiosity.losses.masks import masked_step_mean, terminal_mask
from curiosity.losses.model import (
    nstep_backward_loss,
    nstep_code_loss,
    nstep_reward_loss,
    nstep_transition_loss,
    rollout_latents,
)

__all__ = [
    "double_dqn_loss",
    "double_dqn_target",
    "masked_step_mean",
    "nstep_backward_loss",
    "nstep_code_loss",
    "nstep_reward_loss",
    "nstep_transition_loss",
    "rollout_latents",
    "terminal_mask",
]
