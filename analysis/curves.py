"""Per-row curves from ``metrics.csv``: each run's column on the env-step grid, the mean over seeds with a 95 %
bootstrap band, and the step at which a run's intrinsic reward becomes "stable".

Stable (Figure 7 analogue): the rolling coefficient of variation |SD / mean| of the logged intrinsic reward over
``STABLE_WINDOW`` consecutive rows (``log_every`` env steps each) falls below ``STABLE_CV``; the stable step is the last
step of the first such window.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from analysis.stats import BOOTSTRAP_SEED

BAND_RESAMPLES = 1000
STABLE_WINDOW = 20
STABLE_CV = 0.1


@dataclass
class Curve:
    """Mean of a column over a row's seeds on steps x (T,), with its 95 % bootstrap band (NaN below 2 seeds)."""

    x: np.ndarray
    mean: np.ndarray
    low: np.ndarray
    high: np.ndarray
    n: np.ndarray  # seeds present at each step


def per_run(metrics: pd.DataFrame, column: str, x: str = "step", fill_forward: bool = False) -> pd.DataFrame:
    """The column as a (steps, runs) table: one column per ``run_dir``; with ``fill_forward`` a run's last value is
    carried on after it ended (a cumulative quantity such as coverage)."""
    if column not in metrics:
        return pd.DataFrame()
    wide = metrics.dropna(subset=[column]).pivot_table(index=x, columns="run_dir", values=column, aggfunc="last")
    return wide.ffill() if fill_forward else wide


def mean_band(wide: pd.DataFrame, seed: int = BOOTSTRAP_SEED) -> Curve:
    """Mean over the runs present at each step and a percentile-bootstrap 95 % CI of that mean (``BAND_RESAMPLES``
    resamples, fixed seed), computed block by block of steps where the same runs are present."""
    values = wide.to_numpy(dtype=float)  # (T, runs)
    present = ~np.isnan(values)
    n = present.sum(axis=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # steps no run reached: mean of nothing -> NaN
        mean = np.nanmean(values, axis=1)
    low, high = np.full_like(mean, np.nan), np.full_like(mean, np.nan)
    for mask in {tuple(m) for m in present}:
        if sum(mask) < 2:
            continue
        rows = np.all(present == np.array(mask), axis=1)
        block = values[rows][:, np.array(mask)].T  # (runs present, steps in block)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a step where every run has the same value: a degenerate interval
            ci = stats.bootstrap((block,), np.mean, axis=0, n_resamples=BAND_RESAMPLES, method="percentile",
                                 rng=np.random.default_rng(seed)).confidence_interval  # fmt: skip
        low[rows], high[rows] = ci.low, ci.high
    return Curve(x=wide.index.to_numpy(dtype=float), mean=mean, low=low, high=high, n=n)


def stable_step(steps: np.ndarray, reward: np.ndarray, window: int = STABLE_WINDOW, cv: float = STABLE_CV) -> float:
    """The first env step at which the rolling |SD / mean| (ddof = 1) of ``reward`` (T,) over ``window`` rows is below
    ``cv``; NaN if it never is."""
    s = pd.Series(reward, dtype=float)
    roll = s.rolling(window)
    ratio = (roll.std(ddof=1) / roll.mean().abs()).to_numpy()
    hit = np.flatnonzero(ratio < cv)
    return float(steps[hit[0]]) if hit.size else float("nan")


def training_iterations(run: pd.DataFrame) -> pd.Series:
    """Cumulative training iterations at each logged row of one run: ``train/iterations`` (the window's mean per env
    step) times the env steps since the previous row, summed."""
    per_step = run["train/iterations"].fillna(0.0) if "train/iterations" in run else pd.Series(0.0, index=run.index)
    return (per_step * row_spans(run["step"].to_numpy(dtype=float))).cumsum()


def row_spans(steps: np.ndarray, warmup_steps: int = 0) -> np.ndarray:
    """The env steps each logged row's window covers (T,): since the previous row's step (T,), or since the end of the
    ``warmup_steps`` random steps, whichever is later (the first row: since step 0)."""
    return steps - np.maximum(np.r_[0.0, steps[:-1]], warmup_steps)


def running_rate(run: pd.DataFrame, column: str, warmup_steps: int = 0) -> pd.Series:
    """One run's running mean of a per-step 0/1 column (e.g. ``behaviour/tv``) logged as window means: at each row
    that logs it, the mean over every agent step so far. A row's window is the env steps since the previous row (or
    since the ``warmup_steps`` random steps, which log no behaviour); rows written twice (a resumed run) count once,
    the last. The last value is the run's total rate (``summary.json``'s ``behaviour.tv_rate`` for ``behaviour/tv``).

    Args:
        run: one run's ``metrics.csv`` rows, with ``step`` and ``column``.
    Returns:
        the running rate indexed by env step (rows without ``column`` left out).
    """
    rows = run.drop_duplicates("step", keep="last").sort_values("step")
    covered = row_spans(rows["step"].to_numpy(dtype=float), warmup_steps)
    value = rows[column].to_numpy(dtype=float) if column in rows else np.full(covered.size, np.nan)
    logged = ~np.isnan(value)
    rate = np.cumsum(value[logged] * covered[logged]) / np.cumsum(covered[logged])
    return pd.Series(rate, index=rows["step"].to_numpy()[logged], name=column)
