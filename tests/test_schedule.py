"""The training schedule: when calls happen, the ramp, the early stop."""

from __future__ import annotations

from curiosity.agents.schedule import TrainSchedule


def test_calls_start_after_warmup_every_k_steps_with_ramp() -> None:
    s = TrainSchedule(warmup_steps=4, train_every=3, iters_per_train=10, ramp=[4, 3, 2])
    its = [s.iterations(step) for step in range(16)]
    # first call after the 4th env step (step 3), then every 3 steps: steps 3, 6, 9, 12, 15
    assert its == [0, 0, 0, 40, 0, 0, 30, 0, 0, 20, 0, 0, 10, 0, 0, 10]
    assert s.calls == 5


def test_every_step_and_no_warmup() -> None:
    s = TrainSchedule(warmup_steps=0, train_every=1, iters_per_train=2)
    assert [s.iterations(step) for step in range(3)] == [2, 2, 2]


def test_early_stop_only_at_checkpoints_and_below_threshold() -> None:
    s = TrainSchedule(0, 1, 100, early_stop_every=20, early_stop_threshold=0.01)
    assert not s.stop_early(19, [0.0])  # not a check iteration
    assert not s.stop_early(20, [0.02, 0.02])
    assert s.stop_early(40, [0.01, 0.005])
    assert not TrainSchedule(0, 1, 100).stop_early(20, [0.0])  # disabled


def test_state_round_trip() -> None:
    s = TrainSchedule(0, 1, 5, ramp=[3])
    s.iterations(0)
    t = TrainSchedule(0, 1, 5, ramp=[3])
    t.load_state_dict(s.state_dict())
    assert t.iterations(1) == 5
