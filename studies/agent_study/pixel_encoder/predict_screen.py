"""Offline prototype (not part of the package): how well does the configured transition model predict its own latent?

    python -m studies.agent_study.pixel_encoder.predict_screen ITERS OUT.json [OVERRIDES...]

(config overrides as for runners.train). For model and data seeds 0 and 1 the paper agent's world model is trained
ITERS iterations on 1500 random-policy transitions (from the state of its first training call: a frozen encoder
calibrated on them), then rolled open-loop over 400 held-out random-policy steps. Results:
``results/agent_study/pixel_encoder/README.md``, "Offline: can the learned model follow each latent".
Reports, at k = 1, 3, 5 open-loop steps: RMSE of the model's z_{t+k}, RMSE of persistence (z_t), and
R2_disp = 1 - MSE_model / MSE_persist (the share of the latent's motion the model predicts), in latents standardised
by the held-out set's per-dimension std; and the share of variance of z along which the action matters:
action_gap = RMS over states of (model's 3-step endpoint spread across the 27 sequences) / persistence RMSE(3).
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import torch

from curiosity.runtime.preflight import checked_config
from studies.representation import agent_with_data, random_policy, rollout


def screen(iters: int, overrides: Sequence[str]) -> dict[str, Any]:
    """The rows of the module docstring for seeds 0 and 1 (each printed as it is done)."""
    cfg = checked_config([*overrides, "threads=1"])[1]
    torch.set_num_threads(1)
    res: dict[str, Any] = {"overrides": list(overrides), "iters": iters, "seeds": []}
    for seed in (0, 1):
        torch.manual_seed(seed)
        n_act = int(cfg.env.n_actions)
        train = rollout(cfg, 1500, random_policy(n_act), 1 + 10 * seed)
        held = rollout(cfg, 400, random_policy(n_act), 2 + 10 * seed)
        agent = agent_with_data(cfg, train, first_call=True)
        agent.model.train()
        t0 = time.time()
        for _ in range(iters):
            agent._iteration()
        secs = time.time() - t0
        with agent.model.evaluating():
            obs = torch.as_tensor(np.concatenate([held.obs[:1], held.next_obs]), dtype=torch.float32)
            z = torch.cat([agent.model.encode(obs[i : i + 256]) for i in range(0, len(obs), 256)])
            sd = z.std(0).clamp_min(1e-8)
            acts = torch.as_tensor(held.actions, dtype=torch.long)
            row: dict[str, Any] = {"seed": seed, "train_seconds": secs}
            T = len(acts)
            for k in (1, 3, 5):
                idx = torch.arange(0, T - k)
                zh = z[idx]
                for j in range(k):
                    zh = agent.model.next(zh, acts[idx + j])
                true = z[idx + k]
                mse_m = (((zh - true) / sd) ** 2).sum(1).mean().item()
                mse_p = (((z[idx] - true) / sd) ** 2).sum(1).mean().item()
                row[f"rmse_model_{k}"] = mse_m**0.5
                row[f"rmse_persist_{k}"] = mse_p**0.5
                row[f"r2_disp_{k}"] = 1 - mse_m / mse_p
            seqs = torch.as_tensor(list(itertools.product(range(n_act), repeat=3)), dtype=torch.long)
            starts = z[torch.arange(0, T - 3, 8)]
            ends = starts.repeat_interleave(len(seqs), 0)
            for j in range(3):
                ends = agent.model.next(ends, seqs[:, j].repeat(len(starts)))
            ends = (ends / sd).view(len(starts), len(seqs), -1)
            spread = ends.var(1).sum(-1).mean().sqrt().item()
            row["action_spread_3"] = spread
            row["action_gap_3"] = spread / row["rmse_persist_3"]
        res["seeds"].append(row)
        print(json.dumps(row), flush=True)
    return res


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.pixel_encoder.predict_screen",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("iters", type=int, help="world-model iterations (2000 in the results)")
    parser.add_argument("out", help="JSON file of the rows")
    parser.add_argument("overrides", nargs="*", help="config overrides, as for runners.train")
    args = parser.parse_args(argv)
    res = screen(args.iters, args.overrides)
    with open(args.out, "w") as f:
        json.dump(res, f, indent=1)


if __name__ == "__main__":
    main()
