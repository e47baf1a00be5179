"""The paper's agent: every entropy x estimator x backward combination runs; it explores better than random."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch

from curiosity.agents.paper import PaperAgent, build_world_model
from curiosity.nets.world_model import WorldModel
from curiosity.config import build
from curiosity.intrinsic.base import IntrinsicContext
from curiosity.intrinsic.latent_novelty import LatentNovelty, StateActionNovelty, novelty_class
from curiosity.intrinsic.prediction_error import PredictionError
from curiosity.novelty.estimators import KDENovelty, KNNNovelty
from curiosity.novelty.memory import EmbeddingMemory
from curiosity.replay import ReplayBuffer
from curiosity.runtime.loop import run
from curiosity.types import TransitionBatch
from tests.conftest import compose_cfg

FAST = ["env.renderer=fast", "progress=false", "budget=smoke", "budget.max_steps=80", "budget.warmup_steps=40"]


@pytest.mark.parametrize(
    ("entropy", "estimator", "backward"),
    list(itertools.product(["gaussian_potential", "renyi", "renyi_mi", "none"], ["kde", "knn"], ["off", "on"])),
)
def test_every_entropy_estimator_backward_combination_runs(tmp_path: Path, entropy: str, estimator: str,
                                                           backward: str) -> None:  # fmt: skip
    cfg = compose_cfg([*FAST, f"entropy={entropy}", f"estimator={estimator}", f"backward={backward}"])
    summary = run(cfg, tmp_path)
    assert summary.env_steps == 80
    header = (tmp_path / "metrics.csv").read_text().splitlines()[0].split(",")
    assert {"losses/transition", "losses/entropy", "losses/backward", "intrinsic/reward"} <= set(header)
    rows = (tmp_path / "metrics.csv").read_text().splitlines()[1:]
    last = dict(zip(header, rows[-1].split(","), strict=True))
    assert float(last["losses/transition"]) >= 0 and last["intrinsic/reward"] != ""
    assert (last["losses/backward"] != "") == (backward == "on")


@pytest.mark.parametrize("overrides", [["planner=qtree"], ["+experiment=paper_code"], ["+experiment=paper_text"],
                                       ["env=mountaincar", "env.obs=state", "encoder=mlp"]])  # fmt: skip
def test_planners_presets_and_state_observations_run(tmp_path: Path, overrides: list[str]) -> None:
    summary = run(compose_cfg([*FAST, *overrides]), tmp_path)
    assert summary.env_steps == 80


def test_agent_explores_a_chain_better_than_random(tmp_path: Path) -> None:
    """A 61-cell deterministic corridor, 150 steps: a random walk covers ~25% of it, the agent more than half."""
    common = ["env=chain", "encoder=mlp", "progress=false", "budget=smoke", "budget.max_steps=150",
              "budget.warmup_steps=20", "budget.iters_per_train=4"]  # fmt: skip
    agent, rand = [], []
    for seed in (0, 1):
        agent.append(run(compose_cfg([*common, f"seed={seed}"]), tmp_path / f"a{seed}").final_coverage)
        rand.append(run(compose_cfg([*common, "baseline=random", f"seed={seed}"]), tmp_path / f"r{seed}").final_coverage)
    # measured: agent 0.61, 0.54; random 0.21, 0.38
    assert all(a > r for a, r in zip(agent, rand, strict=True)), (agent, rand)
    assert np.mean(agent) >= 1.3 * np.mean(rand) and min(agent) >= 0.45, (agent, rand)


def test_world_model_dropout_disagreement_is_zero_without_dropout() -> None:
    cfg = compose_cfg(["agent.transition_dropout=0.0"])
    model = build_world_model(cfg)
    z, a = torch.randn(5, cfg.agent.internal_dim), torch.tensor([0, 1, 2, 0, 1])
    assert torch.all(model.dropout_disagreement(z, a, samples=4) < 1e-10)  # round-off only
    cfg = compose_cfg(["agent.transition_dropout=0.5"])
    assert torch.all(build_world_model(cfg).dropout_disagreement(z, a, samples=16) > 0)


def _context(model: WorldModel, replay: ReplayBuffer, warmup_steps: int) -> IntrinsicContext:
    def encode(obs: torch.Tensor) -> torch.Tensor:
        with model.evaluating():
            return model.encode(obs)

    return IntrinsicContext(n_actions=3, obs_shape=(6,), latent_dim=4, warmup_steps=warmup_steps, replay=replay,
                            encode=encode, model=model)  # fmt: skip


def _novelty(novelty_input: str, standardise: bool = False, motion_scale: float = 1.0) -> LatentNovelty:
    cfg = compose_cfg(["env.obs=state", "encoder=mlp"])
    model = build_world_model(cfg)
    replay = ReplayBuffer(100, (6,))
    own = {"state_action": {"action_scale": 2.0}, "state_motion": {"motion_scale": motion_scale}}.get(novelty_input, {})
    cur = novelty_class(novelty_input)(KNNNovelty(k=1, normalise=False), EmbeddingMemory(), _context(model, replay, 4),
                                       standardise=standardise, **own)  # fmt: skip
    rng = np.random.default_rng(0)
    obs = rng.normal(size=6).astype(np.float32)
    for t in range(8):
        nxt = rng.normal(size=6).astype(np.float32)
        replay.add(obs, t % 3, -1.0, nxt, False)
        with torch.no_grad():
            z, z_next = model.encode(torch.as_tensor(np.stack([obs, nxt])))
        cur.add(z, t % 3, t, z_next if novelty_input == "state_motion" else None)
        obs = nxt
    cur.refresh()
    return cur


def test_state_action_novelty_sees_the_action() -> None:
    cur = _novelty("state_action")
    y = cur.memory.tensor()
    assert y.shape == (8, cur.encode(torch.zeros(1, 6)).shape[1] + 3)
    z = y[:1, :-3]  # a stored state, with the action it was stored with (0) and another (1)
    assert float(cur.novelty(z, torch.tensor([0]), z)) == pytest.approx(0.0, abs=1e-6)
    query = cur.embed(z, torch.tensor([1]))
    assert torch.equal(query[0, -3:], torch.tensor([0.0, 2.0, 0.0]))  # action_scale * onehot
    expected = (y - query).norm(dim=1).min()  # k = 1: distance to the nearest stored pair
    assert float(cur.novelty(z, torch.tensor([1]), z)) == pytest.approx(float(expected), rel=1e-5)
    assert float(expected) > 0


def test_state_novelty_scores_the_state_reached() -> None:
    cur = _novelty("state")
    z = cur.memory.tensor()
    assert float(cur.novelty(z[:1] + 100.0, torch.tensor([0]), z[:1])) == pytest.approx(0.0, abs=1e-6)


def test_state_motion_novelty_scores_the_state_reached_and_the_latent_motion_into_it() -> None:
    """Rows [s', m·(s' − s)] re-encoded at the refresh from the replay's o_t and o_{t+1}; a stored transition scores 0
    (k = 1), the same state reached with another motion scores its distance; without s the embedding is refused."""
    cur = _novelty("state_motion", motion_scale=3.0)
    y = cur.memory.tensor()
    with torch.no_grad():
        z = cur.encode(cur.replay.obs_at(np.arange(8)))
        z_next = cur.encode(cur.replay.transitions_at(np.arange(8)).next_obs)
    d = z.shape[1]
    assert y.shape == (8, 2 * d)
    torch.testing.assert_close(y, torch.cat([z_next, 3.0 * (z_next - z)], dim=1))  # batch shapes differ: tolerance
    a = torch.tensor([0])
    assert float(cur.novelty(z[:1], a, z_next[:1])) == pytest.approx(0.0, abs=1e-5)
    query = torch.cat([z_next[:1], 3.0 * (z_next[:1] - z[:1] - 1.0)], dim=1)  # the same s', another motion
    expected = (y - query).norm(dim=1).min()
    assert float(cur.novelty(z[:1] + 1.0, a, z_next[:1])) == pytest.approx(float(expected), rel=1e-4) and expected > 0
    with pytest.raises(ValueError, match="z_next"):
        cur.embed(z, torch.zeros(8, dtype=torch.long))


def test_state_motion_standardises_its_two_parts_apart_and_checkpoints_their_statistics() -> None:
    cur = _novelty("state_motion", standardise=True, motion_scale=2.0)
    y = cur.memory.tensor()
    d = y.shape[1] // 2
    torch.testing.assert_close(y[:, :d].mean(0), torch.zeros(d), atol=1e-5, rtol=0)
    torch.testing.assert_close(y[:, :d].std(0, correction=0), torch.ones(d), atol=1e-4, rtol=0)
    torch.testing.assert_close(y[:, d:].std(0, correction=0), torch.full((d,), 2.0), atol=1e-4, rtol=0)
    twin = _novelty("state_motion", standardise=True, motion_scale=2.0)
    twin.m_mean = twin.m_std = None
    twin.load_state_dict(cur.state_dict())
    assert torch.equal(twin.m_mean, cur.m_mean) and torch.equal(twin.m_std, cur.m_std)
    old = {k: v for k, v in cur.state_dict().items() if k not in ("m_mean", "m_std")}  # a checkpoint from before
    twin.load_state_dict(old)
    assert twin.m_mean is None


def test_a_run_with_state_motion_novelty_runs(tmp_path: Path) -> None:
    summary = run(compose_cfg([*FAST, "intrinsic.terms.novelty.input=state_motion"]), tmp_path)
    assert summary.env_steps == 80
    header = (tmp_path / "metrics.csv").read_text().splitlines()[0].split(",")
    last = dict(zip(header, (tmp_path / "metrics.csv").read_text().splitlines()[-1].split(","), strict=True))
    assert last["intrinsic/reward"] != "" and np.isfinite(float(last["intrinsic/reward"]))


def test_prediction_error_bonus_is_used_before_it_is_updated() -> None:
    cfg = compose_cfg(["env.obs=state", "encoder=mlp"])
    model = build_world_model(cfg)
    pe = PredictionError(_context(model, ReplayBuffer(10, (6,)), 4))
    z, a = torch.randn(2, cfg.agent.internal_dim), torch.tensor([0, 1])
    batch = TransitionBatch(torch.zeros(2, 6), a, torch.zeros(2, 6), torch.zeros(2), torch.zeros(2), z=z, z_next=z + 1.0,
                            index=torch.tensor([10, 11]))  # fmt: skip
    before = pe.real.mean
    r = pe.compute(batch)
    assert pe.real.mean == before  # computing does not move the running mean
    logs = pe.observe(batch)
    assert pe.real.mean != before and torch.isfinite(r).all() and logs["intrinsic/pe_error"] > 0
    early = TransitionBatch(*(getattr(batch, k) for k in ("obs", "act", "next_obs", "rewards", "terminateds")), z=z,
                            z_next=z + 1.0, index=torch.tensor([2, 3]))  # fmt: skip
    after = pe.real.mean
    assert pe.observe(early) == {} and pe.real.mean == after  # the warm-up (index < 4) is not folded in


def test_agent_state_dict_round_trip_gives_the_same_actions(tmp_path: Path) -> None:
    cfg = compose_cfg([*FAST, "env.obs=state", "encoder=mlp", "budget.max_steps=60", "budget.warmup_steps=20"])
    agent = build(cfg.baseline, cfg=cfg)
    assert isinstance(agent, PaperAgent)
    rng = np.random.default_rng(0)
    obs = rng.normal(size=6).astype(np.float32)
    for step in range(30):
        nxt = rng.normal(size=6).astype(np.float32)
        agent.observe(obs, step % 3, -1.0, nxt, False, step)
        obs = nxt
    twin = build(cfg.baseline, cfg=cfg)
    twin.load_state_dict(agent.state_dict())
    torch.manual_seed(5)
    a1 = [agent.act(obs, 30 + i) for i in range(5)]
    torch.manual_seed(5)
    a2 = [twin.act(obs, 30 + i) for i in range(5)]
    assert a1 == a2


def test_refresh_takes_the_random_phase_reference_from_the_memory() -> None:
    cfg = compose_cfg(["env.obs=state", "encoder=mlp"])
    model = build_world_model(cfg)
    replay = ReplayBuffer(100, (6,))
    cur = StateActionNovelty(KDENovelty(bandwidth=1.0, bandwidth_rule="fixed"), EmbeddingMemory(),
                             _context(model, replay, 4))  # fmt: skip
    rng = np.random.default_rng(1)
    obs = rng.normal(size=6).astype(np.float32)
    for t in range(10):
        nxt = rng.normal(size=6).astype(np.float32)
        replay.add(obs, t % 3, -1.0, nxt, False)
        cur.add(torch.zeros(cfg.agent.internal_dim), t % 3, t)
        obs = nxt
    cur.refresh()
    with torch.no_grad():
        expected = cur.embed(model.encode(replay.obs_at(np.arange(4))), replay.actions_at(np.arange(4)))
    torch.testing.assert_close(cur.estimator.reference, expected)  # the first 4 transitions, re-encoded
    torch.testing.assert_close(cur.memory.tensor()[:4], expected)


def test_each_observation_is_encoded_once_per_encoder_state() -> None:
    """The plan's z_t is the memory's z_t: without training in between, one encoder pass per env step (o_{t+1});
    with training after every step, two (act must encode o_{t+1} with the changed encoder). A reused latent equals a
    fresh one exactly (same batch of one, same weights, same machine)."""
    from curiosity.envs import make_env

    for iters, passes in ((0, 1), (1, 2)):
        cfg = compose_cfg(["env.renderer=fast", "budget=smoke", "budget.warmup_steps=4", f"budget.iters_per_train={iters}",
                           "agent.batch_size=4", "planner.horizon=2", "agent.probe_every=0"])  # fmt: skip
        agent = PaperAgent(cfg)
        env = make_env(cfg.env, 100)
        obs, _ = env.reset(seed=0)
        calls: list[int] = []
        agent.model.encoder.register_forward_hook(lambda m, inp, out, calls=calls: calls.append(inp[0].shape[0]))
        per_step = []
        for step in range(12):
            before = len(calls)
            action = agent.act(obs, step) if step >= 4 else step % 3
            nxt, r, term, _, _ = env.step(action)
            agent.observe(obs, action, float(r), nxt, bool(term), step)
            per_step.append(sum(1 for c in calls[before:] if c == 1))
            obs = nxt
        assert per_step[1:4] == [1, 1, 1]  # warm-up: o_t was encoded as the previous step's o_{t+1}
        assert per_step[6:] == [passes] * 6, (iters, per_step)
        with agent.model.evaluating():
            fresh = agent.model.encode(torch.as_tensor(obs).unsqueeze(0))[0]
        assert torch.equal(agent.encode_obs(obs), fresh)


def _drive(agent, env, obs, steps: int, executed: list[int], after_step=None, warmup: int = 4):
    """``warmup`` fixed actions (step % 3), then ``steps`` of the agent's, appended to ``executed``; every transition
    observed; ``after_step(step)`` after each. Returns the last observation."""
    for step in range(warmup + steps):
        action = agent.act(obs, step) if step >= warmup else step % 3
        if step >= warmup:
            executed.append(action)
        nxt, r, term, _, _ = env.step(action)
        agent.observe(obs, action, float(r), nxt, bool(term), step)
        obs = nxt
        if after_step is not None:
            after_step(step)
    return obs


def test_planner_commit_executes_the_chosen_sequence_before_planning_again() -> None:
    from curiosity.envs import make_env

    cfg = compose_cfg(["env.renderer=fast", "budget=smoke", "budget.warmup_steps=4", "agent.batch_size=4", "planner.horizon=3",
                       "planner.commit=3", "planner.hold=1", "agent.probe_every=0"])  # fmt: skip
    agent = PaperAgent(cfg)
    env = make_env(cfg.env, 100)
    obs, _ = env.reset(seed=0)
    plans, executed, chosen = 0, [], []
    plan = agent.planner.plan

    def counting_plan(*args, **kwargs):
        nonlocal plans
        plans += 1
        out = plan(*args, **kwargs)
        chosen.extend(out.sequence)
        return out

    agent.planner.plan = counting_plan

    def round_trip(step: int) -> None:
        if step == 8:  # mid-sequence: the queue survives a checkpoint round trip
            state = agent.state_dict()
            assert state["queue"] == agent.queue and len(agent.queue) == 1
            agent.queue = []
            agent.load_state_dict(state)
            assert agent.queue == state["queue"]

    obs = _drive(agent, env, obs, 12, executed, round_trip)
    assert plans == 4 and executed == chosen  # 12 agent steps, 3 actions per plan, every planned action executed
    agent.act(obs, 16)
    assert len(agent.queue) == 2
    agent.observe(obs, 0, -1.0, obs, True, 16)  # a termination that is not the goal: the loop resets the env
    assert agent.queue == []  # the rest of the sequence was planned for the episode that ended


def test_planner_hold_executes_each_planned_action_hold_times() -> None:
    from curiosity.envs import make_env

    cfg = compose_cfg(["env.renderer=fast", "budget=smoke", "budget.warmup_steps=4", "agent.batch_size=4", "planner.horizon=3",
                       "planner.commit=2", "planner.hold=3", "agent.probe_every=0"])  # fmt: skip
    agent = PaperAgent(cfg)
    env = make_env(cfg.env, 100)
    obs, _ = env.reset(seed=0)
    plans: list[list[int]] = []
    plan = agent.planner.plan

    def recording_plan(*args, **kwargs):
        out = plan(*args, **kwargs)
        plans.append(out.sequence)
        return out

    agent.planner.plan = recording_plan
    executed: list[int] = []
    _drive(agent, env, obs, 12, executed)
    assert len(plans) == 2 and all(len(p) == 9 for p in plans)  # 3 planned actions x 3 steps each
    assert executed == plans[0][:6] + plans[1][:6]  # commit 2 held actions: 6 env steps per plan
    assert all(p[0] == p[1] == p[2] and p[3] == p[4] == p[5] for p in plans)


def test_planner_commit_beyond_the_horizon_is_refused() -> None:
    from curiosity.config import ConfigError, validate

    with pytest.raises(ConfigError, match=r"planner.commit=4: must be <= planner.horizon=3"):
        validate(compose_cfg(["planner.horizon=3", "planner.commit=4"]))
    with pytest.raises(ConfigError, match=r"planner.commit=0"):
        validate(compose_cfg(["planner.commit=0"]))


@pytest.mark.parametrize("encoder", ["conv", "mlp"])
def test_a_frozen_encoder_keeps_its_weights_while_the_model_trains(encoder: str) -> None:
    obs_args = ["env.renderer=fast"] if encoder == "conv" else ["env.obs=state", "encoder=mlp"]
    cfg = compose_cfg([*obs_args, "encoder.frozen=true", "agent.batch_size=8"])
    agent = build(cfg.baseline, cfg=cfg)
    before = {k: v.clone() for k, v in agent.model.state_dict().items()}
    rng = np.random.default_rng(0)
    shape = (4, 32, 32) if encoder == "conv" else (6,)
    obs = rng.random(size=shape).astype(np.float32)
    for step in range(20):
        nxt = rng.random(size=shape).astype(np.float32)
        agent.replay.add(obs, step % 3, -1.0, nxt, False)
        obs = nxt
    for _ in range(3):
        agent._iteration()
    after = agent.model.state_dict()
    enc = [k for k in before if k.startswith("encoder.")]
    assert enc and all(torch.equal(before[k], after[k]) for k in enc)
    assert any(not torch.equal(before[k], after[k]) for k in before if k.startswith("transition."))


def test_conv_with_random_features_trains_its_learned_part_only() -> None:
    cfg = compose_cfg(["env.renderer=fast", "encoder=conv_with_random", "agent.internal_dim=6",
                       "encoder.random_dim=2", "agent.batch_size=8"])  # fmt: skip
    agent = build(cfg.baseline, cfg=cfg)
    rng = np.random.default_rng(0)
    obs = rng.random(size=(5, 4, 32, 32)).astype(np.float32)
    assert agent.model.encode(torch.from_numpy(obs)).shape == (5, 6)
    before = {k: v.clone() for k, v in agent.model.encoder.state_dict().items()}
    for step in range(20):
        agent.replay.add(obs[step % 5], step % 3, -1.0, obs[(step + 1) % 5], False)
    for _ in range(3):
        agent._iteration()
    after = agent.model.encoder.state_dict()
    assert all(torch.equal(before[k], after[k]) for k in before if k.startswith("random."))
    assert all(not torch.equal(before[k], after[k]) for k in before if k.startswith("learned.") and "weight" in k)


def test_the_conv_blur_option_is_the_conv_encoder_on_frames_blurred_with_sigma_4() -> None:
    from curiosity.nets.preprocess import GaussianBlur

    cfg = compose_cfg(["encoder=conv_blur"])
    assert cfg.encoder.blur_sigma == 4.0 and cfg.method_label.startswith("ours-conv_blur-")
    torch.manual_seed(0)
    enc = build(cfg.encoder)
    torch.manual_seed(0)
    same = build(compose_cfg(["encoder=conv", "encoder.blur_sigma=4"]).encoder)
    assert [type(m) for m in enc.preprocess] == [GaussianBlur] and enc.preprocess[0].radius == 12  # ⌈3σ⌉
    obs = torch.rand(8, 4, 32, 32) * 2 - 1
    torch.testing.assert_close(enc(obs), same(obs))  # same weights, same computation: the option only sets keys


def test_a_frozen_encoder_is_standardised_at_the_first_training_call(tmp_path: Path) -> None:
    enc = build(compose_cfg(["encoder.frozen=true", "encoder.blur_sigma=4"]).encoder)
    obs = torch.rand(64, 4, 32, 32)
    assert bool((enc(obs).std(0) < 0.1).all())  # uncalibrated, a random encoder's outputs are small
    enc.calibrate(obs)
    z = enc(obs)
    assert torch.allclose(z.mean(0), torch.zeros(4), atol=1e-4)  # float32 rounding only
    assert torch.allclose(z.std(0, correction=0), torch.ones(4), atol=1e-3)
    # in a run: the first training call calibrates, so the next latents' log-det leaves the floor log(1e-3) * d
    run(compose_cfg([*FAST, "encoder.frozen=true", "budget.max_steps=60", "budget.warmup_steps=40", "log_every=5"]),
        tmp_path / "run")  # fmt: skip
    logdet = [float(v) for v in pd.read_csv(tmp_path / "run" / "metrics.csv")["info/latent_logdet"].dropna()]
    assert logdet and min(logdet) > -10.0


def test_mpc_with_a_terminal_value_trains_q_per_env_step_and_scores_the_leaves(tmp_path: Path) -> None:
    """``planner.value_coef`` > 0: the agent trains a Q (TD loss logged) discounted γ^(1/hold) per env step, the plan
    logs the leaves' value spread, and the probe scores the value on both futures; off, there is no Q."""
    cfg = compose_cfg([*FAST, "planner.value_coef=0.25", "agent.probe_every=8"])
    agent = PaperAgent(cfg)
    assert agent.q is not None and agent.q.gamma == pytest.approx(0.9**0.25)  # default hold 4
    assert PaperAgent(compose_cfg(FAST)).q is None
    run(cfg, tmp_path)
    metrics = pd.read_csv(tmp_path / "metrics.csv")
    assert metrics["losses/q"].notna().any() and metrics["planner/spread/value"].dropna().gt(0).any()
    assert metrics["probe/spearman"].notna().any()
