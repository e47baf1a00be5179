"""Steps-to-goal tables (the paper's Tables 1 and 2) from run directories, as Markdown, LaTeX and CSV.

``python -m analysis.tables RUNS_DIR [--out DIR] [--reference GLOB] [--group-by KEYS] [--pool LABEL=GLOB ...]``
writes ``steps_to_goal.{md,tex,csv}`` and ``incomplete.csv`` to DIR (default ``RUNS_DIR/report``). One row per env and
method as its config defines it (``analysis.rows``): seeds, successes, every seed's value (a censored run as ``>cap``),
mean ± SE with censored runs at their last step (the paper's Table 2 rule) and over successes only, median, IQM with
a stratified-bootstrap 95 % CI, Welch's t-test p against the reference row, and the published number beside ours
(``analysis/paper_numbers.yaml``); below it the compute the runs took and the code commits that made them, naming
every row that pools runs of more than one. Runs without ``summary.json`` are listed apart, never dropped silently.
Where runs have a noisy TV, ``distractor.{md,csv}`` set each method with the TV beside itself without
(``analysis.distractor``). Where runs record ``cpu_seconds``, ``cost.{md,csv}`` set each row's CPU per seed beside its
steps-to-goal and its non-inferiority against the reference row, and ``pareto.{png,pdf,csv}`` plot the one against the
other (``analysis.cost``, ``analysis.pareto``; ``--label SHORT=GLOB`` names their rows).
"""

from __future__ import annotations

import fnmatch
import math
import os
from collections.abc import Sequence
from typing import Any
from pathlib import Path

import pandas as pd
import yaml

from analysis import claims
from analysis.cli import Options, label_option, parser, run
from analysis.collect import load_incomplete
from analysis.cost import MARGIN, parse_labels, write_cost
from analysis.distractor import write_distractor_table
from analysis.figures import load
from analysis.pareto import write_pareto
from analysis.rows import label_rows, load_runs, pool_rows
from analysis.settings import DEFAULT_REFERENCE, margin_setting
from analysis.stats import iqm_ci, mean_se, per_seed_text, welch_p

PAPER_NUMBERS = Path(__file__).with_name("paper_numbers.yaml")
NOTE = ("Steps-to-goal, lower is better. mean ± SE: censored runs (goal not reached, shown `>cap`) counted at their "
        "last step (the paper's Table 2 rule); SE = sample SD (ddof = 1)/√n. success mean: the seeds that reached the "
        "goal only. IQM: mean of the middle 50 % (scipy trim_mean 0.25), 95 % percentile-bootstrap CI over seeds "
        "(stratified by pooled variant; 2000 resamples, seed 0). p: Welch's t-test (scipy ttest_ind, equal_var=False) "
        "against the reference row `{reference}` of the same env (rows matching it pooled). paper: the published "
        "mean ± SE (its source in the CSV).")  # fmt: skip


def paper_numbers(path: Path = PAPER_NUMBERS) -> list[dict]:
    """The published rows: env, method, mean, se, seeds, source, rows (a glob, or a list of globs, over our row labels)."""
    return list(yaml.safe_load(path.read_text()))


def _paper(env: str, labels: Sequence[str], numbers: Sequence[dict]) -> dict[str, object]:
    """The published row of ``env`` whose glob matches one of ``labels`` (a row's label and, pooled, its variants')."""

    def matches(p: dict) -> bool:
        globs = p["rows"] if isinstance(p["rows"], list) else [p["rows"]]
        return p["env"] == env and any(fnmatch.fnmatchcase(x, g) for x in labels for g in globs)

    match = next((p for p in numbers if matches(p)), None)
    if match is None:
        return {"paper_method": "", "paper_mean": math.nan, "paper_se": math.nan, "paper_seeds": math.nan, "paper_source": ""}
    return {"paper_method": match["method"], "paper_mean": float(match["mean"]), "paper_se": float(match["se"]),
            "paper_seeds": float(match["seeds"]) if match["seeds"] is not None else math.nan,
            "paper_source": match["source"]}  # fmt: skip


def steps_table(runs: pd.DataFrame, reference: str = DEFAULT_REFERENCE, numbers: Sequence[dict] = ()) -> pd.DataFrame:
    """One row per (env, row) of ``runs`` (from :func:`analysis.rows.label_rows`/``pool_rows``), sorted."""
    out = []
    for (env, row), g in runs.groupby(["env", "row"], sort=True):
        g = g.sort_values(["stratum", "seed"]) if "stratum" in g else g.sort_values("seed")
        ref = runs[(runs["env"] == env) & runs["row"].map(lambda r: fnmatch.fnmatchcase(r, reference))]
        strata = [s["steps"].tolist() for _, s in g.groupby("stratum", sort=True)] if "stratum" in g else [g["steps"].tolist()]
        mean, se = mean_se(g["steps"])
        mean_s, se_s = mean_se(g.loc[~g["censored"], "steps"])
        point, low, high = iqm_ci(strata)
        is_ref = fnmatch.fnmatchcase(row, reference)
        out.append({
            "env": env, "row": row, "seeds": len(g), "reached": int((~g["censored"]).sum()), "per_seed": per_seed_text(g),
            "mean": mean, "se": se, "mean_success": mean_s, "se_success": se_s, "median": float(g["steps"].median()),
            "iqm": point, "iqm_low": low, "iqm_high": high,
            "welch_p": math.nan if is_ref or ref.empty else welch_p(g["steps"], ref["steps"]),
            "reference": "" if ref.empty else reference,
            **_paper(str(env), [str(row), *map(str, g.get("stratum", []))], numbers),
        })  # fmt: skip
    return pd.DataFrame(out)


def _num(x: float, fmt: str = ".1f") -> str:
    return "–" if math.isnan(x) else format(x, fmt)


def _pm(mean: float, se: float) -> str:
    return _num(mean) + ("" if math.isnan(se) else f" ± {_num(se)}")


def _cells(r: Any) -> list[str]:
    ci = "" if math.isnan(r.iqm_low) else f" [{_num(r.iqm_low)}, {_num(r.iqm_high)}]"
    paper = "" if math.isnan(r.paper_mean) else f"{r.paper_method}: {r.paper_mean:g} ± {r.paper_se:g}"
    return [str(r.env), str(r.row), f"{r.reached} / {r.seeds}", r.per_seed.replace(" ", ", "), _pm(r.mean, r.se),
            _pm(r.mean_success, r.se_success), _num(r.median), _num(r.iqm) + ci, _num(r.welch_p, ".3g"), paper]  # fmt: skip


HEADER = ["env", "method", "reached / seeds", "steps-to-goal per seed", "mean ± SE", "success mean ± SE", "median",
          "IQM [95 % CI]", "Welch p", "paper"]  # fmt: skip


def compute_line(runs: pd.DataFrame) -> str:
    """The compute the finished runs took: their summed ``wall_seconds`` (each run one torch thread, so about its
    CPU time; a run sharing the cores with others took longer than it would alone), per env."""
    if runs.empty:
        return "Compute: no finished run."
    hours = runs.groupby("env", sort=True)["wall_seconds"].agg(["count", "sum"])
    parts = [f"{env} {int(r['count'])} runs, {r['sum'] / 3600:.1f} h" for env, r in hours.iterrows()]
    return (
        "Compute (the finished runs' summed `wall_seconds`, one torch thread each, so about CPU-hours; runs that "
        f"shared the cores count their own, longer, time): {'; '.join(parts)}."
    )


def code_line(runs: pd.DataFrame) -> str:
    """Which code commits made the finished runs (``code`` of :func:`analysis.rows.load_runs`), and every row (``row``,
    per env) whose runs were made by more than one: the same config run by other code may not be the same method, so a
    reader should know where a row pools them. ``""`` where no run recorded its commit."""
    if runs.empty or "code" not in runs:
        return ""
    made = runs[runs["code"].astype(bool)]
    if made.empty:
        return ""
    commits = made.drop_duplicates("run_dir")["code"].value_counts().sort_index()
    if len(commits) == 1:
        return f"Code: every run was made by commit `{commits.index[0]}` (`summary.json`'s `git_commit`)."
    listed = ", ".join(f"`{c}` ({n} run{'s' if n > 1 else ''})" for c, n in commits.items())
    pooled = []
    for (env, row), g in made.groupby(["env", "row"], sort=True):
        counts = g["code"].value_counts().sort_index()
        if len(counts) > 1:
            pooled.append(f"- {env} {row}: " + ", ".join(f"`{c}` ({n})" for c, n in counts.items()))
    text = f"Code: the runs were made by {len(commits)} commits (`summary.json`'s `git_commit`): {listed}."
    if not pooled:
        return text + " Each row's runs share one commit."
    return "\n".join([text + " Rows pooling runs of more than one commit:", "", *pooled])


def machine_line(runs: pd.DataFrame) -> str:
    """Which machines (CPU and vector capability, ``summary.json``'s ``machine``) made the finished runs, with counts:
    the same config and seed repeat exactly only on the same machine, so a seed-by-seed comparison of two rows holds
    only where one machine made both. ``""`` where no run recorded its machine (runs made before the field existed)."""
    if runs.empty or not runs["machine"].astype(bool).any():
        return ""
    counts = runs["machine"].replace("", "not recorded").value_counts().sort_index()
    if len(counts) == 1:
        return f"Machine: every run was made on `{counts.index[0]}` (`summary.json`'s `machine`)."
    listed = ", ".join(f"`{m}` ({n} run{'s' if n > 1 else ''})" for m, n in counts.items())
    return f"Machines (`summary.json`'s `machine`; a seed repeats exactly only on the same one): {listed}."


def to_markdown(table: pd.DataFrame, incomplete: pd.DataFrame, reference: str, compute: str = "",
                code: str = "") -> str:  # fmt: skip
    """The table, its note, the compute the runs took, the code that made them and the runs not finished, as one
    Markdown document."""
    lines = ["| " + " | ".join(HEADER) + " |", "|" + "---|" * len(HEADER)]
    lines += ["| " + " | ".join(c.replace("|", "\\|") for c in _cells(r)) + " |" for r in table.itertuples(index=False)]
    lines += ["", NOTE.format(reference=reference), ""]
    lines += [compute, ""] if compute else []
    lines += [code, ""] if code else []
    if incomplete.empty:
        lines.append("Every run below the directory finished (has `summary.json`).")
    else:
        lines.append(f"Not finished (no `summary.json`), not in the statistics: {len(incomplete)} run(s)")
        lines += [f"- {r.status}: `{r.run_dir}` {r.detail}" for r in incomplete.itertuples(index=False)]
    return "\n".join(lines) + "\n"


def _tex(s: str) -> str:
    for a, b in (("\\", r"\textbackslash{}"), ("_", r"\_"), ("%", r"\%"), ("&", r"\&"), ("#", r"\#"), ("±", r"$\pm$"),
                 (">", r"$>$"), ("–", "--"), ("[", "{[}"), ("]", "{]}"), ("√", r"$\surd$")):  # fmt: skip
        s = s.replace(a, b)
    return s


def to_latex(table: pd.DataFrame) -> str:
    """The table as a booktabs ``tabular`` (no float environment: the paper's file places it)."""
    lines = [r"\begin{tabular}{" + "l" * 4 + "r" * 6 + "}", r"\toprule", " & ".join(_tex(h) for h in HEADER) + r" \\",
             r"\midrule"]  # fmt: skip
    lines += [" & ".join(_tex(c) for c in _cells(r)) + r" \\" for r in table.itertuples(index=False)]
    return "\n".join([*lines, r"\bottomrule", r"\end{tabular}"]) + "\n"


def _relative(df: pd.DataFrame, root: Path) -> pd.DataFrame:
    """Run paths as the root was given plus the path below it, so the files do not depend on where the clone is."""
    if not df.empty and "run_dir" in df:
        df = df.assign(run_dir=[str(root / os.path.relpath(d, root)) for d in df["run_dir"]])
    return df


def write_tables(root: Path, out: Path, reference: str = DEFAULT_REFERENCE, group_by: Sequence[str] = (),
                 pools: Sequence[str] = (), labels: Sequence[str] = ()) -> pd.DataFrame:  # fmt: skip
    """Write ``steps_to_goal.{md,tex,csv}`` and ``incomplete.csv`` for the runs below ``root`` (and the cost table and
    figure where runs record ``cpu_seconds``, their rows named by ``labels``); returns the steps table."""
    parse_labels(labels)  # a malformed label fails before any file is written
    margin = margin_setting(root) or MARGIN  # a bad margin too
    runs = load_runs(root)
    incomplete = _relative(load_incomplete(root), root)
    if runs.empty and incomplete.empty:
        raise FileNotFoundError(f"no run directory below {root}")
    rows = pool_rows(label_rows(runs, group_by), pools) if not runs.empty else runs
    table = steps_table(rows, reference, paper_numbers()) if not runs.empty else pd.DataFrame(columns=["env", "row"])
    out.mkdir(parents=True, exist_ok=True)
    made_by = "\n\n".join(filter(None, [code_line(rows), machine_line(runs)]))  # the code, then the machines
    (out / "steps_to_goal.md").write_text(to_markdown(table, incomplete, reference, compute_line(runs), made_by))
    (out / "steps_to_goal.tex").write_text(to_latex(table))
    table.to_csv(out / "steps_to_goal.csv", index=False, float_format="%.6g", lineterminator="\n")
    cols = ["env", "method", "seed", "status", "detail", "run_dir"]
    incomplete.reindex(columns=cols).to_csv(out / "incomplete.csv", index=False, lineterminator="\n")
    if not runs.empty:
        write_curve_tables(root, out, reference, group_by, pools)
        write_distractor_table(runs, out)
        if write_cost(rows, out, reference, labels, incomplete, margin):
            write_pareto(rows, out, reference, labels, margin)
    return table


def write_curve_tables(root: Path, out: Path, reference: str, group_by: Sequence[str], pools: Sequence[str]) -> None:
    """``spread.{md,csv}`` (Figure 6) and ``stable_step.{md,csv}`` (Figure 7) for the runs that log their columns."""
    _, metrics = load(root, list(group_by), list(pools))
    for name, table, title, note in (
        ("spread", claims.spread_table(metrics, reference), "Spread of the next latents (Figure 6)", claims.SPREAD_NOTE),
        ("stable_step", claims.stable_table(metrics, reference), "Stable intrinsic reward (Figure 7)", claims.STABLE_NOTE),
    ):  # fmt: skip
        if table.empty:
            continue
        (out / f"{name}.md").write_text(claims.to_markdown(table, title, note, reference))
        table.to_csv(out / f"{name}.csv", index=False, float_format="%.6g", lineterminator="\n")


def main() -> None:
    p = parser(__doc__.splitlines()[0])
    p.add_argument("--reference", default=None,
                   help=f"glob over row labels: the Welch test's reference row (default {DEFAULT_REFERENCE})")  # fmt: skip
    label_option(p)

    def command(o: Options) -> str:
        table = write_tables(o.root, o.out, o.args.reference or DEFAULT_REFERENCE, o.group_by, o.pools, o.args.labels or ())
        return f"{len(table)} row(s) written to {o.out}/steps_to_goal.{{md,tex,csv}}"

    run(p, command)


if __name__ == "__main__":
    main()
