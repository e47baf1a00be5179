"""Behaviour columns, the simulator branch, the model probe on a corridor whose answer is known, the oracle planner."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch
from omegaconf import OmegaConf
from torch import nn

from curiosity.envs import make_env
from curiosity.envs.acrobot import AcrobotAdapter
from curiosity.envs.acrobot import directed as acrobot
from curiosity.envs.adapter import EnvAdapter, adapter_of
from curiosity.envs.mountaincar import directed as mountaincar
from curiosity.envs.simulator import Simulator
from curiosity.planning import MPCPlanner
from curiosity.planning.probe import probe_model, tree_latents
from curiosity.planning.rollout import HeldRollout, LatentRollout, SimulatorRollout
from curiosity.runtime.behaviour import BehaviourTracker
from curiosity.runtime.loop import run
from tests.conftest import compose_cfg

CHAIN = 61
STEP = 2.0 / (CHAIN - 1)  # the chain's observation moves by this per cell


# ----------------------------------------------------------------------------- behaviour
def test_behaviour_tracker_counts_actions_repeats_and_directed_steps() -> None:
    tracker = BehaviourTracker(3, acrobot)
    rows = [tracker.record(a, np.array([0.0, 0.0, 0.0, v])) for a, v in [(2, 1.0), (2, -1.0), (0, -1.0), (1, 0.0)]]
    assert rows[0]["behaviour/action_2"] == 1.0 and "behaviour/repeat" not in rows[0]
    assert [r.get("behaviour/repeat") for r in rows[1:]] == [1.0, 0.0, 0.0]
    assert [r.get("behaviour/directed") for r in rows] == [1.0, 0.0, 1.0, None]  # θ̇2 = 0: no directed action
    summary = tracker.summary()
    assert summary["action_freq"] == [0.25, 0.25, 0.5]
    assert summary["repeat_rate"] == pytest.approx(1 / 3) and summary["directed_rate"] == pytest.approx(2 / 3)
    restored = BehaviourTracker(3, acrobot)
    restored.load_state_dict(tracker.state_dict())
    assert restored.summary() == summary


def test_random_actions_score_one_third_on_every_behaviour_rate() -> None:
    rng = np.random.default_rng(0)
    tracker = BehaviourTracker(3, mountaincar)
    for _ in range(30_000):
        tracker.record(int(rng.integers(3)), np.array([0.0, rng.normal()]))
    s = tracker.summary()
    assert s["repeat_rate"] == pytest.approx(1 / 3, abs=0.015) and s["directed_rate"] == pytest.approx(1 / 3, abs=0.015)
    assert adapter_of(compose_cfg(["env=chain", "encoder=mlp"]).env).directed_action is None
    assert adapter_of(compose_cfg().env).directed_action is acrobot


# ----------------------------------------------------------------------------- simulator
@pytest.mark.parametrize("overrides", [["env.renderer=fast"], ["env.renderer=gym"], ["env=mountaincar"],
                                       ["env.obs=state", "encoder=mlp"]])  # fmt: skip
def test_simulator_branch_matches_the_real_env_frame_for_frame(overrides: list[str]) -> None:
    cfg = compose_cfg(overrides)
    env, sim = make_env(cfg.env, 100), Simulator(cfg.env)
    obs, _ = env.reset(seed=3)
    for a in (0, 2, 2):  # leave the rest state so that the frames move
        obs, *_ = env.step(a)
    states = sim.root(env, obs)
    for a in (2, 0, 1, 2):
        states, _ = sim.step(states, np.array([a]))
        obs, *_ = env.step(a)
        np.testing.assert_array_equal(states.physical[0], env.unwrapped.state)  # exact: the same float64 arithmetic
        np.testing.assert_array_equal(states.obs[0], obs)  # exact: the same wrappers on the same state


# ----------------------------------------------------------------------------- probe on the corridor
class Identity1D(nn.Module):
    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return obs.reshape(obs.shape[0], 1).double()


def exact_step(z: torch.Tensor, a: torch.Tensor) -> torch.Tensor:
    """The chain's true latent dynamics away from its walls (latent = observation)."""
    return z + STEP * (a.double() - 1).unsqueeze(1)


def blind_step(z: torch.Tensor, a: torch.Tensor) -> torch.Tensor:
    return z.clone()


def rightward(z: torch.Tensor, a: torch.Tensor, z_next: torch.Tensor) -> dict[str, torch.Tensor]:
    return {"novelty": z_next[:, 0]}


def chain_root(position: int):
    cfg = compose_cfg(["env=chain", "encoder=mlp"])
    env, sim = make_env(cfg.env, 100), Simulator(cfg.env)
    obs, _ = env.reset(seed=0)
    env.unwrapped.state = np.array([float(position)])
    obs = np.array([2.0 * position / (CHAIN - 1) - 1.0], dtype=np.float32)
    return sim, sim.root(env, obs), torch.tensor([float(obs[0])], dtype=torch.float64)


def test_simulator_rollout_equals_an_exact_model_away_from_the_walls() -> None:
    sim, root, z0 = chain_root(30)
    true = tree_latents(SimulatorRollout(sim, root, z0, Identity1D()), 3, 4)
    model = tree_latents(LatentRollout(z0, exact_step), 3, 4)
    for zt, zm in zip(true, model, strict=True):
        torch.testing.assert_close(zt, zm, atol=1e-6, rtol=0)  # float32 observations against float64 arithmetic


def test_probe_gives_the_known_answers_for_an_exact_and_a_blind_model() -> None:
    sim, root, z0 = chain_root(30)
    planner = MPCPlanner(horizon=4, gamma=0.9, temperature=0.0)
    exact = probe_model(planner, z0, exact_step, None, rightward, sim, root, Identity1D())
    for k in range(1, 5):
        assert exact[f"probe/effect_ratio/{k}"] == pytest.approx(1.0, abs=1e-5)
        assert exact[f"probe/error/{k}"] == pytest.approx(0.0, abs=1e-6)
    assert exact["probe/effect_true/1"] == pytest.approx(STEP * np.sqrt(2 / 3), rel=1e-5)  # spread of {−1, 0, 1}·STEP
    assert exact["probe/spearman"] == pytest.approx(1.0, abs=1e-9) and exact["probe/agree"] == 1.0
    blind = probe_model(planner, z0, blind_step, None, rightward, sim, root, Identity1D())
    assert blind["probe/effect_ratio/3"] == 0.0 and blind["probe/error/1"] > 0
    assert "probe/spearman" not in blind  # constant model scores: no rank correlation


def test_held_simulator_rollout_encodes_only_the_held_step_it_returns() -> None:
    sim, root, z0 = chain_root(30)
    calls: list[int] = []

    class Counting(Identity1D):
        def forward(self, obs: torch.Tensor) -> torch.Tensor:
            calls.append(len(obs))
            return super().forward(obs)

    held_tree = tree_latents(HeldRollout(SimulatorRollout(sim, root, z0, Counting()), 3), 3, 2)
    assert calls == [3, 9]  # one encoding per depth (3 and 9 nodes), none for the two inner steps of each
    stepped = tree_latents(SimulatorRollout(sim, root, z0, Identity1D()), 3, 6)  # the same steps, every one encoded
    a, n = torch.arange(3), torch.arange(9)  # held prefixes (a) and (a, b), n = 3a + b, lexicographic
    torch.testing.assert_close(held_tree[0], stepped[2][13 * a])  # one-step prefix a a a: index 9a + 3a + a
    torch.testing.assert_close(held_tree[1], stepped[5][351 * (n // 3) + 13 * (n % 3)])  # a a a b b b


def test_probe_with_held_actions_compares_held_futures() -> None:
    sim, root, z0 = chain_root(30)
    planner = MPCPlanner(horizon=3, gamma=0.9, temperature=0.0, hold=2)
    exact = probe_model(planner, z0, exact_step, None, rightward, sim, root, Identity1D())
    for k in range(1, 4):
        assert exact[f"probe/effect_ratio/{k}"] == pytest.approx(1.0, abs=1e-5)
        assert exact[f"probe/error/{k}"] == pytest.approx(0.0, abs=1e-6)
    assert exact["probe/effect_true/1"] == pytest.approx(2 * STEP * np.sqrt(2 / 3), rel=1e-5)  # a depth is 2 steps
    assert exact["probe/spearman"] == pytest.approx(1.0, abs=1e-9) and exact["probe/agree"] == 1.0


def test_probe_sees_the_wall_that_a_wall_free_model_misses() -> None:
    sim, root, z0 = chain_root(CHAIN - 2)  # one cell from the right wall
    planner = MPCPlanner(horizon=3, gamma=0.9, temperature=0.0)
    out = probe_model(planner, z0, exact_step, None, rightward, sim, root, Identity1D())
    assert out["probe/error/1"] == pytest.approx(0.0, abs=1e-6) and out["probe/error/3"] > 0
    assert out["probe/effect_ratio/3"] > 1.0  # the model thinks the agent can go further than it can


# ----------------------------------------------------------------------------- temperature relative to the spread
def test_spread_temperature_ignores_the_scale_and_offset_of_scores() -> None:
    planner = MPCPlanner(horizon=2, temperature=0.5, temperature_scale="spread")
    g = torch.randn(9, generator=torch.Generator().manual_seed(0), dtype=torch.float64)
    _, p1, h1 = planner.choose(g, torch.Generator().manual_seed(1))
    _, p2, h2 = planner.choose(1e5 * g - 3e4, torch.Generator().manual_seed(1))
    torch.testing.assert_close(p1, p2)
    assert h1 == pytest.approx(h2)
    absolute = MPCPlanner(horizon=2, temperature=0.5)
    assert absolute.choose(1e5 * g, torch.Generator().manual_seed(1))[2] < 1e-6  # absolute τ: greedy at this scale


# ----------------------------------------------------------------------------- in a run
FAST = ["env.renderer=fast", "progress=false", "budget=smoke", "budget.max_steps=90", "budget.warmup_steps=40",
        "agent.probe_every=20"]  # fmt: skip


def test_a_run_logs_behaviour_planner_and_probe_columns(tmp_path: Path) -> None:
    # the paper text's stochastic prediction-error term in planning (MC dropout), so that the noise columns exist
    summary = run(compose_cfg([*FAST, "intrinsic.terms.pe.imagined=dropout", "agent.transition_dropout=0.5"]), tmp_path)
    header = (tmp_path / "metrics.csv").read_text().splitlines()[0].split(",")
    wanted = {"behaviour/action_0", "behaviour/repeat", "behaviour/directed", "planner/first_action_entropy",
              "planner/spread/novelty", "planner/spread/pe", "planner/noise", "planner/noise_flip", "planner/p_first/2",
              "probe/effect_ratio/3", "probe/spearman", "probe/agree"}  # fmt: skip
    assert wanted <= set(header), wanted - set(header)
    written = json.loads((tmp_path / "summary.json").read_text())
    assert written["behaviour"]["agent_steps"] == 50 and len(written["behaviour"]["action_freq"]) == 3
    assert "probe/effect_ratio/1" in written["agent"]["means"] and "planner/noise" in written["agent"]["means"]
    assert summary.behaviour == written["behaviour"]


@pytest.mark.parametrize("overrides", [["planner.model=oracle", "intrinsic.terms.pe.imagined=off", "planner.temperature=0"],
                                       ["agent.transition_ensemble=3", "intrinsic.terms.pe.imagined=ensemble",
                                        "planner.temperature_scale=spread",
                                        "intrinsic.terms.novelty.refresh_drift=0.1",
                                        "agent.transition_dropout=0"]])  # fmt: skip
def test_oracle_ensemble_spread_and_drift_options_run(tmp_path: Path, overrides: list[str]) -> None:
    summary = run(compose_cfg([*FAST, *overrides]), tmp_path)
    assert summary.env_steps == 90
    means = summary.agent["means"]
    if "agent.transition_ensemble=3" in overrides:
        assert "memory/drift" in means and "planner/noise" not in means  # an ensemble is deterministic: no noise
    else:
        assert summary.agent["planner_model"] == "oracle"


# ----------------------------------------------------------------------------- transition ensemble
def test_ensemble_members_disagree_and_each_trains_on_its_own_loss() -> None:
    from curiosity.agents.paper import build_world_model
    from curiosity.agents.representation import Encoded, LossWeights, representation_loss
    from curiosity.info.regularisers import NoRegulariser
    from curiosity.nets import one_hot
    from curiosity.types import SegmentBatch

    torch.manual_seed(0)
    cfg = compose_cfg(["env=chain", "encoder=mlp", "agent.transition_ensemble=4", "agent.transition_dropout=0",
                       "agent.internal_dim=2"])  # fmt: skip
    model = build_world_model(cfg)
    z, a = torch.randn(16, 2), torch.randint(0, 3, (16,))
    assert bool((model.ensemble_disagreement(z, a) > 0).all())
    single = build_world_model(compose_cfg(["env=chain", "encoder=mlp", "agent.internal_dim=2"]))
    assert bool((single.ensemble_disagreement(z, a) == 0).all())
    zs, acts = torch.randn(8, 3, 2, requires_grad=True), torch.randint(0, 3, (8, 2))
    seg = SegmentBatch(obs=torch.zeros(8, 3, 1), act=acts, rewards=torch.zeros(8, 2), terminateds=torch.zeros(8, 2))
    loss, _ = representation_loss(model, seg, Encoded(zs, one_hot(acts, 3).float()), NoRegulariser(),
                                  LossWeights(reward=0.0, detach_targets=True))  # fmt: skip
    loss.backward()
    grads = [m.net[0].weight.grad for m in model.transition.members]
    assert all(g is not None and float(g.abs().sum()) > 0 for g in grads)
    assert not torch.allclose(grads[0], grads[1])  # each member follows its own error


# ----------------------------------------------------------------------------- the probe command
def finished_run(cfg, run_dir: Path) -> None:
    """A finished run directory as the CLI leaves it: the run, then its .hydra/config.yaml (which the job writes)."""
    run(cfg, run_dir)
    (run_dir / ".hydra").mkdir()
    (run_dir / ".hydra" / "config.yaml").write_text(OmegaConf.to_yaml(cfg))


def test_probe_command_on_a_run_directory_and_a_refusal(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from analysis.probe import main

    finished_run(compose_cfg([*FAST, "agent.probe_every=0"]), tmp_path / "run")
    assert main([str(tmp_path / "run"), "--states", "2", "--every", "2", "--json", str(tmp_path / "p.json")]) == 0
    out = capsys.readouterr().out
    assert "| 3 |" in out and "Spearman" in out
    saved = json.loads((tmp_path / "p.json").read_text())
    assert len(saved["states"]) == 2 and "probe/effect_ratio/1" in saved["means"]
    (tmp_path / "run" / "checkpoint.pt").unlink()
    assert main([str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "checkpoint.pt" in err[0]


def test_pe_estimate_signal_is_measured_on_real_transitions(tmp_path: Path) -> None:
    summary = run(compose_cfg([*FAST, "budget.max_steps=100", "agent.transition_ensemble=3",
                               "intrinsic.terms.pe.imagined=ensemble", "agent.transition_dropout=0", "log_every=10"]),
                  tmp_path)  # fmt: skip
    corr = summary.agent["means"]["intrinsic/pe_estimate_corr"]
    assert -1.0 <= corr <= 1.0


# ----------------------------------------------------------------------------- energy and the novelty landscape
def test_energy_is_conserved_without_torque_and_known_at_rest() -> None:
    import gymnasium as gym

    from curiosity.envs.acrobot import energy as acrobot_energy
    from curiosity.envs.mountaincar import energy as mountaincar_energy

    assert acrobot_energy(np.zeros(4)) == pytest.approx(-19.6)  # both links hanging: −(0.5 + 1 + 0.5)·9.8
    env = gym.make("Acrobot-v1").unwrapped
    env.reset(seed=0)
    env.state = np.array([0.5, -0.3, 1.0, -2.0])
    energies = [acrobot_energy(env.state)]
    for _ in range(20):
        env.step(1)  # zero torque
        energies.append(acrobot_energy(env.state))
    assert np.ptp(energies) < 0.05  # rk4 at dt = 0.2 (measured 0.017 J of ~16)
    env.step(2)
    assert abs(acrobot_energy(env.state) - energies[-1]) > 0.05  # torque changes it
    car = gym.make("MountainCar-v0").unwrapped
    car.reset(seed=0)
    car.state = np.array([-0.5, 0.0])
    start = mountaincar_energy(car.state)
    for _ in range(100):
        car.step(1)  # no push
    assert mountaincar_energy(car.state) == pytest.approx(start, abs=1e-6)
    assert EnvAdapter("curiosity/Chain-v0").energy is None and AcrobotAdapter("Acrobot-v1").energy is acrobot_energy


def test_landscape_command_reports_every_variant_and_refuses_the_chain(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from analysis.landscape import main

    finished_run(compose_cfg([*FAST, "agent.probe_every=0", "planner.horizon=3"]), tmp_path / "run")
    assert main([str(tmp_path / "run"), "--states", "2", "--bandwidths", "2", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "kde h=2×median NN" in out and "kde h=0.5×median NN" in out and "knn k=5" in out
    chain = compose_cfg(["env=chain", "encoder=mlp", "progress=false", "budget=smoke", "budget.max_steps=50",
                         "budget.warmup_steps=20"])  # fmt: skip
    finished_run(chain, tmp_path / "chain")
    assert main([str(tmp_path / "chain")]) == 2
    assert "Acrobot or MountainCar" in capsys.readouterr().err


def test_kept_checkpoints_restore_the_run_along_the_way_for_the_landscape(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from analysis.landscape import main
    from curiosity.runtime.checkpoint import kept_checkpoints, read_checkpoint
    from curiosity.runtime.restore import restore_run

    run_dir = tmp_path / "run"
    cfg = compose_cfg([*FAST, "agent.probe_every=0", "planner.horizon=2", "checkpoint_every=20", "checkpoint_keep=true"])
    finished_run(cfg, run_dir)
    kept = kept_checkpoints(run_dir)
    assert list(kept) == [20, 40, 60, 80]  # every periodic checkpoint of the 90-step run; the final one is not kept
    assert [read_checkpoint(path)["step"] for path in kept.values()] == [20, 40, 60, 80]  # later writes left them
    assert restore_run(run_dir, kept[60]).step == 60 and restore_run(run_dir).step == 90
    assert main([str(run_dir), "--states", "1", "--bandwidths", "2", "--step", "40", "60"]) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| 40 |") or line.startswith("| 60 |")]
    assert len(rows) == 2 * 2  # two steps x (KDE at h = 2x, kNN)
    assert main([str(run_dir), "--step", "30"]) == 2
    assert "allowed: all, 40, 60, 80" in capsys.readouterr().err  # 20: within the 40 warm-up steps, not acted yet
    assert main([str(run_dir), "--step", "20"]) == 2
    kept[80].unlink()
    kept[80].write_bytes(b"not a checkpoint")
    assert main([str(run_dir), "--step", "80"]) == 2
    assert "step=80.pt: cannot be read" in capsys.readouterr().err
    plain = tmp_path / "plain"
    finished_run(compose_cfg([*FAST, "agent.probe_every=0", "planner.horizon=2", "checkpoint_every=20"]), plain)
    assert kept_checkpoints(plain) == {} and not (plain / "checkpoints").exists()
    assert main([str(plain), "--step", "all"]) == 2
    assert "checkpoint_keep=true" in capsys.readouterr().err
    for path in kept_checkpoints(run_dir).values():
        if path.name != "step=20.pt":
            path.unlink()  # only the warm-up's checkpoint left: nothing to walk from
    assert main([str(run_dir), "--step", "all"]) == 2
    assert "no checkpoints after its 40 warm-up steps" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["landscape", "probe"])
def test_landscape_and_probe_walk_on_from_the_start_after_the_goal(
    command: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A run checkpointed at the goal (its terminal state) and a walk that reaches the goal: the env is reset and the
    walk goes on, so every requested state is scored."""
    import analysis.landscape as landscape_module
    import analysis.probe as probe_module

    module = landscape_module if command == "landscape" else probe_module

    finished_run(compose_cfg([*FAST, "agent.probe_every=0", "planner.horizon=2"]), tmp_path / "run")
    summary_path = tmp_path / "run" / "summary.json"
    summary = json.loads(summary_path.read_text())
    summary["steps_to_goal"] = summary["env_steps"]  # as if the last step had reached the goal
    summary_path.write_text(json.dumps(summary))
    resets = []
    restore = module.restore_run

    def restore_at_goal(run_dir, checkpoint=None):
        restored = restore(run_dir, checkpoint)
        env, real_step, real_reset = restored.env, restored.env.step, restored.env.reset

        def step_to_goal(action):  # every step reaches the goal
            obs, reward, _, truncated, info = real_step(action)
            return obs, reward, True, truncated, info

        def counted_reset(**kwargs):
            resets.append(1)
            return real_reset(**kwargs)

        env.step, env.reset = step_to_goal, counted_reset
        return restored

    monkeypatch.setattr(module, "restore_run", restore_at_goal)
    if command == "landscape":
        result = landscape_module.landscape(tmp_path / "run", states=3, bandwidths=(2.0,))
        assert all(r["states"] == 3 for r in result.values())
        assert len(resets) == 1 + 3  # the terminal checkpoint, then after each step's goal
    else:
        assert len(probe_module.probe_run(tmp_path / "run", states=3, every=1)) == 3
        assert len(resets) == 1 + 2  # the terminal checkpoint, then after each step between probed states


def test_probe_follows_the_kept_checkpoints(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from analysis.probe import main

    run_dir = tmp_path / "run"
    cfg = compose_cfg([*FAST, "agent.probe_every=0", "planner.horizon=2", "checkpoint_every=20", "checkpoint_keep=true"])
    finished_run(cfg, run_dir)
    assert main([str(run_dir), "--states", "2", "--every", "1", "--step", "40", "80", "--json", str(tmp_path / "p.json")]) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith(("| 40 |", "| 80 |"))]
    assert len(rows) == 2 and all(row.split("|")[2].strip() == "2" for row in rows)  # two states at each step
    saved = json.loads((tmp_path / "p.json").read_text())["steps"]
    assert set(saved) == {"40", "80"} and all(len(v["states"]) == 2 and "probe/agree" in v["means"] for v in saved.values())
    assert main([str(run_dir), "--step", "30"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "allowed: all, 40, 60, 80" in err[0]


def test_diagnostics_do_not_change_what_the_agent_does(tmp_path: Path) -> None:
    """The noise check and the probe draw dropout masks in a forked RNG: the actions are the same without them
    (same config, seed and machine, one thread: exact)."""
    common = [*FAST, "deterministic=true"]
    with_probe = run(compose_cfg([*common, "agent.probe_every=10"]), tmp_path / "a")
    without = run(compose_cfg([*common, "agent.probe_every=0"]), tmp_path / "b")
    assert with_probe.behaviour == without.behaviour  # exact: same seed, same machine, deterministic mode
    rows = [(tmp_path / d / "metrics.csv").read_text().splitlines() for d in ("a", "b")]
    col = rows[0][0].split(",").index("intrinsic/reward")
    assert [r.split(",")[col] for r in rows[0][1:]] == [r.split(",")[col] for r in rows[1][1:]]
