"""Exact values of the n-step model losses, the terminal mask and the double-DQN loss on hand-made segments."""

from __future__ import annotations

import math

import pytest
import torch

from curiosity.losses import (
    double_dqn_loss,
    nstep_backward_loss,
    nstep_code_loss,
    nstep_reward_loss,
    nstep_transition_loss,
    terminal_mask,
)
from curiosity.nets import BackwardPredictor

OFFSETS = torch.tensor([[1.0], [2.0]], dtype=torch.float64)


def shift_transition(z, a_onehot):
    """Toy T: z + (1 if a = 0 else 2)."""
    return z + a_onehot @ OFFSETS


def reference_nll(y, candidates, sigma=1.0):
    sq = (y.unsqueeze(1) - candidates).square().sum(-1)
    return -(torch.logsumexp(-sq / (2 * sigma**2), dim=1) - math.log(candidates.shape[1]))


def onehots(actions, n=2):
    return torch.nn.functional.one_hot(torch.tensor(actions), n).to(torch.float64)


# Segment 1 (no terminal): z0 = 0, actions [0, 1, 0] -> open-loop predictions 1, 3, 4 vs targets 1.5, 3.5, 2.
# Segment 2 (terminal after step 1): z0 = 1, actions [1, 1, 1] -> predictions 3, 5, 7 vs targets 2, 4, 7.
Z0 = torch.tensor([[0.0], [1.0]], dtype=torch.float64)
ACTIONS = torch.stack([onehots([0, 1, 0]), onehots([1, 1, 1])])
TARGETS = torch.tensor([[[1.5], [3.5], [2.0]], [[2.0], [4.0], [7.0]]], dtype=torch.float64)
TERMS = torch.tensor([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]], dtype=torch.float64)


def test_terminal_mask():
    d = torch.tensor([[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 1.0, 0.0]])
    expected = torch.tensor([[1.0, 0, 0, 0], [1, 1, 1, 1], [0, 0, 0, 0]])
    assert torch.equal(terminal_mask(d), expected)
    inclusive = torch.tensor([[1.0, 1, 0, 0], [1, 1, 1, 1], [1, 0, 0, 0]])
    assert torch.equal(terminal_mask(d, include_terminal_step=True), inclusive)


def test_nstep_transition_loss_exact_with_mid_segment_terminal():
    loss = nstep_transition_loss(Z0, ACTIONS, TARGETS, TERMS, shift_transition)
    # seg 1: (0.25 + 0.25 + 4) / 3 ; seg 2: step errors (1, 1, 0), mask (1, 0, 0) -> 1 / 3 ; batch mean.
    assert loss.item() == pytest.approx((4.5 / 3 + 1 / 3) / 2, abs=1e-12)


def test_nstep_transition_loss_terminal_at_first_step_masks_everything():
    terms = torch.tensor([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]], dtype=torch.float64)
    assert nstep_transition_loss(Z0, ACTIONS, TARGETS, terms, shift_transition).item() == 0.0  # exact: all masked


def test_nstep_transition_loss_normalised_value():
    eps = 1e-6
    loss = nstep_transition_loss(Z0, ACTIONS, TARGETS, TERMS, shift_transition, normalised=True, eps=eps)
    # predicted step sizes: seg 1 (1, 2, 1) -> squared (1, 4, 1); seg 2 (2, 2, 2) -> squared 4.
    seg1 = 0.25 / (1 + eps) + 0.25 / (4 + eps) + 4.0 / (1 + eps)
    seg2 = 1.0 / (4 + eps)
    assert loss.item() == pytest.approx((seg1 / 3 + seg2 / 3) / 2, rel=1e-12)


def test_nstep_transition_loss_does_not_detach_targets():
    targets = TARGETS.clone().requires_grad_(True)
    nstep_transition_loss(Z0, ACTIONS, targets, TERMS, shift_transition).backward()
    # d/dtarget of (1/n)(1/B) Σ m (pred - target)^2 = -2 m (pred - target) / (n B)
    expected = torch.tensor([[[-2 * -0.5], [-2 * -0.5], [-2 * 2.0]], [[-2 * 1.0], [0.0], [0.0]]], dtype=torch.float64) / 6
    torch.testing.assert_close(targets.grad, expected)


def test_detached_normaliser_changes_only_gradient():
    def scaled_transition(z, a_onehot):
        return z + scale * (a_onehot @ OFFSETS)

    grads, values = [], []
    for detach in (False, True):
        scale = torch.tensor(1.0, dtype=torch.float64, requires_grad=True)
        loss = nstep_transition_loss(Z0, ACTIONS, TARGETS, TERMS, scaled_transition, normalised=True, detach_normaliser=detach)
        loss.backward()
        values.append(loss.item())
        grads.append(scale.grad.item())
    assert values[0] == values[1]  # exact: the same forward computation, in one process
    assert grads[0] != pytest.approx(grads[1])


def test_nstep_transition_loss_trains_a_real_model():
    from curiosity.nets import ResidualTransition

    torch.manual_seed(0)
    model = ResidualTransition(2, 3, dropout=0.0)
    z0 = torch.randn(4, 2, requires_grad=True)
    acts = torch.nn.functional.one_hot(torch.randint(3, (4, 5)), 3).float()
    loss = nstep_transition_loss(z0, acts, torch.randn(4, 5, 2), torch.zeros(4, 5), model)
    loss.backward()
    assert loss.ndim == 0 and z0.grad is not None and all(p.grad is not None for p in model.parameters())


def test_nstep_reward_loss_exact():
    latents = torch.tensor([[[1.0], [2.0], [3.0]]], dtype=torch.float64)
    actions = onehots([0, 1, 0]).unsqueeze(0)
    rewards = torch.tensor([[1.0, 1.0, 1.0]], dtype=torch.float64)
    terms = torch.tensor([[0.0, 1.0, 0.0]], dtype=torch.float64)

    def reward_model(y):
        return y.sum(-1)  # predictions 2, 3, 4 -> squared errors 1, 4, 9

    assert nstep_reward_loss(latents, actions, rewards, terms, reward_model).item() == pytest.approx(1 / 3)
    kept = nstep_reward_loss(latents, actions, rewards, terms, reward_model, include_terminal_step=True)
    assert kept.item() == pytest.approx(5 / 3)


def shifted_candidates(z_next, generator=None):
    """Two deterministic candidates [z + 0, 1] and [z + 2, 1] (D = 2)."""
    base = torch.cat([z_next, torch.ones_like(z_next)], dim=-1)
    return torch.stack([base, base + torch.tensor([2.0, 0.0], dtype=z_next.dtype)], dim=1)


@pytest.mark.parametrize(("terms", "weight"), [([0.0, 0.0], 1.0), ([0.0, 1.0], 0.5), ([1.0, 0.0], 0.0)])
def test_nstep_backward_loss_exact(terms, weight):
    y = torch.tensor([[[0.0, 1.0], [1.0, 1.0]]], dtype=torch.float64)
    next_latents = torch.tensor([[[1.0], [2.0]]], dtype=torch.float64)
    terms = torch.tensor([terms], dtype=torch.float64)
    loss = nstep_backward_loss(y, next_latents, terms, shifted_candidates, reference_nll)
    per_step = -math.log(0.5 * (math.exp(-0.5) + math.exp(-4.5)))  # squared distances 1 and 9 at both steps
    assert loss.item() == pytest.approx(weight * per_step, rel=1e-12)


def test_nstep_backward_loss_with_predictor_is_seeded_and_differentiable():
    torch.manual_seed(0)
    predictor = BackwardPredictor(latent_dim=2, n_actions=3, n_candidates=4)
    y, z_next, terms = torch.randn(5, 3, 5), torch.randn(5, 3, 2), torch.zeros(5, 3)
    first = nstep_backward_loss(y, z_next, terms, predictor, reference_nll, generator=torch.Generator().manual_seed(1))
    again = nstep_backward_loss(y, z_next, terms, predictor, reference_nll, generator=torch.Generator().manual_seed(1))
    assert first.item() == again.item()  # exact: one seeded computation twice, in one process
    first.backward()
    assert all(p.grad is not None for p in predictor.parameters())


def dqn_inputs():
    q = torch.tensor([[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]], requires_grad=True)
    q_next_online = torch.tensor([[0.0, 5.0, 1.0], [2.0, 1.0, 0.0]], requires_grad=True)
    q_next_target = torch.tensor([[10.0, 20.0, 30.0], [7.0, 8.0, 9.0]], requires_grad=True)
    return q, q_next_online, q_next_target, torch.tensor([2, 0]), torch.tensor([1.0, -1.0]), torch.tensor([0.0, 1.0])


def test_double_dqn_loss_exact():
    # targets: row 0 picks a' = 1 online -> 1 + 0.5 * 20 = 11 ; row 1 terminal -> -1. TD errors: 3 - 11 = -8, 0 + 1 = 1.
    args = dqn_inputs()
    assert double_dqn_loss(*args, gamma=0.5, huber=False).item() == pytest.approx((64 + 1) / 2)
    assert double_dqn_loss(*args, gamma=0.5).item() == pytest.approx((7.5 + 0.5) / 2)


def test_double_dqn_loss_gradient_only_through_online_q():
    q, q_next_online, q_next_target, act, reward, term = dqn_inputs()
    double_dqn_loss(q, q_next_online, q_next_target, act, reward, term, gamma=0.5, huber=False).backward()
    assert q_next_online.grad is None and q_next_target.grad is None
    assert torch.equal(q.grad, torch.tensor([[0.0, 0.0, -8.0], [1.0, 0.0, 0.0]]))  # exact: small-integer TD errors


def test_the_total_loss_is_one_weighted_sum_over_named_terms() -> None:
    from curiosity.agents.representation import LossWeights, total_loss

    x = torch.tensor(2.0, requires_grad=True)
    terms = {"transition": x * 1.0, "entropy": torch.tensor(-1.0), "q": x * x}
    weights = LossWeights(transition=0.5, q=2.0, reward=7.0).of_terms()
    loss = total_loss(terms, weights)
    assert loss.item() == pytest.approx(0.5 * 2 - 1 + 2.0 * 4)  # reward is not a term of this batch: not counted
    loss.backward()
    assert float(x.grad) == pytest.approx(0.5 + 2.0 * 2 * 2)
    with pytest.raises(KeyError):
        total_loss({"unknown": x}, weights)


def test_nstep_code_loss_scores_the_head_of_the_open_loop_rollout_terminal_masked():
    """Head h(z) = (2z, −z): predictions 1, 3, 4 and 3 (then masked) map to codes compared with the given ones."""
    codes = torch.stack([torch.cat([2 * TARGETS, -TARGETS], -1)[0], torch.zeros(3, 2, dtype=torch.float64)])

    def head(z):
        return torch.cat([2 * z, -z], dim=1)

    loss = nstep_code_loss(Z0, ACTIONS, codes, TERMS, shift_transition, head)
    # seg 1: predicted 1, 3, 4 vs targets 1.5, 3.5, 2 -> (2 dz)^2 + dz^2 = 5 dz^2: 5 (0.25 + 0.25 + 4); seg 2: only
    # step 1 counts (terminal after it): predicted 3 -> code (6, -3) vs 0: 45
    assert loss.item() == pytest.approx((5 * 4.5 / 3 + 45 / 3) / 2, rel=1e-12)
    z0 = Z0.clone().requires_grad_(True)
    nstep_code_loss(z0, ACTIONS, codes, TERMS, shift_transition, head).backward()
    assert z0.grad is not None and float(z0.grad.abs().sum()) > 0  # the start latent (the encoder) is trained
