"""How wrong is a run's learned model where the planner looks? ``python -m analysis.probe RUN_DIR [--states N]``.

Restores the run at its checkpoint (``checkpoint.pt``, ``.hydra/config.yaml``), branches the real simulator over
every action sequence of the planner's horizon from that state and from the next ``N - 1`` states the agent's own
policy reaches (acting without learning, every ``--every`` steps), encodes the true futures, and prints the means over
those states of (:mod:`curiosity.planning.probe`): the predicted and the true action effect and their ratio at each
depth, the model's latent error, the Spearman correlation between planner scores from the model and from the true
futures, and how often the best first action agrees. ``--json FILE`` writes the per-state values and the means.

``--step N [N …]`` (or ``--step all``) probes at the checkpoints the run kept along the way (``checkpoint_keep=true``;
those of the warm-up left out) instead of its last one, and prints one row per step. At a checkpoint taken at the goal
(a terminal env), and whenever the walk reaches the goal, the env is reset and the walk goes on from the start state
with the same agent.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import torch

from analysis.checkpoints import checkpoints_at, new_episode, walk_start
from curiosity.envs.simulator import Simulator
from curiosity.planning.probe import probe_model
from curiosity.runtime.restore import RestoreError, restore_run


def probe_run(run_dir: str | Path, states: int = 8, every: int = 5,
              checkpoint: Path | None = None) -> list[dict[str, float]]:  # fmt: skip
    """Probe results at ``states`` states of the run, from its last checkpoint on, or from the checkpoint file
    ``checkpoint`` of that run (see the module docstring)."""
    run = restore_run(run_dir, checkpoint)
    agent, env = run.agent, run.env
    if getattr(agent, "q", True) is not None or not hasattr(agent, "planner"):
        raise RestoreError(f"{run_dir}: the probe needs the paper's agent with planner=mpc (this run: "
                           f"baseline={run.cfg.baseline.name}, planner={run.cfg.planner.name})")  # fmt: skip
    torch.set_num_threads(1)
    agent.env, agent.simulator = env, Simulator(run.cfg.env)
    model, obs, step, out = agent.model, walk_start(Path(run_dir), run), run.step, []
    for i in range(states):
        with model.evaluating():
            z0 = model.encode(torch.as_tensor(obs).unsqueeze(0))[0]
            out.append(probe_model(agent.planner, z0, model.next, agent._reward_fn(), agent.intrinsic.imagined_terms,
                                   agent.simulator, agent.simulator.root(env, obs), model.encode))  # fmt: skip
        for _ in range(every if i + 1 < states else 0):
            obs, _, terminated, _, _ = env.step(agent.act(obs, step))
            step += 1
            if terminated:
                obs = new_episode(env, agent)
    return out


def means(results: list[dict[str, float]]) -> dict[str, float]:
    """Mean of each metric over the states where it is defined."""
    keys = sorted({k for r in results for k in r})
    return {k: float(np.mean([r[k] for r in results if k in r])) for k in keys}


def _table(avg: dict[str, float], n: int) -> str:
    depths = sorted({int(k.rsplit("/", 1)[1]) for k in avg if k.startswith("probe/effect_true/")})
    lines = [f"model probe over {n} state(s): means", "", "| depth | true effect | predicted effect | ratio | latent error |",
             "|---|---|---|---|---|"]  # fmt: skip
    for k in depths:
        ratio = avg.get(f"probe/effect_ratio/{k}", float("nan"))
        lines.append(f"| {k} | {avg[f'probe/effect_true/{k}']:.4g} | {avg[f'probe/effect_pred/{k}']:.4g} | {ratio:.3f} "
                     f"| {avg[f'probe/error/{k}']:.4g} |")  # fmt: skip
    lines += ["", f"Spearman(model scores, true-future scores): {avg.get('probe/spearman', float('nan')):.3f}",
              f"best first action agrees: {avg['probe/agree']:.2f}"]  # fmt: skip
    return "\n".join(lines)


def _step_table(results: dict[int | None, list[dict[str, float]]]) -> str:
    """One row per kept checkpoint: the means over its states of the ranking, the agreement, and the action effect and
    latent error at the first and the deepest depth."""
    lines = ["| step | states | Spearman(model, true futures) | best first action agrees | effect ratio at depth 1 / H "
             "| latent error at depth 1 / H |", "|---|---|---|---|---|---|"]  # fmt: skip
    for step, per_state in results.items():
        avg = means(per_state)
        depths = sorted({int(k.rsplit("/", 1)[1]) for k in avg if k.startswith("probe/effect_true/")})
        one, deep = depths[0], depths[-1]
        ratio = [avg.get(f"probe/effect_ratio/{k}", float("nan")) for k in (one, deep)]
        lines.append(f"| {step} | {len(per_state)} | {avg.get('probe/spearman', float('nan')):.3f} | "
                     f"{avg['probe/agree']:.2f} | {ratio[0]:.3f} / {ratio[1]:.3f} | "
                     f"{avg[f'probe/error/{one}']:.4g} / {avg[f'probe/error/{deep}']:.4g} |")  # fmt: skip
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_dir")
    parser.add_argument("--states", type=int, default=8, help="states to probe (default 8)")
    parser.add_argument("--every", type=int, default=5, help="agent steps between probed states (default 5)")
    parser.add_argument("--json", type=Path, help="write per-state results and means to this file")
    parser.add_argument("--step", nargs="+", metavar="N", help="probe at these kept checkpoints (env steps), or 'all' "
                        "of them (runs made with checkpoint_keep=true), instead of the last checkpoint")  # fmt: skip
    args = parser.parse_args(argv)
    if args.states < 1 or args.every < 1:
        print("error: --states and --every must be >= 1", file=sys.stderr)
        return 2
    try:
        at = checkpoints_at(Path(args.run_dir), args.step)
        by_step = {step: probe_run(args.run_dir, args.states, args.every, path) for step, path in at.items()}
    except RestoreError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    if args.step is not None:
        print(_step_table(by_step))
        if args.json:
            steps = {str(step): {"states": r, "means": means(r)} for step, r in by_step.items()}
            args.json.write_text(json.dumps({"steps": steps}, indent=2) + "\n")
        return 0
    results = by_step[None]
    avg = means(results)
    print(_table(avg, len(results)))
    if args.json:
        args.json.write_text(json.dumps({"states": results, "means": avg}, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
