"""One Markdown report of a results directory: the steps-to-goal table and every figure, embedded.

``python -m analysis.report RUNS_DIR [--out DIR] [--reference GLOB] [--group-by KEYS] [--pool LABEL=GLOB ...]`` writes
the tables (``analysis.tables``) and figures (``analysis.figures``) to DIR (default ``RUNS_DIR/report``) and
``DIR/README.md``, which embeds them with links relative to DIR (GitHub shows it when DIR is browsed).
"""

from __future__ import annotations

import shlex

from analysis.cli import Options, parser, run
from analysis.figures import FIGURES, write_figures
from analysis.tables import DEFAULT_REFERENCE, write_tables

CAPTIONS = {
    "steps_to_goal": "Steps-to-goal: every seed a point, censored seeds as red crosses at their cap, median | and IQM ◆.",
    "reached_fraction": "Fraction of seeds that reached the goal by each env step (the speed of exploration).",
    "coverage": "Coverage of the true state grid, mean over seeds and 95 % bootstrap band (a finished run's last value "
                "carried on).",
    "entropy": "Figure 6 analogue: each entropy regulariser's loss against training iterations, and the common "
               "yardstick `info/latent_logdet` (log det of the next latents' covariance + 1e-3 I) of every run.",
    "intrinsic": "Figure 7 analogue: intrinsic reward (symlog scale), mean and band; dashed: a row's median stable step.",
    "behaviour": "Behaviour: the rate of directed actions and of repeated actions, where runs log them.",
    "tv_presses": "Noisy TV: the fraction of the agent's steps so far that pressed the TV's remote (a run's final "
                  "rate, the table's, carried on after it ended), mean and band; dotted: a random policy.",
}  # fmt: skip


def _command(o: Options) -> str:
    args = [str(o.root)]
    args += [f"--group-by {','.join(o.group_by)}"] if o.group_by else []
    args += [f"--pool {shlex.quote(p)}" for p in o.pools]
    args += [f"--reference {shlex.quote(o.args.reference)}"] if o.args.reference not in (None, DEFAULT_REFERENCE) else []
    return "python -m analysis.report " + " ".join(args)


def write_report(o: Options) -> str:
    """Write the tables, the figures and ``README.md`` embedding them; returns the one-line result."""
    write_tables(o.root, o.out, o.args.reference or DEFAULT_REFERENCE, o.group_by, o.pools)
    written = {path.stem for path in write_figures(o.root, o.out, o.group_by, o.pools)}
    parts = [f"# Report: `{o.root}`", "",
             f"Written by `{_command(o)}` from the run directories' `summary.json`, `.hydra/config.yaml` and "
             "`metrics.csv`; re-running it rewrites these files byte for byte. Tables also as "
             "[LaTeX](steps_to_goal.tex) and [CSV](steps_to_goal.csv); runs not finished in "
             "[incomplete.csv](incomplete.csv).", "",
             "## Steps to goal", "", (o.out / "steps_to_goal.md").read_text().rstrip(), "",
             "## Stable intrinsic reward", "", (o.out / "stability.md").read_text().rstrip(), ""]  # fmt: skip
    for name in ("spread", "stable_step", "distractor"):  # Figures 6 / 7 and the noisy TV, where runs log their columns
        if (o.out / f"{name}.md").is_file():
            parts += ["#" + (o.out / f"{name}.md").read_text().rstrip(), ""]
    parts += ["## Figures", ""]
    for name in (n for n in FIGURES if n in written):  # the TV figure only where runs have a TV
        parts += [f"![{name}]({name}.png)", "", f"{CAPTIONS[name]} ([PDF]({name}.pdf))", ""]
    (o.out / "README.md").write_text("\n".join(parts))
    return f"report written to {o.out}/README.md"


def main() -> None:
    p = parser(__doc__.splitlines()[0])
    p.add_argument("--reference", default=None,
                   help=f"glob over row labels: the Welch test's reference row (default {DEFAULT_REFERENCE})")  # fmt: skip
    run(p, write_report)


if __name__ == "__main__":
    main()
