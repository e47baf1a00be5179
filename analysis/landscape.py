"""Does the novelty the planner maximises point towards progress? ``python -m analysis.landscape RUN_DIR``.

Restores a run at its checkpoint and, at ``--states`` states along the agent's own policy (acting without learning),
branches the real simulator over every action sequence of the planner's horizon, encodes the true futures, and scores
each sequence's discounted novelty return under the run's estimator refitted to its memory re-embedded now, and under
variants (KDE with other bandwidth multipliers, kNN). Neither Acrobot nor MountainCar can be solved without pumping
mechanical energy in (the env adapter's ``energy``), so for each variant it prints the mean Spearman correlation
between the novelty return and the energy the sequence ends with, how often that correlation is positive, and how
often the novelty-best first action is the energy-best one (1/3 by chance with three actions).

``--step N [N …]`` (or ``--step all``) restores the run at the checkpoints it kept along the way (runs made with
``checkpoint_keep=true``: ``checkpoints/step=<n>.pt`` every ``checkpoint_every`` steps; those of the warm-up, before
the agent acts, are left out) instead of its last one, so the landscape can be followed before the goal; the table
then has one row per step and variant.

A run that ended at the goal is checkpointed in its terminal state; there, and whenever the walk reaches the goal, the
env is reset and the walk goes on from the start state with the same agent (model and memory as checkpointed), so a
finished run gives its ``--states`` states too.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import torch
from scipy.stats import spearmanr
from torch import Tensor

from analysis.checkpoints import checkpoints_at, new_episode, walk_start
from curiosity.envs import adapter_of
from curiosity.envs.simulator import Simulator
from curiosity.novelty.estimators import KDENovelty, KNNNovelty
from curiosity.planning.probe import tree_latents
from curiosity.planning.rollout import ReplayRollout, SimulatorRollout, held
from curiosity.runtime.restore import RestoreError, restore_run


def _variants(agent, bandwidths: list[float], k: int) -> dict[str, Callable[[Tensor], Tensor]]:
    """Novelty functions of standardised latents: KDE per bandwidth multiplier, and kNN, fitted to the memory."""
    cur = agent.novelty
    if cur is None:
        raise RestoreError("the landscape needs a run whose intrinsic reward has a latent novelty term")
    keys = cur.memory.keys().numpy()
    z = cur._encode_stored(keys)
    mean, std = z.mean(0), z.std(0, correction=0).clamp_min(1e-8)
    memory = (z - mean) / std
    reference = memory[: min(len(memory), cur.warmup_steps)]
    out = {}
    for h in bandwidths:
        kde = KDENovelty(bandwidth=h)
        kde.fit(memory, reference)
        out[f"kde h={h:g}×median NN"] = lambda zq, f=kde: f((zq - mean) / std)
    knn = KNNNovelty(k=k)
    knn.fit(memory, reference)
    out[f"knn k={k}"] = lambda zq: knn((zq - mean) / std)
    return out


def landscape(run_dir: str | Path, states: int = 20, bandwidths: tuple[float, ...] = (2.0, 0.5),
              k: int = 5, checkpoint: Path | None = None) -> dict[str, dict[str, float]]:  # fmt: skip
    """Per variant: ``rho`` (mean Spearman of novelty return and final energy), ``positive`` (fraction of states
    with rho > 0), ``first_action`` (fraction where the novelty-best first action is the energy-best one). From the
    run's last checkpoint, or from the checkpoint file ``checkpoint`` of that run."""
    run = restore_run(run_dir, checkpoint)
    energy = adapter_of(run.cfg.env).energy
    agent, env, obs, step = run.agent, run.env, walk_start(Path(run_dir), run), run.step
    if energy is None or not hasattr(agent, "planner") or agent.q is not None:
        raise RestoreError(f"{run_dir}: the landscape needs the paper's agent with planner=mpc on Acrobot or MountainCar")
    torch.set_num_threads(1)
    agent.env, agent.simulator = env, Simulator(run.cfg.env)
    planner, model = agent.planner, agent.model
    seqs, first = planner.candidates(), planner.candidates()[:, 0].numpy()
    with model.evaluating():
        variants = _variants(agent, list(bandwidths), k)
    rho: dict[str, list[float]] = {name: [] for name in variants}
    hit: dict[str, list[float]] = {name: [] for name in variants}
    for _ in range(states):
        with model.evaluating():
            z0 = model.encode(torch.as_tensor(obs).unsqueeze(0))[0]
            true = SimulatorRollout(agent.simulator, agent.simulator.root(env, obs), z0, model.encode)
            levels = tree_latents(held(true, planner.hold), planner.n_actions, planner.horizon)
            e = energy(true.states.physical)
            best_first = int(np.argmax([e[first == a].max() for a in range(planner.n_actions)]))
            for name, novelty in variants.items():
                g = planner.scores(z0, seqs, model.next, None, lambda z, a, zn, f=novelty: f(zn),
                                   rollout=ReplayRollout(z0, levels, planner.hold)).numpy()  # fmt: skip
                if np.ptp(g) > 0:
                    rho[name].append(float(spearmanr(g, e).statistic))
                hit[name].append(float(first[int(np.argmax(g))] == best_first))
        obs, _, terminated, _, _ = env.step(agent.act(obs, step))
        step += 1
        if terminated:
            obs = new_episode(env, agent)
    return {name: {"rho": float(np.mean(rho[name])) if rho[name] else float("nan"),
                   "positive": float(np.mean(np.array(rho[name]) > 0)) if rho[name] else float("nan"),
                   "first_action": float(np.mean(hit[name])), "states": float(len(hit[name]))}
            for name in variants}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_dir")
    parser.add_argument("--states", type=int, default=20, help="states along the agent's policy (default 20)")
    parser.add_argument("--bandwidths", type=float, nargs="+", default=[2.0, 0.5], help="KDE multipliers of the median NN")
    parser.add_argument("--k", type=int, default=5, help="neighbours of the kNN variant")
    parser.add_argument("--step", nargs="+", metavar="N", help="restore at these kept checkpoints (env steps), or 'all' "
                        "of them (runs made with checkpoint_keep=true), instead of the last checkpoint")  # fmt: skip
    args = parser.parse_args(argv)
    if args.states < 1 or args.k < 1 or min(args.bandwidths) <= 0:
        print("error: --states and --k must be >= 1 and --bandwidths > 0", file=sys.stderr)
        return 2
    try:
        at = checkpoints_at(Path(args.run_dir), args.step)
        results = {step: landscape(args.run_dir, args.states, tuple(args.bandwidths), args.k, path)
                   for step, path in at.items()}  # fmt: skip
    except RestoreError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    steps = args.step is not None
    print(("| step " if steps else "") + "| novelty | mean Spearman(novelty return, final energy) | states with a "
          "positive one | best first action = energy-best |\n" + ("|---" if steps else "") + "|---|---|---|---|")  # fmt: skip
    for step, result in results.items():
        for name, r in result.items():
            print((f"| {step} " if steps else "") + f"| {name} | {r['rho']:.2f} | {r['positive']:.2f} | "
                  f"{r['first_action']:.2f} (of {r['states']:.0f}) |")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
