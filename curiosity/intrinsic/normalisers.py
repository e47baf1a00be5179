"""Running statistics used to normalise observations and intrinsic rewards (pure torch).

:class:`RunningMeanStd` keeps an element-wise running mean and (population) variance merged batch by batch.
:class:`ReturnNormaliser` divides rewards by the running std of their discounted return, as RND does for its bonus.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import torch
from torch import Tensor


class RunningMeanStd:
    """Element-wise running mean and variance over a stream of batches.

    Batches are merged with the parallel-variance rule (Chan et al.): for a stored (μ, σ², n) and a batch with
    (μ_b, σ_b², n_b), δ = μ_b − μ, n' = n + n_b,

        μ' = μ + δ·n_b/n',   σ'² = (σ²·n + σ_b²·n_b + δ²·n·n_b/n') / n'.

    Variances are population variances (ddof = 0). Statistics start at μ = 0, σ² = 1 with a pseudo-count
    ``epsilon``, so the prior fades after the first real batch; ``epsilon = 0`` gives the exact sample moments.
    State is held in float64 for accuracy over long streams.

    Args:
        shape: Shape of one sample; ``()`` for scalars, ``(4, 32, 32)`` for per-pixel statistics.
        epsilon: Initial pseudo-count (≥ 0).
    """

    def __init__(self, shape: Sequence[int] = (), epsilon: float = 1e-4) -> None:
        if epsilon < 0:
            raise ValueError(f"epsilon must be >= 0, got {epsilon}")
        self.shape = tuple(int(s) for s in shape)
        self._mean = torch.zeros(self.shape, dtype=torch.float64)
        self._var = torch.ones(self.shape, dtype=torch.float64)
        self._count = torch.tensor(float(epsilon), dtype=torch.float64)

    @property
    def mean(self) -> Tensor:
        """Running mean, shape ``shape``, float64."""
        return self._mean

    @property
    def var(self) -> Tensor:
        """Running population variance, shape ``shape``, float64."""
        return self._var

    @property
    def std(self) -> Tensor:
        """Running standard deviation √var, shape ``shape``, float64."""
        return self._var.sqrt()

    @property
    def count(self) -> float:
        """Number of samples seen, plus the initial pseudo-count."""
        return float(self._count)

    def update(self, x: Tensor) -> None:
        """Merge a batch ``x`` of shape (B, *shape) into the statistics; B = 0 is a no-op."""
        x = torch.as_tensor(x).detach().to(device=self._mean.device, dtype=torch.float64)
        if tuple(x.shape[1:]) != self.shape:
            raise ValueError(f"expected a batch of shape (B, *{self.shape}), got {tuple(x.shape)}")
        if x.shape[0] == 0:
            return
        self._merge(x.mean(0), x.var(0, unbiased=False), x.shape[0])

    def _merge(self, batch_mean: Tensor, batch_var: Tensor, batch_count: int) -> None:
        total = self._count + batch_count
        delta = batch_mean - self._mean
        m2 = self._var * self._count + batch_var * batch_count + delta.square() * self._count * batch_count / total
        self._mean = self._mean + delta * batch_count / total
        self._var = m2 / total
        self._count = total

    def normalise(self, x: Tensor, clip: float | None = None, min_std: float = 1e-8) -> Tensor:
        """(x − μ) / max(σ, min_std), optionally clipped to [−clip, clip]; returned in ``x``'s dtype, no state change."""
        mean = self._mean.to(device=x.device, dtype=x.dtype)
        std = self.std.clamp_min(min_std).to(device=x.device, dtype=x.dtype)
        out = (x - mean) / std
        return out.clamp(-clip, clip) if clip is not None else out

    def to(self, device: torch.device | str) -> RunningMeanStd:
        """Move the statistics to ``device`` (in place); returns ``self``."""
        self._mean, self._var, self._count = (t.to(device) for t in (self._mean, self._var, self._count))
        return self

    def state_dict(self) -> dict[str, Any]:
        """Copies of mean, var and count."""
        return {"mean": self._mean.clone(), "var": self._var.clone(), "count": self._count.clone()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned (values are copied, not aliased)."""
        mean = torch.as_tensor(state["mean"], dtype=torch.float64)
        if tuple(mean.shape) != self.shape:
            raise ValueError(f"state has shape {tuple(mean.shape)}, expected {self.shape}")
        device = self._mean.device
        self._mean = mean.to(device).clone()
        self._var = torch.as_tensor(state["var"], dtype=torch.float64).to(device).clone()
        self._count = torch.as_tensor(state["count"], dtype=torch.float64).to(device).clone()


class ReturnNormaliser:
    """Scale rewards by the running std of their discounted return (no mean subtraction), as in RND.

    Over a time-ordered stream of rewards r_t it keeps the running discounted return

        R_t = γ·R_{t−1} + r_t,   R_{−1} = 0,

    never reset at episode ends (RND treats the intrinsic return as non-episodic), feeds every R_t into a scalar
    :class:`RunningMeanStd`, and normalises by r_t / σ_R. The mean of R is *not* subtracted from r.

    Order: :meth:`update_and_normalise` is **update-then-divide**: the returns of the current rewards enter the
    statistics before the division, so the very first rewards are not divided by the prior σ = 1 (RND's order:
    returns of a rollout update the statistics, then the rollout's rewards are divided). :meth:`normalise` alone
    divides by the current σ without touching any state.

    Args:
        gamma: Discount γ of the intrinsic return.
        epsilon: Pseudo-count of the underlying :class:`RunningMeanStd`.
    """

    def __init__(self, gamma: float = 0.99, epsilon: float = 1e-4) -> None:
        self.gamma = float(gamma)
        self.rms = RunningMeanStd(shape=(), epsilon=epsilon)
        self.running_return: Tensor | None = None

    @property
    def std(self) -> Tensor:
        """Running std σ_R of the discounted return, scalar float64."""
        return self.rms.std

    def update(self, rewards: Tensor) -> None:
        """Advance the discounted return over ``rewards`` and merge every R_t into the statistics.

        Args:
            rewards: (T,) one stream, or (T, N) N parallel streams, time along dim 0. The stream layout (the
                trailing shape) must stay the same from call to call.
        """
        rewards = torch.as_tensor(rewards).detach().to(torch.float64)
        if rewards.shape[0] == 0:
            return
        acc = self.running_return
        if acc is None:
            acc = torch.zeros(rewards.shape[1:], dtype=torch.float64, device=rewards.device)
        if acc.shape != rewards.shape[1:]:
            raise ValueError(f"stream layout {tuple(acc.shape)} changed to {tuple(rewards.shape[1:])}")
        returns = torch.empty_like(rewards)
        for t in range(rewards.shape[0]):
            acc = self.gamma * acc + rewards[t]
            returns[t] = acc
        self.running_return = acc
        self.rms.update(returns.reshape(-1))

    def normalise(self, rewards: Tensor, min_std: float = 1e-8) -> Tensor:
        """r / max(σ_R, min_std) in ``rewards``' dtype; changes no state."""
        return rewards / self.std.clamp_min(min_std).to(device=rewards.device, dtype=rewards.dtype)

    def update_and_normalise(self, rewards: Tensor) -> Tensor:
        """:meth:`update` then :meth:`normalise` (update-then-divide); same shapes as :meth:`update`."""
        self.update(rewards)
        return self.normalise(rewards)

    def to(self, device: torch.device | str) -> ReturnNormaliser:
        """Move the state to ``device`` (in place); returns ``self``."""
        self.rms.to(device)
        if self.running_return is not None:
            self.running_return = self.running_return.to(device)
        return self

    def state_dict(self) -> dict[str, Any]:
        """Running statistics and the current discounted return."""
        acc = None if self.running_return is None else self.running_return.clone()
        return {"gamma": self.gamma, "rms": self.rms.state_dict(), "running_return": acc}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned."""
        self.gamma = float(state["gamma"])
        self.rms.load_state_dict(state["rms"])
        acc = state["running_return"]
        if acc is not None:
            acc = torch.as_tensor(acc, dtype=torch.float64).to(self.rms.mean.device).clone()
        self.running_return = acc
