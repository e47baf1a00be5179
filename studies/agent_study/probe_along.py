"""Reference analysis (not the product): how well the default's learned model ranks futures along its runs.

Reads each run's ``probe_along.json`` (``python -m analysis.probe RUN --step all --states 8 --every 5 --json …``: per
kept checkpoint after the warm-up, the probe at 8 states the agent reaches from there acting without learning) and
its ``summary.json``, and prints per run, at each kept step, the mean Spearman correlation between the planner's scores
of the 243 held-action sequences from the learned model and from the true simulator's futures, how often the two
choose the same first action (1/3 by chance), and the model's action effect against the true one (ratio) and latent
error at depth 1 and 5; then across runs the Spearman correlation of steps-to-goal with a run's mean ranking.

    python -m studies.agent_study.probe_along results/agent_study/landscape_along
"""

from __future__ import annotations

import argparse
import json

import numpy as np
from scipy.stats import spearmanr

from analysis.collect import run_dirs


def mean(at: dict, key: str) -> float:
    """Mean of a probe metric over a run's kept steps (where it is defined)."""
    return float(np.mean([m[key] for m in at.values() if key in m]))


def collect(root: str) -> list[tuple[int, int | None, dict[int, dict]]]:
    """Per run below ``root`` with a ``probe_along.json``: seed, steps-to-goal and the probe's means per kept step."""
    rows = []
    for run in run_dirs(root):
        path = run / "probe_along.json"
        if not path.is_file():
            continue
        summary = json.loads((run / "summary.json").read_text())
        steps = json.loads(path.read_text())["steps"]
        rows.append((summary["seed"], summary["steps_to_goal"], {int(k): v["means"] for k, v in steps.items()}))
    return rows


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.probe_along",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("root", help="the runs' directory (results/agent_study/landscape_along)")
    rows = collect(parser.parse_args(argv).root)
    print("| seed | steps-to-goal | Spearman(model scores, true-future scores) at each kept step | mean | same first "
          "action (mean) | effect ratio depth 1 / 5 (mean) | latent error depth 1 / 5 (mean) |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for seed, goal, at in sorted(rows):
        per = ", ".join(f"{s}: {m['probe/spearman']:+.2f}" for s, m in sorted(at.items()))
        print(f"| {seed} | {goal} | {per} | {mean(at, 'probe/spearman'):+.2f} | {mean(at, 'probe/agree'):.2f} | "
              f"{mean(at, 'probe/effect_ratio/1'):.2f} / {mean(at, 'probe/effect_ratio/5'):.2f} | "
              f"{mean(at, 'probe/error/1'):.3f} / {mean(at, 'probe/error/5'):.3f} |")  # fmt: skip
    every = [m["probe/spearman"] for _, _, at in rows for m in at.values()]
    agree = [m["probe/agree"] for _, _, at in rows for m in at.values()]
    print(f"\nover all {len(every)} kept steps of {len(rows)} runs: Spearman mean {np.mean(every):+.2f} (range "
          f"{min(every):+.2f} to {max(every):+.2f}, positive at {sum(v > 0 for v in every)}); same first action "
          f"{np.mean(agree):.2f}")  # fmt: skip
    if len(rows) > 2:
        res = spearmanr([np.mean([m["probe/spearman"] for m in at.values()]) for _, _, at in rows], [g for _, g, _ in rows])
        print(f"across the {len(rows)} runs, Spearman(steps-to-goal, run's mean ranking) = {res.statistic:+.2f} "
              f"(p = {res.pvalue:.2g})")  # fmt: skip


if __name__ == "__main__":
    main()
