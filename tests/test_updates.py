"""NSRS's training as its code runs it (``agent.updates=nsrs``, ``agent.q_intrinsic=relabel``), against our default
(``joint``, ``batch``): which parameters each step moves, the relabelled rewards, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from curiosity.agents.relabel import RelabelledRewards
from curiosity.agents.updates import TDTerm, build_optimizers, step, update_rule
from curiosity.config import build, validate
from curiosity.config.validate import ConfigError
from tests.conftest import compose_cfg

STATE = ["env.obs=state", "encoder=mlp", "budget=smoke", "budget.warmup_steps=12", "agent.batch_size=8"]


def _filled(overrides: list[str], steps: int = 40):
    """The paper's agent (``overrides``) with ``steps`` random transitions of Acrobot's state in its replay."""
    from curiosity.envs import make_env

    cfg = compose_cfg([*STATE, *overrides])
    env = make_env(cfg.env, 1000)
    agent = build(cfg.baseline, cfg=cfg)
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    for t in range(steps):
        a = int(rng.integers(3))
        nxt, r, term, _, _ = env.step(a)
        agent.observe(obs, a, r, nxt, term, t)
        obs = nxt
    return agent


def test_nsrs_rule_steps_the_encoder_twice_in_the_representation_step_and_again_in_the_q_step() -> None:
    torch.manual_seed(0)
    enc, model, q = torch.nn.Linear(2, 2), torch.nn.Sequential(), torch.nn.Linear(2, 1)
    model.add_module("encoder", enc)
    model.add_module("transition", torch.nn.Linear(2, 2))
    opts = build_optimizers("nsrs", {"_target_": "torch.optim.SGD", "lr": 0.1}, model, enc, q)
    assert set(opts) == {"encoder", "model", "q"}
    before, transition = enc.weight.detach().clone(), model.transition.weight.detach().clone()
    loss = enc(torch.ones(1, 2)).sum()
    step((opts["encoder"], opts["model"]), loss)
    # SGD: two steps of the same gradient (ones): the encoder moves 2 x lr, the transition model not at all
    assert torch.allclose(enc.weight, before - 0.2, atol=1e-6) and torch.equal(model.transition.weight, transition)
    q_before = q.weight.detach().clone()
    step((opts["q"],), 100.0 * q(enc(torch.ones(1, 2))).sum(), clamp=1.0)
    assert float((q.weight.detach() - q_before).abs().max()) <= 0.1 + 1e-6  # the clamped gradient: at most lr x 1 per entry
    joint = build_optimizers("joint", {"_target_": "torch.optim.SGD", "lr": 0.1}, model, enc, q)
    assert set(joint) == {"all"} and len(joint["all"].param_groups[0]["params"]) == 6


def _rule_parts():
    torch.manual_seed(0)
    enc, model, q = torch.nn.Linear(2, 2), torch.nn.Sequential(), torch.nn.Linear(2, 1)
    model.add_module("encoder", enc)
    model.add_module("transition", torch.nn.Linear(2, 2))
    return enc, model, q


@pytest.mark.parametrize("name", ["joint", "nsrs"])
def test_an_update_rule_owns_its_steps_and_builds_losses_total_from_the_weighted_terms(name: str) -> None:
    """Both rules log losses/total = Σ_k w_k L_k (the TD term weighted by w_q) and losses/q unweighted; joint scores the
    TD term on the iteration's latents, nsrs re-encodes it after the representation step and skips call 1."""
    enc, model, q = _rule_parts()
    rule = update_rule(name, {"_target_": "torch.optim.SGD", "lr": 0.1}, model, enc, q)
    assert rule.name == name and rule.steps_q(2) and rule.steps_q(1) == (name == "joint")
    x = torch.ones(1, 2)
    called: list[str] = []

    def td(which: str):
        def loss():
            called.append(which)
            return q(enc(x)).square().sum()
        return loss

    rep = {"transition": model.transition(enc(x)).square().sum()}
    weights = {"transition": 2.0, "q": 0.5}
    rep_value, q_value = rep["transition"].item(), q(enc(x)).square().sum().item()
    logs = rule.apply(rep, weights, TDTerm(on_latents=td("on_latents"), fresh=td("fresh")))
    assert called == (["on_latents"] if name == "joint" else ["fresh"])
    if name == "joint":  # both terms scored before the one step
        assert logs["losses/q"] == pytest.approx(q_value, rel=1e-6)
        assert logs["losses/total"] == pytest.approx(2.0 * rep_value + 0.5 * q_value, rel=1e-6)
    else:  # the Q step after the representation step: its TD loss is the re-encoded one
        assert logs["losses/total"] == pytest.approx(2.0 * rep_value + 0.5 * logs["losses/q"], rel=1e-6)
        assert logs["losses/q"] != pytest.approx(q_value, rel=1e-6)  # the encoder had moved
    no_q = rule.apply({"transition": model.transition(enc(x)).square().sum()}, weights, None)
    assert set(no_q) == {"losses/total"}


def test_an_unknown_update_rule_is_refused_in_one_line() -> None:
    enc, model, q = _rule_parts()
    with pytest.raises(ValueError, match=r"agent.updates=adam: allowed: joint, nsrs"):
        update_rule("adam", {"_target_": "torch.optim.SGD", "lr": 0.1}, model, enc, q)


def test_relabelled_rewards_are_the_intrinsic_reward_of_every_stored_transition_after_training(one_thread) -> None:
    agent = _filled(["baseline=nsrs"])
    rel = agent.relabelled
    assert rel is not None and len(rel.values) == len(agent.replay)  # relabelled after the last training call
    first = agent.replay.total_added - len(agent.replay)
    index = np.arange(first, agent.replay.total_added)
    batch = agent.replay.transitions_at(index)
    with torch.no_grad():
        direct = agent.intrinsic.compute(batch.with_latents(agent._encode_eval(batch.obs), agent._encode_eval(batch.next_obs)))
    assert torch.allclose(rel.values, direct.float(), rtol=1e-4, atol=1e-5)  # reused latents = recomputed ones
    newer = torch.tensor([agent.replay.total_added, agent.replay.total_added + 5])
    assert rel.lookup(newer).tolist() == [0.0, 0.0]  # added since: 0 until the next relabel (NSRS)
    by_refresh, by_relabel = [], []
    refresh_encode, relabel_encode = agent.novelty.encode, agent._encode_eval
    agent.novelty.encode = lambda obs: by_refresh.append(len(obs)) or refresh_encode(obs)
    agent._encode_eval = lambda obs: by_relabel.append(len(obs)) or relabel_encode(obs)
    agent._relabel()
    # every stored o_t encoded once, by the memory refresh; the relabel reuses those latents and encodes only the
    # newest transition's o_{t+1} (one continuing episode: every other o_{t+1} is the next transition's o_t)
    assert sum(by_refresh) == len(agent.replay) and by_relabel == [1]
    again = RelabelledRewards()
    again.load_state_dict(rel.state_dict())
    assert torch.equal(again.lookup(torch.from_numpy(index)), rel.values)  # exact: a copy of the same tensor


@pytest.mark.parametrize("overrides", [["baseline=nsrs"], ["+experiment=paper_code"],
                                       ["baseline=nsrs", "agent.updates=joint", "agent.q_intrinsic=batch"],
                                       ["agent.updates=nsrs"]])  # fmt: skip
def test_both_rules_train_and_resume_from_a_checkpoint(overrides: list[str], one_thread) -> None:
    agent = _filled(overrides, steps=20)
    state = agent.state_dict()
    assert ("optimizers" in state) == (agent.rule.name == "nsrs")
    other = build(agent.cfg.baseline, cfg=agent.cfg)
    other.load_state_dict(state)
    names = sorted(agent.optimizers)
    assert sorted(other.optimizers) == names
    for name in names:
        assert other.optimizers[name].state_dict()["state"].keys() == agent.optimizers[name].state_dict()["state"].keys()


def test_nsrs_first_call_trains_the_representation_alone_for_at_least_its_minimum(one_thread) -> None:
    """NSRS's code: no Q step in the first training call, which runs >= 2001 iterations (its early-stop check); here
    ``agent.first_call_min_iterations=30`` over a 16-iteration budget."""
    agent = _filled(["baseline=nsrs", "budget.iters_per_train=16", "agent.first_call_min_iterations=30"], steps=12)
    assert agent.schedule.calls == 1 and agent.q.updates == 0  # the first call: 30 iterations, no Q update
    steps = {float(v["step"]) for v in agent.optimizers["model"].state_dict()["state"].values()}
    assert steps == {30.0} and not agent.optimizers["q"].state_dict()["state"]  # 30 representation steps, no Q step
    agent = _filled(["baseline=nsrs", "budget.iters_per_train=16", "agent.first_call_min_iterations=30"], steps=13)
    assert agent.schedule.calls == 2 and agent.q.updates == 16  # the second call: the budget's 16, each with a Q step
    assert compose_cfg(["baseline=nsrs"]).agent.first_call_min_iterations == 2001


@pytest.mark.parametrize(("overrides", "key"), [
    (["agent.q_intrinsic=relabel"], "agent.q_intrinsic=relabel"),  # MPC has no Q
    (["baseline=icm", "agent.first_call_min_iterations=100"], "agent.first_call_min_iterations=100"),
    (["baseline=icm", "agent.updates=nsrs"], "agent.updates=nsrs"),
    (["baseline=rnd", "agent.q_intrinsic=relabel"], "agent.q_intrinsic=relabel"),
])  # fmt: skip
def test_options_an_agent_does_not_read_are_refused(overrides: list[str], key: str) -> None:
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        validate(compose_cfg(overrides))


def test_the_adaptive_schedule_stops_a_call_once_the_held_out_error_plateaus(one_thread) -> None:
    from curiosity.agents.schedule import TrainSchedule

    schedule = TrainSchedule(4, 1, 40, plateau_every=5, plateau_tol=0.1)
    assert [i for i in range(1, 21) if schedule.checks_plateau(i)] == [5, 10, 15, 20]
    assert schedule.plateaued(1.0, 0.95) and schedule.plateaued(1.0, 1.2) and not schedule.plateaued(1.0, 0.85)
    # a tolerance no fall can meet stops the call at its first check; none at all runs it while the error falls
    stopped = _filled(["budget.plateau_every=2", "budget.plateau_tol=0.99"], steps=14)
    assert stopped._train(40)["train/iterations"] == 2.0
    held = stopped._held_out()
    assert held is not None and len(held) == 14  # fewer than 16 stored: all of them
    assert held.index is not None and held.index.tolist() == list(range(14))  # the newest transitions
    full = _filled(["budget.plateau_every=0"], steps=14)
    assert full._train(40)["train/iterations"] == 40.0  # off: every call runs its iterations


def test_relabelled_q_targets_are_allowed_with_mpcs_terminal_value() -> None:
    """MPC with a terminal value has a Q, so NSRS's relabelled intrinsic rewards may feed its targets."""
    validate(compose_cfg(["agent.q_intrinsic=relabel", "planner.value_coef=0.25"]))
