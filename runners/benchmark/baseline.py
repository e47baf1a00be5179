"""Training-iteration speed of another commit, measured side by side with this tree (``--baseline-commit``).

Both trees run the same small script in a fresh process (the commit's own code, through a temporary ``git worktree``),
alternately, so a change of machine load hits both; the speed-up is the ratio of the medians over rounds. Twice:

- ``speedup``: each tree as its runs train, with the allocator setting a run of that tree makes (this tree's
  ``keep_freed_memory``; none at an older commit);
- ``speedup_same_allocator``: both with the same fixed glibc thresholds, so only the code of the iteration differs.
"""

from __future__ import annotations

import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

from curiosity.runtime.allocator import MMAP_THRESHOLD

REPO = Path(__file__).resolve().parents[2]

# uses only APIs every commit of the project has had: compose_config, build, make_env, replay.add, agent._iteration;
# the allocator setting a run makes, where the tree has one (curiosity/runtime/allocator.py)
SCRIPT = """
import json, sys, time, statistics
import numpy as np, torch
try:
    from curiosity.runtime.allocator import keep_freed_memory
except ImportError:  # a tree from before it: its runs did not set it
    pass
else:
    keep_freed_memory()
from curiosity.config import build
from curiosity.config.compose import compose_config
from curiosity.envs import make_env
batch, repeats, threads = (int(v) for v in sys.argv[1:4])
torch.set_num_threads(threads)
torch.manual_seed(0)
key = "agent.batch_size" if "agent" in compose_config([]) else "batch_size"  # the key's place in this tree
cfg = compose_config(["env.renderer=fast", f"{key}={batch}"])
env = make_env(cfg.env, 1000)
agent = build(cfg.baseline, cfg=cfg)
obs, _ = env.reset(seed=0)
rng = np.random.default_rng(0)
for _ in range(500):
    a = int(rng.integers(3))
    nxt, r, term, _, _ = env.step(a)
    agent.replay.add(obs, a, r, nxt, term)
    obs = nxt
agent.model.train()
times = []
for i in range(repeats + 2):
    start = time.perf_counter()
    agent._iteration()
    if i >= 2:
        times.append(1e3 * (time.perf_counter() - start))
print(json.dumps(statistics.median(times)))
"""


# The same fixed thresholds for both trees (what keep_freed_memory sets; an environment's setting takes precedence).
SAME_ALLOCATOR = {"MALLOC_MMAP_THRESHOLD_": str(MMAP_THRESHOLD), "MALLOC_TRIM_THRESHOLD_": str(2 * MMAP_THRESHOLD)}


def _iteration_ms(tree: Path, batch: int, repeats: int, threads: int, extra_env: dict[str, str]) -> float:
    env = {**os.environ, "PYTHONPATH": str(tree), "OMP_NUM_THREADS": str(threads), "SDL_VIDEODRIVER": "dummy",
           **extra_env}  # fmt: skip
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(batch), str(repeats), str(threads)], cwd=tree, env=env,
                          capture_output=True, text=True, check=False)  # fmt: skip
    if done.returncode:
        raise RuntimeError(f"timing the training iteration in {tree} failed:\n{done.stderr[-2000:]}")
    return float(json.loads(done.stdout.strip().splitlines()[-1]))


@contextlib.contextmanager
def worktree(commit: str, name: str = "baseline") -> Iterator[Path]:
    """A temporary ``git worktree`` of ``commit`` (detached), removed on exit; its directory is named
    ``<name>-<pid>`` (git names the worktree after it: unique per process). A commit git does not know raises
    ``ValueError`` with git's one line."""
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / f"{name}-{os.getpid()}"
        done = subprocess.run(["git", "worktree", "add", "--detach", str(tree), commit], cwd=REPO, check=False,
                              capture_output=True, text=True)  # fmt: skip
        if done.returncode:
            last = (done.stderr.strip().splitlines() or ["git worktree add failed"])[-1]
            raise ValueError(f"commit {commit!r}: {last}")
        try:
            yield tree
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=REPO, check=False, capture_output=True)


def speedup_vs(commit: str, batch: int, repeats: int, threads: int, rounds: int = 2) -> dict[str, float | str]:
    """ms per training iteration at ``batch`` here and at ``commit``, alternating ``rounds`` times, each tree with its
    runs' allocator setting and both with the same one; the ratios."""
    with worktree(commit) as tree:
        ours, theirs, ours_same, theirs_same = [], [], [], []
        for _ in range(rounds):
            theirs.append(_iteration_ms(tree, batch, repeats, threads, {}))
            ours.append(_iteration_ms(REPO, batch, repeats, threads, {}))
            theirs_same.append(_iteration_ms(tree, batch, repeats, threads, SAME_ALLOCATOR))
            ours_same.append(_iteration_ms(REPO, batch, repeats, threads, SAME_ALLOCATOR))
    here, there = statistics.median(ours), statistics.median(theirs)
    here_same, there_same = statistics.median(ours_same), statistics.median(theirs_same)
    return {"commit": commit, "batch": batch, "ms": here, "baseline_ms": there, "speedup": there / here,
            "ms_same_allocator": here_same, "baseline_ms_same_allocator": there_same,
            "speedup_same_allocator": there_same / here_same}  # fmt: skip
