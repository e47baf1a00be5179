"""Planning, refresh and log rho error of the exact memory and of reservoirs of 1,024 and 4,096 rows at memories of
10^3, 10^4 and 10^5 random-policy steps. Usage, from the repository root: python results/bench/reservoir/measure.py OUT.json
"""

import json
import sys
import time

import torch

from curiosity.config import setup
from runners.benchmark.components import planning_at

torch.set_num_threads(1)
setup()
out = {}
for n in [1_000, 10_000, 100_000]:
    for size in [0, 1024, 4096]:
        overrides = [] if size == 0 else ["memory_mode=reservoir", f"memory_size={size}"]
        start = time.time()
        row = planning_at(n, repeats=10, overrides=overrides)
        row["seconds"] = time.time() - start
        out[f"{n}/{size}"] = row
        print(n, size, row, flush=True)
        with open(sys.argv[1], "w") as f:
            json.dump(out, f, indent=1)
