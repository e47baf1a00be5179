"""Offline screen (issue 11, a prototype, not an option): AUC (pumping vs random states) of KDE novelty on the
standardised latent z', on [z', dz] (dz = z' - z; each coordinate standardised by the training latents) and on dz
alone; kernel 2x and 8x the median nearest-neighbour distance. Uses ``studies.representation``'s data and agent.

    python -m studies.agent_study.pixel_encoder.motion_novelty MODEL_SEED DATA_SEED OUT.json

Measured after 0, 1000 and 2000 iterations (``results/agent_study/pixel_encoder/motion_novelty/``).
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence

import numpy as np
import torch
from omegaconf import DictConfig, OmegaConf

from curiosity.build import build
from studies import representation as R

ITERS = (0, 1000, 2000)


def score(cfg: DictConfig, bw: float, memory: np.ndarray, queries: np.ndarray, warmup: int) -> np.ndarray:
    mean, std = memory.mean(0), memory.std(0).clip(min=1e-8)
    mem = torch.as_tensor((memory - mean) / std, dtype=torch.float32)
    ec = OmegaConf.to_container(cfg.estimator, resolve=True)
    ec["bandwidth"] = bw  # type: ignore[index]
    est = build(OmegaConf.create(ec))
    est.fit(mem, mem[: max(2, min(warmup, len(mem)))])
    return est(torch.as_tensor((queries - mean) / std, dtype=torch.float32)).double().numpy()


def variants(z0: np.ndarray, z1: np.ndarray) -> dict[str, np.ndarray]:
    dz = z1 - z0
    return {"z": z1, "z+dz": np.concatenate([z1, dz], 1), "dz": dz}


def screen(seed: int, data_seed: int, iters: Sequence[int], out: str) -> None:
    cfg = R.study_config([f"seed={seed}", "threads=1"])
    torch.set_num_threads(1)
    torch.manual_seed(seed)
    data = R.probe_sets(cfg, 600, 300, data_seed)
    agent = R.agent_with_data(cfg, data.train)
    w = int(cfg.budget.warmup_steps)
    res: dict = {"seed": seed, "data_seed": data_seed, "estimator": OmegaConf.to_container(cfg.estimator), "rows": []}
    P = {k: getattr(data, k) for k in ("train", "random", "pumping")}
    for bw in (2.0, 8.0):  # the reference: the same estimator on the physical state
        nov = score(cfg, bw, P["train"].physical, np.concatenate([P["random"].physical, P["pumping"].physical]), w)
        res[f"auc_physical_bw{bw:g}"] = round(R.auc(nov[300:], nov[:300]), 3)
    done = 0
    for target in iters:
        agent.model.train()
        for _ in range(target - done):
            agent._iteration()
        done = target
        V = {k: variants(R._encode(agent, t.obs), R._encode(agent, t.next_obs)) for k, t in P.items()}
        row = {"iters": done}
        for v in V["train"]:
            for bw in (2.0, 8.0):
                nov = score(cfg, bw, V["train"][v], np.concatenate([V["random"][v], V["pumping"][v]]), w)
                row[f"{v}_bw{bw:g}"] = round(R.auc(nov[300:], nov[:300]), 3)
        res["rows"].append(row)
        print(row, flush=True)
    print({k: v for k, v in res.items() if k.startswith("auc")})
    with open(out, "w") as f:
        json.dump(res, f, indent=1, default=str)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.pixel_encoder.motion_novelty",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("model_seed", type=int, help="the config's seed (the world model's initialisation)")
    parser.add_argument("data_seed", type=int, help="env seed of the training data (probe sets: +1, +2)")
    parser.add_argument("out", help="JSON file of the AUCs")
    args = parser.parse_args(argv)
    screen(args.model_seed, args.data_seed, ITERS, args.out)


if __name__ == "__main__":
    main()
