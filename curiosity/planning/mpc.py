"""Sampling MPC over discrete action sequences in the learned latent model (paper §3.9, eq. 39–41)."""

from __future__ import annotations

from collections.abc import Callable

import torch
from torch import Tensor

StepFn = Callable[[Tensor, Tensor], Tensor]
ScoreFn = Callable[[Tensor, Tensor], Tensor]


class MPCPlanner:
    """Score action sequences by Ĝ = Σ_{i<H} γ^i [R(ŷ_i) + η r_int(ŷ_i)], ŷ_i = [ŝ_i, a_i], sample one ∝ exp(Ĝ/τ).

    ŝ_0 = z0 and ŝ_{i+1} = T(ŝ_i, a_i): every term is scored on the (latent, action) pair *before* stepping, so the
    last action of a sequence is scored but never stepped. Candidates are all A^H sequences when A^H ≤
    ``max_candidates``, else ``max_candidates`` sequences drawn uniformly (with replacement), which must be asked for
    with ``sample_candidates=True``.

    Rollouts run in one batched call per depth. Candidates sharing a prefix share its rollout: at depth i only the
    distinct (prefix, a_i) pairs are scored and stepped (A + A² + … + A^H pairs for the full enumeration, 363 for
    3^5 instead of 5·243), which is exact for a deterministic (eval-mode) model.

    Args:
        horizon: H.
        gamma: discount γ.
        temperature: τ; τ ≤ 0 means argmax (ties to the lowest candidate index).
        eta: intrinsic weight η.
        max_candidates: enumeration limit / number of sampled sequences.
        n_actions: A.
        sample_candidates: whether to sample ``max_candidates`` sequences when A^H exceeds it (else ValueError).
    """

    uses_q = False  # whether the agent must train a Q-function for this planner

    def __init__(
        self,
        horizon: int = 5,
        gamma: float = 0.9,
        temperature: float = 0.1,
        eta: float = 1.0,
        max_candidates: int = 243,
        n_actions: int = 3,
        sample_candidates: bool = False,
    ) -> None:
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

    def candidates(self, generator: torch.Generator | None = None) -> Tensor:
        """Candidate action sequences.

        Returns:
            (N, H) long; all A^H sequences in lexicographic order (first action most significant), or
            ``max_candidates`` uniform draws when A^H is larger.
        """
        total = self.n_actions**self.horizon
        if total <= self.max_candidates:
            codes = torch.arange(total).unsqueeze(1)
            powers = self.n_actions ** torch.arange(self.horizon - 1, -1, -1)
            return torch.div(codes, powers, rounding_mode="floor") % self.n_actions
        return torch.randint(self.n_actions, (self.max_candidates, self.horizon), generator=generator)

    def scores(self, z0: Tensor, seqs: Tensor, step_fn: StepFn, reward_fn: ScoreFn | None, intrinsic_fn: ScoreFn) -> Tensor:
        """Discounted returns Ĝ of each sequence.

        Args:
            z0: (d,) current latent.
            seqs: (N, H) long action sequences.
            step_fn: T(z (M, d), a (M,) long) -> (M, d).
            reward_fn: R(z (M, d), a (M,) long) -> (M,), or None for zero extrinsic reward.
            intrinsic_fn: r_int(z (M, d), a (M,) long) -> (M,).

        Returns:
            (N,) Ĝ.
        """
        seqs = seqs.to(z0.device)
        node = torch.zeros(seqs.shape[0], dtype=torch.long, device=z0.device)
        latents = z0.unsqueeze(0)
        returns = torch.zeros(seqs.shape[0], dtype=z0.dtype, device=z0.device)
        for i in range(seqs.shape[1]):
            pairs, child = torch.unique(node * self.n_actions + seqs[:, i], return_inverse=True)
            z, a = latents[pairs // self.n_actions], pairs % self.n_actions
            score = self.eta * intrinsic_fn(z, a)
            if reward_fn is not None:
                score = score + reward_fn(z, a)
            returns = returns + self.gamma**i * score[child]
            if i + 1 < seqs.shape[1]:
                latents = step_fn(z, a)
            node = child
        return returns

    def plan(
        self,
        z0: Tensor,
        step_fn: StepFn,
        reward_fn: ScoreFn | None,
        intrinsic_fn: ScoreFn,
        generator: torch.Generator | None = None,
    ) -> tuple[int, dict[str, float]]:
        """Choose the first action of a sequence sampled from softmax(Ĝ/τ).

        Args:
            z0: (d,) current latent.
            step_fn: T(z (M, d), a (M,) long) -> (M, d), run in eval mode by the caller.
            reward_fn: R(z, a) -> (M,), or None.
            intrinsic_fn: r_int(z, a) -> (M,).
            generator: RNG for candidate sampling and the softmax draw (CPU generator for CPU tensors).

        Returns:
            (action, info) with info keys ``best_score``, ``chosen_score``, ``entropy`` (nats, of the softmax over
            candidates; 0 for argmax) and ``n_candidates``.
        """
        with torch.no_grad():
            seqs = self.candidates(generator)
            returns = self.scores(z0, seqs, step_fn, reward_fn, intrinsic_fn)
            if self.temperature <= 0:
                index, entropy = int(torch.argmax(returns)), 0.0
            else:
                log_probs = torch.log_softmax(returns / self.temperature, dim=0)
                probs = log_probs.exp()
                index = int(torch.multinomial(probs.cpu(), 1, generator=generator))
                entropy = float(-(probs * log_probs).sum())
        info = {
            "best_score": float(returns.max()),
            "chosen_score": float(returns[index]),
            "entropy": entropy,
            "n_candidates": float(seqs.shape[0]),
        }
        return int(seqs[index, 0]), info
