"""Steps-to-goal per method: every seed, successes/seeds, mean ± standard error.

``python -m analysis.steps_table RUNS_ROOT [--markdown]``. Runs that hit the step cap are censored: they count in
``seeds`` but not in ``reached``; the mean and SE are over the runs that reached the goal, and ``mean_capped``
scores a censored run at its cap (a lower bound on the true mean). SE = sample SD / sqrt(n) (the paper's ±).
"""

from __future__ import annotations

import argparse
import math

import pandas as pd

from analysis.collect import load_summaries


def steps_table(summaries: pd.DataFrame, by: tuple[str, ...] = ("env", "method", "variant")) -> pd.DataFrame:
    """One row per group of ``by``: seeds, reached, per-seed steps, mean ± SE, mean with censored runs at cap."""
    rows = []
    for key, g in summaries.groupby(list(by), sort=True):
        g = g.sort_values("seed")
        reached = g[g["reached_goal"]]["steps_to_goal"].astype(float)
        capped = g["steps_to_goal"].where(g["reached_goal"], g["max_steps"]).astype(float)
        n = len(reached)
        rows.append({
            **dict(zip(by, key if isinstance(key, tuple) else (key,), strict=True)),
            "seeds": len(g),
            "reached": n,
            "per_seed": " ".join(str(int(s)) if ok else f">{int(c)}" for s, ok, c in
                                 zip(g["steps_to_goal"].fillna(0), g["reached_goal"], g["max_steps"], strict=True)),
            "mean": reached.mean() if n else math.nan,
            "se": reached.std(ddof=1) / math.sqrt(n) if n > 1 else math.nan,
            "mean_capped": capped.mean(),
            "wall_seconds_mean": g["wall_seconds"].mean(),
        })  # fmt: skip
    return pd.DataFrame(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("root", help="directory holding run directories (searched recursively)")
    parser.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = parser.parse_args()
    table = steps_table(load_summaries(args.root))
    print(to_markdown(table) if args.markdown else table.to_string(index=False))


def to_markdown(table: pd.DataFrame) -> str:
    """A Markdown table (floats with one decimal)."""
    def cell(v: object) -> str:
        return f"{v:.1f}" if isinstance(v, float) else str(v)

    lines = ["| " + " | ".join(table.columns) + " |", "|" + "---|" * len(table.columns)]
    lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in table.itertuples(index=False)]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
