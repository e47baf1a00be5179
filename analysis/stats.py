"""Statistics of one table row, all from ``scipy.stats``: mean ± standard error, median, IQM with a stratified-bootstrap
95 % CI, and Welch's t-test against a reference row; a percentile-bootstrap CI of any statistic over seeds
(:func:`bootstrap_ci`) and the paired bootstrap upper bound of a ratio of means (:func:`ratio_upper_bound`: the
cheap-seed study's non-inferiority test, ``results/cheap_seed/README.md``).

Every statistic is over the row's seeds with a censored run counted at its last step (the paper's Table 2 rule),
except ``mean_success``/``se_success``, which use the seeds that reached the goal only. SE = sample SD (ddof = 1)/√n.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence

import numpy as np
import pandas as pd
from scipy import stats

BOOTSTRAP_SEED = 0  # fixed: the tables are byte-for-byte the same on every re-run
BOOTSTRAP_RESAMPLES = 2000
NAN = float("nan")


def mean_se(x: Sequence[float]) -> tuple[float, float]:
    """Mean and standard error (ddof = 1) of x (n,); SE is NaN below 2 values, both NaN for none."""
    a = np.asarray(x, dtype=float)
    if a.size == 0:
        return NAN, NAN
    return float(np.mean(a)), float(stats.sem(a, ddof=1)) if a.size > 1 else NAN


def iqm(x: np.ndarray, axis: int = -1) -> np.ndarray:
    """Interquartile mean: the mean of the middle 50 % (``scipy.stats.trim_mean`` cutting 25 % at each end)."""
    return stats.trim_mean(x, 0.25, axis=axis)


def iqm_ci(strata: Sequence[Sequence[float]], seed: int = BOOTSTRAP_SEED) -> tuple[float, float, float]:
    """IQM of all values and its 95 % percentile-bootstrap CI, resampling seeds within each stratum (a pooled row's
    variants), ``BOOTSTRAP_RESAMPLES`` times with a fixed seed. The CI is NaN when a stratum has fewer than 2 values."""
    groups = [np.asarray(s, dtype=float) for s in strata if len(s)]
    point = float(iqm(np.concatenate(groups))) if groups else NAN
    if not groups or min(g.size for g in groups) < 2:
        return point, NAN, NAN

    def statistic(*samples: np.ndarray, axis: int = -1) -> np.ndarray:
        return iqm(np.concatenate(samples, axis=axis), axis=axis)

    res = stats.bootstrap(tuple(groups), statistic, n_resamples=BOOTSTRAP_RESAMPLES, confidence_level=0.95,
                          method="percentile", vectorized=True, rng=np.random.default_rng(seed))  # fmt: skip
    return point, float(res.confidence_interval.low), float(res.confidence_interval.high)


def welch_p(x: Sequence[float], reference: Sequence[float]) -> float:
    """Two-sided p-value of Welch's t-test (``ttest_ind(equal_var=False)``); NaN below 2 values on either side or when
    both samples are constant.

    One constant side is a real case (a row whose every run stopped at the cap): its variance is exactly 0 and the
    test uses the other side's, so scipy's warning about identical data ("precision loss ... catastrophic
    cancellation") says nothing about this p-value and is not shown."""
    a, b = np.asarray(x, dtype=float), np.asarray(reference, dtype=float)
    if a.size < 2 or b.size < 2:
        return NAN
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Precision loss occurred in moment calculation", category=RuntimeWarning)
        p = float(stats.ttest_ind(a, b, equal_var=False).pvalue)
    return p if not math.isnan(p) else NAN


def bootstrap_ci(x: Sequence[float], statistic: Callable[..., np.ndarray], level: float = 0.95,
                 seed: int = BOOTSTRAP_SEED) -> tuple[float, float]:  # fmt: skip
    """Percentile-bootstrap CI of ``statistic`` (a vectorised numpy reduction taking ``axis``, e.g. ``np.median``) over
    the values of ``x`` (seeds), ``BOOTSTRAP_RESAMPLES`` resamples with a fixed seed; NaN below 2 values."""
    a = np.asarray(x, dtype=float)
    if a.size < 2:
        return NAN, NAN
    res = stats.bootstrap((a,), statistic, n_resamples=BOOTSTRAP_RESAMPLES, confidence_level=level, method="percentile",
                          vectorized=True, rng=np.random.default_rng(seed))  # fmt: skip
    return float(res.confidence_interval.low), float(res.confidence_interval.high)


def ratio_upper_bound(new: Sequence[float], ref: Sequence[float], level: float = 0.9, resamples: int = 10_000,
                      seed: int = 0) -> tuple[float, float]:  # fmt: skip
    """mean(new) / mean(ref) of paired values (``new[i]`` and ``ref[i]`` are one seed's two runs) and its one-sided
    ``level`` paired-bootstrap upper bound: the seeds resampled with replacement ``resamples`` times
    (``numpy.random.default_rng(seed).integers``, one (resamples, n) draw; a drawn seed brings both of its values), the
    ratio of the two means recomputed on each resample, the bound being the ``level`` percentile of those ratios
    (``numpy.percentile``, linear interpolation). Both NaN for no pair; raises ValueError for unequal lengths."""
    a, b = np.asarray(new, dtype=float), np.asarray(ref, dtype=float)
    if a.shape != b.shape or a.ndim != 1:
        raise ValueError(f"ratio_upper_bound: paired 1-d arrays expected, got shapes {a.shape} and {b.shape}")
    if a.size == 0:
        return NAN, NAN
    idx = np.random.default_rng(seed).integers(0, a.size, size=(resamples, a.size))
    ratios = a[idx].mean(axis=1) / b[idx].mean(axis=1)
    return float(a.mean() / b.mean()), float(np.percentile(ratios, 100 * level))


def per_seed_text(g: pd.DataFrame) -> str:
    """Every run's steps-to-goal in ``g``'s order, a censored run as ``>last``."""
    return " ".join(f">{int(s)}" if c else str(int(s)) for s, c in zip(g["steps"], g["censored"], strict=True))
