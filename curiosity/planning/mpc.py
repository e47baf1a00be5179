"""Sampling MPC over discrete action sequences in the learned latent model or the simulator (paper §3.9, eq. 39–41)."""

from __future__ import annotations

from typing import ClassVar

import torch
from torch import Tensor

from curiosity.planning.protocols import IntrinsicFn, Plan, PlanRequest, QFn, ScoreFn
from curiosity.planning.rollout import LatentRollout, Rollout, StepFn, held

TEMPERATURE_SCALES = ("absolute", "spread")
PLANNER_MODELS = ("learned", "oracle")


class MPCPlanner:
    """Score action sequences by Ĝ = Σ_{i<H} γ^i [R(ŷ_i) + η r_int(ŷ_i)], ŷ_i = [ŝ_i, a_i], sample one ∝ exp(Ĝ/τ).

    With a terminal value (``value_coef`` κ > 0, not in the paper: TD-MPC's value beyond the horizon, with NSRS's Q),
    Ĝ gains κ γ^H max_a Q(ŝ_H, a), the value of the leaf; the agent then trains Q on replayed transitions
    (``needs_q``), discounted per env step by :attr:`step_discount` = γ^(1/hold), so the leaf's γ^H is the exact
    discount of the H × hold env steps before it.

    ŝ_0 = z0 and ŝ_{i+1} = T(ŝ_i, a_i): the reward term is scored on the (latent, action) pair before stepping, the
    intrinsic term on the edge (ŝ_i, a_i, ŝ_{i+1}) (state novelty scores the state reached). Candidates are all A^H
    sequences when A^H ≤ ``max_candidates``, else ``max_candidates`` sequences drawn uniformly (with replacement),
    which must be asked for with ``sample_candidates=True``.

    Rollouts run in one batched call per depth. Candidates sharing a prefix share its rollout: at depth i only the
    distinct (prefix, a_i) pairs are scored and stepped (A + A² + … + A^H pairs for the full enumeration, 363 for
    3^5 instead of 5·243), which is exact for a deterministic (eval-mode) model.

    Args:
        horizon: H.
        gamma: discount γ.
        temperature: τ; τ ≤ 0 means argmax (ties to the lowest candidate index).
        temperature_scale: ``absolute`` (softmax of Ĝ/τ) or ``spread`` (Ĝ standardised across the candidates first,
            so τ does not depend on the scale of the scores, which moves by orders of magnitude while latents grow).
        eta: intrinsic weight η.
        max_candidates: enumeration limit / number of sampled sequences.
        n_actions: A.
        sample_candidates: whether to sample ``max_candidates`` sequences when A^H exceeds it (else ValueError).
        model: where imagined futures come from: ``learned`` (the world model) or ``oracle`` (the real simulator,
            rendered and encoded: the upper bound a learned model is measured against). The agent builds the rollout.
        commit: how many actions of the chosen sequence the agent executes before it plans again (1: replan at every
            step, receding horizon); the agent executes that many actions of :attr:`Plan.sequence` (× ``hold``).
        value_coef: κ, the weight of the leaf's value κ γ^H max_a Q(ŝ_H, a) (0: no terminal value, no Q). Q sums a
            reward per env step and a depth of the plan one per held action: κ = 1/hold puts them on one scale.
        hold: env steps each action of a candidate is held for (1: every step its own action). A candidate is still
            H actions (A^H candidates), but it looks H × hold steps ahead; each depth's terms are scored once, on
            the edge from the latent before the held action to the latent after it. :attr:`Plan.sequence` holds the
            H × hold env actions, and :attr:`commit` counts env actions (``commit × hold``).
    """

    scores_candidates: ClassVar[bool] = True  # scores an explicit candidate set (candidates(), scores())

    def __init__(
        self,
        horizon: int = 5,
        gamma: float = 0.9,
        temperature: float = 0.1,
        eta: float = 1.0,
        max_candidates: int = 243,
        n_actions: int = 3,
        sample_candidates: bool = False,
        temperature_scale: str = "absolute",
        model: str = "learned",
        commit: int = 1,
        hold: int = 1,
        value_coef: float = 0.0,
    ) -> None:
        if not 1 <= commit <= horizon:
            raise ValueError(f"planner.commit must be in [1, planner.horizon={horizon}], got {commit}")
        if hold < 1:
            raise ValueError(f"planner.hold must be >= 1, got {hold}")
        self.hold = int(hold)
        self.commit = int(commit) * self.hold  # env actions executed per plan
        if horizon < 1 or n_actions < 1 or max_candidates < 1:
            raise ValueError("horizon, n_actions and max_candidates must be >= 1")
        if n_actions**horizon > max_candidates and not sample_candidates:
            raise ValueError(f"horizon={horizon}: {n_actions}^{horizon} sequences exceed max_candidates={max_candidates}; "
                             "pass sample_candidates=True to sample max_candidates of them")  # fmt: skip
        self.sample_candidates = sample_candidates
        self.horizon = horizon
        self.gamma = gamma
        self.temperature = temperature
        self.eta = eta
        self.max_candidates = max_candidates
        self.n_actions = n_actions
        if temperature_scale not in TEMPERATURE_SCALES:
            raise ValueError(f"planner.temperature_scale must be one of {TEMPERATURE_SCALES}, got {temperature_scale!r}")
        if model not in PLANNER_MODELS:
            raise ValueError(f"planner.model must be one of {PLANNER_MODELS}, got {model!r}")
        self.temperature_scale, self.model = temperature_scale, model
        if value_coef < 0:
            raise ValueError(f"planner.value_coef must be >= 0 (0: no terminal value), got {value_coef}")
        self.value_coef = float(value_coef)

    @property
    def needs_q(self) -> bool:
        """Whether the agent must train a Q-function (a terminal value, ``value_coef`` > 0)."""
        return self.value_coef > 0

    @property
    def step_discount(self) -> float:
        """The discount per env step of a Q-function whose values are the plan's leaves: γ^(1/hold)."""
        return float(self.gamma ** (1.0 / self.hold))

    def candidates(self, generator: torch.Generator | None = None) -> Tensor:
        """Candidate action sequences.

        Returns:
            (N, H) long; all A^H sequences in lexicographic order (first action most significant), or
            ``max_candidates`` uniform draws when A^H is larger.
        """
        total = self.n_actions**self.horizon
        if total <= self.max_candidates:
            codes = torch.arange(total, device="cpu").unsqueeze(1)  # candidates are made on the host (CPU generator)
            powers = self.n_actions ** torch.arange(self.horizon - 1, -1, -1, device="cpu")
            return torch.div(codes, powers, rounding_mode="floor") % self.n_actions
        return torch.randint(self.n_actions, (self.max_candidates, self.horizon), generator=generator, device="cpu")

    def score_terms(
        self,
        z0: Tensor,
        seqs: Tensor,
        step_fn: StepFn,
        reward_fn: ScoreFn | None,
        intrinsic_fn: IntrinsicFn,
        rollout: Rollout | None = None,
        q_fn: QFn | None = None,
    ) -> dict[str, Tensor]:
        """Discounted returns of each sequence, term by term; Ĝ is their sum.

        Args:
            z0: (d,) current latent.
            seqs: (N, H) long action sequences.
            step_fn: T(z (M, d), a (M,) long) -> (M, d), the imagined futures unless ``rollout`` is given.
            reward_fn: R(z (M, d), a (M,) long) -> (M,), or None for zero extrinsic reward.
            intrinsic_fn: r_int(z (M, d), a (M,) long, z_next (M, d)) -> (M,), or a mapping of named terms (M,) each
                whose sum is r_int (e.g. ``novelty`` and ``pe``).
            rollout: where the futures come from (:mod:`curiosity.planning.rollout`); default the learned model. Each
                expand covers ``hold`` env steps (a one-step rollout is wrapped in a
                :class:`~curiosity.planning.rollout.HeldRollout`).
            q_fn: Q(z (M, d)) -> (M, A); with ``value_coef`` > 0 it values the leaves (required then), else unused.

        Returns:
            term name -> (N,) Σ_i γ^i term_i: ``reward`` (R), η × each intrinsic term (``intrinsic`` when
            ``intrinsic_fn`` returns one tensor) and, with a terminal value, ``value``: κ γ^H max_a Q(ŝ_H, a).
        """
        if self.needs_q and q_fn is None:
            raise ValueError(f"planner.value_coef={self.value_coef}: the terminal value needs a Q-function (q_fn)")
        seqs = seqs.to(z0.device)
        rollout = held(LatentRollout(z0, step_fn) if rollout is None else rollout, self.hold)
        node = torch.zeros(seqs.shape[0], dtype=torch.long, device=z0.device)
        terms: dict[str, Tensor] = {}
        for i in range(seqs.shape[1]):
            pairs, child = torch.unique(node * self.n_actions + seqs[:, i], return_inverse=True)
            parents, a = pairs // self.n_actions, pairs % self.n_actions
            z = rollout.latents()[parents]
            z_next = rollout.expand(parents, a)
            parts = intrinsic_fn(z, a, z_next)
            parts = {"intrinsic": parts} if isinstance(parts, Tensor) else dict(parts)
            parts = {k: self.eta * v for k, v in parts.items()}
            if reward_fn is not None:
                parts["reward"] = reward_fn(z, a)
            for key, value in parts.items():
                previous = terms.get(key, torch.zeros(seqs.shape[0], dtype=z0.dtype, device=z0.device))
                terms[key] = previous + self.gamma**i * value[child]
            node = child
        if self.needs_q and q_fn is not None:
            leaf = q_fn(rollout.latents()).max(dim=1).values  # one value per distinct leaf
            terms["value"] = self.value_coef * self.gamma ** seqs.shape[1] * leaf[node]
        return terms

    def scores(self, z0: Tensor, seqs: Tensor, step_fn: StepFn, reward_fn: ScoreFn | None, intrinsic_fn: IntrinsicFn,
               rollout: Rollout | None = None, q_fn: QFn | None = None) -> Tensor:  # fmt: skip
        """Ĝ of each sequence, (N,): the sum of :meth:`score_terms` (same arguments)."""
        return _total(self.score_terms(z0, seqs, step_fn, reward_fn, intrinsic_fn, rollout, q_fn))

    def choose(self, returns: Tensor, generator: torch.Generator | None = None) -> tuple[int, Tensor, float]:
        """Index of the chosen sequence, the (N,) choice probabilities, and their entropy in nats.

        τ ≤ 0: argmax (ties to the lowest index), probabilities one-hot. ``temperature_scale=spread``: softmax of
        (Ĝ − mean Ĝ) / (std Ĝ · τ), so τ is in units of the candidates' own spread of scores; ``absolute``: Ĝ/τ.
        """
        if self.temperature <= 0:
            index = int(torch.argmax(returns))
            probs = torch.zeros_like(returns)
            probs[index] = 1.0
            return index, probs, 0.0
        logits = returns
        if self.temperature_scale == "spread":
            logits = (returns - returns.mean()) / returns.std(correction=0).clamp_min(1e-12)
        log_probs = torch.log_softmax(logits / self.temperature, dim=0)
        probs = log_probs.exp()
        index = int(torch.multinomial(probs.cpu(), 1, generator=generator))
        return index, probs, float(-(probs * log_probs).sum())

    def first_action_probs(self, seqs: Tensor, probs: Tensor) -> Tensor:
        """(A,) probability of each first action under the choice probabilities ``probs`` (N,) of ``seqs`` (N, H)."""
        return torch.zeros(self.n_actions, dtype=probs.dtype, device="cpu").index_add_(0, seqs[:, 0].cpu(), probs.cpu())

    def plan(self, request: PlanRequest) -> Plan:
        """Choose a sequence drawn from softmax(Ĝ/τ) (argmax for τ ≤ 0) at ``request.z0``.

        Reads ``z0``, ``step_fn``, ``reward_fn``, ``intrinsic`` (one tensor, or named terms, see :meth:`score_terms`),
        ``generator`` (candidate sampling and the softmax draw; CPU), ``rollout`` and, with a terminal value,
        ``q_fn``.

        Returns:
            the chosen sequence (each action repeated ``hold`` times), its Ĝ, and info keys ``best_score``,
            ``entropy`` (nats, of the choice over candidates; 0 for argmax), ``first_action_entropy`` (nats, of the
            first action's marginal), ``p_first/<a>``, ``n_candidates``, ``spread/<term>`` (std across candidates of
            each term's return) and ``spread/score``.
        """
        with torch.no_grad():
            seqs = self.candidates(request.generator)
            terms = self.score_terms(request.z0, seqs, request.step_fn, request.reward_fn, request.intrinsic,
                                     request.rollout, request.q_fn)  # fmt: skip
            returns = _total(terms)
            index, probs, entropy = self.choose(returns, request.generator)
            first = self.first_action_probs(seqs, probs)
        info = {
            "best_score": float(returns.max()),
            "entropy": entropy,
            "first_action_entropy": float(-(first * first.clamp_min(1e-30).log()).sum()),
            "n_candidates": float(seqs.shape[0]),
            "spread/score": float(returns.std(correction=0)),
            **{f"spread/{k}": float(v.std(correction=0)) for k, v in terms.items()},
            **{f"p_first/{a}": float(p) for a, p in enumerate(first)},
        }
        return Plan([int(a) for a in seqs[index] for _ in range(self.hold)], float(returns[index]), info)


def _total(terms: dict[str, Tensor]) -> Tensor:
    return torch.stack(list(terms.values())).sum(0)
