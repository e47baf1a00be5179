"""``analysis.verdicts``: the fixed rule that turns the committed tables into one verdict per paper claim, on samples
with known outcomes and on tables the analysis writes from synthetic runs."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
from scipy import stats

from analysis.tables import write_tables
from analysis.verdicts import (CLAIMS, NOT_SUPPORTED, OURS, PENDING, REVERSED, SUPPORTED, claim_verdict, judge,
                               seed_values, to_markdown, verdicts)  # fmt: skip
from tests.synthetic_runs import make_run
from tests.test_analysis import analysis

FAST = [300.0, 320, 280, 310, 290, 305, 295, 315, 285, 300]
SLOW = [900.0, 950, 870, 910, 890, 905, 930, 880, 940, 920]
NOISY = [100.0, 600, 150, 550, 200, 500, 250, 450, 300, 400]  # mean 350: not told apart from FAST


@pytest.mark.parametrize(("relation", "a", "b", "expected"), [
    ("<", FAST, SLOW, SUPPORTED), ("<", SLOW, FAST, REVERSED), ("<", FAST, NOISY, NOT_SUPPORTED),
    (">", SLOW, FAST, SUPPORTED), (">", FAST, SLOW, REVERSED),
    ("≈", FAST, NOISY, SUPPORTED), ("≈", FAST, SLOW, NOT_SUPPORTED),
    ("≮", SLOW, FAST, SUPPORTED), ("≮", FAST, NOISY, SUPPORTED), ("≮", FAST, SLOW, REVERSED),
])  # fmt: skip
def test_each_relation_follows_the_rule(relation: str, a: list[float], b: list[float], expected: str) -> None:
    verdict, p = judge(relation, a, b)
    assert verdict == expected
    assert p == pytest.approx(stats.ttest_ind(a, b, equal_var=False).pvalue, rel=1e-12)


def test_a_claim_is_supported_only_when_every_comparison_is() -> None:
    assert claim_verdict([SUPPORTED, SUPPORTED]) == SUPPORTED
    assert claim_verdict([SUPPORTED, NOT_SUPPORTED]) == NOT_SUPPORTED
    assert claim_verdict([SUPPORTED, REVERSED]) == REVERSED
    assert claim_verdict([REVERSED, PENDING]) == PENDING  # no verdict from an unfinished table


def test_per_seed_text_reads_censored_runs_at_their_last_step() -> None:
    assert seed_values("857 368 >3000") == [857.0, 368.0, 3000.0]
    assert seed_values("0.17 -12.64") == [0.17, -12.64]


def _table1(root: Path, nsrs_seeds: int = 10) -> Path:
    """results/table1 from synthetic runs: ours fast, NSRS slower, ICM and RND alike and slowest."""
    runs = root / "table1"
    for seed in range(10):
        make_run(runs, "acrobot", OURS, seed, int(FAST[seed]))
        make_run(runs, "acrobot", "icm", seed, int(NOISY[seed]) + 1000)
        make_run(runs, "acrobot", "rnd", seed, int(NOISY[::-1][seed]) + 1050)
    for seed in range(nsrs_seeds):
        make_run(runs, "acrobot", "nsrs", seed, int(SLOW[seed]) - 300)
    write_tables(runs, runs / "report", reference="nsrs*")
    return root


def test_table_1_from_the_tables_the_analysis_writes(tmp_path: Path) -> None:
    table = verdicts(_table1(tmp_path)).set_index(["claim", "a", "b"])
    t1 = table.loc["Table 1"]
    assert list(t1[t1["counts"]]["verdict"]) == [SUPPORTED, SUPPORTED, SUPPORTED]
    assert set(t1[~t1["counts"]]["verdict"]) == {PENDING}  # no paper_text, paper_code or oracle rows: shown pending,
    assert set(t1["claim_verdict"]) == {SUPPORTED}  # and not part of the claim's verdict
    ours = table.loc[("Table 1", OURS, "nsrs*")]
    steps = pd.read_csv(tmp_path / "table1" / "report" / "steps_to_goal.csv").set_index("row")
    assert ours.a_mean == steps.loc[OURS, "mean"] and ours.a_n == 10  # the table's own numbers
    assert ours.welch_p == pytest.approx(steps.loc[OURS, "welch_p"], rel=1e-6)  # the table's test against NSRS
    assert set(table.drop(index="Table 1")["verdict"]) == {PENDING}  # the other presets have no tables


def test_a_row_short_of_its_seeds_or_a_missing_row_leaves_the_claim_pending(tmp_path: Path) -> None:
    table = verdicts(_table1(tmp_path, nsrs_seeds=9)).set_index(["claim", "a", "b"])
    assert table.loc[("Table 1", OURS, "nsrs*")].why == "nsrs: 9 of 10 seeds"
    assert set(table.loc["Table 1"]["claim_verdict"]) == {PENDING}
    assert {c.name for c in CLAIMS} == set(table.index.get_level_values("claim"))


def test_the_command_writes_the_verdicts_and_refuses_a_missing_directory(tmp_path: Path) -> None:
    root = _table1(tmp_path)
    res = analysis("verdicts", root)
    assert res.returncode == 0, res.stderr
    text = (root / "verdicts.md").read_text()
    assert "**Table 1: supported**" in text and "**Table 2: pending**" in text
    bad = analysis("verdicts", tmp_path / "nowhere")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "no such directory" in bad.stderr


def _fig6(root: Path, gaussian_finished: int) -> Path:
    """results/fig6/report with the tables Figure 6's claim reads: the Rényi arm's spread at env step 200 on 6 runs,
    the Gaussian potential's on 5 (its sixth run reached the goal before step 200), ``gaussian_finished`` runs of it."""
    report = root / "fig6" / "report"
    report.mkdir(parents=True)
    renyi, gauss = "ours-conv_blur-renyi-kde-backward_off-mpc", "ours-conv_blur-gaussian_potential-kde-backward_off-mpc"
    spread = pd.DataFrame({"env": "acrobot", "row": [renyi, gauss], "step": 200,
                           "per_seed": ["7.0 6.2 6.9 7.3 5.4 5.6", "6.0 4.8 3.9 4.5 4.6"], "n": [6, 5],
                           "mean": [6.4, 4.76], "se": [0.3, 0.34]})  # fmt: skip
    spread.to_csv(report / "spread.csv", index=False)
    finished = pd.DataFrame({"env": "acrobot", "row": [renyi, gauss], "seeds": [6, gaussian_finished]})
    finished.to_csv(report / "steps_to_goal.csv", index=False)
    return root


def test_a_value_at_a_step_counts_the_finished_runs_and_tests_those_still_going(tmp_path: Path) -> None:
    """Figure 6 compares the spread at env step 200: a run that reached the goal earlier has no value there and does
    not hold the claim pending; a run not yet finished does."""
    fig6 = verdicts(_fig6(tmp_path / "done", gaussian_finished=6)).set_index("claim").loc["Figure 6"]
    assert (fig6.verdict, fig6.a_n, fig6.b_n, fig6.b_runs, fig6.why) == (SUPPORTED, 6, 5, 6, "")
    assert fig6.welch_p == pytest.approx(stats.ttest_ind([7.0, 6.2, 6.9, 7.3, 5.4, 5.6], [6.0, 4.8, 3.9, 4.5, 4.6],
                                                         equal_var=False).pvalue, rel=1e-12)  # fmt: skip
    assert "(n = 5 of 6 runs; 1 ended before the step)" in to_markdown(verdicts(tmp_path / "done"))
    waiting = verdicts(_fig6(tmp_path / "running", gaussian_finished=5)).set_index("claim").loc["Figure 6"]
    assert waiting.verdict == PENDING and waiting.why.endswith("gaussian_potential-kde-backward_off-mpc: 5 of 6 seeds")


def _noisy_tv(root: Path, hybrid_tv_seeds: int = 8) -> Path:
    """results/noisy_tv from synthetic runs, seeds 0–7: prediction error alone (``ours_pe``) presses the TV often and
    is slowed by it; density alone and the hybrid press it about as a random policy does (1/4) and are not."""
    runs = root / "noisy_tv"
    for seed in range(8):
        jitter = 0.01 * (seed % 4)
        for method, clean, tv, rate in (("ours_pe", FAST, SLOW, 0.6), ("ours_density", FAST, FAST, 0.25),
                                        ("ours_hybrid", FAST, NOISY, 0.3), ("icm", SLOW, SLOW, 0.5),
                                        ("rnd", SLOW, SLOW, 0.26)):  # fmt: skip
            make_run(runs, "acrobot", method, seed, int(clean[seed]))
            if method != "ours_hybrid" or seed < hybrid_tv_seeds:
                make_run(runs, "acrobot", method, seed, int(tv[seed]), distractor="noisy_tv", tv_rate=rate + jitter)
    write_tables(runs, runs / "report")
    return root


def test_the_noisy_tv_claim_reads_the_tv_presses_and_steps_of_the_distractor_table(tmp_path: Path) -> None:
    table = verdicts(_noisy_tv(tmp_path)).set_index("claim")
    tv = table.loc[next(c.name for c in CLAIMS if c.preset == "noisy_tv")]
    counted = tv[tv["counts"]]
    assert list(counted["readout"]) == ["tv_presses", "tv_presses", "tv_steps"]
    assert list(counted["verdict"]) == [SUPPORTED, SUPPORTED, SUPPORTED] and set(tv["claim_verdict"]) == {SUPPORTED}
    pe_density = counted.iloc[0]
    rates = pd.read_csv(tmp_path / "noisy_tv" / "report" / "distractor.csv").set_index(["method", "distractor"])
    assert (pe_density.a_row, pe_density.b_row) == ("ours_pe (TV: noisy_tv)", "ours_density (TV: noisy_tv)")
    assert pe_density.a_mean == rates.loc[("ours_pe", "noisy_tv"), "tv_rate"] and pe_density.a_n == 8
    assert pe_density.welch_p == pytest.approx(stats.ttest_ind([0.6 + 0.01 * (s % 4) for s in range(8)],
                                                               [0.25 + 0.01 * (s % 4) for s in range(8)],
                                                               equal_var=False).pvalue, rel=1e-6)  # fmt: skip
    beside = tv[~tv["counts"]].set_index("a")
    assert beside.loc["ours_pe (TV: noisy_tv)", "verdict"] == SUPPORTED  # the TV slows prediction error alone
    assert beside.loc["ours_density (TV: noisy_tv)", "verdict"] == NOT_SUPPORTED  # and not density alone
    assert "`ours_pe (TV: noisy_tv)`: 0.615 ± 0.004 (n = 8)" in to_markdown(verdicts(tmp_path))


def test_the_noisy_tv_claim_waits_for_every_seed_with_the_tv(tmp_path: Path) -> None:
    table = verdicts(_noisy_tv(tmp_path, hybrid_tv_seeds=7)).set_index("claim")
    tv = table.loc[next(c.name for c in CLAIMS if c.preset == "noisy_tv")]
    assert set(tv["claim_verdict"]) == {PENDING}
    assert tv[tv["counts"]].iloc[1].why == "ours_hybrid (TV: noisy_tv): 7 of 8 seeds"
