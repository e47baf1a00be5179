"""The examples under ``examples/`` run as a user runs them: a fresh process, from outside the repository."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

from tests.conftest import REPO


def test_pieces_example_runs_and_prints_what_each_piece_computed(tmp_path: Path) -> None:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "PYTHONPATH": str(REPO)}
    res = subprocess.run([sys.executable, str(REPO / "examples" / "pieces.py")], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=120)  # fmt: skip
    assert res.returncode == 0, res.stdout + res.stderr
    out = res.stdout
    paired, shuffled = map(float, re.search(r"I_0\.99\(z'; \[z, a\]\) = (\S+) bits paired, (\S+) bits", out).groups())
    assert paired > shuffled  # the next latents depend on the pairs they came from
    inside, outside = map(float, re.search(r"KDE reward inside / outside = (\S+) / (\S+)", out).groups())
    assert inside < outside  # a query outside the memory is the more novel
    assert "planner: 27 candidate sequences, chosen [2, 2, 2]" in out  # away from the visited region
    assert out.rstrip().endswith("ok: all three pieces ran")
