"""How many seeds a non-inferiority rule needs: two points' per-seed steps-to-goal, the ratio of their means, its
paired-bootstrap bound (as ``analysis.cost``), the bootstrap SE of the ratio, the seeds' correlation between the two
points, and how many seeds per point the bound would need to reach the margin at a few true ratios.

    python -m studies.power REFERENCE_DIR POINT_DIR [--margin 1.10] [--level 0.9]

Each directory holds one run per seed (``seed=<n>/summary.json``); a run that did not reach the goal counts at its
cap. The seeds needed are a normal approximation from the SE at the shared seeds (SE ∝ 1/√n):
n = n₀ · (z · SE / (margin − ratio))², z the ``level`` quantile of the standard normal.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from scipy import stats

from analysis.stats import ratio_upper_bound

TRUE_RATIOS = (1.0, 0.95, 0.9)


def steps_by_seed(directory: Path) -> dict[int, float]:
    """seed -> steps-to-goal (the cap for a run that did not reach it) of the finished runs in ``directory``."""
    out = {}
    for summary in sorted(directory.glob("seed=*/summary.json")):
        s = json.loads(summary.read_text())
        out[int(summary.parent.name.split("=", 1)[1])] = float(s["steps_to_goal"] or s["max_steps"])
    return out


def ratio_se(new: np.ndarray, ref: np.ndarray, resamples: int = 10_000, seed: int = 0) -> float:
    """The bootstrap SE of mean(new) / mean(ref) over paired seeds (the resamples of ``ratio_upper_bound``)."""
    idx = np.random.default_rng(seed).integers(0, new.size, size=(resamples, new.size))
    return float((new[idx].mean(axis=1) / ref[idx].mean(axis=1)).std())


def seeds_needed(se: float, n: int, margin: float, ratio: float, level: float = 0.9) -> float:
    """Seeds per point at which the one-sided ``level`` bound of a true ``ratio`` sits at ``margin`` on average, given
    the ratio's SE ``se`` at ``n`` seeds; inf when ``ratio`` ≥ ``margin``."""
    if ratio >= margin:
        return float("inf")
    return n * (float(stats.norm.ppf(level)) * se / (margin - ratio)) ** 2


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m studies.power", description=__doc__.splitlines()[0])
    parser.add_argument("reference", type=Path, help="the reference point's directory (seed=<n>/summary.json)")
    parser.add_argument("point", type=Path, help="the compared point's directory")
    parser.add_argument("--margin", type=float, default=1.10, help="the non-inferiority margin (default 1.10)")
    parser.add_argument("--level", type=float, default=0.9, help="the one-sided bound's level (default 0.9)")
    args = parser.parse_args(argv)
    ref, new = steps_by_seed(args.reference), steps_by_seed(args.point)
    seeds = sorted(set(ref) & set(new))
    if len(seeds) < 3:
        print(f"error: {len(seeds)} seeds shared by {args.reference} and {args.point}; at least 3 needed")
        return 2
    a, b = np.array([new[s] for s in seeds]), np.array([ref[s] for s in seeds])
    ratio, bound = ratio_upper_bound(a, b, level=args.level)
    se = ratio_se(a, b)
    print(f"shared seeds {len(seeds)}; ratio of means {ratio:.3f}; {args.level:.0%} bound {bound:.3f}; bootstrap SE "
          f"{se:.3f}; correlation of the two points over seeds {np.corrcoef(a, b)[0, 1]:+.2f}")  # fmt: skip
    for true in TRUE_RATIOS:
        print(f"true ratio {true}: about {seeds_needed(se, len(seeds), args.margin, true, args.level):.0f} seeds per "
              f"point for the bound to reach {args.margin}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
