"""Load run directories into pandas DataFrames. Reads only ``summary.json``, ``.hydra/config.yaml`` and ``metrics.csv``."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import yaml


def run_dirs(root: str | Path) -> list[Path]:
    """Every run directory below ``root`` (a directory holding ``summary.json``), sorted."""
    return sorted(p.parent for p in Path(root).rglob("summary.json"))


def load_summaries(root: str | Path) -> pd.DataFrame:
    """One row per run: the summary's fields, the run's group choices (``env``, ``entropy``, …), its overrides
    (``variant``: the run directory's parent, e.g. ``+experiment=paper_text`` or ``default``) and its path."""
    rows = []
    for d in run_dirs(root):
        row = json.loads((d / "summary.json").read_text())
        cfg = yaml.safe_load((d / ".hydra" / "config.yaml").read_text())
        for group in ("env", "encoder", "entropy", "estimator", "backward", "baseline", "planner", "budget"):
            node = cfg.get(group)
            if isinstance(node, dict) and "name" in node:
                row[group] = str(node["name"])
        row["variant"] = d.parent.name  # the run's command-line overrides (``default`` when none)
        row["run_dir"] = str(d)
        rows.append(row)
    return pd.DataFrame(rows)


def load_metrics(root: str | Path) -> pd.DataFrame:
    """All ``metrics.csv`` rows below ``root``, with ``method``, ``seed`` and ``run_dir`` columns added."""
    frames = []
    for d in run_dirs(root):
        summary = json.loads((d / "summary.json").read_text())
        df = pd.read_csv(d / "metrics.csv")
        df.insert(0, "method", summary["method"])
        df.insert(1, "seed", summary["seed"])
        df["run_dir"] = str(d)
        frames.append(df)
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
