"""``studies/``: every module imports and answers ``--help`` (``python -m studies.<module> --help``: exit 0, usage
printed), the loss-term plug-ins return a finite scalar with a gradient and train inside the paper agent, and the
imports run one way: ``studies`` may import the package, the analysis and the runners, never the other way round."""

from __future__ import annotations

import ast
import os
import pkgutil
import runpy
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import torch

import studies
from curiosity.agents.representation import Encoded, LossTerm
from curiosity.types import SegmentBatch
from studies.agent_study.terms import ArrowOfTime, InverseDynamics, MotionDecoder, extra_term
from tests.conftest import REPO

MODULES = sorted(m.name for m in pkgutil.walk_packages(studies.__path__, "studies.") if not m.ispkg)
LIBRARIES = {"studies.agent_study.terms"}  # imported by the scripts, no command line of its own
COMMANDS = [m for m in MODULES if m not in LIBRARIES]
PLUG_INS = (InverseDynamics, ArrowOfTime, MotionDecoder)


def test_the_studies_are_found() -> None:
    assert len(COMMANDS) >= 25 and "studies.representation" in COMMANDS and "studies.early" in COMMANDS


@pytest.mark.parametrize("name", MODULES)
def test_every_module_imports_without_running(name: str, capsys) -> None:
    __import__(name)
    assert capsys.readouterr().out == ""  # importing a study does nothing


@pytest.mark.parametrize("name", COMMANDS)
def test_every_command_prints_its_usage(name: str, monkeypatch, capsys) -> None:
    """As ``python -m NAME --help``, in this process (each study's imports, torch's among them, once)."""
    monkeypatch.setattr(sys, "argv", [name, "--help"])
    with warnings.catch_warnings(), pytest.raises(SystemExit) as done:
        warnings.simplefilter("ignore", RuntimeWarning)  # runpy: the module was imported by the test above
        runpy.run_module(name, run_name="__main__", alter_sys=True)
    assert done.value.code in (0, None)
    out = capsys.readouterr().out
    assert out.startswith("usage: python -m " + name), out[:200]


@pytest.mark.parametrize("name", ["studies.refactor.compare", "studies.early"])
def test_python_dash_m_runs_from_the_repository_root(name: str) -> None:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    res = subprocess.run([sys.executable, "-m", name, "--help"], cwd=REPO, env=env, capture_output=True, text=True,
                         timeout=60)  # fmt: skip
    assert res.returncode == 0 and res.stdout.startswith(f"usage: python -m {name}"), res.stderr


def _batch(b: int = 6, n: int = 2, d: int = 4, a: int = 3) -> tuple[SegmentBatch, Encoded]:
    g = torch.Generator().manual_seed(0)
    z = torch.randn(b, n + 1, d, generator=g, requires_grad=True)
    act = torch.randint(a, (b, n), generator=g)
    obs = torch.rand(b, n + 1, 4, 32, 32, generator=g) * 2 - 1  # stacked frames in [-1, 1]
    seg = SegmentBatch(obs=obs, act=act, rewards=torch.zeros(b, n), terminateds=torch.zeros(b, n))
    return seg, Encoded(z=z, a1h=torch.nn.functional.one_hot(act, a).float())


@pytest.mark.parametrize("cls", PLUG_INS, ids=lambda c: c.__name__)
def test_a_plug_in_returns_a_finite_scalar_with_a_gradient(cls: type[LossTerm]) -> None:
    seg, enc = _batch()
    term = cls(latent_dim=4, n_actions=3, coef=0.5)
    assert term.coef == 0.5
    value = term(None, seg, enc)  # the model is not used by these terms
    assert value.shape == () and torch.isfinite(value)
    value.backward()
    assert enc.z.grad is not None and float(enc.z.grad.abs().sum()) > 0  # it shapes the latent
    assert all(p.grad is not None for p in term.parameters())  # and trains its head


def test_a_plug_in_head_is_seeded_and_leaves_the_global_generator_alone() -> None:
    torch.manual_seed(7)
    expected = torch.rand(3)
    torch.manual_seed(7)
    first = ArrowOfTime(latent_dim=4, n_actions=3)
    assert torch.equal(torch.rand(3), expected)
    second = ArrowOfTime(latent_dim=4, n_actions=3)
    assert all(torch.equal(p, q) for p, q in zip(first.parameters(), second.parameters(), strict=True))


def test_the_plug_ins_train_inside_the_paper_agent() -> None:
    """Given as config overrides, the three terms are built with the agent, logged, and their heads move."""
    from studies.representation import agent_with_data, random_policy, rollout, study_config

    torch.set_num_threads(1)
    overrides = [extra_term(name, cls, 0.1) for name, cls in zip(("inverse", "arrow", "motion"), PLUG_INS, strict=True)]
    cfg = study_config(["env.renderer=fast", "threads=1", "agent.batch_size=8", *overrides])
    agent = agent_with_data(cfg, rollout(cfg, 24, random_policy(int(cfg.env.n_actions)), 0))
    assert [type(agent.extra_terms[k]) for k in ("inverse", "arrow", "motion")] == list(PLUG_INS)
    before = [p.detach().clone() for p in agent.extra_terms.parameters()]
    logs, _ = agent._iteration()
    assert all(np.isfinite(logs[f"losses/{k}"]) for k in ("inverse", "arrow", "motion"))
    assert all(not torch.equal(p, q) for p, q in zip(agent.extra_terms.parameters(), before, strict=True))
    assert float(agent.extra_terms["motion"].scale) > 0  # fixed by the first batch, a checkpointed buffer
    assert "motion.scale" in agent.extra_terms.state_dict()


def _imports(path: Path) -> set[str]:
    """The top-level names of the absolute imports in one file."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("folder", ["curiosity", "analysis", "runners"])
def test_nothing_below_imports_studies(folder: str) -> None:
    offenders = [str(p.relative_to(REPO)) for p in (REPO / folder).rglob("*.py") if "studies" in _imports(p)]
    assert offenders == []


def test_studies_import_only_downward() -> None:
    local = {"curiosity", "analysis", "runners", "studies", "tests", "examples"}
    for path in (REPO / "studies").rglob("*.py"):
        assert not (_imports(path) & local) - {"curiosity", "analysis", "runners", "studies"}, path


def test_the_reference_runs_name_the_agent_keys_as_this_tree_does() -> None:
    from studies.refactor.reference_runs import agent_prefix

    assert agent_prefix(REPO) == "agent."  # the agent's keys live in the schema now, no longer in conf/config.yaml


def test_the_power_study_reads_runs_and_its_seed_count_grows_as_the_margin_nears(tmp_path: Path, capsys) -> None:
    from studies.power import main, seeds_needed

    assert seeds_needed(0.2, 30, 1.10, 1.10) == float("inf")
    assert seeds_needed(0.2, 30, 1.10, 1.0) > seeds_needed(0.2, 30, 1.10, 0.9) > 0
    assert seeds_needed(0.2, 30, 1.10, 1.0) == pytest.approx(30 * (1.2816 * 0.2 / 0.1) ** 2, rel=1e-3)
    for name, values in {"ref": [100, 200, 300, 400], "new": [110, None, 330, 380]}.items():
        for seed, steps in enumerate(values):
            run = tmp_path / name / f"seed={seed}"
            run.mkdir(parents=True)
            (run / "summary.json").write_text(f'{{"steps_to_goal": {"null" if steps is None else steps}, "max_steps": 3000}}')
    assert main([str(tmp_path / "ref"), str(tmp_path / "new")]) == 0
    out = capsys.readouterr().out
    assert "shared seeds 4; ratio of means 3.820" in out  # (110 + 3000 + 330 + 380) / 4 over 250: the cap counts


def test_the_screen_stops_a_point_at_three_caps_or_at_one_and_a_half_times_its_base(tmp_path: Path, capsys) -> None:
    from studies.screen import main, screen

    base = {s: 200.0 for s in range(15)}
    assert not screen({s: 300.0 for s in range(15)}, base, 3000).stop  # exactly 1.5x: goes on
    assert screen({s: 301.0 for s in range(15)}, base, 3000).stop
    two_caps = {s: 3000.0 if s < 2 else 100.0 for s in range(15)}
    assert not screen(two_caps, {s: 1000.0 for s in range(15)}, 3000).stop  # two caps, mean 460 against 1000
    three = {**two_caps, 2: 3000.0}
    assert screen(three, {s: 3000.0 for s in range(15)}, 3000).caps == 3
    assert screen(three, {s: 3000.0 for s in range(15)}, 3000).stop
    with pytest.raises(KeyError, match=r"seeds \[14\]"):
        screen({s: 1.0 for s in range(14)}, base, 3000)
    for name, values in {"base": [100] * 15, "point": [None, None, None] + [100] * 12}.items():
        for seed, steps in enumerate(values):
            run = tmp_path / name / f"seed={seed}"
            run.mkdir(parents=True)
            (run / "summary.json").write_text(f'{{"steps_to_goal": {"null" if steps is None else steps}, "max_steps": 3000}}')
    assert main([str(tmp_path / "point"), str(tmp_path / "base")]) == 1
    assert "3 at the cap" in capsys.readouterr().out
    assert main([str(tmp_path / "base"), str(tmp_path / "base")]) == 0
    assert main([str(tmp_path / "base"), str(tmp_path / "base"), "--seeds", "16"]) == 2
    assert "has not finished seeds [15]" in capsys.readouterr().out.splitlines()[-1]
