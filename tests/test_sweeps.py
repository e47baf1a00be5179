"""The paper-claim presets (``+sweep=table1|table2|fig6|fig7|hybrid``, issue 15; ``noisy_tv``, issue 16): what each
sweeps, that every job of it composes and validates, and that one runs into its own results directory and resumes by
re-running the command."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import pytest
from hydra.core.override_parser.overrides_parser import OverridesParser

from curiosity.config.compose import compose_config
from curiosity.runtime.preflight import checked_config
from tests.conftest import CONF, run_cli

# preset -> (results directory, env, the values each swept key takes, seeds)
PRESETS = {
    "table1": (
        "results/table1",
        "acrobot",
        {"+experiment": ["ours", "paper_text", "paper_code", "nsrs", "icm", "rnd", "random", "oracle"]},
        10,
    ),
    "table2": (
        "results/table2",
        "mountaincar",
        {"+experiment": ["ours", "paper_text_renyi", "paper_text_renyi_mi", "nsrs", "icm", "rnd", "random"]},
        10,
    ),
    "fig6": ("results/fig6", "acrobot", {"entropy": ["gaussian_potential", "renyi", "renyi_mi", "none"]}, 6),
    "fig7": ("results/fig7", "acrobot", {"estimator": ["kde", "knn"]}, 6),
    "hybrid": ("results/hybrid", "acrobot", {"+experiment": ["ours_density", "ours_hybrid", "ours_pe"]}, 6),
    "noisy_tv": (
        "results/noisy_tv",
        "acrobot",
        {"+experiment": ["icm", "rnd", "ours_pe", "ours_density", "ours_hybrid"], "env.distractor": ["none", "noisy_tv"]},
        8,
    ),
}


def _swept(params: dict[str, str]) -> dict[str, list[str]]:
    parser = OverridesParser.create()
    out = {}
    for key, value in params.items():
        (override,) = parser.parse_overrides([f"{key}={value}"])
        out[key] = [str(v) for v in override.sweep_string_iterator()] if override.is_sweep_override() else [value]
    return out


# studies over the tuning seeds (not claims): the default agent plus a point's command-line overrides
STUDIES = {"cheap_seed": ("results/cheap_seed", "acrobot", 30)}


def test_every_preset_has_a_file() -> None:
    assert sorted(p.stem for p in (CONF / "sweep").glob("*.yaml")) == sorted([*PRESETS, *STUDIES])


@pytest.mark.parametrize("study", sorted(STUDIES))
def test_a_study_sweeps_the_tuning_seeds_and_its_points_validate(study: str) -> None:
    directory, env, n_seeds = STUDIES[study]
    cfg = compose_config([f"+sweep={study}"], hydra_node=True)
    assert cfg.hydra.sweep.dir == directory and cfg.env.name == env
    assert _swept(dict(cfg.hydra.sweeper.params)) == {"seed": [str(s) for s in range(n_seeds)]}  # tuning seeds only
    point = ["budget.train_every=20", "budget.iters_per_train=64", "encoder.downsample=2", "encoder.pools=[2,3]"]
    _, task = checked_config([f"+sweep={study}", *point])  # a point: the default plus overrides, validated
    assert task.budget.max_steps == 3000 and task.budget.warmup_steps == 64 and task.encoder.downsample == 2


@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_a_preset_sweeps_its_rows_over_held_out_seeds_and_every_job_validates(preset: str) -> None:
    directory, env, rows, n_seeds = PRESETS[preset]
    cfg = compose_config([f"+sweep={preset}"], hydra_node=True)
    assert cfg.hydra.sweep.dir == directory and cfg.env.name == env
    swept = _swept(dict(cfg.hydra.sweeper.params))
    assert swept.pop("seed") == [str(s) for s in range(100, 100 + n_seeds)]  # held-out seeds only (tuning used 0-7)
    assert swept == rows
    labels = set()
    for values in itertools.product(*rows.values()):
        job = [f"+sweep={preset}", *(f"{k}={v}" for k, v in zip(rows, values, strict=True))]
        _, task = checked_config(job)  # composes, appends no unknown key, validates
        assert task.env.name == env and task.budget.max_steps == 3000 and task.budget.warmup_steps == 64
        assert task.budget.stop_at_goal == (preset != "fig7")  # Figure 7's reward curves go on to the cap
        labels.add((task.method_label, repr(values)))
    assert len({label for label, _ in labels}) == len(labels) or preset != "table1"  # Table 1's rows: one label each


def test_a_preset_runs_into_its_directory_and_resumes(tmp_path: Path) -> None:
    args = ["-m", "+sweep=table1", "+experiment=random", "seed=100-101", "budget.max_steps=80"]
    first = run_cli(args, cwd=tmp_path)
    assert first.returncode == 0, first.stderr[-2000:]
    summaries = sorted((tmp_path / "results" / "table1").rglob("summary.json"))
    assert [json.loads(p.read_text())["seed"] for p in summaries] == [100, 101]
    assert all("+sweep" not in str(p) for p in summaries)  # the preset is not part of a run's identity
    before = {p: p.read_bytes() for p in summaries}
    again = run_cli(args, cwd=tmp_path)
    assert again.returncode == 0 and again.stdout.count("already complete") == 2, again.stdout[-2000:]
    assert {p: p.read_bytes() for p in summaries} == before  # exact: the same files, untouched


@pytest.mark.parametrize("launcher", ["joblib", "submitit_local", "submitit_slurm", "slurm"])
def test_a_preset_composes_with_every_launcher(launcher: str) -> None:
    cfg = compose_config(["+sweep=table1", f"hydra/launcher={launcher}"], hydra_node=True)
    assert cfg.hydra.sweep.dir == "results/table1" and "Launcher" in cfg.hydra.launcher._target_
    assert cfg.hydra.sweeper.params["+experiment"].count(",") == 7  # the launcher changes where jobs run, not which
