"""Open-loop latent prediction error of transition models refitted on a run's frozen latents (issue 11, offline).

    python -m studies.agent_study.hold.refit_order RUN_DIR

RUN_DIR: a run directory with its ``checkpoint.pt``. Encodes every replay observation with the run's encoder (eval
mode), standardises the latents per coordinate, fits fresh residual transition models on the first 80 % of the run
(3000 Adam steps, lr 1e-3, batch 64, open-loop n-step loss) and prints the RMS error of open-loop predictions 1, 2, 4,
8, 12 and 20 steps ahead on the last 20 % (test) and on the first 80 % (train), beside persistence (z stays) and
constant latent velocity. Orders: 1 is T(z, a) as the agent's; 2 is T(z, z − z_prev, a)
(``results/agent_study/hold/offline_refit/``).
"""

from __future__ import annotations

import argparse

import torch
from torch import nn

from curiosity.nets.encoders import tanh_mlp
from curiosity.nets.onehot import one_hot
from curiosity.runtime.restore import restore_run

DEPTHS = (1, 2, 4, 8, 12, 20)


class Transition(nn.Module):
    def __init__(self, d: int, n_actions: int, order: int, hidden: int) -> None:
        super().__init__()
        self.order, self.n_actions = order, n_actions
        self.f = tanh_mlp([d * order + n_actions, hidden, 30, 30, hidden, d], dropout=0.0)

    def forward(self, z: torch.Tensor, z_prev: torch.Tensor, a: torch.Tensor) -> torch.Tensor:
        parts = [z] + ([z - z_prev] if self.order == 2 else [])
        return z + self.f(torch.cat([*parts, one_hot(a, self.n_actions).float()], -1))


def rollout(net: Transition, z: torch.Tensor, z_prev: torch.Tensor, acts: torch.Tensor) -> torch.Tensor:
    out = []
    for i in range(acts.shape[1]):
        z, z_prev = net(z, z_prev, acts[:, i]), z
        out.append(z)
    return torch.stack(out, 1)


def frozen_latents(run_dir: str) -> tuple[torch.Tensor, torch.Tensor, int]:
    """A run's replay encoded by its final encoder (eval mode), standardised per coordinate: latents (N, d), the
    actions (N,) and the number of actions."""
    run = restore_run(run_dir)
    model = run.agent.model
    with model.evaluating():
        obs = run.agent.replay.all_obs()
        z_all = torch.cat([model.encode(obs[i : i + 256]) for i in range(0, len(obs), 256)])
    act = torch.as_tensor(run.agent.replay.all_actions()).long()
    return (z_all - z_all.mean(0)) / z_all.std(0), act, model.n_actions


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.hold.refit_order",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("run_dir", help="a run directory with its checkpoint.pt")
    run_dir = parser.parse_args(argv).run_dir
    torch.set_num_threads(1)
    z_all, act, n_actions = frozen_latents(run_dir)
    n_total, split, horizon = len(z_all), int(0.8 * len(z_all)), max(DEPTHS)

    def fit(order: int, hidden: int, n: int) -> Transition:
        torch.manual_seed(0)
        net = Transition(z_all.shape[1], n_actions, order, hidden)
        opt = torch.optim.Adam(net.parameters(), 1e-3)
        g = torch.Generator().manual_seed(0)
        for _ in range(3000):
            s = torch.randint(1, split - n - 1, (64,), generator=g)
            idx = s[:, None] + torch.arange(n + 1)
            loss = (rollout(net, z_all[s], z_all[s - 1], act[idx[:, :n]]) - z_all[idx[:, 1:]]).square().sum(-1).mean()
            opt.zero_grad()
            loss.backward()
            opt.step()
        return net

    def error(pred: torch.Tensor, starts: torch.Tensor) -> str:
        truth = z_all[starts[:, None] + torch.arange(1, horizon + 1)]
        e = (pred - truth).square().sum(-1).mean(0).sqrt()
        return " ".join(f"{k}:{e[k - 1]:.2f}" for k in DEPTHS)

    test, train = torch.arange(split + 1, n_total - horizon - 1), torch.arange(1, split - horizon - 1)
    print(f"transitions {n_total}, latent RMS {z_all.square().sum(-1).mean().sqrt():.2f}; RMS error at k steps ahead")
    steps = torch.arange(1, horizon + 1)[None, :, None]
    print("persistence (test)      ", error(z_all[test][:, None].expand(-1, horizon, -1), test))
    print("constant velocity (test)", error(z_all[test][:, None] + (z_all[test] - z_all[test - 1])[:, None] * steps, test))
    for order, hidden, n in ((1, 10, 2), (1, 64, 2), (1, 64, 8), (2, 64, 2), (2, 64, 8)):
        net = fit(order, hidden, n)
        with torch.no_grad():
            for name, starts in (("test", test), ("train", train)):
                pred = rollout(net, z_all[starts], z_all[starts - 1], act[starts[:, None] + torch.arange(horizon)])
                print(f"order {order} width {hidden} n {n} ({name})".ljust(24), error(pred, starts))


if __name__ == "__main__":
    main()
