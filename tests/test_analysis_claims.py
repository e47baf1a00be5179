"""The Figure 6 / Figure 7 tables (``analysis.claims``) on metrics with known answers: the value at a step is the last
logged one at or before it, runs that ended earlier are left out there, a never-stable run counts at its last step,
and Welch's p is scipy's against the reference rows."""

from __future__ import annotations

import math

import pandas as pd
import pytest
from scipy import stats

from analysis.claims import spread_table, stable_table, to_markdown


def _run(name: str, row: str, steps: list[int], logdet: list[float], reward: list[float]) -> pd.DataFrame:
    return pd.DataFrame({"run_dir": name, "env": "acrobot", "row": row, "step": steps, "info/latent_logdet": logdet,
                         "intrinsic/reward": reward})  # fmt: skip


def _metrics() -> pd.DataFrame:
    steps = list(range(10, 310, 10))  # 30 rows
    flat, noisy = [1.0] * 30, [1.0 if i % 2 else 3.0 for i in range(30)]
    return pd.concat([
        _run("a1", "gp", steps, [float(s) / 100 for s in steps], flat),
        _run("a2", "gp", steps, [float(s) / 50 for s in steps], flat),
        _run("b1", "renyi", steps, [float(s) / 10 for s in steps], noisy),
        _run("b2", "renyi", steps, [float(s) / 20 for s in steps], noisy),
        _run("b3", "renyi", steps[:12], [5.0] * 12, flat[:12]),  # ended at step 120
    ], ignore_index=True)  # fmt: skip


def test_spread_is_each_runs_value_at_the_step_against_the_reference() -> None:
    t = spread_table(_metrics(), reference="gp", steps=(105, 200)).set_index(["row", "step"])
    assert t.loc[("gp", 105)].per_seed == "1.00 2.00"  # the row at step 100, the last at or before 105
    assert t.loc[("renyi", 105)].n == 3 and t.loc[("renyi", 200)].n == 2  # b3 ended at 120: not counted at 200
    expected = stats.ttest_ind([20.0, 10.0], [2.0, 4.0], equal_var=False).pvalue
    assert t.loc[("renyi", 200)].welch_p == pytest.approx(expected, rel=1e-9)
    assert math.isnan(t.loc[("gp", 200)].welch_p)  # the reference itself
    assert t.loc[("renyi", 200)]["mean"] == pytest.approx(15.0) and t.loc[("renyi", 200)].se == pytest.approx(5.0)


def test_a_reward_that_never_settles_counts_at_its_last_step() -> None:
    t = stable_table(_metrics(), reference="gp").set_index("row")
    assert t.loc["gp"].per_seed == "200 200" and t.loc["gp"].stable == 2  # a flat reward: stable once 20 rows exist
    assert t.loc["renyi"].per_seed == ">300 >300 >120" and t.loc["renyi"].stable == 0
    p = stats.ttest_ind([300.0, 300.0, 120.0], [200.0, 200.0], equal_var=False).pvalue
    assert t.loc["renyi"].welch_p == pytest.approx(p, rel=1e-9)
    text = to_markdown(t.reset_index(), "T", "against {reference}", "gp")
    assert "| acrobot | renyi | 0 / 3 | >300 >300 >120 |" in text and "against gp" in text


def test_runs_without_the_columns_give_no_table() -> None:
    m = _metrics().drop(columns=["info/latent_logdet", "intrinsic/reward"])
    assert spread_table(m, "gp").empty and stable_table(m, "gp").empty
    assert spread_table(_metrics(), "gp", steps=(5,)).empty  # nothing logged by step 5
