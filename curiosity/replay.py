"""Circular replay buffer that stores each observation once and samples transitions or n-step segments."""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from curiosity.types import SegmentBatch, TransitionBatch


class ReplayBuffer:
    """FIFO replay of at most ``capacity`` transitions (o_t, a_t, r_t, o_{t+1}, d_t).

    Storage. Observations live in a ring of ``frame_capacity`` frames. A transition keeps the frame index f of o_t;
    o_{t+1} is always frame f + 1. When ``obs`` equals the previous transition's ``next_obs`` (and that transition
    was not terminal) the frame is shared, so a contiguous episode costs one frame per transition plus one per
    episode start. When a frame slot is about to be overwritten, the transitions that use it are evicted (oldest
    first), so with very short episodes fewer than ``capacity`` transitions may be held; the default
    ``frame_capacity = capacity + 1 + capacity // 16`` holds ``capacity`` transitions whenever episodes average at
    least 16 steps.

    Memory per transition ≈ (F/C)·obs_bytes + 22 bytes, obs_bytes = prod(obs_shape) × (1 if ``pixel_uint8`` else 4):
    4×32×32 pixels → ≈ 4.37 KB (uint8) or ≈ 17.4 KB (float32); capacity 10^6 uint8 ≈ 4.4 GB (allocated lazily
    by the OS as it fills).

    ``pixel_uint8=True`` stores observations o = (x − 128)/128 as uint8 x = round(128·o + 128), clipped to [0, 255];
    this is exact when x is an integer (e.g. frames rendered/resized in uint8) and quantises to 1/256 otherwise.

    Episodes. A transition starts a new episode when ``new_episode=True`` is passed, the previous transition was
    terminal, or ``obs`` differs from the previous ``next_obs``. Segments never cross an episode start, never run past
    a terminal transition (they may end with one) and never wrap around the write head.

    Args:
        capacity: C, maximum number of transitions.
        obs_shape: shape of one observation.
        pixel_uint8: store observations as uint8 (see above).
        frame_capacity: F, number of observation slots (≥ 2); defaults as above.
    """

    def __init__(
        self, capacity: int, obs_shape: tuple[int, ...], pixel_uint8: bool = False, frame_capacity: int | None = None
    ) -> None:
        if capacity < 1:
            raise ValueError("capacity must be >= 1")
        self.capacity = int(capacity)
        self.obs_shape = tuple(int(s) for s in obs_shape)
        self.pixel_uint8 = bool(pixel_uint8)
        self.frame_capacity = int(frame_capacity or capacity + 1 + capacity // 16)
        if self.frame_capacity < 2:
            raise ValueError("frame_capacity must be >= 2")
        self._frames = np.zeros((self.frame_capacity, *self.obs_shape), np.uint8 if pixel_uint8 else np.float32)
        self._frame_idx = np.zeros(capacity, np.int64)
        self._act = np.zeros(capacity, np.int64)
        self._rew = np.zeros(capacity, np.float32)
        self._term = np.zeros(capacity, np.bool_)
        self._start = np.zeros(capacity, np.bool_)
        self._oldest = 0
        self._size = 0
        self._next_frame = 0
        self.total_added = 0  # transitions ever added; the oldest stored one has global index total_added - len

    def __len__(self) -> int:
        return self._size

    # ------------------------------------------------------------------ writing
    def add(
        self,
        obs: np.ndarray,
        act: int,
        reward: float,
        next_obs: np.ndarray,
        terminated: bool,
        new_episode: bool = False,
    ) -> None:
        """Append one transition, evicting the oldest ones when full.

        Args:
            obs: o_t, shape ``obs_shape``.
            act: a_t.
            reward: r_t.
            next_obs: o_{t+1}, shape ``obs_shape``.
            terminated: whether o_{t+1} is terminal.
            new_episode: force an episode boundary before this transition.
        """
        obs_e, next_e = self._encode(obs), self._encode(next_obs)
        starts = new_episode or not self._continues(obs_e)
        if self._size == self.capacity:
            self._evict_oldest()
        obs_slot = self._write_frame(obs_e) if starts else (self._next_frame - 1) % self.frame_capacity
        self._write_frame(next_e)
        phys = (self._oldest + self._size) % self.capacity
        self._frame_idx[phys] = obs_slot
        self._act[phys] = int(act)
        self._rew[phys] = float(reward)
        self._term[phys] = bool(terminated)
        self._start[phys] = starts
        self._size += 1
        self.total_added += 1

    def _encode(self, obs: np.ndarray) -> np.ndarray:
        obs = np.asarray(obs)
        if obs.shape != self.obs_shape:
            raise ValueError(f"observation shape {obs.shape} != {self.obs_shape}")
        if self.pixel_uint8:
            return np.clip(np.rint(obs.astype(np.float64) * 128.0 + 128.0), 0, 255).astype(np.uint8)
        return obs.astype(np.float32)

    def _decode(self, frames: np.ndarray) -> torch.Tensor:
        if self.pixel_uint8:
            return (torch.from_numpy(frames).to(torch.float32) - 128.0) / 128.0
        return torch.from_numpy(frames)

    def _continues(self, obs_e: np.ndarray) -> bool:
        """Whether ``obs_e`` is the stored next observation of the newest, non-terminal transition."""
        if self._size == 0:
            return False
        newest = (self._oldest + self._size - 1) % self.capacity
        if self._term[newest]:
            return False
        return bool(np.array_equal(self._frames[(self._next_frame - 1) % self.frame_capacity], obs_e))

    def _write_frame(self, frame: np.ndarray) -> int:
        slot = self._next_frame
        while self._size and self._uses_frame(self._oldest, slot):
            self._evict_oldest()
        self._frames[slot] = frame
        self._next_frame = (slot + 1) % self.frame_capacity
        return slot

    def _uses_frame(self, phys: int, slot: int) -> bool:
        first = int(self._frame_idx[phys])
        return slot in (first, (first + 1) % self.frame_capacity)

    def _evict_oldest(self) -> None:
        self._oldest = (self._oldest + 1) % self.capacity
        self._size -= 1

    # ------------------------------------------------------------------ reading
    def _phys(self, logical: np.ndarray) -> np.ndarray:
        """Ring index of logical positions (0 = oldest transition)."""
        return (self._oldest + logical) % self.capacity

    def _gather(self, logical: np.ndarray) -> tuple[np.ndarray, ...]:
        phys = self._phys(logical)
        return self._frame_idx[phys], self._act[phys], self._rew[phys], self._term[phys]

    def sample_transitions(self, batch_size: int, generator: np.random.Generator) -> TransitionBatch:
        """Uniformly sample transitions (with replacement).

        Returns:
            :class:`TransitionBatch` with obs/next_obs (B, *obs_shape) float32, act (B,) long, rewards and
            terminateds (B,) float32.
        """
        if self._size == 0:
            raise ValueError("cannot sample from an empty buffer")
        return self._transitions(generator.integers(0, self._size, size=batch_size))

    def _transitions(self, logical: np.ndarray, index: torch.Tensor | None = None) -> TransitionBatch:
        frame, act, rew, term = self._gather(logical)
        return TransitionBatch(
            obs=self._decode(self._frames[frame]),
            act=torch.from_numpy(act),
            next_obs=self._decode(self._frames[(frame + 1) % self.frame_capacity]),
            rewards=torch.from_numpy(rew),
            terminateds=torch.from_numpy(term.astype(np.float32)),
            index=index,
        )

    def _breaks(self, logical: np.ndarray) -> np.ndarray:
        """True where a segment may not continue into logical position q ≥ 1: an episode starts there (which is
        always the case right after a terminal transition, see :meth:`_continues`)."""
        return self._start[self._phys(logical)]

    def valid_segment_starts(self, n: int) -> np.ndarray:
        """All logical positions p at which an n-transition segment may start.

        Returns:
            (M,) int64 positions p ≤ len − n with no episode start at p+1..p+n−1 and no terminal at p..p+n−2.
        """
        if n < 1 or self._size < n:
            return np.zeros(0, np.int64)
        broken = np.concatenate([[0], np.cumsum(self._breaks(np.arange(1, self._size)))])
        starts = np.arange(self._size - n + 1)
        return starts[broken[starts + n - 1] == broken[starts]]

    def _segment_ok(self, starts: np.ndarray, n: int) -> np.ndarray:
        if n == 1:
            return np.ones(starts.shape, np.bool_)
        return ~self._breaks(starts[:, None] + np.arange(1, n)).any(axis=1)

    def _segment_starts(self, batch_size: int, n: int, generator: np.random.Generator, tries: int = 8) -> np.ndarray:
        """Uniform draws over valid starts: rejection sampling, then exact enumeration for any remainder."""
        if self._size < n:
            raise ValueError(f"buffer holds {self._size} transitions, fewer than n = {n}")
        accepted: list[np.ndarray] = []
        missing = batch_size
        for _ in range(tries):
            draw = generator.integers(0, self._size - n + 1, size=batch_size)
            keep = draw[self._segment_ok(draw, n)][:missing]
            accepted.append(keep)
            missing -= keep.size
            if missing == 0:
                return np.concatenate(accepted)
        valid = self.valid_segment_starts(n)
        if valid.size == 0:
            raise ValueError(f"no valid segment of length {n} in the buffer")
        return np.concatenate([*accepted, generator.choice(valid, size=missing)])

    def sample_segments(self, batch_size: int, n: int, generator: np.random.Generator) -> SegmentBatch:
        """Uniformly sample n-step segments among the valid ones (with replacement).

        Returns:
            :class:`SegmentBatch` with obs (B, n + 1, *obs_shape), act (B, n) long, rewards and terminateds (B, n).
        """
        starts = self._segment_starts(batch_size, n, generator)
        frame, act, rew, term = self._gather(starts[:, None] + np.arange(n))
        frames = np.concatenate([frame, (frame[:, -1:] + 1) % self.frame_capacity], axis=1)
        return SegmentBatch(
            obs=self._decode(self._frames[frames]),
            act=torch.from_numpy(act),
            rewards=torch.from_numpy(rew),
            terminateds=torch.from_numpy(term.astype(np.float32)),
            index=torch.from_numpy(starts.astype(np.int64) + (self.total_added - self._size)),
        )

    def all_obs(self, start: int = 0, stop: int | None = None) -> torch.Tensor:
        """Observations o_t of stored transitions, oldest first (slice ``start:stop`` to re-embed in chunks).

        Returns:
            (M, *obs_shape) float32, aligned with :meth:`all_actions`.
        """
        logical = np.arange(self._size)[start:stop]
        return self._decode(self._frames[self._frame_idx[self._phys(logical)]])

    def _logical_of_global(self, index: np.ndarray) -> np.ndarray:
        logical = np.asarray(index, dtype=np.int64) - (self.total_added - self._size)
        if logical.size and (logical.min() < 0 or logical.max() >= self._size):
            raise IndexError(
                f"global transition indices {int(np.min(index))}..{int(np.max(index))} are not all stored (the buffer holds "
                f"{self.total_added - self._size}..{self.total_added - 1}); raise agent.replay_capacity"
            )
        return logical

    def transitions_at(self, index: np.ndarray) -> TransitionBatch:
        """Stored transitions by global index: (M,) -> a :class:`TransitionBatch` of M, carrying ``index``."""
        return self._transitions(self._logical_of_global(index), torch.as_tensor(np.asarray(index, dtype=np.int64)))

    def follows(self) -> np.ndarray:
        """(M,) bool, oldest first: True where a stored transition's o_{t+1} is the next stored transition's o_t (the
        same stored observation; False at an episode boundary and for the newest transition)."""
        out = np.zeros(self._size, dtype=np.bool_)
        if self._size > 1:
            out[:-1] = ~self._start[self._phys(np.arange(1, self._size))]
        return out

    def obs_at(self, index: np.ndarray) -> torch.Tensor:
        """o_t of transitions by global index (0 = the first transition ever added): (M,) -> (M, *obs_shape)."""
        return self._decode(self._frames[self._frame_idx[self._phys(self._logical_of_global(index))]])

    def actions_at(self, index: np.ndarray) -> torch.Tensor:
        """a_t of transitions by global index: (M,) -> (M,) long."""
        return torch.from_numpy(self._act[self._phys(self._logical_of_global(index))])

    def all_actions(self, start: int = 0, stop: int | None = None) -> torch.Tensor:
        """Actions a_t of stored transitions, oldest first; (M,) long."""
        return torch.from_numpy(self._act[self._phys(np.arange(self._size)[start:stop])])

    # ------------------------------------------------------------------ checkpointing
    def state_dict(self) -> dict[str, Any]:
        """Live contents as numpy arrays in oldest-first order (only the used frames, not the whole ring)."""
        logical = np.arange(self._size)
        first = int(self._frame_idx[self._oldest]) if self._size else self._next_frame
        n_frames = (self._next_frame - 1 - first) % self.frame_capacity + 1 if self._size else 0
        frame, act, rew, term = self._gather(logical)
        return {
            "config": np.array([self.capacity, self.frame_capacity, int(self.pixel_uint8)], np.int64),
            "obs_shape": np.array(self.obs_shape, np.int64),
            "frames": self._frames[(first + np.arange(n_frames)) % self.frame_capacity].copy(),
            "frame_idx": (frame - first) % self.frame_capacity,
            "act": act,
            "rew": rew,
            "term": term,
            "start": self._start[self._phys(logical)],
            "total_added": np.array(self.total_added, np.int64),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore :meth:`state_dict` output into a buffer built with the same configuration."""
        config = np.array([self.capacity, self.frame_capacity, int(self.pixel_uint8)], np.int64)
        if not np.array_equal(state["config"], config) or tuple(state["obs_shape"]) != self.obs_shape:
            raise ValueError("replay state was saved with a different capacity, frame capacity, dtype or obs shape")
        size, n_frames = len(state["act"]), len(state["frames"])
        self._frames[:n_frames] = state["frames"]
        for name in ("frame_idx", "act", "rew", "term", "start"):
            getattr(self, f"_{name}")[:size] = state[name]
        self._oldest, self._size, self._next_frame = 0, size, n_frames % self.frame_capacity
        self.total_added = int(state["total_added"])
