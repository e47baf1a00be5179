"""The tables behind Figures 6 and 7: per row, a curve's value where the claim looks, tested against a reference row.

- ``spread``: the common yardstick of how far the next latents are spread, ``info/latent_logdet`` (log det of their
  covariance + 1e-3 I; every entropy regulariser is logged on it), at fixed env steps ``SPREAD_STEPS``: Figure 6's
  "spreads s_{t+1} faster" is a larger value early. A run's value at a step is its last row at or before it; a run that
  ended before the step is not counted there.
- ``stable_step``: the env step at which a run's intrinsic reward becomes stable (``analysis.curves.stable_step``):
  Figure 7's "KDE reaches a stable intrinsic reward in fewer steps" is a smaller value. A run whose reward never
  settles is counted at its last step (like a censored steps-to-goal) and shown as ``>last``.

Each row: seeds, every seed's value, mean ± SE (ddof = 1), median, and Welch's p against the rows matching the
reference glob of the same env (``analysis.stats``).
"""

from __future__ import annotations

import fnmatch
import math
from collections.abc import Iterator

import numpy as np
import pandas as pd

from analysis.curves import stable_step
from analysis.stats import mean_se, welch_p

YARDSTICK = "info/latent_logdet"
SPREAD_STEPS = (100, 200, 300)


def _value_at(run: pd.DataFrame, column: str, step: int) -> float:
    """The run's last logged ``column`` at or before ``step``; NaN if it ended earlier or logged nothing by then."""
    if run["step"].max() < step:
        return math.nan
    logged = run[(run["step"] <= step)].dropna(subset=[column])
    return float(logged[column].iloc[-1]) if len(logged) else math.nan


def fmt(x: float, spec: str = ".2f") -> str:
    """``x`` formatted with ``spec``, or – for NaN."""
    return "–" if math.isnan(x) else format(x, spec)


def _row_stats(values: list[float], reference: list[float], is_reference: bool) -> dict[str, float]:
    mean, se = mean_se(values)
    return {"n": len(values), "mean": mean, "se": se, "median": float(np.median(values)) if values else math.nan,
            "welch_p": math.nan if is_reference else welch_p(values, reference)}  # fmt: skip


def _by_row(at: pd.DataFrame, reference: str) -> Iterator[tuple[str, str, pd.DataFrame, dict[str, float]]]:
    """(env, row, its runs, their statistics against the reference rows of the env) for the runs ``at`` (column ``v``)."""
    is_ref = at["row"].map(lambda r: fnmatch.fnmatchcase(r, reference))
    for (env, row), g in at.groupby(["env", "row"], sort=True):
        ref = at[(at["env"] == env) & is_ref]["v"].tolist()
        yield env, row, g, _row_stats(g["v"].tolist(), ref, fnmatch.fnmatchcase(row, reference))


def spread_table(metrics: pd.DataFrame, reference: str, steps: tuple[int, ...] = SPREAD_STEPS) -> pd.DataFrame:
    """One line per (env, row, step) for the runs that log ``YARDSTICK``; empty when none does."""
    if YARDSTICK not in metrics or metrics[YARDSTICK].isna().all():
        return pd.DataFrame()
    per_run = metrics.groupby("run_dir", sort=True)
    first = per_run[["env", "row"]].first()
    out = []
    for step in steps:
        values = pd.Series({d: _value_at(g, YARDSTICK, step) for d, g in per_run}).rename("v")
        for env, row, g, stats in _by_row(first.join(values).dropna(subset=["v"]), reference):
            out.append({"env": env, "row": row, "step": step, "per_seed": " ".join(f"{v:.2f}" for v in g["v"]),
                        **stats})  # fmt: skip
    return pd.DataFrame(out)


def stable_table(metrics: pd.DataFrame, reference: str) -> pd.DataFrame:
    """One line per (env, row) for the runs that log ``intrinsic/reward``; empty when none does."""
    if "intrinsic/reward" not in metrics:
        return pd.DataFrame()
    runs = []
    for _, g in metrics.groupby("run_dir", sort=True):
        g = g.dropna(subset=["intrinsic/reward"])
        if len(g):
            s, last = stable_step(g["step"].to_numpy(), g["intrinsic/reward"].to_numpy()), float(g["step"].iloc[-1])
            runs.append({"env": g["env"].iloc[0], "row": g["row"].iloc[0], "stable": not math.isnan(s),
                         "v": last if math.isnan(s) else s})  # fmt: skip
    if not runs:
        return pd.DataFrame()
    out = []
    for env, row, g, stats in _by_row(pd.DataFrame(runs), reference):
        per_seed = " ".join(f"{v:.0f}" if ok else f">{v:.0f}" for v, ok in zip(g["v"], g["stable"], strict=True))
        out.append({"env": env, "row": row, "stable": int(g["stable"].sum()), "per_seed": per_seed, **stats})
    return pd.DataFrame(out)


def to_markdown(table: pd.DataFrame, title: str, what: str, reference: str) -> str:
    """``table`` (from :func:`spread_table` or :func:`stable_table`) as a Markdown section."""
    step = "step" in table
    head = ["env", "row", *(["env step"] if step else ["stable / seeds"]), "per seed", "mean ± SE", "median", "Welch p"]
    lines = [f"## {title}", "", what.format(reference=reference), "", "| " + " | ".join(head) + " |",
             "|" + "---|" * len(head)]  # fmt: skip
    for r in table.itertuples(index=False):
        first = [str(r.step)] if step else [f"{r.stable} / {r.n}"]
        cells = [r.env, r.row, *first, r.per_seed, f"{fmt(r.mean)} ± {fmt(r.se)}", fmt(r.median), fmt(r.welch_p, ".3g")]
        lines.append("| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |")
    return "\n".join(lines) + "\n"


SPREAD_NOTE = (f"`{YARDSTICK}` (log det of the next latents' covariance + 1e-3 I, the same yardstick for every "
               "objective) at fixed env steps, each run's last logged value at or before the step (runs that ended "
               "earlier are not counted there); larger = more spread. Welch p against `{reference}`.")  # fmt: skip
STABLE_NOTE = ("The env step at which the intrinsic reward becomes stable (rolling |SD / mean| over 20 logged rows "
               "below 0.1, `analysis.curves`); a run whose reward never settles counts at its last step (`>last`). "
               "Smaller = stable sooner. Welch p against `{reference}`.")  # fmt: skip
