"""Terminal masks for n-step segment losses."""

from __future__ import annotations

import torch
from torch import Tensor


def terminal_mask(terminateds: Tensor, *, include_terminal_step: bool = False) -> Tensor:
    """Per-step weights that stop a segment loss at the first terminal transition.

    Default (the paper's (1 − d_{t+i}) factor, made absorbing):  mask_i = Π_{j ≤ i} (1 − d_{t+j}),
    so the step whose successor o_{t+i+1} is terminal is masked, and so is every later step.
    With ``include_terminal_step=True``: mask_i = Π_{j < i} (1 − d_{t+j}), i.e. the terminal transition itself is kept
    and only the steps after it are masked (useful for rewards, where the terminal step's reward is real data).

    Args:
        terminateds: (B, n) float in {0, 1}; d_{t+i} = 1 where o_{t+i+1} is terminal.
        include_terminal_step: keep the step that reaches the terminal.

    Returns:
        (B, n) float mask in {0, 1}, same dtype as ``terminateds``.
    """
    alive = torch.cumprod(1.0 - terminateds, dim=1)
    if not include_terminal_step:
        return alive
    return torch.cat([torch.ones_like(alive[:, :1]), alive[:, :-1]], dim=1)


def masked_step_mean(per_step: Tensor, mask: Tensor) -> Tensor:
    """(1/n) Σ_i mask_i · per_step_i, averaged over the batch.

    Args:
        per_step: (B, n) per-step losses.
        mask: (B, n) weights.

    Returns:
        Scalar mean_b (1/n) Σ_i mask_{b,i} per_step_{b,i}. Masked steps count in n (the paper's 1/n, not 1/Σ mask).
    """
    return (mask * per_step).mean()
