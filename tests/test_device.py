"""The ``device`` key: every tensor the paper's agent makes while acting, learning and resuming is on the configured
device (CI has no GPU, so the check runs on the CPU: with torch's default device set to ``meta``, a tensor created
without naming its device would be a data-less meta tensor and the step would fail); refusals are one line."""

from __future__ import annotations

import pytest
import torch

from curiosity.config import ConfigError, build, validate
from curiosity.envs import make_env
from curiosity.device import resolve_device, to_device
from tests.conftest import compose_cfg

SMALL = [
    "env.renderer=fast",
    "budget=smoke",
    "budget.warmup_steps=8",
    "agent.batch_size=4",
    "intrinsic.terms.novelty.refresh_every=4",
]


@pytest.mark.parametrize("overrides", [["planner.horizon=2", "agent.probe_every=3"], ["+experiment=paper_code"],
                                       ["+experiment=paper_text", "planner.horizon=2"], ["baseline=nsrs"],
                                       ["planner.horizon=2", "planner.model=oracle", "agent.probe_every=0"]])  # fmt: skip
def test_acting_learning_and_resuming_create_tensors_only_on_the_configured_device(overrides: list[str]) -> None:
    cfg = compose_cfg([*SMALL, *overrides, "device=cpu"])
    agent = build(cfg.baseline, cfg=cfg)  # the paper's agent, or NSRS built on it
    env = make_env(cfg.env, 100)
    agent.attach_env(env)
    obs, _ = env.reset(seed=0)
    step = 0

    def steps(n: int) -> None:
        nonlocal obs, step
        for _ in range(n):
            action = agent.act(obs, step) if step >= 8 else step % 3
            nxt, r, term, _, _ = env.step(action)
            agent.observe(obs, action, float(r), nxt, bool(term), step)
            obs, step = nxt, step + 1

    steps(6)  # the warm-up's first steps build the memory on the CPU as usual
    torch.set_default_device("meta")
    try:
        steps(10)  # refreshes, planning, training, the probe: nothing may rely on the default device
        state = agent.state_dict()
        agent.load_state_dict(state)
        steps(2)
    finally:
        torch.set_default_device(None)
    device = resolve_device("cpu")
    assert all(p.device == device for p in agent.model.parameters())
    assert agent.novelty.memory.tensor().device == device


def test_resolve_and_move() -> None:
    assert resolve_device("cpu") == torch.device("cpu")
    assert resolve_device("auto") == torch.device("cuda" if torch.cuda.is_available() else "cpu")
    with pytest.raises(ValueError, match="device='gpu'"):
        resolve_device("gpu")
    keys, gen = torch.arange(3), torch.Generator().get_state()
    moved = to_device({"a": torch.ones(2), "k": [keys, (gen, 1.5)]}, torch.device("cpu"))
    assert moved["k"][0] is keys and moved["k"][1][0] is gen and moved["k"][1][1] == 1.5  # integer/byte stay put


@pytest.mark.skipif(torch.cuda.is_available(), reason="this machine has a GPU")
def test_cuda_without_a_gpu_is_refused_in_one_line() -> None:
    with pytest.raises(ConfigError) as err:
        validate(compose_cfg(["device=cuda"]))
    assert str(err.value).count("\n") == 0 and "device=cuda" in str(err.value) and "allowed: cpu, auto" in str(err.value)


def test_cpu_only_baselines_refuse_a_gpu(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    for baseline in ("icm", "rnd"):
        with pytest.raises(ConfigError, match=f"baseline={baseline} runs on the CPU only"):
            validate(compose_cfg([f"baseline={baseline}", "device=auto"]))
    validate(compose_cfg(["baseline=icm", "device=cpu"]))
    validate(compose_cfg(["device=auto"]))  # the paper's agent follows the device
