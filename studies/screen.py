"""A study's screening rule on a point's first seeds: stop it when too many of them are at the cap or their mean is too
far above its base's over the same seeds (the cheap-seed and oracle-gap studies: seeds 0-14, 3 caps, 1.5x).

    python -m studies.screen POINT_DIR BASE_DIR [--seeds 15] [--caps 3] [--factor 1.5]

Each directory holds one run per seed (``seed=<n>/summary.json``); a run that did not reach the goal counts at its
cap. Prints one line with the verdict; exit 0: go on, 1: stop, 2: a seed of 0 .. seeds-1 has not finished in one of
the two directories.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from studies.power import steps_by_seed


@dataclass(frozen=True)
class Screen:
    """The verdict on seeds 0 .. n-1: how many runs are at the cap, the point's and the base's means."""

    caps: int
    mean: float
    base_mean: float
    stop: bool


def screen(point: dict[int, float], base: dict[int, float], cap: float, seeds: int = 15, max_caps: int = 3,
           factor: float = 1.5) -> Screen:  # fmt: skip
    """Stop when ≥ ``max_caps`` of the point's seeds 0 .. ``seeds``-1 are at ``cap``, or their mean is more than
    ``factor`` × the base's over the same seeds. Raises KeyError naming a seed either lacks."""
    wanted = range(seeds)
    for name, runs in (("point", point), ("base", base)):
        missing = [s for s in wanted if s not in runs]
        if missing:
            raise KeyError(f"the {name} has not finished seeds {missing}")
    steps = np.array([point[s] for s in wanted])
    caps = int((steps >= cap).sum())
    mean, base_mean = float(steps.mean()), float(np.mean([base[s] for s in wanted]))
    return Screen(caps, mean, base_mean, caps >= max_caps or mean > factor * base_mean)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m studies.screen", description=__doc__.splitlines()[0])
    parser.add_argument("point", type=Path, help="the screened point's directory (seed=<n>/summary.json)")
    parser.add_argument("base", type=Path, help="its base's directory")
    parser.add_argument("--seeds", type=int, default=15, help="screen seeds 0 .. seeds-1 (default 15)")
    parser.add_argument("--caps", type=int, default=3, help="stop at this many runs at the cap (default 3)")
    parser.add_argument("--factor", type=float, default=1.5, help="stop above this multiple of the base's mean (1.5)")
    parser.add_argument("--cap", type=float, default=3000, help="the step cap (default 3000)")
    args = parser.parse_args(argv)
    try:
        verdict = screen(steps_by_seed(args.point), steps_by_seed(args.base), args.cap, args.seeds, args.caps, args.factor)
    except KeyError as err:
        print(f"error: {err.args[0]} ({args.point} against {args.base})")
        return 2
    word = "stop" if verdict.stop else "go on"
    print(f"seeds 0-{args.seeds - 1}: {verdict.caps} at the cap; mean {verdict.mean:.1f} against the base's "
          f"{verdict.base_mean:.1f} (x{verdict.mean / verdict.base_mean:.2f}): {word}")  # fmt: skip
    return 1 if verdict.stop else 0


if __name__ == "__main__":
    raise SystemExit(main())
