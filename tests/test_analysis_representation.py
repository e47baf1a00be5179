"""``python -m studies.representation``: its metrics on inputs with known answers, a tiny end-to-end study, refusals."""

from __future__ import annotations

import json

import numpy as np
import pytest

from studies import representation as rep


def test_auc_counts_pairs_and_halves_ties() -> None:
    assert rep.auc(np.array([2.0, 3.0]), np.array([1.0])) == 1.0
    assert rep.auc(np.array([0.0]), np.array([1.0, 2.0])) == 0.0
    assert rep.auc(np.array([1.0, 3.0]), np.array([1.0, 2.0])) == pytest.approx((0.5 + 0 + 1 + 1) / 4)


def test_nn_r2_is_one_for_an_exact_code_and_about_zero_for_noise() -> None:
    rng = np.random.default_rng(0)
    train_y, test_y = rng.normal(size=(400, 3)), rng.normal(size=(200, 3))
    assert rep.nn_r2(train_y, train_y, test_y, test_y) == pytest.approx(np.ones(3), abs=0.1)
    assert np.all(rep.nn_r2(train_y, train_y, train_y[:50], train_y[:50]) == 1.0)  # exact: its own rows
    noise = rep.nn_r2(rng.normal(size=(400, 2)), train_y, rng.normal(size=(200, 2)), test_y)
    assert np.all(noise < 0.2)  # a latent with no information predicts no better than the mean (R² ≈ −1 for 1-NN)


def test_pumping_states_are_novel_in_the_physical_state(tmp_path, capsys) -> None:
    out = tmp_path / "rows.json"
    code = rep.main(["env.renderer=fast", "--iters", "0,2", "--train-steps", "60", "--probe-steps", "30",
                     "--json", str(out)])  # fmt: skip
    assert code == 0
    table = capsys.readouterr().out
    assert table.count("\n") == 4  # header, rule, two rows, each ending a line
    rows = json.loads(out.read_text())["rows"]
    assert [r["iters"] for r in rows] == [0, 2]
    for r in rows:
        assert 0.0 <= r["auc"] <= 1.0 and len(r["r2"]) == 4 and len(r["latent_std"]) == 4
        # the pumping policy reaches energies random play does not: the physical-state reference must see it
        assert r["auc_physical"] > 0.8


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["baseline=icm"], "baseline=icm"),
        (["env=chain", "encoder=mlp"], "env.obs=state"),
        (["--iters", "5,2"], "--iters=5,2"),
        (["planner.horizon=-1"], "planner.horizon=-1"),
    ],
)
def test_refuses_in_one_line(argv, needle, capsys) -> None:
    assert rep.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err
