"""Bad input and numerical faults: invalid values are refused before anything is built, a NaN stops the run with its
name and step and keeps the last good checkpoint, and a failed sweep job is reported without stopping the others."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

from curiosity.config import ConfigError, validate
from curiosity.errors import NumericalFault
from curiosity.info import regularisers
from curiosity.runtime.checkpoint import load_checkpoint
from curiosity.runtime.loop import run
from tests.conftest import compose_cfg, run_cli

INVALID = [
    (["budget.max_steps=0"], "budget.max_steps"),
    (["budget.max_steps=64"], "budget.max_steps"),  # the step cap must exceed the 64 warm-up steps
    (["budget.warmup_steps=-1"], "budget.warmup_steps"),
    (["budget.warmup_steps=1"], "budget.warmup_steps"),  # fewer than n_step: no segment to train on
    (["budget.train_every=0"], "budget.train_every"),
    (["budget.iters_per_train=-2"], "budget.iters_per_train"),
    (["estimator.bandwidth=0"], "estimator.bandwidth"),
    (["estimator.bandwidth=-1.5"], "estimator.bandwidth"),
    (["estimator=knn", "estimator.k=0"], "estimator.k"),
    (["estimator=knn", "estimator.k=64"], "estimator.k"),  # no more neighbours than the first memory holds
    (["intrinsic.alpha=1.5"], "intrinsic.alpha"),
    (["intrinsic.alpha=-0.1"], "intrinsic.alpha"),
    (["entropy=renyi", "entropy.alpha=0"], "entropy.alpha"),
    (["entropy=renyi_mi", "entropy.sigma=-2"], "entropy.sigma"),
    (["entropy=renyi", "entropy.base=1"], "entropy.base"),
    (["entropy=gaussian_potential", "entropy.t=0"], "entropy.t"),
    (["planner.horizon=0"], "planner.horizon"),
    (["planner.gamma=1.5"], "planner.gamma"),
    (["planner.temperature=-1"], "planner.temperature"),
    (["backward=on", "backward.sigma_b=0"], "backward.sigma_b"),
    (["agent.transition_dropout=1.0"], "transition_dropout"),
    (["agent.optimizer.lr=0"], "agent.optimizer.lr"),
    (["agent.batch_size=1"], "batch_size"),
    (["agent.n_step=0"], "n_step"),
    (["log_every=0"], "log_every"),
    (["checkpoint_every=0"], "checkpoint_every"),
    (["seed=-1"], "seed"),
    (["intrinsic.terms.novelty.refresh_every=0"], "intrinsic.terms.novelty.refresh_every"),
    (["env.coverage_bins=[10,10,0,10]"], "env.coverage_bins"),
]


@pytest.mark.parametrize(("overrides", "key"), INVALID)
def test_invalid_values_are_refused_naming_key_value_and_rule(overrides: list[str], key: str) -> None:
    with pytest.raises(ConfigError) as info:
        validate(compose_cfg(overrides))
    message = str(info.value)
    assert f"{key}=" in message and "must be" in message, message


def test_at_least_twenty_invalid_configurations() -> None:
    assert len(INVALID) >= 20


def test_a_nan_loss_stops_the_run_naming_term_and_step(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    calls = {"n": 0}
    original = regularisers.GaussianPotentialRegulariser.__call__

    def poisoned(self, z, a, z_next):
        calls["n"] += 1
        loss, logs = original(self, z, a, z_next)
        return (loss * torch.nan, logs) if calls["n"] > 30 else (loss, logs)  # the 31st training iteration

    monkeypatch.setattr(regularisers.GaussianPotentialRegulariser, "__call__", poisoned)
    cfg = compose_cfg(["budget=smoke", "budget.max_steps=120", "budget.warmup_steps=40", "env.renderer=fast",
                       "checkpoint_every=20", "progress=false"])  # fmt: skip
    with pytest.raises(NumericalFault) as info:
        run(cfg, tmp_path)
    # warm-up 40 steps, then one iteration per step from step 40 (index 39): the 31st runs at env step 70
    assert info.value.term == "losses/entropy" and info.value.step == 70
    assert "losses/entropy is nan at env step 70" in str(info.value)
    rows = (tmp_path / "metrics.csv").read_text().lower().splitlines()[1:]
    assert rows and not any("nan" in row or "inf" in row for row in rows)
    assert int(rows[-1].split(",")[0]) == 60  # the last row written is the last full window before the fault
    assert load_checkpoint(tmp_path)["step"] == 60  # the last good checkpoint, kept


def test_a_failed_sweep_job_does_not_stop_the_others_and_is_listed(tmp_path: Path) -> None:
    sweep = tmp_path / "sweep"
    res = run_cli(["-m", "baseline=random", "budget=smoke", "budget.max_steps=100,-5,90", "env.renderer=fast",
                   f"hydra.sweep.dir={sweep}"], cwd=tmp_path)  # fmt: skip
    assert res.returncode != 0
    assert len(list(sweep.rglob("summary.json"))) == 2  # the two good jobs ran to the end
    listing = (sweep / "failed_jobs.txt").read_text().splitlines()
    assert len(listing) == 1 and "budget.max_steps=-5" in listing[0] and "must be an integer >= 1" in listing[0]
    failed_dir = listing[0].split()[0]
    assert Path(failed_dir).is_dir() and failed_dir in res.stderr
