"""Does the paper hold? One verdict per claim of the paper (§4), computed from the committed tables only.

The paper's results (Tables 1 and 2, Figures 6 and 7, the hybrid of §4.2), and one claim it argues but never tests
(§2.3, §3.2, §3.3.3: density-based novelty resists a noisy TV that draws a prediction-error bonus; issue 16), whose
rule was fixed before any run with the TV: prediction error alone presses the TV more often than density alone, the
hybrid less often than prediction error alone, and the hybrid reaches the goal sooner than prediction error alone with
the TV (each over seeds 100–107 of ``noisy_tv/report/distractor.csv``).

``python -m analysis.verdicts RESULTS_DIR`` reads ``<preset>/report/{steps_to_goal,spread,stable_step,distractor}.csv`` below
RESULTS_DIR (what ``python -m analysis.tables results/<preset>`` writes) and writes ``verdicts.md`` and ``verdicts.csv``
there. Every number it prints is a number of those tables, or a test on their per-seed values.

The rule, fixed before the runs finished (README "Does the paper hold?"): each claim is one or more comparisons of two
rows of one table. A comparison ``A < B`` (A's values lower: fewer steps to the goal, an earlier stable step) is
*supported* when A's mean is below B's and Welch's two-sided p < 0.05, *reversed* when A's mean is above B's with
p < 0.05, and *not supported* otherwise; ``A > B`` mirrors it. ``A ≈ B`` (no difference) is *supported* when p ≥ 0.05
and *not supported* otherwise (weak evidence: a small sample rarely finds a difference). ``A ≮ B`` (A not below B) is
*reversed* when ``A < B`` would be supported and *supported* otherwise. A claim is supported when all its comparisons
are, reversed when any is reversed, and not supported otherwise; comparisons shown beside a claim (Table 1's other
readings of the paper's agent and the oracle-model planner, Table 2's default agents) are tested the same way but do
not enter its verdict. No correction for multiple comparisons. A claim whose table is missing, has a row it counts
short of its seeds or lists unfinished runs gets no verdict (``pending``); a comparison beside a claim is pending on its
own, without holding the claim back. For a value at an env step (the spread of Figure 6), a
row's seeds are its finished runs (``steps_to_goal.csv``): a run that reached the goal before that step has no value
there, so the test is over the runs still going at the step, and the verdict says how many those are.
"""

from __future__ import annotations

import argparse
import fnmatch
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from analysis.claims import fmt
from analysis.stats import welch_p

ALPHA = 0.05
SUPPORTED, NOT_SUPPORTED, REVERSED, PENDING = "supported", "not supported", "reversed", "pending"
# readout -> (table file in <preset>/report/, what a row's values are, the env step for the spread)
READOUTS = {
    "steps": ("steps_to_goal.csv", "steps-to-goal", None),
    "spread@200": ("spread.csv", "spread of the next latents at env step 200 (`info/latent_logdet`)", 200),
    "stable": ("stable_step.csv", "env step of a stable intrinsic reward", None),
    "tv_steps": ("distractor.csv", "steps-to-goal, with or without the noisy TV", None),
    "tv_presses": ("distractor.csv", "TV-press rate (the agent's own steps that pressed the remote)", None),
}
TV = "tv_presses"  # a rate: printed with three decimals


def tv_row(method: str, distractor: str) -> str:
    """The row label of a method with (``noisy_tv``) or without (``none``) the TV in ``distractor.csv``."""
    return f"{method} (TV: {distractor})"


@dataclass(frozen=True)
class Comparison:
    """Row ``a`` against row ``b`` (globs over the table's row labels) in ``relation`` (``<``, ``>``, ``≈``, ``≮``)."""

    a: str
    relation: str
    b: str
    readout: str = "steps"
    seeds: int = 10  # the seeds each row must have (a pooled row: its parts' total)
    seeds_b: int | None = None  # the seeds of row b when they differ
    counts: bool = True  # False: shown and tested beside the claim, not part of its verdict


@dataclass(frozen=True)
class Claim:
    name: str
    paper: str  # the paper's statement and numbers
    preset: str  # results/<preset>
    comparisons: tuple[Comparison, ...]


# The rows of the current default agent (held actions on blurred frames since ccdcc1e) and of the default before it
# (ours-conv-..., with the oracle-model planner's `oracle` row of that default in Table 1), which stay in Tables 1 and 2
OURS = "ours-conv_blur-gaussian_potential-kde-backward_off-mpc"
PREVIOUS_OURS = "ours-conv-gaussian_potential-kde-backward_off-mpc"
CLAIMS = (
    Claim("Table 1", "Acrobot from pixels: Ours 290.0 ± 45.72 < Novelty/NSRS 576.0 ± 66.13 < ICM 932.8 ± 141.54 ≈ RND "
          "953.8 ± 85.98", "table1",
          (Comparison(OURS, "<", "nsrs*"), Comparison("nsrs*", "<", "icm*"), Comparison("icm*", "≈", "rnd*"),
           # the paper's agent as its text reads and as its precursor code ran (docs/method.md §0), and the oracle-model
           # planner (the upper bound): beside the claim, which is about the default agent
           Comparison("paper_text-*", "<", "nsrs*", counts=False), Comparison("paper_code-*", "<", "nsrs*", counts=False),
           Comparison("oracle-conv_blur", "<", "nsrs*", counts=False),
           Comparison(PREVIOUS_OURS, "<", "nsrs*", counts=False), Comparison("oracle", "<", "nsrs*", counts=False))),
    Claim("Table 2", "MountainCar from pixels: Novelty 1158.5 ± 172.8 vs Ours 1456.9 ± 125.7 (two Rényi variants "
          "pooled): \"the improvement is less evident\"", "table2",
          (Comparison("paper_text-renyi (both variants pooled)", "≮", "nsrs*", seeds=20, seeds_b=10),
           # our default agents on the same seeds: beside the claim, which is about the paper's pooled Rényi row
           Comparison(OURS, "≮", "nsrs*", counts=False), Comparison(PREVIOUS_OURS, "≮", "nsrs*", counts=False))),
    Claim("Figure 6", "the matrix-based Rényi objective spreads s_{t+1} faster than the Gaussian potential", "fig6",
          (Comparison("ours-conv_blur-renyi-kde-*", ">", "ours-conv_blur-gaussian_potential-kde-*", "spread@200", 6),)),
    Claim("Figure 7", "KDE reaches a stable intrinsic reward in fewer steps than kNN, and converges faster", "fig7",
          (Comparison("ours-conv_blur-gaussian_potential-kde-*", "<", "ours-conv_blur-gaussian_potential-knn-*", "stable", 6),
           Comparison("ours-conv_blur-gaussian_potential-kde-*", "<", "ours-conv_blur-gaussian_potential-knn-*", "steps", 6))),
    Claim("Hybrid (§4.2)", "the hybrid of prediction error and density beats either alone", "hybrid",
          (Comparison("ours_hybrid", "<", "ours_density", seeds=6), Comparison("ours_hybrid", "<", "ours_pe", seeds=6))),
    # argued in the paper, never tested there (issue 16); the rule fixed on 2026-12-06, before any run with the TV
    Claim("Noisy TV (§2.3, §3.2, §3.3.3; argued, not tested)", "a prediction-error bonus is drawn to a noisy TV; "
          "density-based novelty, alone or in the hybrid, resists it", "noisy_tv",
          (Comparison(tv_row("ours_pe", "noisy_tv"), ">", tv_row("ours_density", "noisy_tv"), TV, 8),
           Comparison(tv_row("ours_hybrid", "noisy_tv"), "<", tv_row("ours_pe", "noisy_tv"), TV, 8),
           Comparison(tv_row("ours_hybrid", "noisy_tv"), "<", tv_row("ours_pe", "noisy_tv"), "tv_steps", 8),
           # beside the claim: the classic prediction-error and observation-novelty baselines at the remote, and
           # whether the TV slows each method down (with it against without it)
           Comparison(tv_row("icm", "noisy_tv"), ">", tv_row("ours_density", "noisy_tv"), TV, 8, counts=False),
           Comparison(tv_row("rnd", "noisy_tv"), ">", tv_row("ours_density", "noisy_tv"), TV, 8, counts=False),
           *(Comparison(tv_row(m, "noisy_tv"), ">", tv_row(m, "none"), "tv_steps", 8, counts=False)
             for m in ("ours_pe", "ours_density", "ours_hybrid", "icm", "rnd")))),
)  # fmt: skip


def seed_values(per_seed: str) -> list[float]:
    """A table's per-seed text (``857 368 >3000``; ``>`` marks a run counted at its last step) as numbers."""
    return [float(v.lstrip(">")) for v in str(per_seed).replace(",", " ").split()]


def judge(relation: str, a: list[float], b: list[float]) -> tuple[str, float]:
    """(verdict, Welch's two-sided p) of ``a relation b`` by the module's rule."""
    p = welch_p(a, b)
    lower = sum(a) / len(a) < sum(b) / len(b)
    significant = not math.isnan(p) and p < ALPHA
    if relation == "≈":
        return (NOT_SUPPORTED if significant else SUPPORTED), p
    if relation == "≮":
        return (REVERSED if significant and lower else SUPPORTED), p
    expected = lower if relation == "<" else not lower
    if not significant:
        return NOT_SUPPORTED, p
    return (SUPPORTED if expected else REVERSED), p


def claim_verdict(verdicts: list[str]) -> str:
    if PENDING in verdicts:
        return PENDING
    if REVERSED in verdicts:
        return REVERSED
    return SUPPORTED if all(v == SUPPORTED for v in verdicts) else NOT_SUPPORTED


def _row(table: pd.DataFrame, pattern: str) -> pd.Series | str:
    """The one row of ``table`` whose label matches ``pattern``, or why there is none."""
    found = table[[fnmatch.fnmatchcase(str(r), pattern) for r in table["row"]]]
    if len(found) != 1:
        return f"{len(found)} rows match `{pattern}`"
    return found.iloc[0]


def _load(report: Path, readout: str) -> pd.DataFrame | str:
    name, _, step = READOUTS[readout]
    path = report / name
    if not path.is_file():
        return f"no table {path}"
    table = pd.read_csv(path)
    if step is not None:
        table = table[table["step"] == step]
    if name == "distractor.csv":  # one row per (method, distractor); the TV-press readout tests the rates
        table = table.assign(row=[tv_row(m, d) for m, d in zip(table["method"], table["distractor"], strict=True)])
        if readout == TV:
            table = table.assign(per_seed=table["tv_per_seed"].fillna(""), mean=table["tv_rate"], se=table["tv_rate_se"])
    return table


def _finished_runs(report: Path, row: str) -> int | None:
    """The finished runs of ``row`` in the preset's ``steps_to_goal.csv``, or None where it has no such row."""
    table = _load(report, "steps")
    if isinstance(table, str):
        return None
    found = table[table["row"] == row]  # the exact label: row labels hold [ ], which a glob would read as a class
    return int(found["seeds"].iloc[0]) if len(found) == 1 else None


def _unfinished(report: Path) -> int:
    path = report / "incomplete.csv"
    return len(pd.read_csv(path)) if path.is_file() else 0


def compare(results: Path, claim: Claim, c: Comparison) -> dict[str, object]:
    """One comparison of a claim: both rows' numbers from the committed table, the test and the verdict."""
    report = results / claim.preset / "report"
    out: dict[str, object] = {"claim": claim.name, "a": c.a, "relation": c.relation, "b": c.b, "readout": c.readout,
                              "counts": c.counts, "table": f"{claim.preset}/report/{READOUTS[c.readout][0]}"}  # fmt: skip
    table = _load(report, c.readout)
    rows = [table if isinstance(table, str) else _row(table, pattern) for pattern in (c.a, c.b)]
    missing = [r for r in rows if isinstance(r, str)]
    if missing:
        return out | {"verdict": PENDING, "why": missing[0]}
    a, b = (seed_values(r["per_seed"]) for r in rows)  # type: ignore[index]
    runs = [len(a), len(b)]
    if READOUTS[c.readout][2] is not None:  # a value at an env step: the runs that ended before it have none
        runs = [_finished_runs(report, r["row"]) or len(v) for r, v in zip(rows, (a, b), strict=True)]  # type: ignore[index]
    short = [f"{r['row']}: {k} of {n} seeds" for r, k, n in zip(rows, runs, (c.seeds, c.seeds_b or c.seeds),
                                                                  strict=True) if k != n]  # fmt: skip
    if unfinished := _unfinished(report):
        short.append(f"{unfinished} unfinished run(s) in {claim.preset}")
    verdict, p = judge(c.relation, a, b)
    for key, r, v, k in (("a", rows[0], a, runs[0]), ("b", rows[1], b, runs[1])):  # the table's own mean and SE
        out |= {f"{key}_row": r["row"], f"{key}_n": len(v), f"{key}_mean": r["mean"], f"{key}_se": r["se"]}  # type: ignore[index]
        out[f"{key}_runs"] = k
        if "iqm" in r:  # type: ignore[operator]
            out |= {f"{key}_iqm": r["iqm"], f"{key}_iqm_low": r["iqm_low"], f"{key}_iqm_high": r["iqm_high"]}  # type: ignore[index]
    return out | {"welch_p": p, "verdict": PENDING if short else verdict, "why": "; ".join(short)}


def verdicts(results: Path) -> pd.DataFrame:
    """One line per comparison of every claim, then its claim's verdict in ``claim_verdict``."""
    lines = [compare(results, claim, c) for claim in CLAIMS for c in claim.comparisons]
    table = pd.DataFrame(lines)
    counted = table[table["counts"]].groupby("claim", sort=False)["verdict"].agg(lambda v: claim_verdict(list(v)))
    table["claim_verdict"] = table["claim"].map(counted)
    return table


def _side(r: pd.Series, key: str) -> str:
    if pd.isna(r.get(f"{key}_n")):
        return "–"
    n, runs = int(r[f"{key}_n"]), r.get(f"{key}_runs", math.nan)
    ended = "" if pd.isna(runs) or int(runs) == n else f" of {int(runs)} runs; {int(runs) - n} ended before the step"
    spec = ".3f" if r["readout"] == TV else ".1f"
    text = f"`{r[f'{key}_row']}`: {fmt(r[f'{key}_mean'], spec)} ± {fmt(r[f'{key}_se'], spec)} (n = {n}{ended})"
    if not pd.isna(r.get(f"{key}_iqm", math.nan)):
        low, high = (fmt(float(r[f"{key}_iqm_{end}"]), ".1f") for end in ("low", "high"))
        text += f", IQM {fmt(float(r[f'{key}_iqm']), '.1f')} [{low}, {high}]"
    return text


def to_markdown(table: pd.DataFrame) -> str:
    lines = ["# Does the paper hold?", "", "Made by `python -m analysis.verdicts results` from the committed tables "
             "(`results/<preset>/report/`); the rule is in `analysis/verdicts.py`: Welch's two-sided t-test on the "
             "per-seed values, α = 0.05, censored runs at their last step.", "",
             "| claim (paper) | comparison | readout | A | B | Welch p | verdict |",
             "|---|---|---|---|---|---|---|"]  # fmt: skip
    papers = {c.name: c.paper for c in CLAIMS}
    for claim, g in table.groupby("claim", sort=False):
        for i, r in enumerate(g.itertuples(index=False)):
            r = pd.Series(r._asdict())
            head = f"**{claim}: {r['claim_verdict']}**. {papers[str(claim)]}" if i == 0 else ""
            verdict = r["verdict"] + (f" ({r['why']})" if r["why"] else "") + ("" if r["counts"] else " (beside the claim)")
            cells = [head, f"A {r['relation']} B", READOUTS[r["readout"]][1], _side(r, "a"),
                     _side(r, "b"), fmt(r.get("welch_p", math.nan), ".3g"), verdict]  # fmt: skip
            lines.append("| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("results", help="the directory holding <preset>/report/ tables (results)")
    p.add_argument("--out", help="where to write verdicts.{md,csv} (default: RESULTS)")
    args = p.parse_args()
    results = Path(args.results)
    if not results.is_dir():
        print(f"error: {results}: no such directory; allowed: the directory holding the presets' results", file=sys.stderr)
        raise SystemExit(2)
    out = Path(args.out) if args.out else results
    out.mkdir(parents=True, exist_ok=True)
    table = verdicts(results)
    (out / "verdicts.md").write_text(to_markdown(table))
    table.to_csv(out / "verdicts.csv", index=False, float_format="%.6g", lineterminator="\n")
    done = table.drop_duplicates("claim")["claim_verdict"].value_counts().to_dict()
    print(f"{len(CLAIMS)} claims ({', '.join(f'{n} {v}' for v, n in sorted(done.items()))}) -> {out}/verdicts.md")


if __name__ == "__main__":
    main()
