"""What the agent does, step by step: action frequencies, repeats, the directed-action rate and, with a noisy TV's
remote control, how often it presses the TV.

Only the agent's own steps count (after the random warm-up). A uniformly random policy over A actions has action
frequencies 1/A, repeat rate 1/A and directed-action rate 1/A (1/3 on Acrobot and MountainCar); an agent whose
numbers sit there acts, as far as these statistics can tell, at random.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np


def behaviour_keys(n_actions: int, directed: bool, tv: bool = False) -> tuple[str, ...]:
    """Metric columns :meth:`BehaviourTracker.record` returns."""
    keys = [f"behaviour/action_{a}" for a in range(n_actions)] + ["behaviour/repeat"]
    keys += ["behaviour/directed"] if directed else []
    return (*keys, "behaviour/tv") if tv else tuple(keys)


class BehaviourTracker:
    """Per-step behaviour columns and their run totals for ``summary.json``.

    Args:
        n_actions: A.
        directed_fn: physical state -> the directed action (or None where it has none); None for envs without one.
        tv_action: the noisy TV's remote-control action (``behaviour/tv`` is 1 when pressed), or None.
    """

    def __init__(self, n_actions: int, directed_fn: Callable[[np.ndarray], int | None] | None,
                 tv_action: int | None = None) -> None:  # fmt: skip
        self.n_actions, self.directed_fn, self.tv_action = n_actions, directed_fn, tv_action
        self.keys = behaviour_keys(n_actions, directed_fn is not None, tv_action is not None)
        self.counts = np.zeros(n_actions, dtype=np.int64)
        self.repeats = self.directed = self.directed_defined = 0
        self.previous: int | None = None

    def record(self, action: int, state_before: np.ndarray) -> dict[str, float]:
        """One agent step: its action and the physical state it was taken in -> this step's columns."""
        out = {f"behaviour/action_{a}": float(a == action) for a in range(self.n_actions)}
        self.counts[action] += 1
        if self.previous is not None:
            out["behaviour/repeat"] = float(action == self.previous)
            self.repeats += int(action == self.previous)
        self.previous = action
        if self.directed_fn is not None:
            target = self.directed_fn(state_before)
            if target is not None:
                out["behaviour/directed"] = float(action == target)
                self.directed += int(action == target)
                self.directed_defined += 1
        if self.tv_action is not None:
            out["behaviour/tv"] = float(action == self.tv_action)
        return out

    def summary(self) -> dict[str, Any]:
        """Run totals: ``action_freq`` (A,), ``repeat_rate``, ``directed_rate`` (None where undefined), ``agent_steps``
        and, with a TV remote, ``tv_rate``."""
        n = int(self.counts.sum())
        out = {
            "agent_steps": n,
            "action_freq": [float(c / n) for c in self.counts] if n else None,
            "repeat_rate": self.repeats / (n - 1) if n > 1 else None,
            "directed_rate": self.directed / self.directed_defined if self.directed_defined else None,
        }
        if self.tv_action is not None:
            out["tv_rate"] = float(self.counts[self.tv_action] / n) if n else None
        return out

    def state_dict(self) -> dict[str, Any]:
        return {"counts": self.counts.copy(), "repeats": self.repeats, "directed": self.directed,
                "directed_defined": self.directed_defined, "previous": self.previous}  # fmt: skip

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.counts = np.array(state["counts"], dtype=np.int64)
        self.repeats, self.directed = int(state["repeats"]), int(state["directed"])
        self.directed_defined, self.previous = int(state["directed_defined"]), state["previous"]
