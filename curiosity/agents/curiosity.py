"""The paper's curiosity signal on learned latents: novelty over a refreshed memory, hybrid with a prediction-error
bonus (paper §3.3), behind the one :class:`~curiosity.intrinsic.IntrinsicReward` interface.

Novelty input (``novelty_input``):
    ``state_action`` (paper text): memory rows y_t = [s_t, c·onehot(a_t)], an edge (s, a, s') is scored by
    novelty(y) with y = [s, c·onehot(a)]; c = ``action_scale`` sets how far apart actions are (method.md §9).
    ``state`` (precursor code, NSRS): memory rows s_t; an edge is scored by the novelty of the state reached, s'.
With ``standardise=True`` the latent part is standardised per dimension by the memory's mean and standard deviation
at the last refresh, so the bandwidth and ``action_scale`` are in units of the latent spread, which drifts while the
encoder trains.

Prediction-error bonus (weight α = ``alpha``): on a real transition, r_pe = log1p(e / (ē + ε)) with the true error
e = ‖T(s, a) − s'‖² (paper Eq. 10). An imagined edge has no true successor; the paper is silent on how the planner
scores it, and ``pe_imagined`` chooses the model's own estimate ê(s, a) of that error, normalised by the running
mean of ê at the real pairs visited:
    ``dropout``: MC-dropout disagreement mean_m ‖T_m(s, a) − T(s, a)‖² (random: a fresh draw at every evaluation);
    ``ensemble``: disagreement of a deep ensemble of transitions (``transition_ensemble`` ≥ 2; deterministic);
    ``off``: imagined edges are scored by novelty alone (weight 1), real transitions keep the hybrid.
Both running means are updated after use, once per env step.
"""

from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np
import torch
from scipy.stats import spearmanr
from torch import Tensor

from curiosity.agents.world_model import WorldModel
from curiosity.intrinsic.base import IntrinsicReward
from curiosity.nets.onehot import one_hot
from curiosity.novelty.memory import EmbeddingMemory
from curiosity.novelty.rewards import PredictionErrorBonus
from curiosity.replay import ReplayBuffer
from curiosity.types import TransitionBatch

NOVELTY_INPUTS = ("state_action", "state")
PE_IMAGINED = ("dropout", "ensemble", "off")
PE_WINDOW = 200  # real transitions in the signal check of the imagined prediction-error estimate
CURIOSITY_KEYS = ("intrinsic/novelty", "intrinsic/pe", "intrinsic/pe_error", "intrinsic/memory_size")


class LatentCuriosity(IntrinsicReward):
    """r_int = (1 − α) r_nov + α r_pe on latent embeddings (see the module docstring).

    Args:
        model: the world model (encoder for embeddings, transition for prediction errors).
        estimator: novelty estimator with ``fit(memory, reference)``, ``set_memory(memory)``, ``__call__(query)``.
        replay: the agent's replay buffer (memory rows are re-embedded from it by global transition index).
        memory: the embedding memory.
        n_actions: A.
        novelty_input: ``state_action`` or ``state``.
        action_scale: c, the length of the action part of y.
        alpha: α ∈ [0, 1].
        pe_average: running mean of the bonus, ``cumulative`` or ``ema``.
        pe_eps: ε.
        dropout_samples: MC-dropout samples for imagined edges (``pe_imagined=dropout``).
        pe_imagined: how imagined edges get their prediction-error term: ``dropout``, ``ensemble`` or ``off``.
        warmup_steps: the random phase: transitions with global index below it form the reference set.
        scale: multiplies ``__call__``.
    """

    def __init__(self, model: WorldModel, estimator: Any, replay: ReplayBuffer, memory: EmbeddingMemory, *,
                 n_actions: int, novelty_input: str = "state_action", action_scale: float = 1.0, alpha: float = 0.5,
                 pe_average: str = "cumulative", pe_eps: float = 1e-8, dropout_samples: int = 8, warmup_steps: int = 64,
                 standardise: bool = True, pe_imagined: str = "dropout", scale: float = 1.0) -> None:  # fmt: skip
        super().__init__(scale)
        if pe_imagined not in PE_IMAGINED:
            raise ValueError(f"pe_imagined must be one of {PE_IMAGINED}, got {pe_imagined!r}")
        self.pe_imagined_kind = pe_imagined
        if novelty_input not in NOVELTY_INPUTS:
            raise ValueError(f"novelty_input must be one of {NOVELTY_INPUTS}, got {novelty_input!r}")
        self.model, self.estimator, self.replay, self.memory = model, estimator, replay, memory
        self.n_actions, self.novelty_input, self.action_scale = n_actions, novelty_input, float(action_scale)
        self.alpha, self.dropout_samples, self.warmup_steps = float(alpha), int(dropout_samples), int(warmup_steps)
        self.pe_real = PredictionErrorBonus(eps=pe_eps, average=pe_average)
        self.pe_imagined = PredictionErrorBonus(eps=pe_eps, average=pe_average)
        self.standardise = bool(standardise)
        self.z_mean: Tensor | None = None
        self.z_std: Tensor | None = None
        self.ready = False
        self.pe_pairs: deque[tuple[float, float]] = deque(maxlen=PE_WINDOW)

    # ------------------------------------------------------------------ memory
    def _std(self, z: Tensor) -> Tensor:
        if self.z_mean is None or self.z_std is None:
            return z
        return (z - self.z_mean) / self.z_std

    def embed(self, z: Tensor, a: Tensor) -> Tensor:
        """Memory/query embedding of pairs: z (N, d), a (N,) long -> (N, d + A) or (N, d)."""
        z = self._std(z)
        if self.novelty_input == "state":
            return z
        return torch.cat([z, self.action_scale * one_hot(a, self.n_actions).to(z.dtype)], dim=1)


    def _encode_stored(self, keys: np.ndarray) -> Tensor:
        """Latents of stored transitions' o_t by global index, with the current encoder: (M,) -> (M, d)."""
        with self.model.evaluating():
            device = next(self.model.parameters()).device
            parts = [self.model.encode(self.replay.obs_at(keys[i : i + 512]).to(device)) for i in range(0, len(keys), 512)]
        return torch.cat(parts)

    def add(self, z: Tensor, a: int, index: int) -> None:
        """Store the embedding of the pair (s_t, a_t) of transition ``index`` (z: (d,) latent of o_t)."""
        emb = self.embed(z.unsqueeze(0), torch.tensor([a], device=z.device))
        self.memory.add(emb, keys=torch.tensor([index], device="cpu"))
        if self.ready:
            self.estimator.set_memory(self.memory.tensor())

    @torch.no_grad()
    def refresh(self) -> None:
        """Re-embed every memory row and the random-phase reference with the current encoder; refit the estimator."""
        keys = self.memory.keys().numpy()
        z = self._encode_stored(keys)
        if self.standardise:
            self.z_mean, self.z_std = z.mean(0), z.std(0, correction=0).clamp_min(1e-8)
        self.memory.replace(self.embed(z, self.replay.actions_at(keys).to(z.device)))
        ref_keys = np.arange(min(self.warmup_steps, self.replay.total_added))
        reference = None
        if len(ref_keys) > 1:
            row = {int(k): i for i, k in enumerate(keys)}
            if all(int(k) in row for k in ref_keys):  # the random phase is in the memory: no second encoding
                z_ref = z[[row[int(k)] for k in ref_keys]]
            else:  # a reservoir may have dropped some of it
                z_ref = self._encode_stored(ref_keys)
            reference = self.embed(z_ref, self.replay.actions_at(ref_keys).to(z.device))
        self.estimator.fit(self.memory.tensor(), reference, stream_size=self.memory.stands_for)
        self.ready = True

    @torch.no_grad()
    def drift(self, rows: int = 64) -> float:
        """How far the memory has gone stale: the median distance, in standardised latent units, between up to ``rows``
        memory rows (evenly spaced) and the embedding the current encoder gives their observations."""
        keys = self.memory.keys()
        index = torch.linspace(0, len(keys) - 1, min(rows, len(keys)), device="cpu").round().long()
        now = self._std(self._encode_stored(keys[index].numpy()))
        stored = self.memory.tensor()[index, : now.shape[1]]
        return float((now - stored).norm(dim=1).median())

    # ------------------------------------------------------------------ rewards
    def novelty(self, z: Tensor, a: Tensor, z_next: Tensor | None) -> Tensor:
        """Novelty of edges (z, a, z_next): (N, d), (N,), (N, d) -> (N,)."""
        if self.novelty_input == "state":
            assert z_next is not None
            return self.estimator(self._std(z_next))
        return self.estimator(self.embed(z, a))

    @property
    def imagined_alpha(self) -> float:
        """The weight of the prediction-error term on imagined edges (0 when ``pe_imagined=off``)."""
        return 0.0 if self.pe_imagined_kind == "off" else self.alpha

    @property
    def stochastic(self) -> bool:
        """Whether :meth:`imagined_terms` draws random numbers (MC dropout), so two evaluations differ."""
        return self.pe_imagined_kind == "dropout" and self.alpha > 0

    def _imagined_error(self, z: Tensor, a: Tensor) -> Tensor:
        if self.pe_imagined_kind == "ensemble":
            return self.model.ensemble_disagreement(z, a)
        return self.model.dropout_disagreement(z, a, self.dropout_samples)

    def imagined_terms(self, z: Tensor, a: Tensor, z_next: Tensor | None = None) -> dict[str, Tensor]:
        """The weighted terms of r_int of imagined edges: ``novelty`` (1 − α) r_nov and, with α > 0, ``pe`` α r̂_pe.

        (N, d), (N,) [, (N, d)] -> name -> (N,); z_next is computed with the model if needed and not given.
        """
        if z_next is None and self.novelty_input == "state":
            z_next = self.model.next(z, a)
        alpha = self.imagined_alpha
        terms = {"novelty": (1 - alpha) * self.novelty(z, a, z_next)}
        if alpha > 0:
            terms["pe"] = alpha * self.pe_imagined.compute(self._imagined_error(z, a))
        return terms

    def imagined(self, z: Tensor, a: Tensor, z_next: Tensor | None = None) -> Tensor:
        """r_int of imagined edges for planners: (N, d), (N,) [, (N, d)] -> (N,), the sum of :meth:`imagined_terms`."""
        terms = self.imagined_terms(z, a, z_next)
        return torch.stack(list(terms.values())).sum(0)

    def _true_error(self, z: Tensor, a: Tensor, z_next: Tensor) -> Tensor:
        with self.model.evaluating():
            return (self.model.next(z, a) - z_next).square().sum(1)

    @torch.no_grad()
    def from_latents(self, z: Tensor, a: Tensor, z_next: Tensor) -> tuple[Tensor, dict[str, float]]:
        """r_int of real transitions from their latents: (B, d), (B,), (B, d) -> (B,), and logged means."""
        r_nov = self.novelty(z, a, z_next)
        err = self._true_error(z, a, z_next)
        r_pe = self.pe_real.compute(err)
        logs = {"intrinsic/novelty": float(r_nov.mean()), "intrinsic/pe": float(r_pe.mean()),
                "intrinsic/pe_error": float(err.mean()), "intrinsic/memory_size": float(len(self.memory))}  # fmt: skip
        return (1 - self.alpha) * r_nov + self.alpha * r_pe, logs

    @torch.no_grad()
    def observe_latents(self, z: Tensor, a: Tensor, z_next: Tensor) -> None:
        """Fold real transitions into both prediction-error running means (after their rewards were used), and keep
        (estimate, true error) pairs for :meth:`pe_estimate_corr`."""
        error = self._true_error(z, a, z_next)
        self.pe_real.update(error)
        if self.pe_imagined_kind == "off":
            return
        estimate = self._imagined_error(z, a)
        if self.imagined_alpha > 0:
            self.pe_imagined.update(estimate)
        self.pe_pairs.extend(zip(estimate.tolist(), error.tolist(), strict=True))

    def pe_estimate_corr(self) -> float | None:
        """Does the imagined prediction-error estimate carry signal? The Spearman correlation between the estimate
        ê(s, a) and the true error ‖T(s, a) − s'‖² of the last ``PE_WINDOW`` real transitions, each taken before
        the model trained on it; None with fewer than 20 pairs or a constant side (e.g. no dropout)."""
        if len(self.pe_pairs) < 20:
            return None
        est, err = np.array(self.pe_pairs).T
        if np.ptp(est) == 0 or np.ptp(err) == 0:
            return None
        return float(spearmanr(est, err).statistic)

    # ------------------------------------------------------------------ IntrinsicReward interface
    @torch.no_grad()
    def _latents(self, batch: TransitionBatch) -> tuple[Tensor, Tensor]:
        with self.model.evaluating():
            return self.model.encode(batch.obs), self.model.encode(batch.next_obs)

    def compute(self, batch: TransitionBatch) -> Tensor:
        """r_int of real transitions (B,), with the running means as they are (no state changes)."""
        z, z_next = self._latents(batch)
        return self.from_latents(z, batch.act, z_next)[0]

    def update(self, batch: TransitionBatch) -> dict[str, float]:
        """Fold the batch's prediction errors into the running means; the representation trains in the agent."""
        z, z_next = self._latents(batch)
        self.observe_latents(z, batch.act, z_next)
        return {}

    # ------------------------------------------------------------------ checkpointing
    def state_dict(self) -> dict[str, Any]:
        est = getattr(self.estimator, "state_dict", None)
        return {"memory": self.memory.state_dict(), "pe_real": self.pe_real.state_dict(),
                "pe_imagined": self.pe_imagined.state_dict(), "ready": self.ready, "z_mean": self.z_mean, "z_std": self.z_std,
                "estimator": est() if est else None, "pe_pairs": list(self.pe_pairs)}  # fmt: skip

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.memory.load_state_dict(state["memory"])
        self.pe_real.load_state_dict(state["pe_real"])
        self.pe_imagined.load_state_dict(state["pe_imagined"])
        self.ready = bool(state["ready"])
        self.z_mean, self.z_std = state["z_mean"], state["z_std"]
        self.pe_pairs = deque(state.get("pe_pairs", []), maxlen=PE_WINDOW)
        if state["estimator"] is not None:
            self.estimator.load_state_dict(state["estimator"])
        if self.ready:
            self.estimator.set_memory(self.memory.tensor())
