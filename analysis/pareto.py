"""Cost against sample efficiency, one point per row: ``pareto.{png,pdf,csv}``.

``python -m analysis.pareto RUNS_DIR [--out DIR] [--reference GLOB] [--label SHORT=GLOB ...] [--group-by KEYS]
[--pool LABEL=GLOB ...]`` writes to DIR (default ``RUNS_DIR/report``); ``python -m analysis.tables`` writes the same
files beside ``cost.{md,csv}`` (:mod:`analysis.cost`, whose rows, short names and reference these are). One panel per
env; each row that records ``cpu_seconds`` is a point at x = its median CPU seconds per seed and y = its mean
steps-to-goal (a run that did not reach the goal at its cap), each with a 95 % percentile-bootstrap CI over its seeds
(:func:`analysis.stats.bootstrap_ci`: 2000 resamples, seed 0), in the row's colour and marker of the other figures
(:func:`analysis.plotting.row_names`). The reference row is a star (edged in black); a dotted line marks
1.10 × its mean (the study's non-inferiority margin, on the means rather than their bound) and a dashed one 1/5 of its
median CPU (the study's "5 × cheaper"); a grey line joins the points no other point beats on both axes (the front).
``pareto.csv`` holds what is plotted.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.container import ErrorbarContainer
from matplotlib.ticker import LogFormatter

from analysis.cli import Options, label_option, parser, run
from analysis.cost import CHEAPER, MARGIN, has_cost, reference_rows, with_extras
from analysis.plotting import TEXT, RowNames, legend_outside, panels, row_names, save, styles
from analysis.rows import label_rows, load_runs, pool_rows
from analysis.settings import DEFAULT_REFERENCE, margin_setting
from analysis.stats import bootstrap_ci

COLUMNS = ["env", "row", "label", "is_reference", "seeds", "cpu_runs", "cpu_median", "cpu_low", "cpu_high", "steps_mean",
           "steps_low", "steps_high", "on_front"]  # fmt: skip


def front(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Whether each point is on the Pareto front: no other point has x and y at most its own, one of them lower."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    beaten = (x[None, :] <= x[:, None]) & (y[None, :] <= y[:, None]) & ((x[None, :] < x[:, None]) | (y[None, :] < y[:, None]))
    return ~beaten.any(axis=1)


def pareto_points(runs: pd.DataFrame, reference: str, labels: dict[tuple[str, str], str]) -> pd.DataFrame:
    """One point per (env, row) of :func:`analysis.cost.with_extras`' runs whose row records ``cpu_seconds``, sorted:
    median CPU seconds per seed and mean steps-to-goal (at cap), each with its 95 % bootstrap CI, and ``on_front``."""
    out = []
    for (env, row), g in runs.groupby(["env", "row"], sort=True):
        cpu = g["cpu_seconds"].dropna().to_numpy(float)
        if cpu.size == 0:
            continue
        matched = reference_rows(runs, str(env), reference)
        cpu_low, cpu_high = bootstrap_ci(cpu, np.median)
        steps_low, steps_high = bootstrap_ci(g["at_cap"].to_numpy(float), np.mean)
        out.append({"env": env, "row": row, "label": labels.get((str(env), str(row)), str(row)),
                    "is_reference": matched == [row], "seeds": len(g), "cpu_runs": int(cpu.size),
                    "cpu_median": float(np.median(cpu)), "cpu_low": cpu_low, "cpu_high": cpu_high,
                    "steps_mean": float(g["at_cap"].mean()), "steps_low": steps_low, "steps_high": steps_high})  # fmt: skip
    points = pd.DataFrame(out, columns=COLUMNS[:-1])
    points["on_front"] = False
    for _, p in points.groupby("env", sort=True):
        points.loc[p.index, "on_front"] = front(p["cpu_median"].to_numpy(), p["steps_mean"].to_numpy())
    return points


def _errors(centre: float, low: float, high: float) -> np.ndarray:
    """Error-bar lengths (2, 1) below and above ``centre``; 0 where the CI is NaN (fewer than 2 seeds)."""
    return np.nan_to_num(np.array([[centre - low], [high - centre]]), nan=0.0)


def _point(ax: Axes, r: pd.Series, label: str, **style: object) -> None:
    """One row's point with its two CIs."""
    ax.errorbar(r.cpu_median, r.steps_mean, xerr=_errors(r.cpu_median, r.cpu_low, r.cpu_high),
                yerr=_errors(r.steps_mean, r.steps_low, r.steps_high), capsize=2, lw=1, label=label, **style)  # fmt: skip


def _panel(ax: Axes, p: pd.DataFrame, prefix: str, names: RowNames, margin: float = MARGIN) -> None:
    """One env's points (legend labels after ``prefix``; the reference's first), the reference's margin and cost lines
    and the front."""
    for _, r in p[p["is_reference"]].iterrows():
        _point(ax, r, f"{prefix}{r.label}, the reference (n={r.seeds})", fmt="*", color=names.style[r.label].colour,
               ms=11, mec="black", mew=0.6)  # fmt: skip
    others = p[~p["is_reference"]]
    for _, r in sorted(others.iterrows(), key=lambda ir: names.rank(ir[1].env, ir[1].row)):
        style = names.style[r.label]
        _point(ax, r, f"{prefix}{r.label} (n={r.seeds})", fmt=style.marker, color=style.colour, ms=5)
    for _, r in p[p["is_reference"]].iterrows():
        ax.axhline(margin * r.steps_mean, color="0.3", ls=":", lw=1, label=f"{margin:.2f} × the reference's mean steps")
        ax.axvline(r.cpu_median / CHEAPER, color="0.5", ls="--", lw=1, label=f"{CHEAPER:g} × cheaper than the reference")
    on = p[p["on_front"]].sort_values("cpu_median")
    if len(on) > 1:
        ax.plot(on["cpu_median"], on["steps_mean"], color="0.6", lw=0.8, zorder=0, label="front (no point beats it on both)")
    ax.set_xscale("log")
    ax.margins(x=0.1, y=0.08)  # a point at the edge keeps its marker whole
    ax.xaxis.set_major_formatter(LogFormatter())
    ax.xaxis.set_minor_formatter(LogFormatter(labelOnlyBase=False, minor_thresholds=(1, 0.6)))
    ax.tick_params(which="both", labelsize=TEXT)
    ax.set_xlabel("CPU s per seed (median, 95 % CI)")
    ax.set_ylabel("steps-to-goal (mean, 95 % CI)")
    ax.set_title(f"{p['env'].iloc[0]} (lower left is better)")


def plot_pareto(points: pd.DataFrame, out: Path, names: RowNames | None = None, margin: float = MARGIN) -> list[Path]:
    """``pareto.png`` and ``pareto.pdf`` of ``points`` (:func:`pareto_points`), rows in the styles of ``names`` (by
    default in the points' order), a line at ``margin`` × the reference's mean steps, the legend outside the panels
    (:func:`analysis.plotting.legend_outside`)."""
    if names is None:
        short = {(str(e), str(r)): str(n) for e, r, n in zip(points["env"], points["row"], points["label"], strict=True)}
        order = list(dict.fromkeys(points["label"].astype(str)))
        names = RowNames(short, order, styles(order))
    envs = sorted(points["env"].astype(str).unique())
    fig, axes = panels(len(envs))
    fig.set_figheight(fig.get_figheight() + 0.3)
    for ax, env in zip(axes, envs, strict=True):
        _panel(ax, points[points["env"] == env], f"{env}: " if len(envs) > 1 else "", names, margin)
    handles: dict[str, object] = {}
    for ax in axes:
        for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, h)
    points_first = sorted(handles, key=lambda label: not isinstance(handles[label], ErrorbarContainer))  # stable
    legend_outside(fig, axes, {label: handles[label] for label in points_first})
    return save(fig, out, "pareto")


def write_pareto(runs: pd.DataFrame, out: Path, reference: str, labels: Sequence[str] = (),
                 margin: float = MARGIN) -> list[Path]:  # fmt: skip
    """``pareto.{png,pdf,csv}`` into ``out`` for labelled runs (``analysis.rows``), their rows named by ``labels``
    (``SHORT=GLOB``), the margin line at ``margin``; returns the files written, none when no run records
    ``cpu_seconds``."""
    runs = with_extras(runs)
    if not has_cost(runs):
        return []
    names = row_names(runs, labels)
    points = pareto_points(runs, reference, names.short)
    paths = plot_pareto(points, out, names, margin)
    points.to_csv(out / "pareto.csv", index=False, float_format="%.6g", lineterminator="\n")
    return [*paths, out / "pareto.csv"]


def pareto_from_dirs(root: Path, out: Path, reference: str, labels: Sequence[str] = (), group_by: Sequence[str] = (),
                     pools: Sequence[str] = ()) -> list[Path]:  # fmt: skip
    """:func:`write_pareto` for the finished runs below ``root`` (the margin from its ``analysis.yaml``, default 1.10);
    ValueError when none records ``cpu_seconds``."""
    runs = load_runs(root)
    if runs.empty:
        raise FileNotFoundError(f"no finished run (with summary.json) below {root}")
    runs = pool_rows(label_rows(runs, group_by), pools)
    if not has_cost(with_extras(runs)):
        raise ValueError(f"no finished run below {root} records cpu_seconds (summary.json): no cost to plot")
    out.mkdir(parents=True, exist_ok=True)
    return write_pareto(runs, out, reference, labels, margin_setting(root) or MARGIN)


def main() -> None:
    p = parser(__doc__.splitlines()[0])
    p.add_argument("--reference", default=None, help=f"glob over row labels: the reference row (default {DEFAULT_REFERENCE})")
    label_option(p)

    def command(o: Options) -> str:
        paths = pareto_from_dirs(o.root, o.out, o.args.reference or DEFAULT_REFERENCE, o.args.labels or (), o.group_by,
                                 o.pools)  # fmt: skip
        return f"{len(paths)} file(s) written to {o.out}"

    run(p, command)


if __name__ == "__main__":
    main()
