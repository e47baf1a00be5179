"""Environments: gymnasium's checker, observation format, renderer agreement, coverage, adapters."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pandas as pd
import pytest
from gymnasium.utils.env_checker import check_env

from curiosity.envs import EnvAdapter, GridCoverage, adapter_of, make_env
from curiosity.envs.acrobot import AcrobotAdapter
from curiosity.envs.adapter import env_actions, env_state_dim
from curiosity.runtime.loop import run
from tests.conftest import compose_cfg

CASES = [("acrobot", "pixels", "gym"), ("acrobot", "pixels", "fast"), ("acrobot", "state", "gym"),
         ("mountaincar", "pixels", "gym"), ("mountaincar", "pixels", "fast"), ("mountaincar", "state", "gym")]  # fmt: skip


def _env(name: str, obs: str, renderer: str, max_steps: int = 3000):
    cfg = compose_cfg([f"env={name}", f"env.obs={obs}", f"env.renderer={renderer}"])
    return make_env(cfg.env, max_steps), cfg


@pytest.mark.parametrize(("name", "obs", "renderer"), CASES)
def test_check_env_passes(name: str, obs: str, renderer: str) -> None:
    env, _ = _env(name, obs, renderer)
    check_env(env, skip_render_check=True)
    env.close()


@pytest.mark.parametrize(("name", "obs", "renderer"), CASES)
def test_observation_format(name: str, obs: str, renderer: str) -> None:
    env, cfg = _env(name, obs, renderer)
    o, _ = env.reset(seed=0)
    if obs == "pixels":
        assert o.shape == (4, 32, 32) and o.dtype == np.float32
        # (x - 128)/128 of uint8 values: exact multiples of 1/128 in [-1, 127/128]; the white background is there
        assert np.all(o * 128 == np.round(o * 128)) and o.min() >= -1 and o.max() == 127 / 128
        assert np.array_equal(o[0], o[3])  # the reset frame repeated
        o2, *_ = env.step(1)
        assert np.array_equal(o2[:3], o[1:])  # oldest first, newest last
    else:
        assert o.shape == (cfg.env.state_dim,) and o.dtype == np.float32
    env.close()


def test_episode_is_not_cut_at_gymnasiums_500_steps() -> None:
    env, _ = _env("acrobot", "state", "gym", max_steps=3000)
    env.reset(seed=0)
    for _ in range(600):
        _, _, terminated, truncated, _ = env.step(1)  # zero torque never reaches the goal
        assert not terminated and not truncated
    env.close()


@pytest.mark.parametrize("name", ["acrobot", "mountaincar"])
def test_fast_renderer_agrees_with_gym_renderer(name: str) -> None:
    gym_env, _ = _env(name, "pixels", "gym")
    fast_env, _ = _env(name, "pixels", "fast")
    og, _ = gym_env.reset(seed=3)
    of, _ = fast_env.reset(seed=3)
    rng = np.random.default_rng(0)
    diffs = []
    adapter = adapter_of(compose_cfg([f"env={name}"]).env)
    for _ in range(150):
        a = int(rng.integers(3))
        og, *_ = gym_env.step(a)
        of, *_ = fast_env.step(a)
        assert np.array_equal(adapter.physical_state(gym_env), adapter.physical_state(fast_env))
        diffs.append(np.abs(og[-1] - of[-1]).mean() * 128)  # gray levels
    # Measured: 0.6 gray levels (Acrobot and MountainCar). Blank frames would differ by ~10, a shifted scene by > 3.
    assert np.mean(diffs) < 1.5, np.mean(diffs)
    # and the scene moves: consecutive frames are not all the same
    assert np.abs(of[0] - of[-1]).sum() > 0 or name == "mountaincar"
    gym_env.close()
    fast_env.close()


def test_grid_coverage_counts_distinct_cells() -> None:
    cov = GridCoverage([0.0, 0.0], [1.0, 1.0], [2, 4])
    assert cov.n_cells == 8 and cov.fraction == 0.0
    for s in ([0.1, 0.1], [0.1, 0.2], [0.9, 0.9], [5.0, 5.0], [-1.0, 0.6]):
        cov.update(np.array(s))
    # cells: (0,0), (0,0), (1,3), (1,3) clipped, (0,2)
    assert cov.fraction == pytest.approx(3 / 8)
    assert cov.cell(np.array([0.6, 0.3])) == 1 * 4 + 1
    restored = GridCoverage([0.0, 0.0], [1.0, 1.0], [2, 4])
    restored.load_state_dict(cov.state_dict())
    assert restored.fraction == cov.fraction


# ----------------------------------------------------------------------------- adapters
class FallingCorridor(gym.Env):
    """41 cells, start 5 cells from the left end: falling off the left end terminates without the goal (info
    ``goal`` False), reaching the right end terminates with it."""

    metadata = {"render_modes": []}  # noqa: RUF012

    def __init__(self) -> None:
        self.observation_space = gym.spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(3)
        self.state = np.array([5.0])

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        self.state = np.array([5.0])
        return self.state.astype(np.float32) / 40, {}

    def step(self, action: int) -> tuple[np.ndarray, float, bool, bool, dict]:
        self.state = self.state + (int(action) - 1)
        at_end = self.state[0] in (0.0, 40.0)
        return self.state.astype(np.float32) / 40, -1.0, at_end, False, {"goal": self.state[0] == 40.0}


if "tests/FallingCorridor-v0" not in gym.registry:  # get_class may import this module a second time
    gym.register(id="tests/FallingCorridor-v0", entry_point=FallingCorridor)


class FallingCorridorAdapter(EnvAdapter):
    """Only the right end is the goal."""

    def goal_reached(self, env: gym.Env, terminated: bool, info: Mapping[str, Any]) -> bool:
        return bool(terminated and info.get("goal", False))


def test_a_termination_that_is_not_the_goal_resets_the_env_and_the_run_goes_on(tmp_path: Path) -> None:
    cfg = compose_cfg(["env=chain", "encoder=mlp", "env.id=tests/FallingCorridor-v0", "baseline=random",
                       "progress=false", "env._target_=tests.test_envs.FallingCorridorAdapter",
                       "env.coverage_low=[-0.5]", "env.coverage_high=[40.5]", "env.coverage_bins=[41]", "budget=smoke",
                       "budget.max_steps=300"])  # fmt: skip
    summary = run(cfg, tmp_path)
    # measured with this seed: one fall off the left end (before the adapters, that fall ended the run as "goal"),
    # the right end never reached in 300 steps
    assert summary.episode_resets >= 1, summary
    assert summary.env_steps == 300 and not summary.reached_goal
    assert json.loads((tmp_path / "summary.json").read_text())["episode_resets"] == summary.episode_resets
    assert (cfg.env.n_actions, cfg.env.state_dim) == (3, 1)  # from the env's own spaces


class NearGoalCorridor(FallingCorridor):
    """The falling corridor started 5 cells from the goal: a random policy reaches it every few hundred steps."""

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        self.state = np.array([35.0])
        return self.state.astype(np.float32) / 40, {}


if "tests/NearGoalCorridor-v0" not in gym.registry:
    gym.register(id="tests/NearGoalCorridor-v0", entry_point=NearGoalCorridor)


def test_a_run_that_goes_on_past_the_goal_counts_the_first_and_ends_at_the_cap(tmp_path: Path) -> None:
    """``budget.stop_at_goal=false`` (Figure 7's fixed-length curves): the goal resets the env and the run goes on; up
    to the first goal it is the run that stops there (same seed and machine: the same actions and rows)."""
    base = ["env=chain", "encoder=mlp", "env.id=tests/NearGoalCorridor-v0", "baseline=random", "progress=false",
            "env._target_=tests.test_envs.FallingCorridorAdapter", "env.coverage_low=[-0.5]",
            "env.coverage_high=[40.5]", "env.coverage_bins=[41]", "budget=smoke", "budget.max_steps=1000"]  # fmt: skip
    stops = run(compose_cfg(base), tmp_path / "stops")
    goes_on = run(compose_cfg([*base, "budget.stop_at_goal=false"]), tmp_path / "goes_on")
    assert stops.reached_goal and stops.goals == 1 and stops.env_steps == stops.steps_to_goal < 1000
    assert goes_on.steps_to_goal == stops.steps_to_goal and goes_on.env_steps == 1000
    assert goes_on.goals >= 2 and goes_on.episode_resets >= goes_on.goals, goes_on
    assert json.loads((tmp_path / "goes_on" / "summary.json").read_text())["goals"] == goes_on.goals
    clock = ["charts/wall_time", "charts/sps"]
    a = pd.read_csv(tmp_path / "stops" / "metrics.csv").drop(columns=clock)
    b = pd.read_csv(tmp_path / "goes_on" / "metrics.csv").drop(columns=clock)
    assert len(b) > len(a) and b["step"].iloc[-1] == 1000
    before_goal = (a.iloc[:-1], b.iloc[: len(a) - 1])  # the stopping run's last row is the goal step
    pd.testing.assert_frame_equal(*before_goal, check_exact=True)  # exact: same seed and machine, the same steps


def test_actions_and_state_size_come_from_the_envs_spaces() -> None:
    assert (env_actions("CartPole-v1"), env_state_dim("CartPole-v1")) == (2, 4)
    for name, actions, dim in (("acrobot", 3, 6), ("mountaincar", 3, 2)):
        cfg = compose_cfg([f"env={name}"])
        assert (cfg.env.n_actions, cfg.env.state_dim, cfg.planner.n_actions) == (actions, dim, actions)
    assert isinstance(adapter_of(compose_cfg().env), AcrobotAdapter)


def test_the_acrobot_adapter_reads_and_sets_the_physical_state() -> None:
    cfg = compose_cfg(["env.renderer=fast"])
    env, adapter = make_env(cfg.env, 100), adapter_of(cfg.env)
    env.reset(seed=0)
    state = np.array([0.1, -0.2, 0.3, -0.4])
    adapter.set_physical_state(env, state)
    assert np.array_equal(adapter.physical_state(env), state)
    assert not adapter.goal_reached(env, False, {}) and adapter.goal_reached(env, True, {})  # termination is its goal


def test_cartpole_goal_is_the_cart_far_out_not_the_pole_falling(tmp_path: Path) -> None:
    """CartPole-v1 (one YAML and one adapter module): a fallen pole resets the env, |x| > 2 is the goal."""
    cfg = compose_cfg(["env=cartpole", "encoder=mlp", "baseline=random", "budget=smoke", "progress=false"])
    summary = run(cfg, tmp_path)
    assert summary.episode_resets >= 1  # a random policy drops the pole within a few dozen steps
    assert (cfg.env.n_actions, cfg.env.state_dim) == (2, 4)
    env, adapter = make_env(cfg.env, 10), adapter_of(cfg.env)
    env.reset(seed=0)
    adapter.set_physical_state(env, np.array([2.1, 0.0, 0.0, 0.0]))
    assert adapter.goal_reached(env, False, {})
    adapter.set_physical_state(env, np.array([0.0, 0.0, 0.3, 0.0]))
    assert not adapter.goal_reached(env, True, {})
