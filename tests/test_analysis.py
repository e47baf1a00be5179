"""The analysis commands on run directories finished or not: a useful result or one clear line, never a traceback."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO, holding_lock

TUNING = REPO / "results" / "tuning"  # three finished seeds and one stopped at env step 1990 (no summary.json)


def analysis(module: str, *args: str | Path, timeout: float = 120) -> subprocess.CompletedProcess:
    """Run ``python -m analysis.<module> ARGS`` from the repository root; ``timeout`` (s) only guards against a hang."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    res = subprocess.run([sys.executable, "-m", f"analysis.{module}", *map(str, args)], cwd=REPO, env=env,
                         capture_output=True, text=True, timeout=timeout)  # fmt: skip
    assert "Traceback" not in res.stdout + res.stderr, res.stderr
    return res


@pytest.fixture
def sweep(tmp_path: Path) -> Path:
    """A copy of results/tuning, plus a job refused before it ran (FAILED.json only)."""
    root = tmp_path / "sweep"
    shutil.copytree(TUNING, root)
    refused = root / "acrobot" / "random" / "+foo=1" / "seed=0"
    refused.mkdir(parents=True)
    (refused / "FAILED.json").write_text(json.dumps({"error": "ConfigError: +foo=1: foo is not a key", "overrides": []}))
    started = root / "acrobot" / "random" / "default" / "seed=0" / ".hydra"  # stopped before its first metrics row
    started.mkdir(parents=True)
    shutil.copy(next(root.rglob("seed=0/.hydra/config.yaml")), started / "config.yaml")
    return root


def test_collect_lists_every_run_with_its_status(sweep: Path) -> None:
    res = analysis("collect", sweep)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert len(lines) == 7 and lines[-1] == "6 run(s): 3 complete, 1 failed, 2 stopped"
    assert any("default/seed=0  before its first metrics row" in line for line in lines)
    assert any(line.startswith("stopped") and "seed=3  at env step 1990" in line for line in lines)
    assert any(line.startswith("failed") and "+foo=1" in line for line in lines)


def test_collect_reads_a_run_whose_lock_a_live_process_holds_as_running(sweep: Path) -> None:
    """The stopped seed 3 with a lock held by a live process reads as running; with the lock's process gone, as
    stopped again (a stale lock)."""
    lock = next(p for p in sweep.rglob("seed=3") if not (p / "summary.json").exists()) / "run.lock"
    with holding_lock(lock.parent) as pid:
        res = analysis("collect", sweep)
    assert any(line.startswith("running") and f"process {pid}, at env step 1990" in line
               for line in res.stdout.splitlines())  # fmt: skip
    assert res.stdout.splitlines()[-1] == "6 run(s): 3 complete, 1 failed, 1 running, 1 stopped"
    assert analysis("collect", sweep).stdout.splitlines()[-1] == "6 run(s): 3 complete, 1 failed, 2 stopped"


@pytest.mark.parametrize("module", ["collect", "steps_table", "profile"])
def test_no_runs_or_no_directory_is_one_line_and_non_zero(tmp_path: Path, module: str) -> None:
    for root in (tmp_path, tmp_path / "missing"):
        res = analysis(module, root)
        assert res.returncode != 0 and res.stderr.startswith("error: ") and len(res.stderr.splitlines()) == 1


def test_steps_table_lists_the_runs_not_finished(sweep: Path) -> None:
    res = analysis("steps_table", sweep, "--markdown")
    assert res.returncode == 0, res.stderr
    assert "| 3 / 3 (1 more not finished) | 365, 1855, 1452 | 1224.0 ± 445.0 |" in res.stdout
    assert "stopped: " in res.stdout and "seed=3  at env step 1990" in res.stdout
    assert "failed: " in res.stdout and "+foo=1" in res.stdout


def test_steps_table_markdown_counts_runs_at_the_cap_beside_the_mean_of_those_that_reached() -> None:
    import pandas as pd

    from analysis.steps_table import to_markdown

    base = {"method": "m", "command": "c", "incomplete": 0, "se": float("nan")}
    table = pd.DataFrame([
        {**base, "seeds": 2, "reached": 2, "per_seed": "100 300", "mean": 200.0, "se": 100.0, "mean_capped": 200.0},
        {**base, "seeds": 2, "reached": 1, "per_seed": "100 >1000", "mean": 100.0, "mean_capped": 550.0},
        {**base, "seeds": 1, "reached": 0, "per_seed": ">1000", "mean": float("nan"), "mean_capped": 1000.0},
    ])  # fmt: skip
    rows = to_markdown(table).splitlines()[2:]
    assert rows[0].endswith("| 200.0 ± 100.0 |")
    assert rows[1].endswith("| 100.0 (reached); 550.0 with the runs at the cap counted at the cap |")
    assert rows[2].endswith("| 1000.0 with the runs at the cap counted at the cap |")


def test_steps_table_splits_one_command_run_with_other_code_defaults(sweep: Path) -> None:
    """Seed 1 made as if by code whose default executes 5 planned actions: the same command line, not the same
    method. It gets its own row, labelled by the key that differs; the others (saved before the key existed) read
    with the value that reproduces them, and the stopped run stays counted with them."""
    import yaml

    config = next(sweep.rglob("seed=1/.hydra/config.yaml"))
    cfg = yaml.safe_load(config.read_text())
    cfg["planner"]["commit"] = 5
    config.write_text(yaml.safe_dump(cfg))
    res = analysis("steps_table", sweep, "--markdown")
    assert res.returncode == 0, res.stderr
    assert (
        "-mpc [planner.commit=1] | `python -m runners.train -m planner.horizon=5 planner.temperature=0 seed=0,2` "
        "| 2 / 2 (1 more not finished) | 365, 1452 |" in res.stdout
    )
    assert (
        "-mpc [planner.commit=5] | `python -m runners.train planner.horizon=5 planner.temperature=0 seed=1` "
        "| 1 / 1 | 1855 |" in res.stdout
    )


def test_steps_table_warns_on_stderr_when_a_row_pools_runs_of_other_code_commits(sweep: Path) -> None:
    """Seed 1 of the mpc row recorded another commit: stdout (the README's table) is unchanged, stderr names the row
    and both commits with their run counts; with every run of one commit there is no warning."""
    before = analysis("steps_table", sweep, "--markdown")
    assert before.returncode == 0 and "pools runs" not in before.stderr
    summary = next(p for p in sweep.rglob("seed=1/summary.json") if "mpc" in str(p))
    data = json.loads(summary.read_text())
    old = data["git_commit"][:7]
    data["git_commit"] = "f" * 40
    summary.write_text(json.dumps(data))
    res = analysis("steps_table", sweep, "--markdown")
    assert res.returncode == 0 and res.stdout == before.stdout
    warning = [line for line in res.stderr.splitlines() if "pools runs of 2 code commits" in line]
    assert len(warning) == 1 and warning[0].startswith("warning: ") and "mpc" in warning[0]
    assert f"{old} (2 runs)" in warning[0] and "fffffff (1 run)" in warning[0]


def test_profile_of_a_sweep_root_profiles_each_run_finished_or_not(sweep: Path) -> None:
    res = analysis("profile", sweep)
    assert res.returncode == 0, res.stderr
    assert res.stdout.count("  total ") == 4 and "(unfinished: up to env step 1990)" in res.stdout  # 4 with metrics


def test_the_results_doc_command_prints_its_table() -> None:
    results = (REPO / "docs" / "results.md").read_text()
    command = re.search(r"`python -m (analysis\.steps_table [^`]*--markdown)`", results)
    assert command, "docs/results.md names its table's command"
    module, *args = command[1].removeprefix("analysis.").split()
    res = analysis(module, *args)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() in results
