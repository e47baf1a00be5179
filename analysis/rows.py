"""Which table row each run belongs to, decided from its resolved ``.hydra/config.yaml`` (never from directory names).

A row is (env, method label) plus the config keys that distinguish runs of that pair: every key whose value differs
between the pair's runs that have it (``seed`` and the bookkeeping keys in ``IGNORED`` left out). Two runs of
the default agent, one with ``planner.horizon=5 planner.temperature=0``, become the rows
``ours-… [planner.horizon=3, planner.temperature=0.02]`` and ``ours-… [planner.horizon=5, planner.temperature=0]``.
``group_by`` names the keys instead (dotted config paths, e.g. ``entropy.name``); ``pool`` merges rows explicitly.
No row counts a seed twice: where another preset ran the same config and seed again, the row is split by directory.
"""

from __future__ import annotations

import fnmatch
import json
import os
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from analysis.collect import run_dirs
from analysis.runconfig import IGNORED, flat_config
from curiosity.runtime.machine import machine_label

def code_commit(summary: dict) -> str:
    """The commit a run's ``summary.json`` records, shortened to 7 characters, ``+dirty`` where the working tree had
    uncommitted changes; ``""`` where it records none."""
    commit = summary.get("git_commit")
    if not commit:
        return ""
    return str(commit)[:7] + ("+dirty" if summary.get("git_dirty") else "")


def load_runs(root: str | Path) -> pd.DataFrame:
    """One row per finished run below ``root``: env, method, seed, steps-to-goal, its value with a censored run at its
    last step (``steps``), ``censored``, ``cap``, the code commit that made it (``code``: ``git_commit``'s first 7
    characters, ``+dirty`` where the tree had uncommitted changes; empty where the summary recorded none), the machine
    that made it (``machine``: CPU and vector capability; empty where the summary recorded none), the run's flat config
    under ``config`` and ``run_dir``."""
    rows = []
    for d in run_dirs(root):
        summary = json.loads((d / "summary.json").read_text())
        cfg = flat_config(d)
        reached = bool(summary["reached_goal"])
        cap = int(summary["max_steps"])
        last = int(summary.get("env_steps") or cap)  # the paper's Table 2 rule: a censored run counts at its last step
        rows.append({
            "env": str(cfg.get("env.name", summary.get("env"))), "method": str(summary["method"]),
            "seed": int(summary["seed"]),
            "reached": reached, "steps": float(summary["steps_to_goal"]) if reached else float(last),
            "censored": not reached, "cap": cap, "wall_seconds": float(summary.get("wall_seconds", float("nan"))),
            "code": code_commit(summary), "machine": machine_label(summary.get("machine")), "config": cfg,
            "run_dir": str(d),
        })  # fmt: skip
    return pd.DataFrame(rows)


def _value(config: dict[str, object], key: str) -> str:
    value = config.get(key, "–")
    return ",".join(map(str, value)) if isinstance(value, tuple) else str(value)


def distinguishing_keys(configs: Sequence[dict[str, object]]) -> list[str]:
    """The keys whose values are not all equal among the configs that have them (``IGNORED`` left out), sorted. A key
    only some configs have (``encoder.blur_sigma`` of a conv encoder beside an MLP's) still tells the others apart."""
    keys = set().union(*(set(c) for c in configs)) - set(IGNORED)
    return sorted(k for k in keys if len({repr(c[k]) for c in configs if k in c}) > 1)


def label_rows(runs: pd.DataFrame, group_by: Sequence[str] = ()) -> pd.DataFrame:
    """``runs`` with a ``row`` column: the method label plus its distinguishing keys (a row repeating a seed split by
    directory, :func:`_split_repeated_seeds`), or the ``group_by`` keys' values."""
    runs = runs.copy()
    labels = pd.Series("", index=runs.index, dtype=object)
    for (_env, method), g in runs.groupby(["env", "method"], sort=True):
        keys = list(group_by) or distinguishing_keys(list(g["config"]))
        for i, cfg in g["config"].items():
            extra = ", ".join(f"{k}={_value(cfg, k)}" for k in keys)
            labels[i] = f"{method} [{extra}]" if extra and not group_by else (extra if group_by else method)
    runs["row"] = labels
    if not group_by:  # named keys group across methods and configs on purpose; a repeated seed is then no repeat
        runs["row"] = _split_repeated_seeds(runs)
    return runs


def _split_repeated_seeds(runs: pd.DataFrame) -> pd.Series:
    """Row labels where no row holds one seed twice: a row in which two runs have the same seed (the same config run
    again by another preset, e.g. a benchmark repeating Table 1's seeds) is split by where its runs live, the first
    directories below the row's common path that tell the repeats apart, as ``label (table1)`` and
    ``label (bench/seeds_078a391)``. Rows without a repeated seed keep their label."""
    labels = runs["row"].copy()
    for (_env, _row), g in runs.groupby(["env", "row"], sort=False):
        if not g["seed"].duplicated().any():
            continue
        paths = [Path(d).parts for d in g["run_dir"]]
        base = len(Path(os.path.commonpath(g["run_dir"].tolist())).parts)
        source = g["run_dir"]
        for depth in range(1, max(len(p) for p in paths) - base + 1):
            source = pd.Series(["/".join(p[base : base + depth]) for p in paths], index=g.index)
            if not pd.DataFrame({"s": source, "seed": g["seed"]}).duplicated().any():
                break
        short = {src: _shortest_prefix(src, set(source)) for src in set(source)}
        labels[g.index] = [f"{row} ({short[src]})" for row, src in zip(g["row"], source, strict=True)]
    return labels


def _shortest_prefix(source: str, sources: set[str]) -> str:
    """The fewest leading directories of ``source`` that no other of ``sources`` starts with."""
    parts = source.split("/")
    for n in range(1, len(parts)):
        prefix = "/".join(parts[:n])
        if not any(o != source and (o == prefix or o.startswith(prefix + "/")) for o in sources):
            return prefix
    return source


def pool_rows(runs: pd.DataFrame, pools: Sequence[str]) -> pd.DataFrame:
    """Merge rows: each ``LABEL=PATTERN`` renames every row matching the glob ``PATTERN`` to ``LABEL`` (per env);
    ``LABEL+=PATTERN`` adds the pooled row ``LABEL`` and keeps the rows it pools. ``stratum`` keeps the row each run
    came from (the bootstrap resamples seeds within each stratum)."""
    runs = runs.copy()
    runs["stratum"] = runs["row"]
    added = []
    for pool in pools:
        label, sep, pattern = pool.partition("=")
        keep = label.endswith("+")
        label = label.removesuffix("+")
        if not sep or not label or not pattern:
            raise ValueError(f"--pool {pool}: expected LABEL=PATTERN or LABEL+=PATTERN (a glob over row labels)")
        match = [fnmatch.fnmatchcase(r, pattern) for r in runs["row"]]
        if keep:
            added.append(runs.loc[match].assign(row=label))
        else:
            runs.loc[match, "row"] = label
    return pd.concat([runs, *added], ignore_index=True) if added else runs
