"""One Markdown report of a results directory: the steps-to-goal table and every figure, embedded.

``python -m analysis.report RUNS_DIR [--out DIR] [--reference GLOB] [--group-by KEYS] [--pool LABEL=GLOB ...]
[--label SHORT=GLOB ...]`` writes the tables (``analysis.tables``) and figures (``analysis.figures``; where runs record
``cpu_seconds``, the cost table and Pareto figure too, ``analysis.cost``) to DIR (default ``RUNS_DIR/report``) and
``DIR/README.md``, which embeds them with links relative to DIR (GitHub shows it when DIR is browsed). The figures name
rows by their short names (``--label`` or ``analysis.yaml``'s ``labels``), which the README lists beside the row labels
of the tables.
"""

from __future__ import annotations

import shlex

from analysis.cli import Options, label_option, parser, run
from analysis.figures import FIGURES, write_figures
from analysis.plotting import row_names
from analysis.rows import label_rows, load_runs, pool_rows
from analysis.settings import DEFAULT_REFERENCE, settings
from analysis.tables import write_tables

CAPTIONS = {
    "steps_to_goal": "Steps-to-goal: every seed a dot in its row's colour, censored seeds as crosses at their cap, "
                     "median | and IQM ◆.",
    "reached_fraction": "Fraction of seeds that reached the goal by each env step (the speed of exploration).",
    "coverage": "Coverage of the true state grid, mean over seeds and 95 % bootstrap band (a finished run's last value "
                "carried on).",
    "entropy": "Figure 6 analogue: each entropy regulariser's loss against training iterations, and the common "
               "yardstick `info/latent_logdet` (log det of the next latents' covariance + 1e-3 I) of every run.",
    "intrinsic": "Figure 7 analogue: intrinsic reward (symlog scale), mean and band; dashed: a row's median stable step.",
    "behaviour": "Behaviour: the rate of directed actions and of repeated actions, where runs log them.",
    "tv_presses": "Noisy TV: the fraction of the agent's steps so far that pressed the TV's remote (a run's final "
                  "rate, the table's, carried on after it ended), mean and band; dotted: a random policy.",
    "pareto": "Cost against sample efficiency: each row's median CPU seconds per seed and mean steps-to-goal, with 95 % "
              "bootstrap CIs over seeds; the reference a star, dotted 1.10 × its mean, dashed 1/5 of its CPU.",
}  # fmt: skip


def _from_file(o: Options) -> bool:
    """Whether the short names are ``analysis.yaml``'s (the bare command applies them: not repeated as options)."""
    return bool(o.args.labels) and list(o.args.labels) == [str(v) for v in settings(o.root).get("labels") or ()]


def _command(o: Options) -> str:
    args = [str(o.root)]
    args += [f"--group-by {','.join(o.group_by)}"] if o.group_by else []
    args += [f"--pool {shlex.quote(p)}" for p in o.pools]
    args += [f"--reference {shlex.quote(o.args.reference)}"] if o.args.reference not in (None, DEFAULT_REFERENCE) else []
    args += [] if _from_file(o) else [f"--label {shlex.quote(label)}" for label in o.args.labels or ()]
    return "python -m analysis.report " + " ".join(args)


def _names_list(o: Options) -> list[str]:
    """The figures' short names beside the row labels they stand for (none where every row keeps its label)."""
    runs = pool_rows(label_rows(load_runs(o.root), o.group_by), o.pools)
    names = row_names(runs, o.args.labels or ())
    named = sorted(((names.rank(e, r), e, r, n) for (e, r), n in names.short.items() if n != r))
    if not named:
        return []
    source = "`analysis.yaml`'s `labels`" if _from_file(o) else "`--label`" if o.args.labels else "automatic"
    several = len({e for _, e, _, _ in named}) > 1
    return [f"Rows in the figures by their short names ({source}):", "",
            *(f"- {f'{e} ' if several else ''}{n}: `{r}`" for _, e, r, n in named), ""]


def write_report(o: Options) -> str:
    """Write the tables, the figures and ``README.md`` embedding them; returns the one-line result."""
    write_tables(o.root, o.out, o.args.reference or DEFAULT_REFERENCE, o.group_by, o.pools, o.args.labels or ())
    written = {path.stem for path in write_figures(o.root, o.out, o.group_by, o.pools, o.args.labels or ())}
    written |= {"pareto"} if (o.out / "pareto.png").is_file() else set()  # the tables' cost step, where runs record CPU
    parts = [f"# Report: `{o.root}`", "",
             f"Written by `{_command(o)}` from the run directories' `summary.json`, `.hydra/config.yaml` and "
             "`metrics.csv`; re-running it rewrites these files byte for byte. Tables also as "
             "[LaTeX](steps_to_goal.tex) and [CSV](steps_to_goal.csv); runs not finished in "
             "[incomplete.csv](incomplete.csv).", "",
             "## Steps to goal", "", (o.out / "steps_to_goal.md").read_text().rstrip(), "",
             "## Stable intrinsic reward", "", (o.out / "stability.md").read_text().rstrip(), ""]  # fmt: skip
    for name in ("spread", "stable_step", "distractor", "cost"):  # Figures 6 / 7, the noisy TV, CPU: where runs log them
        if (o.out / f"{name}.md").is_file():
            parts += ["#" + (o.out / f"{name}.md").read_text().rstrip(), ""]
    parts += ["## Figures", "", *_names_list(o)]
    for name in (n for n in [*FIGURES, "pareto"] if n in written):  # the TV figure only where runs have a TV
        parts += [f"![{name}]({name}.png)", "", f"{CAPTIONS[name]} ([PDF]({name}.pdf))", ""]
    (o.out / "README.md").write_text("\n".join(parts))
    return f"report written to {o.out}/README.md"


def main() -> None:
    p = parser(__doc__.splitlines()[0])
    p.add_argument("--reference", default=None,
                   help=f"glob over row labels: the Welch test's reference row (default {DEFAULT_REFERENCE})")  # fmt: skip
    label_option(p)
    run(p, write_report)


if __name__ == "__main__":
    main()
