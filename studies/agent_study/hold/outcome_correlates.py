"""What goes with a run's steps-to-goal, across every finished run of the new default and its screens.

Reads only committed run files (summary.json, metrics.csv) below ``--root`` (default: the repository's
``results/agent_study/hold``). For each run: steps-to-goal, the mean share of steps pushing with the motion
(behaviour/directed) over the run and over its first 200 env steps, and the mean of the periodic model probe's
Spearman correlation and first-action agreement (probe/spearman, probe/agree). Prints the Spearman correlation of each
with steps-to-goal over all runs.

    python -m studies.agent_study.hold.outcome_correlates > results/agent_study/hold/outcome_correlates/output.txt
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pandas as pd
from scipy import stats

from analysis.collect import run_dirs

HOLD = Path(__file__).resolve().parents[3] / "results" / "agent_study" / "hold"
DIRS = ("default_hold4_blur4", "default_hold4_blur4_heldout", "default_commit2", "default_first1000", "default_iters8",
        "default_ensemble5")  # fmt: skip


def run_rows(root: Path = HOLD) -> pd.DataFrame:
    rows = []
    for name in DIRS:
        for run in run_dirs(root / name):
            summary = run / "summary.json"
            s = json.loads(summary.read_text())
            if s["steps_to_goal"] is None:
                raise SystemExit(f"{summary}: no goal within the cap; this script expects every run to reach it")
            m = pd.read_csv(run / "metrics.csv")
            probed = m.dropna(subset=["probe/spearman"])
            rows.append({
                "dir": name, "seed": s["seed"], "steps": s["steps_to_goal"],
                "directed": m["behaviour/directed"].mean(),
                "directed_first200": m.loc[m["step"] <= 200, "behaviour/directed"].mean(),
                "probe_spearman": probed["probe/spearman"].mean(), "probe_agree": probed["probe/agree"].mean(),
            })  # fmt: skip
    return pd.DataFrame(rows)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.hold.outcome_correlates",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("--root", type=Path, default=HOLD, help=f"the directory holding {', '.join(DIRS[:2])}, … "
                        "(default: results/agent_study/hold)")  # fmt: skip
    df = run_rows(parser.parse_args(argv).root)
    print(df.round(3).to_string(index=False))
    print(f"\n{len(df)} runs; Spearman correlation with steps-to-goal (p-value):")
    for column in ("directed", "directed_first200", "probe_spearman", "probe_agree"):
        r = stats.spearmanr(df["steps"], df[column])
        print(f"  {column:18s} {r.statistic:+.2f} (p = {r.pvalue:.2g})")


if __name__ == "__main__":
    main()
