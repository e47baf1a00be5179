"""Open-loop latent prediction error: the agent's iterated one-step transition vs a direct k-step ("chunk") model.

    python -m studies.agent_study.hold.chunk_model RUN_DIR

RUN_DIR: a run directory with ``checkpoint.pt``. As ``studies.agent_study.hold.refit_order``: the run's frozen,
standardised latents; models fitted on the first 80 % of the run (3000 Adam steps, lr 1e-3, batch 64), RMS error of
open-loop predictions on the last 20 % (test) and the first 80 % (train). The chunk model T_k(z, a_t..a_{t+k-1}) ->
z_{t+k} (residual, the k actions one-hot; k = 1 is the agent's form) is rolled 20/k times for 20 steps; its loss is
open-loop over n chunks (n*k env steps). Each row is the mean over fit seeds 0, 1, 2
(``results/agent_study/hold/offline_refit/``).
"""

from __future__ import annotations

import argparse

import torch
from torch import nn

from curiosity.nets.encoders import tanh_mlp
from curiosity.nets.onehot import one_hot
from studies.agent_study.hold.refit_order import frozen_latents

HORIZON = 20


class Chunk(nn.Module):
    def __init__(self, d: int, n_actions: int, k: int, hidden: int) -> None:
        super().__init__()
        self.k, self.n_actions = k, n_actions
        self.f = tanh_mlp([d + k * n_actions, hidden, 30, 30, hidden, d], dropout=0.0)

    def forward(self, z: torch.Tensor, acts: torch.Tensor) -> torch.Tensor:  # acts (B, k)
        return z + self.f(torch.cat([z, one_hot(acts, self.n_actions).float().flatten(1)], -1))


def rollout(net: Chunk, z: torch.Tensor, acts: torch.Tensor) -> torch.Tensor:
    """Predicted latents after each chunk: (B, n_chunks, d) for acts (B, n_chunks * k)."""
    out = []
    for i in range(acts.shape[1] // net.k):
        z = net(z, acts[:, i * net.k : (i + 1) * net.k])
        out.append(z)
    return torch.stack(out, 1)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.hold.chunk_model",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("run_dir", help="a run directory with its checkpoint.pt")
    run_dir = parser.parse_args(argv).run_dir
    torch.set_num_threads(1)
    z_all, act, n_actions = frozen_latents(run_dir)
    n_total, split = len(z_all), int(0.8 * len(z_all))
    held = (act[1:] == act[:-1]).float().mean()
    print(f"transitions {n_total}, latent RMS {z_all.square().sum(-1).mean().sqrt():.2f}, P(a_t = a_t-1) {held:.2f}")

    def fit(k: int, n: int, hidden: int, seed: int) -> Chunk:
        torch.manual_seed(seed)
        net = Chunk(z_all.shape[1], n_actions, k, hidden)
        opt = torch.optim.Adam(net.parameters(), 1e-3)
        g = torch.Generator().manual_seed(seed)
        for _ in range(3000):
            s = torch.randint(0, split - n * k - 1, (64,), generator=g)
            idx = s[:, None] + torch.arange(n * k + 1)
            truth = z_all[idx[:, k::k]]
            loss = (rollout(net, z_all[s], act[idx[:, :-1]]) - truth).square().sum(-1).mean()
            opt.zero_grad()
            loss.backward()
            opt.step()
        return net

    test, train = torch.arange(split, n_total - HORIZON - 1), torch.arange(0, split - HORIZON - 1)
    depths = (4, 8, 12, 20)
    print("RMS error at k steps ahead (mean over fit seeds 0-2)")
    persist = {d: float((z_all[test + d] - z_all[test]).square().sum(-1).mean().sqrt()) for d in depths}
    print("persistence (test)".ljust(34), " ".join(f"{d}:{persist[d]:.2f}" for d in depths))
    for k, n, hidden in ((1, 2, 10), (1, 8, 10), (4, 2, 10), (4, 2, 64), (4, 5, 10)):
        errs: dict[str, list[torch.Tensor]] = {"test": [], "train": []}
        for seed in range(3):
            net = fit(k, n, hidden, seed)
            for name, starts in (("test", test), ("train", train)):
                with torch.no_grad():
                    pred = rollout(net, z_all[starts], act[starts[:, None] + torch.arange(HORIZON)])
                truth = z_all[starts[:, None] + torch.arange(k, HORIZON + 1, k)]
                errs[name].append((pred - truth).square().sum(-1).mean(0).sqrt())
        for name, e in errs.items():
            m = torch.stack(e).mean(0)
            print(f"chunk k={k} n={n} width {hidden} ({name})".ljust(34), " ".join(f"{d}:{m[d // k - 1]:.2f}" for d in depths))


if __name__ == "__main__":
    main()
