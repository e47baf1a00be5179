"""Baselines under one interface: each runs end to end; NSRS uses NSRS's parts whatever the groups say."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import torch
from sklearn.neighbors import NearestNeighbors

from curiosity.intrinsic.icm import ICM
from curiosity.intrinsic.rnd import RND
from curiosity.config import build
from curiosity.info.regularisers import GaussianPotentialRegulariser
from curiosity.intrinsic.base import IntrinsicReward
from curiosity.novelty.estimators import NSRSKNNNovelty
from curiosity.planning.qtree import QTreePlanner
from curiosity.runtime.loop import run
from tests.conftest import compose_cfg

FAST = ["env.renderer=fast", "progress=false", "budget=smoke", "budget.max_steps=80", "budget.warmup_steps=40"]


@pytest.mark.parametrize(("baseline", "extra_columns"), [
    ("none", ["losses/transition"]), ("icm", ["losses/icm_inverse", "losses/icm_forward", "losses/q"]),
    ("rnd", ["losses/rnd", "losses/q"]), ("nsrs", ["losses/q", "losses/transition"]), ("random", []),
])  # fmt: skip
def test_each_baseline_runs_and_names_its_method(tmp_path: Path, baseline: str, extra_columns: list[str]) -> None:
    summary = run(compose_cfg([*FAST, f"baseline={baseline}"]), tmp_path)
    assert summary.env_steps == 80
    written = json.loads((tmp_path / "summary.json").read_text())
    assert written["method"] == ("random" if baseline == "random" else summary.method)
    assert written["method"] != "" and (baseline == "none") == written["method"].startswith("ours")
    header = (tmp_path / "metrics.csv").read_text().splitlines()[0].split(",")
    assert set(extra_columns) <= set(header)
    last = dict(zip(header, (tmp_path / "metrics.csv").read_text().splitlines()[-1].split(","), strict=True))
    for column in extra_columns:
        assert last[column] != "" and float(last[column]) == float(last[column])  # trained, logged, not NaN


def test_nsrs_is_a_preset_of_its_own_parts() -> None:
    cfg = compose_cfg(["baseline=nsrs", "env.obs=state", "encoder=mlp"])
    agent = build(cfg.baseline, cfg=cfg)
    assert isinstance(agent.planner, QTreePlanner) and agent.planner.depth == 5 and agent.planner.gamma == 0.8
    assert agent.novelty is not None
    assert isinstance(agent.novelty.estimator, NSRSKNNNovelty) and agent.novelty.estimator.k == 5
    assert isinstance(agent.regulariser, GaussianPotentialRegulariser) and agent.regulariser.t == 2.0
    assert set(agent.optimizers) == {"encoder", "model", "q"} and agent.relabelled is not None  # NSRS's code's steps
    for opt in agent.optimizers.values():
        assert isinstance(opt, torch.optim.RMSprop) and opt.defaults["lr"] == 2.5e-4 and opt.defaults["alpha"] == 0.9
    assert agent.novelty.input == "state" and list(agent.intrinsic.terms) == ["novelty"] and agent.q is not None
    assert agent.model.reward_model is None and agent.cfg.agent.n_step == 1 and agent.cfg.agent.batch_size == 64
    assert not agent.novelty.standardise and agent.cfg.agent.replay_capacity == 10_000


def test_nsrs_parts_given_on_the_command_line_replace_the_presets() -> None:
    """A preset, not a rewrite: an ablation of NSRS names the part it changes."""
    cfg = compose_cfg(["baseline=nsrs", "entropy=renyi", "agent.n_step=2", "env.obs=state", "encoder=mlp"])
    assert cfg.entropy.name == "renyi" and cfg.agent.n_step == 2 and cfg.planner.name == "qtree"
    assert cfg.method_label == "nsrs"


def test_nsrs_knn_novelty_matches_a_nearest_neighbour_oracle() -> None:
    gen = torch.Generator().manual_seed(0)
    memory, query = torch.randn(300, 4, generator=gen), torch.randn(17, 4, generator=gen)
    est = NSRSKNNNovelty(k=5)
    est.fit(memory)
    dist, _ = NearestNeighbors(n_neighbors=5).fit(memory.numpy()).kneighbors(query.numpy())
    expected = torch.as_tensor((dist[:, 1:] ** 2).mean(axis=1), dtype=torch.float32)  # 2nd..5th, squared
    torch.testing.assert_close(est(query), expected, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("baseline", ["icm", "rnd"])
def test_q_baselines_build_their_intrinsic_module(baseline: str) -> None:
    cfg = compose_cfg([f"baseline={baseline}"])
    agent = build(cfg.baseline, cfg=cfg)
    assert isinstance(agent.intrinsic, IntrinsicReward) and cfg.intrinsic.name == baseline  # baseline=X picks intrinsic=X
    assert list(agent.intrinsic.terms) == [baseline] and agent.intrinsic.weights == {baseline: 1.0}
    assert isinstance(agent.intrinsic.terms[baseline], ICM if baseline == "icm" else RND)
