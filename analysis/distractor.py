"""The noisy-TV table and figure (issue 16): does a distractor slow each method down, and does it watch the TV?

A method's runs are split by ``env.distractor`` (``none`` for runs made before the key existed). Per (env, method,
distractor): seeds, successes, every seed's steps-to-goal (a censored run as ``>cap``), mean ± SE with censored runs
at their last step, median, Welch's p of the TV runs against the same method without a TV, and the TV-press rate
(``summary.json``'s ``behaviour.tv_rate``: the fraction of the agent's own steps that pressed the remote; a uniformly
random policy presses it 1/4 of the time on Acrobot). The figure: ``behaviour/tv`` against env steps, per method.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from analysis.claims import fmt
from analysis.stats import mean_se, per_seed_text, welch_p

NONE = "none"
NOTE = ("Steps-to-goal, lower is better; censored runs (`>cap`) counted at their last step; SE = sample SD (ddof = 1)"
        "/√n. Welch p: the method with the distractor against the same method without it (scipy ttest_ind, "
        "equal_var=False). TV presses: the fraction of the agent's own steps (after the random warm-up) that pressed "
        "the remote-control action, mean ± SE over seeds; a uniformly random policy presses it 1/A of the time "
        "(A = the env's actions + 1).")  # fmt: skip


def _distractor(config: dict[str, object]) -> str:
    return str(config.get("env.distractor", NONE))


def _tv_rate(run_dir: str) -> float:
    behaviour = json.loads((Path(run_dir) / "summary.json").read_text()).get("behaviour") or {}
    rate = behaviour.get("tv_rate")
    return math.nan if rate is None else float(rate)


def has_distractor(runs: pd.DataFrame) -> bool:
    """Whether any run below the root ran with a distractor."""
    return not runs.empty and any(_distractor(c) != NONE for c in runs["config"])


def distractor_table(runs: pd.DataFrame) -> pd.DataFrame:
    """One line per (env, method, distractor) of :func:`analysis.rows.load_runs`' runs; empty without a distractor.

    Columns: env, method, distractor, n, reached, per_seed (steps-to-goal), mean, se, median, welch_p (against the
    method without a distractor), tv_rate and tv_rate_se (over the runs that report one), tv_per_seed (those rates in
    seed order, space-separated; empty for runs without a TV)."""
    if not has_distractor(runs):
        return pd.DataFrame()
    runs = runs.assign(distractor=[_distractor(c) for c in runs["config"]])
    out = []
    for (env, method), g in runs.groupby(["env", "method"], sort=True):
        clean = g[g["distractor"] == NONE]["steps"].tolist()
        for distractor, d in g.groupby("distractor", sort=True):
            d = d.sort_values("seed")
            mean, se = mean_se(d["steps"].tolist())
            rates = [r for r in map(_tv_rate, d["run_dir"]) if not math.isnan(r)]  # in seed order
            rate, rate_se = mean_se(rates) if rates else (math.nan, math.nan)
            out.append({
                "env": env, "method": method, "distractor": distractor, "n": len(d), "reached": int(d["reached"].sum()),
                "per_seed": per_seed_text(d),
                "mean": mean, "se": se, "median": float(np.median(d["steps"])),
                "welch_p": math.nan if distractor == NONE or not clean else welch_p(d["steps"].tolist(), clean),
                "tv_rate": rate, "tv_rate_se": rate_se, "tv_per_seed": " ".join(f"{r:.6g}" for r in rates),
            })  # fmt: skip
    return pd.DataFrame(out)


def to_markdown(table: pd.DataFrame) -> str:
    head = ["env", "method", "distractor", "reached / seeds", "per seed", "mean ± SE", "median", "Welch p vs none",
            "TV presses"]  # fmt: skip
    lines = ["## Steps-to-goal with and without a noisy TV", "", NOTE, "", "| " + " | ".join(head) + " |",
             "|" + "---|" * len(head)]  # fmt: skip
    for r in table.itertuples(index=False):
        cells = [r.env, r.method, r.distractor, f"{r.reached} / {r.n}", r.per_seed,
                 f"{fmt(r.mean, '.1f')} ± {fmt(r.se, '.1f')}", fmt(r.median, ".1f"), fmt(r.welch_p, ".3g"),
                 "–" if math.isnan(r.tv_rate) else f"{r.tv_rate:.3f} ± {fmt(r.tv_rate_se, '.3f')}"]  # fmt: skip
        lines.append("| " + " | ".join(str(c) for c in cells) + " |")
    return "\n".join(lines) + "\n"


def write_distractor_table(runs: pd.DataFrame, out: Path) -> bool:
    """``distractor.{md,csv}`` into ``out`` when some run had a distractor; returns whether they were written."""
    table = distractor_table(runs)
    if table.empty:
        return False
    (out / "distractor.md").write_text(to_markdown(table))
    table.to_csv(out / "distractor.csv", index=False, float_format="%.6g", lineterminator="\n")
    return True
