"""One-hot encoding of discrete actions."""

from __future__ import annotations

import torch
from torch import Tensor


def one_hot(a: Tensor, n: int) -> Tensor:
    """One-hot encode integer actions.

    Args:
        a: (B,) long action indices in [0, n).
        n: number of actions.

    Returns:
        (B, n) float tensor (dtype ``torch.get_default_dtype()``) with a single 1 per row.
    """
    return torch.nn.functional.one_hot(a.long(), n).to(torch.get_default_dtype())
