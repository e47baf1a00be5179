"""Does an encoder's latent geometry follow the physical state? ``python -m studies.encoder_geometry [OVERRIDES...]``.

Latent novelty can only point to new physical states if latent distances grow with physical ones. This check builds
the encoder the overrides configure (as ``runners.train`` would, untrained: its initialisation under ``--seeds``),
encodes ``--states`` observations of the run's env in physical states drawn over the env's coverage box (pose
uniform, each velocity uniform times u², u uniform: most states slow, some fast; then four random actions, so a
frame stack holds a real motion), and reports the Spearman correlation between pairwise distances of the
standardised latents and of standardised physical features:

- ``rho_all``: the env's state vector (Acrobot: cos θ1, sin θ1, cos θ2, sin θ2, θ̇1, θ̇2; MountainCar: x, ẋ);
- ``rho_pose``: its pose part (every entry but the last P/2, P the physical state's length);
- ``rho_velocity``: its velocity part (the last P/2 entries: the physical velocities);
- ``knn``: the mean overlap of each state's 10 nearest neighbours in the latent and in the state vector;
- ``rho_velocity_white``: ``rho_velocity`` with the latents whitened by their own covariance instead of standardised
  per coordinate, so that a direction of small variance weighs as much as the largest;
- ``r2_velocity_linear``: the share of the velocities' variance a least-squares linear map of the latent (with an
  intercept) explains, fitted on the first half of the states and scored on the second half (1: the velocity is a
  linear read-out of the latent; 0 or below: none of it is).

With ``--train-iters N`` each encoder is first trained with the paper agent's world model (the config's losses and
optimiser) for N gradient iterations on 600 random-policy transitions (data seed ``--data-seed`` + 1), as
``studies.representation`` trains it: what the objective makes of the geometry, without a run.

With ``--run RUN_DIR`` the encoder is instead the run's trained one, restored from its checkpoint (its own config;
overrides and ``--seeds`` are not used): what training made of the geometry.

Nothing is trained and nothing is written unless ``--json FILE`` is given. The numbers are a diagnostic of the
encoder's geometry, to compare configurations at the same seeds.

A study that measures more (``studies.agent_study.pixel_encoder.whitened``) passes its own metrics function to
:func:`main` (``geometry_of``, one row of metrics from the latents and state vectors); one that reports on the offline
training (``studies.agent_study.pixel_encoder.arrow_of_time``) passes ``after_training``, called with each trained agent.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from omegaconf import DictConfig
from scipy.spatial.distance import pdist, squareform
from scipy.stats import spearmanr

from analysis.cli import comma_ints
from curiosity.agents.paper import PaperAgent
from curiosity.config import ConfigError
from curiosity.build import build
from curiosity.envs import adapter_of, make_env
from curiosity.runtime.preflight import checked_config
from curiosity.runtime.restore import RestoreError, restore_run
from studies.representation import agent_with_data, random_policy, rollout


def state_vector(env: gym.Env, physical: np.ndarray) -> np.ndarray:
    """The env's own state observation in its current physical state (``_get_ob`` where the env has one)."""
    get_ob = getattr(env.unwrapped, "_get_ob", None)
    return np.asarray(get_ob() if get_ob is not None else physical, dtype=np.float64)


def sample_states(cfg: DictConfig, n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` observations (n, *obs), state vectors (n, S) and physical states (n, P) of the run's env (module doc)."""
    env, adapter = make_env(cfg.env, max_steps=10**9), adapter_of(cfg.env)
    low, high = np.asarray(cfg.env.coverage_low, dtype=np.float64), np.asarray(cfg.env.coverage_high, dtype=np.float64)
    half = len(low) // 2
    mid = (low[half:] + high[half:]) / 2
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    obs, vectors, physical = [], [], []
    for _ in range(n):
        state = rng.uniform(low, high)
        state[half:] = mid + (state[half:] - mid) * rng.uniform(size=len(low) - half) ** 2
        adapter.set_physical_state(env, state)
        for _ in range(4):
            o, *_ = env.step(int(rng.integers(int(cfg.env.n_actions))))
        p = adapter.physical_state(env).copy()
        obs.append(np.asarray(o, dtype=np.float32))
        vectors.append(state_vector(env, p))
        physical.append(p)
    env.close()
    return np.stack(obs), np.stack(vectors), np.stack(physical)


def _standardised(x: np.ndarray) -> np.ndarray:
    return (x - x.mean(0)) / np.where(x.std(0) > 0, x.std(0), 1.0)


def pairwise(x: np.ndarray) -> np.ndarray:
    """The upper-triangle pairwise Euclidean distances of the rows of ``x`` (n, D) -> (n(n-1)/2,)."""
    return pdist(x)


def knn_overlap(a: np.ndarray, b: np.ndarray, k: int = 10) -> float:
    """Mean fraction of each row's ``k`` nearest neighbours in ``a`` (n, Da) that are among its ``k`` in ``b``."""

    def neighbours(x: np.ndarray) -> np.ndarray:
        d = squareform(pdist(x))
        np.fill_diagonal(d, np.inf)
        return np.argsort(d, axis=1)[:, :k]

    na, nb = neighbours(a), neighbours(b)
    return float(np.mean([len(set(x) & set(y)) / k for x, y in zip(na, nb, strict=True)]))


def whitened(x: np.ndarray) -> np.ndarray:
    """Rows of ``x`` (n, D) centred and rotated onto their covariance's eigenvectors, each scaled to unit variance
    (directions of (near) zero variance are left near zero)."""
    x = x - x.mean(0)
    evals, evecs = np.linalg.eigh(np.atleast_2d(np.cov(x, rowvar=False)))
    return x @ evecs / np.sqrt(np.maximum(evals, 1e-12 * max(float(evals.max()), 1e-300)))


def linear_r2(x: np.ndarray, y: np.ndarray) -> float:
    """Held-out R² of a least-squares affine map from ``x`` (n, D) to ``y`` (n, K): fitted on the first n // 2 rows,
    1 − SSE / SST (summed over the K outputs) on the rest."""
    half = len(x) // 2
    a = np.c_[x, np.ones(len(x))]
    w, *_ = np.linalg.lstsq(a[:half], y[:half], rcond=None)
    resid = y[half:] - a[half:] @ w
    return float(1 - (resid**2).sum() / ((y[half:] - y[half:].mean(0)) ** 2).sum())


METRICS = ("rho_all", "rho_pose", "rho_velocity", "knn", "rho_velocity_white", "r2_velocity_linear")
Geometry = Callable[[np.ndarray, np.ndarray, int], dict[str, float]]
AfterTraining = Callable[[PaperAgent], None]


def geometry(latents: np.ndarray, vectors: np.ndarray, n_velocity: int) -> dict[str, float]:
    """The metrics of the module docstring (:data:`METRICS`): latents (n, d), state vectors (n, S), the last
    ``n_velocity`` entries of which are velocities."""
    z, v = _standardised(latents), _standardised(vectors)
    dz, dvel = pairwise(z), pairwise(v[:, -n_velocity:])
    return {"rho_all": float(spearmanr(dz, pairwise(v)).statistic),
            "rho_pose": float(spearmanr(dz, pairwise(v[:, :-n_velocity])).statistic),
            "rho_velocity": float(spearmanr(dz, dvel).statistic),
            "knn": knn_overlap(z, v),
            "rho_velocity_white": float(spearmanr(pairwise(whitened(latents)), dvel).statistic),
            "r2_velocity_linear": linear_r2(latents, vectors[:, -n_velocity:])}  # fmt: skip


def _encode(encoder: Callable[[torch.Tensor], torch.Tensor], obs: np.ndarray) -> np.ndarray:
    with torch.no_grad():
        return torch.cat([encoder(torch.as_tensor(obs[i : i + 256])) for i in range(0, len(obs), 256)]).double().numpy()


def trained(run_dir: str, states: int = 400, data_seed: int = 0, geometry_of: Geometry = geometry) -> dict[str, Any]:
    """The geometry (``geometry_of``) of the trained encoder of the run in ``run_dir``, restored from its checkpoint."""
    run = restore_run(run_dir)
    torch.set_num_threads(1)
    obs, vectors, physical = sample_states(run.cfg, states, data_seed)
    model = run.agent.model
    with model.evaluating():
        row = geometry_of(_encode(model.encode, obs), vectors, physical.shape[1] - physical.shape[1] // 2)
    return {"run": str(run_dir), "step": run.step, "states": states, "data_seed": data_seed,
            "rows": [{"seed": "trained", **row}], "mean": row}  # fmt: skip


def trained_offline(cfg: DictConfig, iters: int, data_seed: int,
                    after_training: AfterTraining | None = None) -> Callable[[torch.Tensor], torch.Tensor]:  # fmt: skip
    """The paper agent's encoder after ``iters`` world-model iterations on random-policy data (module doc);
    ``after_training`` is called with the trained agent."""
    agent = agent_with_data(cfg, rollout(cfg, 600, random_policy(int(cfg.env.n_actions)), data_seed + 1))
    agent.model.train()
    for _ in range(iters):
        agent._iteration()
    agent.model.eval()
    if after_training is not None:
        after_training(agent)
    return agent.model.encode


def study(overrides: Sequence[str], seeds: Sequence[int], states: int = 400, data_seed: int = 0, train_iters: int = 0,
          geometry_of: Geometry = geometry, after_training: AfterTraining | None = None) -> dict[str, Any]:  # fmt: skip
    """The encoder of ``overrides`` at each initialisation seed (trained ``train_iters`` iterations offline first,
    ``after_training`` called with each trained agent), on one fixed sample of states; its metrics by ``geometry_of``
    (default :func:`geometry`), and their mean over the seeds."""
    cfg = checked_config(overrides)[1]
    torch.set_num_threads(int(cfg.threads))
    obs, vectors, physical = sample_states(cfg, states, data_seed)
    n_velocity = physical.shape[1] - physical.shape[1] // 2
    rows = []
    for seed in seeds:
        torch.manual_seed(seed)
        encoder = trained_offline(cfg, train_iters, data_seed, after_training) if train_iters else build(cfg.encoder)
        rows.append({"seed": int(seed), **geometry_of(_encode(encoder, obs), vectors, n_velocity)})
    mean = {k: float(np.mean([r[k] for r in rows])) for k in rows[0] if k != "seed"}
    return {"overrides": list(overrides), "states": states, "data_seed": data_seed, "train_iters": train_iters,
            "rows": rows, "mean": mean}  # fmt: skip


def main(argv: list[str] | None = None, geometry_of: Geometry = geometry, after_training: AfterTraining | None = None) -> int:
    """The command line (``argv``: config overrides and options in any order); ``geometry_of`` and ``after_training``
    as for :func:`study` (a study that extends the check passes them)."""
    parser = argparse.ArgumentParser(prog="python -m studies.encoder_geometry", description=__doc__.splitlines()[0])
    parser.add_argument("overrides", nargs="*", help="config overrides, as for runners.train (e.g. encoder.blur_sigma=4)")
    parser.add_argument("--seeds", default="0,1,2", help="comma-separated encoder initialisation seeds (0,1,2)")
    parser.add_argument("--states", type=int, default=400, help="states sampled (400)")
    parser.add_argument("--data-seed", type=int, default=0, help="seed of the state sample (0)")
    parser.add_argument("--train-iters", type=int, default=0, help="train each encoder offline first (0: untrained)")
    parser.add_argument("--run", help="measure this run's trained encoder (from its checkpoint) instead")
    parser.add_argument("--json", help="also write the result to this file")
    args = parser.parse_intermixed_args(argv)
    seeds = comma_ints(args.seeds)
    if not seeds or min(seeds) < 0 or args.states < 12 or args.train_iters < 0:
        print(f"error: --seeds={args.seeds} --states={args.states} --train-iters={args.train_iters}: allowed: "
              "integers >= 0, states >= 12, train iterations >= 0", file=sys.stderr)  # fmt: skip
        return 2
    try:
        if args.run:
            out = trained(args.run, args.states, args.data_seed, geometry_of)
        else:
            out = study(args.overrides, seeds, args.states, args.data_seed, args.train_iters, geometry_of, after_training)
    except (ConfigError, RestoreError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    columns = list(out["mean"])
    print("| seed | " + " | ".join(columns) + " |\n" + "|---" * (len(columns) + 1) + "|")
    for r in [*out["rows"], {"seed": "mean", **out["mean"]}]:
        print(f"| {r['seed']} | " + " | ".join(f"{r[k]:.3f}" for k in columns) + " |")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
