"""Why a 2-worker sweep is not 2x a 1-worker one (issue 13, target 5): one budget=smoke run alone vs two at once
(process wall time and the run's own wall_seconds, i.e. start-up vs running), and a pure compute loop alone vs two at
once (what the two cores give any pair of processes). On an idle machine, from the repository root:

    python -m studies.bench.sweep_profile OUT.json

(``results/bench/sweep_profile/profile.json``, ``docs/benchmarks.md``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ENV = {**os.environ, "OMP_NUM_THREADS": "1", "SDL_VIDEODRIVER": "dummy"}
LOOP = (
    "import torch,time; torch.set_num_threads(1); a=torch.randn(256,256); t=time.perf_counter()\n"
    "for _ in range(4000): a=torch.tanh(a@a*0.01)\nprint(time.perf_counter()-t)"
)


def run(cmds: list[list[str]]) -> list[tuple[float, str]]:
    """Start every command at once; (process wall seconds, stdout) of each."""
    start = time.perf_counter()
    procs = [subprocess.Popen(c, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True) for c in cmds]
    out = []
    for p in procs:
        text, _ = p.communicate()
        out.append((time.perf_counter() - start, text))
    return out


def smoke(seed: int, root: Path) -> list[str]:
    return [
        sys.executable,
        "-m",
        "runners.train",
        f"seed={seed}",
        "budget=smoke",
        "progress=false",
        "threads=1",
        f"hydra.run.dir={root}/seed_{seed}",
    ]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.bench.sweep_profile", description=__doc__.splitlines()[0])
    parser.add_argument("out", help="JSON file of the timings")
    path = parser.parse_args(argv).out
    res: dict = {}
    res["compute_alone_s"] = [float(t) for _, t in run([[sys.executable, "-c", LOOP]])]
    res["compute_pair_s"] = [float(t) for _, t in run([[sys.executable, "-c", LOOP]] * 2)]
    with tempfile.TemporaryDirectory() as tmp:
        for name, seeds in (("smoke_alone", [0]), ("smoke_pair", [0, 1])):
            root = Path(tmp) / name
            walls = [w for w, _ in run([smoke(s, root) for s in seeds])]
            inner = [json.loads((root / f"seed_{s}" / "summary.json").read_text())["wall_seconds"] for s in seeds]
            res[name] = {"process_wall_s": walls, "run_wall_s": inner}
    res["import_s"] = float(
        subprocess.run(
            [
                sys.executable,
                "-c",
                "import time; t=time.perf_counter(); import torch, "
                "gymnasium, runners.train, curiosity.agents.paper; print(time.perf_counter()-t)",
            ],
            env=ENV,
            capture_output=True,
            text=True,
        ).stdout
    )
    print(json.dumps(res, indent=1))
    Path(path).write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
