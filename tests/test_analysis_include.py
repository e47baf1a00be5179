"""``include`` in a results directory's ``analysis.yaml`` (``analysis.include``): runs another preset made with the same
config count in this directory's tables, a run of its own wins over an included run of the same config and seed, and a
bad setting is one line."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from analysis.collect import run_dirs
from analysis.rows import label_rows, load_runs
from tests.synthetic_runs import make_run
from tests.test_analysis import analysis


def _lender(root: Path) -> Path:
    """Another preset's directory: random seeds 0-3 (steps 1000 + 100 seed) and nsrs seeds 0-1."""
    for seed in range(4):
        make_run(root / "table", "acrobot", "random", seed, 1000 + 100 * seed, behaviour=False)
    for seed in range(2):
        make_run(root / "table", "acrobot", "nsrs", seed, 500 + seed)
    return root / "table"


def _rows(directory: Path) -> dict[str, list[float]]:
    runs = label_rows(load_runs(directory)).sort_values("seed")
    return {row: g["steps"].tolist() for row, g in runs.groupby("row")}


def test_included_runs_join_the_rows_of_the_directory(tmp_path: Path) -> None:
    lender = _lender(tmp_path)
    fig = tmp_path / "fig"
    make_run(fig, "acrobot", "knn", 0, 700, estimator="knn")
    (fig / "analysis.yaml").write_text("include: ['../table/acrobot/random/h3/seed=[0-2]']\n")
    assert _rows(fig) == {"knn": [700.0], "random": [1000.0, 1100.0, 1200.0]}  # seeds 0-2 only: the glob decides
    included = run_dirs(fig)[1:]
    assert included == [lender / "acrobot" / "random" / "h3" / f"seed={s}" for s in range(3)]  # normalised paths
    res = analysis("tables", fig, "--reference", "random")
    assert res.returncode == 0, res.stderr
    table = pd.read_csv(fig / "report" / "steps_to_goal.csv")
    assert sorted(zip(table["row"], table["seeds"], strict=True)) == [("knn", 1), ("random", 3)]
    assert not (lender / "report").exists()  # the lender's directory is read, never written


def test_a_run_of_the_directory_wins_over_an_included_run_of_the_same_config_and_seed(tmp_path: Path) -> None:
    _lender(tmp_path)
    fig = tmp_path / "fig"
    make_run(fig, "acrobot", "random", 1, 1111, behaviour=False)  # the same config and seed as the lender's seed 1
    make_run(fig, "acrobot", "random", 2, 2222, behaviour=False, horizon=5)  # seed 2 with another config: not the same
    (fig / "analysis.yaml").write_text("include: ['../table/acrobot/random/h3/seed=*']\n")
    assert _rows(fig) == {"random [planner.horizon=3]": [1000.0, 1111.0, 1200.0, 1300.0],
                          "random [planner.horizon=5]": [2222.0]}  # fmt: skip


@pytest.mark.parametrize(("setting", "message"), [
    ("include: ['../table/acrobot/rnd/*/seed=*']\n", "matches no finished run directory"),
    ("include: '../table/acrobot/random/h3/seed=0'\n", "is not allowed; allowed: a list of globs"),
    ("include: [3]\n", "is not allowed; allowed: a list of globs"),
])  # fmt: skip
def test_a_bad_include_is_one_line(tmp_path: Path, setting: str, message: str) -> None:
    _lender(tmp_path)
    fig = tmp_path / "fig"
    make_run(fig, "acrobot", "knn", 0, 700, estimator="knn")
    (fig / "analysis.yaml").write_text(setting)
    res = analysis("tables", fig)
    assert res.returncode == 1 and res.stderr.count("\n") == 1 and message in res.stderr, res.stderr
    assert "include" in res.stderr and not (fig / "report").exists()


def test_the_committed_presets_include_only_runs_of_the_same_config(tmp_path: Path) -> None:
    """Every committed ``include`` glob names runs whose config is the one the preset's own sweep would run: Figure 6's
    default arm is Table 1's default agent, the hybrid rows are the noisy-TV rows without the TV, and the noisy-TV
    test's ICM and RND without the TV are Table 1's rows. Each committed run a glob matches has the config (bookkeeping
    keys aside) of the preset's job on its seed."""
    from omegaconf import OmegaConf

    from analysis.runconfig import IGNORED, flat_config
    from analysis.settings import settings
    from curiosity.config.compose import compose_config

    results = Path(__file__).resolve().parents[1] / "results"
    # these runs were made with the default before issue 50 (the presets that follow the default now compose it with
    # these overrides)
    before = ["budget=quick", "encoder=conv_blur", "agent.transition_hidden=10", "intrinsic.terms.novelty.input=state"]
    expected = {
        "fig6": [["+sweep=fig6", "entropy=gaussian_potential", *before]],
        "hybrid": [["+sweep=hybrid", f"+experiment={e}", *before] for e in ("ours_density", "ours_hybrid", "ours_pe")],
        "noisy_tv": [["+sweep=noisy_tv", f"+experiment={e}", "env.distractor=none"] for e in ("icm", "rnd")],
    }  # fmt: skip

    def identity(run_dir: Path) -> dict[str, object]:
        return {k: v for k, v in flat_config(run_dir).items() if k not in IGNORED}

    checked = 0
    for preset, jobs in expected.items():
        patterns = settings(results / preset)["include"]
        assert len(patterns) == len(jobs), preset
        for pattern, job in zip(patterns, jobs, strict=True):
            lent = pattern.split("/")  # ../<preset>/<env>/<method label>/<overrides>/seed=<glob>
            cfg = compose_config(job)
            assert lent[0] == ".." and lent[2] == cfg.env.name and lent[3] == cfg.method_label, pattern
            for run_dir in sorted((results / preset).glob(pattern)):
                if not (run_dir / "summary.json").exists():
                    continue
                seed = int(run_dir.name.removeprefix("seed="))
                made = tmp_path / preset / lent[3] / run_dir.name
                (made / ".hydra").mkdir(parents=True)
                OmegaConf.save(compose_config([*job, f"seed={seed}"]), made / ".hydra" / "config.yaml")
                assert identity(run_dir) == identity(made), run_dir
                checked += 1
    assert checked >= 6  # Table 1's default agent on seeds 100-105 at least (Figure 6)


def test_flat_config_is_read_once_and_again_when_the_file_changes(tmp_path: Path) -> None:
    """The analysis reads every run's config several times per command: ``flat_config`` keeps what it read per file
    version, and a rewritten ``.hydra/config.yaml`` (an edited or re-run directory) is read again."""
    from analysis.runconfig import flat_config
    from tests.synthetic_runs import make_runs

    root = make_runs(tmp_path / "runs")
    run = next(p.parent for p in sorted(root.rglob("summary.json")))
    first = flat_config(run)
    first["planner.horizon"] = -1  # a caller's change does not reach the next caller
    assert flat_config(run)["planner.horizon"] != -1
    config = run / ".hydra" / "config.yaml"
    text = config.read_text()
    assert "horizon: " in text
    config.write_text(text.replace("horizon: ", "horizon: 7 #", 1))
    assert flat_config(run)["planner.horizon"] == 7


def test_no_row_counts_a_seed_twice_runs_of_the_same_config_and_seed_are_split_by_directory(tmp_path: Path) -> None:
    """A parent directory holding two presets that ran the same config on the same seeds (a benchmark repeating a
    table's seeds): the repeated row is split by the shortest directory that tells its runs apart; a row without a
    repeated seed keeps its label."""
    for seed in range(4):
        make_run(tmp_path / "table1", "acrobot", "random", seed, 1000 + seed, behaviour=False)
    for name in ("seeds_a", "seeds_b"):
        for seed in range(2):
            make_run(tmp_path / "bench" / name, "acrobot", "random", seed, 2000 + seed, behaviour=False)
    make_run(tmp_path / "bench" / "seeds_a", "acrobot", "nsrs", 0, 500)
    make_run(tmp_path / "table1", "acrobot", "nsrs", 1, 600)
    assert _rows(tmp_path) == {
        "nsrs": [500.0, 600.0],  # seeds 0 and 1: no repeat, one row over both directories
        "random (bench/seeds_a)": [2000.0, 2001.0],
        "random (bench/seeds_b)": [2000.0, 2001.0],
        "random (table1)": [1000.0, 1001.0, 1002.0, 1003.0],
    }
    assert _rows(tmp_path / "table1") == {"nsrs": [600.0], "random": [1000.0, 1001.0, 1002.0, 1003.0]}
