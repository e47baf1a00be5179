"""The cost table and the Pareto figure (``analysis.cost``, ``analysis.pareto``) on synthetic runs with known CPU
seconds, and the paired bootstrap bound behind the cheap-seed study's non-inferiority rule (``analysis.stats``)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from scipy import stats

from analysis.cli import Options
from analysis.cost import parse_labels, short_labels
from analysis.report import write_report
from analysis.stats import bootstrap_ci, ratio_upper_bound
from analysis.tables import write_tables
from tests.synthetic_runs import make_run
from tests.test_analysis import analysis

REFERENCE = "nsrs [[]planner.horizon=3]"
LABELS = ["cheap=nsrs [[]planner.horizon=5]"]
# (seed, steps-to-goal or None for the cap, CPU seconds): the reference (horizon 3) and a cheaper point (horizon 5)
TODAY = [(0, 400, 100.0), (1, 600, 120.0), (2, None, 300.0), (3, 800, 140.0)]
CHEAP = [(0, 500, 20.0), (1, 900, 30.0), (2, 1000, 25.0)]


def _add(run_dir: Path, **fields: object) -> None:
    """Merge ``fields`` into a run's ``summary.json`` (the behaviour rates and probe means a real run records)."""
    path = run_dir / "summary.json"
    path.write_text(json.dumps({**json.loads(path.read_text()), **fields}))


@pytest.fixture(scope="module")
def root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The two points on acrobot (the cheap one's seed 3 stopped, not finished), and mountaincar runs without CPU."""
    root = tmp_path_factory.mktemp("cost") / "runs"
    for seed, steps, cpu in TODAY:
        d = make_run(root, "acrobot", "nsrs", seed, steps, cpu_seconds=cpu, horizon=3)
        _add(d, behaviour={"directed_rate": 0.5, "repeat_rate": 0.8}, agent={"means": {"probe/spearman": 0.2 + seed / 10}})
    for seed, steps, cpu in CHEAP:
        make_run(root, "acrobot", "nsrs", seed, steps, cpu_seconds=cpu, horizon=5)
    make_run(root, "acrobot", "nsrs", 3, None, horizon=5, status="stopped")
    make_run(root, "mountaincar", "nsrs", 0, 1000, cap=1900)
    return root


@pytest.fixture(scope="module")
def out(root: Path) -> Path:
    write_tables(root, root.parent / "out", REFERENCE, labels=LABELS)
    return root.parent / "out"


def test_the_bound_is_the_ratio_for_identical_and_scaled_rows() -> None:
    x = np.array([400.0, 600.0, 3000.0, 800.0, 350.0])
    assert ratio_upper_bound(x, x) == (1.0, 1.0)  # every resample's ratio is exactly 1
    assert ratio_upper_bound(2 * x, x) == (2.0, 2.0)  # twice as slow on every seed: every resample says 2
    assert ratio_upper_bound(x, 2 * x, level=0.5) == (0.5, 0.5)


def test_the_bound_is_the_90th_percentile_of_paired_resampled_ratios() -> None:
    new, ref = np.array([500.0, 900.0, 1000.0, 300.0]), np.array([400.0, 600.0, 3000.0, 350.0])
    idx = np.random.default_rng(0).integers(0, 4, size=(10_000, 4))  # the README's rule, written out
    expected = np.percentile(new[idx].mean(axis=1) / ref[idx].mean(axis=1), 90)
    ratio, bound = ratio_upper_bound(new, ref)
    assert ratio == pytest.approx(2700 / 4350, rel=1e-12) and bound == pytest.approx(expected, rel=1e-12)
    assert ratio < bound  # an upper bound, from the one seed (3000 at the cap) that flatters the new row
    assert all(math.isnan(v) for v in ratio_upper_bound([], []))
    with pytest.raises(ValueError, match="paired"):
        ratio_upper_bound([1.0, 2.0], [1.0])


def test_the_bootstrap_ci_is_scipys() -> None:
    x = [100.0, 120.0, 300.0, 140.0]
    res = stats.bootstrap((np.array(x),), np.median, n_resamples=2000, method="percentile", rng=np.random.default_rng(0))
    assert bootstrap_ci(x, np.median) == pytest.approx(tuple(res.confidence_interval), rel=1e-12)
    assert all(math.isnan(v) for v in bootstrap_ci([5.0], np.mean))


def test_the_cost_table_has_every_column(out: Path) -> None:
    table = pd.read_csv(out / "cost.csv").set_index("label")
    assert list(table.index) == ["planner.horizon=3", "cheap"]  # sorted by row; no mountaincar line: no CPU recorded
    today, cheap = table.loc["planner.horizon=3"], table.loc["cheap"]
    assert bool(today.is_reference) and not bool(cheap.is_reference)
    assert (today.seeds, today.reached, today.at_cap) == (4, 3, 1)
    assert today["mean"] == 1200.0 and today["median"] == 700.0  # the censored seed counted at its cap, 3000
    assert today.se == pytest.approx(np.std([400, 600, 3000, 800], ddof=1) / 2, rel=1e-5)
    assert (today.cpu_median, today.cpu_mean) == (130.0, 165.0)
    assert (cheap.cpu_median, cheap.cpu_mean, cheap.cpu_ratio) == (25.0, 25.0, 5.2)  # 130 / 25
    assert cheap.not_finished == "1 stopped" and pd.isna(today.not_finished)  # an empty cell
    ratio, bound = ratio_upper_bound([500, 900, 1000], [400, 600, 3000])  # the seeds both finished: 0, 1, 2
    assert (cheap.shared, cheap.ratio) == (3, 0.6) and cheap.ratio_bound == pytest.approx(bound, rel=1e-5)
    assert ratio == pytest.approx(0.6) and bound > 1.10 and cheap.non_inferior == "no"  # 3 seeds: a wide bound
    assert today.directed_rate == 0.5 and today.probe_spearman == pytest.approx(0.35) and math.isnan(cheap.repeat_rate)
    text = (out / "cost.md").read_text()
    assert "| acrobot | cheap | 3 / 3 | 1 stopped | 800.0 ± 152.8 | 900.0 |" in text
    assert "| 25 | 25 | 5.20× | 0.600 |" in text and "| 0.500 | 0.800 | 0.350 |" in text  # today: behaviour, probe
    assert "TV presses" not in text  # no run has a TV
    assert "- acrobot `cheap`: `nsrs [planner.horizon=5]`" in text


def test_the_pareto_csv_holds_what_is_plotted(root: Path, out: Path) -> None:
    points = pd.read_csv(out / "pareto.csv").set_index("label")
    today, cheap = points.loc["planner.horizon=3"], points.loc["cheap"]
    assert (today.cpu_median, today.steps_mean, cheap.cpu_median, cheap.steps_mean) == (130.0, 1200.0, 25.0, 800.0)
    low, high = bootstrap_ci([100.0, 120.0, 300.0, 140.0], np.median)
    assert (today.cpu_low, today.cpu_high) == pytest.approx((low, high), rel=1e-5)
    low, high = bootstrap_ci([500.0, 900.0, 1000.0], np.mean)
    assert (cheap.steps_low, cheap.steps_high) == pytest.approx((low, high), rel=1e-5)
    assert bool(cheap.on_front) and not bool(today.on_front)  # cheaper and faster: it beats the reference on both
    assert (out / "pareto.png").stat().st_size > 0 and (out / "pareto.pdf").stat().st_size > 0


def test_the_pareto_command_reads_the_settings_and_rewrites_the_same_bytes(root: Path, out: Path, tmp_path: Path) -> None:
    (root / "analysis.yaml").write_text(yaml.safe_dump({"reference": REFERENCE, "labels": LABELS}))
    try:
        res = analysis("pareto", root, "--out", tmp_path)
    finally:
        (root / "analysis.yaml").unlink()
    assert res.returncode == 0, res.stderr
    for name in ("pareto.png", "pareto.pdf", "pareto.csv"):  # another process, the same bytes as the tables' step
        assert (tmp_path / name).read_bytes() == (out / name).read_bytes(), name


def test_the_margin_setting_moves_the_rule_and_a_bad_one_is_refused_in_one_line(root: Path, tmp_path: Path) -> None:
    """``analysis.yaml``'s ``margin`` replaces 1.10 in the rule column, its header and the caption; a margin that is
    not a number > 0 stops the command with one line before any file is written."""
    settings = root / "analysis.yaml"
    settings.write_text(yaml.safe_dump({"reference": REFERENCE, "labels": LABELS, "margin": 2.5}))
    try:
        res = analysis("tables", root, "--out", tmp_path / "wide")
        settings.write_text(yaml.safe_dump({"reference": REFERENCE, "margin": "wide"}))
        bad = analysis("tables", root, "--out", tmp_path / "bad")
    finally:
        settings.unlink()
    assert res.returncode == 0, res.stderr
    table = pd.read_csv(tmp_path / "wide" / "cost.csv").set_index("label")
    bound = table.loc["cheap"].ratio_bound
    assert table.loc["cheap"].non_inferior == ("yes" if bound <= 2.5 else "no")
    text = (tmp_path / "wide" / "cost.md").read_text()
    assert "non-inferior (≤ 2.50)" in text and "non-inferior when the bound is ≤ 2.50" in text and "1.10" not in text
    assert bad.returncode == 1 and not (tmp_path / "bad").exists()
    assert bad.stderr.strip().splitlines()[-1].endswith("margin: 'wide' is not allowed; allowed: a number > 0")


def test_without_cpu_seconds_there_is_no_cost_table(tmp_path: Path) -> None:
    root = tmp_path / "runs"
    for seed, steps, _cpu in TODAY:  # runs made before summary.json recorded cpu_seconds
        make_run(root, "acrobot", "nsrs", seed, steps)
    write_tables(root, tmp_path / "out", REFERENCE, labels=LABELS)
    assert (tmp_path / "out" / "steps_to_goal.md").is_file()
    assert not any((tmp_path / "out" / name).exists() for name in ("cost.md", "cost.csv", "pareto.png", "pareto.csv"))
    res = analysis("pareto", root, "--out", tmp_path / "fig")
    assert res.returncode == 1 and res.stderr.strip().splitlines() == [
        f"error: no finished run below {root} records cpu_seconds (summary.json): no cost to plot"]  # fmt: skip


def test_short_names_come_from_the_labels_or_the_keys() -> None:
    rows = pd.DataFrame({"env": ["a", "a", "b"], "row": ["m [k=1]", "m [k=2]", "m [k=1]"]})
    assert short_labels(rows) == {("a", "m [k=1]"): "k=1", ("a", "m [k=2]"): "k=2", ("b", "m [k=1]"): "k=1"}
    assert short_labels(rows, ["today=*k=1]"])[("a", "m [k=1]")] == "today"
    with pytest.raises(ValueError, match="matches 2 rows of a"):
        short_labels(rows, ["both=m *"])
    with pytest.raises(ValueError, match="expected SHORT=GLOB"):
        parse_labels(["no glob"])


def test_the_report_embeds_the_cost_table_and_the_figure(root: Path, tmp_path: Path) -> None:
    args = type("Args", (), {"reference": REFERENCE, "labels": LABELS})()
    write_report(Options(root, tmp_path, [], [], args))  # type: ignore[arg-type]
    text = (tmp_path / "README.md").read_text()
    assert "### Cost per seed" in text and "![pareto](pareto.png)" in text
    assert "--label 'cheap=nsrs [[]planner.horizon=5]'" in text
