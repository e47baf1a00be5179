"""n-step terminal-masked model losses: transition (paper eq. 19/20), reward (§3.7) and backward predictor (§3.5)."""

from __future__ import annotations

from collections.abc import Callable

import torch
from torch import Tensor

from curiosity.losses.masks import masked_step_mean, terminal_mask

TransitionFn = Callable[[Tensor, Tensor], Tensor]
NLLFn = Callable[[Tensor, Tensor], Tensor]


def rollout_latents(z0: Tensor, actions_onehot: Tensor, transition: TransitionFn) -> Tensor:
    """Open-loop rollout ŝ_{t+i+1} = T(ŝ_{t+i}, a_{t+i}) from ŝ_t = z0.

    Args:
        z0: (B, d) start latents.
        actions_onehot: (B, n, A) one-hot actions a_t .. a_{t+n-1}.
        transition: T(z (B, d), a_onehot (B, A)) -> (B, d).

    Returns:
        (B, n + 1, d) latents [ŝ_t, ŝ_{t+1}, ..., ŝ_{t+n}] (index 0 is z0 itself).
    """
    states = [z0]
    for i in range(actions_onehot.shape[1]):
        states.append(transition(states[-1], actions_onehot[:, i]))
    return torch.stack(states, dim=1)


def nstep_transition_loss(
    z0: Tensor,
    actions_onehot: Tensor,
    targets: Tensor,
    terminateds: Tensor,
    transition: TransitionFn,
    *,
    normalised: bool = False,
    eps: float = 1e-6,
    detach_normaliser: bool = False,
) -> Tensor:
    """Terminal-masked n-step latent transition loss.

    L = (1/n) Σ_{i<n} m_i ‖ŝ_{t+i+1} − s_{t+i+1}‖², averaged over the batch, with m = :func:`terminal_mask`.
    Normalised (paper eq. 20): step i is divided by ‖ŝ_{t+i+1} − ŝ_{t+i}‖² + ε (predicted step size, ŝ_t = z0).
    Gradients flow into ``targets`` unless the caller detaches them.

    Args:
        z0: (B, d) encoded start latents s_t = E(o_t).
        actions_onehot: (B, n, A) one-hot actions.
        targets: (B, n, d) target latents s_{t+1} .. s_{t+n}.
        terminateds: (B, n) terminal flags d_{t+i}.
        transition: T(z (B, d), a_onehot (B, A)) -> (B, d).
        normalised: use the normalised variant.
        eps: ε of the normalised variant.
        detach_normaliser: stop gradients through the normaliser (not in the paper; as written it is not detached,
            which also rewards larger predicted steps).

    Returns:
        Scalar loss.
    """
    states = rollout_latents(z0, actions_onehot, transition)
    per_step = (states[:, 1:] - targets).square().sum(-1)
    if normalised:
        step_size = (states[:, 1:] - states[:, :-1]).square().sum(-1)
        if detach_normaliser:
            step_size = step_size.detach()
        per_step = per_step / (step_size + eps)
    return masked_step_mean(per_step, terminal_mask(terminateds))


def nstep_code_loss(
    z0: Tensor,
    actions_onehot: Tensor,
    codes: Tensor,
    terminateds: Tensor,
    transition: TransitionFn,
    head: Callable[[Tensor], Tensor],
) -> Tensor:
    """Terminal-masked n-step loss of the codes the model predicts: L = (1/n) Σ_{i<n} m_i ‖h(ŝ_{t+i+1}) − c_{t+i+1}‖²,
    ŝ the open-loop rollout of :func:`rollout_latents` from z0, h a head from latents to codes, c the codes of the
    observations reached (e.g. a frozen random encoder's, which the planner's novelty scores), averaged over the batch.

    Args:
        z0: (B, d) start latents.
        actions_onehot: (B, n, A) one-hot actions.
        codes: (B, n, k) the codes of o_{t+1} .. o_{t+n}.
        terminateds: (B, n) terminal flags.
        transition: T(z (B, d), a_onehot (B, A)) -> (B, d).
        head: h(z (M, d)) -> (M, k).

    Returns:
        Scalar loss.
    """
    states = rollout_latents(z0, actions_onehot, transition)[:, 1:]
    b, n, d = states.shape
    predicted = head(states.reshape(b * n, d)).reshape(b, n, -1)
    return masked_step_mean((predicted - codes).square().sum(-1), terminal_mask(terminateds))


def nstep_reward_loss(
    latents: Tensor,
    actions_onehot: Tensor,
    rewards: Tensor,
    terminateds: Tensor,
    reward_model: Callable[[Tensor], Tensor],
    *,
    include_terminal_step: bool = False,
) -> Tensor:
    """Terminal-masked n-step reward regression (paper §3.7).

    L_R = (1/n) Σ_{i<n} m_i (R([s_{t+i}, a_{t+i}]) − r_{t+i})², averaged over the batch.

    Args:
        latents: (B, n, d) encoded latents s_t .. s_{t+n-1}.
        actions_onehot: (B, n, A) one-hot actions.
        rewards: (B, n) rewards r_t .. r_{t+n-1}.
        terminateds: (B, n) terminal flags.
        reward_model: R(y (N, d + A)) -> (N,).
        include_terminal_step: keep the reward of the step that reaches the terminal (the paper masks it).

    Returns:
        Scalar loss.
    """
    b, n, _ = latents.shape
    y = torch.cat([latents, actions_onehot], dim=-1).reshape(b * n, -1)
    per_step = (reward_model(y).reshape(b, n) - rewards).square()
    return masked_step_mean(per_step, terminal_mask(terminateds, include_terminal_step=include_terminal_step))


def nstep_backward_loss(
    y: Tensor,
    next_latents: Tensor,
    terminateds: Tensor,
    predictor: Callable[..., Tensor],
    nll_fn: NLLFn,
    *,
    generator: torch.Generator | None = None,
) -> Tensor:
    """Terminal-masked n-step backward-predictor loss (paper eq. 25).

    L_back = (1/n) Σ_{i<n} m_i · nll(y_{t+i}, B(s_{t+i+1}, ε)), averaged over the batch, with
    nll(y, ŷ) = −log (1/K) Σ_k exp(−‖y − ŷ^(k)‖² / (2σ_b²)) supplied by ``nll_fn``.

    Args:
        y: (B, n, D) true predecessors [s_{t+i}, onehot a_{t+i}], D = d + A.
        next_latents: (B, n, d) successors s_{t+i+1}.
        terminateds: (B, n) terminal flags.
        predictor: B(z_next (N, d), generator=...) -> (N, K, D).
        nll_fn: nll(y (N, D), candidates (N, K, D)) -> (N,).
        generator: RNG forwarded to ``predictor`` for ε.

    Returns:
        Scalar loss.
    """
    b, n, dim = y.shape
    candidates = predictor(next_latents.reshape(b * n, -1), generator=generator)
    per_step = nll_fn(y.reshape(b * n, dim), candidates).reshape(b, n)
    return masked_step_mean(per_step, terminal_mask(terminateds))
