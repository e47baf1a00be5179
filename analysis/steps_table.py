"""Steps-to-goal per method: every seed, successes/seeds, mean ± standard error, and the runs not finished.

``python -m analysis.steps_table ROOT [ROOT ...] [--markdown]``. Runs that hit the step cap are censored: they count
in ``seeds`` but not in ``reached``; the mean and SE are over the runs that reached the goal, and ``mean_capped``
scores a censored run at its cap (a lower bound on the true mean). SE = sample SD / sqrt(n) (the paper's ±).
Runs without ``summary.json`` (stopped, failed, running) are not in the statistics; each group counts them
(``incomplete``) and every one is listed below the table. ``--markdown`` prints the table the README shows.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

import pandas as pd

from analysis.collect import existing_roots, load_incomplete, load_summaries
from analysis.rows import code_commit, distinguishing_keys
from analysis.runconfig import flat_config

BY = ("env", "method", "variant")


def command(variant: str, seeds: list[int]) -> str:
    """The command that runs a group's seeds: ``python -m runners.train [-m] <overrides> [seed=...]``."""
    overrides = [] if variant == "default" else re.split(r",(?![^\[]*\])", variant)
    if seeds != [0]:
        contiguous = len(seeds) > 1 and seeds == list(range(seeds[0], seeds[-1] + 1))
        overrides.append(f"seed={seeds[0]}-{seeds[-1]}" if contiguous else "seed=" + ",".join(map(str, seeds)))
    return " ".join(["python -m runners.train", *(["-m"] if len(seeds) > 1 else []), *overrides])


def _incomplete_counts(incomplete: pd.DataFrame | None) -> dict[tuple, int]:
    if incomplete is None or incomplete.empty or not set(BY) <= set(incomplete):
        return {}
    return {tuple(k): len(g) for k, g in incomplete.groupby(list(BY), sort=True)}


def split_code_defaults(
    summaries: pd.DataFrame, incomplete: pd.DataFrame | None = None
) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """``summaries`` (and ``incomplete``, the unfinished runs) with each (env, method, variant) group split where its
    runs' configs differ: the same command line run by code with other defaults (e.g. the default agent before and
    after a default changed) is not one method. The keys that differ (:func:`analysis.rows.distinguishing_keys` over
    the saved configs, read with the values that reproduce older runs) are appended to ``method``:
    ``ours-… [planner.commit=1]``."""

    def usable(f: pd.DataFrame | None) -> bool:
        return f is not None and not f.empty and "run_dir" in f

    frames = [f[[*BY, "run_dir"]] for f in (summaries, incomplete) if usable(f)]
    if not frames:
        return summaries, incomplete
    labels: dict[str, str] = {}
    for _key, g in pd.concat(frames, ignore_index=True).groupby(list(BY), sort=False):
        dirs = [d for d in g["run_dir"] if (Path(d) / ".hydra" / "config.yaml").exists()]
        configs = {d: flat_config(d) for d in dirs} if len(dirs) > 1 else {}
        keys = distinguishing_keys(list(configs.values())) if configs else []
        for d, cfg in configs.items() if keys else ():
            labels[d] = " [" + ", ".join(f"{k}={cfg.get(k, '–')}" for k in keys) + "]"

    def relabel(f: pd.DataFrame | None) -> pd.DataFrame | None:
        if not usable(f):
            return f
        f = f.copy()
        f["method"] = [f"{m}{labels[d]}" if d in labels else m for m, d in zip(f["method"], f["run_dir"], strict=True)]
        return f

    return relabel(summaries), relabel(incomplete)


def steps_table(summaries: pd.DataFrame, by: tuple[str, ...] = BY, incomplete: pd.DataFrame | None = None) -> pd.DataFrame:
    """One row per group of ``by``: seeds, reached, per-seed steps, mean ± SE, mean with censored runs at cap, the
    command that runs the group, and how many of its runs are ``incomplete`` (rows of :func:`load_incomplete`).
    With the default ``by``, runs of one command line whose configs differ are separate rows
    (:func:`split_code_defaults`)."""
    if by == BY:
        summaries, incomplete = split_code_defaults(summaries, incomplete)
    unfinished = _incomplete_counts(incomplete) if by == BY else {}
    rows = []
    for key, g in summaries.groupby(list(by), sort=True):
        key = key if isinstance(key, tuple) else (key,)
        g = g.sort_values("seed")
        reached = g[g["reached_goal"]]["steps_to_goal"].astype(float)
        capped = g["steps_to_goal"].where(g["reached_goal"], g["max_steps"]).astype(float)
        n = len(reached)
        rows.append({
            **dict(zip(by, key, strict=True)),
            "seeds": len(g),
            "reached": n,
            "per_seed": " ".join(str(int(s)) if ok else f">{int(c)}" for s, ok, c in
                                 zip(g["steps_to_goal"].fillna(0), g["reached_goal"], g["max_steps"], strict=True)),
            "mean": reached.mean() if n else math.nan,
            "se": reached.std(ddof=1) / math.sqrt(n) if n > 1 else math.nan,
            "mean_capped": capped.mean(),
            "wall_seconds_mean": g["wall_seconds"].mean(),
            "command": command(str(g["variant"].iloc[0]), [int(s) for s in g["seed"]]) if "variant" in g else "",
            "incomplete": unfinished.get(key, 0),
        })  # fmt: skip
    return pd.DataFrame(rows)


def pooled_commits(summaries: pd.DataFrame, by: tuple[str, ...] = BY) -> list[str]:
    """One line per group of ``by`` whose finished runs were made by more than one code commit (``git_commit`` of
    their summaries, ``+dirty`` where the tree had uncommitted changes): the same config run by other code may not be
    the same method, so a reader should know a row pools them. Groups of one commit, and runs that recorded none, give
    no line."""
    if summaries.empty or "git_commit" not in summaries:
        return []
    if by == BY:
        summaries, _ = split_code_defaults(summaries)
    f = summaries[summaries["git_commit"].notna()].copy()
    dirty = f["git_dirty"].fillna(False).astype(bool) if "git_dirty" in f else pd.Series(False, index=f.index)
    f["code"] = [code_commit({"git_commit": c, "git_dirty": d}) for c, d in zip(f["git_commit"], dirty, strict=True)]
    lines = []
    for key, g in f.groupby(list(by), sort=True):
        counts = g["code"].value_counts(sort=False).sort_index()
        if len(counts) > 1:
            name = " ".join(str(k) for k in (key if isinstance(key, tuple) else (key,)))
            made = ", ".join(f"{c} ({n} run{'s' if n > 1 else ''})" for c, n in counts.items())
            lines.append(f"{name}: pools runs of {len(counts)} code commits: {made}")
    return lines


def to_markdown(table: pd.DataFrame) -> str:
    """The README's table: method, command, seeds reaching the goal, steps-to-goal per seed, mean ± SE (over the runs
    that reached the goal, and where some did not, also the mean with those counted at the cap)."""
    lines = ["| method | command | seeds reaching the goal | steps-to-goal per seed | mean ± SE |", "|---|---|---|---|---|"]
    for row in table.itertuples(index=False):
        mean = "–" if math.isnan(row.mean) else f"{row.mean:.1f}" + ("" if math.isnan(row.se) else f" ± {row.se:.1f}")
        if row.reached < row.seeds:  # every seed counted: a run at the cap scores the cap (a lower bound)
            capped = f"{row.mean_capped:.1f} with the runs at the cap counted at the cap"
            mean = f"{mean} (reached); {capped}" if row.reached else capped
        seeds = f"{row.reached} / {row.seeds}" + (f" ({row.incomplete} more not finished)" if row.incomplete else "")
        lines.append(f"| {row.method} | `{row.command}` | {seeds} | {row.per_seed.replace(' ', ', ')} | {mean} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("roots", nargs="+", help="directories holding run directories (searched recursively)")
    parser.add_argument("--markdown", action="store_true", help="print the README's Markdown table")
    args = parser.parse_args()
    roots = existing_roots(args.roots)
    summaries = pd.concat([load_summaries(r) for r in roots], ignore_index=True)
    incomplete = pd.concat([load_incomplete(r) for r in roots], ignore_index=True)
    if summaries.empty and incomplete.empty:
        print(f"error: no run directory below {' '.join(args.roots)}", file=sys.stderr)
        raise SystemExit(1)
    if not summaries.empty:
        table = steps_table(summaries, incomplete=incomplete)
        print(to_markdown(table) if args.markdown else table.to_string(index=False))
        for line in pooled_commits(summaries):  # on stderr: the table on stdout stays what the README quotes
            print(f"warning: {line}", file=sys.stderr)
    if not incomplete.empty:
        print(f"\nNot finished (no summary.json), not in the table's statistics: {len(incomplete)} run(s)")
        for row in incomplete.itertuples(index=False):
            print(f"  {row.status}: {row.run_dir}  {row.detail}")


if __name__ == "__main__":
    main()
