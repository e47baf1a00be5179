"""``python -m studies.encoder_geometry``: its metrics on inputs with known answers, a tiny end-to-end run, refusals."""

from __future__ import annotations

import json

import numpy as np
import pytest

from studies import encoder_geometry as geo


def test_geometry_is_one_for_the_state_itself_and_about_zero_for_noise() -> None:
    rng = np.random.default_rng(0)
    vectors = rng.normal(size=(120, 4))
    exact = geo.geometry(vectors * 3.0 + 1.0, vectors, n_velocity=2)  # any scale and shift: standardised first
    assert exact["rho_all"] == pytest.approx(1.0) and exact["knn"] == pytest.approx(1.0)
    velocity_only = geo.geometry(vectors[:, 2:], vectors, n_velocity=2)
    assert velocity_only["rho_velocity"] == pytest.approx(1.0)
    assert abs(velocity_only["rho_pose"]) < 0.1  # independent columns: the pose distances are unrelated
    noise = geo.geometry(rng.normal(size=(120, 4)), vectors, n_velocity=2)
    assert abs(noise["rho_all"]) < 0.1 and noise["knn"] < 0.25


def test_velocity_read_out_finds_a_small_or_linear_velocity_that_distances_miss() -> None:
    rng = np.random.default_rng(1)
    vectors = rng.normal(size=(300, 4))  # two pose columns, two velocity columns
    pose, velocity = vectors[:, :2], vectors[:, 2:]
    mixed = np.c_[pose, 1e-3 * velocity] @ rng.normal(size=(4, 4))  # velocity in a tiny direction, rotated in
    row = geo.geometry(mixed, vectors, n_velocity=2)
    assert row["r2_velocity_linear"] == pytest.approx(1.0, abs=1e-6)  # a linear read-out finds it exactly
    assert row["rho_velocity"] < 0.1 and row["rho_velocity_white"] > 0.4  # distances see it only once whitened
    blind = geo.geometry(pose + 0.0, vectors, n_velocity=2)
    assert abs(blind["r2_velocity_linear"]) < 0.15 and abs(blind["rho_velocity_white"]) < 0.1  # held out: ≈ 0, noisy
    squared = geo.geometry(np.c_[pose, velocity**2], vectors, n_velocity=2)  # not linear in the velocity
    assert squared["r2_velocity_linear"] < 0.1


def test_knn_overlap_counts_shared_neighbours() -> None:
    a = np.arange(6, dtype=float)[:, None]
    assert geo.knn_overlap(a, a, k=2) == 1.0
    assert geo.knn_overlap(a, a[::-1].copy(), k=2) == 1.0  # the same neighbourhoods in another order


def test_an_end_to_end_run_writes_its_rows(tmp_path, capsys) -> None:
    out = tmp_path / "geometry.json"
    assert geo.main(["env.renderer=fast", "encoder.blur_sigma=2", "--seeds", "0,1", "--states", "30",
                     "--json", str(out)]) == 0  # fmt: skip
    assert capsys.readouterr().out.count("\n") == 5  # header, rule, two seeds, the mean
    result = json.loads(out.read_text())
    assert [r["seed"] for r in result["rows"]] == [0, 1] and result["overrides"][-1] == "encoder.blur_sigma=2"
    assert all(-1.0 <= r["rho_velocity"] <= 1.0 for r in result["rows"])


def test_offline_training_changes_the_encoder(tmp_path) -> None:
    untrained, trained = tmp_path / "u.json", tmp_path / "t.json"
    common = ["env.renderer=fast", "--seeds", "0", "--states", "30"]
    assert geo.main([*common, "--json", str(untrained)]) == 0
    assert geo.main([*common, "--train-iters", "3", "--json", str(trained)]) == 0
    before, after = (json.loads(p.read_text()) for p in (untrained, trained))
    assert after["train_iters"] == 3 and before["train_iters"] == 0
    assert after["mean"] != before["mean"]  # the agent's encoder after three optimiser steps


def test_the_state_vector_encoder_sees_the_velocity(capsys) -> None:
    # a random MLP of Acrobot's state vector weighs the velocities most (they span ±4π and ±9π, the pose ±1)
    assert geo.main(["env.obs=state", "encoder=mlp", "--seeds", "0", "--states", "150"]) == 0
    mean = capsys.readouterr().out.strip().splitlines()[-1].split("|")
    assert float(mean[4]) > float(mean[3])  # rho_velocity > rho_pose


def test_bad_arguments_get_one_line(capsys) -> None:
    assert geo.main(["--seeds", "a"]) == 2
    assert "error: --seeds=a" in capsys.readouterr().err
    assert geo.main(["encoder.blur_sigma=-1", "--states", "20"]) == 2
    assert "encoder.blur_sigma=-1" in capsys.readouterr().err


def test_a_trained_run_is_measured_from_its_checkpoint(tmp_path, capsys) -> None:
    from tests.conftest import compose_cfg
    from tests.test_diagnostics import FAST, finished_run

    finished_run(compose_cfg([*FAST, "agent.probe_every=0", "encoder.blur_sigma=2"]), tmp_path / "run")
    out = tmp_path / "g.json"
    assert geo.main(["--run", str(tmp_path / "run"), "--states", "30", "--json", str(out)]) == 0
    result = json.loads(out.read_text())
    assert result["step"] == 90 and result["rows"][0]["seed"] == "trained"
    assert -1.0 <= result["mean"]["rho_velocity"] <= 1.0
    capsys.readouterr()
    (tmp_path / "run" / "checkpoint.pt").unlink()
    assert geo.main(["--run", str(tmp_path / "run")]) == 2
    assert "no checkpoint.pt" in capsys.readouterr().err
