"""MPC against brute force and softmax statistics; the Q-tree against a recursive search and NSRS's ordering bug."""

from __future__ import annotations

import itertools

import pytest
import torch

from curiosity.nets import QNetwork, ResidualTransition, one_hot
from curiosity.planning import MPCPlanner, Planner, PlanRequest, QTreePlanner

# ----------------------------------------------------------------------------- MPC toy model
OFFSET = torch.tensor([1.0, 0.0, -1.0], dtype=torch.float64)
BONUS = torch.tensor([0.0, 0.0, 2.5], dtype=torch.float64)


def toy_step(z, a):
    return z + OFFSET[a].unsqueeze(1)


def toy_reward(z, a):
    """Latent plus an action bonus: action 2 pays now but lowers every later latent."""
    return z[:, 0] + BONUS[a]


def zero_intrinsic(z, a, z_next=None):
    return torch.zeros(z.shape[0], dtype=z.dtype)


def brute_force_returns(z0, seqs, step, reward, intrinsic, gamma, eta):
    out = []
    for seq in seqs.tolist():
        z, total = z0.unsqueeze(0), 0.0
        for i, a in enumerate(seq):
            act = torch.tensor([a])
            z_next = step(z, act)
            total += gamma**i * float(reward(z, act) + eta * intrinsic(z, act, z_next))
            z = z_next
        out.append(total)
    return torch.tensor(out, dtype=torch.float64)


@pytest.mark.parametrize("temperature", [0.0, 1e-6])
def test_mpc_low_temperature_picks_the_best_sequence(temperature):
    planner = MPCPlanner(horizon=3, gamma=0.9, temperature=temperature)
    z0 = torch.tensor([0.5], dtype=torch.float64)
    seqs = planner.candidates()
    expected = brute_force_returns(z0, seqs, toy_step, toy_reward, zero_intrinsic, 0.9, 1.0)
    best = seqs[int(expected.argmax())]
    assert best.tolist() == [0, 2, 2]  # greedy would take the bonus (action 2) now; raising z first pays more
    plan = planner.plan(PlanRequest(z0, toy_step, zero_intrinsic, toy_reward, generator=torch.Generator().manual_seed(0)))
    assert plan.action == 0 and plan.sequence == [0, 2, 2]
    assert plan.info["best_score"] == pytest.approx(float(expected.max()))
    assert plan.score == pytest.approx(float(expected.max()))


def test_mpc_enumerates_all_sequences_lexicographically():
    seqs = MPCPlanner(horizon=3, n_actions=3).candidates()
    assert seqs.tolist() == [list(s) for s in itertools.product(range(3), repeat=3)]


def test_mpc_samples_candidates_beyond_the_limit():
    planner = MPCPlanner(horizon=6, max_candidates=50, n_actions=3, sample_candidates=True)
    seqs = planner.candidates(torch.Generator().manual_seed(0))
    assert seqs.shape == (50, 6) and seqs.min() >= 0 and seqs.max() <= 2
    with pytest.raises(ValueError, match="sample_candidates"):  # sampling is asked for, never silent
        MPCPlanner(horizon=6, max_candidates=50, n_actions=3)


@pytest.mark.parametrize(("horizon", "max_candidates"), [(4, 81), (5, 40)])
def test_mpc_scores_match_brute_force_on_random_nets(horizon, max_candidates):
    torch.manual_seed(0)
    model = ResidualTransition(2, 3, dropout=0.5).double().eval()
    memory = torch.randn(20, 5, dtype=torch.float64)

    def step(z, a):
        return model(z, one_hot(a, 3).double())

    def reward(z, a):
        return torch.sin(z).sum(1) * (a.double() - 1)

    def intrinsic(z, a, z_next):
        y = torch.cat([z, one_hot(a, 3).double()], 1)
        return torch.cdist(y, memory).min(1).values + torch.cos(z_next).sum(1)

    planner = MPCPlanner(horizon=horizon, gamma=0.8, eta=0.7, max_candidates=max_candidates, sample_candidates=True)
    z0 = torch.randn(2, dtype=torch.float64)
    seqs = planner.candidates(torch.Generator().manual_seed(1))
    with torch.no_grad():
        expected = brute_force_returns(z0, seqs, step, reward, intrinsic, 0.8, 0.7)
        torch.testing.assert_close(planner.scores(z0, seqs, step, reward, intrinsic), expected)


def held_brute_force_returns(z0, seqs, step, reward, intrinsic, gamma, eta, hold):
    """Each action held ``hold`` steps; reward on the state before the held action, intrinsic on its whole edge."""
    out = []
    for seq in seqs.tolist():
        z, total = z0.unsqueeze(0), 0.0
        for i, a in enumerate(seq):
            act = torch.tensor([a])
            z_next = z
            for _ in range(hold):
                z_next = step(z_next, act)
            total += gamma**i * float(reward(z, act) + eta * intrinsic(z, act, z_next))
            z = z_next
        out.append(total)
    return torch.tensor(out, dtype=torch.float64)


def test_mpc_held_actions_match_brute_force_and_expand_the_plan():
    torch.manual_seed(0)
    model = ResidualTransition(2, 3, dropout=0.0).double().eval()

    def step(z, a):
        return model(z, one_hot(a, 3).double())

    def intrinsic(z, a, z_next):
        return torch.cos(z_next).sum(1) - 0.3 * (z_next - z).square().sum(1)

    planner = MPCPlanner(horizon=3, gamma=0.8, eta=0.7, temperature=0.0, hold=3, commit=2)
    z0 = torch.randn(2, dtype=torch.float64)
    seqs = planner.candidates()
    assert seqs.shape == (27, 3)  # A^H candidates whatever the hold
    with torch.no_grad():
        expected = held_brute_force_returns(z0, seqs, step, toy_reward, intrinsic, 0.8, 0.7, 3)
        torch.testing.assert_close(planner.scores(z0, seqs, step, toy_reward, intrinsic), expected)
        one_step = held_brute_force_returns(z0, seqs, step, toy_reward, intrinsic, 0.8, 0.7, 1)
    assert not torch.allclose(expected, one_step)  # holding changes what is scored
    plan = planner.plan(PlanRequest(z0, step, intrinsic, toy_reward))
    best = seqs[int(expected.argmax())].tolist()
    assert plan.sequence == [a for a in best for _ in range(3)]  # 9 env actions, each planned action held 3 steps
    assert planner.commit == 6  # commit counts held actions: 2 of them, 6 env actions
    with pytest.raises(ValueError, match=r"planner\.hold"):
        MPCPlanner(horizon=3, hold=0)


def test_mpc_scores_rewards_before_stepping():
    def poisoned_step(z, a):
        return torch.full_like(z, float("nan"))

    planner = MPCPlanner(horizon=1, temperature=0.0)
    z0 = torch.tensor([2.0], dtype=torch.float64)
    scores = planner.scores(z0, planner.candidates(), poisoned_step, toy_reward, zero_intrinsic)
    assert scores.tolist() == [2.0, 2.0, 4.5]  # exact: sums of binary fractions (IEEE 754, any CPU)


def first_action_counts(planner, z0, reward, draws):
    gen = torch.Generator().manual_seed(123)
    counts = torch.zeros(3)
    for _ in range(draws):
        counts[planner.plan(PlanRequest(z0, toy_step, zero_intrinsic, reward, generator=gen)).action] += 1
    return counts


def chi_square(counts, probs):
    expected = probs * counts.sum()
    return float(((counts - expected) ** 2 / expected).sum())


def test_mpc_high_temperature_is_near_uniform_over_first_actions():
    planner = MPCPlanner(horizon=3, temperature=1e6)
    counts = first_action_counts(planner, torch.tensor([0.5], dtype=torch.float64), toy_reward, 3000)
    assert chi_square(counts, torch.full((3,), 1 / 3)) < 13.8  # df = 2, p = 0.001


def test_mpc_samples_from_the_softmax():
    def log_weights(z, a):
        return torch.log(a.double() + 1)  # exp(G / 1) ∝ 1, 2, 3

    planner = MPCPlanner(horizon=1, temperature=1.0)
    counts = first_action_counts(planner, torch.tensor([0.0], dtype=torch.float64), log_weights, 3000)
    assert chi_square(counts, torch.tensor([1 / 6, 2 / 6, 3 / 6])) < 13.8
    info = planner.plan(PlanRequest(torch.zeros(1), toy_step, zero_intrinsic, log_weights,
                                    generator=torch.Generator().manual_seed(0))).info  # fmt: skip
    probs = torch.tensor([1 / 6, 2 / 6, 3 / 6])
    assert info["entropy"] == pytest.approx(float(-(probs * probs.log()).sum()), rel=1e-5)


# ----------------------------------------------------------------------------- Q-tree
def brute_force_tree(z0, step, novelty, q, depth, gamma, n_actions=3):
    """Recursive V(a0) = n(z1) + γ W(z1, depth - 1), W(z, 0) = max Q(z), W(z, r) = max_a [n(T(z, a)) + γ W(T(z, a), r - 1)]."""

    def child(z, a):
        return step(z.unsqueeze(0), torch.tensor([a]))[0]

    def w(z, remaining):
        if remaining == 0:
            return float(q(z.unsqueeze(0)).max())
        return max(float(novelty(child(z, a).unsqueeze(0))) + gamma * w(child(z, a), remaining - 1) for a in range(n_actions))

    return torch.tensor(
        [float(novelty(child(z0, a).unsqueeze(0))) + gamma * w(child(z0, a), depth - 1) for a in range(n_actions)],
        dtype=z0.dtype,
    )


def on_reached_state(novelty):
    """NSRS's edge reward: the novelty of the state reached."""
    return lambda z, a, z_next: novelty(z_next)


def released_nsrs_values(z0, step, novelty, q, depth, gamma, n_actions=3):
    """NSRS's released ordering: levels built action-major (row j·n + i) but backed up as if state-major."""
    z, levels = z0.unsqueeze(0), []
    for _ in range(depth):
        n = z.shape[0]
        z = step(z.repeat(n_actions, 1), torch.arange(n_actions).repeat_interleave(n))
        levels.append(novelty(z))
    value = levels[-1] + gamma * q(z).max(1).values
    for level in reversed(levels[:-1]):
        value = level + gamma * value.reshape(-1, n_actions).max(1).values
    return value


@pytest.mark.parametrize("depth", [1, 2, 3])
def test_qtree_equals_recursive_brute_force(depth):
    torch.manual_seed(depth)
    model = ResidualTransition(3, 3, dropout=0.1).double().eval()
    qnet = QNetwork(3, 3).double()
    memory = torch.randn(15, 3, dtype=torch.float64)

    def step(z, a):
        return model(z, one_hot(a, 3).double())

    def novelty(z):
        return torch.cdist(z, memory).square().topk(3, largest=False).values.mean(1)

    z0 = torch.randn(3, dtype=torch.float64)
    with torch.no_grad():
        planner = QTreePlanner(horizon=depth, gamma=0.8)
        expected = brute_force_tree(z0, step, novelty, qnet, depth, 0.8)
        edge = on_reached_state(novelty)
        torch.testing.assert_close(planner.values(z0, step, edge, qnet), expected)
        assert planner.plan(PlanRequest(z0, step, edge, q_fn=qnet)).action == int(expected.argmax())


def path_step(z, a):
    """z' = 10 z + a: from z0 = 0 the level-2 latent 10·a0 + a1 names its path."""
    return 10 * z + a.unsqueeze(1).to(z.dtype)


def path_novelty(z):
    return 5.0 * (z[:, 0] == 20).to(z.dtype)  # only the path (a0, a1) = (2, 0) is novel


def zero_q(z):
    return torch.zeros(z.shape[0], 3, dtype=z.dtype)


def test_qtree_fixes_the_released_subtree_mixup():
    z0 = torch.zeros(1, dtype=torch.float64)
    planner = QTreePlanner(horizon=2, gamma=0.8)
    values = planner.values(z0, path_step, on_reached_state(path_novelty), zero_q)
    assert values.tolist() == pytest.approx([0.0, 0.0, 4.0])
    torch.testing.assert_close(values, brute_force_tree(z0, path_step, path_novelty, zero_q, 2, 0.8))
    assert planner.plan(PlanRequest(z0, path_step, on_reached_state(path_novelty), q_fn=zero_q)).action == 2
    released = released_nsrs_values(z0, path_step, path_novelty, zero_q, 2, 0.8)
    assert int(released.argmax()) == 0  # the released ordering credits the novel leaf to a0 = 0


def test_qtree_levels_are_state_major_and_ties_go_low():
    planner = QTreePlanner(horizon=2, n_actions=3)
    children = planner.expand(torch.tensor([[0.0], [1.0]]), path_step)
    assert children[:, 0].tolist() == [0, 1, 2, 10, 11, 12]
    plan = planner.plan(PlanRequest(torch.zeros(1), path_step, lambda z, a, zn: torch.zeros(zn.shape[0]), q_fn=zero_q))
    assert plan.action == 0 and plan.info["value_gap"] == 0.0 and plan.sequence == [0]


def test_qtree_edge_reward_sees_parent_action_and_child() -> None:
    """A state-action edge reward (novelty of [z, a]) is applied to the pair taken, not to the state reached."""
    planner = QTreePlanner(horizon=1, gamma=0.5)
    seen = []

    def edge(z, a, z_next):
        seen.append((z.clone(), a.clone(), z_next.clone()))
        return a.to(z.dtype) * 10.0

    def step(z, a):
        return z + a.unsqueeze(1).to(z.dtype)

    values = planner.values(torch.tensor([1.0]), step, edge, lambda z: torch.zeros(z.shape[0], 3))
    torch.testing.assert_close(values, torch.tensor([0.0, 10.0, 20.0]))
    z, a, z_next = seen[0]
    assert torch.equal(z, torch.ones(3, 1)) and torch.equal(a, torch.arange(3))
    assert torch.equal(z_next[:, 0], torch.tensor([1.0, 2.0, 3.0]))  # exact: integer sums


def test_both_planners_are_planners_and_declare_what_they_need():
    """One ``plan(PlanRequest) -> Plan`` signature; a Q-function is declared (``needs_q``), and refused when missing."""
    mpc, tree = MPCPlanner(horizon=2), QTreePlanner(horizon=2)
    assert isinstance(mpc, Planner) and isinstance(tree, Planner)
    assert (mpc.needs_q, tree.needs_q) == (False, True) and mpc.horizon == tree.horizon == 2
    assert (mpc.step_discount, tree.step_discount) == (pytest.approx(0.9), pytest.approx(0.8))
    with pytest.raises(ValueError, match="needs a Q-function"):
        tree.plan(PlanRequest(torch.zeros(1), path_step, lambda z, a, zn: torch.zeros(zn.shape[0])))
    named = {"a": lambda z, a, zn: path_novelty(zn), "b": lambda z, a, zn: torch.zeros(zn.shape[0], dtype=zn.dtype)}

    def terms(z, a, zn):
        return {k: f(z, a, zn) for k, f in named.items()}

    request = PlanRequest(torch.zeros(1, dtype=torch.float64), path_step, terms, q_fn=zero_q)
    assert tree.plan(request).action == 2  # named terms are summed, as one tensor would be


def test_mpc_terminal_value_adds_the_leaves_q_by_brute_force_and_changes_the_choice():
    """``value_coef`` κ: Ĝ + κ γ^H max_a Q(ŝ_H, a) at the held rollout's leaf, on random nets (tolerance: float64 sums
    in another order); a Q that pays for a high leaf turns the plan from the reward's best to the leaf's."""
    torch.manual_seed(0)
    model = ResidualTransition(2, 3, dropout=0.0).double().eval()
    q_net = QNetwork(2, 3).double().eval()

    def step(z, a):
        return model(z, one_hot(a, 3).double())

    def intrinsic(z, a, z_next):
        return torch.cos(z_next).sum(1)

    planner = MPCPlanner(horizon=3, gamma=0.8, eta=0.7, temperature=0.0, hold=2, value_coef=0.5)
    assert planner.needs_q and planner.step_discount == pytest.approx(0.8**0.5)
    z0 = torch.randn(2, dtype=torch.float64)
    seqs = planner.candidates()
    with torch.no_grad():
        base = held_brute_force_returns(z0, seqs, step, toy_reward, intrinsic, 0.8, 0.7, 2)
        leaves = []
        for seq in seqs.tolist():
            z = z0.unsqueeze(0)
            for a in seq:
                for _ in range(2):
                    z = step(z, torch.tensor([a]))
            leaves.append(float(q_net(z).max()))
        expected = base + 0.5 * 0.8**3 * torch.tensor(leaves, dtype=torch.float64)
        terms = planner.score_terms(z0, seqs, step, toy_reward, intrinsic, q_fn=q_net)
        torch.testing.assert_close(terms["value"], expected - base)
        torch.testing.assert_close(planner.scores(z0, seqs, step, toy_reward, intrinsic, q_fn=q_net), expected)
    with pytest.raises(ValueError, match="needs a Q-function"):
        planner.scores(z0, seqs, step, toy_reward, intrinsic)
    # on the toy model action 0 raises the latent; a Q paying 100 per unit of leaf latent outweighs the bonus path
    toy = MPCPlanner(horizon=3, gamma=0.9, temperature=0.0, value_coef=1.0)
    request = PlanRequest(torch.tensor([0.5], dtype=torch.float64), toy_step, zero_intrinsic, toy_reward)
    assert MPCPlanner(horizon=3, gamma=0.9, temperature=0.0).plan(request).sequence == [0, 2, 2]
    request.q_fn = lambda z: 100.0 * z.repeat(1, 3)
    plan = toy.plan(request)
    assert plan.sequence == [0, 0, 0] and "spread/value" in plan.info
    assert not MPCPlanner(horizon=3).needs_q
    with pytest.raises(ValueError, match=r"planner\.value_coef"):
        MPCPlanner(horizon=3, value_coef=-1.0)
