"""The slowly moving target encoder (``agent.target_tau``): Polyak averaging, no gradient, and what the loss reads."""

from __future__ import annotations

import pytest
import torch
from torch import nn

from curiosity.agents.paper import PaperAgent
from curiosity.agents.representation import LossWeights, encode_segments, representation_terms
from curiosity.nets.polyak import PolyakCopy
from tests.conftest import compose_cfg
from tests.test_agent import _drive


class _Scaled(nn.Module):
    def __init__(self) -> None:
        super().__init__()
        self.lin = nn.Linear(3, 2)
        self.register_buffer("scale", torch.ones(2))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.lin(x) * self.scale


def test_polyak_copy_moves_by_tau_copies_buffers_and_carries_no_gradient() -> None:
    torch.manual_seed(0)
    online = _Scaled()
    target = PolyakCopy(online, tau=0.25)
    before = target.copy.lin.weight.clone()
    with torch.no_grad():
        online.lin.weight.add_(1.0)
        online.scale.fill_(3.0)
    target.update()
    torch.testing.assert_close(target.copy.lin.weight, before + 0.25 * (online.lin.weight - before))
    assert torch.equal(target.copy.scale, online.scale)  # buffers are copied, not averaged
    out = target(torch.ones(4, 3))
    assert out.shape == (4, 2) and not out.requires_grad
    assert [p.requires_grad for p in target.parameters()] == [False, False]
    assert set(target.state_dict()) == {"copy.lin.weight", "copy.lin.bias", "copy.scale"}  # the online module is not saved
    one = PolyakCopy(online, tau=1.0)
    with torch.no_grad():
        online.lin.bias.add_(2.0)
    one.update()
    assert torch.equal(one.copy.lin.bias, online.lin.bias)
    for tau in (0.0, 1.5):
        with pytest.raises(ValueError, match="tau"):
            PolyakCopy(online, tau)


def _filled_agent(overrides: list[str], steps: int) -> PaperAgent:
    """An agent whose replay holds ``steps`` real Acrobot transitions (actions step % 3), before any training."""
    from curiosity.envs import make_env

    cfg = compose_cfg(["env.renderer=fast", "budget=smoke", "agent.batch_size=4", "agent.probe_every=0", *overrides])
    agent = PaperAgent(cfg)
    env = make_env(cfg.env, 100)
    obs, _ = env.reset(seed=0)
    for step in range(steps):
        nxt, r, term, _, _ = env.step(step % 3)
        agent.replay.add(obs, step % 3, float(r), nxt, bool(term))
        obs = nxt
    return agent


def test_the_transition_loss_reads_the_target_encoders_latents_not_the_online_ones() -> None:
    """With a target encoder the n-step targets are its latents (no gradient): replacing the online latents of
    o_{t+1} .. o_{t+n} by anything leaves the transition term as it was; without one, it changes."""
    agent = _filled_agent(["agent.target_tau=0.5", "agent.reward_coef=0"], steps=12)
    assert agent.target_encoder is not None and agent.target_encoder.tau == 0.5
    with torch.no_grad():  # the online encoder moves away from its copy
        for p in agent.model.encoder.parameters():
            p.add_(0.05 * torch.randn_like(p))
    seg = agent.replay.sample_segments(4, 2, agent.rng)
    enc = encode_segments(agent.model, seg, agent.target_encoder)
    assert enc.targets is not None and enc.targets.shape == (4, 2, 4) and not enc.targets.requires_grad
    frames = seg.obs[:, 1:].reshape(8, *seg.obs.shape[2:])
    torch.testing.assert_close(enc.targets, agent.target_encoder(frames).reshape(4, 2, -1))
    weights = LossWeights(reward=0.0, detach_targets=False)

    def transition(e):
        return float(representation_terms(agent.model, seg, e, agent.regulariser, weights)[0]["transition"].detach())

    garbage = torch.cat([enc.z[:, :1], enc.z[:, 1:] + 10.0], dim=1)
    assert transition(type(enc)(garbage, enc.a1h, enc.targets)) == transition(enc)  # exact: the same tensors are read
    online = encode_segments(agent.model, seg)
    assert transition(type(enc)(garbage, online.a1h)) != pytest.approx(transition(online))


def test_an_agent_with_a_target_encoder_trains_it_slowly_and_checkpoints_it() -> None:
    from curiosity.envs import make_env

    cfg = compose_cfg(["env.renderer=fast", "budget=smoke", "budget.warmup_steps=6", "budget.iters_per_train=3",
                       "agent.batch_size=4", "agent.target_tau=0.01", "agent.probe_every=0"])  # fmt: skip
    agent = PaperAgent(cfg)
    assert PaperAgent(compose_cfg(["budget=smoke"])).target_encoder is None  # off by default
    assert agent.target_encoder is not None
    start = [p.clone() for p in agent.target_encoder.parameters()]
    env = make_env(cfg.env, 100)
    _drive(agent, env, env.reset(seed=0)[0], 4, [], warmup=6)
    online = [p.detach() for p in agent.model.encoder.parameters()]
    moved = [float((p - s).abs().max()) for p, s in zip(agent.target_encoder.parameters(), start, strict=True)]
    behind = [float((o - p).abs().max()) for o, p in zip(online, agent.target_encoder.parameters(), strict=True)]
    assert max(moved) > 0 and max(behind) > max(moved)  # it follows the online encoder, slowly
    twin = PaperAgent(cfg)
    twin.load_state_dict(agent.state_dict())
    assert all(torch.equal(a, b) for a, b in zip(twin.target_encoder.parameters(), agent.target_encoder.parameters(),
                                                   strict=True))  # fmt: skip
