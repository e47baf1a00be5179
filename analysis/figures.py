"""The paper's figures and the exploration pictures, from run directories, as PNG and PDF.

``python -m analysis.figures RUNS_DIR [--out DIR] [--group-by KEYS] [--pool LABEL=GLOB ...]`` writes to DIR (default
``RUNS_DIR/report``), one panel per env, rows defined as in ``analysis.tables``:

- ``steps_to_goal``: every seed a point, censored runs as red crosses at their cap, median (|) and IQM (◆) marked;
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

from analysis.cli import Options, parser, run
from analysis.collect import load_metrics
from analysis.curves import STABLE_CV, STABLE_WINDOW, mean_band, per_run, running_rate, stable_step, training_iterations
from analysis.plotting import colours, legend_below, note, panels, save
from analysis.rows import label_rows, load_runs, pool_rows
from analysis.stats import iqm


def _envs(runs: pd.DataFrame) -> list[str]:
    return sorted(runs["env"].unique())


def plot_steps_to_goal(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path) -> list[Path]:
    """Steps-to-goal per row: seeds as points (censored: red × at the cap), median and IQM marked."""
    envs = _envs(runs)
    fig, axes = panels(len(envs), height=1.2 + 0.45 * runs.groupby("env")["row"].nunique().max())
    for ax, env in zip(axes, envs, strict=True):
        rows = sorted(runs.loc[runs["env"] == env, "row"].unique())
        for i, row in enumerate(rows):
            g = runs[(runs["env"] == env) & (runs["row"] == row)].sort_values(["seed"])
            jitter = np.linspace(-0.15, 0.15, len(g)) if len(g) > 1 else np.zeros(1)
            ok = ~g["censored"].to_numpy()
            ax.scatter(g["steps"][ok], i + jitter[ok], s=14, color="C0", label="seed reached the goal")
            ax.scatter(g["steps"][~ok], i + jitter[~ok], s=22, marker="x", color="C3", label="seed censored at its cap")
            ax.scatter([g["steps"].median()], [i], s=120, marker="|", color="k", label="median")
            ax.scatter([float(iqm(g["steps"].to_numpy()))], [i], s=30, marker="D", facecolor="none", color="k", label="IQM")
        ax.set_yticks(range(len(rows)), [r.replace(" [", "\n[") for r in rows], fontsize=6)
        ax.set_xlabel("env steps to goal (lower is better)")
        ax.set_title(env)
        ax.set_ylim(-0.6, len(rows) - 0.4)
    legend_below(fig, axes)
    return save(fig, out, "steps_to_goal")


def plot_reached_fraction(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path) -> list[Path]:
    """Fraction of a row's seeds that reached the goal by each env step (censored seeds never do)."""
    envs, colour = _envs(runs), colours(runs["row"])
    fig, axes = panels(len(envs))
    for ax, env in zip(axes, envs, strict=True):
        e = runs[runs["env"] == env]
        cap = int(e["cap"].max())
        for row, g in e.groupby("row", sort=True):
            reached = np.sort(g.loc[~g["censored"], "steps"].to_numpy())
            x = np.concatenate([[0], reached, [cap]])
            y = np.concatenate([[0], np.arange(1, reached.size + 1), [reached.size]]) / len(g)
            ax.step(x, y, where="post", color=colour[row], label=f"{row} (n={len(g)})")
        ax.set(xlabel="env steps", ylabel="fraction of seeds at the goal", ylim=(-0.02, 1.02), title=env)
    legend_below(fig, axes)
    return save(fig, out, "reached_fraction")


def _band(ax: Axes, wide: pd.DataFrame, colour: tuple[float, ...], label: str) -> None:
    """The mean of ``wide``'s runs as a line and its bootstrap band (nothing for a column no run logs)."""
    if wide.empty:
        return
    curve = mean_band(wide)
    ax.plot(curve.x, curve.mean, color=colour, lw=1, label=label)
    ax.fill_between(curve.x, curve.low, curve.high, color=colour, alpha=0.2, lw=0)


def _curve_panels(runs: pd.DataFrame, metrics: pd.DataFrame, column: str, ylabel: str, name: str,
                  fill_forward: bool = False) -> tuple[object, list[Axes]]:  # fmt: skip
    envs, colour = _envs(runs), colours(runs["row"])
    fig, axes = panels(len(envs))
    for ax, env in zip(axes, envs, strict=True):
        e = metrics[metrics["env"] == env]
        shown = False
        for row, g in e.groupby("row", sort=True):
            wide = per_run(g, column, fill_forward=fill_forward)
            if not wide.empty:
                _band(ax, wide, colour[row], f"{row} (n={wide.shape[1]})")
                shown = True
        if shown:
            ax.set(xlabel="env steps", ylabel=ylabel, title=env)
        else:
            note(ax, f"{env}: no run logs {column}")
    return fig, axes


def plot_coverage(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path) -> list[Path]:
    """Coverage of the true state grid against env steps: mean over seeds and 95 % bootstrap band."""
    fig, axes = _curve_panels(runs, metrics, "charts/coverage", "coverage of the state grid", "coverage", True)
    legend_below(fig, axes)
    return save(fig, out, "coverage")


def plot_entropy(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path) -> list[Path]:
    """Figure 6 analogue: each regulariser's loss against training iterations (its own panel: the scales differ) and
    the yardstick ``info/latent_logdet`` of every run in one panel."""
    m = metrics.assign(entropy=[str(c.get("entropy.name", "none")) for c in metrics["config"]])
    m = m[m["entropy"] != "none"] if "losses/entropy" in m else m.iloc[:0]
    m = m.assign(iterations=pd.concat([training_iterations(g) for _, g in m.groupby("run_dir")]) if len(m) else [])
    entropies = sorted(m["entropy"].unique()) if len(m) else []
    colour = colours(runs["row"])
    fig, axes = panels(len(entropies) + 1)
    for ax, entropy in zip(axes, entropies, strict=False):
        for (env, row), g in m[m["entropy"] == entropy].groupby(["env", "row"], sort=True):
            _band(ax, per_run(g, "losses/entropy", x="iterations"), colour[row], f"{env}: {row}")
        ax.set(xlabel="training iterations", ylabel="losses/entropy", title=f"entropy={entropy}")
    ax = axes[-1]
    logged = metrics.dropna(subset=["info/latent_logdet"]) if "info/latent_logdet" in metrics else metrics.iloc[:0]
    for (env, row), g in logged.groupby(["env", "row"], sort=True):
        _band(ax, per_run(g, "info/latent_logdet"), colour[row], f"{env}: {row}")
    if logged.empty:
        note(ax, "info/latent_logdet (log det of the next latents' covariance)\nis not logged by these runs")
    else:
        ax.set(xlabel="env steps", ylabel="info/latent_logdet", title="yardstick: log det Cov(z') + 1e-3 I")
    if not entropies:
        note(axes[0], "no run has an entropy regulariser with losses/entropy") if len(axes) > 1 else None
    legend_below(fig, axes)
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


def plot_intrinsic(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path) -> list[Path]:
    """Figure 7 analogue: the intrinsic reward against env steps, each row's median stable step dashed; also writes
    ``stability.{md,csv}``."""
    table = stability(runs, metrics)
    fig, axes = _curve_panels(runs, metrics, "intrinsic/reward", "intrinsic/reward (symlog scale)", "intrinsic")
    colour = colours(runs["row"])
    for ax, env in zip(axes, _envs(runs), strict=True):
        ax.set_yscale("symlog")  # early rewards of a fresh memory are orders of magnitude above the later ones
        for row, g in table[table["env"] == env].groupby("row", sort=True):
            if g["stable_step"].notna().any():
                ax.axvline(float(g["stable_step"].median()), color=colour[row], ls="--", lw=0.8)
    legend_below(fig, axes)
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


def plot_behaviour(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path) -> list[Path]:
    """``behaviour/directed`` and ``behaviour/repeat`` against env steps, all envs in each panel."""
    colour = colours(runs["row"])
    fig, axes = panels(2)
    for ax, column in zip(axes, ("behaviour/directed", "behaviour/repeat"), strict=True):
        logged = metrics.dropna(subset=[column]) if column in metrics else metrics.iloc[:0]
        for (env, row), g in logged.groupby(["env", "row"], sort=True):
            _band(ax, per_run(g, column), colour[row], f"{env}: {row}")
        if logged.empty:
            note(ax, f"no run logs {column}\n(runs log it since the behaviour columns were added)")
        else:
            ax.set(xlabel="env steps", ylabel=column, title=column.split("/")[1] + " rate")
    legend_below(fig, axes)
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


def plot_tv_presses(runs: pd.DataFrame, metrics: pd.DataFrame, out: Path) -> list[Path]:
    """The running TV-press rate against env steps per row (``tv_press_curves``), one panel per env; nothing when no
    run has a TV remote."""
    if "behaviour/tv" not in metrics or metrics["behaviour/tv"].isna().all():
        return []
    tv_runs = metrics.loc[metrics["behaviour/tv"].notna(), "run_dir"].unique()
    logged = metrics[metrics["run_dir"].isin(tv_runs)]
    envs, colour = sorted(logged["env"].unique()), colours(logged["row"])
    fig, axes = panels(len(envs))
    for ax, env in zip(axes, envs, strict=True):
        e = logged[logged["env"] == env]
        for row, g in e.groupby("row", sort=True):
            wide = tv_press_curves(g)
            _band(ax, wide, colour[row], f"{row} (n={wide.shape[1]})")
        n_actions = int(e["config"].iloc[0].get("env.n_actions", 4))
        ax.axhline(1 / n_actions, color="0.4", ls=":", lw=1, label=f"random policy (1/{n_actions})")
        ax.set(xlabel="env steps", ylabel="TV presses so far (fraction of the agent's steps)", title=env)
        ax.set_ylim(bottom=0)
    legend_below(fig, axes)
    return save(fig, out, "tv_presses")


FIGURES: dict[str, Callable[[pd.DataFrame, pd.DataFrame, Path], list[Path]]] = {
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


def write_figures(root: Path, out: Path, group_by: Sequence[str] = (), pools: Sequence[str] = ()) -> list[Path]:
    """Every figure of ``FIGURES`` for the runs below ``root``, into ``out``; returns the files written."""
    runs, metrics = load(root, list(group_by), list(pools))
    out.mkdir(parents=True, exist_ok=True)
    return [path for plot in FIGURES.values() for path in plot(runs, metrics, out)]


def main() -> None:
    def command(o: Options) -> str:
        return f"{len(write_figures(o.root, o.out, o.group_by, o.pools))} file(s) written to {o.out}"

    run(parser(__doc__.splitlines()[0]), command)


if __name__ == "__main__":
    main()
