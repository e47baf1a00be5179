"""Statistics of one table row, all from ``scipy.stats``: mean ± standard error, median, IQM with a stratified-bootstrap
95 % CI, and Welch's t-test against a reference row.

Every statistic is over the row's seeds with a censored run counted at its last step (the paper's Table 2 rule),
except ``mean_success``/``se_success``, which use the seeds that reached the goal only. SE = sample SD (ddof = 1)/√n.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np
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
