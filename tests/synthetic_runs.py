"""Synthetic run directories with known numbers, for the analysis tests (written like a real run: ``.hydra/config.yaml``,
``metrics.csv``, ``summary.json``; a failed run has ``FAILED.json``, a stopped one no ``summary.json``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

LOG_EVERY = 10


def _config(env: str, method: str, seed: int, entropy: str, estimator: str, horizon: int, distractor: str) -> dict:
    n_actions = 3 + (distractor == "noisy_tv")
    return {"env": {"name": env, "n_actions": n_actions, "distractor": distractor}, "entropy": {"name": entropy, "coef": 1.0},
            "estimator": {"name": estimator}, "planner": {"name": "mpc", "horizon": horizon},
            "budget": {"name": "quick"}, "seed": seed, "progress": False, "threads": 1, "method_label": method}  # fmt: skip


def _metrics(seed: int, last: int, estimator: str, behaviour: bool, tv_rate: float | None = None) -> pd.DataFrame:
    """Rows every 10 steps up to ``last``: coverage rising to last/10000, a decaying intrinsic reward (KDE settles
    sooner than kNN), entropy loss, yardstick, iterations and, with ``behaviour``, behaviour columns."""
    step = np.arange(LOG_EVERY, last + 1, LOG_EVERY)
    rng = np.random.default_rng(seed)
    decay = 100.0 if estimator == "kde" else 400.0
    df = pd.DataFrame({
        "step": step, "charts/coverage": step / 10000.0,
        "intrinsic/reward": 1.0 + np.exp(-step / decay) * (1 + 0.5 * rng.standard_normal(step.size)),
        "losses/entropy": -np.log1p(step / 100.0), "info/latent_logdet": np.log1p(step / 50.0),
        "train/iterations": np.where(step > 60, 8.0, np.nan),
    })  # fmt: skip
    if behaviour:
        df["behaviour/directed"] = np.clip(step / last, 0, 1)
        df["behaviour/repeat"] = 0.5
    if tv_rate is not None:  # the remote pressed at this rate, from the first row on
        df["behaviour/tv"] = tv_rate
    return df


def make_run(root: Path, env: str, method: str, seed: int, steps: int | None, cap: int = 3000, *, entropy: str = "none",
             estimator: str = "kde", horizon: int = 3, status: str = "complete", behaviour: bool = True,
             distractor: str = "none", tv_rate: float | None = None, cpu_seconds: float | None = None) -> Path:  # fmt: skip
    """One run directory under ``root/<env>/<method>/h<horizon>/seed=<seed>``: ``steps`` is its steps-to-goal (None: it
    hit ``cap``); ``status`` ``failed`` writes FAILED.json and ``stopped`` nothing more (both: no summary.json). With
    ``distractor`` (under ``<distractor>/`` then), ``tv_rate`` is the TV-press rate its summary and metrics report.
    ``cpu_seconds``, where given, is the CPU time its summary records (a run made before the field existed has none)."""
    d = root / env / method / f"h{horizon}" / (distractor if distractor != "none" else "") / f"seed={seed}"
    (d / ".hydra").mkdir(parents=True)
    config = _config(env, method, seed, entropy, estimator, horizon, distractor)
    (d / ".hydra" / "config.yaml").write_text(yaml.safe_dump(config))
    last = steps if steps is not None else cap
    if status != "complete":
        last = min(last, 500)
    _metrics(seed, last, estimator, behaviour, tv_rate).to_csv(d / "metrics.csv", index=False)
    if status == "failed":
        (d / "FAILED.json").write_text(json.dumps({"error": "NumericalFault: losses/entropy is nan at env step 500"}))
    elif status == "complete":
        summary = {"method": method, "seed": seed, "env": env, "steps_to_goal": steps, "reached_goal": steps is not None,
                   "env_steps": last, "max_steps": cap, "wall_seconds": 1.0,
                   "behaviour": {"tv_rate": tv_rate} if tv_rate is not None else None}  # fmt: skip
        if cpu_seconds is not None:
            summary["cpu_seconds"] = cpu_seconds
        (d / "summary.json").write_text(json.dumps(summary))
    return d


RENYI = "ours-mlp-renyi-kde-backward_off-mpc"
RENYI_MI = "ours-mlp-renyi_mi-knn-backward_off-mpc"
# The known numbers: (env, method, seed, steps-to-goal or None for the cap, keyword arguments).
RUNS = [
    ("mountaincar", "nsrs", 0, 1000, {"cap": 1900}),
    ("mountaincar", "nsrs", 1, 1200, {"cap": 1900}),
    ("mountaincar", "nsrs", 2, None, {"cap": 1900}),  # censored: counted at 1900
    ("mountaincar", "nsrs", 3, 800, {"cap": 1900}),
    ("mountaincar", RENYI, 0, 1500, {"cap": 1900, "entropy": "renyi"}),
    ("mountaincar", RENYI, 1, 1700, {"cap": 1900, "entropy": "renyi"}),
    ("mountaincar", RENYI_MI, 0, 1300, {"cap": 1900, "entropy": "renyi_mi", "estimator": "knn"}),
    ("mountaincar", RENYI_MI, 1, None, {"cap": 1900, "entropy": "renyi_mi", "estimator": "knn"}),
    ("mountaincar", RENYI_MI, 2, 1100, {"cap": 1900, "entropy": "renyi_mi", "estimator": "knn"}),
    ("acrobot", "random", 0, 1700, {"behaviour": False}),
    ("acrobot", "random", 1, 2100, {"behaviour": False}),
    ("acrobot", "nsrs", 0, 600, {}),
    ("acrobot", "nsrs", 1, 700, {}),
    ("acrobot", "nsrs", 2, 500, {}),
    ("acrobot", "nsrs", 0, 900, {"horizon": 5}),  # the same method with another planner horizon: its own row
    ("acrobot", "nsrs", 1, 1100, {"horizon": 5}),
]


def make_runs(root: Path) -> Path:
    """Every run of ``RUNS``, plus a failed run and a stopped one (no summary.json); returns ``root``."""
    for env, method, seed, steps, kw in RUNS:
        make_run(root, env, method, seed, steps, **kw)
    make_run(root, "acrobot", "random", 2, None, status="failed")
    make_run(root, "acrobot", "random", 3, None, status="stopped")
    return root
