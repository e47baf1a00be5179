"""How deep one env step of the default agent goes: followed from the loop (``runtime/loop.py:_Run._step``), every chain
of calls enters each file of ``curiosity/`` at most twice (a file is *entered* when a call moves into it from another
file; calls within a file, and frames outside ``curiosity/`` such as torch's, do not count). So a call chain goes down
the layers with at most one call back (a planner calling the model it was handed, ...), never back and forth."""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path
from types import FrameType
from typing import Any

from tests.conftest import REPO, compose_cfg

PACKAGE = str(REPO / "curiosity") + "/"
LOOP = str(REPO / "curiosity" / "runtime" / "loop.py")
MOST = 2


def _entries(chain: list[str]) -> Counter[str]:
    """How many times a chain of files (outermost first, non-package frames removed) enters each file."""
    out: Counter[str] = Counter()
    previous = None
    for file in chain:
        if file != previous:
            out[file] += 1
        previous = file
    return out


class CallChains:
    """A profiler hook: for every call into ``curiosity/`` below the traced ``_step``, the entries of its call chain;
    keeps each file's worst chain."""

    def __init__(self) -> None:
        self.worst: dict[str, tuple[int, list[str]]] = {}

    def __call__(self, frame: FrameType, event: str, arg: Any) -> None:
        if event != "call" or not frame.f_code.co_filename.startswith(PACKAGE):
            return
        chain: list[str] = []
        f: FrameType | None = frame
        while f is not None:
            name = f.f_code.co_filename
            if name.startswith(PACKAGE):
                chain.append(name)
            if name == LOOP and f.f_code.co_name == "_step":
                break
            f = f.f_back
        if f is None:
            return  # not below the traced step
        chain.reverse()
        for file, n in _entries(chain).items():
            if n > self.worst.get(file, (0, []))[0]:
                self.worst[file] = (n, [str(Path(c).relative_to(PACKAGE)) for c in chain])


def test_the_entry_count_counts_moves_into_a_file_not_calls_within_it() -> None:
    assert _entries(["a", "a", "b", "b", "c"]) == Counter({"a": 1, "b": 1, "c": 1})
    assert _entries(["a", "b", "a", "b", "a"]) == Counter({"a": 3, "b": 2})


def test_one_env_step_of_the_default_agent_enters_each_file_at_most_twice(tmp_path: Path, one_thread) -> None:
    """The default agent (pixels, MPC, KDE novelty, the probe on) over steps that plan, probe, train and refresh."""
    from curiosity.runtime.loop import _Run

    warmup = 8
    cfg = compose_cfg(["budget=smoke", f"budget.warmup_steps={warmup}", "agent.probe_every=20", "progress=false"])
    run = _Run(cfg, tmp_path, None)
    for _ in range(warmup):
        run._step()
        run.step += 1
    chains = CallChains()
    for traced in [True, *[False] * 8, True]:  # the first agent step plans, probes and trains; the tenth refreshes
        sys.setprofile(chains if traced else None)
        try:
            run._step()
        finally:
            sys.setprofile(None)
        run.step += 1
    assert "agents/paper.py" in {str(Path(f).relative_to(PACKAGE)) for f in chains.worst}
    over = {str(Path(f).relative_to(PACKAGE)): (n, " -> ".join(chain)) for f, (n, chain) in chains.worst.items() if n > MOST}
    assert not over, f"files entered more than {MOST} times along one call chain: {over}"
