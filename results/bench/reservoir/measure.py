import json, sys, time
import torch
torch.set_num_threads(1)
from curiosity.config import setup; setup()
from runners.benchmark.components import planning_at
out = {}
for n in [1_000, 10_000, 100_000]:
    for size in [0, 1024, 4096]:
        ov = [] if size == 0 else ["memory_mode=reservoir", f"memory_size={size}"]
        t = time.time()
        r = planning_at(n, repeats=10, overrides=ov)
        r["seconds"] = time.time() - t
        out[f"{n}/{size}"] = r
        print(n, size, r, flush=True)
        json.dump(out, open(sys.argv[1], "w"), indent=1)
