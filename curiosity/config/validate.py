"""Range checks for every numeric field, run before any environment is built."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from omegaconf import DictConfig, OmegaConf

from curiosity.config.build import choice


class ConfigError(ValueError):
    """An invalid configuration value; the message names each key, its value and what is allowed."""


_ABSENT = object()

Rule = tuple[str, Callable[[Any], bool], str]

RULES: list[Rule] = [
    ("seed", lambda v: v >= 0, "an integer >= 0"),
    ("threads", lambda v: v >= 1, "an integer >= 1"),
    ("log_every", lambda v: v >= 1, "an integer >= 1"),
    ("checkpoint_every", lambda v: v >= 1, "an integer >= 1"),
    ("internal_dim", lambda v: v >= 1, "an integer >= 1"),
    ("n_step", lambda v: v >= 1, "an integer >= 1"),
    ("batch_size", lambda v: v >= 2, "an integer >= 2"),
    ("optimizer.lr", lambda v: isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0, "a learning rate > 0"),
    ("transition_coef", lambda v: v >= 0, "a number >= 0"),
    ("reward_coef", lambda v: v >= 0, "a number >= 0"),
    ("transition_hidden", lambda v: v >= 1, "an integer >= 1"),
    ("transition_dropout", lambda v: 0 <= v < 1, "a probability in [0, 1)"),
    ("replay_capacity", lambda v: v >= 1, "an integer >= 1"),
    ("action_scale", lambda v: v >= 0, "a number >= 0"),
    ("hybrid_alpha", lambda v: 0 <= v <= 1, "a weight in [0, 1]"),
    ("pe_eps", lambda v: v > 0, "a number > 0"),
    ("pe_dropout_samples", lambda v: v >= 1, "an integer >= 1"),
    ("memory_size", lambda v: v >= 1, "an integer >= 1"),
    ("memory_refresh_every", lambda v: v >= 1, "an integer >= 1"),
    ("q_coef", lambda v: v >= 0, "a number >= 0"),
    ("q_target_every", lambda v: v >= 1, "an integer >= 1"),
    ("env.frame_size", lambda v: v >= 8, "an integer >= 8"),
    ("env.frame_stack", lambda v: v >= 1, "an integer >= 1"),
    ("env.state_dim", lambda v: v >= 1, "an integer >= 1"),
    ("env.n_actions", lambda v: v >= 2, "an integer >= 2"),
    ("env.coverage_bins", lambda v: len(v) > 0 and all(b >= 1 for b in v), "a non-empty list of integers >= 1"),
    ("budget.max_steps", lambda v: v >= 1, "an integer >= 1 (the env-step cap)"),
    ("budget.warmup_steps", lambda v: v >= 0, "an integer >= 0"),
    ("budget.train_every", lambda v: v >= 1, "an integer >= 1"),
    ("budget.iters_per_train", lambda v: v >= 0, "an integer >= 0"),
    ("budget.ramp", lambda v: all(r >= 1 for r in v), "a list of integers >= 1"),
    ("budget.early_stop_every", lambda v: v >= 0, "an integer >= 0 (0 disables the early stop)"),
    ("budget.early_stop_threshold", lambda v: v > 0, "a number > 0"),
    ("estimator.bandwidth", lambda v: v > 0, "a number > 0"),
    ("estimator.k", lambda v: v >= 1, "an integer >= 1"),
    ("entropy.coef", lambda v: v >= 0, "a number >= 0"),
    ("entropy.t", lambda v: v > 0, "a number > 0"),
    ("entropy.alpha", lambda v: v > 0, "a Renyi order > 0"),
    ("entropy.sigma", lambda v: v > 0, "a kernel width > 0"),
    ("entropy.base", lambda v: v > 0 and v != 1, "a logarithm base > 0 and != 1"),
    ("backward.coef", lambda v: v >= 0, "a number >= 0"),
    ("backward.sigma_b", lambda v: v > 0, "a number > 0"),
    ("backward.n_candidates", lambda v: v >= 1, "an integer >= 1"),
    ("backward.noise_dim", lambda v: v >= 1, "an integer >= 1"),
    ("backward.hidden", lambda v: v >= 1, "an integer >= 1"),
    ("planner.horizon", lambda v: v >= 1, "an integer >= 1"),
    ("planner.gamma", lambda v: 0 <= v <= 1, "a discount in [0, 1]"),
    ("planner.temperature", lambda v: v >= 0, "a number >= 0 (0 = argmax)"),
    ("planner.eta", lambda v: v >= 0, "a number >= 0"),
    ("planner.max_candidates", lambda v: v >= 1, "an integer >= 1"),
    ("transition_ensemble", lambda v: v >= 1, "an integer >= 1 (1: one transition model)"),
    ("memory_refresh_drift", lambda v: v >= 0, "a number >= 0 (0: refresh on the schedule only)"),
    ("probe_every", lambda v: v >= 0, "an integer >= 0 (0: no model probe)"),
]


def _cross_field_errors(cfg: DictConfig) -> list[str]:
    errors = []
    low, high = list(cfg.env.coverage_low), list(cfg.env.coverage_high)
    if not len(low) == len(high) == len(cfg.env.coverage_bins):
        errors.append("env.coverage_low, env.coverage_high, env.coverage_bins: must have one length")
    elif any(h <= lo for lo, h in zip(low, high, strict=True)):
        errors.append(f"env.coverage_high={high}: must be > env.coverage_low={low} in every dimension")
    k = OmegaConf.select(cfg, "estimator.k", default=None)
    if k is not None and k >= cfg.budget.warmup_steps:
        errors.append(f"estimator.k={k}: must be < budget.warmup_steps={cfg.budget.warmup_steps} (the first memory)")
    if choice(cfg.pe_imagined) == "ensemble" and cfg.transition_ensemble < 2:
        errors.append(f"pe_imagined=ensemble: needs transition_ensemble >= 2, got {cfg.transition_ensemble}")
    if cfg.budget.warmup_steps < cfg.n_step:
        errors.append(f"budget.warmup_steps={cfg.budget.warmup_steps}: must be >= n_step={cfg.n_step} (segments to sample)")
    if cfg.budget.max_steps <= cfg.budget.warmup_steps:
        errors.append(
            f"budget.max_steps={cfg.budget.max_steps}: must be > budget.warmup_steps={cfg.budget.warmup_steps}"
        )
    return errors


def validate(cfg: DictConfig, rules: list[Rule] | None = None) -> None:
    """Check every rule whose key is present in ``cfg``.

    Raises:
        ConfigError: listing every violated key as ``key=value: must be <allowed>``.
    """
    errors = []
    for key, ok, allowed in RULES if rules is None else rules:
        value = OmegaConf.select(cfg, key, default=_ABSENT)
        if value is _ABSENT:
            continue
        if not ok(value):
            errors.append(f"{key}={value!r}: must be {allowed}")
    if not errors:
        errors = _cross_field_errors(cfg)
    if errors:
        raise ConfigError("invalid configuration:\n  " + "\n  ".join(errors))
