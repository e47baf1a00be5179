"""Replay buffer: segment validity (property test), frame sharing, uint8 round-trip and checkpointing."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from curiosity.replay import ReplayBuffer


def make_stream(n_transitions, seed, max_len=12):
    """Random episodes; reward = global transition id. Episodes end by termination, truncation or a forced reset to
    the very observation the previous episode stopped at (only the explicit flag marks that boundary)."""
    rng = np.random.default_rng(seed)
    stream, episode, obs, forced = [], 0, np.array([0.0, 0.0], np.float32), False
    while len(stream) < n_transitions:
        length = int(rng.integers(1, max_len + 1))
        ending = rng.choice(["terminal", "truncated", "reset_same_obs"])
        for k in range(length):
            nxt = np.array([episode, k + 1], np.float32) + rng.normal(size=2).astype(np.float32)
            terminal = ending == "terminal" and k == length - 1
            stream.append(
                dict(
                    obs=obs,
                    act=int(rng.integers(3)),
                    reward=float(len(stream)),
                    next_obs=nxt,
                    terminated=terminal,
                    new_episode=forced and k == 0,
                    episode=episode,
                )
            )
            obs = nxt
        episode += 1
        forced = ending == "reset_same_obs"
        if not forced:
            obs = np.array([episode, 0.0], np.float32) + rng.normal(size=2).astype(np.float32)
    return stream[:n_transitions]


def add(buffer, t):
    buffer.add(t["obs"], t["act"], t["reward"], t["next_obs"], t["terminated"], new_episode=t["new_episode"])


def check_segments(buffer, stream, n_seen, n, rng):
    batch = buffer.sample_segments(64, n, rng)
    ids = batch.rewards.numpy().astype(int)
    oldest_live = n_seen - len(buffer)
    for seg, row in enumerate(ids):
        assert np.array_equal(row, row[0] + np.arange(n)), "segment spans the write head or skips transitions"
        assert row[0] >= oldest_live and row[-1] < n_seen
        truth = [stream[i] for i in row]
        assert len({t["episode"] for t in truth}) == 1, "segment crosses an episode boundary"
        assert not any(t["terminated"] for t in truth[:-1]), "segment runs past a terminal transition"
        expected_obs = np.stack([t["obs"] for t in truth] + [truth[-1]["next_obs"]])
        assert np.array_equal(batch.obs[seg].numpy(), expected_obs)
        assert batch.act[seg].tolist() == [t["act"] for t in truth]
        assert batch.terminateds[seg].tolist() == [float(t["terminated"]) for t in truth]


def ground_truth_starts(stream, n_seen, size, n):
    live = stream[n_seen - size : n_seen]
    starts = []
    for p in range(size - n + 1):
        window = live[p : p + n]
        if len({t["episode"] for t in window}) == 1 and not any(t["terminated"] for t in window[:-1]):
            starts.append(p)
    return np.array(starts, np.int64)


@pytest.mark.parametrize(("capacity", "frame_capacity", "seed"), [(60, None, 0), (40, 41, 1), (7, 3, 2)])
def test_segments_never_cross_terminals_episodes_or_the_write_head(capacity, frame_capacity, seed):
    stream = make_stream(400, seed)
    buffer = ReplayBuffer(capacity, (2,), frame_capacity=frame_capacity)
    rng = np.random.default_rng(seed)
    for i, t in enumerate(stream):
        add(buffer, t)
        assert 1 <= len(buffer) <= capacity
        if i % 13 == 12:
            for n in (1, 3, 5):
                valid = buffer.valid_segment_starts(n)
                assert np.array_equal(valid, ground_truth_starts(stream, i + 1, len(buffer), n))
                if valid.size:
                    check_segments(buffer, stream, i + 1, n, rng)


def test_transitions_and_all_obs_match_the_newest_stream():
    stream = make_stream(300, 5)  # episodes of 6.5 steps on average: 100 transitions need ~115 frames
    buffer = ReplayBuffer(100, (2,), frame_capacity=200)
    for t in stream:
        add(buffer, t)
    assert len(buffer) == 100
    live = stream[-100:]
    assert np.array_equal(buffer.all_obs().numpy(), np.stack([t["obs"] for t in live]))
    assert buffer.all_actions().tolist() == [t["act"] for t in live]
    assert np.array_equal(buffer.all_obs(10, 20).numpy(), np.stack([t["obs"] for t in live[10:20]]))
    batch = buffer.sample_transitions(128, np.random.default_rng(0))
    for j, ident in enumerate(batch.rewards.numpy().astype(int)):
        t = stream[ident]
        assert ident >= 200
        assert np.array_equal(batch.obs[j].numpy(), t["obs"]) and np.array_equal(batch.next_obs[j].numpy(), t["next_obs"])
        assert int(batch.act[j]) == t["act"] and float(batch.terminateds[j]) == float(t["terminated"])
    assert batch.act.dtype == torch.int64 and batch.obs.dtype == torch.float32


def test_contiguous_episode_stores_one_frame_per_transition():
    buffer = ReplayBuffer(50, (3,))
    obs = np.zeros(3, np.float32)
    for k in range(30):
        nxt = np.full(3, k + 1.0, np.float32)
        buffer.add(obs, 0, 0.0, nxt, False)
        obs = nxt
    assert buffer.state_dict()["frames"].shape[0] == 31
    buffer.add(np.full(3, -1.0, np.float32), 0, 0.0, np.zeros(3, np.float32), False)  # obs differs: new episode
    assert buffer.state_dict()["frames"].shape[0] == 33
    assert buffer.valid_segment_starts(2).max() == 28  # no segment joins the two episodes


def test_fallback_finds_rare_valid_segments():
    buffer = ReplayBuffer(200, (1,))
    for k in range(150):  # 150 one-step episodes (all terminal), then one 6-step episode
        buffer.add(np.array([k], np.float32), 0, 0.0, np.array([k + 0.5], np.float32), True)
    obs = np.array([1000.0], np.float32)
    for k in range(6):
        buffer.add(obs, 1, float(k), obs + 1, False)
        obs = obs + 1
    batch = buffer.sample_segments(32, 5, np.random.default_rng(0))
    assert set(batch.rewards[:, 0].tolist()) <= {0.0, 1.0}
    assert set(batch.rewards[:, 0].tolist()) == {0.0, 1.0}
    with pytest.raises(ValueError):
        buffer.sample_segments(4, 7, np.random.default_rng(0))


def test_pixel_uint8_round_trip_is_exact():
    rng = np.random.default_rng(0)
    shape = (4, 8, 8)
    xs = rng.integers(0, 256, size=(11, *shape))
    observations = ((xs - 128) / 128).astype(np.float32)
    buffer = ReplayBuffer(20, shape, pixel_uint8=True)
    for k in range(10):
        buffer.add(observations[k], k % 3, 0.0, observations[k + 1], False)
    assert buffer._frames.dtype == np.uint8
    assert np.array_equal(buffer.all_obs().numpy(), observations[:10])
    seg = buffer.sample_segments(8, 10, rng)
    assert np.array_equal(seg.obs[0].numpy(), observations)
    assert seg.obs.dtype == torch.float32


def test_state_dict_round_trip_and_identical_continuation():
    stream = make_stream(260, 7)
    original = ReplayBuffer(90, (2,))
    for t in stream[:200]:
        add(original, t)
    state = original.state_dict()
    assert all(isinstance(v, np.ndarray) for v in state.values())
    restored = ReplayBuffer(90, (2,))
    restored.load_state_dict(state)
    for t in stream[200:]:
        add(original, t)
        add(restored, t)
    assert len(restored) == len(original)
    assert np.array_equal(restored.all_obs().numpy(), original.all_obs().numpy())
    for n in (1, 4):
        a = original.sample_segments(32, n, np.random.default_rng(3))
        b = restored.sample_segments(32, n, np.random.default_rng(3))
        for field in ("obs", "act", "rewards", "terminateds"):
            assert torch.equal(getattr(a, field), getattr(b, field))
    with pytest.raises(ValueError):
        ReplayBuffer(91, (2,)).load_state_dict(state)


def test_empty_buffer_and_bad_shapes_raise():
    buffer = ReplayBuffer(5, (2,))
    with pytest.raises(ValueError):
        buffer.sample_transitions(1, np.random.default_rng(0))
    with pytest.raises(ValueError):
        buffer.add(np.zeros(3), 0, 0.0, np.zeros(2), False)


def test_global_indices_survive_eviction() -> None:
    buf = ReplayBuffer(capacity=4, obs_shape=(1,))
    for t in range(6):
        buf.add(np.array([float(t)], np.float32), t % 3, 0.0, np.array([float(t + 1)], np.float32), False)
    assert buf.total_added == 6 and len(buf) == 4
    assert buf.obs_at(np.array([2, 5]))[:, 0].tolist() == [2.0, 5.0]
    assert buf.actions_at(np.array([2, 5])).tolist() == [2, 2]
    with pytest.raises(IndexError, match="replay_capacity"):
        buf.obs_at(np.array([1]))
    restored = ReplayBuffer(capacity=4, obs_shape=(1,))
    restored.load_state_dict(buf.state_dict())
    assert restored.total_added == 6 and restored.obs_at(np.array([3]))[0, 0] == 3.0
