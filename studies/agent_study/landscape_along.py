"""Reference analysis (not the product): the novelty landscape along the default's runs, before the goal.

Reads each run's ``landscape_along.md`` (``python -m analysis.landscape RUN --step all --states 10 --bandwidths 2``:
one row per kept checkpoint and novelty variant) and its ``summary.json``, and prints per run the mean Spearman
correlation of a sequence's novelty return with the energy it ends with at each kept step after the warm-up, and
across runs the Spearman correlation of steps-to-goal with the run's mean of that correlation and with how often the
novelty-best first action was the energy-best one.

    python -m studies.agent_study.landscape_along results/agent_study/landscape_along
"""

from __future__ import annotations

import argparse
import json
import re

import numpy as np
from scipy.stats import spearmanr

from analysis.collect import run_dirs

VARIANT = "kde h=2×median NN"


def collect(root: str) -> list[tuple[int, int | None, dict[int, tuple[float, float]]]]:
    """Per run below ``root``: seed, steps-to-goal and, per kept step after the warm-up, (Spearman, agreement)."""
    rows = []
    for run in run_dirs(root):
        summary = json.loads((run / "summary.json").read_text())
        warmup = summary["warmup_steps"]
        table = (run / "landscape_along.md").read_text().splitlines()
        at = {}
        for line in table:
            cells = [c.strip() for c in line.strip("|").split("|")]
            if len(cells) == 5 and cells[1] == VARIANT and cells[0].isdigit() and int(cells[0]) > warmup:
                match = re.match(r"[-\d.]+", cells[4])
                assert match is not None, line
                at[int(cells[0])] = (float(cells[2]), float(match.group()))
        rows.append((summary["seed"], summary["steps_to_goal"], at))
    return rows


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.landscape_along",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("root", help="the runs' directory (results/agent_study/landscape_along)")
    rows = collect(parser.parse_args(argv).root)
    print("| seed | steps-to-goal | Spearman(novelty return, final energy) at each kept step after the warm-up | mean | "
          "novelty-best first action = energy-best (mean) |\n|---|---|---|---|---|")  # fmt: skip
    for seed, steps, at in sorted(rows):
        per = ", ".join(f"{s}: {r:+.2f}" for s, (r, _) in at.items())
        print(f"| {seed} | {steps} | {per} | {np.mean([r for r, _ in at.values()]):+.2f} | "
              f"{np.mean([a for _, a in at.values()]):.2f} |")  # fmt: skip
    steps = [s for _, s, _ in rows]
    for name, i in (("mean Spearman(novelty, energy)", 0), ("first-action agreement", 1)):
        values = [np.mean([v[i] for v in at.values()]) for _, _, at in rows]
        res = spearmanr(values, steps)
        print(f"\nacross the {len(rows)} runs, Spearman(steps-to-goal, run's {name}) = {res.statistic:+.2f} "
              f"(p = {res.pvalue:.2g})")  # fmt: skip


if __name__ == "__main__":
    main()
