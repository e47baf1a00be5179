"""Does the learned latent make unseen states look novel? ``python -m studies.representation [OVERRIDES...]``.

Novelty can only guide exploration if the encoder maps states the agent has not met away from those it has. This
check trains the paper agent's world model (the config the overrides compose, as ``runners.train`` would) offline on
one fixed random-policy dataset, and at each of ``--iters`` gradient iterations encodes two probe sets the model never
trained on: held-out random-policy states, and states of a policy that pushes with the motion half of the time
(the env adapter's ``directed_action``), which climbs just past the energies random play reaches: the frontier an exploring
agent should find novel. It reports, per checkpoint:

- ``auc``: how often a pumping state is more novel than a held-out random state under the run's estimator fitted to
  the training latents (0.5: novelty cannot tell them apart; 1: every pumping state is more novel);
- ``auc_physical``: the same estimator on the standardised physical state, the reference a perfect state encoder
  gives;
- ``rho_energy``: Spearman correlation between latent novelty and mechanical energy (the env adapter's ``energy``)
  over both probe sets;
- ``r2``: how well the latent determines each physical state variable (1-nearest-neighbour regression from the
  training latents to the held-out random states: 1 perfect, ≤ 0 no information).

Nothing is written unless ``--json FILE`` is given. The numbers depend on the data seed and the model's seed; they are
a diagnostic, not a result, and are meant to be compared across configurations at the same seeds.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from omegaconf import DictConfig
from scipy.stats import spearmanr

from analysis.cli import comma_ints
from curiosity.agents.paper import PaperAgent
from curiosity.config import ConfigError
from curiosity.build import build, choice
from curiosity.envs import adapter_of, make_env
from curiosity.runtime.preflight import checked_config

Policy = Callable[[np.ndarray, np.random.Generator], int]


@dataclass
class Trajectory:
    """Transitions of one policy: obs (T, *obs), actions (T,), next obs (T, *obs), physical state reached (T, P)."""

    obs: np.ndarray
    actions: np.ndarray
    next_obs: np.ndarray
    physical: np.ndarray


def rollout(cfg: DictConfig, steps: int, policy: Policy, seed: int) -> Trajectory:
    """``steps`` transitions of ``policy`` (physical state, rng -> action) in the run's env from ``reset(seed)``."""
    env, adapter = make_env(cfg.env, max_steps=10**9), adapter_of(cfg.env)
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    rows: list[tuple[Any, int, Any, np.ndarray]] = []
    for _ in range(steps):
        action = policy(adapter.physical_state(env), rng)
        next_obs, _, _, _, _ = env.step(action)
        rows.append((obs, action, next_obs, adapter.physical_state(env).copy()))
        obs = next_obs
    env.close()
    o, a, n, p = zip(*rows, strict=True)
    return Trajectory(np.asarray(o), np.asarray(a), np.asarray(n), np.asarray(p))


def pumping_policy(env_cfg: Any, n_actions: int, p: float = 0.5) -> Policy:
    """With probability ``p`` the directed action (push with the motion), else a uniform random action; uniform where
    the state has no directed action. p = 0.5 climbs past random play's energies without leaving its neighbourhood
    at once (Acrobot, 300 states from rest: median energy 11 J against random play's −10 J; a KDE on the physical
    state ranks these states above held-out random ones 86 % of the time, where p = 1 gives 100 %)."""
    directed = adapter_of(env_cfg).directed_action
    if directed is None:
        raise ConfigError([f"env.id={env_cfg.id}: the representation check needs an env with a directed action; "
                           "allowed: Acrobot-v1, MountainCar-v0"])  # fmt: skip

    def policy(state: np.ndarray, rng: np.random.Generator) -> int:
        action = directed(state)
        if action is not None and rng.random() < p:
            return action
        return int(rng.integers(n_actions))

    return policy


def random_policy(n_actions: int) -> Policy:
    return lambda state, rng: int(rng.integers(n_actions))


def auc(positive: np.ndarray, negative: np.ndarray) -> float:
    """P(a positive score > a negative one) + ½ P(tie), over all pairs: (P,), (N,) -> [0, 1]."""
    diff = positive[:, None] - negative[None, :]
    return float((diff > 0).mean() + 0.5 * (diff == 0).mean())


def nn_r2(train_z: np.ndarray, train_y: np.ndarray, test_z: np.ndarray, test_y: np.ndarray) -> np.ndarray:
    """R² per column of predicting test_y (T, P) by the y of each test latent's nearest training latent."""
    d2 = ((test_z[:, None, :] - train_z[None, :, :]) ** 2).sum(-1)
    pred = train_y[d2.argmin(1)]
    var = ((test_y - test_y.mean(0)) ** 2).sum(0)
    return 1.0 - ((pred - test_y) ** 2).sum(0) / np.where(var > 0, var, np.nan)


def novelty_scores(cfg: DictConfig, memory: np.ndarray, queries: np.ndarray, warmup: int) -> np.ndarray:
    """The run's estimator (``estimator`` group) fitted to ``memory`` (N, D), scoring ``queries`` (Q, D) -> (Q,).
    Both are standardised by the memory's statistics first, as the agent does with ``standardise_latents``."""
    mean, std = memory.mean(0), memory.std(0).clip(min=1e-8)
    mem = torch.as_tensor((memory - mean) / std, dtype=torch.float32)
    estimator = build(cfg.estimator)
    estimator.fit(mem, mem[: max(2, min(warmup, len(mem)))])
    return estimator(torch.as_tensor((queries - mean) / std, dtype=torch.float32)).double().numpy()


def study_config(overrides: Sequence[str]) -> DictConfig:
    """The run config of ``overrides``, checked as ``runners.train`` checks it; the paper's agent only."""
    task = checked_config(overrides)[1]
    if choice(task.baseline.name) != "none" or choice(task.env.obs) != "pixels":
        what = f"baseline={choice(task.baseline.name)} env.obs={choice(task.env.obs)}"
        raise ConfigError([f"{what}: the representation check trains the paper agent's world model from pixels; "
                           "allowed: baseline=none with env.obs=pixels"])  # fmt: skip
    return task


@dataclass
class ProbeSets:
    """The fixed data of a study: training transitions, held-out random states, pumping states."""

    train: Trajectory
    random: Trajectory
    pumping: Trajectory


def probe_sets(cfg: DictConfig, train_steps: int, probe_steps: int, data_seed: int) -> ProbeSets:
    """Random-policy training data (``train_steps``), ``probe_steps`` held-out random states (another seed) and
    ``probe_steps`` states of the half-directed pumping policy (a third seed), each run from ``reset``."""
    n_actions = int(cfg.env.n_actions)
    train = rollout(cfg, train_steps, random_policy(n_actions), data_seed)
    held_out = rollout(cfg, probe_steps, random_policy(n_actions), data_seed + 1)
    pump = rollout(cfg, probe_steps, pumping_policy(cfg.env, n_actions), data_seed + 2)
    return ProbeSets(train, held_out, pump)


def _encode(agent: PaperAgent, obs: np.ndarray) -> np.ndarray:
    with agent.model.evaluating(), torch.no_grad():
        parts = [agent.model.encode(torch.as_tensor(obs[i : i + 256], dtype=torch.float32)) for i in range(0, len(obs), 256)]
    return torch.cat(parts).double().numpy()


def physical_auc(cfg: DictConfig, data: ProbeSets) -> float:
    """The reference: the AUC of the run's estimator on the physical state instead of the latent (fixed per study)."""
    p_train, p_rand, p_pump = data.train.physical, data.random.physical, data.pumping.physical
    nov = novelty_scores(cfg, p_train, np.concatenate([p_rand, p_pump]), int(cfg.budget.warmup_steps))
    return auc(nov[len(p_rand) :], nov[: len(p_rand)])


def measure(agent: PaperAgent, cfg: DictConfig, data: ProbeSets, auc_physical: float) -> dict[str, Any]:
    """The metrics of the module docstring for the agent's current encoder (``auc_physical`` from
    :func:`physical_auc`)."""
    z_train, z_rand, z_pump = (_encode(agent, t.next_obs) for t in (data.train, data.random, data.pumping))
    nov = novelty_scores(cfg, z_train, np.concatenate([z_rand, z_pump]), int(cfg.budget.warmup_steps))
    p_train, p_rand, p_pump = data.train.physical, data.random.physical, data.pumping.physical
    energy = adapter_of(cfg.env).energy
    assert energy is not None  # every env with a directed action has an energy
    r = len(z_rand)
    return {"auc": auc(nov[r:], nov[:r]), "auc_physical": auc_physical,
            "rho_energy": float(spearmanr(nov, energy(np.concatenate([p_rand, p_pump]))).statistic),
            "r2": [round(float(v), 3) for v in nn_r2(z_train, p_train, z_rand, p_rand)],
            "latent_std": [round(float(v), 3) for v in z_train.std(0)]}  # fmt: skip


def agent_with_data(cfg: DictConfig, data: Trajectory, first_call: bool = False) -> PaperAgent:
    """A new paper agent of ``cfg`` whose replay holds the transitions of ``data`` (extrinsic reward −1, none final).

    ``first_call``: then also as at its first training call, the call counted by its schedule and a frozen encoder
    calibrated on the data (``encoder.frozen``; trained encoders are left as they are), as a run's first call does."""
    agent = PaperAgent(cfg)
    for i in range(len(data.actions)):
        agent.replay.add(data.obs[i], int(data.actions[i]), -1.0, data.next_obs[i], False)
    if first_call:
        agent.schedule.iterations(int(agent.schedule.warmup_steps) - 1)  # the step that ends the warm-up: call 1
        assert agent.schedule.calls == 1
        agent._calibrate()
    return agent


def study(overrides: Sequence[str], iters: Sequence[int], train_steps: int = 600, probe_steps: int = 300,
          data_seed: int = 1) -> list[dict[str, Any]]:  # fmt: skip
    """Train the configured world model on the fixed random-policy data; measure at each of ``iters`` (ascending)."""
    cfg = study_config(overrides)
    torch.set_num_threads(int(cfg.threads))
    torch.manual_seed(int(cfg.seed))
    data = probe_sets(cfg, train_steps, probe_steps, data_seed)
    agent = agent_with_data(cfg, data.train)
    reference = physical_auc(cfg, data)
    out, done = [], 0
    for target in iters:
        agent.model.train()
        for _ in range(target - done):
            agent._iteration()
        done = target
        out.append({"iters": done, **measure(agent, cfg, data, reference)})
    return out


def _table(rows: list[dict[str, Any]]) -> str:
    lines = ["| iterations | AUC pumping vs random (latent) | AUC (physical state) | Spearman(novelty, energy) | "
             "1-NN R² per physical variable | latent std |", "|---|---|---|---|---|---|"]  # fmt: skip
    for r in rows:
        lines.append(
            f"| {r['iters']} | {r['auc']:.3f} | {r['auc_physical']:.3f} | {r['rho_energy']:.2f} | "
            f"{', '.join(f'{v:.2f}' for v in r['r2'])} | {', '.join(f'{v:.2g}' for v in r['latent_std'])} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m studies.representation", description=__doc__.splitlines()[0])
    parser.add_argument("overrides", nargs="*", help="config overrides, as for runners.train (e.g. agent.internal_dim=8)")
    parser.add_argument("--iters", default="0,300,1000", help="comma-separated iteration counts (default 0,300,1000)")
    parser.add_argument("--train-steps", type=int, default=600, help="random-policy training transitions (600)")
    parser.add_argument("--probe-steps", type=int, default=300, help="states in each probe set (300)")
    parser.add_argument("--data-seed", type=int, default=1, help="env seed of the training data (probe sets: +1, +2)")
    parser.add_argument("--json", help="also write the rows to this file")
    args = parser.parse_args(argv)
    iters = comma_ints(args.iters)
    if not iters or min(iters) < 0 or iters != sorted(iters) or args.train_steps < 2 or args.probe_steps < 5:
        print(f"error: --iters={args.iters} --train-steps={args.train_steps} --probe-steps={args.probe_steps}: "
              "allowed: ascending integers >= 0, train steps >= 2, probe steps >= 5", file=sys.stderr)  # fmt: skip
        return 2
    try:
        rows = study(args.overrides, iters, args.train_steps, args.probe_steps, args.data_seed)
    except ConfigError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(_table(rows))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"overrides": args.overrides, "train_steps": args.train_steps, "probe_steps": args.probe_steps,
                       "data_seed": args.data_seed, "rows": rows}, fh, indent=1)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
