"""Latent novelty's inputs: each ``input`` name builds its own :class:`LatentNovelty` subclass, ``state_action`` with
a KDE equals its formula worked by hand, and :class:`KDENovelty` is the reward it extends (old checkpoints load)."""

from __future__ import annotations

import re

import numpy as np
import pytest
import torch

from curiosity.intrinsic.base import IntrinsicContext
from curiosity.intrinsic.latent_novelty import INPUTS, NOVELTY_INPUTS, LatentNovelty, StateNovelty
from curiosity.novelty import KDENoveltyReward
from curiosity.novelty.estimators import KDENovelty, KNNNovelty
from curiosity.novelty.memory import EmbeddingMemory
from curiosity.replay import ReplayBuffer

FRAMES = (4, 32, 32)  # square frames: random_target builds its random conv encoder of them
WEIGHTS = torch.linspace(-1.0, 1.0, 18).reshape(6, 3)  # a fixed linear encoder of 6-dimensional observations


def _context(obs_shape: tuple[int, ...], replay: ReplayBuffer) -> IntrinsicContext:
    def encode(obs: torch.Tensor) -> torch.Tensor:
        return obs.flatten(1)[:, :6] @ WEIGHTS

    return IntrinsicContext(n_actions=3, obs_shape=obs_shape, latent_dim=3, warmup_steps=4, replay=replay, encode=encode)


@pytest.mark.parametrize("name", INPUTS)
def test_each_input_builds_its_own_class(name: str) -> None:
    context = _context(FRAMES, ReplayBuffer(10, FRAMES))
    cur = LatentNovelty.from_context(context=context, estimator=KNNNovelty(), input=name)
    assert type(cur) is NOVELTY_INPUTS[name] and isinstance(cur, LatentNovelty) and cur.input == name
    assert (cur.target is not None) == (name == "random_target")
    assert ("novelty/target_loss" in cur.log_keys) == (name == "random_target")


def test_the_four_inputs_are_four_classes_and_an_unknown_one_is_refused_in_one_line() -> None:
    assert INPUTS == ("state_action", "state", "state_motion", "random_target")
    assert len(set(NOVELTY_INPUTS.values())) == 4
    context = _context((6,), ReplayBuffer(10, (6,)))
    message = "novelty input must be one of ('state_action', 'state', 'state_motion', 'random_target'), got 'pixels'"
    with pytest.raises(ValueError, match=re.escape(message)):
        LatentNovelty.from_context(context=context, estimator=KNNNovelty(), input="pixels")
    with pytest.raises(TypeError):  # the base has no input: it says neither what a row is nor how an edge scores
        LatentNovelty(KNNNovelty(), EmbeddingMemory(), context)  # type: ignore[abstract]
    assert type(StateNovelty(KNNNovelty(), EmbeddingMemory(), context)) is StateNovelty


def test_state_action_kde_novelty_equals_its_formula_by_hand() -> None:
    """-log((1/N) Σ_i exp(−‖y − y_i‖² / (2h²))), y = [(z − mean) / std, c·onehot(a)], rows y_i of the replay's o_t."""
    replay = ReplayBuffer(100, (6,))
    estimator = KDENovelty(bandwidth=0.7, baseline="none", bandwidth_rule="fixed")
    cur = LatentNovelty.from_context(context=_context((6,), replay), estimator=estimator, input="state_action",
                                     action_scale=2.0, motion_scale=5.0)  # fmt: skip
    rng = np.random.default_rng(3)
    obs = rng.normal(size=(11, 6)).astype(np.float32)
    for t in range(10):
        replay.add(obs[t], t % 3, -1.0, obs[t + 1], False)
        cur.add(torch.zeros(3), t % 3, t)  # placeholders: the refresh re-encodes every row from the replay
    cur.refresh()
    z = torch.as_tensor(obs[:10], dtype=torch.float64) @ WEIGHTS.double()
    mean, std = z.mean(0), z.std(0, correction=0)
    onehot = torch.eye(3, dtype=torch.float64)
    rows = torch.cat([(z - mean) / std, 2.0 * onehot[np.arange(10) % 3]], dim=1)
    q_z, q_a = torch.as_tensor(rng.normal(size=(5, 3)), dtype=torch.float32), torch.tensor([0, 1, 2, 1, 0])
    y = torch.cat([(q_z.double() - mean) / std, 2.0 * onehot[q_a]], dim=1)
    expected = -torch.exp(-((y[:, None] - rows[None]) ** 2).sum(-1) / (2 * 0.7**2)).mean(1).log()
    got = cur.novelty(q_z, q_a, q_z)
    assert got.shape == (5,) and got.dtype == torch.float32
    torch.testing.assert_close(got.double(), expected, rtol=1e-5, atol=1e-5)


def test_kde_novelty_is_its_reward_and_keeps_the_checkpoint_format() -> None:
    est = KDENovelty(bandwidth=1.0, baseline="scalar", bandwidth_rule="median_nn", standardise=True)
    assert isinstance(est, KDENoveltyReward)  # the baselines and the KDE are its own
    memory = torch.randn(40, 3, generator=torch.Generator().manual_seed(0))
    est.fit(memory, reference=memory[:10])
    state = est.state_dict()
    assert set(state) == {"bandwidth", "reward", "mean", "std"}
    assert set(state["reward"]) == {"baseline", "reference", "log_rho0_bar", "mem_mean", "mem_std"}
    twin = KDENovelty(bandwidth=1.0, baseline="scalar", bandwidth_rule="median_nn", standardise=True)
    twin.load_state_dict(state)
    twin.set_memory(memory)
    query = torch.randn(6, 3, generator=torch.Generator().manual_seed(1))
    assert twin.bandwidth == est.bandwidth != 1.0 and torch.equal(twin(query), est(query))
