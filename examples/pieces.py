"""The three pieces of ``curiosity`` on small random tensors, outside any agent: ``python examples/pieces.py``.

1. Information (``curiosity.info``): matrix-based Rényi entropy and mutual information of a batch of latents, and the
   Gaussian-potential dispersion loss.
2. Novelty (``curiosity.novelty``): KDE log-density, the KDE novelty reward with a random-phase baseline, and kNN
   distances of queries against a memory of embeddings.
3. Planning (``curiosity.planning``): the MPC planner choosing an action sequence in a toy latent model, scored by
   KDE novelty of the latents it would reach.

Takes a few seconds on a CPU; docs/pieces.md explains each call. tests/test_examples.py runs it.
"""

from __future__ import annotations

import torch

from curiosity.info import gaussian_potential, renyi_entropy, renyi_mutual_information
from curiosity.novelty import KDENoveltyReward, kde_log_density, knn_distance
from curiosity.planning import MPCPlanner, PlanRequest


def information(g: torch.Generator) -> None:
    """Latents z, one-hot actions a and next latents z' that depend on both: I(z'; [z, a]) > I(z'; shuffled pairs)."""
    n, d, n_actions = 64, 4, 3
    z = torch.randn(n, d, generator=g, dtype=torch.float64)
    a = torch.nn.functional.one_hot(torch.randint(n_actions, (n,), generator=g), n_actions).to(torch.float64)
    effect = torch.randn(n_actions, d, generator=g, dtype=torch.float64)
    z_next = z + a @ effect + 0.05 * torch.randn(n, d, generator=g, dtype=torch.float64)
    y = torch.cat([z, a], dim=1)  # the state-action pair [s, a] of the paper's Eq. (5)

    h = renyi_entropy(z_next, sigma=2.0, alpha=0.99)  # Gaussian kernel exp(-d²/(2σ²)), bits (base 2)
    mi = renyi_mutual_information(z_next, y, sigma=2.0, alpha=0.99)
    shuffled = renyi_mutual_information(z_next, y[torch.randperm(n, generator=g)], sigma=2.0, alpha=0.99)
    spread = gaussian_potential(z_next, t=2.0)  # natural log, <= 0; lower is more spread out
    collapsed = gaussian_potential(0.01 * z_next, t=2.0)
    print(f"info: H_0.99(z') = {h:.3f} bits (at most log2 {n} = 6)")
    print(f"info: I_0.99(z'; [z, a]) = {mi:.3f} bits paired, {shuffled:.3f} bits with the pairs shuffled")
    print(f"info: L_unif(z') = {spread:.3f}, of z' shrunk 100x = {collapsed:.3f}")
    assert mi > shuffled and spread < collapsed


def novelty(g: torch.Generator) -> torch.Tensor:
    """A memory around the origin; a query inside it is less novel than one outside it. Returns the memory."""
    memory = torch.randn(400, 2, generator=g, dtype=torch.float64)
    random_phase = torch.randn(50, 2, generator=g, dtype=torch.float64)  # what a random policy met first
    queries = torch.tensor([[0.0, 0.0], [4.0, 0.0]], dtype=torch.float64)  # inside, outside

    log_rho = kde_log_density(queries, memory, bandwidth=0.5)
    reward = KDENoveltyReward(bandwidth=0.5, baseline="scalar")  # r = log ρ̄0 − log ρ(y)
    reward.set_reference(random_phase)
    reward.fit(memory)
    r = reward(queries)
    knn = knn_distance(queries, memory, k=5)
    print(f"novelty: log rho inside / outside = {log_rho[0]:.3f} / {log_rho[1]:.3f}")
    print(f"novelty: KDE reward inside / outside = {r[0]:.3f} / {r[1]:.3f}")
    print(f"novelty: mean distance to 5 nearest inside / outside = {knn[0]:.3f} / {knn[1]:.3f}")
    assert r[0] < r[1] and knn[0] < knn[1]
    return memory


def planning(memory: torch.Tensor) -> None:
    """A toy latent model: action 0 moves left, 1 stays, 2 moves right; the memory lies left of the start, so the
    novelty-seeking plan moves right at every step."""
    moves = torch.tensor([[-0.5, 0.0], [0.0, 0.0], [0.5, 0.0]], dtype=torch.float64)
    seen = memory - torch.tensor([2.0, 0.0], dtype=torch.float64)  # the visited region: centred at x = -2

    def step_fn(z: torch.Tensor, a: torch.Tensor) -> torch.Tensor:  # T(z (M, d), a (M,)) -> (M, d)
        return z + moves[a]

    def intrinsic(z: torch.Tensor, a: torch.Tensor, z_next: torch.Tensor) -> torch.Tensor:  # r_int of each edge, (M,)
        return -kde_log_density(z_next, seen, bandwidth=0.5)  # novelty of the state reached

    planner = MPCPlanner(horizon=3, gamma=0.9, temperature=0.0, n_actions=3, max_candidates=27)  # τ = 0: argmax
    plan = planner.plan(PlanRequest(z0=torch.zeros(2, dtype=torch.float64), step_fn=step_fn, intrinsic=intrinsic))
    print(f"planner: {int(plan.info['n_candidates'])} candidate sequences, chosen {plan.sequence}, score {plan.score:.3f}")
    assert plan.sequence == [2, 2, 2]


def main() -> None:
    g = torch.Generator().manual_seed(0)
    information(g)
    memory = novelty(g)
    planning(memory)
    print("ok: all three pieces ran")


if __name__ == "__main__":
    main()
