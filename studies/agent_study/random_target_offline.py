"""Offline (issue 11): can a head g(s) carry a frozen random encoder's novelty geometry r = R(o) through the trained
latent and the learned model?

    python -m studies.agent_study.random_target_offline RUN_DIR

RUN_DIR: a run directory with its ``checkpoint.pt``. Encodes the run's replay with its final encoder (s) and with a
fresh random ConvEncoder on blurred frames (r, seed 0), standardised on the first 30 % of the run; fits g: s -> r (tanh
MLP 64-64, 4000 Adam steps) on that 30 %; on the later 70 % prints g's R², the Spearman correlation of KDE novelties
(bandwidth 2 x the median nearest-neighbour distance of the memory = the first 30 %) of true r against g(s) and against
s's own novelty, and the same for latents imagined k = 4, 8, 20 steps ahead by the run's learned model under the
actions taken (``results/agent_study/random_target/offline/output.txt``).
"""

from __future__ import annotations

import argparse

import numpy as np
import torch
from scipy import stats

from curiosity.nets.encoders import ConvEncoder, tanh_mlp
from curiosity.runtime.restore import restore_run


def kde_nov(mem: torch.Tensor, q: torch.Tensor) -> torch.Tensor:
    d = torch.cdist(mem, mem)
    d.fill_diagonal_(float("inf"))
    h = 2 * d.min(1).values.median()
    dq = torch.cdist(q, mem)
    return -(torch.logsumexp(-dq.square() / (2 * h * h), 1) - np.log(len(mem)))


def report(run_dir: str) -> None:
    torch.set_num_threads(1)
    run = restore_run(run_dir)
    model = run.agent.model
    with model.evaluating(), torch.no_grad():
        obs = run.agent.replay.all_obs()
        z = torch.cat([model.encode(obs[i : i + 256]) for i in range(0, len(obs), 256)])
        act = torch.as_tensor(run.agent.replay.all_actions()).long()
        torch.manual_seed(0)
        enc = ConvEncoder(in_channels=obs.shape[1], latent_dim=4, blur_sigma=4.0).eval()
        r = torch.cat([enc(obs[i : i + 256]) for i in range(0, len(obs), 256)])
    n = len(z)
    split = int(0.3 * n)  # fit on the first 30 % (a run's early memory), test on later states
    zs = (z - z[:split].mean(0)) / z[:split].std(0)
    rs = (r - r[:split].mean(0)) / r[:split].std(0)
    print(f"transitions {n}, fit on first {split}")

    torch.manual_seed(0)
    g = tanh_mlp([zs.shape[1], 64, 64, rs.shape[1]])
    opt = torch.optim.Adam(g.parameters(), 1e-3)
    for _ in range(4000):
        i = torch.randint(0, split, (64,))
        loss = (g(zs[i]) - rs[i]).square().sum(-1).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
    with torch.no_grad():
        test = torch.arange(split, n)
        gz = g(zs)
        r2 = 1 - (gz[test] - rs[test]).square().sum(0) / (rs[test] - rs[test].mean(0)).square().sum(0)
        print("R2 of g(z) -> r on later states per coord", [round(float(v), 2) for v in r2])
        q = test[::5]
        nov_r = kde_nov(rs[:split], rs[q])
        nov_g = kde_nov(rs[:split], gz[q])
        nov_z = kde_nov(zs[:split], zs[q])
        print(f"Spearman with novelty on r: g(z) vs r-memory {stats.spearmanr(nov_r, nov_g)[0]:.2f}; "
              f"z on z-memory {stats.spearmanr(nov_r, nov_z)[0]:.2f}")  # fmt: skip
        # imagined: learned model rolled k steps with the actions taken, from z (raw), then standardise and g
        for k in (4, 8, 20):
            starts = test[test < n - k][::5]
            zk = z[starts]
            for j in range(k):
                zk = model.next(zk, act[starts + j])
            zk_s = (zk - z[:split].mean(0)) / z[:split].std(0)
            true_r = rs[starts + k]
            nov_true = kde_nov(rs[:split], true_r)
            nov_img_g = kde_nov(rs[:split], g(zk_s))
            nov_img_z = kde_nov(zs[:split], zk_s)
            nov_true_z = kde_nov(zs[:split], zs[starts + k])
            print(f"k={k}: Spearman(true r-novelty, imagined g-novelty) {stats.spearmanr(nov_true, nov_img_g)[0]:.2f}; "
                  f"(true z-novelty, imagined z-novelty) {stats.spearmanr(nov_true_z, nov_img_z)[0]:.2f}; "
                  f"(true r-novelty, true z-novelty) {stats.spearmanr(nov_true, nov_true_z)[0]:.2f}")  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.random_target_offline",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("run_dir", help="a run directory with its checkpoint.pt")
    report(parser.parse_args(argv).run_dir)


if __name__ == "__main__":
    main()
