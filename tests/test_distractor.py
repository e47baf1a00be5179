"""The noisy TV (issue 16): the patch shows noise, the rest of the frame is the clean frame, the remote control is the
env's no-op plus a redraw, and the TV survives checkpoints, the simulator and a real run."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from curiosity.config import ConfigError, validate
from curiosity.envs import adapter_of, make_env
from curiosity.envs.distractor import NoisyTV, find_tv
from curiosity.envs.make import make_single_obs_env, observe_state
from curiosity.envs.simulator import Simulator
from curiosity.envs.state import env_state, restore_env
from curiosity.runtime.behaviour import BehaviourTracker
from curiosity.runtime.restore import restore_run
from tests.conftest import compose_cfg, run_cli

VARIANTS = ["noisy_tv", "noisy_tv_background"]
PATCH = (slice(0, 5), slice(0, 5))  # the default patch: 5x5 at the top-left


def _pair(name: str, distractor: str, renderer: str = "fast"):
    """The same env with and without the distractor, and the distractor's config."""
    clean = compose_cfg([f"env={name}", f"env.renderer={renderer}"])
    cfg = compose_cfg([f"env={name}", f"env.renderer={renderer}", f"env.distractor={distractor}"])
    return make_env(clean.env, 3000), make_env(cfg.env, 3000), cfg


def _outside(frame: np.ndarray) -> np.ndarray:
    mask = np.ones(frame.shape[-2:], dtype=bool)
    mask[PATCH] = False
    return frame[..., mask]


@pytest.mark.parametrize("name", ["acrobot", "mountaincar"])
@pytest.mark.parametrize("distractor", VARIANTS)
def test_check_env_passes_with_the_tv(name: str, distractor: str) -> None:
    _, env, cfg = _pair(name, distractor, renderer="gym")
    check_env(env, skip_render_check=True)
    assert env.action_space.n == 3 + (distractor == "noisy_tv") == cfg.env.n_actions
    env.close()


@pytest.mark.parametrize("name", ["acrobot", "mountaincar"])
def test_remote_control_redraws_the_patch_and_applies_the_noop(name: str) -> None:
    clean, env, _ = _pair(name, "noisy_tv")
    adapter = adapter_of(compose_cfg([f"env={name}"]).env)
    c, _ = clean.reset(seed=4)
    o, _ = env.reset(seed=4)
    tv_action = env.action_space.n - 1
    rng = np.random.default_rng(0)
    pressed = frozen = 0
    for _ in range(60):
        a = int(rng.integers(env.action_space.n))
        o2, *_ = env.step(a)
        c, *_ = clean.step(1 if a == tv_action else a)  # the TV action is the env's no-op (Acrobot: no torque)
        assert np.array_equal(adapter.physical_state(env), adapter.physical_state(clean))  # exact: same env, same actions
        # every frame of the stack equals the clean frame outside the patch (same renderer, same state: exact)
        assert np.array_equal(_outside(o2), _outside(c))  # exact: the TV writes only its patch
        changed = not np.array_equal(o2[-1][PATCH], o[-1][PATCH])
        if a == tv_action:
            pressed += 1
            assert changed  # fresh noise (25 uniform gray levels equal by chance: probability 256^-25)
        else:
            frozen += 1
            assert not changed  # exact: the patch stays frozen (the same values, copied)
        o = o2
    assert pressed > 5 and frozen > 30
    assert len(np.unique(o[-1][PATCH])) > 5  # noise, not a flat patch


def test_background_tv_changes_every_step_with_the_envs_own_actions() -> None:
    clean, env, _ = _pair("acrobot", "noisy_tv_background")
    assert env.action_space.n == 3
    clean.reset(seed=1)
    o, _ = env.reset(seed=1)
    for a in [0, 1, 2, 2, 1, 0, 0, 1]:
        o2, *_ = env.step(a)
        c, *_ = clean.step(a)
        assert np.array_equal(_outside(o2), _outside(c))  # exact: the TV writes only its patch
        assert not np.array_equal(o2[-1][PATCH], o[-1][PATCH])
        o = o2


def test_the_tv_is_seeded_by_reset_and_restored_from_a_checkpoint() -> None:
    _, env, cfg = _pair("acrobot", "noisy_tv")
    a, _ = env.reset(seed=7)
    _, again, _ = _pair("acrobot", "noisy_tv")
    b, _ = again.reset(seed=7)
    assert np.array_equal(a, b)  # exact: same seed, same generator
    for action in [3, 0, 3, 2]:
        env.step(action)
    saved = env_state(env, adapter_of(cfg.env))
    fresh = make_env(cfg.env, 3000)
    restore_env(fresh, saved, seed=7, adapter=adapter_of(cfg.env))
    for action in [3, 1, 3, 3, 0]:  # the same noise follows on both (the generator's state came back)
        x, *_ = env.step(action)
        y, *_ = fresh.step(action)
        assert np.array_equal(x, y)  # exact: same state, same generator, same machine


def test_simulator_imagines_the_tv() -> None:
    """Imagined frames: the TV action is the no-op plus fresh noise; other actions keep the previous frame's patch."""
    clean, env, cfg = _pair("acrobot", "noisy_tv")
    clean.reset(seed=2)
    obs, _ = env.reset(seed=2)
    sim = Simulator(cfg.env)
    root = sim.root(env, obs)
    nxt, _ = sim.step(root.take(np.array([0, 0, 0, 0])), np.array([0, 1, 2, 3]))
    truth, *_ = clean.step(1)
    assert np.array_equal(_outside(nxt.obs[3][-1]), _outside(truth[-1]))  # exact: the no-op, the same renderer
    for i in range(3):
        assert np.array_equal(nxt.obs[i][-1][PATCH], obs[-1][PATCH])  # exact: frozen, a copy of the same values
    assert not np.array_equal(nxt.obs[3][-1][PATCH], obs[-1][PATCH])  # redrawn


def test_behaviour_counts_tv_presses() -> None:
    tracker = BehaviourTracker(4, None, tv_action=3)
    rows = [tracker.record(a, np.zeros(4)) for a in [3, 0, 3, 3]]
    assert [r["behaviour/tv"] for r in rows] == [1.0, 0.0, 1.0, 1.0]
    assert tracker.summary()["tv_rate"] == 0.75 and "behaviour/tv" in tracker.keys


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (
            ["env.distractor=noisy_tv", "env.obs=state", "encoder=mlp"],
            "env.distractor=noisy_tv: the noisy TV is a patch of the frame",
        ),
        (
            ["env.distractor=noisy_tv", "env.tv.size=8", "env.tv.col=30"],
            "env.tv.size=8, env.tv.row=0, env.tv.col=30: the patch must lie inside",
        ),
        (["env.distractor=noisy_tv", "env.tv.size=0"], "env.tv.size=0"),
    ],
)
def test_bad_distractor_settings_are_refused_in_one_line(overrides: list[str], message: str) -> None:
    with pytest.raises(ConfigError, match=re.escape(message)) as info:
        validate(compose_cfg(overrides))
    assert "\n" not in str(info.value)


def test_remote_needs_a_noop_action() -> None:
    env = make_env(compose_cfg(["env=acrobot", "env.renderer=fast"]).env, 100)
    with pytest.raises(ValueError, match="no no-op"):
        NoisyTV(env.env, 5, 0, 0, remote=True, noop_action=None)  # the frame env under the stack


def test_smoke_run_with_the_tv_shows_the_patch_and_logs_presses(tmp_path: Path) -> None:
    """``python -m runners.train env.distractor=noisy_tv budget=smoke``: the run's frames show the patch."""
    out = tmp_path / "run"
    result = run_cli(["env.distractor=noisy_tv", "budget=smoke", f"hydra.run.dir={out}"], cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]
    summary = json.loads((out / "summary.json").read_text())
    assert 0 <= summary["behaviour"]["tv_rate"] <= 1 and len(summary["behaviour"]["action_freq"]) == 4
    with open(out / "metrics.csv") as f:
        rows = list(csv.DictReader(f))
    assert "behaviour/tv" in rows[0]
    restored = restore_run(out)
    tv = find_tv(restored.env)
    assert tv is not None and tv.remote
    frame = restored.obs[-1]
    assert np.array_equal(frame[PATCH], tv.patch)  # exact: the frame shows the TV's patch
    clean = make_single_obs_env(compose_cfg().env, 100)  # the same renderer, without the TV
    clean.reset(seed=0)
    adapter_of(restored.cfg.env).set_physical_state(clean, adapter_of(restored.cfg.env).physical_state(restored.env))
    expected = observe_state(clean, None)  # pixel wrappers render from the physical state
    assert np.array_equal(_outside(frame), _outside(expected))  # exact: same renderer, same state, same machine
