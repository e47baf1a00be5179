"""Plug-in terms of the representation loss (``agent.extra_terms``): built from the config, added to L with their
weight, logged, trained with the world model, saved in checkpoints; none configured, the loss is what it was."""

from __future__ import annotations

import torch
from torch import Tensor

from curiosity.agents.representation import Encoded, LossTerm
from curiosity.config import build
from curiosity.nets.world_model import WorldModel
from curiosity.types import SegmentBatch
from tests.test_updates import _filled

HEAD = "tests.test_loss_plugins.InverseHead"


class InverseHead(LossTerm):
    """Which action led from z_t to z_{t+1}: cross-entropy of a linear head on [z_t, z_{t+1}] (a test plug-in)."""

    def __init__(self, latent_dim: int, n_actions: int, coef: float = 1.0) -> None:
        super().__init__(coef)
        self.head = torch.nn.Linear(2 * latent_dim, n_actions)

    def forward(self, model: WorldModel, seg: SegmentBatch, enc: Encoded) -> Tensor:
        logits = self.head(torch.cat([enc.z[:, 0], enc.z[:, 1]], dim=1))
        return torch.nn.functional.cross_entropy(logits, seg.act[:, 0])


def test_a_plug_in_term_is_logged_trained_and_saved(one_thread) -> None:
    agent = _filled([f"+agent.extra_terms.inverse={{_target_: {HEAD}, coef: 0.5}}"], steps=16)
    term = agent.extra_terms["inverse"]
    assert type(term).__name__ == "InverseHead" and term.coef == 0.5  # built from its _target_
    assert "losses/inverse" in agent.metric_keys
    before = term.head.weight.detach().clone()
    logs = agent._train(3)
    assert logs["losses/inverse"] > 0
    assert not torch.equal(term.head.weight, before)  # the head is in the optimiser: its weights moved
    state = agent.state_dict()
    other = build(agent.cfg.baseline, cfg=agent.cfg)
    other.load_state_dict(state)
    assert torch.equal(other.extra_terms["inverse"].head.weight, term.head.weight)  # exact: a copy of the saved tensor


def test_the_total_is_the_weighted_sum_with_the_plug_in_term(one_thread) -> None:
    agent = _filled([f"+agent.extra_terms.inverse={{_target_: {HEAD}, coef: 0.5}}"], steps=16)
    logs, _ = agent._iteration()
    weights = {"transition": 1.0, "entropy": 1.0, "reward": float(agent.cfg.agent.reward_coef), "inverse": 0.5}
    expected = sum(w * logs[f"losses/{k}"] for k, w in weights.items() if f"losses/{k}" in logs)
    assert abs(logs["losses/total"] - expected) <= 1e-4 * max(1.0, abs(expected))  # float sums in another order


def test_without_plug_ins_no_extra_column_and_no_checkpoint_entry(one_thread) -> None:
    agent = _filled([], steps=14)
    assert len(agent.extra_terms) == 0 and "extra_terms" not in agent.state_dict()
    assert not [k for k in agent.metric_keys if k.startswith("losses/") and k.split("/")[1] not in
                ("transition", "entropy", "reward", "backward", "total", "q")]  # fmt: skip
