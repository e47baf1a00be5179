"""When to train and for how long: the ``budget`` group's schedule."""

from __future__ import annotations

from collections.abc import Sequence


class TrainSchedule:
    """Training calls after the random warm-up.

    A call happens at every env step ``s`` (0-based) with ``s + 1 >= warmup_steps`` and
    ``(s + 1 - warmup_steps) % train_every == 0``; call ``k`` (0-based) runs ``iters_per_train * ramp[k]`` gradient
    iterations (``ramp[k] = 1`` past the end of ``ramp``). With ``early_stop_every > 0`` a call may stop at every
    multiple of ``early_stop_every`` iterations once the mean evaluation transition error over the iterations since
    the previous check is at most ``early_stop_threshold`` (the precursor's rule, docs/protocol.md §3.4).

    With ``plateau_every > 0`` (the adaptive schedule) ``iters_per_train`` is a call's most: every ``plateau_every``
    iterations the agent measures its model's error on the transitions held out of training so far (those that
    arrived since the previous call, :meth:`plateaued`), and the call stops once that error fell by less than the
    fraction ``plateau_tol`` since the previous measurement (or rose): it trains while the model still learns the new
    data, and stops when it has plateaued.

    Args:
        warmup_steps: uniformly random env steps before the first call.
        train_every: env steps between calls.
        iters_per_train: iterations of one call.
        ramp: multipliers of ``iters_per_train`` for the first calls (the precursor: 4, 3, 2).
        early_stop_every: iterations between early-stop checks; 0 never stops early.
        early_stop_threshold: the error at or below which a call stops.
        plateau_every: iterations between held-out checks of the adaptive schedule; 0: off.
        plateau_tol: the relative fall of the held-out error below which a call stops.
    """

    def __init__(
        self,
        warmup_steps: int,
        train_every: int,
        iters_per_train: int,
        ramp: Sequence[int] = (),
        early_stop_every: int = 0,
        early_stop_threshold: float = 1 / 256,
        plateau_every: int = 0,
        plateau_tol: float = 0.02,
    ) -> None:
        self.warmup_steps = warmup_steps
        self.train_every = train_every
        self.iters_per_train = iters_per_train
        self.ramp = list(ramp)
        self.early_stop_every = early_stop_every
        self.early_stop_threshold = early_stop_threshold
        self.plateau_every = plateau_every
        self.plateau_tol = plateau_tol
        self.calls = 0

    def iterations(self, step: int) -> int:
        """Iterations to run after env step ``step``; counts the call. 0 when no call is due."""
        since = step + 1 - self.warmup_steps
        if since < 0 or since % self.train_every != 0:
            return 0
        mult = self.ramp[self.calls] if self.calls < len(self.ramp) else 1
        self.calls += 1
        return self.iters_per_train * mult

    def stop_early(self, iteration: int, window_errors: Sequence[float]) -> bool:
        """Whether the call stops after ``iteration`` (1-based) given the errors since the previous check."""
        if self.early_stop_every <= 0 or iteration % self.early_stop_every != 0 or not window_errors:
            return False
        return sum(window_errors) / len(window_errors) <= self.early_stop_threshold

    def checks_plateau(self, iteration: int) -> bool:
        """Whether the adaptive schedule measures the held-out error after ``iteration`` (1-based)."""
        return self.plateau_every > 0 and iteration % self.plateau_every == 0

    def plateaued(self, before: float, now: float) -> bool:
        """Whether the held-out error ``now`` fell by less than ``plateau_tol`` of ``before`` (the previous one)."""
        return now > (1.0 - self.plateau_tol) * before

    def state_dict(self) -> dict[str, int]:
        return {"calls": self.calls}

    def load_state_dict(self, state: dict[str, int]) -> None:
        self.calls = int(state["calls"])
