"""A weighted sum of named intrinsic rewards: the paper's hybrid (Eq. 11) is ``{novelty: 1 − α, pe: α}``.

Every agent takes its intrinsic reward from the ``intrinsic`` config group, which builds a :class:`Mixture` of the
terms it names (``intrinsic=hybrid``: latent novelty and the prediction-error bonus; ``intrinsic=icm``: ICM alone).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import torch
from torch import Tensor

from curiosity.build import build
from curiosity.intrinsic.base import IntrinsicContext, IntrinsicReward
from curiosity.types import TransitionBatch


def hybrid_intrinsic_reward(r_nov: Tensor, r_pe: Tensor, *, alpha: float = 0.5) -> Tensor:
    """Hybrid intrinsic reward (paper Eq. 11): r_int = (1 − α) r_nov + α r_pe, α ∈ [0, 1], (B,), (B,) -> (B,)."""
    if not 0.0 <= alpha <= 1.0:
        raise ValueError(f"alpha must be in [0, 1], got {alpha}")
    return (1.0 - alpha) * r_nov + alpha * r_pe


class Mixture(IntrinsicReward):
    """r_int = Σ_k w_k r_k over named terms (in the order given).

    Real transitions (:meth:`compute`) use the weights as given. Imagined edges (:meth:`imagined_terms`) are scored by
    the terms that can imagine them (``imaginable``); their weights are rescaled to the same total, so a term that
    scores real transitions only (e.g. ``pe`` with ``imagined=off``) hands its weight to the others (if all of those
    have weight 0, they share the total equally).

    Args:
        terms: name -> reward; each term's mean is logged as ``intrinsic/<name>``.
        weights: name -> w_k ≥ 0, one per term.
        scale: multiplies ``__call__``.
    """

    def __init__(self, terms: Mapping[str, IntrinsicReward], weights: Mapping[str, float], scale: float = 1.0) -> None:
        super().__init__(scale)
        if not terms:
            raise ValueError("an intrinsic reward needs at least one term")
        if set(weights) != set(terms):
            raise ValueError(f"intrinsic.weights must name every term once: terms {sorted(terms)}, weights {sorted(weights)}")
        bad = {k: w for k, w in weights.items() if not float(w) >= 0}
        if bad:
            raise ValueError(f"intrinsic.weights must be >= 0, got {bad}")
        self.terms = dict(terms)
        self.weights = {name: float(weights[name]) for name in self.terms}
        keys = [f"intrinsic/{name}" for name in self.terms] + [k for t in self.terms.values() for k in t.log_keys]
        self.log_keys = tuple(dict.fromkeys(keys))
        self.needs_latents = any(t.needs_latents for t in self.terms.values())

    @classmethod
    def from_config(cls, *, terms: Mapping[str, Any], weights: Mapping[str, float], context: IntrinsicContext,
                    scale: float = 1.0) -> Mixture:  # fmt: skip
        """Build each term from its config node (a ``_target_`` taking ``context``) and weigh them."""
        return cls({name: build(node, context=context) for name, node in terms.items()}, weights, scale)

    @classmethod
    def hybrid(cls, *, terms: Mapping[str, Any], alpha: float, context: IntrinsicContext, weights: Any = None,
               scale: float = 1.0) -> Mixture:  # fmt: skip
        """The paper's hybrid (Eq. 11) of a ``novelty`` and a ``pe`` term: weights {novelty: 1 − α, pe: α}."""
        if weights is not None:
            raise ValueError("intrinsic=hybrid weighs its terms by intrinsic.alpha; allowed: intrinsic.alpha=<0..1>")
        if not 0.0 <= float(alpha) <= 1.0:
            raise ValueError(f"intrinsic.alpha must be in [0, 1], got {alpha}")
        return cls.from_config(terms=terms, weights={"novelty": 1.0 - float(alpha), "pe": float(alpha)}, context=context,
                               scale=scale)  # fmt: skip

    def term(self, kind: type[IntrinsicReward]) -> Any:
        """The first term that is a ``kind``, or None (e.g. ``term(LatentNovelty)`` for its memory)."""
        return next((t for t in self.terms.values() if isinstance(t, kind)), None)

    @property
    def ready(self) -> bool:
        return all(t.ready for t in self.terms.values())

    @property
    def imaginable(self) -> bool:
        return any(t.imaginable for t in self.terms.values())

    def imagined_weights(self) -> dict[str, float]:
        """The weight of each term on imagined edges (see the class docstring); only terms with weight > 0."""
        active = {name: w for name, w in self.weights.items() if self.terms[name].imaginable}
        if not active:
            raise ValueError(f"no term of this intrinsic reward ({', '.join(self.terms)}) can score imagined steps")
        total, share = sum(self.weights.values()), sum(active.values())
        if share > 0:
            return {name: w * total / share for name, w in active.items() if w > 0}
        return {name: total / len(active) for name in active}

    @property
    def stochastic(self) -> bool:
        return any(self.terms[name].stochastic for name in self.imagined_weights())

    def compute_terms(self, batch: TransitionBatch) -> dict[str, Tensor]:
        """Every term's raw bonus of real transitions, name -> (B,) (terms of weight 0 too, for the logs)."""
        return {name: term.compute(batch) for name, term in self.terms.items()}

    def combine(self, values: Mapping[str, Tensor]) -> Tensor:
        """Σ_k w_k values[k] over the terms of weight > 0, (B,) each -> (B,)."""
        total: Tensor | None = None
        for name, w in self.weights.items():
            if w > 0:
                total = w * values[name] if total is None else total + w * values[name]
        if total is None:
            return torch.zeros_like(next(iter(values.values())))
        return total

    @torch.no_grad()
    def transition_logs(self, batch: TransitionBatch) -> dict[str, float]:
        """What an agent logs of a real transition (a batch of one) once the terms are ready: each term's raw bonus
        (``intrinsic/<name>``) and the reward it learns from, ``scale`` × Σ_k w_k r_k (``intrinsic/reward``); {} before.
        Every agent logs through this, so the logged reward means the same for all."""
        if not self.ready:
            return {}
        terms = self.compute_terms(batch)
        logs = {f"intrinsic/{name}": float(v.mean()) for name, v in terms.items()}
        logs["intrinsic/reward"] = float(self.scale * self.combine(terms)[0])
        return logs

    def compute(self, batch: TransitionBatch) -> Tensor:
        active = {name: self.terms[name].compute(batch) for name, w in self.weights.items() if w > 0}
        return self.combine(active) if active else torch.zeros(len(batch), device=batch.act.device)

    def imagined_terms(self, z: Tensor, a: Tensor, z_next: Tensor) -> dict[str, Tensor]:
        """The weighted terms of imagined edges, name -> (N,): z (N, d), a (N,) long, z_next (N, d)."""
        return {name: w * self.terms[name].imagine(z, a, z_next) for name, w in self.imagined_weights().items()}

    def imagine(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        """r_int of imagined edges, (N,): the sum of :meth:`imagined_terms`."""
        return torch.stack(list(self.imagined_terms(z, a, z_next).values())).sum(0)

    def update(self, batch: TransitionBatch) -> dict[str, float]:
        logs: dict[str, float] = {}
        for term in self.terms.values():
            logs.update(term.update(batch))
        return logs

    def observe(self, batch: TransitionBatch) -> dict[str, float]:
        logs: dict[str, float] = {}
        for term in self.terms.values():
            logs.update(term.observe(batch))
        return logs

    def summary(self) -> dict[str, Any]:
        out: dict[str, Any] = {"intrinsic_weights": dict(self.weights)}
        for term in self.terms.values():
            out.update(term.summary())
        return out

    def to(self, device: torch.device | str) -> Mixture:
        for term in self.terms.values():
            term.to(device)
        return self

    def state_dict(self) -> dict[str, Any]:
        return {name: term.state_dict() for name, term in self.terms.items()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        missing = set(self.terms) - set(state)
        if missing:
            raise ValueError(f"the checkpoint has no state for intrinsic term(s) {sorted(missing)}: saved {sorted(state)}")
        for name, term in self.terms.items():
            term.load_state_dict(state[name])
