"""Every intrinsic reward of the ``intrinsic`` group through the one interface, in both agents that take one."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from curiosity.agents.paper import PaperAgent
from curiosity.agents.q_agent import IntrinsicQAgent
from curiosity.config import build
from curiosity.intrinsic.base import IntrinsicReward
from curiosity.intrinsic.mixture import Mixture, hybrid_intrinsic_reward
from curiosity.runtime.loop import run
from curiosity.types import TransitionBatch
from tests.conftest import compose_cfg

CONF = Path(__file__).resolve().parents[1] / "conf" / "intrinsic"
REGISTERED = sorted(p.stem for p in CONF.glob("*.yaml"))
STATE = ["env.obs=state", "encoder=mlp", "budget=smoke", "budget.warmup_steps=12", "agent.batch_size=8"]
WITH_NOVELTY = ("hybrid", "novelty")  # options with a latent novelty term (its memory refreshes every 5 steps here)
# (option, extra overrides, agent): every option in both agents, where the agent has the parts it needs
OBS_OR_LATENT = ("icm", "rnd", "re3")  # read frames by default; on latents they also score imagined steps
CASES = [
    (name, ["intrinsic.terms.pe.imagined=ensemble", "agent.transition_ensemble=2"] if name == "pe" else [], "paper")
    for name in REGISTERED
    if name not in OBS_OR_LATENT
]
CASES += [(name, [f"intrinsic.terms.{name}.input=latent"], "paper") for name in OBS_OR_LATENT]
CASES += [(name, [], "q") for name in REGISTERED if name not in ("hybrid", "pe")]  # the Q agent has no world model
CASES += [(name, [f"intrinsic.terms.{name}.input=latent"], "q") for name in OBS_OR_LATENT]


def _agent(option: str, extra: list[str], kind: str) -> PaperAgent | IntrinsicQAgent:
    baseline = ["baseline=icm"] if kind == "q" else []  # the Q agent; intrinsic= below picks its reward
    refresh = ["intrinsic.terms.novelty.refresh_every=5"] if option in WITH_NOVELTY else []
    cfg = compose_cfg([*STATE, *baseline, f"intrinsic={option}", *refresh, *extra])
    agent = build(cfg.baseline, cfg=cfg)
    assert isinstance(agent, PaperAgent if kind == "paper" else IntrinsicQAgent)
    rng = np.random.default_rng(0)
    obs = rng.normal(size=6).astype(np.float32)
    for step in range(30):
        nxt = rng.normal(size=6).astype(np.float32)
        agent.observe(obs, int(step % 3), -1.0, nxt, False, step)
        obs = nxt
    return agent


def _batch(agent: PaperAgent | IntrinsicQAgent) -> TransitionBatch:
    batch = agent.replay.sample_transitions(8, np.random.default_rng(1))
    encode = agent._encode_eval
    return batch.with_latents(encode(batch.obs), encode(batch.next_obs))


def _same(a: Any, b: Any) -> bool:
    """Whether two state dicts hold equal values (tensors and arrays element-wise), recursively."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return isinstance(b, (list, tuple)) and len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, torch.Tensor):
        return isinstance(b, torch.Tensor) and a.shape == b.shape and torch.equal(a, b)
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b)
    return bool(a == b)


@pytest.mark.parametrize(("option", "extra", "kind"), CASES)
def test_every_registered_reward_through_the_interface(option: str, extra: list[str], kind: str) -> None:
    """Shapes; ``compute`` and ``imagine`` change no state; a checkpoint round trip scores the same (exactly: same
    machine, same process); every term is an :class:`IntrinsicReward`."""
    agent = _agent(option, extra, kind)
    reward = agent.intrinsic
    assert isinstance(reward, Mixture) and reward.ready
    assert all(isinstance(term, IntrinsicReward) for term in reward.terms.values())
    batch = _batch(agent)
    before = copy.deepcopy(reward.state_dict())
    out = reward.compute(batch)
    assert out.shape == (8,) and torch.isfinite(out).all()
    terms = reward.compute_terms(batch)
    assert set(terms) == set(reward.terms) and all(v.shape == (8,) for v in terms.values())
    if reward.imaginable:
        assert reward.imagine(batch.z, batch.act, batch.z_next).shape == (8,)
    assert _same(before, reward.state_dict()), "compute/imagine changed the reward's state"
    assert set(reward.log_keys) >= {f"intrinsic/{name}" for name in reward.terms}
    twin = _agent(option, extra, kind)  # same seed and inputs: rebuild, then overwrite with the trained state
    twin.intrinsic.load_state_dict(copy.deepcopy(reward.state_dict()))
    if isinstance(agent, PaperAgent):
        twin.model.load_state_dict(agent.model.state_dict())
    # the checkpoint round trip the product promises: the same values, to the bit
    torch.testing.assert_close(twin.intrinsic.compute(batch), out, rtol=0, atol=0)  # exact: same machine, process, inputs


def test_the_hybrid_is_the_papers_equation_11() -> None:
    agent = _agent("hybrid", ["intrinsic.alpha=0.3"], "paper")
    batch = _batch(agent)
    terms = agent.intrinsic.compute_terms(batch)
    expected = hybrid_intrinsic_reward(terms["novelty"], terms["pe"], alpha=0.3)
    torch.testing.assert_close(agent.intrinsic.compute(batch), expected)
    assert agent.intrinsic.weights == pytest.approx({"novelty": 0.7, "pe": 0.3})


def test_imagined_weights_go_to_the_terms_that_imagine() -> None:
    """intrinsic.terms.pe.imagined=off: a planner's imagined steps are scored by novelty with the whole weight (the
    hybrid's total)."""
    off = _agent("hybrid", ["intrinsic.terms.pe.imagined=off"], "paper").intrinsic
    assert off.imagined_weights() == {"novelty": 1.0}
    dropout = _agent("hybrid", ["intrinsic.terms.pe.imagined=dropout", "agent.transition_dropout=0.2"], "paper").intrinsic
    assert dropout.imagined_weights() == {"novelty": 0.5, "pe": 0.5} and dropout.stochastic
    only_pe = _agent("hybrid", ["intrinsic.terms.pe.imagined=off", "intrinsic.alpha=1"], "paper").intrinsic
    assert only_pe.imagined_weights() == {"novelty": 1.0}  # novelty's weight is 0, the only term that imagines
    z, a = torch.randn(5, 4), torch.tensor([0, 1, 2, 0, 1])
    terms = off.imagined_terms(z, a, z)
    assert set(terms) == {"novelty"}
    torch.testing.assert_close(terms["novelty"], off.terms["novelty"].imagine(z, a, z))


def test_mixture_refuses_weights_that_do_not_match_its_terms() -> None:
    pe = _agent("pe", ["intrinsic.terms.pe.imagined=ensemble", "agent.transition_ensemble=2"], "paper").intrinsic.terms["pe"]
    with pytest.raises(ValueError, match="must name every term"):
        Mixture({"pe": pe}, {"novelty": 1.0})
    with pytest.raises(ValueError, match=">= 0"):
        Mixture({"pe": pe}, {"pe": -1.0})


def test_the_planner_refuses_a_reward_that_cannot_imagine() -> None:
    cfg = compose_cfg([*STATE, "intrinsic=rnd"])  # RND on observations: no imagined latent steps
    with pytest.raises(ValueError, match="intrinsic=rnd: no term scores imagined"):
        build(cfg.baseline, cfg=cfg)


@pytest.mark.parametrize("overrides", [["intrinsic=rnd", "intrinsic.terms.rnd.input=latent"],
                                       ["baseline=icm", "intrinsic=novelty"]])  # fmt: skip
def test_a_reward_drives_the_other_agent_end_to_end(tmp_path: Path, overrides: list[str]) -> None:
    """RND (on latents) drives the paper's planner; latent novelty drives the Q agent; both log their term."""
    cfg = compose_cfg(["env.renderer=fast", "progress=false", "budget=smoke", "budget.max_steps=80",
                       "budget.warmup_steps=40", *overrides])  # fmt: skip
    assert run(cfg, tmp_path).env_steps == 80
    header = (tmp_path / "metrics.csv").read_text().splitlines()[0].split(",")
    name = "rnd" if "intrinsic=rnd" in overrides else "novelty"
    assert {f"intrinsic/{name}", "intrinsic/reward"} <= set(header)
    last = dict(zip(header, (tmp_path / "metrics.csv").read_text().splitlines()[-1].split(","), strict=True))
    assert last[f"intrinsic/{name}"] != ""


def test_re3_is_the_log_distance_to_the_kth_neighbour_in_a_fixed_random_space() -> None:
    from curiosity.intrinsic.base import IntrinsicContext
    from curiosity.intrinsic.re3 import RE3

    re3 = RE3.from_context(context=IntrinsicContext(n_actions=3, obs_shape=(6,), latent_dim=4), k=2, capacity=5)
    assert not re3.ready and re3.needs_latents is False
    rng = torch.Generator().manual_seed(0)
    seen = torch.randn(7, 6, generator=rng)
    before = copy.deepcopy(re3.encoder.state_dict())
    re3.observe(TransitionBatch(seen, torch.zeros(7, dtype=torch.long), seen, torch.zeros(7), torch.zeros(7)))
    assert re3.ready and len(re3.memory) == 5  # first in, first out
    query = torch.randn(3, 6, generator=rng)
    batch = TransitionBatch(query, torch.zeros(3, dtype=torch.long), query, torch.zeros(3), torch.zeros(3))
    with torch.no_grad():
        y, memory = re3.encoder(query), re3.encoder(seen[2:])
    expected = torch.log1p(torch.cdist(y, memory).sort(dim=1).values[:, 1])  # the 2nd nearest of the last 5
    torch.testing.assert_close(re3.compute(batch), expected)
    assert _same(before, re3.encoder.state_dict()) and re3.update(batch) == {}  # the encoder never trains
