"""``python -m studies.early``: early means and their Spearman correlation with steps-to-goal on synthetic run
directories with known numbers (``tests/synthetic_runs.py``: ``behaviour/directed`` = min(step / last step, 1), logged
every 10 steps), against numpy and scipy on the same arrays; refusals in one line with nothing written."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.stats import spearmanr

from studies.early import correlations, early_table, write_early
from tests.conftest import REPO
from tests.synthetic_runs import make_run

# (method, seed, steps-to-goal or None for the 3000-step cap)
RUNS = [("ours", 0, 400), ("ours", 1, 800), ("ours", 2, None), ("ours", 3, 300), ("ours", 4, 150),
        ("nsrs", 0, 500), ("nsrs", 1, 600)]  # fmt: skip


@pytest.fixture
def root(tmp_path: Path) -> Path:
    for method, seed, steps in RUNS:
        make_run(tmp_path / "runs", "acrobot", method, seed, steps)
    make_run(tmp_path / "runs", "acrobot", "ours", 5, None, status="stopped")  # unfinished: not counted
    return tmp_path / "runs"


def early(*args: str | Path, timeout: float = 120) -> subprocess.CompletedProcess:
    """Run ``python -m studies.early ARGS`` from the repository root; ``timeout`` (s) only guards against a hang."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    res = subprocess.run([sys.executable, "-m", "studies.early", *map(str, args)], cwd=REPO, env=env,
                         capture_output=True, text=True, timeout=timeout)  # fmt: skip
    assert "Traceback" not in res.stdout + res.stderr, res.stderr
    return res


def expected_directed(last: int, until: int) -> float:
    step = np.arange(10, last + 1, 10)
    return float(np.clip(step[step <= until] / last, 0, 1).mean())


def test_early_means_and_spearman_against_numpy_and_scipy(root: Path) -> None:
    table = early_table(root, ["behaviour/directed", "behaviour/repeat"], until=200)
    ours = table[table["row"] == "ours"].set_index("seed")
    assert list(ours.index) == [0, 1, 2, 3, 4]  # the stopped run (no summary.json) is left out
    for seed, steps in ((0, 400), (1, 800), (2, 3000), (3, 300), (4, 150)):
        assert ours.loc[seed, "behaviour/directed"] == pytest.approx(expected_directed(steps, 200), rel=1e-12)
        assert ours.loc[seed, "steps"] == steps
    assert ours.loc[2, "censored"] and not ours.loc[0, "censored"]
    assert list(ours["whole_run"]) == [False, False, False, False, True]  # seed 4 reached the goal at step 150

    corr = correlations(table, ["behaviour/directed", "behaviour/repeat"]).set_index(["row", "column"])
    want = spearmanr(ours["behaviour/directed"], ours["steps"])
    assert corr.loc[("ours", "behaviour/directed"), "rho"] == pytest.approx(want.statistic, abs=1e-12)
    assert corr.loc[("ours", "behaviour/directed"), "p"] == pytest.approx(want.pvalue, rel=1e-9)
    # the more directed early (seed 4: its whole run to step 150, mean 0.533), the sooner the goal, on every seed
    assert want.statistic == pytest.approx(-1.0, abs=1e-12)
    assert np.isnan(corr.loc[("ours", "behaviour/repeat"), "rho"])  # a constant column has no rank correlation
    assert corr.loc[("nsrs", "behaviour/directed"), "n"] == 2 and np.isnan(corr.loc[("nsrs", "behaviour/directed"), "rho"])


def test_the_command_writes_the_tables_and_rewrites_the_same_bytes(root: Path, tmp_path: Path) -> None:
    res = early(root, "--out", tmp_path / "a", "--until", "200", "--columns", "behaviour/directed")
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == f"2 correlation(s) written to {tmp_path / 'a'}/early.{{md,csv}}"
    csv = pd.read_csv(tmp_path / "a" / "early.csv")
    assert len(csv) == 7 and set(csv["row"]) == {"ours", "nsrs"}
    assert "| acrobot | ours | 4 | 150 * |" in (tmp_path / "a" / "early.md").read_text()
    write_early(root, tmp_path / "b", ["behaviour/directed"], 200)
    for name in ("early.md", "early.csv"):  # exact: the same files read twice on one machine
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_default_columns_no_run_logs_are_left_out(root: Path, tmp_path: Path) -> None:
    res = early(root, "--out", tmp_path)  # the synthetic runs log no probe/spearman
    assert res.returncode == 0, res.stderr
    header = pd.read_csv(tmp_path / "early.csv", nrows=0).columns
    assert "behaviour/directed" in header and "probe/spearman" not in header


@pytest.mark.parametrize(("args", "key"), [
    (["--columns", "no/such_column"], "--columns no/such_column"),
    (["--columns", "behaviour/directed,behaviour/direct"], "--columns behaviour/direct"),  # a typo beside a real one
    (["--until", "ten"], "--until ten"), (["--until", "0"], "--until 0")])  # fmt: skip
def test_bad_input_is_one_line_and_writes_nothing(root: Path, tmp_path: Path, args: list[str], key: str) -> None:
    res = early(root, "--out", tmp_path / "out", *args)
    assert res.returncode == 1 and res.stderr.startswith(f"error: {key}: ") and len(res.stderr.splitlines()) == 1
    assert "allowed" in res.stderr and not (tmp_path / "out").exists()


def test_an_included_run_is_named_relative_to_the_directory(tmp_path: Path) -> None:
    """A run another preset made (``include`` in ``analysis.yaml``) is listed by its path from the directory, so the
    committed CSV names no machine's paths."""
    for seed, steps in ((0, 400), (1, 800), (2, 300)):
        make_run(tmp_path / "lender", "acrobot", "ours", seed, steps)
    make_run(tmp_path / "fig", "acrobot", "knn", 0, 700, estimator="knn")
    (tmp_path / "fig" / "analysis.yaml").write_text("include: ['../lender/acrobot/ours/h3/seed=*']\n")
    res = early(tmp_path / "fig", "--columns", "behaviour/directed")
    assert res.returncode == 0, res.stderr
    csv = pd.read_csv(tmp_path / "fig" / "report" / "early.csv")
    assert sorted(csv["run_dir"]) == ["../lender/acrobot/ours/h3/seed=0", "../lender/acrobot/ours/h3/seed=1",
                                      "../lender/acrobot/ours/h3/seed=2", "acrobot/knn/h3/seed=0"]  # fmt: skip
