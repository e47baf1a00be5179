"""What a seed costs against what it achieves (the cheap-seed study, ``results/cheap_seed/README.md``): ``cost.{md,csv}``.

Written by ``python -m analysis.tables RUNS_DIR`` (with ``pareto.{png,pdf,csv}``, :mod:`analysis.pareto`) whenever
some finished run's ``summary.json`` records ``cpu_seconds`` (the run process's CPU time over its loop, summed over
resumes); a directory whose runs predate it gets neither file. One line per (env, row) of the rows that record it, rows
as in ``analysis.tables`` (a row still running is shown with the seeds it finished and the runs it has not):

- steps-to-goal over the row's finished seeds, a run that did not reach the goal counted at its cap (the study's
  rule): mean ± SE, median, IQM with its 95 % bootstrap CI (:mod:`analysis.stats`), the seeds that reached the goal;
- CPU seconds per seed: median and mean, and the reference row's median over this row's (``× cheaper``);
- the study's non-inferiority statistic against the reference row: mean(row) / mean(reference) over the seeds both
  finished, its one-sided 90 % paired-bootstrap upper bound (:func:`analysis.stats.ratio_upper_bound`: 10,000
  resamples of the shared seeds, ``numpy.random.default_rng(0)``) and whether that bound is at most the margin (1.10,
  the cheap-seed study's; ``analysis.yaml``'s ``margin`` sets another);
- the behaviour rates (``summary.json``'s ``behaviour``) and the probe's Spearman (``agent.means['probe/spearman']``),
  means over the seeds that record them, each column only where some run records it.

Rows also get a short name (``--label SHORT=GLOB`` or ``analysis.yaml``'s ``labels``; otherwise the keys in the row
label's brackets where they tell the env's rows apart), which the Markdown table and the figure show.
"""

from __future__ import annotations

import fnmatch
import json
import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from analysis.claims import fmt
from analysis.runconfig import IGNORED, flat_config
from analysis.stats import iqm_ci, mean_se, ratio_upper_bound

MARGIN = 1.10  # the cheap-seed study's rule 2: not worse when the bound of mean(point) / mean(today) is at most this
CHEAPER = 5.0  # README rule 3: the new default must be at least this many times cheaper (median CPU seconds)
BEHAVIOUR = ("directed_rate", "repeat_rate", "tv_rate")  # summary.json's behaviour rates, in this order
PROBE = "probe/spearman"
EXTRA = ("cpu_seconds", *BEHAVIOUR, "probe_spearman")


def note(margin: float = MARGIN) -> str:
    """The cost table's caption, its rule at ``margin``."""
    return ("Cost per seed against steps-to-goal, lower is better for both. Steps: a run that did not reach the goal "
            "counted at its cap; SE = sample SD (ddof = 1)/√n; IQM with its 95 % percentile-bootstrap CI over seeds "
            "(2000 resamples, seed 0). CPU s: `summary.json`'s `cpu_seconds` per seed (runs without it left out of the "
            "CPU columns); × cheaper: the reference row's median over this row's. Ratio: mean(row) / mean(reference) "
            "over the seeds both finished (shared); bound: its one-sided 90 % paired-bootstrap upper bound (10,000 "
            "resamples of the shared seeds with replacement, numpy default_rng(0), 90th percentile of the resampled "
            f"ratios); non-inferior when the bound is ≤ {margin:.2f}. The study's rule applies to a point that ran all "
            "the seeds its README names; before, the column is provisional. Behaviour and probe: means over the "
            "seeds that record them.")  # fmt: skip


def summary_extras(run_dir: str | Path) -> dict[str, float]:
    """A finished run's ``cpu_seconds``, behaviour rates and probe Spearman from its ``summary.json`` (NaN if absent)."""
    summary = json.loads((Path(run_dir) / "summary.json").read_text())
    behaviour = summary.get("behaviour") or {}
    means = (summary.get("agent") or {}).get("means") or {}

    def number(x: object) -> float:
        return float(x) if isinstance(x, int | float) and not isinstance(x, bool) else math.nan

    return {"cpu_seconds": number(summary.get("cpu_seconds")), **{k: number(behaviour.get(k)) for k in BEHAVIOUR},
            "probe_spearman": number(means.get(PROBE))}  # fmt: skip


def with_extras(runs: pd.DataFrame) -> pd.DataFrame:
    """Labelled runs (``analysis.rows``) with the :func:`summary_extras` columns and ``at_cap``: steps-to-goal with a
    run that did not reach the goal at its cap."""
    extras = pd.DataFrame([summary_extras(d) for d in runs["run_dir"]], index=runs.index, columns=list(EXTRA))
    at_cap = runs["steps"].where(~runs["censored"].astype(bool), runs["cap"].astype(float))
    return pd.concat([runs, extras], axis=1).assign(at_cap=at_cap.astype(float))


def has_cost(runs: pd.DataFrame) -> bool:
    """Whether some run records ``cpu_seconds`` (a :func:`with_extras` frame)."""
    return not runs.empty and bool(runs["cpu_seconds"].notna().any())


def parse_labels(specs: Sequence[str]) -> list[tuple[str, str]]:
    """``["today=GLOB", …]`` -> [("today", "GLOB"), …]; ValueError for an item without ``=`` or a side empty."""
    out = []
    for spec in specs:
        short, sep, pattern = spec.partition("=")
        if not sep or not short.strip() or not pattern:
            raise ValueError(f"label {spec!r}: expected SHORT=GLOB (a short name, then a glob over row labels)")
        out.append((short.strip(), pattern))
    return out


def _automatic(row: str) -> str:
    """The keys in a row label's brackets and what follows them (``nsrs [planner.horizon=5] (bench)`` ->
    ``planner.horizon=5 (bench)``); the label itself without brackets."""
    match = re.fullmatch(r"(.*?) \[(.*)\](.*)", row)
    return match[2] + match[3] if match else row


def short_labels(rows: pd.DataFrame, specs: Sequence[str] = ()) -> dict[tuple[str, str], str]:
    """A short name for every (env, row) of ``rows``: the first ``SHORT=GLOB`` of ``specs`` whose glob matches the row
    (ValueError when one glob matches two rows of an env), otherwise :func:`_automatic`'s where it is unique in its
    env, otherwise the row label."""
    pairs = sorted(set(zip(rows["env"].astype(str), rows["row"].astype(str), strict=True)))
    labels = parse_labels(specs)
    out: dict[tuple[str, str], str] = {}
    for env in sorted({e for e, _ in pairs}):
        names = [r for e, r in pairs if e == env]
        for short, pattern in labels:
            hits = [r for r in names if fnmatch.fnmatchcase(r, pattern)]
            if len(hits) > 1:
                raise ValueError(f"label {short}={pattern} matches {len(hits)} rows of {env}: {'; '.join(hits)}")
            if hits and (env, hits[0]) not in out:
                out[(env, hits[0])] = short
        given = {out[(env, r)] for r in names if (env, r) in out}
        auto = {r: _automatic(r) for r in names if (env, r) not in out}
        for r, a in auto.items():
            out[(env, r)] = a if list(auto.values()).count(a) == 1 and a not in given else r
    return out


def reference_rows(runs: pd.DataFrame, env: str, reference: str) -> list[str]:
    """The row labels of ``env`` that the glob ``reference`` matches, sorted."""
    names = sorted(set(runs.loc[runs["env"] == env, "row"].astype(str)))
    return [r for r in names if fnmatch.fnmatchcase(r, reference)]


def _identity(config: dict[str, object]) -> tuple[tuple[str, str], ...]:
    return tuple(sorted((k, repr(v)) for k, v in config.items() if k not in IGNORED))


def not_finished(runs: pd.DataFrame, incomplete: pd.DataFrame) -> dict[tuple[str, str], str]:
    """Per (env, row): the runs without ``summary.json`` (:func:`analysis.collect.load_incomplete`) whose config, but
    for the keys ``analysis.rows.IGNORED`` (the seed among them), is that of one of the row's finished runs, counted by
    status (``1 running, 2 stopped``)."""
    if incomplete.empty:
        return {}
    rows: dict[tuple[tuple[str, str], ...], tuple[str, str]] = {}
    for env, row, cfg in zip(runs["env"], runs["row"], runs["config"], strict=True):
        rows.setdefault(_identity(cfg), (str(env), str(row)))
    counts: dict[tuple[str, str], dict[str, int]] = {}
    for run_dir, status in zip(incomplete["run_dir"], incomplete["status"], strict=True):
        if not (Path(run_dir) / ".hydra" / "config.yaml").is_file():
            continue
        key = rows.get(_identity(flat_config(run_dir)))
        if key is not None:
            counts.setdefault(key, {}).setdefault(str(status), 0)
            counts[key][str(status)] += 1
    return {k: ", ".join(f"{n} {s}" for s, n in sorted(c.items())) for k, c in counts.items()}


def _paired(g: pd.DataFrame, ref: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """The steps (at cap) of the seeds both rows finished, in seed order; none when a row repeats a seed."""
    if g["seed"].duplicated().any() or ref["seed"].duplicated().any():
        return np.empty(0), np.empty(0)
    both = g.merge(ref, on="seed", suffixes=("", "_ref")).sort_values("seed")
    return both["at_cap"].to_numpy(float), both["at_cap_ref"].to_numpy(float)


def _against(g: pd.DataFrame, ref: pd.DataFrame | None, is_ref: bool, margin: float = MARGIN) -> dict[str, Any]:
    """The CPU ratio and the non-inferiority statistic of a row's runs ``g`` against the reference row's."""
    if ref is None or is_ref:
        return {"cpu_ratio": math.nan, "shared": 0, "ratio": math.nan, "ratio_bound": math.nan, "non_inferior": ""}
    new, old = _paired(g[["seed", "at_cap"]], ref[["seed", "at_cap"]])
    ratio, bound = ratio_upper_bound(new, old)
    cpu = g["cpu_seconds"].median()
    return {"cpu_ratio": float(ref["cpu_seconds"].median() / cpu) if cpu > 0 else math.nan, "shared": len(new),
            "ratio": ratio, "ratio_bound": bound,
            "non_inferior": "" if math.isnan(bound) else ("yes" if bound <= margin else "no")}  # fmt: skip


def cost_table(runs: pd.DataFrame, reference: str, labels: dict[tuple[str, str], str],
               unfinished: dict[tuple[str, str], str] | None = None, margin: float = MARGIN) -> pd.DataFrame:  # fmt: skip
    """One line per (env, row) of :func:`with_extras`' runs whose row has a run recording ``cpu_seconds``, sorted; the
    reference is the one row of the env the glob ``reference`` matches (the ratio columns are empty where it matches
    none or several: ``reference_rows``); a row is non-inferior when its bound is at most ``margin``."""
    out = []
    for (env, row), g in runs.groupby(["env", "row"], sort=True):
        if g["cpu_seconds"].isna().all():
            continue
        g = g.sort_values(["stratum", "seed"]) if "stratum" in g else g.sort_values("seed")
        matched = reference_rows(runs, str(env), reference)
        ref = runs[(runs["env"] == env) & (runs["row"] == matched[0])] if len(matched) == 1 else None
        strata = [s["at_cap"].tolist() for _, s in g.groupby("stratum", sort=True)] if "stratum" in g else [g["at_cap"]]
        mean, se = mean_se(g["at_cap"])
        point, low, high = iqm_ci(strata)
        cpu = g["cpu_seconds"].dropna()
        is_ref = len(matched) == 1 and row == matched[0]
        out.append({
            "env": env, "row": row, "label": labels.get((str(env), str(row)), str(row)), "is_reference": is_ref,
            "seeds": len(g), "reached": int((~g["censored"]).sum()), "at_cap": int(g["censored"].sum()),
            "not_finished": (unfinished or {}).get((str(env), str(row)), ""),
            "mean": mean, "se": se, "median": float(g["at_cap"].median()), "iqm": point, "iqm_low": low, "iqm_high": high,
            "cpu_runs": len(cpu), "cpu_median": float(cpu.median()), "cpu_mean": float(cpu.mean()),
            **_against(g, ref, is_ref, margin),
            **{k: float(g[k].mean()) if g[k].notna().any() else math.nan for k in (*BEHAVIOUR, "probe_spearman")},
        })  # fmt: skip
    return pd.DataFrame(out)


def _shown(table: pd.DataFrame) -> list[str]:
    """The behaviour and probe columns some line of ``table`` has."""
    return [k for k in (*BEHAVIOUR, "probe_spearman") if table[k].notna().any()]


def header(margin: float = MARGIN) -> list[str]:
    return ["env", "point", "reached / seeds", "not finished", "steps mean ± SE", "median", "IQM [95 % CI]",
            "CPU s / seed: median", "mean", "× cheaper", "ratio of means", "90 % bound", f"non-inferior (≤ {margin:.2f})",
            "shared seeds"]  # fmt: skip


TITLES = {"directed_rate": "directed", "repeat_rate": "repeat", "tv_rate": "TV presses", "probe_spearman": "probe ρ"}


def _cells(r: Any, extra: Sequence[str]) -> list[str]:
    ci = "" if math.isnan(r.iqm_low) else f" [{fmt(r.iqm_low, '.1f')}, {fmt(r.iqm_high, '.1f')}]"
    against = ["(reference)", "–", "–", "–", "–"] if r.is_reference else [
        "–" if math.isnan(r.cpu_ratio) else f"{r.cpu_ratio:.2f}×", fmt(r.ratio, ".3f"), fmt(r.ratio_bound, ".3f"),
        r.non_inferior or "–", str(r.shared) if r.shared else "–"]  # fmt: skip
    se = "" if math.isnan(r.se) else f" ± {fmt(r.se, '.1f')}"
    return [str(r.env), str(r.label), f"{r.reached} / {r.seeds}", r.not_finished or "–", fmt(r.mean, ".1f") + se,
            fmt(r.median, ".1f"), fmt(r.iqm, ".1f") + ci, fmt(r.cpu_median, ".0f"), fmt(r.cpu_mean, ".0f"), *against,
            *(fmt(getattr(r, k), ".3f") for k in extra)]  # fmt: skip


def _reference_line(runs: pd.DataFrame, table: pd.DataFrame, reference: str) -> str:
    """Which row each env compares against, or why none."""
    parts = []
    for env in sorted(table["env"].astype(str).unique()):
        matched = reference_rows(runs, env, reference)
        if len(matched) == 1:
            parts.append(f"{env}: `{matched[0]}`")
        else:
            parts.append(f"{env}: the glob matches {len(matched)} rows, so no ratio (name one row)")
    return f"Reference `{reference}`: " + "; ".join(parts) + "."


def to_markdown(table: pd.DataFrame, runs: pd.DataFrame, reference: str, margin: float = MARGIN) -> str:
    """The cost table under a heading, its note, the reference row of each env and the full label of every short name."""
    extra = _shown(table)
    head = header(margin) + [TITLES[k] for k in extra]
    lines = ["## Cost per seed", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(c.replace("|", "\\|") for c in _cells(r, extra)) + " |"
              for r in table.itertuples(index=False)]  # fmt: skip
    lines += ["", note(margin), "", _reference_line(runs, table, reference)]
    named = [f"- {r.env} `{r.label}`: `{r.row}`" for r in table.itertuples(index=False) if r.label != r.row]
    lines += ["", "Points (short name: row label):", "", *named] if named else []
    return "\n".join(lines) + "\n"


def write_cost(runs: pd.DataFrame, out: Path, reference: str, labels: Sequence[str] = (),
               incomplete: pd.DataFrame | None = None, margin: float = MARGIN) -> bool:  # fmt: skip
    """``cost.{md,csv}`` into ``out`` for labelled runs (``analysis.rows``) when some run records ``cpu_seconds``, a row
    non-inferior when its bound is at most ``margin``; returns whether they were written (``analysis.pareto`` then
    draws the same rows)."""
    runs = with_extras(runs)
    if not has_cost(runs):
        return False
    short = short_labels(runs, labels)
    unfinished = not_finished(runs, incomplete if incomplete is not None else pd.DataFrame())
    table = cost_table(runs, reference, short, unfinished, margin)
    out.mkdir(parents=True, exist_ok=True)
    (out / "cost.md").write_text(to_markdown(table, runs, reference, margin))
    table.to_csv(out / "cost.csv", index=False, float_format="%.6g", lineterminator="\n")
    return True
