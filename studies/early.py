"""What runs did early, beside how soon they reached the goal: ``python -m studies.early RUNS_DIR [--until N]
[--columns COL,COL] [--out DIR]``.

Per finished run: the mean of each chosen ``metrics.csv`` column over its logged rows up to env step ``--until``
(default 200; the runs stop at the goal, so a run that reached it sooner is averaged over its whole run and marked),
beside its steps-to-goal (a censored run at its last step). Per row of runs (labelled as the tables label them) and
column: Spearman's rank correlation between those means and steps-to-goal over the row's seeds, with its two-sided p
(``scipy.stats.spearmanr``; ties, such as several runs at the cap, get their mean rank). A negative ρ: the runs that did
more of it early reached the goal sooner. It is a correlation over seeds, not a cause: the instrument that says which
behaviour to change one thing at a time for (issue 11's "instrument it first").

A column named with ``--columns`` that no run logs is refused in one line (a typo would otherwise read as a column
never logged); of the default columns, those no run logs are left out (baselines log no model probe).

Writes ``early.md`` (per row and column: ρ, p, the runs it is over; then every run's means) and ``early.csv`` (one line
per run) into ``--out`` (default ``RUNS_DIR/report``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path

import pandas as pd
from scipy.stats import spearmanr

from analysis.claims import fmt
from analysis.cli import Options, parser, run
from analysis.collect import load_metrics
from analysis.rows import label_rows, load_runs, pool_rows

DEFAULT_COLUMNS = ("behaviour/directed", "behaviour/repeat", "probe/spearman", "charts/coverage")
DEFAULT_UNTIL = 200


def early_means(metrics: pd.DataFrame, columns: Sequence[str], until: int) -> dict[str, float]:
    """Mean of each column over one run's ``metrics.csv`` rows with ``step`` ≤ ``until`` (NaN where none has a value),
    and ``last_step``, the run's last logged step."""
    window = metrics[metrics["step"] <= until]
    out = {c: float(window[c].mean()) if c in window and window[c].notna().any() else math.nan for c in columns}
    return out | {"last_step": int(metrics["step"].max()) if len(metrics) else 0}


def early_table(root: str | Path, columns: Sequence[str], until: int, group_by: Sequence[str] = (),
                pools: Sequence[str] = (), strict: bool = True) -> pd.DataFrame:  # fmt: skip
    """One line per finished run below ``root``: env, row, seed, steps (censored at the last step), censored,
    ``whole_run`` (the run ended before ``until``) and the early mean of each column that some run logs. A column no
    run logs is refused (``strict``, a column asked for by name) or left out (the default columns)."""
    runs = load_runs(root)
    if runs.empty:
        raise ValueError(f"{root}: no finished run (a directory holding summary.json) below it")
    runs = pool_rows(label_rows(runs, group_by), pools)
    metrics = load_metrics(root)  # every run's rows, each file read once; a column one run lacks is NaN there
    per_run = dict(tuple(metrics.groupby("run_dir", sort=False)))
    header = set(metrics.columns) - {"method", "seed", "run_dir"}
    unknown = [c for c in columns if c not in header]
    if (strict and unknown) or len(unknown) == len(columns):
        examples = ", ".join(sorted(header - {"step"})[:6])
        raise ValueError(f"--columns {unknown[0]}: no run below {root} logs it; allowed: a column of the runs' "
                         f"metrics.csv ({examples}, …)")  # fmt: skip
    columns = [c for c in columns if c in header]
    lines = []
    for r in runs.itertuples(index=False):
        means = early_means(per_run[r.run_dir], columns, until)
        lines.append({"env": r.env, "row": r.row, "seed": int(r.seed), "steps": float(r.steps), "censored": bool(r.censored),
                      "whole_run": means.pop("last_step") < until, **means, "run_dir": r.run_dir})  # fmt: skip
    return pd.DataFrame(lines).sort_values(["env", "row", "seed"], kind="stable", ignore_index=True)


def correlations(table: pd.DataFrame, columns: Sequence[str]) -> pd.DataFrame:
    """Per (env, row, column): ``n`` (the runs with a value), Spearman's ``rho`` and ``p`` between the early mean and
    steps-to-goal (NaN with fewer than 3 runs or a constant side)."""
    out = []
    for (env, row), g in table.groupby(["env", "row"], sort=False):
        for c in columns:
            have = g[g[c].notna()]
            rho = p = math.nan
            if len(have) >= 3 and have[c].nunique() > 1 and have["steps"].nunique() > 1:
                result = spearmanr(have[c], have["steps"])
                rho, p = float(result.statistic), float(result.pvalue)
            out.append({"env": env, "row": row, "column": c, "n": len(have), "rho": rho, "p": p})
    return pd.DataFrame(out)


def to_markdown(table: pd.DataFrame, corr: pd.DataFrame, columns: Sequence[str], until: int) -> str:
    lines = [f"# Early behaviour and steps-to-goal (the first {until} env steps)", "",
             f"Per run: the mean of each column over its logged rows up to env step {until} (a run marked `*` reached "
             "the goal sooner: its whole run); steps-to-goal with a censored run (`>`) at its last step. Per row: "
             "Spearman's ρ between those means and steps-to-goal over its runs, two-sided p (scipy.stats.spearmanr); "
             "ρ < 0: more of it early, the goal sooner. A correlation over seeds, not a cause.", "",
             "| env | row | column | runs | Spearman ρ | p |", "|---|---|---|---|---|---|"]  # fmt: skip
    for r in corr.itertuples(index=False):
        lines.append(f"| {r.env} | {r.row} | `{r.column}` | {r.n} | {fmt(r.rho, '.2f')} | {fmt(r.p, '.3g')} |")
    lines += ["", "| env | row | seed | steps-to-goal | " + " | ".join(f"`{c}`" for c in columns) + " |",
              "|---|---|---|---|" + "---|" * len(columns)]  # fmt: skip
    for r in table.to_dict("records"):
        steps = f"{'>' if r['censored'] else ''}{int(r['steps'])}{' *' if r['whole_run'] else ''}"
        values = " | ".join(fmt(r[c], ".3f") for c in columns)
        lines.append(f"| {r['env']} | {r['row']} | {r['seed']} | {steps} | {values} |")
    return "\n".join(lines) + "\n"


def write_early(root: Path, out: Path, columns: Sequence[str], until: int, group_by: Sequence[str] = (),
                pools: Sequence[str] = (), strict: bool = True) -> pd.DataFrame:  # fmt: skip
    """``early.{md,csv}`` into ``out``; returns the correlations. Nothing is written when the input is refused."""
    table = early_table(root, columns, until, group_by, pools, strict)
    columns = [c for c in columns if c in table]
    corr = correlations(table, columns)
    out.mkdir(parents=True, exist_ok=True)
    (out / "early.md").write_text(to_markdown(table, corr, columns, until))
    csv = table.assign(run_dir=[os.path.relpath(d, root) for d in table["run_dir"]])  # an included run: ../<preset>/…
    csv.to_csv(out / "early.csv", index=False, float_format="%.6g", lineterminator="\n")
    return corr


def main() -> None:
    p = parser(__doc__.splitlines()[0])
    p.prog = "python -m studies.early"
    p.add_argument("--until", default=str(DEFAULT_UNTIL), help=f"the window's last env step (default {DEFAULT_UNTIL})")
    p.add_argument("--columns", default=None,
                   help=f"comma-separated metrics.csv columns (default {','.join(DEFAULT_COLUMNS)})")  # fmt: skip

    def command(o: Options) -> str:
        until = o.args.until
        if not until.isdigit() or int(until) < 1:
            raise ValueError(f"--until {until}: allowed: a positive integer env step")
        named = o.args.columns is not None  # a named column must be logged; of the defaults, those some run logs
        columns = [c for c in o.args.columns.split(",") if c] if named else list(DEFAULT_COLUMNS)
        if not columns:
            raise ValueError(f"--columns {o.args.columns!r}: allowed: comma-separated metrics.csv columns")
        corr = write_early(o.root, o.out, columns, int(until), o.group_by, o.pools, strict=named)
        return f"{len(corr)} correlation(s) written to {o.out}/early.{{md,csv}}"

    run(p, command)


if __name__ == "__main__":
    main()
