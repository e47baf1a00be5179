"""Planning, refresh and log rho error of the exact memory and of reservoirs of 1,024 and 4,096 rows at memories of
10^3, 10^4 and 10^5 random-policy steps.

    python -m studies.bench.reservoir OUT.json

From the repository root (``runners.benchmark.components.planning_at``, 10 timed planning steps each; the exact memory
and ``intrinsic.terms.novelty.memory_mode=reservoir memory_size=1024 | 4096``). OUT.json is rewritten after each
measurement (``results/bench/reservoir/``).
"""

from __future__ import annotations

import argparse
import json
import time

import torch

from curiosity.config import setup
from runners.benchmark.components import planning_at

MEMORIES = (1_000, 10_000, 100_000)
SIZES = (0, 1024, 4096)  # 0: the exact memory


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.bench.reservoir", description=__doc__.splitlines()[0])
    parser.add_argument("out", help="JSON file: '<memory>/<reservoir size>' -> the measurements")
    path = parser.parse_args(argv).out
    torch.set_num_threads(1)
    setup()
    out = {}
    for n in MEMORIES:
        for size in SIZES:
            overrides = [] if size == 0 else ["intrinsic.terms.novelty.memory_mode=reservoir",
                                              f"intrinsic.terms.novelty.memory_size={size}"]  # fmt: skip
            start = time.time()
            row = planning_at(n, repeats=10, overrides=overrides)
            row["seconds"] = time.time() - start
            out[f"{n}/{size}"] = row
            print(n, size, row, flush=True)
            with open(path, "w") as f:
                json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
