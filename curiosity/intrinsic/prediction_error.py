"""The prediction-error bonus (paper §3.3, Eq. 10): how badly the latent transition model predicted a transition.

On a real transition, r_pe = log1p(e / (ē + ε)) with the true error e = ‖T(s, a) − s'‖² and ē its running mean over
the real transitions seen (after the warm-up). An imagined edge has no true successor; the paper is silent on how the
planner scores it, and ``imagined`` chooses the model's own estimate ê(s, a) of that error, normalised by the running
mean of ê at the real pairs visited:
    ``dropout``: MC-dropout disagreement mean_m ‖T_m(s, a) − T(s, a)‖² (random: a fresh draw at every evaluation);
    ``ensemble``: disagreement of a deep ensemble of transitions (``agent.transition_ensemble`` ≥ 2; deterministic);
    ``off``: imagined edges get no prediction-error term (a mixture gives its weight to the terms that imagine).
Both running means are updated after use, once per env step (:meth:`PredictionError.observe`).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from typing import Any

import numpy as np
import torch
from torch import Tensor

from curiosity.intrinsic.base import IntrinsicContext, IntrinsicReward, latents_of
from curiosity.types import TransitionBatch

IMAGINED = ("dropout", "ensemble", "off")
PE_WINDOW = 200  # real transitions in the signal check of the imagined prediction-error estimate


def squared_prediction_error(pred: Tensor, target: Tensor) -> Tensor:
    """e_b = ‖ŝ_b − s_b‖² summed (not averaged) over features, (B, d), (B, d) -> (B,), without gradient."""
    if pred.shape != target.shape or pred.dim() != 2:
        raise ValueError(f"pred and target must both be (B, d), got {tuple(pred.shape)} and {tuple(target.shape)}")
    with torch.no_grad():
        return (pred - target).pow(2).sum(dim=1)


def prediction_error_bonus(error: Tensor, mean_error: float, *, eps: float = 1e-8) -> Tensor:
    """Normalised prediction-error bonus (paper Eq. 10): r_pe = log(1 + e / (ē + ε)), (B,) -> (B,).

    Args:
        error: (B,) squared prediction errors e ≥ 0 (see :func:`squared_prediction_error`).
        mean_error: running mean ē of the error from *before* this batch.
        eps: ε > 0 guarding ē = 0.
    """
    return torch.log1p(error.detach() / (float(mean_error) + eps))


class PredictionErrorBonus:
    """Prediction-error bonus r_pe = log1p(e / (ē + ε)) with a running mean ē, updated after use.

    ``__call__(e)`` computes the reward with the ē from before the batch, then updates ē with the batch
    (``compute`` and ``update`` do one half each, e.g. ``compute`` alone for imagined transitions).

    Running mean (``average``):
        ``"cumulative"``: the mean of every error seen so far, ē ← (c ē + Σ_b e_b) / (c + B), c = errors seen.
        ``"ema"``: exponential moving average of batch means, ē ← β ē + (1 − β) mean_b e_b, β = ``ema_decay``.
    In both, the first update sets ē to the first batch's mean; before it, ē = ``initial_mean``.

    Args:
        eps: ε > 0 in the denominator.
        average: ``"cumulative"`` or ``"ema"``.
        ema_decay: β ∈ [0, 1) for ``"ema"``.
        initial_mean: ē used before any update.
    """

    def __init__(
        self, eps: float = 1e-8, average: str = "cumulative", ema_decay: float = 0.99, initial_mean: float = 1.0
    ) -> None:
        if average not in ("cumulative", "ema"):
            raise ValueError(f"average must be 'cumulative' or 'ema', got {average!r}")
        if not 0.0 <= ema_decay < 1.0:
            raise ValueError(f"ema_decay must be in [0, 1), got {ema_decay}")
        self.eps = float(eps)
        self.average = average
        self.ema_decay = float(ema_decay)
        self.mean = float(initial_mean)
        self.count = 0

    def compute(self, error: Tensor) -> Tensor:
        """r_pe for squared errors (B,) -> (B,) with the current ē; does not update ē."""
        return prediction_error_bonus(error, self.mean, eps=self.eps)

    def update(self, error: Tensor) -> None:
        """Fold a batch of squared errors (B,) into the running mean ē."""
        e = error.detach().to(torch.float64).reshape(-1)
        if e.numel() == 0:
            return
        if self.count == 0:
            self.mean = float(e.mean())
        elif self.average == "cumulative":
            self.mean = (self.count * self.mean + float(e.sum())) / (self.count + e.numel())
        else:
            self.mean = self.ema_decay * self.mean + (1.0 - self.ema_decay) * float(e.mean())
        self.count += e.numel()

    def __call__(self, error: Tensor) -> Tensor:
        """Reward with the ē from before this batch, then update ē: (B,) -> (B,)."""
        reward = self.compute(error)
        self.update(error)
        return reward

    def state_dict(self) -> dict[str, Any]:
        """Running statistics: ``{"mean": ē, "count": errors seen}``."""
        return {"mean": self.mean, "count": self.count}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore the running statistics saved by :meth:`state_dict`."""
        self.mean, self.count = float(state["mean"]), int(state["count"])


class PredictionError(IntrinsicReward):
    """r_pe of the agent's latent transition model (see the module docstring).

    Args:
        context: the agent's parts; ``model`` (the world model with its transition) is required.
        imagined: how imagined edges get their term: ``dropout``, ``ensemble`` or ``off``.
        dropout_samples: MC-dropout samples per imagined edge (``imagined=dropout``).
        average: running mean of the errors, ``cumulative`` or ``ema``.
        eps: ε.
        log_every: env steps between logs of ``intrinsic/pe_estimate_corr`` (it ranks 200 pairs).
        scale: multiplies ``__call__``.
    """

    needs_latents = True
    needs_model = True
    log_keys = ("intrinsic/pe_error", "intrinsic/pe_estimate_corr")

    @classmethod
    def can_imagine(cls, options: Mapping[str, Any]) -> bool:
        return str(options.get("imagined", "off")) != "off"

    def __init__(self, context: IntrinsicContext, *, imagined: str = "off", dropout_samples: int = 8,
                 average: str = "cumulative", eps: float = 1e-8, log_every: int = 10, scale: float = 1.0) -> None:  # fmt: skip
        super().__init__(scale)
        if imagined not in IMAGINED:
            raise ValueError(f"the imagined prediction error must be one of {IMAGINED}, got {imagined!r}")
        if context.model is None:
            raise ValueError("the prediction-error bonus needs a latent transition model: only the paper's agent "
                             "(baseline=none or nsrs) has one")  # fmt: skip
        self.model, self.kind, self.dropout_samples = context.model, imagined, int(dropout_samples)
        self.warmup_steps, self.log_every = context.warmup_steps, int(log_every)
        self.real = PredictionErrorBonus(eps=eps, average=average)
        self.imagined_mean = PredictionErrorBonus(eps=eps, average=average)
        self.pairs: deque[tuple[float, float]] = deque(maxlen=PE_WINDOW)

    @classmethod
    def from_context(cls, *, context: IntrinsicContext, **kwargs: Any) -> PredictionError:
        """The constructor, keyword-only (as the ``intrinsic`` config group calls it)."""
        return cls(context, **kwargs)

    @property
    def imaginable(self) -> bool:
        return self.kind != "off"

    @property
    def stochastic(self) -> bool:
        return self.kind == "dropout"

    def summary(self) -> dict[str, Any]:
        return {"pe_imagined": self.kind}

    def _true_error(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        with self.model.evaluating():
            return (self.model.next(z, a) - z_next).square().sum(1)

    def _estimate(self, z: Tensor, a: Tensor) -> Tensor:
        if self.kind == "ensemble":
            return self.model.ensemble_disagreement(z, a)
        return self.model.dropout_disagreement(z, a, self.dropout_samples)

    @torch.no_grad()
    def compute(self, batch: TransitionBatch) -> Tensor:
        """r_pe of real transitions from their latents, with the running mean as it is: (B,)."""
        z, z_next = latents_of(batch, "the prediction-error bonus")
        return self.real.compute(self._true_error(z, batch.act, z_next))

    def imagine(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        """r̂_pe of imagined edges from the model's own error estimate (``imagined``), (N,)."""
        if self.kind == "off":
            raise ValueError("imagined=off: this prediction-error term scores real transitions only")
        return self.imagined_mean.compute(self._estimate(z, a))

    def update(self, batch: TransitionBatch) -> dict[str, float]:
        """Nothing trains here (the transition model trains in the agent's representation loss)."""
        return {}

    @torch.no_grad()
    def observe(self, batch: TransitionBatch) -> dict[str, float]:
        """Fold real transitions after the warm-up into both running means (after their rewards were used); keep
        (estimate, true error) pairs for :meth:`estimate_corr`, logged every ``log_every`` steps."""
        if batch.index is None or int(batch.index[0]) < self.warmup_steps:
            return {}
        z, z_next = latents_of(batch, "the prediction-error bonus")
        error = self._true_error(z, batch.act, z_next)
        logs = {"intrinsic/pe_error": float(error.mean())}
        self.real.update(error)
        if self.kind != "off":
            estimate = self._estimate(z, batch.act)
            self.imagined_mean.update(estimate)
            self.pairs.extend(zip(estimate.tolist(), error.tolist(), strict=True))
        corr = self.estimate_corr() if (int(batch.index[-1]) + 1) % self.log_every == 0 else None
        if corr is not None:
            logs["intrinsic/pe_estimate_corr"] = corr
        return logs

    def estimate_corr(self) -> float | None:
        """Does the imagined prediction-error estimate carry signal? The Spearman correlation between the estimate
        ê(s, a) and the true error ‖T(s, a) − s'‖² of the last ``PE_WINDOW`` real transitions, each taken before
        the model trained on it; None with fewer than 20 pairs or a constant side (e.g. no dropout)."""
        if len(self.pairs) < 20:
            return None
        est, err = np.array(self.pairs).T
        if np.ptp(est) == 0 or np.ptp(err) == 0:
            return None
        from scipy.stats import spearmanr  # on first use: importing scipy.stats takes ~1 s

        return float(spearmanr(est, err).statistic)

    def state_dict(self) -> dict[str, Any]:
        return {"real": self.real.state_dict(), "imagined": self.imagined_mean.state_dict(), "pairs": list(self.pairs)}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.real.load_state_dict(state["real"])
        self.imagined_mean.load_state_dict(state["imagined"])
        self.pairs = deque(state.get("pairs", []), maxlen=PE_WINDOW)
