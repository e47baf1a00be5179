"""How wrong is the learned model where it matters? The planner's imagined futures against the real simulator's.

From one state of a run, the probe expands the full tree of action sequences of the planner's horizon twice, once
with the learned transition and once with the real simulator (each true future rendered and encoded with the run's
encoder), and reports:

With ``planner.hold`` > 1 a depth is that many env steps (each action held), as the planner sees it.

(a) the action effect at depth k = 1..H: the RMS spread of the depth-k latents across all A^k action prefixes,
    predicted (``effect_pred/k``) and true (``effect_true/k``), their ratio (``effect_ratio/k``; 1 is right, 0 is a
    model that ignores the action), and the RMS error of the predicted latents (``error/k``);
(b) the Spearman rank correlation between the planner's scores Ĝ of every candidate sequence computed on the
    model's futures and on the true futures (``spearman``; a terminal value, Q of the leaf, is in both);
(c) whether the first action of the best sequence is the same under both (``agree``, 1 or 0).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch
from torch import Tensor

from curiosity.envs.simulator import Simulator, SimStates
from curiosity.planning.mpc import MPCPlanner
from curiosity.planning.protocols import IntrinsicFn, QFn, ScoreFn
from curiosity.planning.rollout import LatentRollout, ReplayRollout, Rollout, SimulatorRollout, StepFn, held


def tree_latents(rollout: Rollout, n_actions: int, horizon: int) -> list[Tensor]:
    """Latents of every action prefix of length 1..H, expanded depth by depth.

    Returns:
        H tensors; the k-th is (A^k, d), prefixes in lexicographic order (first action most significant).
    """
    out, width = [], 1
    for _ in range(horizon):
        index = torch.arange(width * n_actions, device=rollout.latents().device)
        out.append(rollout.expand(index // n_actions, index % n_actions))
        width *= n_actions
    return out


def _rms(x: Tensor) -> float:
    return float(x.square().sum(-1).mean().sqrt())


def probe_keys(horizon: int) -> tuple[str, ...]:
    """The metric names :func:`probe_model` returns, prefixed ``probe/``."""
    per_depth = [f"probe/{name}/{k}" for k in range(1, horizon + 1)
                 for name in ("effect_true", "effect_pred", "effect_ratio", "error")]  # fmt: skip
    return (*per_depth, "probe/spearman", "probe/agree")


@torch.no_grad()
def probe_model(planner: MPCPlanner, z0: Tensor, step_fn: StepFn, reward_fn: ScoreFn | None, intrinsic_fn: IntrinsicFn,
                simulator: Simulator, root: SimStates, encode: Callable[[Tensor], Tensor],
                q_fn: QFn | None = None) -> dict[str, float]:  # fmt: skip
    """Probe the model at one state (see the module docstring).

    Args:
        planner: the run's MPC planner (its horizon, actions, γ, η and candidates).
        z0: (d,) latent of the root observation.
        step_fn: the learned T(z (M, d), a (M,) long) -> (M, d), in eval mode.
        reward_fn: R(z, a) -> (M,) or None, as the planner uses it.
        intrinsic_fn: the planner's r_int(z, a, z_next) (a tensor or named terms).
        simulator: the run env's simulator; ``root`` the state to branch from.
        encode: observations (M, *obs_shape) -> latents (M, d), in eval mode.
        q_fn: the leaves' value Q(z (M, d)) -> (M, A) of a planner with a terminal value, or None.

    Returns:
        ``probe/...`` metrics (:func:`probe_keys`); a ratio or correlation that is undefined (a zero true effect,
        constant scores) is left out.
    """
    h, a = planner.horizon, planner.n_actions
    predicted = tree_latents(held(LatentRollout(z0, step_fn), planner.hold), a, h)
    true = tree_latents(held(SimulatorRollout(simulator, root, z0, encode), planner.hold), a, h)
    out: dict[str, float] = {}
    for k, (zp, zt) in enumerate(zip(predicted, true, strict=True), start=1):
        effect_true, effect_pred = _rms(zt - zt.mean(0)), _rms(zp - zp.mean(0))
        out[f"probe/effect_true/{k}"], out[f"probe/effect_pred/{k}"] = effect_true, effect_pred
        out[f"probe/error/{k}"] = _rms(zp - zt)
        if effect_true > 0:
            out[f"probe/effect_ratio/{k}"] = effect_pred / effect_true
    seqs = planner.candidates(torch.Generator(device="cpu").manual_seed(0))
    g_model = planner.scores(z0, seqs, step_fn, reward_fn, intrinsic_fn, q_fn=q_fn).cpu().numpy()
    full = len(seqs) == a**h  # all sequences: score the true tree above again instead of simulating it twice
    replay = ReplayRollout(z0, true, planner.hold) if full else SimulatorRollout(simulator, root, z0, encode)
    g_true = planner.scores(z0, seqs, step_fn, reward_fn, intrinsic_fn, rollout=replay, q_fn=q_fn).cpu().numpy()
    if np.ptp(g_model) > 0 and np.ptp(g_true) > 0:
        from scipy.stats import spearmanr  # on first use: importing scipy.stats takes ~1 s

        out["probe/spearman"] = float(spearmanr(g_model, g_true).statistic)
    out["probe/agree"] = float(int(seqs[int(np.argmax(g_model)), 0]) == int(seqs[int(np.argmax(g_true)), 0]))
    return out
