"""Random-target novelty (``intrinsic.terms.novelty.input=random_target``): a frozen random conv encoder R of the
frames holds the memory, a head g predicts R's codes from the agent's latent for imagined steps."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch

from curiosity.config import ConfigError, validate
from curiosity.intrinsic.base import IntrinsicContext
from curiosity.intrinsic.latent_novelty import LatentNovelty
from curiosity.novelty.estimators import KNNNovelty
from curiosity.novelty.random_target import RandomTarget, target_loss
from curiosity.replay import ReplayBuffer
from curiosity.runtime.loop import run
from curiosity.types import TransitionBatch
from tests.conftest import compose_cfg

SHAPE = (4, 32, 32)


def _frames(n: int, seed: int) -> torch.Tensor:
    """Frames of a bright square at random places (what R's blur and convolutions see of a moving link)."""
    rng = np.random.default_rng(seed)
    out = np.zeros((n, *SHAPE), dtype=np.float32)
    for i in range(n):
        r, c = rng.integers(0, 24, size=2)
        out[i, :, r : r + 8, c : c + 8] = 1.0
    return torch.as_tensor(out)


def test_the_random_encoder_is_frozen_standardised_once_and_the_head_learns_its_codes() -> None:
    target = RandomTarget(SHAPE, latent_dim=4, seed=3)
    frames = _frames(128, 0)
    target.calibrate(frames)
    codes = target.codes(frames)
    assert codes.shape == (128, 4)
    torch.testing.assert_close(codes.mean(0), torch.zeros(4), atol=1e-4, rtol=0)  # standardised on these frames
    torch.testing.assert_close(codes.std(0, correction=0), torch.ones(4), atol=1e-3, rtol=0)
    target.calibrate(_frames(128, 1))  # once: a second call changes nothing
    torch.testing.assert_close(target.codes(frames), codes, atol=1e-6, rtol=0)
    weights = {k: v.clone() for k, v in target.encoder.state_dict().items()}
    z = codes @ torch.tensor([[1.0, 0.5, 0.0, 0.0], [0.0, 1.0, 0.2, 0.0], [0.0, 0.0, 1.0, -0.3], [0.1, 0.0, 0.0, 1.0]])
    first = target.fit_step(z, frames)
    for _ in range(400):
        last = target.fit_step(z, frames)
    assert last < 0.3 * first, (first, last)  # measured: 3.89 -> 0.010
    assert all(torch.equal(v, target.encoder.state_dict()[k]) for k, v in weights.items())  # exact: R never trains
    assert float(target_loss(target.predict(z), codes)) < 0.3 * first


def test_building_a_random_target_keeps_the_run_random_stream() -> None:
    torch.manual_seed(11)
    before = torch.get_rng_state()
    RandomTarget(SHAPE, latent_dim=4, seed=0)
    assert torch.equal(torch.get_rng_state(), before)  # exact: the draws happen in a forked generator
    a, b = RandomTarget(SHAPE, 4, seed=5), RandomTarget(SHAPE, 4, seed=5)
    assert all(torch.equal(v, b.state_dict()[k]) for k, v in a.state_dict().items())  # same seed, same R and g


def test_a_random_target_needs_square_frames() -> None:
    with pytest.raises(ValueError, match=re.escape("square image frames (env.obs=pixels); got an observation of shape (6,)")):
        RandomTarget((6,), latent_dim=4)


def _novelty() -> tuple[LatentNovelty, ReplayBuffer]:
    replay = ReplayBuffer(100, SHAPE)

    def encode(obs: torch.Tensor) -> torch.Tensor:  # a stand-in latent: the mean brightness of four quadrants
        return torch.stack([obs[:, -1, :16, :16], obs[:, -1, :16, 16:], obs[:, -1, 16:, :16], obs[:, -1, 16:, 16:]],
                           1).mean((2, 3))  # fmt: skip

    context = IntrinsicContext(n_actions=3, obs_shape=SHAPE, latent_dim=4, warmup_steps=6, replay=replay, encode=encode)
    cur = LatentNovelty.from_context(context=context, estimator=KNNNovelty(k=1, normalise=False), input="random_target")
    frames = _frames(9, 2)
    for t in range(8):
        replay.add(frames[t].numpy(), t % 3, -1.0, frames[t + 1].numpy(), False)
        cur.observe(_batch(frames[t : t + 1], frames[t + 1 : t + 2], t, encode))
    return cur, replay


def _batch(
    obs: torch.Tensor, nxt: torch.Tensor, index: int, encode: Callable[[torch.Tensor], torch.Tensor]
) -> TransitionBatch:
    return TransitionBatch(obs, torch.tensor([index % 3]), nxt, torch.tensor([-1.0]), torch.tensor([0.0]),
                           z=encode(obs), z_next=encode(nxt), index=torch.tensor([index]))  # fmt: skip


def test_random_target_novelty_keeps_r_codes_in_memory_and_scores_imagined_latents_through_the_head() -> None:
    cur, replay = _novelty()
    assert cur.ready and bool(cur.target.calibrated)  # the refresh at the warm-up's end standardised R
    assert "novelty/target_loss" in cur.log_keys
    obs = replay.obs_at(np.arange(8))
    codes = cur.target.codes(obs)
    torch.testing.assert_close(cur.memory.tensor(), cur._std(codes), atol=1e-4, rtol=1e-4)  # rows: R(o_t); batch shapes differ
    # a real transition is scored by R's code of the frame it reached: a frame in memory scores 0 (k = 1)
    real = TransitionBatch(obs[:1], torch.tensor([0]), obs[3:4], torch.zeros(1), torch.zeros(1))
    assert float(cur.compute(real)) == pytest.approx(0.0, abs=1e-3)  # encoded alone, not in a batch of 8: round-off
    # an imagined latent is scored by the head's code for it
    z = torch.randn(5, 4)
    expected = (cur.memory.tensor()[None] - cur._std(cur.target.predict(z))[:, None]).norm(dim=2).min(1).values
    torch.testing.assert_close(cur.imagine(z, torch.zeros(5, dtype=torch.long), z), expected, atol=1e-5, rtol=1e-5)
    # training moves the head only, towards R's codes
    batch = _batch(obs, replay.transitions_at(np.arange(8)).next_obs, 0, cur.encode)
    losses = [cur.update(batch)["novelty/target_loss"] for _ in range(300)]
    assert losses[-1] < 0.5 * losses[0], (losses[0], losses[-1])


def test_random_target_novelty_checkpoints_the_head_and_its_optimiser() -> None:
    cur, _ = _novelty()
    twin, _ = _novelty()
    z = torch.randn(4, 4)
    for _ in range(5):
        cur.update(_batch(_frames(4, 7), _frames(4, 8), 0, cur.encode))
    twin.load_state_dict(cur.state_dict())
    a = torch.zeros(4, dtype=torch.long)
    assert torch.equal(twin.imagine(z, a, z), cur.imagine(z, a, z))  # exact: same machine, same inputs and shapes
    batch = _batch(_frames(4, 9), _frames(4, 10), 0, cur.encode)
    assert twin.update(batch) == cur.update(batch)  # the optimiser's moments came along


def test_random_target_novelty_on_state_observations_is_refused_in_one_line() -> None:
    overrides = ["env.obs=state", "encoder=mlp", "intrinsic.terms.novelty.input=random_target"]
    with pytest.raises(ConfigError, match=re.escape("intrinsic.terms.novelty.input=random_target: encodes frames")) as info:
        validate(compose_cfg(overrides))
    assert "\n" not in str(info.value)


def test_a_run_with_random_target_novelty_trains_its_head(tmp_path: Path) -> None:
    fast = ["env.renderer=fast", "progress=false", "budget=smoke", "budget.max_steps=80", "budget.warmup_steps=40"]
    summary = run(compose_cfg([*fast, "intrinsic.terms.novelty.input=random_target"]), tmp_path)
    assert summary.env_steps == 80
    lines = (tmp_path / "metrics.csv").read_text().splitlines()
    header = lines[0].split(",")
    losses = [float(v) for row in lines[1:] if (v := dict(zip(header, row.split(","), strict=True))["novelty/target_loss"])]
    assert losses and all(np.isfinite(losses)), losses


def test_the_code_term_trains_the_encoder_and_transition_to_predict_the_codes_but_not_the_head(tmp_path: Path) -> None:
    """``agent.code_coef`` > 0: L gains the n-step code loss (logged as ``losses/code``); its gradient reaches the
    encoder and the transition model, never the head g (which keeps its own fit); it needs random-code novelty."""
    from curiosity.agents.paper import PaperAgent
    from curiosity.agents.representation import encode_segments
    from curiosity.envs import make_env
    from tests.test_agent import _drive

    cfg = compose_cfg(["env.renderer=fast", "budget=smoke", "budget.warmup_steps=8", "budget.iters_per_train=2",
                       "agent.batch_size=4", "agent.probe_every=0", "intrinsic.terms.novelty.input=random_target",
                       "agent.code_coef=0.5"])  # fmt: skip
    agent = PaperAgent(cfg)
    term = agent.extra_terms["code"]
    assert term.coef == 0.5 and not list(term.parameters())  # g is the novelty's, not the term's
    assert "losses/code" in agent.metric_keys and "code" not in PaperAgent(compose_cfg(["budget=smoke"])).extra_terms
    env = make_env(cfg.env, 100)
    _drive(agent, env, env.reset(seed=0)[0], 4, [], warmup=8)
    target = agent.novelty.target
    assert bool(target.calibrated)
    seg = agent.replay.sample_segments(4, 2, agent.rng)
    agent.model.zero_grad(set_to_none=True)
    target.head.zero_grad(set_to_none=True)
    loss = term(agent.model, seg, encode_segments(agent.model, seg))
    loss.backward()
    assert float(loss.detach()) > 0
    assert all(p.grad is None for p in target.head.parameters())
    assert any(p.grad is not None and float(p.grad.abs().sum()) > 0 for p in agent.model.encoder.parameters())
    assert any(p.grad is not None and float(p.grad.abs().sum()) > 0 for p in agent.model.transition.parameters())
    with pytest.raises(ConfigError, match=re.escape("agent.code_coef=0.5: the model predicts the random codes")):
        validate(compose_cfg(["agent.code_coef=0.5", "intrinsic.terms.novelty.input=state"]))
    summary = run(compose_cfg(["env.renderer=fast", "progress=false", "budget=smoke", "budget.max_steps=80",
                               "budget.warmup_steps=40", "intrinsic.terms.novelty.input=random_target",
                               "agent.code_coef=1"]), tmp_path)  # fmt: skip
    codes = pd.read_csv(tmp_path / "metrics.csv")["losses/code"].dropna()
    assert summary.env_steps == 80 and len(codes) and (codes > 0).all()
