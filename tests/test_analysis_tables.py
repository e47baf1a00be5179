"""``analysis.tables`` on synthetic run directories with known numbers: exact means and SEs, scipy's Welch p and
bootstrap CI on the same arrays, config-defined rows, explicit pooling, censored, failed and stopped runs."""

from __future__ import annotations

import math
import shutil
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from analysis.rows import distinguishing_keys, label_rows, load_runs, pool_rows
from analysis.stats import iqm_ci, welch_p
from analysis.tables import paper_numbers, steps_table, write_tables
from tests.synthetic_runs import RENYI, RENYI_MI, make_run, make_runs
from tests.test_analysis import analysis

POOL = "ours (Rényi, pooled)=ours-*renyi*"


@pytest.fixture(scope="module")
def root(tmp_path_factory: pytest.TempPathFactory):
    return make_runs(tmp_path_factory.mktemp("runs"))


@pytest.fixture(scope="module")
def table(root) -> pd.DataFrame:
    return write_tables(root, root.parent / "out", pools=[POOL]).set_index(["env", "row"])


def test_rows_come_from_the_config_not_the_directory(root) -> None:
    rows = sorted(set(label_rows(load_runs(root))["row"]))
    assert rows == ["nsrs", "nsrs [planner.horizon=3]", "nsrs [planner.horizon=5]", RENYI, RENYI_MI, "random"]
    by_entropy = sorted(set(label_rows(load_runs(root), ["entropy.name"])["row"]))
    assert by_entropy == ["entropy.name=none", "entropy.name=renyi", "entropy.name=renyi_mi"]  # across methods


def test_a_key_only_some_runs_have_still_tells_those_runs_apart() -> None:
    """Blurred and unblurred conv-encoder runs beside an MLP-encoder run (which has no ``encoder.blur_sigma``): the
    blur still separates the conv runs; a key with one value wherever it is present separates nothing."""
    conv = {"encoder.name": "conv", "encoder.blur_sigma": 0.0, "seed": 0}
    configs = [conv, {**conv, "encoder.blur_sigma": 4.0, "seed": 1}, {"encoder.name": "mlp", "seed": 2}]
    assert distinguishing_keys(configs) == ["encoder.blur_sigma", "encoder.name"]
    assert distinguishing_keys([conv, {"encoder.name": "mlp", "seed": 0}]) == ["encoder.name"]


def test_censored_runs_count_at_their_cap_and_successes_apart(table: pd.DataFrame) -> None:
    r = table.loc[("mountaincar", "nsrs")]
    assert (r.seeds, r.reached, r.per_seed) == (4, 3, "1000 1200 >1900 800")
    assert r["mean"] == 1225.0  # exact: (1000 + 1200 + 1900 + 800) / 4
    assert r.se == pytest.approx(np.std([1000, 1200, 1900, 800], ddof=1) / 2, rel=1e-12)
    assert r.mean_success == 1000.0 and r.se_success == pytest.approx(200 / math.sqrt(3), rel=1e-12)
    assert r["median"] == 1100.0 and r.iqm == 1100.0  # the middle two of four


def test_pooling_is_explicit_and_the_bootstrap_is_stratified(root, table: pd.DataFrame) -> None:
    assert ("mountaincar", RENYI) not in table.index
    r = table.loc[("mountaincar", "ours (Rényi, pooled)")]
    assert (r.seeds, r.reached, r.per_seed) == (5, 4, "1500 1700 1300 >1900 1100")
    assert r["mean"] == 1500.0 and r.se == pytest.approx(np.std([1500, 1700, 1300, 1900, 1100], ddof=1) / math.sqrt(5))
    assert r.paper_mean == 1456.9 and r.paper_se == 125.7 and r.paper_seeds == 8
    res = stats.bootstrap(([1500.0, 1700.0], [1300.0, 1900.0, 1100.0]),
                          lambda a, b, axis: stats.trim_mean(np.concatenate([a, b], axis=axis), 0.25, axis=axis),
                          n_resamples=2000, method="percentile", rng=np.random.default_rng(0))  # fmt: skip
    low, high = res.confidence_interval
    assert (r.iqm_low, r.iqm_high) == pytest.approx((low, high), rel=1e-9)
    assert iqm_ci([[1500.0, 1700.0], [1300.0, 1900.0, 1100.0]]) == pytest.approx((1500.0, low, high), rel=1e-9)


def test_welch_p_against_the_reference_row_is_scipys(table: pd.DataFrame, root) -> None:
    r = table.loc[("mountaincar", "ours (Rényi, pooled)")]
    expected = stats.ttest_ind([1500, 1700, 1300, 1900, 1100], [1000, 1200, 1900, 800], equal_var=False).pvalue
    assert r.welch_p == pytest.approx(expected, rel=1e-9)
    assert math.isnan(table.loc[("mountaincar", "nsrs")].welch_p)  # the reference itself
    runs = pool_rows(label_rows(load_runs(root)), [POOL])
    other = steps_table(runs, reference="random", numbers=paper_numbers()).set_index(["env", "row"])
    p = stats.ttest_ind([600, 700, 500], [1700, 2100], equal_var=False).pvalue
    assert other.loc[("acrobot", "nsrs [planner.horizon=3]")].welch_p == pytest.approx(p, rel=1e-9)
    assert math.isnan(other.loc[("mountaincar", "nsrs")].welch_p)  # no random row in MountainCar


def test_welch_p_of_a_row_at_the_cap_is_scipys_and_quiet() -> None:
    # every run at the cap: a constant side, whose variance is 0; scipy's identical-data warning is not passed on
    capped, reference = [3000.0] * 6, [233.0, 586.0, 3000.0, 1315.0, 367.0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p = welch_p(capped, reference)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        expected = stats.ttest_ind(capped, reference, equal_var=False).pvalue
    assert p == pytest.approx(expected, rel=1e-9) and 0.0 < p < 1.0
    assert math.isnan(welch_p([3000.0] * 3, [3000.0] * 4))  # both constant: no test


def test_paper_numbers_sit_beside_ours_with_their_source(table: pd.DataFrame) -> None:
    r = table.loc[("acrobot", "random")]
    assert (r.paper_mean, r.paper_se, r.paper_method) == (1713.3, 316.3, "Random") and "NSRS" in r.paper_source
    assert {p["method"] for p in paper_numbers()} >= {"ICM", "RND", "Novelty (NSRS)", "Ours", "Random"}


def test_the_files_list_the_runs_not_finished(root, table: pd.DataFrame) -> None:
    out = root.parent / "out"
    md = (out / "steps_to_goal.md").read_text()
    assert "| mountaincar | nsrs | 3 / 4 | 1000, 1200, >1900, 800 | 1225.0 ± 239.4 | 1000.0 ± 115.5 |" in md
    assert "failed: " in md and "random/h3/seed=2" in md and "stopped: " in md and "random/h3/seed=3" in md
    incomplete = pd.read_csv(out / "incomplete.csv")
    assert sorted(incomplete["status"]) == ["failed", "stopped"]
    assert r"\begin{tabular}" in (out / "steps_to_goal.tex").read_text()
    assert len(pd.read_csv(out / "steps_to_goal.csv")) == len(table)


def test_the_command_writes_the_same_bytes_twice(root, tmp_path) -> None:
    for name in ("a", "b"):
        res = analysis("tables", root, "--out", tmp_path / name, "--pool", POOL)
        assert res.returncode == 0, res.stderr
    for f in ("steps_to_goal.md", "steps_to_goal.tex", "steps_to_goal.csv", "incomplete.csv"):
        assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes()  # exact: the same computation


def test_bad_input_is_one_line(tmp_path) -> None:
    for args in ([tmp_path], [tmp_path / "missing"], [tmp_path, "--pool", "nolabel"]):
        res = analysis("tables", *args)
        assert res.returncode != 0 and res.stderr.startswith("error: ") and len(res.stderr.splitlines()) == 1


def test_a_run_without_a_hydra_config_is_read_from_its_summary(tmp_path) -> None:
    """A run made outside Hydra (e.g. in-process) may lack ``.hydra/config.yaml``: its summary still counts."""
    from analysis.collect import load_summaries
    from tests.synthetic_runs import make_run

    d = make_run(tmp_path, "acrobot", "nsrs", 0, 640)
    shutil.rmtree(d / ".hydra")
    (row,) = load_summaries(tmp_path).to_dict("records")
    assert row["steps_to_goal"] == 640 and row["method"] == "nsrs" and "entropy" not in row


def test_a_pool_with_plus_adds_the_pooled_row_beside_its_parts(root) -> None:
    runs = pool_rows(label_rows(load_runs(root)), [POOL.replace("=", "+=", 1)])
    table = steps_table(runs, numbers=paper_numbers()).set_index(["env", "row"])
    for row in (RENYI, RENYI_MI, "ours (Rényi, pooled)"):
        assert ("mountaincar", row) in table.index
    pooled = table.loc[("mountaincar", "ours (Rényi, pooled)")]
    parts = table.loc[[("mountaincar", RENYI), ("mountaincar", RENYI_MI)]]
    assert pooled.seeds == parts.seeds.sum() == 5 and pooled.paper_mean == 1456.9


def test_a_directory_s_analysis_yaml_makes_its_tables_with_the_bare_command(tmp_path, root) -> None:
    runs = tmp_path / "runs"
    shutil.copytree(root, runs)
    (runs / "analysis.yaml").write_text(f"pool: ['{POOL.replace('=', '+=', 1)}']\nreference: random\n")
    assert analysis("tables", runs).returncode == 0
    text = (runs / "report" / "steps_to_goal.md").read_text()
    assert "ours (Rényi, pooled)" in text and RENYI in text and "`random`" in text  # pooled beside parts; the reference
    assert analysis("tables", runs, "--reference", "nsrs*").returncode == 0  # the command line wins
    assert "`nsrs*`" in (runs / "report" / "steps_to_goal.md").read_text()
    (runs / "analysis.yaml").write_text("pools: []\n")
    bad = analysis("tables", runs)
    assert bad.returncode == 1 and bad.stderr.count("\n") == 1 and "allowed: pool, group_by, reference" in bad.stderr


def test_the_compute_line_sums_the_finished_runs_wall_seconds_per_env() -> None:
    from analysis.tables import compute_line

    runs = pd.DataFrame({"env": ["acrobot", "acrobot", "mountaincar"], "wall_seconds": [1800.0, 3600.0, 720.0]})
    assert compute_line(runs).endswith("acrobot 2 runs, 1.5 h; mountaincar 1 runs, 0.2 h.")
    assert compute_line(runs.iloc[:0]) == "Compute: no finished run."


def test_the_noisy_tv_table_sets_each_method_with_the_tv_beside_itself_without(tmp_path: Path) -> None:
    from analysis.distractor import distractor_table
    from analysis.figures import load, tv_press_curves, write_figures
    from analysis.rows import load_runs

    for seed, (clean, tv) in enumerate([(500, 900), (600, None), (700, 1100)]):
        make_run(tmp_path, "acrobot", "icm", seed, clean)
        make_run(tmp_path, "acrobot", "icm", seed, tv, distractor="noisy_tv", tv_rate=0.5 + 0.1 * seed)
        make_run(tmp_path, "acrobot", "ours_density", seed, clean + 10)
        make_run(tmp_path, "acrobot", "ours_density", seed, clean + 20, distractor="noisy_tv", tv_rate=0.25)
    table = distractor_table(load_runs(tmp_path)).set_index(["method", "distractor"])
    icm = table.loc[("icm", "noisy_tv")]
    assert icm["n"] == 3 and icm["reached"] == 2 and icm["per_seed"] == "900 >3000 1100"
    assert icm["mean"] == pytest.approx((900 + 3000 + 1100) / 3)
    assert icm["welch_p"] == pytest.approx(stats.ttest_ind([900, 3000, 1100], [500, 600, 700], equal_var=False).pvalue)
    assert icm["tv_rate"] == pytest.approx(0.6) and icm["tv_rate_se"] == pytest.approx(0.1 / np.sqrt(3))
    assert math.isnan(table.loc[("icm", "none"), "welch_p"]) and math.isnan(table.loc[("icm", "none"), "tv_rate"])
    assert table.loc[("ours_density", "noisy_tv"), "tv_rate"] == pytest.approx(0.25)
    write_tables(tmp_path, tmp_path / "report")
    md = (tmp_path / "report" / "distractor.md").read_text()
    assert "| acrobot | icm | noisy_tv | 2 / 3 | 900 >3000 1100 |" in md
    steps = pd.read_csv(tmp_path / "report" / "steps_to_goal.csv")  # the rows name the distractor, not the action count
    assert set(steps["row"]) == {f"{m} [env.distractor={d}]" for m in ("icm", "ours_density") for d in ("none", "noisy_tv")}
    written = {p.name for p in write_figures(tmp_path, tmp_path / "report")}
    assert {"tv_presses.png", "tv_presses.pdf"} <= written
    curves = tv_press_curves(load(tmp_path, [], [])[1])  # the figure's curves end at each run's rate in the table
    assert curves.shape[1] == 6 and sorted(curves.iloc[-1].round(6)) == [0.25] * 3 + [0.5, 0.6, 0.7]


def test_no_distractor_no_tv_table_and_no_tv_figure(tmp_path: Path) -> None:
    from analysis.figures import write_figures

    make_runs(tmp_path)
    write_tables(tmp_path, tmp_path / "report")
    assert not (tmp_path / "report" / "distractor.md").exists()
    assert not any(p.stem == "tv_presses" for p in write_figures(tmp_path, tmp_path / "report"))


def test_the_report_names_the_code_commits_and_each_row_that_pools_several(tmp_path: Path) -> None:
    """Runs that recorded no commit give no line; all of one commit, one line naming it; a run of another commit
    names the row it falls in (with its run counts) and no other row."""
    import json

    root = make_runs(tmp_path / "runs")
    write_tables(root, tmp_path / "none")
    assert "Code:" not in (tmp_path / "none" / "steps_to_goal.md").read_text()
    summaries = sorted(root.rglob("summary.json"))
    for s in summaries:
        s.write_text(json.dumps({**json.loads(s.read_text()), "git_commit": "a" * 40, "git_dirty": False}))
    write_tables(root, tmp_path / "one")
    md = (tmp_path / "one" / "steps_to_goal.md").read_text()
    assert "Code: every run was made by commit `aaaaaaa`" in md and "pooling" not in md
    other = next(s for s in summaries if json.loads(s.read_text())["method"] == "random")
    other.write_text(json.dumps({**json.loads(other.read_text()), "git_commit": "b" * 40, "git_dirty": True}))
    write_tables(root, tmp_path / "two")
    text = (tmp_path / "two" / "steps_to_goal.md").read_text()
    line = next(x for x in text.splitlines() if x.startswith("Code:"))
    n = len(summaries)
    assert "by 2 commits" in line and f"`aaaaaaa` ({n - 1} runs)" in line and "`bbbbbbb+dirty` (1 run)" in line
    assert line.endswith("Rows pooling runs of more than one commit:")
    pooled = [x for x in text.split(line)[1].split("Not finished")[0].splitlines() if x.startswith("- ")]
    assert len(pooled) == 1 and "random" in pooled[0] and pooled[0].endswith("`aaaaaaa` (1), `bbbbbbb+dirty` (1)")


def test_the_report_names_the_machines_once_runs_record_them(tmp_path: Path) -> None:
    """Runs made before summaries recorded their machine give no line (the committed reports stay as they are); one
    machine, one line naming it; two, each with its run count and the runs that recorded none."""
    import json

    root = make_runs(tmp_path / "runs")
    write_tables(root, tmp_path / "none")
    assert "Machine" not in (tmp_path / "none" / "steps_to_goal.md").read_text()
    summaries = sorted(root.rglob("summary.json"))
    intel = {"cpu": "Intel(R) Xeon(R) Processor", "cpu_capability": "AVX512", "torch": "2.13.0+cpu"}
    for s in summaries:
        s.write_text(json.dumps({**json.loads(s.read_text()), "machine": intel}))
    write_tables(root, tmp_path / "one")
    md = (tmp_path / "one" / "steps_to_goal.md").read_text()
    assert "Machine: every run was made on `Intel(R) Xeon(R) Processor (AVX512)`" in md
    amd = {"cpu": "AMD EPYC 7B13", "cpu_capability": "AVX2"}
    summaries[0].write_text(json.dumps({**json.loads(summaries[0].read_text()), "machine": amd}))
    summaries[1].write_text(json.dumps({k: v for k, v in json.loads(summaries[1].read_text()).items() if k != "machine"}))
    write_tables(root, tmp_path / "three")
    line = next(x for x in (tmp_path / "three" / "steps_to_goal.md").read_text().splitlines() if x.startswith("Machines"))
    n = len(summaries)
    assert "`AMD EPYC 7B13 (AVX2)` (1 run)" in line and f"`Intel(R) Xeon(R) Processor (AVX512)` ({n - 2} runs)" in line
    assert "`not recorded` (1 run)" in line
