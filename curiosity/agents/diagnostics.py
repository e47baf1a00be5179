"""What the paper's agent measures beside planning, through one interface (:class:`PlanDiagnostics`): the noise of
stochastic plan scores, the model probe against the real simulator, and the run means of the planner, probe and
memory columns that ``summary.json`` reports.

None of it changes the run: the diagnostics draw their dropout masks inside a forked random stream, and they only
read the planner, the model and the intrinsic reward they are handed.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import torch
from torch import Tensor

from curiosity.envs.simulator import SimStates
from curiosity.planning.probe import probe_keys, probe_model
from curiosity.planning.protocols import IntrinsicFn, Planner, QFn, ScoreFn
from curiosity.planning.rollout import StepFn

# run means of these planner/probe/memory columns go to summary.json ("agent")
SUMMARY_KEYS = ("planner/first_action_entropy", "planner/noise", "planner/noise_flip", "probe/effect_ratio/1",
                "probe/effect_ratio/3", "probe/spearman", "probe/agree", "memory/drift", "memory/refreshed",
                "intrinsic/pe_estimate_corr")  # fmt: skip
NOISE_KEYS = ("planner/noise", "planner/noise_flip")


@dataclass
class PlanView:
    """What the diagnostics read at one planning step.

    Attributes:
        z0: (d,) the latent planned from.
        step_fn: the learned transition T(z (M, d), a (M,)) -> (M, d), eval mode.
        reward_fn: the reward model R(z, a) -> (M,), or None.
        intrinsic: the intrinsic terms of imagined edges (the planner's).
        stochastic: whether those terms draw noise (MC dropout), so that two evaluations differ.
        root: the real simulator's state at this observation (for the probe), made on demand.
        encode: E(o) -> z for the probe's true futures.
        q_fn: Q(z (M, d)) -> (M, A), the leaves' value of a planner with a terminal value, or None.
    """

    z0: Tensor
    step_fn: StepFn
    reward_fn: ScoreFn | None
    intrinsic: IntrinsicFn
    stochastic: bool
    root: Callable[[], SimStates]
    encode: Callable[[Tensor], Tensor]
    q_fn: QFn | None = None


class PlanDiagnostics:
    """The paper agent's diagnostics of planning (``planner/noise*``, ``probe/*``) and its run means.

    Args:
        planner: the agent's planner; the diagnostics run only for planners that score an explicit candidate set
            (``planner.scores_candidates``: MPC), and only on the learned model.
        probe_every: agent steps between probes against the real simulator (0: none).
        warmup_steps: the random warm-up, before which no agent step happens.
        learned: whether the planner imagines with the learned model (False: the oracle, whose futures are true).
        simulator: the real simulator the probe branches (None: no probe).
    """

    def __init__(self, planner: Planner, probe_every: int, warmup_steps: int, learned: bool,
                 simulator: Any | None = None) -> None:  # fmt: skip
        self.planner = planner
        scores = bool(getattr(planner, "scores_candidates", False))
        self.probe_every = int(probe_every) if scores else 0  # the probe scores every candidate, as MPC does
        self.noise = scores and learned
        self.warmup_steps = int(warmup_steps)
        self.simulator = simulator
        self.totals: dict[str, list[float]] = {}  # key -> [sum, count] of SUMMARY_KEYS

    @property
    def keys(self) -> tuple[str, ...]:
        """The probe's metric columns (the noise columns are the agent's own)."""
        return probe_keys(self.planner.horizon) if self.probe_every else ()

    @property
    def needs_simulator(self) -> bool:
        return self.probe_every > 0

    def after_plan(self, view: PlanView, step: int) -> dict[str, float]:
        """The noise of the plan's scores and, when due, the probe, at agent step ``step``; the run's random streams
        are left as they were."""
        with torch.random.fork_rng(devices=[]):  # dropout masks drawn here never change the run's stream
            logs = self._score_noise(view)
            logs.update(self._probe(view, step))
        return logs

    def _score_noise(self, view: PlanView) -> dict[str, float]:
        """Two fresh evaluations of the (stochastic) scores of every candidate: their noise and whether the best first
        action flips between them. Only with full enumeration and a stochastic term."""
        planner: Any = self.planner
        if not self.noise or not view.stochastic or planner.n_actions**planner.horizon > planner.max_candidates:
            return {}
        seqs = planner.candidates()
        g1, g2 = (planner.scores(view.z0, seqs, view.step_fn, view.reward_fn, view.intrinsic, q_fn=view.q_fn)
                  for _ in range(2))  # fmt: skip
        flip = int(seqs[int(g1.argmax()), 0]) != int(seqs[int(g2.argmax()), 0])
        return {"planner/noise": float((g1 - g2).std(correction=0)) / 2**0.5, "planner/noise_flip": float(flip)}

    def _probe(self, view: PlanView, step: int) -> dict[str, float]:
        if not self.probe_every or (step - self.warmup_steps) % self.probe_every:
            return {}
        assert self.simulator is not None, "attach_env() was not called"
        start = time.perf_counter()
        out = probe_model(self.planner, view.z0, view.step_fn, view.reward_fn, view.intrinsic, self.simulator,
                          view.root(), view.encode, view.q_fn)  # type: ignore[arg-type]  # fmt: skip
        out["timing/probe_ms"] = 1e3 * (time.perf_counter() - start)
        return out

    def tally(self, logs: Mapping[str, float]) -> None:
        """Add the ``SUMMARY_KEYS`` among ``logs`` to the run's sums."""
        for key in SUMMARY_KEYS:
            if key in logs:
                total = self.totals.setdefault(key, [0.0, 0])
                total[0] += logs[key]
                total[1] += 1

    def means(self) -> dict[str, float]:
        """The run means of the tallied keys (``summary.json``'s ``agent.means``)."""
        return {k: total / n for k, (total, n) in self.totals.items() if n}

    def state_dict(self) -> dict[str, list[float]]:
        return self.totals

    def load_state_dict(self, totals: Mapping[str, Any]) -> None:
        self.totals = {k: list(v) for k, v in totals.items()}
