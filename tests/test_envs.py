"""Environments: gymnasium's checker, observation format, renderer agreement, coverage."""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from curiosity.envs import GridCoverage, make_env, physical_state
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
    for _ in range(150):
        a = int(rng.integers(3))
        og, *_ = gym_env.step(a)
        of, *_ = fast_env.step(a)
        assert np.array_equal(physical_state(gym_env), physical_state(fast_env))
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
