"""Double-DQN temporal-difference loss (NSRS Q step, docs/protocol.md §3.3)."""

from __future__ import annotations

import torch
from torch import Tensor
from torch.nn import functional as F


def double_dqn_target(
    q_next_online: Tensor, q_next_target: Tensor, reward: Tensor, terminated: Tensor, gamma: float
) -> Tensor:
    """Bootstrapped target y = r + γ (1 − d) Q_tgt(s', argmax_a Q(s', a)), without gradient.

    Args:
        q_next_online: (B, A) online Q(s', ·), used only to pick the action.
        q_next_target: (B, A) target Q_tgt(s', ·).
        reward: (B,) reward (extrinsic + intrinsic, as the caller decides).
        terminated: (B,) float in {0, 1}; 1 where s' is terminal.
        gamma: discount.

    Returns:
        (B,) detached targets.
    """
    with torch.no_grad():
        best = q_next_online.argmax(dim=1, keepdim=True)
        bootstrap = q_next_target.gather(1, best).squeeze(1)
        return reward + gamma * (1.0 - terminated) * bootstrap


def double_dqn_loss(
    q: Tensor,
    q_next_online: Tensor,
    q_next_target: Tensor,
    act: Tensor,
    reward: Tensor,
    terminated: Tensor,
    gamma: float,
    *,
    huber: bool = True,
) -> Tensor:
    """Double-DQN loss mean_b ℓ(Q(s, a) − y) with y from :func:`double_dqn_target`.

    NSRS uses ``SmoothL1Loss`` (Huber with δ = 1: ℓ(x) = ½x² for |x| < 1, else |x| − ½), hence ``huber=True`` by
    default; ``huber=False`` gives the plain squared error ℓ(x) = x².

    Args:
        q: (B, A) online Q(s, ·) (with gradient).
        q_next_online: (B, A) online Q(s', ·).
        q_next_target: (B, A) target-network Q(s', ·).
        act: (B,) long actions taken.
        reward: (B,) rewards.
        terminated: (B,) terminal flags.
        gamma: discount.
        huber: Huber (smooth L1, δ = 1) if True, else mean squared error.

    Returns:
        Scalar loss.
    """
    y = double_dqn_target(q_next_online, q_next_target, reward, terminated, gamma)
    q_taken = q.gather(1, act.long().unsqueeze(1)).squeeze(1)
    if huber:
        return F.smooth_l1_loss(q_taken, y)
    return F.mse_loss(q_taken, y)
