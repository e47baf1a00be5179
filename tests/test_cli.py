"""End-to-end: the real CLI in a subprocess writes a complete run directory; sweeps; bad input."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import pytest
import yaml
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from analysis.collect import load_summaries
from analysis.steps_table import steps_table
from curiosity.runtime.behaviour import behaviour_keys
from tests.conftest import run_cli

CHARTS = ["step", "charts/coverage", "charts/wall_time", "charts/sps", "charts/extrinsic_reward", "intrinsic/reward"]


def _run_dirs(root: Path) -> list[Path]:
    return sorted(p.parent for p in root.rglob("summary.json"))


def test_smoke_run_writes_csv_summary_and_tensorboard(tmp_path: Path) -> None:
    out = tmp_path / "run"
    res = run_cli(["baseline=random", "budget=smoke", "seed=7", f"hydra.run.dir={out}"], cwd=tmp_path)
    assert res.returncode == 0, res.stderr[-3000:]
    assert (out / ".hydra" / "config.yaml").is_file()
    with (out / "metrics.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == [*CHARTS, *behaviour_keys(3, directed=True)]  # the random baseline logs no agent columns
    assert [int(r["step"]) for r in rows] == list(range(10, 201, 10))  # log_every=10 up to the 200-step cap
    cov = [float(r["charts/coverage"]) for r in rows]
    assert all(0 < c <= 1 for c in cov) and cov == sorted(cov)  # coverage never decreases
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seed"] == 7 and summary["method"] == "random" and summary["max_steps"] == 200
    assert summary["env_steps"] == 200 and summary["reached_goal"] is False and summary["steps_to_goal"] is None
    assert (summary["wall_seconds"] > 0 and len(summary["git_commit"]) in (7, 40)) or summary["git_commit"] == "unknown"
    assert summary["cpu_seconds"] > 0  # the process's CPU time over the loop (what a study's cost column reads)
    machine = summary["machine"]  # which CPU made it: a seed repeats exactly only on the same machine
    assert machine["cpu"] and machine["cpu_capability"] and machine["torch"].startswith("2.") and machine["torch_threads"] >= 1
    events = list((out / "tb").glob("events.out.tfevents.*"))
    assert len(events) == 1
    acc = EventAccumulator(str(events[0]))
    acc.Reload()
    assert {"charts/coverage", "charts/sps"} <= set(acc.Tags()["scalars"])
    tb_cov = acc.Scalars("charts/coverage")
    assert [e.step for e in tb_cov] == list(range(10, 201, 10))
    assert [e.value for e in tb_cov] == pytest.approx(cov, rel=1e-6)
    assert "random seed=7" in res.stdout + res.stderr  # the one-line summary


def test_multirun_seed_range_gives_integer_seeds_and_one_dir_per_job(tmp_path: Path) -> None:
    res = run_cli(["-m", "estimator=kde,knn", "seed=0-1", "baseline=random", "budget=smoke",
                   "env.renderer=fast", f"hydra.sweep.dir={tmp_path / 'sweep'}"], cwd=tmp_path)  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    dirs = _run_dirs(tmp_path / "sweep")
    assert len(dirs) == 4
    seeds = []
    for d in dirs:
        cfg = yaml.safe_load((d / ".hydra" / "config.yaml").read_text())
        assert isinstance(cfg["seed"], int)
        assert json.loads((d / "summary.json").read_text())["seed"] == cfg["seed"]
        assert d.name == f"seed={cfg['seed']}" and (d / "metrics.csv").is_file() and any((d / "tb").iterdir())
        seeds.append(cfg["seed"])
    assert sorted(seeds) == [0, 0, 1, 1]
    # the analysis reads these run directories back
    table = steps_table(load_summaries(tmp_path / "sweep"))
    assert table[["method", "seeds", "reached"]].values.tolist() == [["random", 2, 0], ["random", 2, 0]]
    assert sorted(table["variant"]) == ["baseline=random,budget=smoke,env.renderer=fast,estimator=kde",
                                        "baseline=random,budget=smoke,env.renderer=fast,estimator=knn"]  # fmt: skip
    assert table["mean_capped"].tolist() == [200.0, 200.0] and "per_seed" in table


@pytest.mark.parametrize(
    ("args", "key"),
    [
        (["budget.max_steps=-5"], "budget.max_steps"),
        (["estimator=kdee"], "estimator"),
        (["seedd=1"], "seedd"),
        (["seed=1.5"], "seed"),
        (["-m", "seed=3-1"], "seed"),
        (["-m", "seed=a-b"], "seed"),
    ],
)
def test_bad_input_fails_before_any_env_is_built(tmp_path: Path, args: list[str], key: str) -> None:
    out = tmp_path / "run"
    res = run_cli([*args, "baseline=random", f"hydra.run.dir={out}", f"hydra.sweep.dir={out}"], cwd=tmp_path)
    assert res.returncode == 2
    assert res.stderr.startswith("error: ") and key in res.stderr and len(res.stderr.splitlines()) == 1
    assert not out.exists()  # refused before Hydra made the run directory


def test_help_lists_the_groups_a_user_sets_and_the_launchers(tmp_path: Path) -> None:
    res = run_cli(["--help"], cwd=tmp_path)
    assert res.returncode == 0, res.stderr[-2000:]
    assert "estimator: kde, knn" in res.stdout and "submitit_local" in res.stdout
    assert "schema/" not in res.stdout  # the typed schemas are internal


def test_the_group_listing_is_made_only_for_the_help(monkeypatch: pytest.MonkeyPatch) -> None:
    """Hydra resolves the help template while composing every run's config; the listing (≈ 1 s) is skipped unless
    the command line asks for the help (the --help run above shows it is made then)."""
    from curiosity.config import resolvers

    calls = []
    monkeypatch.setattr(resolvers, "_groups_listing", lambda: calls.append(1) or "estimator: kde, knn")
    monkeypatch.setattr(sys, "argv", ["runners.train", "seed=1", "budget=smoke"])
    assert "--help" in resolvers.help_groups() and calls == []
    monkeypatch.setattr(sys, "argv", ["runners.train", "--help"])
    assert resolvers.help_groups() == "estimator: kde, knn" and calls == [1]


def test_a_sampling_planner_says_so_in_the_log_and_the_summary(tmp_path: Path) -> None:
    out = tmp_path / "run"
    args = ["planner.horizon=6", "planner.max_candidates=50", "planner.sample_candidates=true", "budget=smoke",
            "budget.max_steps=70", "env.renderer=fast", f"hydra.run.dir={out}"]  # fmt: skip
    res = run_cli(args, cwd=tmp_path)
    assert res.returncode == 0, res.stderr[-3000:]
    assert json.loads((out / "summary.json").read_text())["planner_sampled_candidates"] == 50
    assert "scores 50 sampled sequences of the 3^6 per step" in (out / "train.log").read_text()
