"""``analysis.heatmap``: the grid, the frame stacks' histories, and the command on a short real MountainCar run."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from analysis.heatmap import history, plane
from tests.conftest import run_cli
from tests.test_analysis import analysis


def test_the_grid_and_the_histories_integrated_backwards() -> None:
    grid = plane("mountaincar", 5)
    assert grid.physical.shape == (25, 2) and grid.xs[0] == -1.2 and grid.ys[-1] == 0.07
    assert grid.physical[1].tolist() == [grid.xs[1], grid.ys[0]]  # x varies fastest (image rows are velocities)
    states = history("mountaincar", np.array([-0.5, 0.25]), 4)
    assert [s[0] for s in states] == pytest.approx([-1.2, -1.0, -0.75, -0.5])  # x − 3v clipped to the track's end
    assert all(s[1] == 0.25 for s in states)
    acrobot = plane("acrobot", 3)
    assert acrobot.physical.shape == (9, 4) and not acrobot.physical[:, 2:].any()  # zero velocity
    assert len({s.tobytes() for s in history("acrobot", acrobot.physical[4], 4)}) == 1


@pytest.mark.slow
def test_the_command_maps_a_trained_run_and_refuses_what_it_cannot(tmp_path: Path) -> None:
    run = tmp_path / "mc"
    res = run_cli(["env=mountaincar", "env.renderer=fast", "budget=smoke", "budget.max_steps=80", f"hydra.run.dir={run}"],
                  cwd=tmp_path)  # fmt: skip
    assert res.returncode == 0, res.stderr
    res = analysis("heatmap", run, "--grid", "6", "--out", tmp_path / "map")
    assert res.returncode == 0, res.stderr
    with Image.open(tmp_path / "map" / "heatmap.png") as im:
        im.verify()
    assert (tmp_path / "map" / "heatmap.pdf").stat().st_size > 0
    random = tmp_path / "random"
    args = ["baseline=random", "budget=smoke", "budget.max_steps=70", "env.renderer=fast", f"hydra.run.dir={random}"]
    assert run_cli(args, cwd=tmp_path).returncode == 0
    for bad in (random, tmp_path / "missing", tmp_path):
        res = analysis("heatmap", bad)
        assert res.returncode != 0 and res.stderr.startswith("error: ") and len(res.stderr.splitlines()) == 1, res.stderr
