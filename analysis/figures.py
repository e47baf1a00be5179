"""The paper's figures and the exploration pictures, from run directories, as PNG and PDF.

``python -m analysis.figures RUNS_DIR [--out DIR] [--group-by KEYS] [--pool LABEL=GLOB ...] [--label SHORT=GLOB ...]``
writes to DIR (default ``RUNS_DIR/report``), one panel per env, rows defined as in ``analysis.tables`` and shown by their
short names (``--label`` or ``analysis.yaml``'s ``labels``; :func:`analysis.plotting.row_names`), each row in its own
colour and marker, in the order the labels list them, sized for a paper (:mod:`analysis.plotting`):

- ``steps_to_goal``: every seed a dot in its row's colour, censored runs as crosses at their cap, median (|) and IQM (◆)
  marked;
- ``reached_fraction``: the fraction of seeds that reached the goal by each env step (an empirical CDF per row);
- ``coverage``: ``charts/coverage`` against env steps, mean and 95 % bootstrap band (a run's last value carried on
  after it ended);
- ``entropy`` (Figure 6 analogue): ``losses/entropy`` against training iterations, one panel per regulariser, and
  the common yardstick ``info/latent_logdet`` of every run on one scale;
- ``intrinsic`` (Figure 7 analogue): ``intrinsic/reward`` against env steps, mean and band, with each row's median
  "stable" step (``analysis.curves``) dashed; ``stability.{md,csv}`` list the stable step of every seed;
- ``behaviour``: ``behaviour/directed`` and ``behaviour/repeat`` against env steps, where runs log them;
- ``tv_presses`` (only where some run has a noisy TV's remote, ``env.distractor=noisy_tv``): the fraction of the
  agent's steps so far that pressed the TV (``analysis.curves.running_rate`` of ``behaviour/tv``; a run's final
  rate, the table's, carried on after it ended), mean and band, against env steps, with a random policy's rate dotted.

A panel whose runs do not log its column says so instead of being left out.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from analysis.cli import Options, label_option, parser, run
from analysis.collect import load_metrics
from analysis.curves import STABLE_CV, STABLE_WINDOW, mean_band, per_run, running_rate, stable_step, training_iterations
from analysis.plotting import DOUBLE, LINESTYLES, SINGLE, RowNames, legend_outside, marks, note, panels, row_names, save
from analysis.rows import label_rows, load_runs, pool_rows
from analysis.stats import iqm

ENTROPIES = {"gaussian_potential": "Gaussian potential", "renyi": "Rényi", "renyi_mi": "Rényi MI"}  # panel titles


def _envs(runs: pd.DataFrame) -> list[str]:
    return sorted(runs["env"].unique())


def _names(runs: pd.DataFrame, names: RowNames | None) -> RowNames:
    return names if names is not None else row_names(runs)


def _groups(frame: pd.DataFrame, keys: list[str], names: RowNames) -> list[tuple[tuple[str, ...], pd.DataFrame]]:
    """``frame`` grouped by ``keys`` (ending with ``row``), in the legends' order of the rows."""
    groups = [(k if isinstance(k, tuple) else (k,), g) for k, g in frame.groupby(keys, sort=True)]
    env_of = (lambda k, g: k[0]) if keys[0] == "env" else (lambda k, g: g["env"].iloc[0])
    return sorted(groups, key=lambda kg: (names.rank(env_of(*kg), kg[0][-1]), kg[0]))


def _label(names: RowNames, env: str, row: str, several_envs: bool) -> str:
    """A row's short name, after its env where a panel draws several envs."""
    return f"{env}: {names(env, row)}" if several_envs else names(env, row)


def _fit_row_labels(fig: Figure, axes: Sequence[Axes], data_height: float) -> None:
    """Widen a figure whose panels name their rows on the y axis so that each panel's data area stays wider than tall
    beside the longest name: one column (``SINGLE``) where that fits, up to two (``DOUBLE``)."""
    renderer = fig.canvas.get_renderer()
    labels = max((t.get_window_extent(renderer).width for ax in axes for t in ax.get_yticklabels()), default=0.0)
    need = len(axes) * (labels / fig.dpi + 0.35 + max(2.0, 1.1 * data_height)) + 0.1
    fig.set_figwidth(min(DOUBLE, max(SINGLE, need)))


def plot_steps_to_goal(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path, names: RowNames | None = None) -> list[Path]:
    """Steps-to-goal per row (named by its short name, top to bottom in the legends' order): seeds as dots in the
    row's colour (censored: a cross at the cap), median and IQM marked."""
    names = _names(runs, names)
    envs = _envs(runs)
    fig, axes = panels(len(envs))
    n_rows = int(runs.groupby("env")["row"].nunique().max())
    fig.set_figheight(max(1.8, 0.8 + 0.22 * n_rows))
    for ax, env in zip(axes, envs, strict=True):
        e = runs[runs["env"] == env]
        rows = [k[-1] for k, _ in _groups(e, ["row"], names)]
        for i, row in enumerate(rows):
            g = e[e["row"] == row].sort_values(["seed"])
            style = names.style[names(env, row)]
            jitter = np.linspace(-0.2, 0.2, len(g)) if len(g) > 1 else np.zeros(1)
            ok = ~g["censored"].to_numpy()
            ax.scatter(g["steps"][ok], i + jitter[ok], s=10, color=style.colour, alpha=0.85, lw=0)
            ax.scatter(g["steps"][~ok], i + jitter[~ok], s=16, marker="x", color=style.colour, lw=1)
            ax.scatter([g["steps"].median()], [i], s=110, marker="|", color="k", lw=1.5, zorder=3)
            ax.scatter([float(iqm(g["steps"].to_numpy()))], [i], s=28, marker="D", facecolor="none", color="k", zorder=3)
        ax.set_yticks(range(len(rows)), [names(env, r) for r in rows])
        ax.set_xlabel("env steps to goal (lower is better)")
        ax.set_title(env)
        ax.set_ylim(len(rows) - 0.5, -0.5)  # the first row on top
    _fit_row_labels(fig, axes, 0.22 * n_rows)
    key = {"seed that reached the goal": Line2D([], [], ls="", marker="o", ms=3.5, color="0.35"),
           "seed censored at its cap": Line2D([], [], ls="", marker="x", ms=4, color="0.35"),
           "median": Line2D([], [], ls="", marker="|", ms=9, mew=1.5, color="k"),
           "IQM": Line2D([], [], ls="", marker="D", ms=5, mfc="none", color="k")}  # fmt: skip
    if not runs["censored"].any():  # a key only for what is drawn
        del key["seed censored at its cap"]
    legend_outside(fig, axes, key)
    return save(fig, out, "steps_to_goal")


def plot_reached_fraction(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path, names: RowNames | None = None) -> list[Path]:
    """Fraction of a row's seeds that reached the goal by each env step (censored seeds never do)."""
    names = _names(runs, names)
    envs = _envs(runs)
    fig, axes = panels(len(envs))
    for ax, env in zip(axes, envs, strict=True):
        e = runs[runs["env"] == env]
        cap = int(e["cap"].max())
        for (row,), g in _groups(e, ["row"], names):
            reached = np.sort(g.loc[~g["censored"], "steps"].to_numpy())
            x = np.concatenate([[0], reached, [cap]])
            y = np.concatenate([[0], np.arange(1, reached.size + 1), [reached.size]]) / len(g)
            name = names(env, row)
            ax.step(x, y, where="post", color=names.style[name].colour, marker=names.style[name].marker,
                    label=name, **marks(names.order.index(name), x.size))  # fmt: skip
        ax.set(xlabel="env steps", ylabel="fraction of seeds at the goal", ylim=(-0.02, 1.02), title=env)
    _legend(fig, axes, names)
    return save(fig, out, "reached_fraction")


def _band(ax: Axes, wide: pd.DataFrame, names: RowNames, name: str, label: str, ls: str = "-") -> None:
    """The mean of ``wide``'s runs as a line in the style of ``name`` and its bootstrap band (nothing for a column no
    run logs)."""
    if wide.empty:
        return
    curve = mean_band(wide)
    style = names.style[name] if name in names.style else names.style[names.order[0]]
    ax.plot(curve.x, curve.mean, color=style.colour, marker=style.marker, ls=ls, label=label,
            **marks(names.order.index(name) if name in names.order else 0, len(curve.x)))  # fmt: skip
    ax.fill_between(curve.x, curve.low, curve.high, color=style.colour, alpha=0.18, lw=0)


def _curve_panels(runs: pd.DataFrame, metrics: pd.DataFrame, column: str, ylabel: str, names: RowNames,
                  fill_forward: bool = False) -> tuple[object, list[Axes]]:  # fmt: skip
    envs = _envs(runs)
    fig, axes = panels(len(envs))
    for ax, env in zip(axes, envs, strict=True):
        e = metrics[metrics["env"] == env]
        shown = False
        for (row,), g in _groups(e, ["row"], names):
            wide = per_run(g, column, fill_forward=fill_forward)
            if not wide.empty:
                _band(ax, wide, names, names(env, row), names(env, row))
                shown = True
        if shown:
            ax.set(xlabel="env steps", ylabel=ylabel, title=env)
        else:
            note(ax, f"{env}: no run logs {column}")
    return fig, axes


def plot_coverage(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path, names: RowNames | None = None) -> list[Path]:
    """Coverage of the true state grid against env steps: mean over seeds and 95 % bootstrap band."""
    names = _names(runs, names)
    fig, axes = _curve_panels(runs, metrics, "charts/coverage", "coverage of the state grid", names, True)
    _legend(fig, axes, names)
    return save(fig, out, "coverage")


def _legend(fig: Figure, axes: Sequence[Axes], names: RowNames, extra: dict[str, object] | None = None) -> None:
    """The figure's legend outside its panels: every row drawn once, in the names' order (``env: name`` where a panel
    draws several envs), then ``extra``."""
    handles: dict[str, object] = {}
    for ax in axes:
        for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, h)

    def rank(label: str) -> tuple[int, str]:
        name = label if label in names.order else label.partition(": ")[2]
        return (names.order.index(name) if name in names.order else len(names.order), label)

    ordered = {label: handles[label] for label in sorted(handles, key=rank)}
    legend_outside(fig, axes, {**ordered, **(extra or {})})


def _several_envs(frame: pd.DataFrame) -> tuple[bool, dict[str, str]]:
    """Whether ``frame`` holds several envs, and a line style per env."""
    envs = sorted(frame["env"].unique()) if len(frame) else []
    return len(envs) > 1, {env: LINESTYLES[i % len(LINESTYLES)] for i, env in enumerate(envs)}


def plot_entropy(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path, names: RowNames | None = None) -> list[Path]:
    """Figure 6 analogue: each regulariser's loss against training iterations (its own panel: the scales differ) and
    the yardstick ``info/latent_logdet`` of every run in one panel."""
    names = _names(runs, names)
    m = metrics.assign(entropy=[str(c.get("entropy.name", "none")) for c in metrics["config"]])
    m = m[m["entropy"] != "none"] if "losses/entropy" in m else m.iloc[:0]
    m = m.assign(iterations=pd.concat([training_iterations(g) for _, g in m.groupby("run_dir")]) if len(m) else [])
    entropies = sorted(m["entropy"].unique()) if len(m) else []
    several, ls = _several_envs(metrics)
    fig, axes = panels(len(entropies) + 1)
    for ax, entropy in zip(axes, entropies, strict=False):
        for (env, row), g in _groups(m[m["entropy"] == entropy], ["env", "row"], names):
            _band(ax, per_run(g, "losses/entropy", x="iterations"), names, names(env, row),
                  _label(names, env, row, several), ls[env])  # fmt: skip
        ax.set(xlabel="training iterations", ylabel="losses/entropy", title=f"loss: {ENTROPIES.get(entropy, entropy)}")
    ax = axes[-1]
    logged = metrics.dropna(subset=["info/latent_logdet"]) if "info/latent_logdet" in metrics else metrics.iloc[:0]
    for (env, row), g in _groups(logged, ["env", "row"], names):
        _band(ax, per_run(g, "info/latent_logdet"), names, names(env, row), _label(names, env, row, several), ls[env])
    if logged.empty:
        note(ax, "info/latent_logdet (log det of the next latents' covariance)\nis not logged by these runs")
    else:
        ax.set(xlabel="env steps", ylabel="info/latent_logdet", title="yardstick: log det Cov(z′)")
    if not entropies:
        note(axes[0], "no run has an entropy regulariser with losses/entropy") if len(axes) > 1 else None
    _legend(fig, axes, names)
    return save(fig, out, "entropy")


def _estimator(config: dict[str, object]) -> str:
    """The novelty estimator of a paper-agent run (``kde``, ``knn``), or the baseline a run is (``baseline nsrs``)."""
    baseline = str(config.get("baseline.name", "none"))
    return str(config.get("estimator.name", "")) if baseline == "none" else f"baseline {baseline}"


def stability(runs: pd.DataFrame, metrics: pd.DataFrame) -> pd.DataFrame:
    """The stable step (``analysis.curves.stable_step``) of every run that logs ``intrinsic/reward``."""
    rows = []
    for _, g in metrics.groupby("run_dir", sort=True):
        g = g.dropna(subset=["intrinsic/reward"]) if "intrinsic/reward" in g else g.iloc[:0]
        if g.empty:
            continue
        step = stable_step(g["step"].to_numpy(), g["intrinsic/reward"].to_numpy())
        rows.append({"env": g["env"].iloc[0], "row": g["row"].iloc[0], "estimator": _estimator(g["config"].iloc[0]),
                     "seed": int(g["seed"].iloc[0]), "stable_step": step, "last_step": int(g["step"].iloc[-1])})  # fmt: skip
    return pd.DataFrame(rows, columns=["env", "row", "estimator", "seed", "stable_step", "last_step"])


def plot_intrinsic(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path, names: RowNames | None = None) -> list[Path]:
    """Figure 7 analogue: the intrinsic reward against env steps, each row's median stable step dashed; also writes
    ``stability.{md,csv}``."""
    names = _names(runs, names)
    table = stability(runs, metrics)
    fig, axes = _curve_panels(runs, metrics, "intrinsic/reward", "intrinsic reward (symlog scale)", names)
    dashed = False
    for ax, env in zip(axes, _envs(runs), strict=True):
        ax.set_yscale("symlog")  # early rewards of a fresh memory are orders of magnitude above the later ones
        for (row,), g in _groups(table[table["env"] == env], ["row"], names):
            if g["stable_step"].notna().any():
                ax.axvline(float(g["stable_step"].median()), color=names.style[names(env, row)].colour, ls="--", lw=0.8)
                dashed = True
    dash = {"a row's median stable step": Line2D([], [], color="0.35", ls="--", lw=0.8)} if dashed else {}
    _legend(fig, axes, names, dash)
    table.to_csv(out / "stability.csv", index=False, float_format="%.6g", lineterminator="\n")
    summary = table.groupby(["env", "row", "estimator"], sort=True)["stable_step"].agg(
        seeds="size", stable="count", median="median").reset_index()  # fmt: skip
    lines = [f"Stable intrinsic reward: the rolling |SD / mean| over {STABLE_WINDOW} logged rows first below "
             f"{STABLE_CV} (median over the seeds that reach it).", "",
             "| env | method | estimator | seeds stable | median stable step |", "|---|---|---|---|---|"]  # fmt: skip
    lines += [f"| {r.env} | {r.row} | {r.estimator} | {r.stable} / {r.seeds} | "
              f"{'–' if np.isnan(r.median) else int(r.median)} |" for r in summary.itertuples(index=False)]  # fmt: skip
    (out / "stability.md").write_text("\n".join(lines) + "\n")
    return [*save(fig, out, "intrinsic"), out / "stability.md", out / "stability.csv"]


def plot_behaviour(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path, names: RowNames | None = None) -> list[Path]:
    """``behaviour/directed`` and ``behaviour/repeat`` against env steps, all envs in each panel."""
    names = _names(runs, names)
    fig, axes = panels(2)
    for ax, column in zip(axes, ("behaviour/directed", "behaviour/repeat"), strict=True):
        logged = metrics.dropna(subset=[column]) if column in metrics else metrics.iloc[:0]
        several, ls = _several_envs(logged)
        for (env, row), g in _groups(logged, ["env", "row"], names):
            _band(ax, per_run(g, column), names, names(env, row), _label(names, env, row, several), ls[env])
        if logged.empty:
            note(ax, f"no run logs {column}\n(runs log it since the behaviour columns were added)")
        else:
            ax.set(xlabel="env steps", ylabel=column, title=column.split("/")[1] + " rate")
    _legend(fig, axes, names)
    return save(fig, out, "behaviour")


def tv_press_curves(metrics: pd.DataFrame) -> pd.DataFrame:
    """Each TV run's running press rate (``running_rate`` of ``behaviour/tv`` after ``budget.warmup_steps``) as a
    (steps, runs) table, a run's final rate carried on after it ended."""
    curves = []
    for run_dir, g in metrics.groupby("run_dir", sort=True):
        if "behaviour/tv" in g and g["behaviour/tv"].notna().any():
            warmup = int(g["config"].iloc[0].get("budget.warmup_steps", 0))
            curves.append(running_rate(g, "behaviour/tv", warmup).rename(run_dir))
    return pd.concat(curves, axis=1).sort_index().ffill() if curves else pd.DataFrame()


def plot_tv_presses(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path, names: RowNames | None = None) -> list[Path]:
    """The running TV-press rate against env steps per row (``tv_press_curves``), one panel per env; nothing when no
    run has a TV remote."""
    if "behaviour/tv" not in metrics or metrics["behaviour/tv"].isna().all():
        return []
    names = _names(runs, names)
    tv_runs = metrics.loc[metrics["behaviour/tv"].notna(), "run_dir"].unique()
    logged = metrics[metrics["run_dir"].isin(tv_runs)]
    envs = sorted(logged["env"].unique())
    fig, axes = panels(len(envs))
    for ax, env in zip(axes, envs, strict=True):
        e = logged[logged["env"] == env]
        for (row,), g in _groups(e, ["row"], names):
            _band(ax, tv_press_curves(g), names, names(env, row), names(env, row))
        n_actions = int(e["config"].iloc[0].get("env.n_actions", 4))
        ax.axhline(1 / n_actions, color="0.4", ls=":", lw=1, label=f"random policy (1/{n_actions})")
        ax.set(xlabel="env steps", ylabel="TV presses so far (rate)", title=env)
        ax.set_ylim(bottom=0)
    _legend(fig, axes, names)
    return save(fig, out, "tv_presses")


FIGURES: dict[str, Callable[[pd.DataFrame, pd.DataFrame, Path, RowNames | None], list[Path]]] = {
    "steps_to_goal": plot_steps_to_goal, "reached_fraction": plot_reached_fraction, "coverage": plot_coverage,
    "entropy": plot_entropy, "intrinsic": plot_intrinsic, "behaviour": plot_behaviour, "tv_presses": plot_tv_presses,
}  # fmt: skip


def load(root: Path, group_by: Sequence[str], pools: Sequence[str]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The finished runs with their row labels, and their metrics rows joined with env, row and config."""
    runs = load_runs(root)
    if runs.empty:
        raise FileNotFoundError(f"no finished run (with summary.json) below {root}")
    runs = pool_rows(label_rows(runs, group_by), pools)
    metrics = load_metrics(root).merge(runs[["run_dir", "env", "row", "config"]], on="run_dir")
    return runs, metrics


def write_figures(root: Path, out: Path, group_by: Sequence[str] = (), pools: Sequence[str] = (),
                  labels: Sequence[str] = ()) -> list[Path]:  # fmt: skip
    """Every figure of ``FIGURES`` for the runs below ``root``, into ``out``, rows named by ``labels`` (``SHORT=GLOB``,
    :func:`analysis.plotting.row_names`); returns the files written."""
    runs, metrics = load(root, list(group_by), list(pools))
    names = row_names(runs, labels)
    out.mkdir(parents=True, exist_ok=True)
    return [path for plot in FIGURES.values() for path in plot(runs, metrics, out, names)]


def main() -> None:
    def command(o: Options) -> str:
        return f"{len(write_figures(o.root, o.out, o.group_by, o.pools, o.args.labels or ()))} file(s) written to {o.out}"

    p = parser(__doc__.splitlines()[0])
    label_option(p)
    run(p, command)


if __name__ == "__main__":
    main()
