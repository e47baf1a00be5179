"""Load run directories into pandas DataFrames. Reads only ``summary.json``, ``.hydra/config.yaml``, ``metrics.csv``,
``FAILED.json`` and ``run.lock``.

``python -m analysis.collect ROOT [ROOT ...]`` prints one line per run directory below the roots: its status
(complete, stopped, failed, running), what it reached, and its path.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import pandas as pd
import yaml
from omegaconf import OmegaConf

from analysis.include import included_runs
from curiosity.runtime.checkpoint import lock_holder

GROUPS = ("env", "encoder", "entropy", "estimator", "backward", "baseline", "planner", "budget")
# A directory holds a run when it has one of these (a job refused before it started leaves only FAILED.json).
RUN_MARKERS = ("summary.json", "metrics.csv", "FAILED.json", ".hydra/config.yaml")


def run_dirs(root: str | Path) -> list[Path]:
    """Every finished run directory below ``root`` (a directory holding ``summary.json``), sorted, then the finished
    runs of other directories that ``root/analysis.yaml`` includes (:mod:`analysis.include`), sorted."""
    local = sorted(p.parent for p in Path(root).rglob("summary.json"))
    return local + included_runs(root, local)


def all_run_dirs(root: str | Path) -> list[Path]:
    """Every run directory below ``root``, finished or not (``root`` itself included), sorted."""
    found = set()
    for name in RUN_MARKERS:
        depth = len(Path(name).parts)  # the run directory is this many levels above the file
        found |= {p.parents[depth - 1] for p in Path(root).rglob(Path(name).name) if p.match(name)}
    return sorted(found)


def last_step(run_dir: Path) -> int | None:
    """The last env step a run's ``metrics.csv`` logged; None without one, or before its first row."""
    try:
        with (run_dir / "metrics.csv").open(newline="") as f:
            rows = list(csv.reader(f))
        return int(rows[-1][0]) if len(rows) > 1 else None
    except (OSError, ValueError):  # no file, or a last row being written
        return None


def run_status(run_dir: str | Path) -> tuple[str, str]:
    """(status, detail) of a run directory: complete, running, failed or stopped, and what it reached."""
    run_dir = Path(run_dir)
    step = last_step(run_dir)
    at = f"at env step {step}" if step is not None else "before its first metrics row"
    if (run_dir / "summary.json").exists():
        summary = json.loads((run_dir / "summary.json").read_text())
        goal = summary["steps_to_goal"]
        return "complete", f"goal at step {goal}" if goal is not None else f"goal not reached in {summary['max_steps']}"
    if (pid := lock_holder(run_dir)) is not None:
        return "running", f"process {pid}, {at}"
    if (run_dir / "FAILED.json").exists():
        error = json.loads((run_dir / "FAILED.json").read_text())["error"]
        return "failed", f"{at}: {' '.join(error.split())}"
    return "stopped", f"{at}; its command, run again, resumes it"


def _identity(run_dir: Path) -> dict[str, object]:
    """env, method, seed and the groups of a run, from its ``.hydra/config.yaml`` (empty if it has none)."""
    path = run_dir / ".hydra" / "config.yaml"
    if not path.exists():
        return {}
    cfg = OmegaConf.load(path)
    row: dict[str, object] = {"env": cfg.env.name, "method": cfg.method_label, "seed": int(cfg.seed)}
    return row | {g: str(cfg[g].name) for g in GROUPS if g in cfg and "name" in cfg[g]}


def load_incomplete(root: str | Path) -> pd.DataFrame:
    """One row per run below ``root`` without ``summary.json``: env, method, variant, seed, status, detail, run_dir."""
    rows = []
    for d in all_run_dirs(root):
        if (d / "summary.json").exists():
            continue
        status, detail = run_status(d)
        rows.append({**_identity(d), "variant": d.parent.name, "status": status, "detail": detail, "run_dir": str(d)})
    return pd.DataFrame(rows)


def load_summaries(root: str | Path) -> pd.DataFrame:
    """One row per run: the summary's fields, the run's group choices (``env``, ``entropy``, …), its overrides
    (``variant``: the run directory's parent, e.g. ``+experiment=paper_text`` or ``default``) and its path."""
    rows = []
    for d in run_dirs(root):
        row = json.loads((d / "summary.json").read_text())
        config = d / ".hydra" / "config.yaml"
        cfg = yaml.safe_load(config.read_text()) if config.exists() else {}  # a run made outside Hydra may have none
        for group in GROUPS:
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


def existing_roots(roots: list[str]) -> list[Path]:
    """The roots as paths; exits with status 2 and one line naming a root that does not exist."""
    missing = [r for r in roots if not Path(r).is_dir()]
    if missing:
        print(f"error: {missing[0]}: no such directory; allowed: a run directory or a directory holding some",
              file=sys.stderr)  # fmt: skip
        raise SystemExit(2)
    return [Path(r) for r in roots]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[-1].strip())
    parser.add_argument("roots", nargs="+", help="directories holding run directories (searched recursively)")
    dirs = [d for root in existing_roots(parser.parse_args().roots) for d in all_run_dirs(root)]
    if not dirs:
        print("error: no run directory below these roots (one holds summary.json, metrics.csv or FAILED.json)",
              file=sys.stderr)  # fmt: skip
        raise SystemExit(1)
    counts: dict[str, int] = {}
    for d in dirs:
        status, detail = run_status(d)
        counts[status] = counts.get(status, 0) + 1
        print(f"{status:9s} {d}  {detail}")
    print(f"{len(dirs)} run(s): " + ", ".join(f"{n} {status}" for status, n in sorted(counts.items())))


if __name__ == "__main__":
    main()
